#!/usr/bin/env python3
"""Where a hex mesh misses its input: the input vertices farthest from the mesh
boundary (every boundary quad as four triangles around its centre, exact
point-triangle distances, as the library's Hausdorff distance measures it),
relative to the input's bounding-box diagonal (BENCHMARKS.md "With mean
ascent", cgal_spool). Until 2026-12-05 the quads were sampled 5 x 5 and the
nearest sample taken, which overstates the distance by up to half a sample
spacing on coarse meshes (HexGen's rod: 0.98 % sampled, 0.48 % exact).

    python3 benches/surface_gap.py INPUT.off|INPUT.obj HEX.vtk [N]

HEX.vtk is a legacy VTK unstructured grid of hexahedra in the input's
coordinates (hex.vtk of `sddpm run`, or /tmp/voxel_probe.vtk of
the probe examples/hex_probe.rs (removed from the tree; `git show 19585e7:examples/hex_probe.rs`)). Needs numpy.
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


def point_triangles(p, t):
    """Smallest distance from point p to the triangles t (n x 3 x 3): the closest
    point by the Voronoi regions of each triangle's vertices, edges and face."""
    a, b, c = t[:, 0], t[:, 1], t[:, 2]
    ab, ac, ap = b - a, c - a, p - a
    d1, d2 = (ab * ap).sum(1), (ac * ap).sum(1)
    bp = p - b
    d3, d4 = (ab * bp).sum(1), (ac * bp).sum(1)
    cp = p - c
    d5, d6 = (ab * cp).sum(1), (ac * cp).sum(1)
    va = d3 * d6 - d5 * d4
    vb = d5 * d2 - d1 * d6
    vc = d1 * d4 - d3 * d2
    den = va + vb + vc
    den = np.where(np.abs(den) > 1e-300, den, 1e-300)
    v = vb / den
    w = vc / den
    q = a + ab * v[:, None] + ac * w[:, None]
    # edge regions
    with np.errstate(divide="ignore", invalid="ignore"):
        e_ab = np.clip(d1 / np.where(d1 - d3 != 0, d1 - d3, 1), 0, 1)
        e_ac = np.clip(d2 / np.where(d2 - d6 != 0, d2 - d6, 1), 0, 1)
        e_bc = np.clip((d4 - d3) / np.where((d4 - d3) + (d5 - d6) != 0, (d4 - d3) + (d5 - d6), 1), 0, 1)
    q = np.where(((vc <= 0) & (d1 >= 0) & (d3 <= 0))[:, None], a + ab * e_ab[:, None], q)
    q = np.where(((vb <= 0) & (d2 >= 0) & (d6 <= 0))[:, None], a + ac * e_ac[:, None], q)
    q = np.where(((va <= 0) & (d4 - d3 >= 0) & (d5 - d6 >= 0))[:, None], b + (c - b) * e_bc[:, None], q)
    q = np.where(((d1 <= 0) & (d2 <= 0))[:, None], a, q)
    q = np.where(((d3 >= 0) & (d4 <= d3))[:, None], b, q)
    q = np.where(((d6 >= 0) & (d5 <= d6))[:, None], c, q)
    return np.sqrt(((q - p) ** 2).sum(1)).min()


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
    tris = []
    for key, n in count.items():
        if n != 1:
            continue
        q = pts[faces[key]]
        c = q.mean(0)
        for k in range(4):
            tris.append((q[k], q[(k + 1) % 4], c))
    tris = np.array(tris)
    verts = read_surface(surf)
    diag = np.linalg.norm(verts.max(0) - verts.min(0))
    d = np.array([point_triangles(v, tris) for v in verts]) / diag
    print(f"{len(verts)} input vertices, {len(tris)} boundary triangles; largest distances / diagonal:")
    for i in np.argsort(-d)[:top]:
        print(f"  vertex {i} at {np.round(verts[i], 3).tolist()}: {100 * d[i]:.2f} %")


if __name__ == "__main__":
    main()
