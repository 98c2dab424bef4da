#!/usr/bin/env python3
"""The viewer's tools under Xvfb (app/view_tools.cpp): strain colours, recording, OBJ export and scene saving,
driven through the hidden automation flags --strain-colours, --record, --save-obj and --save-scene.

Checks:
  * --record DIR --frames 12: exit 0, exactly 12 PNG frames of the window's size in DIR;
  * --strain-colours: the screenshot shows the strain colour map (blue..red pixels that are not the cloth's
    red/beige material colours) over a real share of the frame, and --stats-json says strain_colours: true;
  * --save-obj: an OBJ with one 'v' and one 'vn' line per particle and one 'f' line per triangle;
  * --save-scene: a scene file that `drape run --scene FILE` loads and runs (exit 0, same particle count);
  * --record FILE.mp4 (only when ffmpeg is on PATH; otherwise the check is skipped and the script says so): exit 0,
    an MP4 ('ftyp' box) of nonzero size;
  * write failures (a recording, an OBJ or a scene under /proc): exit 5 (write_failed) with one line on stderr
    naming the path.
Exit 0 on success, 1 with a message naming the failed check.

Usage: viewer_tools.py --drape build/release/drape
"""
import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from viewer_smoke import read_png, is_cloth  # noqa: E402  (the same PNG decoder and cloth colours)

# A private Xvfb per run (scripts/with_xvfb.sh: the command's own exit code, nothing added to its output).
WITH_XVFB = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "scripts", "with_xvfb.sh")
XVFB = [WITH_XVFB, "-s", "-screen 0 1600x1000x24"]
failures = []


def check(ok, what):
    print(("ok: " if ok else "FAIL: ") + what)
    if not ok:
        failures.append(what)


def view(drape, *args, timeout=240):
    cmd = XVFB + [drape, "view", "--width", "480", "--height", "320", "--no-vsync", *args]
    return subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)


def stderr_lines(p):
    # with_xvfb.sh and Mesa add nothing on success; keep drape's own lines.
    return [l for l in p.stderr.splitlines() if l.strip()]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--drape", required=True)
    args = ap.parse_args()
    drape = os.path.abspath(args.drape)
    if shutil.which("Xvfb") is None:
        print("skip: Xvfb is not installed")
        return 0
    tmp = tempfile.mkdtemp(prefix="drape_tools_")
    try:
        # 1. PNG recording, strain colours, OBJ and scene at exit, all in one run of a 16 x 16 cloth.
        rec, shot = os.path.join(tmp, "rec"), os.path.join(tmp, "shot.png")
        obj, scene = os.path.join(tmp, "last.obj"), os.path.join(tmp, "saved.json")
        p = view(drape, "--size", "16", "--frames", "12", "--strain-colours", "--record", rec, "--screenshot",
                 shot, "--save-obj", obj, "--save-scene", scene, "--stats-json")
        check(p.returncode == 0, f"recording run exits 0 (got {p.returncode}: {p.stderr.strip()[-300:]})")
        stats = json.loads(p.stdout.strip().splitlines()[-1]) if p.returncode == 0 else {}
        check(stats.get("strain_colours") is True, "--stats-json reports strain_colours: true")
        frames = sorted(f for f in os.listdir(rec) if f.endswith(".png")) if os.path.isdir(rec) else []
        check(len(frames) == 12, f"--record DIR wrote 12 PNG frames (found {len(frames)})")
        if frames:
            w, h, _, _ = read_png(os.path.join(rec, frames[-1]))
            check((w, h) == tuple(stats.get("framebuffer", [0, 0])), f"recorded frames are {w} x {h}, the window's size")
        if os.path.exists(shot):
            w, h, rows, ch = read_png(shot)
            mapped = material = 0
            for row in rows:
                for x in range(0, w * ch, ch):
                    r, g, b = row[x], row[x + 1], row[x + 2]
                    if is_cloth(r, g, b):
                        material += 1
                    elif max(r, g, b) - min(r, g, b) > 70:  # saturated: the strain map (blue/cyan/green/...)
                        mapped += 1
            share = mapped / float(w * h)
            check(share > 0.03, f"strain colours cover {100 * share:.1f}% of the frame (> 3%)")
            check(material < mapped, f"fewer material-coloured pixels ({material}) than strain-coloured ({mapped})")
        else:
            check(False, "screenshot written")
        n = stats.get("particles", 0)
        if os.path.exists(obj):
            lines = open(obj).read().splitlines()
            v = sum(1 for l in lines if l.startswith("v "))
            vn = sum(1 for l in lines if l.startswith("vn "))
            f = sum(1 for l in lines if l.startswith("f "))
            check(v == n and vn == n and f == stats.get("triangles"),
                  f"--save-obj: {v} v, {vn} vn, {f} f lines for {n} particles, {stats.get('triangles')} triangles")
        else:
            check(False, "--save-obj wrote the OBJ")
        if os.path.exists(scene):
            r = subprocess.run([drape, "run", "--scene", scene, "--steps", "5", "--json"], capture_output=True,
                               text=True, timeout=120)
            ran = json.loads(r.stdout) if r.returncode == 0 else {}
            check(r.returncode == 0 and ran.get("particles") == n,
                  f"the saved scene runs with drape run (rc {r.returncode}, {ran.get('particles')} particles)")
        else:
            check(False, "--save-scene wrote the scene file")

        # 2. Video through ffmpeg, when there is one.
        if shutil.which("ffmpeg"):
            mp4 = os.path.join(tmp, "clip.mp4")
            p = view(drape, "--size", "16", "--frames", "30", "--record", mp4)
            size = os.path.getsize(mp4) if os.path.exists(mp4) else 0
            head = open(mp4, "rb").read(12) if size else b""
            check(p.returncode == 0 and size > 1000 and head[4:8] == b"ftyp",
                  f"--record FILE.mp4 wrote an MP4 of {size} bytes (rc {p.returncode})")
        else:
            print("skip: ffmpeg is not on PATH, the .mp4 recording is not checked")

        # 3. Write failures: exit 5 and one line naming the path.
        cases = [("--record", "/proc/drape_no_dir/frames"), ("--save-obj", "/proc/drape_no.obj"),
                 ("--save-scene", "/proc/drape_no/scene.json")]
        if shutil.which("ffmpeg"):
            cases.append(("--record", "/proc/drape_no.mp4"))
        for flag, path in cases:
            p = view(drape, "--size", "16", "--frames", "3", flag, path)
            lines = [l for l in stderr_lines(p) if "drape view" in l]
            check(p.returncode == 5 and len(lines) == 1 and path in lines[0],
                  f"{flag} {path}: exit 5 with one line naming it (rc {p.returncode}, lines {lines})")
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    if failures:
        print(f"{len(failures)} check(s) failed")
        return 1
    print("all viewer tool checks passed")
    return 0


if __name__ == "__main__":
    sys.exit(main())
