//! Legacy VTK of the spline for ParaView: each element sampled on an
//! (s+1)^3 grid of points as s^3 linear hexahedra, with the Jacobian
//! determinant and scaled Jacobian as point data and the element id and level
//! as cell data; and the control mesh / control points.

use crate::error::{Error, Result};
use crate::export::vtk::{to_vtk_legacy, VTK_HEXAHEDRON};
use crate::spline::{det3, map_from_bezier, scaled_det, BasisKind, Spline};
use std::fmt::Write as _;
use std::path::Path;

/// VTK text of the spline sampled with `s` sub-cells per direction and element.
pub fn spline_vtk_string(sp: &Spline, s: usize) -> Result<String> {
    if s == 0 || s > 32 {
        return Err(Error::InvalidArgument(format!("samples per direction must be 1..=32, got {s}")));
    }
    let m = s + 1;
    let ne = sp.num_elements();
    let mut pts = Vec::with_capacity(ne * m * m * m);
    let mut det = Vec::with_capacity(pts.capacity());
    let mut sj = Vec::with_capacity(pts.capacity());
    for e in 0..ne {
        let pb = sp.bezier_points(e)?;
        for k in 0..m {
            for j in 0..m {
                for i in 0..m {
                    let p = [i as f64 / s as f64, j as f64 / s as f64, k as f64 / s as f64];
                    let (x, jac) = map_from_bezier(&pb, p);
                    pts.push(x);
                    det.push(det3(&jac));
                    sj.push(scaled_det(&jac));
                }
            }
        }
    }
    let mut out = String::with_capacity(pts.len() * 80);
    out.push_str("# vtk DataFile Version 3.0\nsddpm TH-spline3D sampled per element\nASCII\nDATASET UNSTRUCTURED_GRID\n");
    let _ = writeln!(out, "POINTS {} double", pts.len());
    for p in &pts {
        let _ = writeln!(out, "{:.17e} {:.17e} {:.17e}", p[0], p[1], p[2]);
    }
    let ncell = ne * s * s * s;
    let _ = writeln!(out, "CELLS {} {}", ncell, 9 * ncell);
    let id = |e: usize, i: usize, j: usize, k: usize| e * m * m * m + i + m * (j + m * k);
    for e in 0..ne {
        for k in 0..s {
            for j in 0..s {
                for i in 0..s {
                    let _ = writeln!(
                        out,
                        "8 {} {} {} {} {} {} {} {}",
                        id(e, i, j, k),
                        id(e, i + 1, j, k),
                        id(e, i + 1, j + 1, k),
                        id(e, i, j + 1, k),
                        id(e, i, j, k + 1),
                        id(e, i + 1, j, k + 1),
                        id(e, i + 1, j + 1, k + 1),
                        id(e, i, j + 1, k + 1)
                    );
                }
            }
        }
    }
    let _ = writeln!(out, "CELL_TYPES {ncell}");
    for _ in 0..ncell {
        let _ = writeln!(out, "{VTK_HEXAHEDRON}");
    }
    let _ = writeln!(out, "CELL_DATA {ncell}\nSCALARS element int 1\nLOOKUP_TABLE default");
    for e in 0..ne {
        for _ in 0..s * s * s {
            let _ = writeln!(out, "{e}");
        }
    }
    let _ = writeln!(out, "SCALARS level int 1\nLOOKUP_TABLE default");
    for el in sp.elements() {
        for _ in 0..s * s * s {
            let _ = writeln!(out, "{}", el.level);
        }
    }
    let _ = writeln!(out, "POINT_DATA {}\nSCALARS jacobian double 1\nLOOKUP_TABLE default", pts.len());
    for v in &det {
        let _ = writeln!(out, "{v:.9e}");
    }
    let _ = writeln!(out, "SCALARS scaled_jacobian double 1\nLOOKUP_TABLE default");
    for v in &sj {
        let _ = writeln!(out, "{v:.9e}");
    }
    Ok(out)
}

/// Write the sampled spline.
pub fn write_spline_vtk(path: &Path, sp: &Spline, samples: usize) -> Result<()> {
    let s = spline_vtk_string(sp, samples)?;
    std::fs::write(path, s).map_err(|e| Error::io(path.display(), e))
}

/// Write the control mesh (hex topology, fitted control points of the vertex functions).
pub fn write_control_mesh_vtk(path: &Path, sp: &Spline) -> Result<()> {
    let m = sp.control_mesh();
    let s = to_vtk_legacy(&m, "sddpm spline control mesh", &[]);
    std::fs::write(path, s).map_err(|e| Error::io(path.display(), e))
}

/// Write every control point as a VTK vertex with its kind (0 vertex function,
/// 1 + level for Bernstein functions).
pub fn write_control_points_vtk(path: &Path, sp: &Spline) -> Result<()> {
    let p = sp.control_points();
    let mut out = String::new();
    out.push_str("# vtk DataFile Version 3.0\nsddpm spline control points\nASCII\nDATASET UNSTRUCTURED_GRID\n");
    let _ = writeln!(out, "POINTS {} double", p.len());
    for q in p {
        let _ = writeln!(out, "{:.17e} {:.17e} {:.17e}", q[0], q[1], q[2]);
    }
    let _ = writeln!(out, "CELLS {} {}", p.len(), 2 * p.len());
    for i in 0..p.len() {
        let _ = writeln!(out, "1 {i}");
    }
    let _ = writeln!(out, "CELL_TYPES {}", p.len());
    for _ in 0..p.len() {
        let _ = writeln!(out, "1");
    }
    let _ = writeln!(out, "CELL_DATA {}\nSCALARS kind int 1\nLOOKUP_TABLE default", p.len());
    for i in 0..p.len() {
        let k = match sp.basis_kind(i) {
            BasisKind::Vertex(_) => 0,
            BasisKind::Bernstein { level, .. } => 1 + level as i32,
        };
        let _ = writeln!(out, "{k}");
    }
    std::fs::write(path, out).map_err(|e| Error::io(path.display(), e))
}
