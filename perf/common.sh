# Shared helpers for perf/record.sh and perf/callgrind.sh. Sourced, not run.
# shellcheck shell=bash

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
OUT="${DRAPE_PERF_OUT:-$ROOT/perf/out}"
JOBS="${JOBS:-1}"

die() {
    echo "$(basename "$0"): error: $*" >&2
    exit 1
}
say() { echo "$(basename "$0"): $*" >&2; }

need_cmd() { # need_cmd COMMAND "how to install"
    command -v "$1" >/dev/null 2>&1 || die "'$1' not found. Install it: $2"
}

# Validates a positive integer option value.
need_uint() { # need_uint NAME VALUE
    [[ "$2" =~ ^[0-9]+$ ]] && (("$2" > 0)) || die "$1 must be a positive integer (got '$2')"
}

git_rev() { git -C "$ROOT" describe --always --dirty 2>/dev/null || echo unknown; }
