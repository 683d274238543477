#!/usr/bin/env bash
# install-deps.sh: install RayCache's build and test dependencies on Debian 12 / Ubuntu.
# Idempotent: when every package is already installed it does not touch apt at all.
# Runs apt as root, or through sudo when not root. --bench adds what scripts/bench.sh needs for plots.
set -euo pipefail

packages=(
  cmake g++ clang libclang-rt-dev ninja-build git pkg-config
  libglm-dev doctest-dev libembree-dev libtbb-dev
  libvulkan-dev mesa-vulkan-drivers glslang-tools vulkan-validationlayers
  libstb-dev libcli11-dev libassimp-dev assimp-testmodels libbenchmark-dev
)
if [[ "${1:-}" == "--bench" ]]; then packages+=(python3 python3-matplotlib); fi

missing=()
for p in "${packages[@]}"; do
  status=$(dpkg-query -W -f='${db:Status-Status}' "$p" 2>/dev/null || true)
  [[ "$status" == "installed" ]] || missing+=("$p")
done

if [[ ${#missing[@]} -eq 0 ]]; then
  echo "install-deps: all ${#packages[@]} packages already installed"
  exit 0
fi
echo "install-deps: installing ${missing[*]}"

if [[ $(id -u) -eq 0 ]]; then
  as_root=()
elif command -v sudo >/dev/null 2>&1; then
  as_root=(sudo)
else
  echo "install-deps: not root and no sudo; install as root: ${missing[*]}" >&2
  exit 1
fi

export DEBIAN_FRONTEND=noninteractive
"${as_root[@]}" env DEBIAN_FRONTEND=noninteractive apt-get update
"${as_root[@]}" env DEBIAN_FRONTEND=noninteractive \
  apt-get install -y --no-install-recommends "${missing[@]}"
