#!/usr/bin/env bash
# Profiles a real headless `drape run` with Linux perf and writes, under perf/out/ (git-ignored):
#   perf.data            the raw samples (event cpu-clock by default: works with or without hardware counters)
#   run.txt              what the profiled run printed (throughput, strain, checksum)
#   stat.txt             perf stat of a second, unprofiled run: cycles, instructions, IPC, L1d loads and misses (if counters work)
#   report.txt           top symbols without and with children, the split inside the fused substep kernel
#   annotate.txt         perf annotate of the hottest symbol (instruction level)
#   perf.script.txt      `perf script` output (input of both viewers below)
#   flamegraph.svg       flame graph, SIMD wrapper frames (xsimd::, _mm512_*, drape::simd::) folded into their caller
#   flamegraph-full.svg  flame graph with every frame
#   speedscope.html      offline interactive viewer (speedscope) with this profile preloaded
# Builds the `profile` CMake preset (-O3 -g, frame pointers) in build/profile first when needed.
#
# Usage: perf/record.sh [--size N] [--threads T] [--steps S] [--call-graph dwarf[,BYTES]|fp] [--freq HZ] [--event EV]
#                       [--no-stat] [-- DRAPE_RUN_ARGS...]
# Environment (same meaning, flags win): DRAPE_SIZE (316), DRAPE_THREADS (2), DRAPE_STEPS (3000), CALL_GRAPH (dwarf),
# PERF_FREQ (4000), PERF_EVENT (cpu-clock), PERF_STAT (1; 0 = skip the counter run), JOBS (build jobs, 1),
# DRAPE_PERF_OUT (output directory, perf/out).
# When the CPU's hardware counters are usable, a second run under `perf stat` adds cycles, instructions, IPC and L1d
# figures (stat.txt, section 0 of report.txt).
# See docs/profiling.md for how to read the results.
set -euo pipefail
# shellcheck source=perf/common.sh
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"

size="${DRAPE_SIZE:-316}"
threads="${DRAPE_THREADS:-2}"
steps="${DRAPE_STEPS:-3000}"
call_graph="${CALL_GRAPH:-dwarf}"
freq="${PERF_FREQ:-4000}"
event="${PERF_EVENT:-cpu-clock}"
stat="${PERF_STAT:-1}"
extra=()

usage() { sed -n '2,21p' "$0" | sed 's/^# \{0,1\}//'; }
while (($#)); do
    case "$1" in
    --size) size="${2:?--size needs a value}"; shift 2 ;;
    --threads) threads="${2:?--threads needs a value}"; shift 2 ;;
    --steps) steps="${2:?--steps needs a value}"; shift 2 ;;
    --call-graph) call_graph="${2:?--call-graph needs dwarf or fp}"; shift 2 ;;
    --freq) freq="${2:?--freq needs a value}"; shift 2 ;;
    --event) event="${2:?--event needs a perf event name}"; shift 2 ;;
    --no-stat) stat=0; shift ;;
    -h | --help) usage; exit 0 ;;
    --) shift; extra=("$@"); break ;;
    *) die "unknown argument '$1' (see --help)" ;;
    esac
done
need_uint --size "$size"
need_uint --threads "$threads"
need_uint --steps "$steps"
need_uint --freq "$freq"
case "$call_graph" in dwarf | dwarf,[0-9]* | fp) ;; *) die "--call-graph must be dwarf, dwarf,STACK_BYTES or fp (got '$call_graph')" ;; esac

# --- perf itself ------------------------------------------------------------------------------------------------------
need_cmd perf "apt-get install linux-perf"
perf version >/dev/null 2>&1 || die "'perf version' fails: $(perf version 2>&1 | head -n 2). Install linux-perf for this kernel."
paranoid="$(cat /proc/sys/kernel/perf_event_paranoid 2>/dev/null || echo 2)"
if [[ "$(id -u)" != 0 ]]; then
    if ((paranoid > 2)); then
        die "kernel.perf_event_paranoid is $paranoid: unprivileged perf is disabled. Run as root, or allow it with
    sudo sysctl -w kernel.perf_event_paranoid=1    (2 also works: user-space samples only)"
    elif ((paranoid == 2)); then
        [[ "$event" == *:* ]] || event="$event:u"
        say "kernel.perf_event_paranoid is 2: recording user space only ($event). For kernel frames too:"
        say "    sudo sysctl -w kernel.perf_event_paranoid=1"
    fi
fi
need_cmd cmake "scripts/setup.sh (or apt-get install cmake build-essential)"

# --- build ------------------------------------------------------------------------------------------------------------
build="$ROOT/build/profile"
cd "$ROOT"
if [[ ! -f "$build/CMakeCache.txt" ]]; then
    say "configuring the 'profile' preset in build/profile"
    cmake --preset profile >/dev/null || die "cmake --preset profile failed (missing packages? run scripts/setup.sh)"
