#!/usr/bin/env python3
"""Plots drape_implicit convergence's CSV: relative energy error against iterations and against wall time, one row
of panels per grid size. Usage: plot_convergence.py convergence.csv out.png (needs python3-matplotlib)."""
import csv
import sys
from collections import defaultdict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main() -> int:
    if len(sys.argv) != 3:
        print("usage: plot_convergence.py convergence.csv out.png", file=sys.stderr)
        return 2
    curves = defaultdict(lambda: defaultdict(list))  # n -> method -> [(k, wall_ms, error)]
    steps = {}
    with open(sys.argv[1], newline="") as f:
        for row in csv.DictReader(f):
            err = float(row["relative_error"])
            steps[int(row["n"])] = float(row["h_s"])
            curves[int(row["n"])][row["method"]].append((int(row["iterations"]), 1e3 * float(row["wall_s"]), err))
    sizes = sorted(curves)
    fig, axes = plt.subplots(len(sizes), 2, figsize=(11, 4 * len(sizes)), squeeze=False)
    for r, n in enumerate(sizes):
        for method, pts in curves[n].items():
            pts = [p for p in pts if p[2] > 0.0]
            axes[r][0].loglog([p[0] for p in pts], [p[2] for p in pts], marker="o", ms=3, label=method)
            axes[r][1].loglog([p[1] for p in pts], [p[2] for p in pts], marker="o", ms=3, label=method)
        axes[r][0].set_xlabel("iterations k")
        axes[r][1].set_xlabel("wall time of the step (ms)")
        for c in range(2):
            axes[r][c].set_ylabel("(G(x_k) - G*) / |G(x_0) - G*|")
            axes[r][c].set_title(f"hang N = {n} ({n * n} particles), one step h = {steps[n]:.4g} s")
            axes[r][c].grid(True, which="both", alpha=0.3)
        axes[r][0].legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(sys.argv[2], dpi=110)
    print(f"wrote {sys.argv[2]}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
