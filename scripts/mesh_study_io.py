"""What the mesh-study scripts share (mesh_noise.py, mesh_study_fits.py, compare_mesh_studies.py).

A study is the fem.json that `tissue verify fem` writes: /mesh_convergence/CASE/levels, coarse to fine, each with
mesh_size_mm and sample_displacements_mm (samples by 3, mm) when it solved, or an "error" when it did not. The
observed order and the refinement ratio are computed as experiments/comparator/mesh_study_estimate.cpp computes them,
so the scripts print the orders `verify fem` prints.
"""
import json
import math

import numpy as np


def read_study(path, case):
    """/mesh_convergence/CASE of the study at PATH; exits with what was expected when it is not there."""
    try:
        with open(path) as f:
            return json.load(f)["mesh_convergence"][case]
    except OSError as e:
        raise SystemExit(f"{path}: cannot read it ({e.strerror}); expected the fem.json of `tissue verify fem`")
    except (ValueError, KeyError):
        raise SystemExit(f"{path}: no /mesh_convergence/{case} in it; expected the fem.json of `tissue verify fem` "
                         f"run on that case")


def solved(study):
    """The levels of a study (read_study) that solved, coarse to fine."""
    return [level for level in study["levels"] if "sample_displacements_mm" in level and "error" not in level]


def rms(d):
    """RMS over the samples of the distances in d (samples by 3) [the unit of d]."""
    d = np.asarray(d).reshape(-1, 3)
    return math.sqrt((d ** 2).sum() / d.shape[0])


def ratio_ending_at(h, l):
    """The refinement ratio of levels l - 2, l - 1, l: the mean of its two steps."""
    return 0.5 * (h[l - 2] / h[l - 1] + h[l - 1] / h[l])


def observed_order(a, b, c, ratio):
    """The observed order of levels a, b, c (coarse to fine) from the norms of their differences over every sample;
    0 when the differences do not decrease."""
    d1, d2 = np.linalg.norm(np.asarray(b) - a), np.linalg.norm(np.asarray(c) - b)
    return math.log(d1 / d2) / math.log(ratio) if d2 > 0 and d1 > d2 else 0.0
