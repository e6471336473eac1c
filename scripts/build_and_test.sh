#!/usr/bin/env bash
# Quick-start command 2: install what is missing, build, and run every test suite with ctest.
# Suites labelled `long` run too (CI runs everything); pass -LE long to skip them locally.
# Then a short fuzzing run (label `fuzz`, TISSUE_FUZZ_SECONDS each, default 20 s) of the case and STL readers
# in build-fuzz/ (Clang, libFuzzer + ASan/UBSan; README "Sanitizers and fuzzing"); TISSUE_FUZZ_SECONDS=0 skips it.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install_dependencies.sh
scripts/build.sh
jobs=$(nproc 2>/dev/null || echo 2)
ctest --test-dir build --output-on-failure -j"$jobs" "$@"

fuzz_seconds=${TISSUE_FUZZ_SECONDS:-20}
if [ "$fuzz_seconds" -gt 0 ]; then
  mkdir -p build-fuzz
  log=build-fuzz/build.log
  if ! { cmake -S . -B build-fuzz -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_COMPILER=clang++ -DTISSUE_FUZZ=ON \
               -DTISSUE_FUZZ_SECONDS="$fuzz_seconds" && cmake --build build-fuzz -j"$jobs"; } > "$log" 2>&1; then
    cat "$log" >&2
    echo "build_and_test: the fuzzing build failed (log above, kept in $log)" >&2
    exit 1
  fi
  # The fuzzers' own output is long: keep it in a file, print each target's counts, and all of it on a failure.
  if ! ctest --test-dir build-fuzz -L fuzz -V > build-fuzz/fuzz.log 2>&1; then
    cat build-fuzz/fuzz.log >&2
    echo "build_and_test: a fuzz target found a crash (reproducers in build-fuzz/fuzz/artifacts/)" >&2
    exit 1
  fi
  grep -E "Test command|stat::number_of_executed_units|stat::peak_rss_mb|tests passed" build-fuzz/fuzz.log
fi
