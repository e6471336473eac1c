#!/usr/bin/env python3
"""Summarise the FEM scaling benchmark (bench_fem, BM_FemBlock) and estimate the largest mesh per node.

  scripts/fem_scaling_summary.py results/bench/bench_fem_scaling.json [more.json ...] [--node-memory-gb 64 128 256]
                                 [--processes-per-node 64]

Reads Google Benchmark JSON reports of build/bin/bench_fem and prints, from the numbers in them only:
  * per block size: DOFs, Newton iterations, seconds per Newton iteration, peak memory and bytes per DOF, for
    one process and (when measured in the same run) for all the processes of the mpirun job, with the speed-up;
  * the growth exponent of the time per Newton iteration against the DOFs (least squares on log-log, AMG on one
    process), overall and between neighbouring sizes;
  * memory = fixed + per_dof * DOFs (least squares over the one-process AMG runs), and from it the largest
    number of DOFs a node of the given memory holds with the given MPI processes, keeping 10 % for the system.
The BM_LungSmall pair (AMG against the direct solver, same run) is summarised too when present.
"""
import argparse
import json
import math
import sys


def load(paths):
    runs = []
    for path in paths:
        try:
            with open(path) as f:
                report = json.load(f)
        except (OSError, json.JSONDecodeError) as e:
            sys.exit(f"{path}: cannot read a Google Benchmark JSON report ({e})")
        for b in report.get("benchmarks", []):
            if b.get("error_occurred"):
                continue
            b["_file"] = path
            runs.append(b)
    return runs


def fit_line(xs, ys):
    """Least-squares y = a + b x."""
    n = len(xs)
    mx, my = sum(xs) / n, sum(ys) / n
    sxx = sum((x - mx) ** 2 for x in xs)
    b = sum((x - mx) * (y - my) for x, y in zip(xs, ys)) / sxx
    return my - b * mx, b


def block_runs(runs, prefix):
    out = {}
    for b in runs:
        name = b["name"]
        if name.startswith(prefix + "/"):
            n = int(name[len(prefix) + 1:].split("/")[0])
            out[n] = b
    return dict(sorted(out.items()))


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("reports", nargs="+")
    parser.add_argument("--node-memory-gb", type=float, nargs="+", default=[64.0, 128.0, 256.0])
    parser.add_argument("--processes-per-node", type=int, default=1,
                        help="MPI processes per node, each with the fixed memory of one process")
    args = parser.parse_args()
    runs = load(args.reports)

    lung = {b["name"].split("/")[1]: b for b in runs if b["name"].startswith("BM_LungSmall/")}
    if "amg" in lung and "direct" in lung:
        a, d = lung["amg"], lung["direct"]
        print("lung_small (configs/lung_small.json), whole run, same benchmark run:")
        for label, b in (("AMG", a), ("direct", d)):
            print(f"  {label:6s}: {b['dofs']:.0f} DOFs, {b['real_time'] / 1e3:.1f} s wall, {b['cpu_time'] / 1e3:.1f} s CPU, "
                  f"linear solves {b['linear_solve_s']:.1f} s, assembly {b['assembly_s']:.1f} s, "
                  f"Newton {b['newton_iterations']:.0f}, GMRES {b['gmres_iterations']:.0f}, peak {b['peak_memory_MB']:.0f} MB")
        print(f"  speed-up AMG over direct: {d['real_time'] / a['real_time']:.2f}x wall, "
              f"{d['cpu_time'] / a['cpu_time']:.2f}x CPU, "
              f"{d['linear_solve_s'] / a['linear_solve_s']:.2f}x in the linear solves")
        if "max_sample_difference_to_amg" in d:
            print(f"  largest sample difference direct vs AMG (relative): {d['max_sample_difference_to_amg']:.2e}")
        print()

    one = block_runs(runs, "BM_FemBlock/amg/one_process")
    direct = block_runs(runs, "BM_FemBlock/direct/one_process")
    together = block_runs(runs, "BM_FemBlock/amg/all_processes")
    if not one:
        return
    print("BM_FemBlock (lung material block, 2 steps), AMG:")
    print("   n       DOFs  Newton  s/Newton(1p)  peak MB(1p)  B/DOF(1p)  s/Newton(Np)  Np  speed-up  direct s/Newton")
    for n, b in one.items():
        line = (f"{n:4d} {b['dofs']:10.0f} {b['newton_iterations']:7.0f} {b['s_per_newton_iteration']:13.3f}"
                f" {b['peak_memory_MB']:12.0f} {b['bytes_per_dof']:10.0f}")
        t = together.get(n)
        if t:
            line += (f" {t['s_per_newton_iteration']:13.3f} {t['processes']:3.0f}"
                     f" {b['s_per_newton_iteration'] / t['s_per_newton_iteration']:9.2f}")
        else:
            line += " " * 36
        if n in direct:
            line += f" {direct[n]['s_per_newton_iteration']:16.3f}"
        print(line)

    sizes = list(one.values())
    if len(sizes) >= 2:
        lx = [math.log(b["dofs"]) for b in sizes]
        ly = [math.log(b["s_per_newton_iteration"]) for b in sizes]
        _, slope = fit_line(lx, ly)
        print(f"\ntime per Newton iteration ~ DOFs^{slope:.2f} (least squares, {sizes[0]['dofs']:.0f} to "
              f"{sizes[-1]['dofs']:.0f} DOFs, one process)")
        for p, q in zip(sizes, sizes[1:]):
            local = math.log(q["s_per_newton_iteration"] / p["s_per_newton_iteration"]) / math.log(q["dofs"] / p["dofs"])
            print(f"  {p['dofs']:.0f} -> {q['dofs']:.0f} DOFs: exponent {local:.2f}")
        fixed_mb, per_dof_mb = fit_line([b["dofs"] for b in sizes], [b["peak_memory_MB"] for b in sizes])
        per_dof_bytes = per_dof_mb * 1024.0 * 1024.0
        print(f"\npeak memory ~ {fixed_mb:.0f} MB + {per_dof_bytes:.0f} bytes/DOF (least squares, one process)")
        p = args.processes_per_node
        for gb in args.node_memory_gb:
            usable_mb = 0.9 * gb * 1024.0
            print(f"  a {gb:.0f} GB node with {p} MPI process{'es' if p > 1 else ''} holds about "
                  f"{(usable_mb - p * fixed_mb) / per_dof_mb / 1e6:.1f} M DOFs (90 % of its memory)")


if __name__ == "__main__":
    main()
