#!/usr/bin/env python3
"""Viewer frame rate against particle count (BENCH.md figure 4, seed 000's experiment).

Runs the real viewer (`drape view`) under Xvfb + Mesa llvmpipe for each size of scene "hang" with a fixed number of
substeps per frame, no vsync, panels shown as a user sees them, and collects its --stats-json: the median FPS over the
frames after the first few, and the median milliseconds of simulation, publish (normals + vertex writes into the
mapped buffer) and draw (GL calls + panels + swap, where llvmpipe rasterises; it includes the fence wait).

Writes viewer_fps.json (raw objects), viewer_fps.csv, viewer_fps.md (table) and viewer_fps.png (plot, when matplotlib
is importable) into --out.

Usage: python3 docs/bench/viewer_fps.py --drape build/release/drape [--out docs/bench] [--substeps 10] [--quick]
"""
import argparse
import csv
import json
import os
import shutil
import subprocess
import sys
import time

# (target particle count of seed 000's experiment and beyond, N: particles per side, N^2 nearest the target)
# A private Xvfb per run (the repository's scripts/with_xvfb.sh).
WITH_XVFB = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "scripts", "with_xvfb.sh")
SIZES = [(100, 10), (300, 17), (500, 22), (700, 26), (900, 30), (1100, 33), (1300, 36), (1600, 40), (3600, 60),
         (6400, 80), (10000, 100), (100000, 316), (250000, 500), (1000000, 1000)]
SEED000 = {100: 60, 300: 50, 500: 31, 700: 22, 900: 16, 1100: 13, 1300: 10, 1600: 8, 3600: 5, 6400: 3}


def frames_for(n):
    # About 2-4 s of drawing per point; enough frames for a stable median.
    if n <= 100:
        return 300
    if n <= 316:
        return 150
    if n <= 500:
        return 100
    return 60


def run(drape, n, substeps, full_mesh, width, height):
    cmd = [WITH_XVFB, "-s", "-screen 0 1600x1000x24", drape, "view", "--size", str(n), "--substeps",
           str(substeps), "--frames", str(frames_for(n)), "--no-vsync", "--stats-json", "--width", str(width),
           "--height", str(height)]
    if full_mesh:
        cmd.append("--full-mesh")
    load = os.getloadavg()[0]
    t0 = time.time()
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=1200)
    if p.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)} exited {p.returncode}: {p.stderr}")
    j = json.loads(p.stdout.strip().splitlines()[-1])
    j["full_mesh"] = full_mesh
    j["load_before"] = load
    j["wall_seconds"] = time.time() - t0
    return j


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--drape", help="the drape executable (required unless --from-json)")
    ap.add_argument("--out", default=os.path.dirname(os.path.abspath(__file__)))
    ap.add_argument("--substeps", type=int, default=10)
    ap.add_argument("--width", type=int, default=1280)
    ap.add_argument("--height", type=int, default=800)
    ap.add_argument("--quick", action="store_true", help="only up to 10k particles")
    ap.add_argument("--from-json", help="rewrite the table and plot from a saved viewer_fps.json (no runs)")
    args = ap.parse_args()
    if args.from_json:
        results = json.load(open(args.from_json))
        write_outputs(results, args)
        return
    if not args.drape:
        sys.exit("viewer_fps: --drape is required (or --from-json)")
    if not shutil.which("Xvfb"):
        sys.exit("viewer_fps: Xvfb not found (scripts/setup.sh installs xvfb)")

    results = []
    for target, n in SIZES:
        if args.quick and n > 100:
            break
        variants = [False, True] if n >= 316 else [False]
        for full in variants:
            j = run(args.drape, n, args.substeps, full, args.width, args.height)
            j["target"] = target
            results.append(j)
            f = j["frame_ms"]
            print(f"N={n:5d} {j['particles']:8d} particles{' full mesh' if full else '          '}: "
                  f"{j['fps']:7.1f} FPS  sim {f['sim']:7.2f} ms  publish {f['publish']:6.2f} ms  "
                  f"draw {f['draw']:7.2f} ms  (triangles drawn {j['triangles_drawn']}, load {j['load_before']:.2f})",
                  flush=True)

    os.makedirs(args.out, exist_ok=True)
    with open(os.path.join(args.out, "viewer_fps.json"), "w") as fh:
        json.dump(results, fh, indent=1)
    write_outputs(results, args)


