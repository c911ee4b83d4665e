#!/usr/bin/env bash
# The main job, from a fresh Debian 12 machine: install what is missing, build,
# and render the Cornell box with the ray tracer (testbed render).
set -euo pipefail
cd "$(dirname "$0")/.."
tools/setup.sh
cmake -S . -B build/release -DCMAKE_BUILD_TYPE=Release -DTB_TESTS=OFF >/dev/null
cmake --build build/release -j "$(nproc)"
# The main job: the Cornell box through the Whitted ray tracer (direct light
# from the area light with soft shadows, spectral bands to sRGB).
build/release/testbed render scenes/cornell-box.mid -o cornell-box.png --spp 16
echo "image: $(pwd)/cornell-box.png"
