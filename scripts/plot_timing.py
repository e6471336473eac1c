#!/usr/bin/env python3
"""Grouped bars of the time per deformation result against the force (the analogue of the paper's Fig. 9).

Usage: plot_timing.py TIMING_JSON OUT_PNG

TIMING_JSON is the timing.json of `tissue reproduce`: one row per force with, per model, the wall time of one
deformation result (or the error that stopped it), and the surrogate's query time per force when it was measured.
Failed runs are drawn as missing bars. The time axis is logarithmic: a surrogate query takes microseconds, a full
solve seconds. Needs Debian's python3-matplotlib (scripts/install_dependencies.sh).
"""
import json
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

COLOURS = ["black", "tab:blue", "tab:green", "tab:red", "tab:purple", "tab:brown"]


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    with open(sys.argv[1]) as f:
        timing = json.load(f)
    # One bar per timed model (the timing case's /compare list, in its order), then the surrogate's query.
    rows = [dict(r["models"], force_N=r["force_N"]) for r in timing["rows"]]
    models = [(m["name"], f"{m['name']} ({m['role'].split(':')[0]}), full solve", COLOURS[k % len(COLOURS)])
              for k, m in enumerate(timing["models"])]
    surrogate = timing.get("surrogate", {})
    if surrogate.get("status") == "measured":
        for r, s in zip(rows, surrogate["rows"]):
            r["surrogate"] = s
        models.append(("surrogate", "surrogate query (Levenberg-Marquardt fit)", "tab:orange"))
    forces = [r["force_N"] for r in rows]
    width = 0.8 / len(models)
    fig, ax = plt.subplots(figsize=(8, 4.5))
    for k, (key, label, colour) in enumerate(models):
        xs = [i + (k - (len(models) - 1) / 2) * width for i in range(len(rows))]
        ys = [r.get(key, {}).get("seconds", 0.0) for r in rows]
        ax.bar(xs, ys, width, label=label, color=colour)
    ax.set_yscale("log")
    ax.set_xticks(range(len(rows)))
    ax.set_xticklabels([f"{f:.2f}" for f in forces])
    ax.set_xlabel("force [N]")
    ax.set_ylabel("time per deformation result [s]")
    ax.set_title(f"{os.path.basename(timing['config'])}: {timing['steps']} time step(s) per result")
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.14), ncol=len(models), frameon=False)
    fig.tight_layout()
    fig.savefig(sys.argv[2], dpi=120, bbox_inches="tight")


if __name__ == "__main__":
    main()