fi
say "building build/profile/drape (-j$JOBS)"
cmake --build "$build" --target drape -j "$JOBS" >"$build/record-build.log" 2>&1 ||
    { tail -n 30 "$build/record-build.log" >&2; die "build failed; full log: $build/record-build.log"; }
bin="$build/drape"
[[ -x "$bin" ]] || die "$bin was not built"

# --- record -----------------------------------------------------------------------------------------------------------
mkdir -p "$OUT"
rm -f "$OUT/perf.data" "$OUT/perf.data.old"
run_cmd=("$bin" run --scene hang --size "$size" --threads "$threads" --steps "$steps" "${extra[@]}")
say "perf record -e $event -F $freq --call-graph $call_graph -- ${run_cmd[*]#"$ROOT/"}"
if ! perf record -e "$event" -F "$freq" --call-graph "$call_graph" -o "$OUT/perf.data" -- "${run_cmd[@]}" \
    >"$OUT/run.txt" 2>"$OUT/record.log"; then
    cat "$OUT/record.log" "$OUT/run.txt" >&2
    if grep -qiE "paranoid|permission|not permitted|EACCES" "$OUT/record.log"; then
        die "perf record was refused: lower kernel.perf_event_paranoid (sudo sysctl -w kernel.perf_event_paranoid=1) or run as root"
    fi
    die "perf record failed (log above, also in $OUT/record.log)"
fi
cat "$OUT/run.txt"
grep '^\[ perf record' "$OUT/record.log" >&2 || true
[[ -s "$OUT/perf.data" ]] || die "perf wrote no $OUT/perf.data"

# --- hardware counters (a second run, not sampled) --------------------------------------------------------------------
# Four hardware events at most: with six, this VM's PMU read cache-misses as 0 (no multiplexing shown).
stat_events="task-clock,cycles,instructions,L1-dcache-loads,L1-dcache-load-misses"
rm -f "$OUT/stat.txt"
if [[ "$stat" != 0 ]]; then
    probe="$(perf stat -x, -e cycles,instructions -- true 2>&1 >/dev/null || true)"
    if grep -q '^[0-9]' <<<"$probe"; then
        say "perf stat -e $stat_events -- (same command)"
        perf stat -e "$stat_events" -o "$OUT/stat.txt" -- "${run_cmd[@]}" >"$OUT/stat.run.txt" 2>&1 ||
            { say "perf stat failed (non-fatal)"; rm -f "$OUT/stat.txt"; }
    else
        say "hardware counters not available here: no perf stat (cpu-clock sampling works without them)"
    fi
fi

# --- report -----------------------------------------------------------------------------------------------------------
# Long C++ names are cut at 200 characters (full names: perf report -i $OUT/perf.data).
report() {
    perf report -i "$OUT/perf.data" --stdio "$@" 2>/dev/null |
        awk '{ sub(/[ \t]+$/, "") } /^# *$|^# \.\.|^# \(Tip:|^# To display/ { next }
             { if (length($0) > 200) $0 = substr($0, 1, 197) "..."; print }'
}
say "writing perf.script.txt"
# No symbol offsets (+0x..): frames of one function merge in the viewers. Offsets: perf script -i $OUT/perf.data
perf script -i "$OUT/perf.data" -F comm,tid,time,period,event,ip,sym,dso >"$OUT/perf.script.txt" 2>"$OUT/script.log" ||
    { cat "$OUT/script.log" >&2; die "perf script failed"; }

say "writing report.txt"
{
    echo "drape perf profile  $(date -u '+%Y-%m-%d %H:%M UTC')  git $(git_rev)  host: $(nproc) cpu(s), $(uname -r)"
    echo "command: perf record -e $event -F $freq --call-graph $call_graph -o ${OUT#"$ROOT/"}/perf.data -- ${run_cmd[*]#"$ROOT/"}"
    echo
    sed 's/^/  /' "$OUT/run.txt"
    echo
    if [[ -f "$OUT/stat.txt" ]]; then
        echo "=== 0. Hardware counters: perf stat of a second, unprofiled run of the same command (scene building included) ==="
        grep -vE '^#|^ *$' "$OUT/stat.txt" | sed 's/[[:space:]]*$//'
        grep -m1 'particle-substeps/s' "$OUT/stat.run.txt" | sed 's/^ */  that run: /'
        awk -v p="$((size * size))" -v n="$steps" '$2 ~ /^instructions/ { gsub(/,/, "", $1); printf "  instructions per particle-substep (whole run, setup included): %.1f\n", $1 / (p * n) }' "$OUT/stat.txt"
        echo
    fi
    echo "=== 1. Top symbols, self time (perf report --no-children) ==="
    report --no-children -F overhead,dso,sym -g none --percent-limit 0.3
    echo
    echo "=== 2. Top symbols with children (perf report --children; inlined frames show as '(inlined)' with dwarf stacks;"
    echo "===    SIMD wrapper frames _mm512_*, xsimd::*, drape::simd::* left out here) ==="
    report --children -F overhead_children,overhead,sym -g none --percent-limit 2 |
        awk '!/\[\.\] (_mm[0-9]*_|xsimd::|drape::simd::)/ && n++ < 45'
    echo
    echo "=== 3. Inside the fused substep kernel: samples by innermost inlined drape function ==="
    if [[ "$call_graph" == dwarf* ]]; then
        awk -f "$ROOT/perf/fused_breakdown.awk" "$OUT/perf.script.txt"
    else
        echo "(needs --call-graph dwarf: frame-pointer stacks carry no inlined frames)"
    fi
} | cat -s >"$OUT/report.txt"

