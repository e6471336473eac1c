#!/usr/bin/env bash
# Quick-start command 1: install what is missing, build, and run the main job (the paper reproduction
# on the built-in lung). Results go to results/.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install_dependencies.sh
scripts/build.sh
# A subcommand exists when `tissue --help` lists it (`tissue X --help` exits 0 even for an unknown X).
has_command() { build/bin/tissue "$@" --help 2>/dev/null | grep -qE "^Usage: .*tissue $* "; }
if has_command reproduce; then
  build/bin/tissue reproduce --out results/reproduce
else
  echo "[reproduce] 'tissue reproduce' is not implemented yet (it needs the comparator);"
  echo "[reproduce] running what exists: both shipped cases through each available model."
  for case in configs/lung_small.json configs/lung_large.json; do
    name=$(basename "$case" .json)
    build/bin/tissue case check "$case"
    build/bin/tissue case mesh "$case" --out "results/$name/geometry"
    for model in fem meshless; do
      if has_command solve "$model"; then
        build/bin/tissue solve "$model" "$case" --out "results/$name/$model"
      fi
    done
  done
fi
