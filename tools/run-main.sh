#!/usr/bin/env bash
# The main job, from a fresh Debian 12 machine: install what is missing, build,
# and run testbed.
set -euo pipefail
cd "$(dirname "$0")/.."
tools/setup.sh
cmake -S . -B build/release -DCMAKE_BUILD_TYPE=Release -DTB_TESTS=OFF >/dev/null
cmake --build build/release -j "$(nproc)"
build/release/testbed help
