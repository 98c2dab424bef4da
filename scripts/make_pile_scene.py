#!/usr/bin/env python3
"""Writes scenes/examples/pile.json: the cloth pile of issue 9 (docs/self_collision.md).

A 64 x 64 wool cloth, 1 m, crumpled into deep pleats: its rows follow the curve y = A sin(k x) by arc length (A = 5 cm,
a pleat every 12 cm, so A k = 2.6), the sheet tilted by 25 degrees about z, its lowest point 5 cm above the ground, at
rest. The straight springs across a pleat's tip start up to 11 % short: the start flings a particle at 8.4 m/s in the
first explicit substep (placed a straight spacing apart instead, it starts still, but the implicit pile test then
crosses itself: docs/self_collision.md). Dropped, the pleats fall over onto each other. Self-collision on (h = 4 mm).
Usage: python3 scripts/make_pile_scene.py [OUT.json]
"""
import json
import math
import sys

N = 64
AMPLITUDE = 0.05
WAVE = 2.0 * 3.14159265358979 / 0.12
TILT = 25.0 * 3.14159265358979 / 180.0


def row_positions():
    """x, y of each row i (arc length i / (N - 1) along the curve), tilted."""
    cx, cs = [0.0], [0.0]
    k = 1
    while cs[-1] < 1.01:
        x = 1e-5 * k
        dy = AMPLITUDE * (math.sin(WAVE * x) - math.sin(WAVE * (x - 1e-5)))
        cs.append(cs[-1] + math.sqrt(1e-10 + dy * dy))
        cx.append(x)
        k += 1
    rows = []
    at = 0
    for i in range(N):
        s = i / (N - 1)
        while at < len(cs) and cs[at] < s:  # the first table entry with arc length >= s
            at += 1
        x = cx[min(at, len(cx) - 1)]
        y = AMPLITUDE * math.sin(WAVE * x)
        rows.append((math.cos(TILT) * x - math.sin(TILT) * y - 0.2,
                     math.sin(TILT) * x + math.cos(TILT) * y + AMPLITUDE + 0.05))
    return rows


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else "scenes/examples/pile.json"
    rows = row_positions()
    positions = []
    for j in range(N):  # particle j * N + i: column i along the curve, row j along z
        for i in range(N):
            x, y = rows[i]
            positions.append([float("%.9g" % x), float("%.9g" % y), float("%.9g" % (j / (N - 1) - 0.5))])
    scene = {
        "scene": "pile",
        "description": "Issue 9's cloth pile: a 64 x 64 wool cloth, 1 m, crumpled into deep pleats (rows placed by arc "
                       "length: springs across the pleat tips start up to 11 % short), "
                       "dropped onto the ground with self-collision (4 mm). Made by scripts/make_pile_scene.py",
        "cloth": {"type": "grid", "n": N, "size": 1.0, "plane": "horizontal", "centre": [0, 0, 0], "pins": "none"},
        "material": "wool",
        "physics": {"self_collision": {"thickness": 0.004, "friction": 0.3}},
        "colliders": [{"type": "ground", "height": 0, "thickness": 0.002, "friction": 0.5}],
        "state": {"origin": [0, 0, 0], "positions": positions, "velocities": [[0, 0, 0]] * (N * N), "pinned": []},
    }
    state = scene.pop("state")
    text = json.dumps(scene, indent=2)[:-2]  # without the closing brace: the state follows, a particle a line
    triples = lambda key: ",\n      ".join(json.dumps(p) for p in state[key])
    text += (',\n  "state": {\n    "origin": [0, 0, 0],\n    "positions": [\n      ' + triples("positions") +
             '],\n    "velocities": [\n      ' + triples("velocities") + '],\n    "pinned": []\n  }\n}\n')
    with open(out, "w") as f:
        f.write(text)


if __name__ == "__main__":
    main()
