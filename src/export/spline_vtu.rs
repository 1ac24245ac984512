//! The spline sampled per element as VTK XML (spline.vtu): each element on an
//! (s+1)^3 grid of points as s^3 linear hexahedra, the same grid, cells and data
//! as the legacy form of [`super::spline_vtk`], in binary: one raw appended data
//! block (little-endian, UInt64 block headers, 32-bit floats and integers), which
//! ParaView, VTK's vtkXMLUnstructuredGridReader and meshio read. About 45 bytes a
//! cell and 20 a point.
//!
//! Arrays: points (Float32 x 3), point data "jacobian" and "scaled_jacobian"
//! (Float32), cell data "element" and "level" (Int32), cells "connectivity",
//! "offsets" (Int32) and "types" (UInt8, all VTK_HEXAHEDRON).

use super::spline_vtk::{sample, sub_cells, Samples};
use crate::error::{Error, Result};
use crate::export::vtk::VTK_HEXAHEDRON;
use crate::spline::Spline;
use std::fmt::Write as _;
use std::path::Path;

/// One array of the appended block: its XML attributes and its bytes.
struct Array {
    kind: &'static str,
    name: &'static str,
    components: usize,
    bytes: Vec<u8>,
}

fn f32s(v: impl Iterator<Item = f64>) -> Vec<u8> {
    v.flat_map(|x| (x as f32).to_le_bytes()).collect()
}

fn i32s(v: impl Iterator<Item = usize>) -> Vec<u8> {
    v.flat_map(|x| (x as i32).to_le_bytes()).collect()
}

/// The spline sampled with `s` sub-cells per element edge (1..=32) as VTU bytes.
pub fn spline_vtu_bytes(sp: &Spline, s: usize) -> Result<Vec<u8>> {
    let Samples { pts, det, sj } = sample(sp, s)?;
    let ne = sp.num_elements();
    let per = s * s * s;
    let ncell = ne * per;
    if pts.len() > i32::MAX as usize || 8 * ncell > i32::MAX as usize {
        return Err(Error::LimitExceeded(format!("{ncell} sampled cells do not fit 32-bit VTU indices; use fewer samples per element edge")));
    }
    let levels: Vec<usize> = sp.elements().iter().map(|e| e.level as usize).collect();
    let points = Array { kind: "Float32", name: "Points", components: 3, bytes: f32s(pts.iter().flat_map(|p| p.iter().copied())) };
    let point_data = [
        Array { kind: "Float32", name: "jacobian", components: 1, bytes: f32s(det.iter().copied()) },
        Array { kind: "Float32", name: "scaled_jacobian", components: 1, bytes: f32s(sj.iter().copied()) },
    ];
    let cell_data = [
        Array { kind: "Int32", name: "element", components: 1, bytes: i32s((0..ncell).map(|c| c / per)) },
        Array { kind: "Int32", name: "level", components: 1, bytes: i32s((0..ncell).map(|c| levels[c / per])) },
    ];
    let cells = [
        Array { kind: "Int32", name: "connectivity", components: 1, bytes: i32s(sub_cells(ne, s).flat_map(|c| c.into_iter())) },
        Array { kind: "Int32", name: "offsets", components: 1, bytes: i32s((1..=ncell).map(|c| 8 * c)) },
        Array { kind: "UInt8", name: "types", components: 1, bytes: vec![VTK_HEXAHEDRON as u8; ncell] },
    ];
    let mut offset = 0usize;
    let mut xml = String::new();
    let mut tag = |xml: &mut String, a: &Array| {
        let _ = writeln!(
            xml,
            "        <DataArray type=\"{}\" Name=\"{}\" NumberOfComponents=\"{}\" format=\"appended\" offset=\"{offset}\"/>",
            a.kind, a.name, a.components
        );
        offset += 8 + a.bytes.len();
    };
    xml.push_str("<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n  <UnstructuredGrid>\n");
    let _ = writeln!(xml, "    <Piece NumberOfPoints=\"{}\" NumberOfCells=\"{ncell}\">", pts.len());
    xml.push_str("      <PointData Scalars=\"scaled_jacobian\">\n");
    point_data.iter().for_each(|a| tag(&mut xml, a));
    xml.push_str("      </PointData>\n      <CellData Scalars=\"element\">\n");
    cell_data.iter().for_each(|a| tag(&mut xml, a));
    xml.push_str("      </CellData>\n      <Points>\n");
    tag(&mut xml, &points);
    xml.push_str("      </Points>\n      <Cells>\n");
    cells.iter().for_each(|a| tag(&mut xml, a));
    xml.push_str("      </Cells>\n    </Piece>\n  </UnstructuredGrid>\n  <AppendedData encoding=\"raw\">\n   _");
    let mut out = xml.into_bytes();
    out.reserve(offset + 64);
    for a in point_data.iter().chain(&cell_data).chain([&points]).chain(&cells) {
        out.extend_from_slice(&(a.bytes.len() as u64).to_le_bytes());
        out.extend_from_slice(&a.bytes);
    }
    out.extend_from_slice(b"\n  </AppendedData>\n</VTKFile>\n");
    Ok(out)
}

