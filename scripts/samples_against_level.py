#!/usr/bin/env python3
"""How far a solve's samples.csv lies from one level of a mesh study: the same mesh solved another way.

`tissue solve fem` under `mpirun -np N` on a case at one of a study's mesh sizes meshes exactly that level's mesh
(Gmsh is deterministic), so its samples must equal the level's, which `tissue verify fem` solved on one process, to
the solver's tolerances. This prints their distance: relative (over all sample displacements), RMS per sample and
the largest component, in mm (results/verify/mpi_level/README.md).

Usage: scripts/samples_against_level.py SAMPLES.csv STUDY.json CASE SIZE_MM
"""
import argparse
import csv

import numpy as np

from mesh_study_io import read_study, rms, solved


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("samples_csv")
    parser.add_argument("study")
    parser.add_argument("case")
    parser.add_argument("size_mm", type=float)
    a = parser.parse_args()
    levels = [level for level in solved(read_study(a.study, a.case)) if abs(level["mesh_size_mm"] - a.size_mm) < 1e-9]
    if not levels:
        raise SystemExit(f"{a.study}: no solved level of {a.case} at {a.size_mm:g} mm")
    level = levels[0]
    with open(a.samples_csv) as f:
        rows = sorted(csv.DictReader(f), key=lambda r: int(r["sample"]))
    u = np.array([[float(r["ux_mm"]), float(r["uy_mm"]), float(r["uz_mm"])] for r in rows])
    v = np.array(level["sample_displacements_mm"])
    if u.shape != v.shape:
        raise SystemExit(f"{a.samples_csv}: {len(u)} samples, the study's level {len(v)}")
    d = u - v
    print(f"{a.case} at {a.size_mm:g} mm ({level.get('n_dofs', '?')} DOFs in the study, {level.get('seconds', 0):.0f} s "
          f"there): relative {np.linalg.norm(d) / np.linalg.norm(v):.3g}, RMS per sample "
          f"{rms(d):.3g} mm, largest component {np.abs(d).max():.3g} mm")


if __name__ == "__main__":
    main()
