#!/usr/bin/python3
"""Cross-check of the reference's error bar: least-squares fits of the mesh study's sample displacements.

`tissue verify fem` extrapolates the samples by Richardson from the last three levels with one order (the observed
one inside 0.3 of the expected one, the expected one otherwise; docs/EXPERIMENTS.md §1c). Where the observed order
lies between two plausible ones (lung_large: 2.61 and 2.63 against the expected 2), this script fits, for each sample
component over the last N levels,

    u_h = u* + a h^p            (one term, p = 2 or 3)
    u_h = u* + a h^2 + b h^3    (two terms: the graded singular lines' pollution and the smooth P2 error)

and prints each fit's residual and the distance of the finest level from its u* (RMS over the samples, relative to
the largest sample displacement). Reads results/verify/fem.json (or the file given). Needs python3-numpy.

It also prints the observed orders of two groups of samples apart: those within the graded ball under the probe
(1.5 load radii of the load centre, where the FEM's local size is GeometrySpec::load_patch_size, which falls like
h^g with /geometry/refinement/load_patch_grading g) and those beyond it (where the size grows to h over one more load
radius, so it falls like h). The two groups are refined at different rates, so one order over all samples mixes
them (`tissue verify fem` prints the same orders, "By zone", and writes them as
richardson.observed_orders_by_zone). The sample points and the load centre come from the study's sample_points_mm
and load_centre_mm, or, for a study written before those were, from `build/bin/tissue case check` on its config
(run from the repository's root, after the build).

    /usr/bin/python3 scripts/mesh_study_fits.py [results/verify/fem.json]
"""
import json
import re
import subprocess
import sys

import numpy as np

from mesh_study_io import observed_order, ratio_ending_at, rms, solved

FITS = [("h^2", [2]), ("h^3", [3]), ("h^2 + h^3", [2, 3])]


def observed_orders(h, u):
    """The observed order of each consecutive three levels of `u` (levels by values)."""
    return [observed_order(u[l - 2], u[l - 1], u[l], ratio_ending_at(h, l)) for l in range(2, len(h))]


def samples_and_centre(config):
    """The sample points and the load centre [mm] that `tissue case check` prints for `config`."""
    text = subprocess.run(["build/bin/tissue", "case", "check", config], check=True, capture_output=True,
                          text=True).stdout
    number = r"(-?\d+(?:\.\d+)?)"
    points = [[float(x) for x in m] for m in re.findall(rf"^\s+\d+\s+\(\s*{number},\s*{number},\s*{number}\)",
                                                       text, re.M)]
    centre = re.search(rf"^load centre\s+\(\s*{number},\s*{number},\s*{number}\)", text, re.M)
    return np.array(points), np.array([float(x) for x in centre.groups()])


def print_group_orders(study, h, u):
    if "sample_points_mm" in study:  # written by `tissue verify fem` since the zones were added
        points, centre = np.array(study["sample_points_mm"]), np.array(study["load_centre_mm"])
        radius = study["load_radius_mm"]
    else:
        with open(study["config"]) as f:
            radius = json.load(f)["load"]["radius"]
        points, centre = samples_and_centre(study["config"])
    distance = np.linalg.norm(points - centre, axis=1)
    by_sample = u.reshape(len(h), -1, 3)
    for name, chosen in [("within 1.5 load radii (local size ~ h^g)", distance <= 1.5 * radius),
                         ("beyond 1.5 load radii (local size ~ h)", distance > 1.5 * radius)]:
        if chosen.sum() == 0:
            continue
        orders = observed_orders(h, by_sample[:, chosen, :].reshape(len(h), -1))
        print(f"  samples {name}: {chosen.sum()} of {len(distance)}, observed orders "
              f"{', '.join(f'{x:.2f}' for x in orders)}")


