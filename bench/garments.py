#!/usr/bin/python3
"""Figures of the garments issue, measured with the real `drape run` CLI (no separate code path):

  1. BENCH.md figure 3, quality-normalised time: wall seconds for 2 s of "hang" with max structural strain <= 10 %
     and every value finite, at N = 32, 100, 316 on 2 threads, with the settings used;
  2. strain limiting: max strain and cost against the number of passes (soft hang, N = 100);
  3. throughput of the garment scenes (tshirt, drape, sphere, flag) on 2 threads, with the stages that ran;
  4. the drape scene's drape coefficient (Cusick: (A_shadow - A_disc) / (A_cloth - A_disc)) for several bending
     stiffnesses, from the exported final frame;
  5. a picture of each scene's final frame (docs/img/scene_<name>.png, matplotlib from the OBJ export).

Writes docs/bench/garments.md (+ .json with every raw result). Usage:
  bench/garments.py [--drape build/release/drape] [--only quality,passes,scenes,drape,pictures]
"""
import argparse
import json
import math
import os
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def run(drape, args):
    cmd = [drape, "run", "--json"] + [str(a) for a in args]
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0 and not p.stdout.strip():
        sys.exit(f"garments.py: {' '.join(cmd)} failed ({p.returncode}): {p.stderr.strip()}")
    j = json.loads(p.stdout.strip().splitlines()[-1])
    j["command"] = "drape run " + " ".join(str(a) for a in args)
    print(f"  {j['command']}: wall {j['wall_seconds']:.2f} s, max strain {j['max_strain']:.4f}, "
          f"{j['particle_substeps_per_second']:.3g} p-s/s", file=sys.stderr)
    return j


def read_obj(path):
    v, f = [], []
    with open(path) as fh:
        for line in fh:
            if line.startswith("v "):
                v.append(tuple(float(t) for t in line.split()[1:4]))
            elif line.startswith("f "):
                f.append(tuple(int(t.split("/")[0]) - 1 for t in line.split()[1:4]))
    return v, f


def shadow_area(vertices, faces, cell=0.002):
    """Area of the union of the triangles projected on the x-z plane, by rasterising on a fine grid."""
    import numpy as np
    xs = np.array([p[0] for p in vertices]); zs = np.array([p[2] for p in vertices])
    x0, z0 = xs.min() - cell, zs.min() - cell
    nx, nz = int((xs.max() - x0) / cell) + 2, int((zs.max() - z0) / cell) + 2
    covered = np.zeros((nz, nx), dtype=bool)
    for a, b, c in faces:
        px = np.array([xs[a], xs[b], xs[c]]); pz = np.array([zs[a], zs[b], zs[c]])
        i0, i1 = int((px.min() - x0) / cell), int((px.max() - x0) / cell) + 1
        k0, k1 = int((pz.min() - z0) / cell), int((pz.max() - z0) / cell) + 1
        gx, gz = np.meshgrid(x0 + (np.arange(i0, i1) + 0.5) * cell, z0 + (np.arange(k0, k1) + 0.5) * cell)
        d = (pz[1] - pz[2]) * (px[0] - px[2]) + (px[2] - px[1]) * (pz[0] - pz[2])
        if abs(d) < 1e-18:
            continue
        l1 = ((pz[1] - pz[2]) * (gx - px[2]) + (px[2] - px[1]) * (gz - pz[2])) / d
        l2 = ((pz[2] - pz[0]) * (gx - px[2]) + (px[0] - px[2]) * (gz - pz[2])) / d
        inside = (l1 >= 0) & (l2 >= 0) & (l1 + l2 <= 1)
        covered[k0:k1, i0:i1] |= inside
    return covered.sum() * cell * cell


