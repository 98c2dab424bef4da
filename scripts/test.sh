#!/usr/bin/env bash
# Builds drape and runs every test: the Release build (ctest), then the whole suite again under
# AddressSanitizer + UndefinedBehaviorSanitizer (asan preset). Run scripts/setup.sh first on a fresh machine.
# Usage: scripts/test.sh [--no-asan]
set -euo pipefail
cd "$(dirname "$0")/.."
jobs=${DRAPE_JOBS:-$(nproc)}

echo "== release: configure, build, test"
cmake --preset release >/dev/null
cmake --build --preset release -j "$jobs"
ctest --preset release -j 1

if [ "${1:-}" != "--no-asan" ]; then
    echo "== asan (ASan + UBSan): configure, build, test"
    cmake --preset asan >/dev/null
    cmake --build --preset asan -j "$jobs"
    ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=1} \
    UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1} \
        ctest --preset asan -j 1
fi
echo "== all tests passed"
