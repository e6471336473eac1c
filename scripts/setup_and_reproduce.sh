#!/usr/bin/env bash
# Quick-start command 1: install what is missing, build, and run the main job: the paper reproduction on the
# built-in lung (`tissue reproduce`, configs/reproduce.json). Results go to results/reproduce/.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install_dependencies.sh
scripts/build.sh
build/bin/tissue reproduce --out results/reproduce
