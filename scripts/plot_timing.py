#!/usr/bin/env python3
"""Grouped bars of the time per deformation result against the force (the analogue of the paper's Fig. 9).

Usage: plot_timing.py TIMING_JSON OUT_PNG

TIMING_JSON is the timing.json of `tissue reproduce`: one row per force with, per model, the wall time of one
deformation result (or the error that stopped it). Failed runs are drawn as missing bars. Needs Debian's
python3-matplotlib (scripts/install_dependencies.sh).
"""
import json
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

MODELS = [("meshless", "meshless, full solve (enrichment)", "tab:blue"), ("fem", "FEM reference", "black")]


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    with open(sys.argv[1]) as f:
        timing = json.load(f)
    rows = timing["rows"]
    forces = [r["force_N"] for r in rows]
    width = 0.8 / len(MODELS)
    fig, ax = plt.subplots(figsize=(8, 4.5))
    for k, (key, label, colour) in enumerate(MODELS):
        xs = [i + (k - (len(MODELS) - 1) / 2) * width for i in range(len(rows))]
        ys = [r[key].get("seconds", 0.0) for r in rows]
        ax.bar(xs, ys, width, label=label, color=colour)
    ax.set_xticks(range(len(rows)))
    ax.set_xticklabels([f"{f:.2f}" for f in forces])
    ax.set_xlabel("force [N]")
    ax.set_ylabel("time per deformation result [s]")
    ax.set_title(f"{timing['config']}: {timing['steps']} time step(s) per result")
    ax.legend()
    fig.tight_layout()
    fig.savefig(sys.argv[2], dpi=120)


if __name__ == "__main__":
    main()
