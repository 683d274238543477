#!/usr/bin/env bash
# gpu-bundle.sh: packs what checks RayCache's GLSL on another machine's Vulkan device (a GPU lent without
# this machine's compilers and packages) into build-bundle/: the Vulkan tests and the example tracer's
# cache tests (RelWithDebInfo, from build/), the Vulkan tracer (Release, from build-release/), their SPIR-V,
# the shared libraries they load that are not the C and C++ runtimes, the validation layer, and run.sh, which runs the tests and the
# tracer's walkthroughs there and writes their output to the folder it is given (default: ./gpu-results).
# Build first: the README's test command (build/) and the Vulkan tracer (build-release/). The bundle is
# about 24 MiB; libraries the other machine's driver needs (glvnd's dispatch library for NVIDIA's) are
# carried too and used only where that machine lacks them.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
out=build-bundle
tracer=build-release/examples/vulkan_whitted/raycache_vulkan_whitted
for f in "$tracer" build/tests/vulkan/raycache_test_vulkan_face build/tests/example_vulkan/raycache_test_example_vulkan_cache; do
  [[ -x $f ]] || { echo "gpu-bundle.sh: $f is missing: build it first (README)" >&2; exit 1; }
done
rm -rf "$out" && mkdir -p "$out"/{bin,tests,shaders/tracer,shaders/tests,lib,lib-fallback,layers}
cp "$tracer" "$out/bin/"
cp build-release/examples/vulkan_whitted/shaders/*.spv "$out/shaders/tracer/"
cp build/tests/vulkan/shaders/*.spv "$out/shaders/tests/"
for t in build/tests/vulkan/raycache_test_vulkan_* build/tests/example_vulkan/raycache_test_example_vulkan_{cache,whitted}; do
  [[ $t == *.cmake ]] || strip -o "$out/tests/$(basename "$t")" "$t"
done
# Every library the programs load but the C and C++ runtimes, which the other machine has (newer ones serve
# older programs; an older libstdc++ forced on it could keep its Vulkan driver from loading).
ldd "$out"/bin/* "$out"/tests/* | awk '/=> \// {print $3}' | sort -u |
  grep -vE '/(libc|libm|libdl|libpthread|librt|libstdc\+\+|libgcc_s|ld-linux[^/]*)\.so' | xargs -r cp -L -t "$out/lib/"
for l in libGLdispatch.so.0 libGLX.so.0 libX11.so.6 libxcb.so.1 libXau.so.6 libXdmcp.so.6 libbsd.so.0 libmd.so.0; do
  p=$(ldconfig -p | awk -v l="$l" '$1 == l && /x86-64/ {print $NF; exit}')
  [[ -n $p ]] && cp -L "$p" "$out/lib-fallback/"
done
cat > "$out/run.sh" <<'RUN'
#!/usr/bin/env bash
# Runs the bundled Vulkan tests and the tracer's walkthroughs on this machine's Vulkan device; output in $1
# (tests.txt, tests-full.txt, summary.txt, walkthroughs.txt).
# SIZE (1024x1024) and FRAMES (20) set the walkthroughs; SKIP_TESTS=1 runs only those.
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
results=${1:-gpu-results}
mkdir -p "$results"
libraries=$(mktemp -d)
tar xJf "$here/libraries.tar.xz" -C "$libraries"
export LD_LIBRARY_PATH="$libraries/lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
ldconfig -p 2>/dev/null | grep -q libGLdispatch.so.0 || export LD_LIBRARY_PATH="$LD_LIBRARY_PATH:$libraries/lib-fallback"
[[ -z ${VK_DRIVER_FILES:-} && -f /usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json ]] &&
  export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
export RAYCACHE_TEST_SHADERS="$here/shaders/tests" RAYCACHE_VULKAN_WHITTED_SHADERS="$here/shaders/tracer"
# The tests run with the carried validation layer (any error it reports fails them); the walkthroughs without.
export VK_LAYER_PATH="$libraries/layers${VK_LAYER_PATH:+:$VK_LAYER_PATH}"
command -v nvidia-smi >/dev/null && nvidia-smi --query-gpu=name,driver_version --format=csv,noheader | tee "$results/device.txt"
run_log=$(mktemp)
for t in "$here"/tests/*; do
  [[ ${SKIP_TESTS:-0} == 1 ]] && break
  timeout 120 "$t" > "$run_log" 2>&1
  rc=$?
  { echo "== $(basename "$t"): exit $rc"; cat "$run_log"; } >> "$results/tests-full.txt"
  echo "$(basename "$t"): exit $rc $(grep -E '^\[doctest\] test cases' "$run_log")"
done | tee "$results/tests.txt"
# Each scene with each cache, then with every cube resting from the second frame on (--min-hit-rate 2:
# nearly every ray traced, so the cached shader's own cost shows against the uncached one).
for scene in behind-32 grid-32 reflective-32; do
  for mode in cct cdct ceiling "cct --min-hit-rate 2" "cdct --min-hit-rate 2"; do
    # shellcheck disable=SC2086 # $mode holds options
    RCX_VULKAN_VALIDATION=0 timeout 120 "$here/bin/raycache_vulkan_whitted" --scene "$scene" --size "${SIZE:-1024x1024}" --path orbit \
      --frames "${FRAMES:-20}" --cache $mode --compare --shader-stats --out "$libraries/png" > "$run_log" 2>&1
    { echo "\$ raycache_vulkan_whitted --scene $scene --cache $mode: exit $?"; cat "$run_log"; } >> "$results/walkthroughs.txt"
    echo "$scene $mode: $(grep -E '^(summary (GPU|after)|tracing shader)' "$run_log" | sed 's/^summary //' | tr '\n' ' ')"
  done
done | tee "$results/summary.txt"
RUN
chmod +x "$out/run.sh"
# The validation layer, so that the tests check the other driver's use too (two of them require it).
layer_json=/usr/share/vulkan/explicit_layer.d/VkLayer_khronos_validation.json
if [[ -f $layer_json ]]; then
  layer_library=$(ldconfig -p | awk '$1 == "libVkLayer_khronos_validation.so" {print $NF; exit}')
  layer_library=${layer_library:-/usr/lib/x86_64-linux-gnu/libVkLayer_khronos_validation.so}
  cp -L "$layer_library" "$out/layers/"
  sed 's|"library_path": *"[^"]*"|"library_path": "./libVkLayer_khronos_validation.so"|' "$layer_json" > "$out/layers/VkLayer_khronos_validation.json"
fi
# Compressed, the libraries (Embree is most of them) take a quarter of the room; run.sh unpacks them.
tar cJf "$out/libraries.tar.xz" -C "$out" lib lib-fallback layers && rm -rf "$out/lib" "$out/lib-fallback" "$out/layers"
du -sh "$out"
