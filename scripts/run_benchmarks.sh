#!/usr/bin/env bash
# Run the Google Benchmark programs and keep their JSON reports in results/bench/ (docs/PERFORMANCE.md).
#   scripts/run_benchmarks.sh            all four: bench_mls, bench_efg, bench_fem, bench_surrogate (about 25 min on 2 cores)
#   scripts/run_benchmarks.sh bench_fem  only the named ones
# Each report is written to a temporary file and moved into place only when its benchmark finished, so an
# interrupted run never leaves a half-written report. Speed is compared as ratios within one run.
set -euo pipefail
cd "$(dirname "$0")/.."
if [[ "${1:-}" == "-h" || "${1:-}" == "--help" ]]; then
  sed -n '2,6p' "$0" | sed 's/^# \{0,1\}//'
  exit 0
fi
benches=("$@")
[[ ${#benches[@]} -eq 0 ]] && benches=(bench_mls bench_efg bench_fem bench_surrogate)
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DTISSUE_BUILD_BENCHMARKS=ON >/dev/null
cmake --build build -j"$(nproc 2>/dev/null || echo 2)" --target "${benches[@]}"
mkdir -p results/bench
for b in "${benches[@]}"; do
  echo "== $b" >&2
  tmp=$(mktemp "results/bench/.${b}.XXXXXX")
  if build/bin/"$b" --benchmark_out="$tmp" --benchmark_out_format=json; then
    mv "$tmp" "results/bench/${b}.json"
    echo "wrote results/bench/${b}.json" >&2
  else
    rm -f "$tmp"
    echo "$b failed; results/bench/${b}.json left unchanged" >&2
    exit 1
  fi
done
