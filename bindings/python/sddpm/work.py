"""The unit of work for scale-out: one mesh file in, one result folder out.

``mesh_file`` is a plain function of picklable arguments returning a small dict, so
any scheduler can run it; with Dask (distributed) on many machines::

    from dask.distributed import Client
    client = Client("scheduler:8786")                # or LocalCluster() on one machine
    futures = client.map(sddpm.work.mesh_file, paths, out_dirs, level=2)
    summaries = client.gather(futures)

Each worker process loads the library and the embedded model once (cached per
process); errors are returned in the summary (status and message), not raised,
so one bad file does not fail the whole map.
"""

from __future__ import annotations

import json
import os
import time
from typing import Optional

_MODEL = None


def _model():
    global _MODEL
    if _MODEL is None:
        from . import Model

        _MODEL = Model.embedded()
    return _MODEL


def mesh_file(path: str, out_dir: str, contexts: Optional[str] = None, level: Optional[int] = None, seed: int = 0,
              steps: Optional[int] = None, spline: bool = True) -> dict:
    """Mesh one file: polycube (user contexts or automated), hex mesh, spline; write
    hex.vtu, hex.k, spline.bext, model.k and summary.json into out_dir. Returns the summary."""
    from . import Contexts, HexMesh, Mesh, Polycube, SddpmError, SddpmValueError, Spline

    t0 = time.time()
    summary = {"file": str(path), "folder": str(out_dir), "status": "OK"}
    try:
        os.makedirs(out_dir, exist_ok=True)
        mesh = Mesh.load(path)
        mesh.validate()
        summary["genus"] = mesh.genus
        ctx = Contexts.parse(contexts) if contexts else None
        pc = Polycube.generate(_model(), mesh, ctx, seed=seed, steps=steps)
        hexm = HexMesh.build(pc, level=-1 if level is None else level)
        hexm.write(os.path.join(out_dir, "hex.vtu"))
        hexm.write(os.path.join(out_dir, "hex.k"))
        q = hexm.quality()
        summary.update({k: q[k] for k in ("elements", "min_scaled_jacobian", "mean_scaled_jacobian", "inverted", "hausdorff_relative", "level")})
        summary["verified_polycube"] = bool(q["verified_polycube"])
        if spline:
            sp = Spline.build(hexm)
            sp.write(out_dir)
            summary["basis_functions"] = sp.counts()[1]
    except (SddpmError, SddpmValueError) as e:
        summary.update({"status": e.name, "error": e.message})
    except FileNotFoundError as e:
        summary.update({"status": "IO", "error": f"{e.filename}: {e.strerror}"})
    summary["seconds"] = time.time() - t0
    summary["worker_pid"] = os.getpid()
    try:
        with open(os.path.join(out_dir, "summary.json"), "w") as f:
            json.dump(summary, f, indent=2)
    except OSError:
        pass
    return summary
