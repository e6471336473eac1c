#!/usr/bin/env python3
"""Do two mesh studies of one case extrapolate to the same sample displacements, within their bars?

Two `tissue verify fem` studies of the same case in different mesh families (e.g. the shipped load-patch grading,
results/verify/fem.json, and the one-rate family, results/verify/one_rate/fem.json; docs/FEM_REFERENCE.md, "One rate
at every sample") estimate the same exact samples. Each study's last two levels are extrapolated here at one assumed
order p, u* = u_f + (u_f - u_{f-1}) / (r^p - 1), r the mean refinement ratio of the last three levels (as
experiments/comparator/mesh_study_estimate.cpp does), with the bar |u_f - u_{f-1}| / (r^p - 1). It prints, in mm RMS
per sample, the distance between the two extrapolations, each bar and their root sum of squares.

Usage: scripts/compare_mesh_studies.py STUDY_A.json STUDY_B.json CASE [--order 2 3]
"""
import argparse
import math

import numpy as np

from mesh_study_io import ratio_ending_at, read_study, rms, solved


def levels(path, case):
    levels = solved(read_study(path, case))
    return [np.array(l["sample_displacements_mm"]) for l in levels], [l["mesh_size_mm"] for l in levels]


def extrapolate(u, h, order):
    r = ratio_ending_at(h, len(h) - 1)
    step = (u[-1] - u[-2]) / (r ** order - 1.0)
    return u[-1] + step, rms(step)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("study_a")
    parser.add_argument("study_b")
    parser.add_argument("case")
    parser.add_argument("--order", type=float, nargs="+", default=[2.0, 3.0])
    a = parser.parse_args()
    ua, ha = levels(a.study_a, a.case)
    ub, hb = levels(a.study_b, a.case)
    if len(ua) < 3 or len(ub) < 3:
        raise SystemExit("each study needs three solved levels")
    print(f"{a.case}: A {a.study_a} levels {ha} mm; B {a.study_b} levels {hb} mm")
    print(f"  finest levels {rms(ua[-1] - ub[-1]):.4f} mm RMS apart; peak sample |u| "
          f"{np.linalg.norm(ua[-1], axis=1).max():.4f} mm")
    print("  | order | A's bar [mm] | B's bar [mm] | combined bar | extrapolations apart | apart / combined |")
    print("  |---|---|---|---|---|---|")
    for p in a.order:
        xa, ba = extrapolate(ua, ha, p)
        xb, bb = extrapolate(ub, hb, p)
        combined = math.hypot(ba, bb)
        apart = rms(xa - xb)
        print(f"  | {p:g} | {ba:.4f} | {bb:.4f} | {combined:.4f} | {apart:.4f} | {apart / combined:.2f} |")


if __name__ == "__main__":
    main()
