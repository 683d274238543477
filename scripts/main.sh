#!/usr/bin/env bash
# main.sh: installs the dependencies, builds the Embree example tracer (Release, build-release/) and runs
# the main job: behind-32 (thesis Figure 5.2) rendered with the cache off and with each technique, frame
# by frame from the same viewpoint, printing per frame the speed-up over the cache off and the PSNR
# against the uncached frame. PNGs and difference images go to out/main/.
# Arguments are passed to every tracer run (for example: --size 512x512 --face-size 256).
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

bash scripts/install-deps.sh

generator=()
if [[ ! -f build-release/CMakeCache.txt ]] && command -v ninja >/dev/null 2>&1; then generator=(-G Ninja); fi
cmake -S . -B build-release "${generator[@]}" -DCMAKE_BUILD_TYPE=Release -DRAYCACHE_BUILD_TESTS=OFF -DRAYCACHE_BUILD_BENCHMARKS=OFF
cmake --build build-release --target raycache_embree_whitted -j"$(nproc 2>/dev/null || echo 2)"

tracer=build-release/examples/embree_whitted/raycache_embree_whitted
common=(--scene behind-32 --size 1024x1024 --face-size 512 --path fixed --frames 5 --compare)
echo
echo "===== CCT: colour caching (frame 0 is cold: every ray traced and stored) ====="
"$tracer" "${common[@]}" --cache cct --out out/main/cct "$@"
echo
echo "===== CDCT: colour + depth, relief search over a min-depth pyramid ====="
"$tracer" "${common[@]}" --cache cdct --out out/main/cdct "$@"
echo
echo "Images: out/main/{cct,cdct}/ (frames, uncached references, difference images: blue = equal, red = different)."
echo "The same on Vulkan (lavapipe): cmake --build build-release --target raycache_vulkan_whitted, then"
echo "  RCX_VULKAN_VALIDATION=0 build-release/examples/vulkan_whitted/raycache_vulkan_whitted --scene behind-32 --size 512x512 --path fixed --frames 4 --cache cct --compare [--hybrid]"
echo "Full benchmarks (thesis Tables 5.1 on Vulkan, 5.2, 5.3, Figure 5.9, quality, memory): scripts/bench.sh -> docs/RESULTS.md"