def render(obj_path, png_path, title, colliders=()):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection
    import numpy as np
    v, f = read_obj(obj_path)
    v = np.array(v)
    # Matplotlib's 3-D axes are z-up: show drape's y-up world as (x, z, y).
    tris = v[np.array(f)][:, :, [0, 2, 1]]
    n = np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0])
    n /= np.linalg.norm(n, axis=1, keepdims=True) + 1e-12
    light = np.array([0.4, -0.5, 0.75]); light /= np.linalg.norm(light)
    shade = 0.25 + 0.75 * np.abs(n @ light)
    colours = np.outer(shade, np.array([0.85, 0.35, 0.25]))
    fig = plt.figure(figsize=(6, 6), dpi=110)
    ax = fig.add_subplot(projection="3d")
    ax.add_collection3d(Poly3DCollection(tris, facecolors=np.clip(colours, 0, 1), edgecolor="none"))
    lo, hi = v.min(axis=0), v.max(axis=0)
    c, r = (lo + hi) / 2, (hi - lo).max() / 2 * 1.1
    ax.set_xlim(c[0] - r, c[0] + r); ax.set_ylim(c[2] - r, c[2] + r); ax.set_zlim(c[1] - r, c[1] + r)
    ax.view_init(elev=14, azim=-60)
    ax.set_title(title, fontsize=10)
    ax.set_axis_off()
    fig.tight_layout()
    fig.savefig(png_path)
    plt.close(fig)