/// Write the sampled spline as VTU ([`spline_vtu_bytes`]).
pub fn write_spline_vtu(path: &Path, sp: &Spline, samples: usize) -> Result<()> {
    let b = spline_vtu_bytes(sp, samples)?;
    std::fs::write(path, b).map_err(|e| Error::io(path.display(), e))
}

/// One array read back from a VTU with a raw appended block: its name, type and
/// values as f64.
#[derive(Debug, Clone, PartialEq)]
pub struct VtuArray {
    pub name: String,
    pub kind: String,
    pub values: Vec<f64>,
}

/// Read the arrays of a VTU written by [`spline_vtu_bytes`] (raw appended data,
/// UInt64 headers, Float32 / Int32 / UInt8 arrays), in the order of the XML.
pub fn parse_spline_vtu(b: &[u8]) -> std::result::Result<Vec<VtuArray>, String> {
    let marker: &[u8] = b"<AppendedData encoding=\"raw\">";
    let start = b.windows(marker.len()).position(|w| w == marker).ok_or("no raw appended data")?;
    let data = start + b[start..].iter().position(|&c| c == b'_').ok_or("no '_' before the appended data")? + 1;
    let head = std::str::from_utf8(&b[..start]).map_err(|_| "the XML part is not UTF-8")?;
    let attr = |t: &str, k: &str| t.split(&format!("{k}=\"")).nth(1).and_then(|r| r.split('"').next()).map(str::to_string);
    let mut out = Vec::new();
    for t in head.split("<DataArray").skip(1) {
        let t = t.split('>').next().unwrap_or("");
        let (Some(name), Some(kind), Some(off)) = (attr(t, "Name"), attr(t, "type"), attr(t, "offset")) else { return Err(format!("a DataArray without Name, type or offset: {t}")) };
        let off: usize = off.parse().map_err(|_| format!("bad offset {off}"))?;
        let at = data + off;
        let len = b.get(at..at + 8).map(|h| u64::from_le_bytes(h.try_into().unwrap()) as usize).ok_or("an array past the end")?;
        let bytes = b.get(at + 8..at + 8 + len).ok_or("an array past the end")?;
        let values: Vec<f64> = match kind.as_str() {
            "Float32" => bytes.chunks_exact(4).map(|c| f32::from_le_bytes(c.try_into().unwrap()) as f64).collect(),
            "Int32" => bytes.chunks_exact(4).map(|c| i32::from_le_bytes(c.try_into().unwrap()) as f64).collect(),
            "UInt8" => bytes.iter().map(|&v| v as f64).collect(),
            other => return Err(format!("unsupported type {other}")),
        };
        out.push(VtuArray { name, kind, values });
    }
    Ok(out)
}
