#!/usr/bin/env python3
"""Where a hex mesh's mean scaled Jacobian is lost: the elements grouped by
whether they have a boundary face and by size (mean edge length against the
median element's: small < 0.6, middle 0.6-0.85, large >= 0.85; with local
refinement the small ones are mostly split voxels' and the middle ones
transition templates' or thin boundary-layer elements), with each group's count,
mean and its share of the deficit sum(0.85 - SJ) (BENCHMARKS.md "The mean and
the fit of refined meshes").

    python3 benches/sj_classes.py HEX.vtk

HEX.vtk is a legacy VTK unstructured grid of hexahedra with the cell data
`scaled_jacobian` (hex.vtk of `sddpm run`, /tmp/voxel_probe.vtk of
the probe examples/hex_probe.rs (removed from the tree; `git show 19585e7:examples/hex_probe.rs`)). Needs numpy.
"""
import sys
from collections import Counter

import numpy as np

from surface_gap import FACES, read_vtk

EDGES = [(0, 1), (1, 2), (2, 3), (3, 0), (4, 5), (5, 6), (6, 7), (7, 4), (0, 4), (1, 5), (2, 6), (3, 7)]


def cell_values(path, name, n):
    lines = open(path).read().split("\n")
    i = next((k for k, l in enumerate(lines) if l.startswith("SCALARS " + name)), None)
    if i is None:
        sys.exit(f"{path}: no cell data '{name}'")
    vals = []
    for l in lines[i + 2:]:
        if len(vals) >= n:
            break
        vals += [float(x) for x in l.split()]
    return np.array(vals[:n])


def main():
    path = sys.argv[1]
    pts, cells = read_vtk(path)
    sj = cell_values(path, "scaled_jacobian", len(cells))
    count = Counter(tuple(sorted(c[k] for k in f)) for c in cells for f in FACES)
    boundary = np.array([any(count[tuple(sorted(c[k] for k in f))] == 1 for f in FACES) for c in cells])
    size = np.array([np.mean([np.linalg.norm(pts[c[a]] - pts[c[b]]) for a, b in EDGES]) for c in cells])
    med = np.median(size)
    print(f"{len(cells)} elements, mean {sj.mean():.3f}, min {sj.min():.3f}; deficit sum(0.85 - SJ) = {(0.85 - sj).sum():.1f}")
    for bname, b in (("boundary", boundary), ("interior", ~boundary)):
        for sname, s in (("small", size < 0.6 * med), ("middle", (size >= 0.6 * med) & (size < 0.85 * med)), ("large", size >= 0.85 * med)):
            k = b & s
            if k.any():
                print(f"  {bname:9s} {sname:6s} {k.sum():6d} elements, mean {sj[k].mean():.3f}, deficit {(0.85 - sj[k]).sum():7.1f}")


if __name__ == "__main__":
    main()
