#!/usr/bin/env python3
"""Merge one case's mesh study from a `tissue verify fem` run into the committed results/verify/fem.{json,md}.

A study of one case (`tissue verify fem --config configs/lung_large.json --sizes ... --out DIR`) takes hours; the
committed results hold every shipped case. This replaces that case's `mesh_convergence` entry in fem.json and its
"## Mesh convergence: CASE" section in fem.md with the run's, and recomputes `reference_mesh_size_mm` over all cases
as `tissue verify fem` does (the coarsest size that converged for every case; null when one did not). The rest
(the closed-form checks, the other cases) is left as committed.

Usage: scripts/merge_mesh_study.py RUN_DIR CASE [--into results/verify]
Writes each file to a temporary sibling first and renames it over the old one, so a failure leaves the old file.
"""
import argparse
import json
import os
import re
import sys


def section(md, case):
    """The '## Mesh convergence: CASE ...' section of fem.md, up to the next '## ' heading or the end."""
    return re.search(r"(## Mesh convergence: %s \(.*?)(?=\n## |\Z)" % re.escape(case), md, re.S)


def write_atomically(path, text):
    tmp = path + ".tmp"
    with open(tmp, "w") as f:
        f.write(text)
    os.replace(tmp, path)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("run_dir", help="the --out folder of a `tissue verify fem` run (fem.json, fem.md)")
    parser.add_argument("case", help="the case name to take from it (e.g. lung_large)")
    parser.add_argument("--into", default=os.path.join(os.path.dirname(__file__), "..", "results", "verify"),
                        help="the folder of the committed fem.json and fem.md (default: results/verify)")
    a = parser.parse_args()

    run_json, run_md = os.path.join(a.run_dir, "fem.json"), os.path.join(a.run_dir, "fem.md")
    into_json, into_md = os.path.join(a.into, "fem.json"), os.path.join(a.into, "fem.md")
    with open(run_json) as f:
        run = json.load(f)
    with open(into_json) as f:
        committed = json.load(f)
    with open(run_md) as f:
        md_run = f.read()
    with open(into_md) as f:
        md_committed = f.read()

    study = run.get("mesh_convergence", {}).get(a.case)
    if study is None:
        sys.exit(f"{run_json}: no /mesh_convergence/{a.case} (the run's cases: "
                 f"{', '.join(run.get('mesh_convergence', {})) or 'none'})")
    if any("error" in level for level in study["levels"]):
        sys.exit(f"{run_json}: a level of {a.case} failed; not merged")
    if a.case not in committed.get("mesh_convergence", {}):
        sys.exit(f"{into_json}: no /mesh_convergence/{a.case} to replace")
    new_md, old_md = section(md_run, a.case), section(md_committed, a.case)
    if new_md is None or old_md is None:
        sys.exit(f"no '## Mesh convergence: {a.case}' section in {run_md if new_md is None else into_md}")

    committed["mesh_convergence"][a.case] = study
    sizes = [s["converged_mesh_size_mm"] for s in committed["mesh_convergence"].values()]
    committed["reference_mesh_size_mm"] = None if any(s is None for s in sizes) else min(sizes)
    md = md_committed[:old_md.start(1)] + new_md.group(1) + md_committed[old_md.end(1):]

    write_atomically(into_json, json.dumps(committed, indent=2, sort_keys=True) + "\n")
    write_atomically(into_md, md)
    levels = ", ".join(f"{level['mesh_size_mm']:g}" for level in study["levels"])
    print(f"merged {a.case} ({levels} mm) from {a.run_dir} into {into_json} and {into_md}")


if __name__ == "__main__":
    main()
