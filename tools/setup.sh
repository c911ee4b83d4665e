#!/usr/bin/env bash
# Installs the Debian 12 packages Testbed builds, tests and runs with.
# Idempotent: packages already installed are skipped, and apt is not touched
# when nothing is missing. Run as root (or with sudo available).
#   tools/setup.sh           build + test dependencies
#   tools/setup.sh --bench   also the benchmark peers (POV-Ray, hyperfine)
set -euo pipefail

packages=(
  # toolchain
  build-essential cmake pkg-config git clang libclang-rt-14-dev libomp-dev
  # libraries linked into Testbed
  libpng-dev libopenexr-dev libssl-dev libassimp-dev libopenmpi-dev openmpi-bin
  # Vulkan: loader, Mesa's CPU driver (lavapipe), shader compiler and tools, validation layers
  libvulkan-dev mesa-vulkan-drivers glslang-tools spirv-tools vulkan-validationlayers vulkan-tools
  # tests: unit framework, independent RLE reader/writer, importer test models, plots,
  # Embree (an independent ray-tracing oracle in the default suite), the de_DE
  # charmaps test_mid_roundtrip's locale test builds with localedef
  libcmocka-dev netpbm assimp-testmodels gnuplot-nox python3 libembree-dev locales
)
if [[ "${1:-}" == "--bench" ]]; then
  packages+=(povray hyperfine time)
fi

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if ((${#missing[@]} == 0)); then
  echo "setup: all ${#packages[@]} packages already installed"
  exit 0
fi

sudo=""
if [[ $(id -u) -ne 0 ]]; then sudo="sudo"; fi
echo "setup: installing ${missing[*]}"
$sudo apt-get update -qq
DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