def print_last_changes(h, u):
    """Each sample's last two changes between levels [um] and the cosine between them: a power of h moves every
    sample the same way at every level (cosine 1), so a sample that turns shows where the levels stop following one."""
    if len(h) < 3:
        return
    by_sample = u.reshape(len(h), -1, 3)
    d1, d2 = by_sample[-2] - by_sample[-3], by_sample[-1] - by_sample[-2]
    n1, n2 = np.linalg.norm(d1, axis=1), np.linalg.norm(d2, axis=1)
    cosines = np.sum(d1 * d2, axis=1) / np.maximum(n1 * n2, 1e-300)
    print(f"  each sample's changes {h[-3]:g} -> {h[-2]:g} and {h[-2]:g} -> {h[-1]:g} mm [um], and their cosine: "
          + "; ".join(f"{i}: {1e3 * a:.2f}, {1e3 * b:.2f}, {c:+.2f}" for i, (a, b, c) in enumerate(zip(n1, n2, cosines))))


def print_rigid_part(study, h, u):
    """Split each change between consecutive levels into its best rigid motion (a translation and a small rotation
    about the samples' centroid, least squares over the samples) and the rest. A change that is mostly rigid moves
    every sample alike, however far from the probe: it comes from how the whole body deforms and is held (e.g. its
    surface and volume as the mesh represents them), not from the error under the probe."""
    if "sample_points_mm" not in study or len(h) < 2:
        return
    points = np.array(study["sample_points_mm"])
    x = points - points.mean(axis=0)
    rigid = np.zeros((3 * len(points), 6))
    for i, (a, b, c) in enumerate(x):  # u = t + w x (x - centroid)
        rigid[3 * i:3 * i + 3, :3] = np.eye(3)
        rigid[3 * i:3 * i + 3, 3:] = [[0, c, -b], [-c, 0, a], [b, -a, 0]]
    print("  | change | RMS [um] | its rigid part [um] | the rest [um] | translation [um] | rotation [urad] |")
    print("  |---|---|---|---|---|---|")
    for l in range(1, len(h)):
        d = 1e3 * (u[l] - u[l - 1])  # um
        motion = np.linalg.lstsq(rigid, d, rcond=None)[0]
        fitted = rigid @ motion
        print(f"  | {h[l - 1]:g} -> {h[l]:g} mm | {rms(d):.2f} | {rms(fitted):.2f} | {rms(d - fitted):.2f} | "
              f"({', '.join(f'{v:.2f}' for v in motion[:3])}) | "
              f"({', '.join(f'{1e3 * v:.1f}' for v in motion[3:])}) |")


def main(path):
    with open(path) as f:
        studies = json.load(f)["mesh_convergence"]
    for case, study in studies.items():
        levels = solved(study)
        for level in study["levels"]:
            if level not in levels:
                print(f"{case}: the {level['mesh_size_mm']:g} mm level did not solve; left out")
        h = np.array([level["mesh_size_mm"] for level in levels])
        u = np.array([np.ravel(level["sample_displacements_mm"]) for level in levels])
        peak = np.max(np.linalg.norm(u[-1].reshape(-1, 3), axis=1))
        print(f"{case}: levels {', '.join(f'{x:g}' for x in h)} mm; peak sample displacement {peak:.4f} mm")
        for i, order in enumerate(observed_orders(h, u)):
            print(f"  observed order over {h[i]:g} / {h[i + 1]:g} / {h[i + 2]:g} mm: {order:.2f}")
        print_group_orders(study, h, u)
        print_last_changes(h, u)
        print_rigid_part(study, h, u)
        print("  | fit | levels | residual RMS [mm] | finest level from u* (RMS) |")
        print("  |---|---|---|---|")
        for name, powers in FITS:
            for count in range(len(powers) + 2, len(h) + 1):
                hs, us = h[-count:], u[-count:]
                design = np.column_stack([np.ones(count)] + [hs**p for p in powers])
                coefficients = np.linalg.lstsq(design, us, rcond=None)[0]
                residual = np.sqrt(np.mean((design @ coefficients - us) ** 2))
                distance = np.sqrt(np.mean(np.sum(((us[-1] - coefficients[0]).reshape(-1, 3)) ** 2, axis=1)))
                print(f"  | {name} | {', '.join(f'{x:g}' for x in hs)} mm | {residual:.1e} | "
                      f"{distance:.4f} mm ({100 * distance / peak:.2f} %) |")


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "results/verify/fem.json")
