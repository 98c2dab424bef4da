#!/usr/bin/env bash
# Counts instructions of a short headless `drape run` with valgrind's callgrind and prints the top functions.
# Instruction counts are repeatable (unlike wall time on this shared VM), so they show whether a change removed work.
#
# valgrind (3.19 in Debian 12) cannot execute AVX-512, so this uses its own build, build/callgrind: RelWithDebInfo
# -O3 -g, DRAPE_NATIVE=OFF and -march=x86-64-v3 (AVX2 + FMA, 8 float lanes instead of 16). Its counts describe that
# AVX2 kernel, not the AVX-512 one perf/record.sh profiles: compare callgrind counts only with callgrind counts.
#
# Usage: perf/callgrind.sh [--size N] [--threads T] [--steps S] [-- DRAPE_RUN_ARGS...]
# Environment (flags win): CG_SIZE (100), CG_THREADS (1), CG_STEPS (50), CG_MARCH (x86-64-v3), JOBS (1),
# DRAPE_PERF_OUT (perf/out).
# Writes perf/out/callgrind.out (open with kcachegrind or callgrind_annotate) and perf/out/callgrind.txt.
set -euo pipefail
# shellcheck source=perf/common.sh
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"

size="${CG_SIZE:-100}"
threads="${CG_THREADS:-1}"
steps="${CG_STEPS:-50}"
march="${CG_MARCH:-x86-64-v3}"
extra=()
while (($#)); do
    case "$1" in
    --size) size="${2:?--size needs a value}"; shift 2 ;;
    --threads) threads="${2:?--threads needs a value}"; shift 2 ;;
    --steps) steps="${2:?--steps needs a value}"; shift 2 ;;
    -h | --help) sed -n '2,13p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    --) shift; extra=("$@"); break ;;
    *) die "unknown argument '$1' (see --help)" ;;
    esac
done
need_uint --size "$size"
need_uint --threads "$threads"
need_uint --steps "$steps"
need_cmd valgrind "apt-get install valgrind"
need_cmd callgrind_annotate "apt-get install valgrind"
need_cmd cmake "scripts/setup.sh (or apt-get install cmake build-essential)"

# --- build (no AVX-512) -----------------------------------------------------------------------------------------------
build="$ROOT/build/callgrind"
cd "$ROOT"
if [[ ! -f "$build/CMakeCache.txt" ]]; then
    say "configuring build/callgrind (-O3 -g, -march=$march, no AVX-512)"
    mkdir -p "$build"
    cmake -S "$ROOT" -B "$build" -DCMAKE_BUILD_TYPE=RelWithDebInfo "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O3 -g -DNDEBUG" \
        -DDRAPE_NATIVE=OFF "-DCMAKE_CXX_FLAGS=-march=$march" -DDRAPE_FRAME_POINTERS=ON \
        -DDRAPE_BUILD_TESTS=OFF -DDRAPE_BUILD_BENCH=OFF -DDRAPE_BUILD_RENDER=OFF >"$build/callgrind-configure.log" 2>&1 ||
        { tail -n 20 "$build/callgrind-configure.log" >&2; rm -f "$build/CMakeCache.txt"; die "configure failed"; }
fi
say "building build/callgrind/drape (-j$JOBS)"
if ! cmake --build "$build" --target drape -j "$JOBS" >"$build/callgrind-build.log" 2>&1; then
    grep -m 10 -E 'error' "$build/callgrind-build.log" >&2 || tail -n 30 "$build/callgrind-build.log" >&2
    die "the -march=$march build failed (full log: $build/callgrind-build.log). valgrind cannot run AVX-512 code,
    so callgrind needs drape to build without it: the non-AVX-512 code paths (e.g. core/include/drape/simd.hpp) must compile."
fi
bin="$build/drape"

