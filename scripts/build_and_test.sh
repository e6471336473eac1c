#!/usr/bin/env bash
# Quick-start command 2: install what is missing, build, and run every test suite with ctest.
# Suites labelled `long` run too (CI runs everything); pass -LE long to skip them locally.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install_dependencies.sh
scripts/build.sh
jobs=$(nproc 2>/dev/null || echo 2)
ctest --test-dir build --output-on-failure -j"$jobs" "$@"
