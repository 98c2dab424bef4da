#!/usr/bin/env bash
# Installs the npm tools perf/record.sh uses (versions pinned in perf/package-lock.json) into perf/node_modules
# (git-ignored). Idempotent: does nothing when the installed tree matches the lock file.
#   flamegraph  perf script -> flame graph SVG
#   speedscope  offline interactive profile viewer (reads perf script output)
set -euo pipefail
# shellcheck source=perf/common.sh
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"

need_cmd node "apt-get install nodejs npm"
need_cmd npm "apt-get install npm"
dir="$ROOT/perf"
stamp="$dir/node_modules/.drape-lock"
if [[ -f "$stamp" ]] && cmp -s "$stamp" "$dir/package-lock.json" &&
    [[ -x "$dir/node_modules/.bin/flamegraph" && -f "$dir/node_modules/speedscope/dist/release/index.html" ]]; then
    exit 0
fi
say "installing flamegraph and speedscope into perf/node_modules (npm ci)"
(cd "$dir" && npm ci --no-audit --no-fund --loglevel=error 2>&1) | { grep -v 'Unknown user config' >&2 || true; } ||
    die "npm ci failed in perf/ (it needs the npm registry once; the outputs other than the flame graph are written)"
cp "$dir/package-lock.json" "$stamp"
