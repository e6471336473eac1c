#!/usr/bin/env python3
"""RMSE against wall time for the FEM and each meshless model from one sweep, and the time ratio at equal accuracy.

Usage: equal_accuracy.py SWEEP_DIR [--png OUT_PNG] [--md OUT_MD] [--fem-size POINTER] [--spacing POINTER]
                         [--note TEXT]

SWEEP_DIR is a `tissue sweep` folder (its summary.csv) whose runs scored the models against the extrapolated
reference (the sweep file's "compare": {"reference": "extrapolated", ...}, e.g. configs/sweeps/equal_accuracy.json):
each row then holds the FEM's own RMSE against the extrapolated samples (fem_rmse_vs_extrapolated_mm) beside each
meshless model M's (M_rmse_mm), and each model's solve time (fem_seconds, M_seconds; the geometry, built once per
run for both, is not in either).

Writes (defaults in SWEEP_DIR):
- equal_accuracy.png: RMSE (% of the extrapolated peak sample displacement, fem_peak_mm) against wall time,
  log-log, one line for the FEM (its mesh sizes) and one per meshless model (its node spacings);
- equal_accuracy.md: the points, and for each meshless point the FEM's time at the same RMSE, interpolated
  log-log between the two FEM mesh sizes whose RMSEs bracket it (linear in log time against log RMSE), and the
  ratio model time / FEM time at equal accuracy. A point whose RMSE is outside the FEM's range gets no ratio
  (no extrapolation), and the table says so.

A FEM mesh size solved in several runs has one RMSE (the same solve) and several times: the median is used, and
the table lists them all. Needs python3 and Debian's python3-matplotlib, nothing else.
"""
import argparse
import csv
import math
import os
import statistics
import sys


def number(text):
    try:
        return float(text)
    except (TypeError, ValueError):
        return None


def fmt_g(value, digits=3):
    return "–" if value is None else f"{value:.{digits}g}"


def read_points(summary_csv, fem_size, spacing):
    with open(summary_csv, newline="") as f:
        reader = csv.DictReader(f)
        fields = reader.fieldnames or []
        rows = [r for r in reader if r.get("status") == "ok"]
    if "fem_rmse_vs_extrapolated_mm" not in fields:
        sys.exit(f"{summary_csv}: no column fem_rmse_vs_extrapolated_mm (a sweep from before that column?)")
    for column in (fem_size, spacing):
        if column not in fields:
            sys.exit(f"{summary_csv}: no parameter column {column} (see --fem-size / --spacing)")
    models = [c[: -len("_rmse_mm")] for c in fields if c.endswith("_rmse_mm") and not c.startswith("fem_")]
    fem = {}  # mesh size -> {"rmse_mm", "peak_mm", "times": [...]}
    meshless = {m: [] for m in models}
    missing = []
    for r in rows:
        peak = number(r["fem_peak_mm"])
        size = number(r[fem_size])
        rmse = number(r["fem_rmse_vs_extrapolated_mm"])
        if rmse is None:
            missing.append(r["run_id"])
        else:
            level = fem.setdefault(size, {"rmse_mm": rmse, "peak_mm": peak, "times": [], "runs": []})
            if abs(level["rmse_mm"] - rmse) > 1e-9 * max(1.0, rmse):
                sys.exit(f"{summary_csv}: the FEM at {size:g} mm has two RMSEs ({level['rmse_mm']} and {rmse} mm): "
                         "not the same reference")
            level["times"].append(number(r["fem_seconds"]))
            level["runs"].append(r["run_id"])
        for m in models:
            e, t = number(r[f"{m}_rmse_mm"]), number(r[f"{m}_seconds"])
            if e is not None and t is not None:
                meshless[m].append({"spacing": number(r[spacing]), "rmse_mm": e, "peak_mm": peak, "seconds": t,
                                    "nodes": r.get("meshless_nodes", ""), "fem_size": size, "run": r["run_id"]})
    if missing:
        sys.exit(f"{summary_csv}: runs {', '.join(missing)} have no fem_rmse_vs_extrapolated_mm: they were scored "
                 "against the solved FEM, not the extrapolated samples")
    if len(fem) < 2:
        sys.exit(f"{summary_csv}: {len(fem)} FEM mesh size(s) solved; the curve needs at least 2")
    levels = []
    for size, level in fem.items():
        level["size"] = size
        level["seconds"] = statistics.median(level["times"])
        levels.append(level)
    levels.sort(key=lambda level: -level["size"])  # coarse to fine
    for points in meshless.values():
        points.sort(key=lambda p: -p["spacing"])
    return levels, meshless


