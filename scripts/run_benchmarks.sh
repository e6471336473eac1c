#!/usr/bin/env bash
# Run the Google Benchmark programs and keep their JSON reports in results/bench/ (docs/PERFORMANCE.md).
#   scripts/run_benchmarks.sh            all: bench_mls, bench_efg, bench_fem, bench_cut, bench_surrogate, bench_fem_preconditioners
#                                        (hours: bench_fem alone takes over an hour on 2 cores)
#   scripts/run_benchmarks.sh bench_fem  only the named ones
#   BENCH_FILTER='/32/' BENCH_SUFFIX=_32k scripts/run_benchmarks.sh bench_efg
#                                        only the matching benchmarks, into results/bench/bench_efg_32k.json
# bench_fem runs under `mpirun -np 2` (TISSUE_BENCH_PROCESSES), so its one- and two-process figures come from
# the same run; the others run as one process, except bench_efg with EFG_BENCH_PROCESSES=N: under `mpirun -np N`
# (one OpenMP thread each), its Krylov solves distributed over the N processes.
# Each report is written to a temporary file and moved into place only when its benchmark finished, so an
# interrupted run never leaves a half-written report. Speed is compared as ratios within one run.
set -euo pipefail
cd "$(dirname "$0")/.."
if [[ "${1:-}" == "-h" || "${1:-}" == "--help" ]]; then
  sed -n '2,12p' "$0" | sed 's/^# \{0,1\}//'
  exit 0
fi
benches=("$@")
[[ ${#benches[@]} -eq 0 ]] && benches=(bench_mls bench_efg bench_fem bench_cut bench_surrogate bench_fem_preconditioners)
# OpenMPI: allow root (containers, CI) and more processes than cores.
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_btl_vader_single_copy_mechanism=none
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DTISSUE_BUILD_BENCHMARKS=ON >/dev/null
cmake --build build -j"$(nproc 2>/dev/null || echo 2)" --target "${benches[@]}"
mkdir -p results/bench
for b in "${benches[@]}"; do
  echo "== $b" >&2
  tmp=$(mktemp "results/bench/.${b}.XXXXXX")
  out="results/bench/${b}${BENCH_SUFFIX:-}.json"
  launcher=()
  [[ "$b" == bench_fem ]] && launcher=(mpirun -np "${TISSUE_BENCH_PROCESSES:-2}" --oversubscribe)
  [[ "$b" == bench_efg && -n "${EFG_BENCH_PROCESSES:-}" ]] &&
    launcher=(mpirun -np "$EFG_BENCH_PROCESSES" --oversubscribe -x OMP_NUM_THREADS=1)
  if "${launcher[@]}" build/bin/"$b" --benchmark_out="$tmp" --benchmark_out_format=json \
      --benchmark_filter="${BENCH_FILTER:-.}"; then
    mv "$tmp" "$out"
    echo "wrote $out" >&2
  else
    rm -f "$tmp"
    echo "$b failed; $out left unchanged" >&2
    exit 1
  fi
done
