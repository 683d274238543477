#!/usr/bin/env bash
# bench.sh: regenerates docs/RESULTS.md and docs/results/ from scratch: the walkthrough, the headline
# (raycache_walkthrough_bench: camera paths with persisting caches, and start-up time and memory), the
# thesis's experiments on the Embree tracer (raycache_bench: Table 5.2 on grid-N and behind-N, Table 5.3,
# Figure 5.9, quality), Table 5.1 and the ray-space hierarchy against a per-frame BVH on the Vulkan tracer
# (raycache_vulkan_bench, raycache_rsh_bench; on lavapipe where there is no GPU), the Vulkan tracer's single
# image and resting cubes (bench/vulkan_single_image.py, bench/vulkan_resting.py), the Embree tracer with
# costlier rays (bench/costly_rays.py), the micro-benchmarks
# (raycache_micro_bench), and the plots.
#   scripts/bench.sh           the full run (about 45 minutes on 2 cores)
#   scripts/bench.sh --quick   small images, one round: checks the pipeline, not results (writes to build-bench/quick)
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
bash scripts/install-deps.sh --bench

generator=()
if command -v ninja >/dev/null 2>&1 && [[ ! -f build-bench/CMakeCache.txt ]]; then generator=(-G Ninja); fi
cmake -S . -B build-bench "${generator[@]}" -DCMAKE_BUILD_TYPE=Release -DRAYCACHE_BUILD_TESTS=OFF
cmake --build build-bench -j"$(nproc)"

# A Vulkan benchmark (raycache_vulkan_bench, raycache_rsh_bench): exit 77 = no Vulkan device; RESULTS.md
# is then made without its section.
vulkan_bench() {
  local name=$1 rc=0
  shift
  if [[ -x build-bench/bench/$name ]]; then
    build-bench/bench/$name "$@" || rc=$?
    if [[ $rc -eq 77 ]]; then echo "bench.sh: no Vulkan device: no $name section"; rc=0; fi
  else
    echo "bench.sh: $name was not built (no Vulkan headers or glslangValidator): no section of it"
  fi
  return $rc
}

if [[ "${1:-}" == "--quick" ]]; then
  out=build-bench/quick
  rm -rf "$out"
  build-bench/bench/raycache_walkthrough_bench --quick --out "$out"
  build-bench/bench/raycache_dynamic_bench --quick --out "$out"
  build-bench/bench/raycache_bench --quick --out "$out"
  vulkan_bench raycache_vulkan_bench --quick --out "$out"
  vulkan_bench raycache_rsh_bench --quick --out "$out"
  build-bench/bench/raycache_micro_bench --benchmark_min_time=0.01 --benchmark_out="$out/micro.json" --benchmark_out_format=json
  /usr/bin/python3 bench/make_results.py "$out" "$out/RESULTS.md"
  exit 0
fi

out=docs/results
# Only what this script writes (the files at the top of docs/results): its folders hold runs made by hand,
# on lent GPU machines or the Vulkan tracer's own options, that this machine may not be able to repeat.
mkdir -p "$out"
find "$out" -maxdepth 1 -type f -delete
build-bench/bench/raycache_walkthrough_bench --out "$out"
build-bench/bench/raycache_dynamic_bench --out "$out"
# Table 5.2 on grid-N and behind-N (N = 1..32) at the thesis's 1024x1024, 9 rounds: about 4 minutes.
build-bench/bench/raycache_bench --out "$out"
vulkan_bench raycache_vulkan_bench --out "$out"
# dynamic-64, moving spheres analytic, then tessellated up to 145 k triangles, 128x128 (about 5 minutes on lavapipe).
vulkan_bench raycache_rsh_bench --out "$out"
# The Vulkan tracer's single image with and without a warm-up pass (about 2 minutes on lavapipe), and its
# walkthroughs with and without resting cubes (about 6 minutes).
if [[ -x build-bench/examples/vulkan_whitted/raycache_vulkan_whitted ]]; then
  /usr/bin/python3 bench/vulkan_single_image.py build-bench/examples/vulkan_whitted/raycache_vulkan_whitted "$out/vulkan_single_image"
  /usr/bin/python3 bench/vulkan_resting.py build-bench/examples/vulkan_whitted/raycache_vulkan_whitted "$out/vulkan_resting"
fi
# Where the cache pays as rays get costlier: soft shadows of 1, 4 and 16 shadow rays (about 13 minutes).
/usr/bin/python3 bench/costly_rays.py build-bench/examples/embree_whitted/raycache_embree_whitted "$out/costly_rays" 2
build-bench/bench/raycache_micro_bench --benchmark_min_time=0.5 --benchmark_repetitions=3 \
  --benchmark_report_aggregates_only=true --benchmark_out="$out/micro.json" --benchmark_out_format=json
# Debian's python: the one python3-matplotlib installs into.
/usr/bin/python3 bench/make_results.py "$out" docs/RESULTS.md