def final_frame(drape, scene_args, sim_seconds, workdir, threads=2):
    """Runs a scene for sim_seconds with an OBJ export of the initial and the final frame; returns (json, obj path)."""
    out = os.path.join(workdir, "obj")
    subprocess.run(["rm", "-rf", out])
    j = run(drape, scene_args + ["--threads", threads, "--sim-seconds", sim_seconds, "--export-obj", out,
                                 "--every", 1000000000])
    frames = sorted(os.listdir(out))
    return j, os.path.join(out, frames[-1])


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--drape", default=os.path.join(ROOT, "build", "release", "drape"))
    ap.add_argument("--only", default="quality,passes,scenes,drape,pictures")
    ap.add_argument("--out", default=os.path.join(ROOT, "docs", "bench", "garments.md"))
    a = ap.parse_args()
    if not os.access(a.drape, os.X_OK):
        sys.exit(f"garments.py: {a.drape} not found; build it: cmake --preset release && cmake --build --preset release")
    only = set(a.only.split(","))
    results, md = {}, ["# Garment, quality and scene figures", "",
                       f"Measured by `bench/garments.py` with `{os.path.relpath(a.drape, ROOT)}` on this machine "
                       f"(2 cores, AVX-512). Every row is one `drape run` (command shown).", ""]
    work = tempfile.mkdtemp(prefix="drape_garments_")

    if "quality" in only:
        print("quality-normalised figure", file=sys.stderr)
        rows = []
        for n, extra in [(32, []), (100, []), (316, ["--stiffness", 2000])]:
            j = run(a.drape, ["--scene", "hang", "--size", n, "--threads", 2, "--sim-seconds", 2] + extra)
            j["pass"] = bool(j["finite"] and j["max_strain"] <= 0.10)
            rows.append(j)
        results["quality"] = rows
        md += ["## BENCH.md figure 3: quality-normalised time (2 s of hang, max structural strain <= 10 %, finite)", "",
               "| N | particles | settings | substeps | dt (s) | max strain at 2 s | finite | wall (s) | passes |",
               "|---|---|---|---|---|---|---|---|---|"]
        for j in rows:
            settings = (f"k = {j['stiffness']:g} N/m, shear 0.5 k, bend 0.1 k, damping 0.05, drag 0.2/s, "
                        f"strain limit {'off' if j['strain_limit'] == 0 else j['strain_limit']}")
            md.append(f"| {j['n']} | {j['particles']} | {settings} | {j['substeps']} | {j['dt']:.3g} | "
                      f"{j['max_strain']:.4f} | {j['finite']} | {j['wall_seconds']:.2f} | "
                      f"{'yes' if j['pass'] else 'no'} |")
        md.append("")

    if "passes" in only:
        print("strain limiting passes", file=sys.stderr)
        rows = [run(a.drape, ["--scene", "hang", "--size", 100, "--threads", 2, "--stiffness", 100, "--sim-seconds", 1,
                               "--strain-limit", 0 if p == 0 else 0.1] + ([] if p == 0 else ["--strain-passes", p]))
                for p in (0, 1, 2, 4, 8)]
        results["passes"] = rows
        base = rows[0]["wall_seconds"]
        md += ["## Strain limiting: max strain and cost against passes (hang N = 100, k = 100 N/m, limit 10 %, 1 s)", "",
               "| passes | max strain at 1 s | wall (s) | cost vs no limiting |", "|---|---|---|---|"]
        for p, j in zip((0, 1, 2, 4, 8), rows):
            md.append(f"| {'off' if p == 0 else p} | {j['max_strain']:.4f} | {j['wall_seconds']:.2f} | "
                      f"{j['wall_seconds'] / base:.2f}x |")
        md.append("")

    if "scenes" in only or "pictures" in only:
        print("scenes", file=sys.stderr)
        rows = []
        os.makedirs(os.path.join(ROOT, "docs", "img"), exist_ok=True)
        for name, secs in [("tshirt", 2), ("drape", 2), ("sphere", 2), ("flag", 2), ("hang", 2)]:
            j, obj = final_frame(a.drape, ["--scene", name], secs, work)
            rows.append(j)
            if "pictures" in only:
                png = os.path.join(ROOT, "docs", "img", f"scene_{name}.png")
                render(obj, png, f"{name}: {j['particles']} particles, t = {j['sim_seconds']:.2f} s")
                j["picture"] = os.path.relpath(png, os.path.join(ROOT, "docs"))
        results["scenes"] = rows
        md += ["## Scenes on 2 threads (2 s simulated each)", "",
               "| scene | particles | springs (seams) | substeps | dt (s) | particle-substeps/s | max strain | stages |",
               "|---|---|---|---|---|---|---|---|"]
        for j in rows:
            md.append(f"| {j['scene']} | {j['particles']} | {j['springs']} ({j['seam_springs']}) | {j['substeps']} | "
                      f"{j['dt']:.3g} | {j['particle_substeps_per_second']:.3g} | {j['max_strain']:.4f} | "
                      f"{' + '.join(j['stages'])} |")
        md.append("")
        if "pictures" in only:
            md += [f"![{j['scene']}]({j['picture']})" for j in rows] + [""]

    if "drape" in only:
        print("drape coefficient", file=sys.stderr)
        rows = []
        base = json.load(open(os.path.join(ROOT, "scenes", "drape.json")))
        disc = next(c for c in base["colliders"] if c["type"] == "disc")
        a_disc = math.pi * disc["radius"] ** 2
        a_cloth = base["cloth"]["size"] ** 2
        for bend in (0.0, 0.02, 0.1, 0.3, 1.0):
            scene = json.loads(json.dumps(base))
            scene["material"]["bend_ratio"] = bend
            path = os.path.join(work, f"drape_bend_{bend}.json")
            json.dump(scene, open(path, "w"))
            j, obj = final_frame(a.drape, ["--scene", path], 3, work)
            v, f = read_obj(obj)
            shadow = shadow_area(v, f)
            j["bend_ratio"] = bend
            j["shadow_area"] = shadow
            j["drape_coefficient"] = (shadow - a_disc) / (a_cloth - a_disc)
            rows.append(j)
        results["drape"] = rows
        md += ["## Drape coefficient of the drape scene (seed 001's cloth on a disc, Cusick's shadow ratio)", "",
               f"(A_shadow - A_disc) / (A_cloth - A_disc), A_cloth = {a_cloth:.3f} m^2, A_disc = {a_disc:.4f} m^2 "
               "(radius 0.15 m); the shadow is the union of the final frame's triangles projected on the floor "
               "(rasterised at 2 mm), after 3 s. Structural k = 1000 N/m; bend k = ratio x 1000 N/m.", "",
               "| bend ratio | bend k (N/m) | shadow area (m^2) | drape coefficient | max strain |", "|---|---|---|---|---|"]
        for j in rows:
            md.append(f"| {j['bend_ratio']} | {j['bend_ratio'] * 1000:g} | {j['shadow_area']:.4f} | "
                      f"{j['drape_coefficient']:.3f} | {j['max_strain']:.4f} |")
        md.append("")

    os.makedirs(os.path.dirname(a.out), exist_ok=True)
    with open(a.out, "w") as fh:
        fh.write("\n".join(md) + "\n")
    with open(os.path.splitext(a.out)[0] + ".json", "w") as fh:
        json.dump(results, fh, indent=1)
    print("\n".join(md))


if __name__ == "__main__":
    main()
