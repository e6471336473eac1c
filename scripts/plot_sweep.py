#!/usr/bin/env python3
"""RMSE and wall time against a swept parameter, from a sweep's summary.csv (`tissue sweep`).

Usage: plot_sweep.py SUMMARY_CSV OUT_PNG --x POINTER [--with POINTER ...] [--title TITLE]

Left: the eq. 34 RMSE of each scored model (the columns MODEL_rmse_mm) against the reference; right: the wall
time of each model (fem_seconds is the reference's). With more than one swept parameter, one line per combination of the others
(--with names the pointers zipped with --x, which vary with it and so make no lines of their own). Needs Debian's
python3-matplotlib (scripts/install_dependencies.sh).
"""
import argparse
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

FIXED = {"run_id", "status"}
STYLES = ["o-", "s--", "^:", "d-.", "v--", "x:"]


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("summary_csv")
    parser.add_argument("out_png")
    parser.add_argument("--x", required=True, help="the JSON pointer of the parameter on the x axis")
    parser.add_argument("--with", dest="zipped", action="append", default=[],
                        help="a pointer zipped with --x (repeatable): it varies with x, so it is not a line of its own")
    parser.add_argument("--title", default="")
    args = parser.parse_args()
    with open(args.summary_csv, newline="") as f:
        reader = csv.DictReader(f)
        rows = [r for r in reader if r["status"] == "ok"]
        parameters = [c for c in reader.fieldnames if c.startswith("/")]
        models = [c[: -len("_rmse_mm")] for c in reader.fieldnames if c.endswith("_rmse_mm")]
    if args.x not in parameters:
        sys.exit(f"{args.summary_csv}: no parameter column {args.x}")
    others = [p for p in parameters if p != args.x and p not in args.zipped]
    try:
        for r in rows:
            r["_x"] = float(r[args.x])
    except ValueError:
        sys.exit(f"{args.x} has non-numeric values: nothing to plot")
    series = {}
    for r in rows:
        series.setdefault(tuple(r[p] for p in others), []).append(r)
    fig, (ax_rmse, ax_time) = plt.subplots(1, 2, figsize=(11, 4.5))
    for key, group in sorted(series.items()):
        group.sort(key=lambda r: r["_x"])
        xs = [r["_x"] for r in group]
        suffix = "".join(f", {p}={v}" for p, v in zip(others, key))

        def values(column):
            return [float(r[column]) if r[column] else float("nan") for r in group]

        for k, model in enumerate(models):
            ax_rmse.plot(xs, values(f"{model}_rmse_mm"), STYLES[(k + 1) % len(STYLES)], label=model + suffix)
        for k, model in enumerate(["fem"] + models):
            ax_time.plot(xs, values(f"{model}_seconds"), STYLES[k % len(STYLES)], label=model + suffix)
    xlabel = args.x + "".join(f" (with {p})" for p in args.zipped)
    ax_rmse.set_xlabel(xlabel)
    ax_rmse.set_ylabel("RMSE against the reference [mm] (eq. 34)")
    ax_rmse.set_ylim(bottom=0)
    ax_time.set_xlabel(xlabel)
    ax_time.set_ylabel("wall time of the model [s]")
    ax_time.set_ylim(bottom=0)
    for ax in (ax_rmse, ax_time):
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    if args.title:
        fig.suptitle(args.title)
    fig.tight_layout()
    fig.savefig(args.out_png, dpi=120)


if __name__ == "__main__":
    main()
