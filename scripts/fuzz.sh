#!/usr/bin/env bash
# Fuzzes the scene loader (fuzz/fuzz_scene.cpp) with libFuzzer under ASan + UBSan for SECONDS (default 60), starting
# from the seed corpus fuzz/corpus/scene. Builds the 'fuzz' CMake preset (clang++) in build/fuzz first. The corpus is
# copied to a temporary directory, so the repository is not modified; inputs that crash are kept in build/fuzz/crashes.
# fuzz/scene.dict (the format's keys, JSON literals, edge numbers) guides the mutations.
# Exit 0 when the run ends without a crash, non-zero (and the crash's reproducer path) otherwise.
# Usage: scripts/fuzz.sh [SECONDS] [extra libFuzzer flags...]      (needs clang and libclang-rt-14-dev: scripts/setup.sh)
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-60}
shift || true
if ! [[ "$seconds" =~ ^[0-9]+$ ]] || [ "$seconds" -lt 1 ]; then
    echo "fuzz.sh: SECONDS must be a whole number >= 1 (got '$seconds')" >&2
    exit 2
fi
jobs=${DRAPE_JOBS:-$(nproc)}
command -v clang++ >/dev/null || { echo "fuzz.sh: clang++ not found (run scripts/setup.sh)" >&2; exit 2; }

echo "== fuzz: configure and build (preset fuzz, clang++, ASan + UBSan + libFuzzer)"
launcher=()
if command -v ccache >/dev/null; then
    launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache -DCMAKE_C_COMPILER_LAUNCHER=ccache)
fi
cmake --preset fuzz "${launcher[@]}" >/dev/null
cmake --build --preset fuzz -j "$jobs"

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cp -r fuzz/corpus/scene "$work/corpus"
crashes=build/fuzz/crashes
rm -rf "$crashes"
mkdir -p "$crashes"

echo "== fuzz: drape_fuzz_scene for $seconds s on $(ls "$work/corpus" | wc -l) seed inputs"
# -rss_limit_mb: one input may build a 20,000-particle scene; -timeout: one input taking 10 s is a hang.
# -max_len: scene files are small; 64 KiB leaves room for long outlines. detect_leaks: the loader must not leak.
set +e
ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=1:symbolize=1} \
UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1} \
    build/fuzz/drape_fuzz_scene "$work/corpus" -dict=fuzz/scene.dict -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 \
    -max_len=65536 -print_final_stats=1 -artifact_prefix="$crashes/" "$@" 2>&1 | tee "$work/log" |
    grep -avE '^#[0-9]+.*(NEW|REDUCE)|^\s+NEW_FUNC|^"|^###### (Recommended|End of recommended)'
status=${PIPESTATUS[0]}
set -e
grep -aE '^#[0-9]+\s' "$work/log" | tail -1 | sed 's/^/== fuzz: last status: /' || true
if [ "$status" != 0 ]; then
    echo "== fuzz: FAILED (exit $status); reproducer(s): $(ls "$crashes" 2>/dev/null | sed "s|^|$crashes/|" | tr '\n' ' ')" >&2
    echo "   replay one with: build/fuzz/drape_fuzz_scene FILE" >&2
    exit 1
fi
echo "== fuzz: no crash in $seconds s"
