#!/usr/bin/env bash
# The whole test suite, from a fresh Debian 12 machine: install what is missing,
# build with -Werror, run every CTest test; then build again with clang under
# AddressSanitizer + UBSan and run the unit tests and the fuzzers there.
#   tools/run-tests.sh [--quick]   (--quick: skip the sanitizer build)
set -euo pipefail
cd "$(dirname "$0")/.."
jobs=$(nproc)

tools/setup.sh

echo "== build (gcc, -Werror)"
cmake -S . -B build/ci -DCMAKE_BUILD_TYPE=RelWithDebInfo -DTB_WERROR=ON >/dev/null
cmake --build build/ci -j "$jobs"
echo "== tests"
ctest --test-dir build/ci --output-on-failure -j "$jobs" --timeout 900

if [[ "${1:-}" != "--quick" ]]; then
  echo "== build (clang, ASan + UBSan, fuzzers)"
  CC=clang cmake -S . -B build/asan -DCMAKE_BUILD_TYPE=Debug -DTB_WERROR=ON \
    -DTB_SANITIZE=ON -DTB_FUZZ=ON >/dev/null
  cmake --build build/asan -j "$jobs"
  echo "== unit tests and fuzzers under sanitizers"
  ASAN_OPTIONS=detect_leaks=1:abort_on_error=1:quarantine_size_mb=256 UBSAN_OPTIONS=print_stacktrace=1 \
    LSAN_OPTIONS=suppressions=$PWD/tests/lsan.supp \
    LD_PRELOAD=$PWD/build/asan/tests/libtb_keep_loaded.so \
    ctest --test-dir build/asan --output-on-failure -j "$jobs" -L 'unit|fuzz' --timeout 900
fi