def percent(rmse_mm, peak_mm):
    return 100.0 * rmse_mm / peak_mm


def fem_time_at(levels, rmse_mm):
    """The FEM's time at this RMSE, log-log between the consecutive mesh sizes that bracket it (the coarsest such
    pair, the cheaper one, when the FEM's RMSE is not monotonic); None and why when outside the FEM's range."""
    for a, b in zip(levels, levels[1:]):
        lo, hi = sorted((a["rmse_mm"], b["rmse_mm"]))
        if lo <= rmse_mm <= hi:
            if a["rmse_mm"] == b["rmse_mm"]:
                return min(a["seconds"], b["seconds"]), (a, b)
            w = (math.log(rmse_mm) - math.log(a["rmse_mm"])) / (math.log(b["rmse_mm"]) - math.log(a["rmse_mm"]))
            return math.exp(math.log(a["seconds"]) + w * (math.log(b["seconds"]) - math.log(a["seconds"]))), (a, b)
    return None, None


def write_table(path, sweep_dir, levels, meshless, note):
    lo = min(level["rmse_mm"] for level in levels)
    hi = max(level["rmse_mm"] for level in levels)
    peak = levels[0]["peak_mm"]
    out = [f"# Equal accuracy: {os.path.basename(os.path.normpath(sweep_dir))}", ""]
    out.append(f"From `{os.path.join(sweep_dir, 'summary.csv')}` by `scripts/equal_accuracy.py`. RMSE (eq. 34) against "
               f"the Richardson-extrapolated FEM samples, in mm and in % of their peak ({peak:.4f} mm); times are "
               "each model's solve (`timings.total_seconds`: set-up, assembly and solve; the geometry, built once per "
               "run for both models, is in neither).")
    if note:
        out += ["", note]
    out += ["", "## The FEM (its mesh sizes)", "",
            "| mesh size [mm] | RMSE [mm] | RMSE [% of peak] | time [s] (median) | times of its runs [s] |",
            "|---|---|---|---|---|"]
    for level in levels:
        out.append(f"| {level['size']:g} | {level['rmse_mm']:.4f} | {percent(level['rmse_mm'], peak):.3f} | "
                   f"{level['seconds']:.1f} | {', '.join(f'{t:.1f}' for t in level['times'])} |")
    out += ["", f"The FEM's range: {percent(lo, peak):.3f}–{percent(hi, peak):.3f} % "
                f"({lo:.4f}–{hi:.4f} mm). A meshless RMSE outside it gets no ratio: the FEM's time there would be an "
                "extrapolation.", ""]
    for model, points in meshless.items():
        out += [f"## {model}: time at equal accuracy", "",
                "| node spacing [mm] | nodes | RMSE [mm] | RMSE [% of peak] | time [s] | FEM levels bracketing it | "
                "FEM time at this RMSE [s] | time / FEM time |",
                "|---|---|---|---|---|---|---|---|"]
        for p in points:
            t_fem, pair = fem_time_at(levels, p["rmse_mm"])
            if t_fem is None:
                where = "below" if p["rmse_mm"] < lo else "above"
                bracket = f"outside the FEM's range ({where} it)"
                cells = "– | –"
            else:
                bracket = f"{pair[0]['size']:g} and {pair[1]['size']:g} mm"
                cells = f"{t_fem:.1f} | **{p['seconds'] / t_fem:.2f}**"
            out.append(f"| {p['spacing']:g} | {p['nodes'] or '–'} | {p['rmse_mm']:.4f} | "
                       f"{percent(p['rmse_mm'], peak):.3f} | {p['seconds']:.1f} | {bracket} | {cells} |")
        out.append("")
    with open(path, "w") as f:
        f.write("\n".join(out))