top_sym="$(perf report -i "$OUT/perf.data" --stdio --no-children -F overhead,sym -g none 2>/dev/null |
    awk '/^ +[0-9.]+%/ && !found { sub(/^ +[0-9.]+% +\[[^]]*\] /, ""); sub(/[[:space:]]+$/, ""); print; found = 1 }')"
if [[ -n "$top_sym" ]]; then
    perf annotate -i "$OUT/perf.data" --stdio --no-source "$top_sym" >"$OUT/annotate.txt" 2>/dev/null ||
        say "perf annotate failed (non-fatal)"
fi

# --- flame graph and speedscope (npm tools in perf/node_modules) ------------------------------------------------------
"$ROOT/perf/node_tools.sh"
nm="$ROOT/perf/node_modules"
title="drape hang N=$size, $threads thread(s), $steps substeps, $event, $call_graph call graph"
flame() { # flame INPUT OUTPUT
    # The flamegraph package writes `&&` unescaped inside onmouseover attributes: strict XML parsers (browsers opening
    # the .svg directly, rsvg) reject that, so it is escaped here.
    "$nm/.bin/flamegraph" -t perf --titletext "$title" --countname samples <"$1" |
        sed 's/ && / \&amp;\&amp; /g' >"$2"
}
say "writing flamegraph.svg, flamegraph-full.svg"
# Readable variant: drop the SIMD wrapper frames and give the kernel one name (its ELF symbol and its DWARF name as an
# inline caller differ).
awk '/^[ \t]+[0-9a-f]+ (_mm[0-9]*_|xsimd::|drape::simd::)/ { next }
     { sub(/ drape::kernels::\(anonymous namespace\)::fused_block</, " fused_block<"); print }' \
    "$OUT/perf.script.txt" >"$OUT/perf.script.folded-simd.txt"
flame "$OUT/perf.script.folded-simd.txt" "$OUT/flamegraph.svg"
flame "$OUT/perf.script.txt" "$OUT/flamegraph-full.svg"
rm -f "$OUT/perf.script.folded-simd.txt"
for svg in "$OUT/flamegraph.svg" "$OUT/flamegraph-full.svg"; do
    grep -q '<rect' "$svg" || die "flamegraph produced an empty SVG: $svg"
    if command -v python3 >/dev/null; then # a browser shows nothing for an SVG that is not well-formed XML
        python3 -c 'import sys, xml.etree.ElementTree as E; E.parse(sys.argv[1])' "$svg" ||
            die "$svg is not well-formed XML"
    fi
done

say "writing speedscope.html (+ speedscope/)"
rm -rf "$OUT/speedscope"
cp -r "$nm/speedscope/dist/release" "$OUT/speedscope"
node -e '
const fs = require("fs");
const [src, dst] = process.argv.slice(1);
const b64 = fs.readFileSync(src).toString("base64");
fs.writeFileSync(dst, "speedscope.loadFileFromBase64(" + JSON.stringify("perf.script.txt") + "," + JSON.stringify(b64) + ")\n");
' "$OUT/perf.script.txt" "$OUT/speedscope/profile.js"
cat >"$OUT/speedscope.html" <<EOF
<!DOCTYPE html>
<meta charset="utf-8">
<title>drape profile (speedscope)</title>
<script>
// speedscope loads a local profile from a script named by absolute path in #localProfilePath, as its own CLI does.
var js = new URL('speedscope/profile.js', location.href).pathname;
location.replace('speedscope/index.html#localProfilePath=' + encodeURIComponent(js) +
                 '&view=left-heavy&title=' + encodeURIComponent('$title'));
</script>
<p>Opening speedscope... If nothing shows, open speedscope/index.html and drop perf.script.txt into it.</p>
EOF

echo
echo "perf/record.sh: done. Outputs in ${OUT#"$ROOT/"}/:"
for f in run.txt stat.txt report.txt annotate.txt perf.script.txt flamegraph.svg flamegraph-full.svg speedscope.html perf.data; do
    [[ -e "$OUT/$f" ]] && printf '  %-20s %s\n' "$f" "$(du -h "$OUT/$f" | cut -f1)"
done
echo
awk '/^=== 1\./ { f = 1; next } /^=== 2\./ { f = 0 } f && /^ +[0-9.]+%/ && n++ < 8' "$OUT/report.txt"
