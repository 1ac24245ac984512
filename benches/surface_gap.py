#!/usr/bin/env python3
"""Where a hex mesh misses its input: the input vertices farthest from the mesh
boundary (bilinear boundary quads sampled 5 x 5), relative to the input's
bounding-box diagonal (BENCHMARKS.md "With mean ascent", cgal_spool).

    python3 benches/surface_gap.py INPUT.off|INPUT.obj HEX.vtk [N]

HEX.vtk is a legacy VTK unstructured grid of hexahedra in the input's
coordinates (hex.vtk of `sddpm run`, or /tmp/voxel_probe.vtk of
examples/hex_probe.rs). Needs numpy.
"""
import sys
from collections import Counter

import numpy as np


def read_vtk(path):
    tok = open(path).read().split("\n")
    i = 0
    while not tok[i].startswith("POINTS"):
        i += 1
    n = int(tok[i].split()[1])
    vals = []
    i += 1
    while len(vals) < 3 * n:
        vals += tok[i].split()
        i += 1
    pts = np.array(vals, float).reshape(n, 3)
    while not tok[i].startswith("CELLS"):
        i += 1
    m = int(tok[i].split()[1])
    cells = [[int(x) for x in tok[i + 1 + k].split()[1:]] for k in range(m)]
    return pts, cells


def read_surface(path):
    if path.endswith(".off"):
        t = open(path).read().split()
        nv = int(t[1])
        return np.array(t[4:4 + 3 * nv], float).reshape(nv, 3)
    v = [l.split()[1:4] for l in open(path) if l.startswith("v ")]
    return np.array(v, float)


FACES = [(0, 3, 2, 1), (4, 5, 6, 7), (0, 1, 5, 4), (1, 2, 6, 5), (2, 3, 7, 6), (3, 0, 4, 7)]


def main():
    surf, hexf = sys.argv[1], sys.argv[2]
    top = int(sys.argv[3]) if len(sys.argv) > 3 else 10
    pts, cells = read_vtk(hexf)
    count = Counter()
    for c in cells:
        for f in FACES:
            count[tuple(sorted(c[k] for k in f))] += 1
    faces = {}
    for c in cells:
        for f in FACES:
            faces.setdefault(tuple(sorted(c[k] for k in f)), [c[k] for k in f])
    uv = np.linspace(0.0, 1.0, 5)
    samples = []
    for key, n in count.items():
        if n != 1:
            continue
        q = pts[faces[key]]
        for a in uv:
            for b in uv:
                samples.append((1 - a) * (1 - b) * q[0] + a * (1 - b) * q[1] + a * b * q[2] + (1 - a) * b * q[3])
    samples = np.array(samples)
    verts = read_surface(surf)
    diag = np.linalg.norm(verts.max(0) - verts.min(0))
    d = np.array([np.min(np.linalg.norm(samples - v, axis=1)) for v in verts]) / diag
    print(f"{len(verts)} input vertices, {len(samples)} boundary samples; largest distances / diagonal:")
    for i in np.argsort(-d)[:top]:
        print(f"  vertex {i} at {np.round(verts[i], 3).tolist()}: {100 * d[i]:.2f} %")


if __name__ == "__main__":
    main()
