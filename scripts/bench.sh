#!/usr/bin/env bash
# bench.sh: regenerates docs/RESULTS.md and docs/results/ from scratch: the thesis's experiments on the
# Embree tracer (raycache_bench), the micro-benchmarks (raycache_micro_bench), and the plots.
#   scripts/bench.sh           the full run (about 5 minutes on 2 cores)
#   scripts/bench.sh --quick   small images, one round: checks the pipeline, not results (writes to build-bench/quick)
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
bash scripts/install-deps.sh --bench

generator=()
if command -v ninja >/dev/null 2>&1 && [[ ! -f build-bench/CMakeCache.txt ]]; then generator=(-G Ninja); fi
cmake -S . -B build-bench "${generator[@]}" -DCMAKE_BUILD_TYPE=Release -DRAYCACHE_BUILD_TESTS=OFF
cmake --build build-bench --target raycache_bench raycache_micro_bench -j"$(nproc)"

if [[ "${1:-}" == "--quick" ]]; then
  out=build-bench/quick
  rm -rf "$out"
  build-bench/bench/raycache_bench --quick --out "$out"
  build-bench/bench/raycache_micro_bench --benchmark_min_time=0.01 --benchmark_out="$out/micro.json" --benchmark_out_format=json
  /usr/bin/python3 bench/make_results.py "$out" "$out/RESULTS.md"
  exit 0
fi

out=docs/results
rm -rf "$out"
mkdir -p "$out"
build-bench/bench/raycache_bench --out "$out"
build-bench/bench/raycache_micro_bench --benchmark_min_time=0.5 --benchmark_repetitions=3 \
  --benchmark_report_aggregates_only=true --benchmark_out="$out/micro.json" --benchmark_out_format=json
# Debian's python: the one python3-matplotlib installs into.
/usr/bin/python3 bench/make_results.py "$out" docs/RESULTS.md
