#!/usr/bin/env python3
"""Where a hex mesh puts its elements along one axis: for each tenth of the
mesh's extent along AXIS (0 = x, default), how many elements have their centre
there and their mean edge length (the three edges at node 0 of each element),
to compare a mesh with HexGen's (BENCHMARKS.md "Lattice placement").

    python3 benches/element_sizes.py HEX.vtk [AXIS]

HEX.vtk is a legacy VTK unstructured grid of hexahedra (hex.vtk of `sddpm run`,
/tmp/voxel_probe.vtk of the probe examples/hex_probe.rs (removed from the tree; `git show 19585e7:examples/hex_probe.rs`), or a reference_hex mesh). Needs numpy.
"""
import importlib.util
import os
import sys

import numpy as np

_spec = importlib.util.spec_from_file_location("surface_gap", os.path.join(os.path.dirname(os.path.abspath(__file__)), "surface_gap.py"))
sg = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(sg)


def main():
    path = sys.argv[1]
    axis = int(sys.argv[2]) if len(sys.argv) > 2 else 0
    pts, cells = sg.read_vtk(path)
    p = pts[np.array(cells)]
    centre = p.mean(axis=1)[:, axis]
    edge = sum(np.linalg.norm(p[:, k] - p[:, 0], axis=1) for k in (1, 3, 4)) / 3.0
    lo, hi = pts[:, axis].min(), pts[:, axis].max()
    which = np.minimum(((centre - lo) / (hi - lo) * 10).astype(int), 9)
    print(f"{len(cells)} elements; per tenth of axis {axis} ({lo:.3g} .. {hi:.3g}): elements, mean edge")
    for k in range(10):
        sel = which == k
        mean = edge[sel].mean() if sel.any() else float("nan")
        print(f"  {k}: {int(sel.sum()):6d}  {mean:.3g}")


if __name__ == "__main__":
    main()
