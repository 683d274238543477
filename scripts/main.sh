#!/usr/bin/env bash
# main.sh: install dependencies, build RayCache in build/ (Release) and run the demo if there is one.
# Arguments are passed to the demo.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

bash scripts/install-deps.sh

generator=()
if [[ ! -f build/CMakeCache.txt ]] && command -v ninja >/dev/null 2>&1; then generator=(-G Ninja); fi
cmake -S . -B build "${generator[@]}" -DCMAKE_BUILD_TYPE=Release
cmake --build build -j"$(nproc 2>/dev/null || echo 2)"

demo=build/examples/demo/raycache_demo
if [[ -x "$demo" ]]; then
  echo "===== $demo $* ====="
  "$demo" "$@"
else
  echo "main.sh: no $demo (examples/demo not present or RAYCACHE_BUILD_EXAMPLES=OFF); build done"
fi
