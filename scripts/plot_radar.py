#!/usr/bin/env python3
"""Radar diagram of the sample displacements of the three models (the paper's Figs. 7-8).

Usage: plot_radar.py SAMPLES_CSV OUT_PNG [--title TITLE]

SAMPLES_CSV is the samples.csv of `tissue compare` (one row per sample and model, eq. 33 magnitudes in mm).
One spoke per sample; one closed line per model. Flagged samples (load-patch edge or near the cut) carry a
`*` on their spoke label. Needs Debian's python3-matplotlib (scripts/install_dependencies.sh).
"""
import argparse
import csv
import math
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

STYLE = {
    "fem": dict(color="black", linestyle="-", marker="o", label="FEM reference"),
    "enrichment": dict(color="tab:blue", linestyle="--", marker="s", label="meshless, enrichment (proposed)"),
    "visibility": dict(color="tab:red", linestyle=":", marker="^", label="meshless, visibility (baseline)"),
}


def read_samples(path):
    magnitudes, flagged = {}, {}
    with open(path, newline="") as f:
        for row in csv.DictReader(f):
            sample = int(row["sample"])
            magnitudes.setdefault(row["model"], {})[sample] = float(row["magnitude_mm"])
            flagged[sample] = row["flagged"] == "1"
    return magnitudes, flagged


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("samples_csv")
    parser.add_argument("out_png")
    parser.add_argument("--title", default="")
    args = parser.parse_args()
    magnitudes, flagged = read_samples(args.samples_csv)
    samples = sorted(flagged)
    if not samples:
        sys.exit(f"{args.samples_csv}: no samples")
    angles = [2 * math.pi * k / len(samples) for k in range(len(samples))]
    fig, ax = plt.subplots(figsize=(6.5, 6.5), subplot_kw=dict(polar=True))
    for model in ["fem", "enrichment", "visibility"] + sorted(set(magnitudes) - set(STYLE)):
        if model not in magnitudes:
            continue
        values = [magnitudes[model][s] for s in samples]
        style = STYLE.get(model, dict(label=model))
        ax.plot(angles + angles[:1], values + values[:1], markersize=4, linewidth=1.5, **style)
    ax.set_xticks(angles)
    ax.set_xticklabels([f"{s}*" if flagged[s] else str(s) for s in samples])
    ax.set_rlabel_position(90)
    ax.set_ylim(bottom=0)
    title = "Sample displacement magnitude [mm] (eq. 33)"
    ax.set_title(f"{args.title}\n{title}" if args.title else title, pad=20)
    ax.legend(loc="lower center", bbox_to_anchor=(0.5, -0.2), ncol=1, frameon=False, fontsize=9)
    if any(flagged.values()):
        fig.text(0.02, 0.02, "* flagged: on the load-patch edge or near the cut", fontsize=8)
    fig.tight_layout()
    fig.savefig(args.out_png, dpi=120)


if __name__ == "__main__":
    main()
