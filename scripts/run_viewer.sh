#!/usr/bin/env bash
# Opens the drape viewer. With a working display it opens the window (close it or press Ctrl+Q to quit).
# Without one (a server, CI, a container) it runs the viewer under Xvfb + Mesa for a few seconds, saves a screenshot
# and prints the stats JSON (fps, frame_ms {sim, publish, draw}, particles, springs, substeps_per_frame, threads).
#
# Usage: scripts/run_viewer.sh [drape view options...]     e.g. scripts/run_viewer.sh --size 316 --substeps 10
# Environment: DRAPE=path/to/drape (default build/release/drape, built if missing),
#              DRAPE_SCREENSHOT=file.png (headless only, default drape_viewer.png),
#              DRAPE_FRAMES=K (headless only, default 300, ~3 s at the default size).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
drape=${DRAPE:-$root/build/release/drape}

if [ ! -x "$drape" ]; then
    echo "run_viewer: $drape not found; building it (cmake --preset release)" >&2
    (cd "$root" && cmake --preset release >/dev/null && cmake --build --preset release --target drape -j "$(nproc)")
fi

display_works() {
    [ -n "${DISPLAY:-}" ] || return 1
    if command -v xdpyinfo >/dev/null 2>&1; then xdpyinfo >/dev/null 2>&1; return; fi
    if command -v glxinfo >/dev/null 2>&1; then glxinfo -B >/dev/null 2>&1; return; fi
    return 0
}

if display_works; then
    echo "run_viewer: opening the viewer on $DISPLAY (F1 in the window lists the keys)" >&2
    exec "$drape" view "$@"
fi

if ! command -v Xvfb >/dev/null 2>&1; then
    echo "run_viewer: no display and no Xvfb; install it with scripts/setup.sh (Debian package xvfb)" >&2
    exit 2
fi
shot=${DRAPE_SCREENSHOT:-drape_viewer.png}
frames=${DRAPE_FRAMES:-300}
echo "run_viewer: no display; running $frames frames under Xvfb + Mesa llvmpipe (software OpenGL 4.5)" >&2
"$root/scripts/with_xvfb.sh" -s "-screen 0 1600x1000x24" "$drape" view --frames "$frames" --screenshot "$shot" --stats-json \
    --no-vsync "$@"
echo "run_viewer: screenshot saved to $shot" >&2