def write_outputs(results, args):
    os.makedirs(args.out, exist_ok=True)
    cols = ["target", "particles", "n", "full_mesh", "triangles", "triangles_drawn", "substeps_per_frame", "threads",
            "fps", "sim_ms", "publish_ms", "draw_ms", "swap_ms", "total_ms", "load_before"]
    with open(os.path.join(args.out, "viewer_fps.csv"), "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(cols)
        for j in results:
            f = j["frame_ms"]
            w.writerow([j["target"], j["particles"], j["n"], int(j["full_mesh"]), j["triangles"], j["triangles_drawn"],
                        j["substeps_per_frame"], j["threads"], f"{j['fps']:.2f}", f"{f['sim']:.3f}",
                        f"{f['publish']:.3f}", f"{f['draw']:.3f}", f"{f['swap']:.3f}", f"{f['total']:.3f}",
                        f"{j['load_before']:.2f}"])

    r0 = results[0]
    loads = [j["load_before"] for j in results]
    md = [f"Viewer frame rate, scene hang, {results[0]['substeps_per_frame']} substeps per frame, {r0['threads']} threads, "
          f"{r0['framebuffer'][0]}x{r0['framebuffer'][1]} window with panels, no vsync, "
          f"{r0['gl_renderer']} ({r0['gl_version']}) under Xvfb. Medians over the frames after the first few. "
          f"1-minute load average before the runs: {min(loads):.2f} to {max(loads):.2f} (the viewer's own runs "
          f"included). Every row is the viewer's default except those marked --full-mesh, which draw every triangle.",
          "",
          "| particles | N | seed 000 FPS | drape FPS | sim ms | publish ms | draw ms | triangles drawn |",
          "|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for j in results:
        f = j["frame_ms"]
        seed = SEED000.get(j["target"], "")
        tri = f"{j['triangles_drawn']:,}" + (" (all, --full-mesh)" if j["full_mesh"] else " (all)" if
                                             j["lod_stride"] == 1 else f" (1 row and column in {j['lod_stride']})")
        md.append(f"| {j['particles']:,} | {j['n']} | {seed} | {j['fps']:.1f} | {f['sim']:.2f} | {f['publish']:.2f} | "
                  f"{f['draw']:.2f} | {tri} |")
    with open(os.path.join(args.out, "viewer_fps.md"), "w") as fh:
        fh.write("\n".join(md) + "\n")
    print("\n".join(md))

    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("viewer_fps: matplotlib not importable; no plot (use Debian's /usr/bin/python3 with python3-matplotlib)")
        return
    lod = [j for j in results if not j["full_mesh"]]
    full = [j for j in results if j["full_mesh"]]
    fig, (a, b) = plt.subplots(1, 2, figsize=(13, 5))
    a.loglog([j["particles"] for j in lod], [j["fps"] for j in lod], "o-", label="drape viewer")
    if full:
        a.loglog([j["particles"] for j in full], [j["fps"] for j in full], "s--", label="drape, every triangle drawn")
    a.loglog(list(SEED000), list(SEED000.values()), "x:", color="grey", label="seed 000 (Python, 1 step/frame)")
    a.axhline(60, color="green", lw=0.8, ls="--")
    a.axhline(30, color="orange", lw=0.8, ls="--")
    a.set_xlabel("particles")
    a.set_ylabel("frames per second")
    a.set_title(f"Viewer FPS, {results[0]['substeps_per_frame']} substeps/frame, llvmpipe, 2 cores")
    a.grid(True, which="both", alpha=0.3)
    a.legend()
    px = [j["particles"] for j in lod]
    for key, label, style in (("total", "whole frame", "k-"), ("draw", "draw (GL + panels + swap)", "o-"),
                              ("sim", "simulation (10 substeps)", "s-"),
                              ("publish", "publish (normals + vertex writes)", "^-")):
        b.loglog(px, [max(j["frame_ms"][key], 1e-3) for j in lod], style, label=label)
    if full:
        b.loglog([j["particles"] for j in full], [j["frame_ms"]["draw"] for j in full], "o--", color="C0",
                 alpha=0.5, label="draw, every triangle")
    b.set_xlabel("particles")
    b.set_ylabel("ms per frame (median)")
    b.set_title("Where a frame goes")
    b.legend(fontsize=8)
    b.grid(True, which="both", alpha=0.3)
    fig.tight_layout()
    fig.savefig(os.path.join(args.out, "viewer_fps.png"), dpi=110)
    print("viewer_fps: wrote", os.path.join(args.out, "viewer_fps.png"))


if __name__ == "__main__":
    main()
