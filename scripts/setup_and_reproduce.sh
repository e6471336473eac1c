#!/usr/bin/env bash
# Quick-start command 1: install what is missing, build, and run the main job (the paper reproduction
# on the built-in lung). Results go to results/.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install_dependencies.sh
scripts/build.sh
if build/bin/tissue reproduce --help >/dev/null 2>&1; then
  build/bin/tissue reproduce --out results/reproduce
else
  echo "[reproduce] 'tissue reproduce' is not implemented yet (it needs the comparator);"
  echo "[reproduce] running what exists: both shipped cases through each available model."
  for case in configs/lung_small.json configs/lung_large.json; do
    name=$(basename "$case" .json)
    build/bin/tissue case check "$case"
    build/bin/tissue case mesh "$case" --out "results/$name/geometry"
    for model in fem meshless; do
      if build/bin/tissue solve "$model" --help >/dev/null 2>&1; then
        build/bin/tissue solve "$model" "$case" --out "results/$name/$model"
      fi
    done
  done
fi
