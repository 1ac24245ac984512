#!/usr/bin/env python3
"""Write the square torus of the unit tests (src/mesh/tests.rs `square_torus`: a
3 x 3 x 1 block of unit voxels without the centre one, every face on x, y, z
integers) as an OBJ file, for the probe examples/hex_probe.rs (removed from the tree; `git show 19585e7:examples/hex_probe.rs`) (BENCHMARKS.md "Features on
the lattice").

    python3 benches/square_torus.py OUT.obj
"""
import sys

FACES = [
    ((-1, 0, 0), [(0, 0, 0), (0, 0, 1), (0, 1, 1), (0, 1, 0)]),
    ((1, 0, 0), [(1, 0, 0), (1, 1, 0), (1, 1, 1), (1, 0, 1)]),
    ((0, -1, 0), [(0, 0, 0), (1, 0, 0), (1, 0, 1), (0, 0, 1)]),
    ((0, 1, 0), [(0, 1, 0), (0, 1, 1), (1, 1, 1), (1, 1, 0)]),
    ((0, 0, -1), [(0, 0, 0), (0, 1, 0), (1, 1, 0), (1, 0, 0)]),
    ((0, 0, 1), [(0, 0, 1), (1, 0, 1), (1, 1, 1), (0, 1, 1)]),
]


def filled(x, y, z):
    return 0 <= x < 3 and 0 <= y < 3 and z == 0 and not (x == 1 and y == 1)


def main():
    ids, tris = {}, []

    def vid(p):
        return ids.setdefault(p, len(ids))

    for x in range(3):
        for y in range(3):
            if not filled(x, y, 0):
                continue
            for d, corners in FACES:
                if filled(x + d[0], y + d[1], d[2]):
                    continue
                v = [vid((x + o[0], y + o[1], o[2])) for o in corners]
                tris += [(v[0], v[1], v[2]), (v[0], v[2], v[3])]
    with open(sys.argv[1], "w") as f:
        for p, _ in sorted(ids.items(), key=lambda a: a[1]):
            f.write("v %d %d %d\n" % p)
        for t in tris:
            f.write("f %d %d %d\n" % (t[0] + 1, t[1] + 1, t[2] + 1))


if __name__ == "__main__":
    main()
