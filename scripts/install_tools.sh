#!/usr/bin/env bash
# Installs the profiling tools used by perf/record.sh, perf/callgrind.sh and bench/sweep.py (docs/profiling.md):
#   linux-perf, valgrind, node + npm (Debian packages), python3-matplotlib, and the npm tools of perf/package.json
#   (flamegraph, speedscope) into perf/node_modules. Idempotent: installs only what is missing. Run as root or with sudo.
# The build dependencies themselves come from scripts/setup.sh.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"

declare -A tool_package=([perf]=linux-perf [valgrind]=valgrind [callgrind_annotate]=valgrind [node]=nodejs [npm]=npm)
missing=()
for tool in perf valgrind callgrind_annotate node npm; do
    command -v "$tool" >/dev/null 2>&1 || missing+=("${tool_package[$tool]}")
done
if ! /usr/bin/python3 -c 'import matplotlib' 2>/dev/null; then missing+=(python3-matplotlib); fi
if ((${#missing[@]})); then
    mapfile -t missing < <(printf '%s\n' "${missing[@]}" | sort -u)
    echo "install_tools: installing ${missing[*]}"
    SUDO=""
    if [ "$(id -u)" != 0 ]; then SUDO="sudo"; fi
    export DEBIAN_FRONTEND=noninteractive
    $SUDO apt-get update -qq
    $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
else
    echo "install_tools: perf, valgrind, node, npm and matplotlib present"
fi
"$ROOT/perf/node_tools.sh"
echo "install_tools: npm tools in perf/node_modules ready"
