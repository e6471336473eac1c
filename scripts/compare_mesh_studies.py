#!/usr/bin/env python3
"""Do two mesh studies of one case extrapolate to the same sample displacements, within their bars?

Two `tissue verify fem` studies of the same case in different mesh families (e.g. the shipped load-patch grading,
results/verify/fem.json, and the one-rate family, results/verify/one_rate/fem.json; docs/FEM_REFERENCE.md, "One rate
at every sample") estimate the same exact samples. Each study's last two levels are extrapolated here at one order
p, u* = u_f + (u_f - u_{f-1}) / (r^p - 1), r the mean refinement ratio of the last three levels (as
experiments/comparator/mesh_study_estimate.cpp does), with the bar |u_f - u_{f-1}| / (r^p - 1). It prints, in mm RMS
per sample, the distance between the two extrapolations, each bar and their root sum of squares: at each order of
--order, and at the order `verify fem` would use for each study (its observed order within 0.3 of --expected-order,
else the one that gives the larger bar).

With --jittered-a / --jittered-b, a study's levels are the means of its meshes: its own and those of studies of the
same case at sizes a percent or so away (matched to the nearest level within 5 %, as scripts/mesh_noise.py does),
which averages out the noise between non-nested meshes (docs/FEM_REFERENCE.md, "The linear lab").

Last, it gives each of A's levels' distance from A's and from B's extrapolation (at the orders `verify fem` would
use): for A's reference level (the mesh `compare` solves, 12 mm for the shipped cases) this is the error that
`compare`'s bar estimates, measured against an independent family.

Usage: scripts/compare_mesh_studies.py STUDY_A.json STUDY_B.json CASE [--order 2 3] [--jittered-a F ...]
       [--jittered-b F ...]
"""
import argparse
import math

import numpy as np

from mesh_study_io import (level_meshes, means, observed_order, order_for_the_estimate, ratio_ending_at,
                           richardson_step, rms)


def levels(path, case, jittered):
    """The study's level sizes and samples (the means of its meshes), and how many meshes each level has."""
    h, _, meshes, _, left_out = level_meshes(path, case, jittered)
    for other, size in left_out:
        print(f"{other}: level {size:g} mm is more than 5 % from every level of {path}: left out")
    return means(meshes), h, [len(group) for group in meshes]


def extrapolate(u, h, order):
    step = richardson_step(u, h, order)
    return u[-1] + step, rms(step)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("study_a")
    parser.add_argument("study_b")
    parser.add_argument("case")
    parser.add_argument("--order", type=float, nargs="+", default=[2.0, 3.0])
    parser.add_argument("--expected-order", type=float, default=2.0,
                        help="the order the case's samples are expected to converge at (verify fem's, for the lung "
                             "cases 2)")
    parser.add_argument("--jittered-a", nargs="+", default=[], metavar="STUDY",
                        help="studies of the case beside A's levels: A's levels become the means of their meshes")
    parser.add_argument("--jittered-b", nargs="+", default=[], metavar="STUDY",
                        help="the same for B")
    a = parser.parse_args()
    ua, ha, na = levels(a.study_a, a.case, a.jittered_a)
    ub, hb, nb = levels(a.study_b, a.case, a.jittered_b)
    if len(ua) < 3 or len(ub) < 3:
        raise SystemExit("each study needs three solved levels")
    print(f"{a.case}: A {a.study_a} levels {ha} mm, meshes per level {na}; "
          f"B {a.study_b} levels {hb} mm, meshes per level {nb}")
    print(f"  finest levels {rms(ua[-1] - ub[-1]):.4f} mm RMS apart; peak sample |u| "
          f"{np.linalg.norm(ua[-1], axis=1).max():.4f} mm")
    observed = [observed_order(u[-3], u[-2], u[-1], ratio_ending_at(h, len(h) - 1)) for u, h in ((ua, ha), (ub, hb))]
    used = [order_for_the_estimate(p, a.expected_order) for p in observed]
    print(f"  observed orders of the last three levels: A {observed[0]:.2f}, B {observed[1]:.2f} (expected "
          f"{a.expected_order:g} +- 0.3); verify fem would extrapolate with A {used[0]:.2f}, B {used[1]:.2f}")
    print("  | order | A's bar [mm] | B's bar [mm] | combined bar | extrapolations apart | apart / combined |")
    print("  |---|---|---|---|---|---|")
    rows = [(f"{p:g}", p, p) for p in a.order] + [(f"verify fem's ({used[0]:.2f} / {used[1]:.2f})", *used)]
    for label, pa, pb in rows:
        xa, ba = extrapolate(ua, ha, pa)
        xb, bb = extrapolate(ub, hb, pb)
        combined = math.hypot(ba, bb)
        apart = rms(xa - xb)
        print(f"  | {label} | {ba:.4f} | {bb:.4f} | {combined:.4f} | {apart:.4f} | {apart / combined:.2f} |")

    xa, ba = extrapolate(ua, ha, used[0])
    xb, bb = extrapolate(ub, hb, used[1])
    print("  | A's level (its mean with --jittered-a) | from A's extrapolation [mm] | from B's extrapolation [mm] | "
          "B's bar [mm] |")
    print("  |---|---|---|---|")
    for size, u in zip(ha, ua):
        print(f"  | {size:g} mm | {rms(u - xa):.4f} | {rms(u - xb):.4f} | {bb:.4f} |")


if __name__ == "__main__":
    main()