def draw(path, levels, meshless, title):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import matplotlib.ticker

    peak = levels[0]["peak_mm"]
    fig, ax = plt.subplots(figsize=(7, 5))
    by_time = sorted(levels, key=lambda level: level["seconds"])
    ax.plot([level["seconds"] for level in by_time], [percent(level["rmse_mm"], peak) for level in by_time], "s-",
            color="black", label="FEM (mesh size)")
    for level in levels:
        ax.annotate(f"{level['size']:g} mm", (level["seconds"], percent(level["rmse_mm"], peak)),
                    textcoords="offset points", xytext=(5, 5), fontsize=8)
        if len(level["times"]) > 1:  # every run's time of this level, the line through the median
            ax.plot(level["times"], [percent(level["rmse_mm"], peak)] * len(level["times"]), "|", color="gray")
    for k, (model, points) in enumerate(meshless.items()):
        points = sorted(points, key=lambda p: p["seconds"])
        ax.plot([p["seconds"] for p in points], [percent(p["rmse_mm"], peak) for p in points],
                ["o-", "^-", "d-", "v-"][k % 4], label=f"{model} (node spacing)")
        for p in points:
            ax.annotate(f"{p['spacing']:g}", (p["seconds"], percent(p["rmse_mm"], peak)), textcoords="offset points",
                        xytext=(5, -10), fontsize=8)
    ax.set_xscale("log")
    ax.set_yscale("log")
    # A narrow log range has few decade ticks: put plain-numbered ticks at round values inside the data's range.
    plain = matplotlib.ticker.FuncFormatter(lambda v, _: f"{v:g}")
    for axis, lim, mantissas in ((ax.xaxis, ax.get_xlim(), (1, 2, 3, 5)),
                                 (ax.yaxis, ax.get_ylim(), (1, 1.2, 1.4, 1.6, 1.8, 2, 2.5, 3, 4, 5, 6, 7, 8, 9))):
        ticks = [m * 10.0 ** e for e in range(-3, 6) for m in mantissas if lim[0] <= m * 10.0 ** e <= lim[1]]
        axis.set_major_locator(matplotlib.ticker.FixedLocator(ticks))
        axis.set_minor_locator(matplotlib.ticker.NullLocator())
        axis.set_major_formatter(plain)
    ax.set_xlabel("wall time of the model's solve [s]")
    ax.set_ylabel("RMSE against the extrapolated reference [% of peak]")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    if title:
        ax.set_title(title)
    fig.tight_layout()
    fig.savefig(path, dpi=120)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("sweep_dir")
    parser.add_argument("--png", help="default SWEEP_DIR/equal_accuracy.png")
    parser.add_argument("--md", help="default SWEEP_DIR/equal_accuracy.md")
    parser.add_argument("--fem-size", default="/geometry/mesh_size", help="the FEM mesh size's column")
    parser.add_argument("--spacing", default="/meshless/node_spacing", help="the node spacing's column")
    parser.add_argument("--note", default="", help="a line for the table, e.g. the machine's load during the runs")
    parser.add_argument("--title", default="")
    args = parser.parse_args()
    levels, meshless = read_points(os.path.join(args.sweep_dir, "summary.csv"), args.fem_size, args.spacing)
    md = args.md or os.path.join(args.sweep_dir, "equal_accuracy.md")
    png = args.png or os.path.join(args.sweep_dir, "equal_accuracy.png")
    write_table(md, args.sweep_dir, levels, meshless, args.note)
    draw(png, levels, meshless, args.title)
    print(f"wrote {md} and {png}")


if __name__ == "__main__":
    main()
