//! Legacy VTK of the spline for ParaView: each element sampled on an
//! (s+1)^3 grid of points as s^3 linear hexahedra, with the Jacobian
//! determinant and scaled Jacobian as point data and the element id and level
//! as cell data; and the control mesh / control points.

use crate::error::{Error, Result};
use crate::export::vtk::{to_vtk_legacy, VTK_HEXAHEDRON};
use crate::spline::{det3, map_from_bezier, scaled_det, BasisKind, Spline};
use std::fmt::Write as _;
use std::path::Path;

/// The spline sampled on each element's (s+1)^3 grid: points, Jacobian
/// determinants and scaled Jacobians, element by element, i fastest.
pub(crate) struct Samples {
    pub(crate) pts: Vec<[f64; 3]>,
    pub(crate) det: Vec<f64>,
    pub(crate) sj: Vec<f64>,
}

pub(crate) fn sample(sp: &Spline, s: usize) -> Result<Samples> {
    if s == 0 || s > 32 {
        return Err(Error::InvalidArgument(format!("samples per direction must be 1..=32, got {s}")));
    }
    let m = s + 1;
    let n = sp.num_elements() * m * m * m;
    let mut out = Samples { pts: Vec::with_capacity(n), det: Vec::with_capacity(n), sj: Vec::with_capacity(n) };
    for e in 0..sp.num_elements() {
        let pb = sp.bezier_points(e)?;
        for k in 0..m {
            for j in 0..m {
                for i in 0..m {
                    let p = [i as f64 / s as f64, j as f64 / s as f64, k as f64 / s as f64];
                    let (x, jac) = map_from_bezier(&pb, p);
                    out.pts.push(x);
                    out.det.push(det3(&jac));
                    out.sj.push(scaled_det(&jac));
                }
            }
        }
    }
    Ok(out)
}

/// The s^3 linear hexahedra of each of `ne` sampled elements, as point ids in
/// VTK's node order.
pub(crate) fn sub_cells(ne: usize, s: usize) -> impl Iterator<Item = [usize; 8]> {
    let m = s + 1;
    let id = move |e: usize, i: usize, j: usize, k: usize| e * m * m * m + i + m * (j + m * k);
    (0..ne * s * s * s).map(move |c| {
        let (e, r) = (c / (s * s * s), c % (s * s * s));
        let (i, j, k) = (r % s, (r / s) % s, r / (s * s));
        [
            id(e, i, j, k),
            id(e, i + 1, j, k),
            id(e, i + 1, j + 1, k),
            id(e, i, j + 1, k),
            id(e, i, j, k + 1),
            id(e, i + 1, j, k + 1),
            id(e, i + 1, j + 1, k + 1),
            id(e, i, j + 1, k + 1),
        ]
    })
}

/// VTK text of the spline sampled with `s` sub-cells per direction and element.
pub fn spline_vtk_string(sp: &Spline, s: usize) -> Result<String> {
    let Samples { pts, det, sj } = sample(sp, s)?;
    let ne = sp.num_elements();
    let mut out = String::with_capacity(pts.len() * 80);
    out.push_str("# vtk DataFile Version 3.0\nsddpm TH-spline3D sampled per element\nASCII\nDATASET UNSTRUCTURED_GRID\n");
    let _ = writeln!(out, "POINTS {} double", pts.len());
    for p in &pts {
        let _ = writeln!(out, "{:.17e} {:.17e} {:.17e}", p[0], p[1], p[2]);
    }
    let ncell = ne * s * s * s;
    let _ = writeln!(out, "CELLS {} {}", ncell, 9 * ncell);
    for c in sub_cells(ne, s) {
        let _ = writeln!(out, "8 {} {} {} {} {} {} {} {}", c[0], c[1], c[2], c[3], c[4], c[5], c[6], c[7]);
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

/// Write the sampled spline (ASCII, [`spline_vtk_string`]).
pub fn write_spline_vtk(path: &Path, sp: &Spline, samples: usize) -> Result<()> {
    let s = spline_vtk_string(sp, samples)?;
    std::fs::write(path, s).map_err(|e| Error::io(path.display(), e))
}

/// The sampled spline as binary legacy VTK (the same grid, cells and data as
/// [`spline_vtk_string`]; big-endian 32-bit floats and integers, as the legacy
/// format prescribes): about a fifth of the ASCII size, read by ParaView and VTK.
pub fn spline_vtk_binary(sp: &Spline, s: usize) -> Result<Vec<u8>> {
    let Samples { pts, det, sj } = sample(sp, s)?;
    let ne = sp.num_elements();
    let npts = pts.len();
    let ncell = ne * s * s * s;
    let mut out: Vec<u8> = Vec::with_capacity(20 * npts + 40 * ncell + 512);
    let f32s = |out: &mut Vec<u8>, v: f64| out.extend_from_slice(&(v as f32).to_be_bytes());
    let i32s = |out: &mut Vec<u8>, v: usize| out.extend_from_slice(&(v as i32).to_be_bytes());
    out.extend_from_slice(format!("# vtk DataFile Version 3.0\nsddpm TH-spline3D sampled per element\nBINARY\nDATASET UNSTRUCTURED_GRID\nPOINTS {npts} float\n").as_bytes());
    for x in &pts {
        for &c in x {
            f32s(&mut out, c);
        }
    }
    out.extend_from_slice(format!("\nCELLS {} {}\n", ncell, 9 * ncell).as_bytes());
    for c in sub_cells(ne, s) {
        i32s(&mut out, 8);
        for v in c {
            i32s(&mut out, v);
        }
    }
    out.extend_from_slice(format!("\nCELL_TYPES {ncell}\n").as_bytes());
    for _ in 0..ncell {
        i32s(&mut out, VTK_HEXAHEDRON as usize);
    }
    out.extend_from_slice(format!("\nCELL_DATA {ncell}\nSCALARS element int 1\nLOOKUP_TABLE default\n").as_bytes());
    for e in 0..ne {
        for _ in 0..s * s * s {
            i32s(&mut out, e);
        }
    }
    out.extend_from_slice(b"\nSCALARS level int 1\nLOOKUP_TABLE default\n");
    for el in sp.elements() {
        for _ in 0..s * s * s {
            i32s(&mut out, el.level as usize);
        }
    }
    out.extend_from_slice(format!("\nPOINT_DATA {npts}\nSCALARS jacobian float 1\nLOOKUP_TABLE default\n").as_bytes());
    for &v in &det {
        f32s(&mut out, v);
    }
    out.extend_from_slice(b"\nSCALARS scaled_jacobian float 1\nLOOKUP_TABLE default\n");
    for &v in &sj {
        f32s(&mut out, v);
    }
    out.push(b'\n');
    Ok(out)
}

/// Write the sampled spline as binary legacy VTK ([`spline_vtk_binary`]).
pub fn write_spline_vtk_binary(path: &Path, sp: &Spline, samples: usize) -> Result<()> {
    let b = spline_vtk_binary(sp, samples)?;
    std::fs::write(path, b).map_err(|e| Error::io(path.display(), e))
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
