"""FreeCAD macro: mesh the selected shape's tessellation with libsddpm.

Select one solid in FreeCAD and run this macro (Macro > Macros... > Execute), with
the `sddpm` Python package on FreeCAD's sys.path (`pip install ./bindings/python`
into FreeCAD's Python: the library comes inside it; or copy bindings/python/sddpm
next to the macro and set SDDPM_LIBRARY to libsddpm.so). It writes the hex mesh
(VTU, LS-DYNA), the spline (BEXT + LS-DYNA deck) and a JSON report into a folder
next to the document (or the temp folder) and prints a summary in the report view.

The work itself is `mesh_tessellation`, which FreeCAD is not needed for (the
package's tests call it on a mesh read from disk).
"""

import json
import os
import tempfile


def mesh_tessellation(points, triangles, out_dir, contexts=None, tolerance_note="", level=None, seed=0):
    """points: (n, 3) floats; triangles: (m, 3) ints. Returns the summary dict."""
    import numpy as np
    import sddpm

    os.makedirs(out_dir, exist_ok=True)
    mesh = sddpm.Mesh.from_arrays(np.asarray(points, dtype=float), np.asarray(triangles, dtype=np.int64))
    mesh.validate()  # raises SddpmError naming the problem (open, non-manifold, ...)
    model = sddpm.Model.embedded()
    ctx = sddpm.Contexts.parse(contexts) if contexts else None
    pc = sddpm.Polycube.generate(model, mesh, ctx, seed=seed)
    hexm = sddpm.HexMesh.build(pc, level=level if level is not None else -1)
    hexm.write(os.path.join(out_dir, "hex.vtu"))
    hexm.write(os.path.join(out_dir, "hex.k"))
    spline = sddpm.Spline.build(hexm)
    spline.write(out_dir)
    q = hexm.quality()
    summary = {
        "genus": mesh.genus,
        "polycube_verified": bool(q["verified_polycube"]),
        "hex": q,
        "spline": {"elements": spline.counts()[0], "basis_functions": spline.counts()[1]},
        "folder": out_dir,
        "tessellation": tolerance_note,
    }
    with open(os.path.join(out_dir, "report.json"), "w") as f:
        json.dump(summary, f, indent=2)
    return summary


def main():  # pragma: no cover - needs FreeCAD
    import FreeCAD
    import FreeCADGui

    sel = FreeCADGui.Selection.getSelection()
    if len(sel) != 1 or not hasattr(sel[0], "Shape"):
        FreeCAD.Console.PrintError("libsddpm: select exactly one solid\n")
        return
    shape = sel[0].Shape
    tol = 0.002 * shape.BoundBox.DiagonalLength
    pts, tris = shape.tessellate(tol)
    doc_dir = os.path.dirname(FreeCAD.ActiveDocument.FileName or "") or tempfile.gettempdir()
    out = os.path.join(doc_dir, f"{sel[0].Label}_sddpm")
    try:
        s = mesh_tessellation([(p.x, p.y, p.z) for p in pts], tris, out, tolerance_note=f"tessellate({tol:.4g})")
    except Exception as e:  # SddpmError carries the status name and the message
        FreeCAD.Console.PrintError(f"libsddpm: {e}\n")
        return
    h = s["hex"]
    FreeCAD.Console.PrintMessage(
        f"libsddpm: {h['elements']} hex elements, min scaled Jacobian {h['min_scaled_jacobian']:.3f}, "
        f"{h['inverted']} inverted; spline with {s['spline']['basis_functions']} functions; files in {out}\n"
    )
    if not s["polycube_verified"]:
        FreeCAD.Console.PrintWarning("libsddpm: no polycube passed verification; the best-fitting one was used\n")


if __name__ == "__main__":  # FreeCAD runs macros as __main__
    main()
