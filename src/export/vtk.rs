//! Legacy VTK (ASCII) unstructured grids of hexahedra: write with optional
//! per-cell scalars, and read back (also HexGen's published meshes).

use crate::error::{Error, Result};
use crate::hex::HexMesh;
use std::fmt::Write as _;
use std::path::Path;

/// VTK cell type of a linear hexahedron.
pub const VTK_HEXAHEDRON: u32 = 12;

/// Legacy VTK text of a hex mesh; `cell_data` are named per-element scalars.
pub fn to_vtk_legacy(m: &HexMesh, title: &str, cell_data: &[(&str, &[f64])]) -> String {
    let mut s = String::with_capacity(64 * (m.nodes.len() + m.elements.len()));
    let title: String = title.chars().filter(|c| *c != '\n').take(255).collect();
    s.push_str("# vtk DataFile Version 3.0\n");
    s.push_str(&title);
    s.push_str("\nASCII\nDATASET UNSTRUCTURED_GRID\n");
    let _ = writeln!(s, "POINTS {} double", m.nodes.len());
    for p in &m.nodes {
        let _ = writeln!(s, "{:.17e} {:.17e} {:.17e}", p[0], p[1], p[2]);
    }
    let _ = writeln!(s, "CELLS {} {}", m.elements.len(), 9 * m.elements.len());
    for e in &m.elements {
        let _ = writeln!(s, "8 {} {} {} {} {} {} {} {}", e[0], e[1], e[2], e[3], e[4], e[5], e[6], e[7]);
    }
    let _ = writeln!(s, "CELL_TYPES {}", m.elements.len());
    for _ in &m.elements {
        let _ = writeln!(s, "{VTK_HEXAHEDRON}");
    }
    if !cell_data.is_empty() {
        let _ = writeln!(s, "CELL_DATA {}", m.elements.len());
        for (name, vals) in cell_data {
            let _ = writeln!(s, "SCALARS {name} double 1\nLOOKUP_TABLE default");
            for v in vals.iter() {
                let _ = writeln!(s, "{v:.17e}");
            }
        }
    }
    s
}

pub fn write_vtk_legacy(path: &Path, m: &HexMesh, title: &str, cell_data: &[(&str, &[f64])]) -> Result<()> {
    std::fs::write(path, to_vtk_legacy(m, title, cell_data)).map_err(|e| Error::io(path.display(), e))
}

/// Read an ASCII legacy VTK unstructured grid whose cells are all hexahedra.
pub fn read_vtk_legacy(path: &Path) -> Result<HexMesh> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path.display(), e))?;
    parse_vtk_legacy(&text).map_err(|m| Error::parse(path.display(), m))
}

/// Parse the text of an ASCII legacy VTK unstructured grid of hexahedra.
pub fn parse_vtk_legacy(text: &str) -> std::result::Result<HexMesh, String> {
    let mut lines = text.lines();
    let head = lines.next().ok_or("empty file")?;
    if !head.starts_with("# vtk DataFile") {
        return Err("not a legacy VTK file (first line)".into());
    }
    lines.next(); // title
    let fmt = lines.next().ok_or("missing ASCII/BINARY line")?.trim().to_ascii_uppercase();
    if fmt != "ASCII" {
        return Err(format!("only ASCII legacy VTK is read, this file is {fmt}"));
    }
    let rest: Vec<&str> = lines.flat_map(|l| l.split_whitespace()).collect();
    let mut i = 0usize;
    let mut m = HexMesh::default();
    let mut cell_types: Vec<u32> = Vec::new();
    let num = |tok: Option<&&str>, what: &str| -> std::result::Result<usize, String> {
        tok.ok_or_else(|| format!("missing {what}"))?.parse::<usize>().map_err(|_| format!("bad {what}"))
    };
    while i < rest.len() {
        match rest[i].to_ascii_uppercase().as_str() {
            "DATASET" => {
                if rest.get(i + 1).map(|s| s.to_ascii_uppercase()) != Some("UNSTRUCTURED_GRID".into()) {
                    return Err("only UNSTRUCTURED_GRID datasets are read".into());
                }
                i += 2;
            }
            "POINTS" => {
                let n = num(rest.get(i + 1), "point count")?;
                if n > 100_000_000 {
                    return Err(format!("{n} points is more than this reader accepts"));
                }
                i += 3;
                if i + 3 * n > rest.len() {
                    return Err("the file ends inside POINTS".into());
                }
                m.nodes.reserve(n);
                for k in 0..n {
                    let mut p = [0.0; 3];
                    for (a, slot) in p.iter_mut().enumerate() {
                        *slot = rest[i + 3 * k + a].parse::<f64>().map_err(|_| format!("bad coordinate of point {k}"))?;
                        if !slot.is_finite() {
                            return Err(format!("point {k} has a non-finite coordinate"));
                        }
                    }
                    m.nodes.push(p);
                }
                i += 3 * n;
            }
            "CELLS" => {
                let n = num(rest.get(i + 1), "cell count")?;
                let total = num(rest.get(i + 2), "cell list size")?;
                i += 3;
                if i + total > rest.len() || total < n {
                    return Err("the file ends inside CELLS".into());
                }
                let end = i + total;
                for k in 0..n {
                    let cnt = num(rest.get(i), "cell size")?;
                    if cnt != 8 {
                        return Err(format!("cell {k} has {cnt} nodes; only hexahedra are read"));
                    }
                    if i + 9 > end {
                        return Err("the CELLS list is shorter than announced".into());
                    }
                    let mut e = [0u32; 8];
                    for (a, slot) in e.iter_mut().enumerate() {
                        *slot = rest[i + 1 + a].parse::<u32>().map_err(|_| format!("bad node id in cell {k}"))?;
                    }
                    m.elements.push(e);
                    i += 9;
                }
                i = end;
            }
            "CELL_TYPES" => {
                let n = num(rest.get(i + 1), "cell type count")?;
                i += 2;
                for k in 0..n {
                    let t = num(rest.get(i + k), "cell type")?;
                    cell_types.push(t as u32);
                }
                i += n;
            }
            "CELL_DATA" | "POINT_DATA" => break,
            _ => i += 1,
        }
    }
    if let Some((k, t)) = cell_types.iter().enumerate().find(|(_, &t)| t != VTK_HEXAHEDRON) {
        return Err(format!("cell {k} has VTK type {t}; only hexahedra (12) are read"));
    }
    if let Some((k, e)) = m.elements.iter().enumerate().find(|(_, e)| e.iter().any(|&v| v as usize >= m.nodes.len())) {
        return Err(format!("cell {k} refers to node {} of {}", e.iter().max().unwrap(), m.nodes.len()));
    }
    Ok(m)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn write_read_round_trip_and_reference_meshes() {
        let m = HexMesh::unit_cube();
        let t = to_vtk_legacy(&m, "unit", &[("scaled_jacobian", &[1.0])]);
        assert_eq!(parse_vtk_legacy(&t).unwrap(), m);
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/meshes/reference_hex");
        let rod = read_vtk_legacy(&dir.join("hexgen_rod_hex.vtk")).unwrap();
        assert_eq!((rod.nodes.len(), rod.elements.len()), (1815, 1280));
        assert!(parse_vtk_legacy("# vtk DataFile\nx\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 2 float\n0 0 0\n").is_err());
    }
}
