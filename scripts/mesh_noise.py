#!/usr/bin/env python3
"""How much does a mesh study's observed order depend on the particular mesh at each level?

Gmsh's unstructured meshes are not nested: two meshes of nominal sizes 12 and 12.12 mm share no element, and the
samples move between them by a mesh-to-mesh "noise" that has nothing to do with h. A level's change is the
difference of two such meshes, so its noise enters every observed order. This script measures it: beside a
committed study (`tissue verify fem`, results/verify/fem.json), studies of the same case at sizes a percent or so
away from its levels (jittered: the smooth error moves by about p percent of itself, so what moves more is noise)
are matched to the nearest level (within 5 % of its size). For each level with jittered meshes it prints:

- the noise: the RMS over the samples of each mesh's distance from the meshes' mean, with n - 1 (um and % of the
  peak), beside the level's change to the next finer level;
- each jittered mesh's RMS distance from the study's mesh at its level (also the way to compare two studies of the
  same sizes that differ in something else, e.g. how the samples are read);
- for each three consecutive levels, the observed order of the study's own meshes (as `verify fem` computes it:
  log(|u_b - u_a| / |u_c - u_b|) / log r, norms over every sample) and its range over every combination of the
  meshes at those levels, and the order of the levels' means.

A study run with `tissue verify fem --meshes-per-level N` holds its own meshes per level (each level's samples are
then their mean); they are read as the level's meshes, and no jittered study is needed.

Usage: scripts/mesh_noise.py STUDY.json CASE [JITTERED.json ...]
"""
import argparse
import itertools
import math

import numpy as np

from mesh_study_io import (level_meshes, means, observed_order as order, order_for_the_estimate, ratio_ending_at,
                           richardson_step, rms)


def print_estimate_of_the_means(h, level_means, expected):
    """The remaining error of the finest level's mean, from the last three levels' means, as `verify fem` estimates it
    (order_for_the_estimate)."""
    ratio = ratio_ending_at(h, len(h) - 1)
    p = order(level_means[-3], level_means[-2], level_means[-1], ratio)
    used = order_for_the_estimate(p, expected)
    within = used == p
    step = richardson_step(level_means, h, used)
    relative = np.linalg.norm(step) / np.linalg.norm(level_means[-1])
    print(f"The means of {h[-3]:g} / {h[-2]:g} / {h[-1]:g} mm: observed order {p:.2f}, "
          f"{'within' if within else 'outside'} {expected:g} +- 0.3; "
          f"{'Richardson with it' if within else f'order {used:.2f} assumed'}: the finest mean's remaining error is "
          f"{100 * relative:.2f} % of the sample displacements, {rms(step) * 1e3:.2f} um RMS per sample.")


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("study")
    parser.add_argument("case")
    parser.add_argument("jittered", nargs="*")
    parser.add_argument("--expected-order", type=float, default=2.0,
                        help="the order the case's samples are expected to converge at (verify fem's, for the lung "
                             "cases 2), for the estimate from the levels' means")
    args = parser.parse_args()

    h, own, meshes, matched, left_out = level_meshes(args.study, args.case, args.jittered)
    if len(h) < 3:
        raise SystemExit(f"{args.study}: {args.case} has {len(h)} solved levels; an order needs 3")
    levels = list(zip(h, own))
    for path, size in left_out:
        print(f"{path}: level {size:g} mm is more than 5 % from every level of {args.study}: left out")
    distances = [(path, size, h[l], u - own[l]) for path, size, l, u in matched]
    peak = max(np.linalg.norm(levels[-1][1], axis=1))

    print(f"{args.case}: {len(h)} levels, peak sample displacement {peak:.4f} mm")
    if distances:
        print("| jittered study | its level | the study's level | RMS distance | each sample's distance [um] |")
        print("|---|---|---|---|---|")
    for path, size, level, d in distances:
        each = ", ".join(f"{x * 1e3:.1f}" for x in np.linalg.norm(d, axis=1))
        print(f"| {path} | {size:g} mm | {level:g} mm | {rms(d) * 1e3:.2f} um ({rms(d) / peak * 100:.3f} %) | {each} |")
    print("| level | meshes | noise (RMS) | change to the next level (RMS) | noise / change |")
    print("|---|---|---|---|---|")
    for l, group in enumerate(meshes):
        change = rms(levels[l + 1][1] - levels[l][1]) if l + 1 < len(h) else None
        change_text = f"{change * 1e3:.2f} um" if change is not None else ""
        if len(group) < 2:
            print(f"| {h[l]:g} mm | 1 | not measured | {change_text} | |")
            continue
        mean = sum(group) / len(group)
        noise = math.sqrt(sum(rms(u - mean) ** 2 for u in group) / (len(group) - 1))
        ratio = f"{noise / change:.2f}" if change else ""
        print(f"| {h[l]:g} mm | {len(group)} | {noise * 1e3:.2f} um ({noise / peak * 100:.3f} %) | {change_text} | "
              f"{ratio} |")

    level_means = means(meshes)
    # How far the means' order itself rests on each mesh: the means with one mesh left out at each level (a jackknife;
    # a level with fewer than three meshes keeps them all).
    leave_one_out = [[sum(g[:k] + g[k + 1:]) / (len(g) - 1) for k in range(len(g))] if len(g) >= 3 else [mean]
                     for g, mean in zip(meshes, level_means)]
    print("| levels | observed order (the study's meshes) | range over the meshes' combinations | order of the means | "
          "order of the means with one mesh left out at each level (range) |")
    print("|---|---|---|---|---|")
    for l in range(2, len(h)):
        ratio = ratio_ending_at(h, l)
        own = order(levels[l - 2][1], levels[l - 1][1], levels[l][1], ratio)
        combos = [order(a, b, c, ratio) for a, b, c in itertools.product(meshes[l - 2], meshes[l - 1], meshes[l])]
        spread = f"{min(combos):.2f} to {max(combos):.2f} ({len(combos)})" if len(combos) > 1 else "one mesh each"
        jack = [order(a, b, c, ratio) for a, b, c in itertools.product(*leave_one_out[l - 2:l + 1])]
        jack_text = f"{min(jack):.2f} to {max(jack):.2f} ({len(jack)})" if len(jack) > 1 else "fewer than three meshes"
        print(f"| {h[l - 2]:g} / {h[l - 1]:g} / {h[l]:g} mm | {own:.2f} | {spread} | "
              f"{order(*level_means[l - 2:l + 1], ratio):.2f} | {jack_text} |")
    print_estimate_of_the_means(h, level_means, args.expected_order)
    print("An order of 0.00 means the changes did not decrease. Levels with one mesh add no noise to the range, so "
          "the range is a lower bound on the spread where a level was not jittered.")


if __name__ == "__main__":
    main()