# --- run --------------------------------------------------------------------------------------------------------------
mkdir -p "$OUT"
run_cmd=("$bin" run --scene hang --size "$size" --threads "$threads" --steps "$steps" "${extra[@]}")
say "valgrind --tool=callgrind -- ${run_cmd[*]#"$ROOT/"}"
rm -f "$OUT/callgrind.out"
if ! valgrind --tool=callgrind --callgrind-out-file="$OUT/callgrind.out" -- "${run_cmd[@]}" \
    >"$OUT/callgrind.run.txt" 2>"$OUT/callgrind.log"; then
    tail -n 25 "$OUT/callgrind.log" >&2
    die "valgrind failed (log: $OUT/callgrind.log)"
fi

# --- report -----------------------------------------------------------------------------------------------------------
# Names are cut at 160 characters; the full ones are in perf/out/callgrind.out.
annotate() {
    callgrind_annotate "$@" "$OUT/callgrind.out" 2>/dev/null |
        awk '{ if (length($0) > 160) $0 = substr($0, 1, 157) "..."; print }'
}
total="$(annotate --auto=no | awk '/PROGRAM TOTALS/ && !f { gsub(/,/, "", $1); print $1; f = 1 }')"
# Inclusive count of the stepping loop: everything a substep costs, without scene building.
stepping="$(annotate --auto=no --inclusive=yes | awk '/Simulation::step_impl/ && !f { gsub(/,/, "", $1); print $1; f = 1 }')"
particles=$((size * size))
{
    echo "drape callgrind  $(date -u '+%Y-%m-%d %H:%M UTC')  git $(git_rev)  build: -O3 -g -march=$march (no AVX-512)"
    echo "command: valgrind --tool=callgrind -- ${run_cmd[*]#"$ROOT/"}"
    echo
    sed 's/^/  /' "$OUT/callgrind.run.txt"
    echo
    echo "instructions (Ir), whole program:        ${total:-?}"
    if [[ -n "$stepping" ]]; then
        echo "instructions in Simulation::step_impl:   $stepping  (inclusive: the substeps without scene building)"
        awk -v s="$stepping" -v p="$particles" -v n="$steps" \
            'BEGIN { printf "instructions per particle-substep:       %.1f  (%d particles x %d substeps)\n", s / (p * n), p, n }'
    fi
    echo
    echo "=== Top functions, self Ir (inlined code counted in the function it was inlined into) ==="
    # callgrind_annotate 3.19 lists file:function pairs (one line per source file that contributed code, headers of
    # inlined functions included); summed here per function.
    callgrind_annotate --auto=no --threshold=100 "$OUT/callgrind.out" 2>/dev/null | awk -v total="${total:-0}" '
        /file:function/ { t = 1; next }
        t && /^ *[0-9,]+ \(/ {
            ir = $1; gsub(/,/, "", ir)
            rest = $0; sub(/^ *[0-9,]+ \( *[0-9.]+%\) +/, "", rest); sub(/ \[[^]]*\]$/, "", rest)
            fn = substr(rest, index(rest, ":") + 1)
            sum[fn] += ir
        }
        END { for (f in sum) printf "%15.0f %6.2f%%  %s\n", sum[f], total ? 100 * sum[f] / total : 0, f }' |
        sort -rn | awk '{ if (length($0) > 180) $0 = substr($0, 1, 177) "..."; if (n++ < 20) print }'
    echo
    echo "=== Top entries, inclusive Ir (callgrind_annotate --inclusive=yes; file:function) ==="
    annotate --auto=no --inclusive=yes --threshold=99 | awk '/file:function/ { t = 1; next } t && /^ *[0-9,]+ / && n++ < 25'
} >"$OUT/callgrind.txt"
cat "$OUT/callgrind.txt"
echo
echo "perf/callgrind.sh: wrote ${OUT#"$ROOT/"}/callgrind.out and callgrind.txt (kcachegrind ${OUT#"$ROOT/"}/callgrind.out to browse)"
