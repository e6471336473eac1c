#!/usr/bin/env python3
"""How much the meshless model's sample displacements change between the node clouds of a sweep.

Reads a `tissue sweep` folder whose parameters include /meshless/node_spacing (docs/EXPERIMENTS.md, "The EFG
convergence study on the lung") and prints, for each combination of the other parameters, the change of all the
enrichment model's sample displacements from one spacing to the next finer one, relative to the finer cloud's
(the measure `tissue verify fem` uses for the FEM's levels), beside each run's RMSE against the reference.

    python3 scripts/efg_sample_change.py results/sweeps/efg_convergence
"""
import csv
import math
import sys
from collections import defaultdict
from pathlib import Path

SPACING = "/meshless/node_spacing"
MODEL = "enrichment"


def sample_vectors(run_folder: Path):
    """The model's displacement vectors [mm], in sample order."""
    rows = {}
    with open(run_folder / "samples.csv", newline="") as f:
        for row in csv.DictReader(f):
            if row["model"] == MODEL:
                rows[int(row["sample"])] = [float(row[k]) for k in ("ux_mm", "uy_mm", "uz_mm")]
    return [rows[i] for i in sorted(rows)]


def relative_change(coarse, fine):
    diff = math.sqrt(sum((a - b) ** 2 for u, v in zip(coarse, fine) for a, b in zip(u, v)))
    norm = math.sqrt(sum(b * b for v in fine for b in v))
    return diff / norm


def main(argv):
    if len(argv) != 2 or argv[1] in ("-h", "--help"):
        print(__doc__.strip())
        return 0 if len(argv) == 2 else 2
    sweep = Path(argv[1])
    summary = sweep / "summary.csv"
    if not summary.is_file():
        print(f"error: {summary} not found: run the sweep first", file=sys.stderr)
        return 1
    with open(summary, newline="") as f:
        runs = [r for r in csv.DictReader(f)]
    if not runs or SPACING not in runs[0]:
        print(f"error: {summary}: the sweep has no parameter {SPACING}", file=sys.stderr)
        return 1
    others = [k for k in runs[0] if k.startswith("/") and k != SPACING]
    groups = defaultdict(list)
    for r in runs:
        if r["status"] != "ok":
            continue
        groups[tuple(r[k] for k in others)].append(r)
    header = [*others, "node spacing [mm]", "nodes", "RMSE against the reference [mm]",
              "change of the EFG samples from the previous spacing"]
    print("| " + " | ".join(header) + " |")
    print("|" + "---|" * len(header))
    for key, group in groups.items():
        group.sort(key=lambda r: -float(r[SPACING]))
        previous = None
        for r in group:
            u = sample_vectors(sweep / "runs" / r["run_id"])
            change = "" if previous is None else f"{100.0 * relative_change(previous, u):.2f} %"
            print("| " + " | ".join([*key, r[SPACING], r["meshless_nodes"],
                                       f"{float(r['enrichment_rmse_mm']):.4f}", change]) + " |")
            previous = u
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
