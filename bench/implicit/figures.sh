#!/usr/bin/env bash
# Runs every figure of the implicit solver (issue 8, docs/implicit.md "Figures") with drape_implicit and writes them
# into an output directory: build/bench/implicit by default (a trial run never overwrites the committed figures);
# `--out docs/bench/implicit` refreshes those.
#   realtime.md / .json       real-time factor at quality, implicit beside explicit, N = 100, 316
#   realtime1000.md / .json   the same at N = 1000
#   convergence.md / .json / .csv / .png   relative energy error against iterations and wall time, N = 100, 316
#   throughput.md / .json     vertex-iterations/s beside particle-substeps/s; thread scaling 1 -> 2
#   rest.md / .json           whether the hang comes to rest (largest motion per step once a second), N = 32, 100
#   settled.md / .json, settled_fas_at_rest.md / .json   the settled-shape criterion at 10 sweeps with the strain
#             limit, N = 32, 100: each run's shape after 8 s under drag 5/s against the explicit equilibrium reached
#             from it, the plain multilevel guess and FAS at rest (docs/implicit.md, "FAS at rest under light air drag,
#             and the settled shape")
#   machine.txt               date, CPU, load average before and after
# Usage: bench/implicit/figures.sh [--out DIR] [--build DIR] [--quick] [-- extra drape_implicit realtime flags]
#   --quick   N = 100 only with a 4 s settle (a smoke run of the whole pipeline, a few minutes)
#   --settle-1000 S   settled-shape time at N = 1000 (default 10 s; 0 = skip the settled shape and its reference: the
#             10 s run and the long-run reference at 1e6 particles take tens of minutes while the solver is slow)
# The full run takes about an hour on 2 shared cores (N = 316 and 1000 dominate).
# Builds the drape_implicit target in the build directory (default build/release, configured already).
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
out="$root/build/bench/implicit"
build="$root/build/release"
quick=0
settle1000=10
extra=()
while [[ $# -gt 0 ]]; do
  case "$1" in
    --out) out=$2; shift 2 ;;
    --build) build=$2; shift 2 ;;
    --quick) quick=1; shift ;;
    --settle-1000) settle1000=$2; shift 2 ;;
    --) shift; extra=("$@"); break ;;
    *) echo "figures.sh: unknown option $1 (--out DIR, --build DIR, --quick, --settle-1000 S, -- realtime flags)" >&2; exit 2 ;;
  esac
done
mkdir -p "$out"
cmake --build "$build" --target drape_implicit -j2 >/dev/null
bin="$build/drape_implicit"
py=/usr/bin/python3; [[ -x $py ]] || py=python3

if [[ $quick == 1 ]]; then
  rt_sizes=100; cv_sizes=100; tp_sizes=316; settle=(--settle-time 4)
else
  rt_sizes=100,316; cv_sizes=100,316; tp_sizes=316,1000; settle=()
fi
{
  echo "date: $(date -u +%FT%TZ)"
  echo "cpu: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2- | sed 's/^ //') x $(nproc)"
  echo "load before: $(cut -d' ' -f1-3 /proc/loadavg)"
} > "$out/machine.txt"

echo "== throughput" >&2
"$bin" throughput --n "$tp_sizes" --threads 2 --json-out "$out/throughput.json" | tee "$out/throughput.md"
echo "== convergence" >&2
"$bin" convergence --n "$cv_sizes" --threads 2 --csv "$out/convergence.csv" --json-out "$out/convergence.json" | tee "$out/convergence.md"
"$py" "$root/bench/implicit/plot_convergence.py" "$out/convergence.csv" "$out/convergence.png"
echo "== rest" >&2
"$bin" rest --n 32,100 --threads 2 --json-out "$out/rest.json" | tee "$out/rest.md"
echo "== settled shape" >&2
settled=(--n 32,100 --threads 2 --settle-time 10 --settle-drag 5 --explicit-reference --ref-drag 5 --iterations 10
         --strain-limit 0.095 --explicit-budget 0 --explicit-short 0.0001)
"$bin" realtime "${settled[@]}" --json-out "$out/settled.json" | tee "$out/settled.md"
"$bin" realtime "${settled[@]}" --fas-at-rest --json-out "$out/settled_fas_at_rest.json" | tee "$out/settled_fas_at_rest.md"
echo "== realtime" >&2
"$bin" realtime --n "$rt_sizes" --threads 2 "${settle[@]}" "${extra[@]}" --json-out "$out/realtime.json" | tee "$out/realtime.md"
if [[ $quick == 0 ]]; then
  "$bin" realtime --n 1000 --threads 2 --settle-time "$settle1000" "${extra[@]}" --json-out "$out/realtime1000.json" \
    | tee "$out/realtime1000.md"
fi
echo "load after: $(cut -d' ' -f1-3 /proc/loadavg)" >> "$out/machine.txt"
cat "$out/machine.txt"
