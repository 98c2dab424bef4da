#!/usr/bin/env bash
# Runs a command on a private Xvfb server and exits with the command's own exit code.
#
# Usage: scripts/with_xvfb.sh [-s "Xvfb arguments"] command [args...]     (default "-screen 0 1600x1000x24")
#
# Why not xvfb-run: at exit xvfb-run removes its temporary directory, and when that fails (seen under CI's load:
# "xvfb-run: error: problem while cleaning up temporary directory") it exits 5 and prints a line of its own,
# whatever the command returned, so a check of the command's exit code and stderr failed for a reason that is not
# drape's. Here Xvfb picks a free display itself (-displayfd), needs no temporary directory or xauth, and is stopped
# (and waited for) before the command's exit code is returned.
set -u
server_args="-screen 0 1600x1000x24"
if [ "${1:-}" = "-s" ]; then
    server_args=$2
    shift 2
fi
if [ $# -eq 0 ]; then
    echo "with_xvfb: no command given (usage: with_xvfb.sh [-s \"Xvfb arguments\"] command [args...])" >&2
    exit 2
fi
if ! command -v Xvfb >/dev/null 2>&1; then
    echo "with_xvfb: Xvfb not found; install it with scripts/setup.sh (Debian package xvfb)" >&2
    exit 2
fi
ready=$(mktemp "${TMPDIR:-/tmp}/drape_xvfb.XXXXXX") || {
    echo "with_xvfb: cannot create a temporary file in ${TMPDIR:-/tmp}" >&2
    exit 3
}
server=""
cleanup() { # also when interrupted: no server or file left behind
    if [ -n "$server" ]; then kill "$server" 2>/dev/null; fi
    rm -f "$ready"
}
trap cleanup EXIT
# shellcheck disable=SC2086 # the server arguments are words
Xvfb -displayfd 3 -nolisten tcp $server_args 3>"$ready" 2>/dev/null &
server=$!
display=""
for _ in $(seq 1 300); do # up to 30 s for the server to come up
    display=$(tr -dc '0-9' <"$ready")
    [ -n "$display" ] && break
    if ! kill -0 "$server" 2>/dev/null; then break; fi
    sleep 0.1
done
rm -f "$ready"
if [ -z "$display" ]; then
    echo "with_xvfb: Xvfb did not start (arguments: $server_args)" >&2
    exit 3
fi
DISPLAY=":$display" "$@"
code=$?
kill "$server" 2>/dev/null
wait "$server" 2>/dev/null
server="" # reaped: the exit trap must not signal a reused pid
exit "$code"
