#!/usr/bin/env python3
"""Write the generated pathological inputs of BENCHMARKS.md "Bad and pathological
inputs" into a folder (default /tmp/patho): a 1e6 x 1 x 1e-6 box, a unit box scaled
by 1e307 and by 1e-300, a flat two-sided square, and a binary STL of 10^7 random
triangles (500 MB; numpy, seed 0); with --limit also a closed torus of exactly
MAX_TRIANGLES = 5,000,000 triangles (binary STL, 250 MB), the largest input the
library accepts, for the memory and time figures of docs/errors.md "Limits"."""
import struct
import sys
from pathlib import Path

import numpy as np

args = [a for a in sys.argv[1:] if not a.startswith("--")]
out = Path(args[0] if args else "/tmp/patho")
out.mkdir(parents=True, exist_ok=True)


def box(sx, sy, sz):
    v = np.array([[x, y, z] for z in (0, sz) for y in (0, sy) for x in (0, sx)], float)
    quads = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]]
    t = []
    for a in quads:
        t += [[a[0], a[1], a[2]], [a[0], a[2], a[3]]]
    return v, np.array(t)


def off(name, v, t):
    with open(out / name, "w") as f:
        f.write(f"OFF\n{len(v)} {len(t)} 0\n")
        for p in v:
            f.write(f"{p[0]:.17g} {p[1]:.17g} {p[2]:.17g}\n")
        for a in t:
            f.write(f"3 {a[0]} {a[1]} {a[2]}\n")


off("aspect_1e12.off", *box(1e6, 1, 1e-6))
v, t = box(1, 1, 1)
off("near_f64_max.off", v * 1e307, t)
off("tiny_1e-300.off", v * 1e-300, t)
off("coplanar.off", np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float), np.array([[0, 1, 2], [0, 2, 3], [0, 2, 1], [0, 3, 2]]))
n = 10_000_000
rec = np.zeros(n, dtype=[("n", "<f4", 3), ("v", "<f4", 9), ("a", "<u2")])
rec["v"] = np.random.default_rng(0).random((n, 9), dtype=np.float32)
with open(out / "huge_1e7.stl", "wb") as f:
    f.write(b"huge".ljust(80, b" "))
    f.write(struct.pack("<I", n))
    f.write(rec.tobytes())
if "--limit" in sys.argv:
    # torus: major radius 1, minor 0.35, nu x nv quads split in two = 5,000,000 triangles
    nu, nv = 2000, 1250
    u = np.arange(nu) * 2 * np.pi / nu
    w = np.arange(nv) * 2 * np.pi / nv
    uu, ww = np.meshgrid(u, w, indexing="ij")
    pts = np.stack([(1 + 0.35 * np.cos(ww)) * np.cos(uu), (1 + 0.35 * np.cos(ww)) * np.sin(uu), 0.35 * np.sin(ww)], -1).astype(np.float32)
    i, j = np.meshgrid(np.arange(nu), np.arange(nv), indexing="ij")
    a, b = pts[i, j], pts[(i + 1) % nu, j]
    c, d = pts[(i + 1) % nu, (j + 1) % nv], pts[i, (j + 1) % nv]
    tris = np.concatenate([np.stack([a, b, c], 2).reshape(-1, 9), np.stack([a, c, d], 2).reshape(-1, 9)])
    rec = np.zeros(len(tris), dtype=[("n", "<f4", 3), ("v", "<f4", 9), ("a", "<u2")])
    rec["v"] = tris
    with open(out / "torus_5m.stl", "wb") as f:
        f.write(b"torus at the triangle limit".ljust(80, b" "))
        f.write(struct.pack("<I", len(tris)))
        f.write(rec.tobytes())
print(f"wrote the files into {out}")
