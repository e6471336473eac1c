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


def level_meshes(path, case, jittered=()):
    """Every mesh solved at each level of the study at PATH: its own (its `meshes` when `verify fem
    --meshes-per-level` made it, else its one mesh), then those of the JITTERED studies (the same case at sizes a
    percent or so away), each matched to the nearest level within 5 % of its size.

    Returns (h, own, meshes, matched, left_out): the levels' sizes [mm]; the study's samples at each level (samples
    by 3, mm; the mean of its own meshes); each level's list of meshes' samples, the study's own first; the matched
    jittered meshes as (path, size, level index, samples); and the jittered levels matched to none, as (path, size).
    """
    levels = solved(read_study(path, case))
    h = [l["mesh_size_mm"] for l in levels]
    own = [np.array(l["sample_displacements_mm"]) for l in levels]
    meshes = [[np.array(m["sample_displacements_mm"]) for m in l.get("meshes", [])] or [u]
              for l, u in zip(levels, own)]
    matched, left_out = [], []
    for other in jittered:
        for level in solved(read_study(other, case)):
            size, u = level["mesh_size_mm"], np.array(level["sample_displacements_mm"])
            nearest = min(range(len(h)), key=lambda l: abs(h[l] - size))
            if abs(h[nearest] - size) > 0.05 * h[nearest]:
                left_out.append((other, size))
                continue
            meshes[nearest].append(u)
            matched.append((other, size, nearest, u))
    return h, own, meshes, matched, left_out


def means(meshes):
    """Each level's mean over its meshes (level_meshes)."""
    return [sum(group) / len(group) for group in meshes]


def order_for_the_estimate(observed, expected, band=0.3):
    """The order `verify fem` extrapolates with (experiments/comparator/mesh_study_estimate.cpp): the observed one
    when it lies within BAND of the expected one; otherwise the one that gives the larger bar (the observed one, at
    least 1, below the expected one; the expected one above it)."""
    if abs(observed - expected) <= band:
        return observed
    return max(observed, 1.0) if observed < expected else expected


def richardson_step(u, h, order):
    """The Richardson correction of the finest level, (u_f - u_{f-1}) / (r^p - 1), r the mean refinement ratio of the
    last three levels (as experiments/comparator/mesh_study_estimate.cpp computes it); u* = u_f + the step, and the
    step is the finest level's estimated error."""
    r = ratio_ending_at(h, len(h) - 1)
    return (u[-1] - u[-2]) / (r ** order - 1.0)


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
