#!/usr/bin/env bash
# main.sh: installs the dependencies, builds the Embree example tracer (Release, build-release/) and runs
# the main job: a walkthrough of behind-32 (the camera orbits the main mirror 1 degree a frame), rendered
# with the cache off and with each technique, frame by frame, printing per frame the speed-up over the
# cache off and the PSNR against the uncached frame, then the means after frame 0 (which is cold); then
# the CCT once more with soft shadows, whose costlier rays show where the cache pays.
# PNGs and difference images go to out/main/. Arguments are passed to every tracer run
# (for example: --size 512x512 --path pan).
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

bash scripts/install-deps.sh

generator=()
if [[ ! -f build-release/CMakeCache.txt ]] && command -v ninja >/dev/null 2>&1; then generator=(-G Ninja); fi
cmake -S . -B build-release "${generator[@]}" -DCMAKE_BUILD_TYPE=Release -DRAYCACHE_BUILD_TESTS=OFF -DRAYCACHE_BUILD_BENCHMARKS=OFF
cmake --build build-release --target raycache_embree_whitted -j"$(nproc 2>/dev/null || echo 2)"

tracer=build-release/examples/embree_whitted/raycache_embree_whitted
common=(--scene behind-32 --size 1024x1024 --path orbit --step 1 --frames 16 --compare)
echo
echo "===== CCT: colour caching; adaptive cube sizes, texels at colour edges traced (frame 0 is cold);"
echo "      a cube whose hits saved less than its lookups cost (about 50% hits here) rests the next frame"
echo "      (its rays traced, a sixteenth probing, fewer while it keeps not paying) ====="
"$tracer" "${common[@]}" --cache cct --out out/main/cct "$@"
echo
echo "===== CDCT: colour + depth, secant search (a few texel reads), doubtful answers traced; rests below about 60% hits ====="
"$tracer" "${common[@]}" --cache cdct --out out/main/cdct "$@"
echo
echo "===== CCT with costlier rays: soft shadows, 16 shadow rays a shaded hit (512x512, 10 frames);"
echo "      the cache's own work stays the same, so it pays more ====="
"$tracer" "${common[@]}" --size 512x512 --frames 10 --light-samples 16 --cache cct --quiet --out out/main/cct-soft "$@"
echo
echo "Images: out/main/{cct,cdct,cct-soft}/ (frames, uncached references, difference images: blue = equal, red = different)."
echo "Other paths: --path pan or --path fixed; a single image with a warm-up pass: --frames 1 --warm-up 2."
echo "The same on Vulkan (lavapipe): cmake --build build-release --target raycache_vulkan_whitted, then"
echo "  RCX_VULKAN_VALIDATION=0 build-release/examples/vulkan_whitted/raycache_vulkan_whitted --scene behind-32 --size 512x512 --path orbit --frames 4 --cache cct --compare [--hybrid]"
echo "Full benchmarks (the walkthrough table, costlier rays, thesis Tables 5.1-5.3, Figure 5.9, memory): scripts/bench.sh -> docs/RESULTS.md"
