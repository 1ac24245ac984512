"""Mesh every file of a folder on a Dask cluster with the Python package's work unit.

    python3 examples/dask_batch.py IN_DIR OUT_DIR [scheduler-address]

Without an address a LocalCluster (one worker process per core) is started; with
one (e.g. tcp://head:8786) the work goes to that cluster's workers, which need the
package themselves (`pip install ./bindings/python`, or a wheel of it: the library
is inside).
"""
import pathlib
import sys

from dask.distributed import Client, LocalCluster

import sddpm


def main():
    src, out = pathlib.Path(sys.argv[1]), pathlib.Path(sys.argv[2])
    files = sorted(p for p in src.iterdir() if p.suffix.lower() in (".obj", ".stl", ".off"))
    client = Client(sys.argv[3]) if len(sys.argv) > 3 else Client(LocalCluster(threads_per_worker=1))
    futures = client.map(sddpm.work.mesh_file, [str(f) for f in files], [str(out / f.stem) for f in files])
    for s in client.gather(futures):
        print(f"{pathlib.Path(s['file']).name:30} {s['status']:20} {s.get('elements', '-')!s:>8} elements  "
              f"min SJ {s.get('min_scaled_jacobian', float('nan')):.3f}  {s['seconds']:.1f} s")
    client.close()


if __name__ == "__main__":
    main()
