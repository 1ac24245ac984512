//! Hex-mesh files besides legacy VTK: VTU (VTK XML unstructured grid, ASCII, with
//! per-cell scalars), Medit .mesh (HexaLab, gmsh) and the LS-DYNA keyword format
//! (*NODE, *ELEMENT_SOLID with the part, section, material and analysis cards of a
//! deck that runs alone). Every writer has a reader so that tests can parse the
//! files back. All keep the VTK_HEXAHEDRON node order (bottom face 0-3
//! counter-clockwise seen from the top face, top face 4-7 above it), which is also
//! LS-DYNA's positive-volume order for 8-node solids; Medit and LS-DYNA ids are 1-based.
//! [`write_hex_files`] writes the hex stage's files of a run folder.

use crate::error::{Error, Result};
use super::lsdyna::{model_cards, DeckOptions};
use super::vtk::write_vtk_legacy;
use crate::hex::report::{HEX_K, HEX_MESH, HEX_VTK, HEX_VTU};
use crate::hex::{HexMesh, HexResult};
use std::fmt::Write as _;
use std::path::Path;

const VTK_HEXAHEDRON: u8 = 12;

fn write_text(path: &Path, text: String) -> Result<()> {
    std::fs::write(path, text).map_err(|e| Error::io(path.display(), e))
}

fn read_text(path: &Path) -> Result<String> {
    std::fs::read_to_string(path).map_err(|e| Error::io(path.display(), e))
}

fn check_mesh(m: &HexMesh) -> std::result::Result<(), String> {
    if let Some((k, e)) = m.elements.iter().enumerate().find(|(_, e)| e.iter().any(|&v| v as usize >= m.nodes.len())) {
        return Err(format!("element {k} refers to node {} of {}", e.iter().max().unwrap(), m.nodes.len()));
    }
    Ok(())
}

// ---------------------------------------------------------------- VTU

/// VTU text (ASCII data, Float64 points, Int64 connectivity) with named per-cell scalars.
pub fn to_vtu(m: &HexMesh, cell_data: &[(&str, &[f64])]) -> String {
    let mut s = String::with_capacity(80 * (m.nodes.len() + m.elements.len()));
    s.push_str("<?xml version=\"1.0\"?>\n");
    s.push_str("<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n");
    s.push_str("  <UnstructuredGrid>\n");
    let _ = writeln!(s, "    <Piece NumberOfPoints=\"{}\" NumberOfCells=\"{}\">", m.nodes.len(), m.elements.len());
    s.push_str("      <Points>\n        <DataArray type=\"Float64\" Name=\"Points\" NumberOfComponents=\"3\" format=\"ascii\">\n");
    for p in &m.nodes {
        let _ = writeln!(s, "          {:.17e} {:.17e} {:.17e}", p[0], p[1], p[2]);
    }
    s.push_str("        </DataArray>\n      </Points>\n      <Cells>\n");
    s.push_str("        <DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n");
    for e in &m.elements {
        let _ = writeln!(s, "          {} {} {} {} {} {} {} {}", e[0], e[1], e[2], e[3], e[4], e[5], e[6], e[7]);
    }
    s.push_str("        </DataArray>\n        <DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n");
    for k in 0..m.elements.len() {
        let _ = writeln!(s, "          {}", 8 * (k + 1));
    }
    s.push_str("        </DataArray>\n        <DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">\n");
    for _ in &m.elements {
        let _ = writeln!(s, "          {VTK_HEXAHEDRON}");
    }
    s.push_str("        </DataArray>\n      </Cells>\n");
    if !cell_data.is_empty() {
        let _ = writeln!(s, "      <CellData Scalars=\"{}\">", xml_escape(cell_data[0].0));
        for (name, vals) in cell_data {
            let _ = writeln!(s, "        <DataArray type=\"Float64\" Name=\"{}\" format=\"ascii\">", xml_escape(name));
            for v in vals.iter() {
                let _ = writeln!(s, "          {v:.17e}");
            }
            s.push_str("        </DataArray>\n");
        }
        s.push_str("      </CellData>\n");
    }
    s.push_str("    </Piece>\n  </UnstructuredGrid>\n</VTKFile>\n");
    s
}

fn xml_escape(t: &str) -> String {
    t.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;").replace('"', "&quot;")
}

pub fn write_vtu(path: &Path, m: &HexMesh, cell_data: &[(&str, &[f64])]) -> Result<()> {
    write_text(path, to_vtu(m, cell_data))
}

/// The mesh and the named cell scalars of an ASCII VTU file of hexahedra (as [`to_vtu`] writes).
pub type VtuContent = (HexMesh, Vec<(String, Vec<f64>)>);

pub fn read_vtu(path: &Path) -> Result<VtuContent> {
    parse_vtu(&read_text(path)?).map_err(|m| Error::parse(path.display(), m))
}

fn attr<'a>(tag: &'a str, name: &str) -> Option<&'a str> {
    let key = format!("{name}=\"");
    let i = tag.find(&key)? + key.len();
    let j = tag[i..].find('"')? + i;
    Some(&tag[i..j])
}

/// Parse ASCII VTU text of hexahedra: Points, connectivity / offsets / types, Float64 cell data.
pub fn parse_vtu(text: &str) -> std::result::Result<VtuContent, String> {
    if !text.contains("<VTKFile") || !text.contains("UnstructuredGrid") {
        return Err("not a VTK XML unstructured grid".into());
    }
    let piece = text.find("<Piece").ok_or("no <Piece>")?;
    let ptag_end = text[piece..].find('>').ok_or("bad <Piece>")? + piece;
    let ptag = &text[piece..ptag_end];
    let np: usize = attr(ptag, "NumberOfPoints").and_then(|v| v.parse().ok()).ok_or("bad NumberOfPoints")?;
    let nc: usize = attr(ptag, "NumberOfCells").and_then(|v| v.parse().ok()).ok_or("bad NumberOfCells")?;
    let mut arrays: Vec<(String, String, bool, &str)> = Vec::new(); // (name, type, in CellData, body)
    let mut pos = 0;
    while let Some(i) = text[pos..].find("<DataArray") {
        let start = pos + i;
        let tag_end = text[start..].find('>').ok_or("bad <DataArray>")? + start;
        let tag = &text[start..tag_end];
        if let Some(f) = attr(tag, "format") {
            if f != "ascii" {
                return Err(format!("only ascii DataArrays are read, found format=\"{f}\""));
            }
        }
        let end = text[tag_end..].find("</DataArray>").ok_or("unterminated <DataArray>")? + tag_end;
        let before = &text[..start];
        let in_cell = before.rfind("<CellData").is_some_and(|c| before.rfind("</CellData>").is_none_or(|e| e < c));
        arrays.push((
            attr(tag, "Name").unwrap_or("").to_string(),
            attr(tag, "type").unwrap_or("").to_string(),
            in_cell,
            &text[tag_end + 1..end],
        ));
        pos = end;
    }
    let find = |name: &str| arrays.iter().find(|a| a.0 == name && !a.2).map(|a| a.3);
    let nums = |body: &str, what: &str| -> std::result::Result<Vec<f64>, String> {
        body.split_whitespace().map(|t| t.parse::<f64>().map_err(|_| format!("bad number {t:?} in {what}"))).collect()
    };
    let pts = nums(find("Points").ok_or("no Points array")?, "Points")?;
    if pts.len() != 3 * np {
        return Err(format!("Points has {} values, expected {}", pts.len(), 3 * np));
    }
    let conn = nums(find("connectivity").ok_or("no connectivity array")?, "connectivity")?;
    let offs = nums(find("offsets").ok_or("no offsets array")?, "offsets")?;
    let types = nums(find("types").ok_or("no types array")?, "types")?;
    if offs.len() != nc || types.len() != nc {
        return Err("offsets / types do not match NumberOfCells".into());
    }
    let mut m = HexMesh { nodes: pts.chunks(3).map(|c| [c[0], c[1], c[2]]).collect(), elements: Vec::with_capacity(nc) };
    let mut prev = 0usize;
    for k in 0..nc {
        if types[k] as u8 != VTK_HEXAHEDRON {
            return Err(format!("cell {k} has VTK type {}; only hexahedra (12) are read", types[k]));
        }
        let o = offs[k] as usize;
        if o != prev + 8 || o > conn.len() {
            return Err(format!("cell {k} does not have 8 nodes"));
        }
        let mut e = [0u32; 8];
        for (a, slot) in e.iter_mut().enumerate() {
            *slot = conn[prev + a] as u32;
        }
        m.elements.push(e);
        prev = o;
    }
    check_mesh(&m)?;
    let mut data = Vec::new();
    for a in arrays.iter().filter(|a| a.2) {
        let v = nums(a.3, &a.0)?;
        if v.len() != nc {
            return Err(format!("cell array {} has {} values for {} cells", a.0, v.len(), nc));
        }
        data.push((a.0.clone(), v));
    }
    Ok((m, data))
}

// ---------------------------------------------------------------- Medit

/// Medit .mesh text (MeshVersionFormatted 2, 1-based ids, reference 0 on vertices, 1 on hexahedra).
pub fn to_medit(m: &HexMesh) -> String {
    let mut s = String::with_capacity(64 * (m.nodes.len() + m.elements.len()));
    s.push_str("MeshVersionFormatted 2\n\nDimension 3\n\n");
    let _ = writeln!(s, "Vertices\n{}", m.nodes.len());
    for p in &m.nodes {
        let _ = writeln!(s, "{:.17e} {:.17e} {:.17e} 0", p[0], p[1], p[2]);
    }
    let _ = writeln!(s, "\nHexahedra\n{}", m.elements.len());
    for e in &m.elements {
        let _ = writeln!(s, "{} {} {} {} {} {} {} {} 1", e[0] + 1, e[1] + 1, e[2] + 1, e[3] + 1, e[4] + 1, e[5] + 1, e[6] + 1, e[7] + 1);
    }
    s.push_str("\nEnd\n");
    s
}

pub fn write_medit(path: &Path, m: &HexMesh) -> Result<()> {
    write_text(path, to_medit(m))
}

pub fn read_medit(path: &Path) -> Result<HexMesh> {
    parse_medit(&read_text(path)?).map_err(|m| Error::parse(path.display(), m))
}

/// Parse Medit .mesh text: Vertices and Hexahedra (other sections are skipped).
pub fn parse_medit(text: &str) -> std::result::Result<HexMesh, String> {
    let toks: Vec<&str> = text.lines().map(|l| l.split('#').next().unwrap_or("")).flat_map(|l| l.split_whitespace()).collect();
    if toks.first().map(|t| t.eq_ignore_ascii_case("MeshVersionFormatted")) != Some(true) {
        return Err("not a Medit mesh (MeshVersionFormatted missing)".into());
    }
    let mut m = HexMesh::default();
    let mut i = 0;
    let count = |t: Option<&&str>| -> std::result::Result<usize, String> { t.ok_or("missing count")?.parse().map_err(|_| "bad count".to_string()) };
    while i < toks.len() {
        match toks[i].to_ascii_lowercase().as_str() {
            "dimension" => {
                if toks.get(i + 1) != Some(&"3") {
                    return Err("only 3D meshes are read".into());
                }
                i += 2;
            }
            "vertices" => {
                let n = count(toks.get(i + 1))?;
                i += 2;
                if i + 4 * n > toks.len() {
                    return Err("the file ends inside Vertices".into());
                }
                for k in 0..n {
                    let mut p = [0.0; 3];
                    for (a, slot) in p.iter_mut().enumerate() {
                        *slot = toks[i + 4 * k + a].parse().map_err(|_| format!("bad coordinate of vertex {}", k + 1))?;
                    }
                    m.nodes.push(p);
                }
                i += 4 * n;
            }
            "hexahedra" => {
                let n = count(toks.get(i + 1))?;
                i += 2;
                if i + 9 * n > toks.len() {
                    return Err("the file ends inside Hexahedra".into());
                }
                for k in 0..n {
                    let mut e = [0u32; 8];
                    for (a, slot) in e.iter_mut().enumerate() {
                        let id: u64 = toks[i + 9 * k + a].parse().map_err(|_| format!("bad vertex id in hexahedron {}", k + 1))?;
                        if id == 0 {
                            return Err(format!("hexahedron {} uses vertex id 0 (ids are 1-based)", k + 1));
                        }
                        *slot = (id - 1) as u32;
                    }
                    m.elements.push(e);
                }
                i += 9 * n;
            }
            "end" => break,
            _ => i += 1,
        }
    }
    check_mesh(&m)?;
    Ok(m)
}

// ---------------------------------------------------------------- LS-DYNA

/// A number in a 16-character E field (Fortran E16.9 style: d.ddddddddde+XX).
fn e16(x: f64) -> String {
    if x == 0.0 || !x.is_finite() {
        return format!("{:>16}", if x.is_finite() { "0.0".to_string() } else { format!("{x}") });
    }
    let exp = x.abs().log10().floor() as i32;
    let mut mant = x / 10f64.powi(exp);
    let mut exp = exp;
    // rounding to 8 decimals may give 10.0
    if format!("{:.8}", mant.abs()).starts_with("10") {
        mant /= 10.0;
        exp += 1;
    }
    let s = format!("{mant:.8}e{}{:02}", if exp < 0 { '-' } else { '+' }, exp.abs());
    format!("{s:>16}")
}

/// LS-DYNA keyword deck of the mesh that runs alone ([`to_lsdyna_deck`]) with the
/// default deck options (steel in mm-t-s, modal analysis), part `pid`.
pub fn to_lsdyna(m: &HexMesh, title: &str, pid: u32) -> String {
    let o = DeckOptions { part_id: pid, ..DeckOptions::default() };
    // the default material and analysis are valid: the cards cannot fail
    to_lsdyna_deck(m, title, &o).unwrap_or_default()
}

/// Element formulation of hex.k's *SECTION_SOLID: 2, the fully integrated
/// selectively reduced hexahedron (no hourglass modes; usable in implicit runs).
pub const HEX_ELFORM: i64 = 2;

/// LS-DYNA keyword deck of the mesh: *KEYWORD, *TITLE, *NODE (I8, 3 x E16),
/// *ELEMENT_SOLID (10 x I8, part `o.part_id`, 1-based ids), then *PART,
/// *SECTION_SOLID ([`HEX_ELFORM`]), *MAT_ELASTIC and the analysis's control cards
/// ([`crate::export::lsdyna::model_cards`]), *END.
pub fn to_lsdyna_deck(m: &HexMesh, title: &str, o: &DeckOptions) -> Result<String> {
    let pid = o.part_id;
    let mut s = String::with_capacity(64 * (m.nodes.len() + m.elements.len()));
    s.push_str("*KEYWORD\n*TITLE\n");
    let t: String = title.chars().filter(|c| *c != '\n').take(80).collect();
    s.push_str(&t);
    s.push_str("\n*NODE\n$#   nid               x               y               z\n");
    for (k, p) in m.nodes.iter().enumerate() {
        let _ = writeln!(s, "{:>8}{}{}{}", k + 1, e16(p[0]), e16(p[1]), e16(p[2]));
    }
    s.push_str("*ELEMENT_SOLID\n$#   eid     pid      n1      n2      n3      n4      n5      n6      n7      n8\n");
    for (k, e) in m.elements.iter().enumerate() {
        let _ = write!(s, "{:>8}{:>8}", k + 1, pid);
        for v in e {
            let _ = write!(s, "{:>8}", v + 1);
        }
        s.push('\n');
    }
    s.push_str(&model_cards(o, HEX_ELFORM, "hex mesh")?);
    s.push_str("*END\n");
    Ok(s)
}

/// Write the mesh as a deck with the default deck options ([`to_lsdyna`]).
pub fn write_lsdyna(path: &Path, m: &HexMesh, title: &str) -> Result<()> {
    write_text(path, to_lsdyna_deck(m, title, &DeckOptions::default())?)
}

pub fn read_lsdyna(path: &Path) -> Result<HexMesh> {
    parse_lsdyna(&read_text(path)?).map_err(|m| Error::parse(path.display(), m))
}

/// Parse *NODE and *ELEMENT_SOLID (fixed 8/16-column fields or comma-separated free
/// format). Node ids may be arbitrary; elements are renumbered onto the node order read.
pub fn parse_lsdyna(text: &str) -> std::result::Result<HexMesh, String> {
    #[derive(PartialEq)]
    enum Sec {
        None,
        Node,
        Solid,
    }
    let mut sec = Sec::None;
    let mut ids: std::collections::HashMap<u64, u32> = std::collections::HashMap::new();
    let mut m = HexMesh::default();
    let mut raw_elems: Vec<[u64; 8]> = Vec::new();
    let fields = |line: &str, widths: &[usize]| -> Vec<String> {
        if line.contains(',') {
            return line.split(',').map(|t| t.trim().to_string()).collect();
        }
        let mut out = Vec::new();
        let mut p = 0;
        for &w in widths {
            if p >= line.len() {
                break;
            }
            let e = (p + w).min(line.len());
            out.push(line.get(p..e).unwrap_or("").trim().to_string());
            p = e;
        }
        out
    };
    for (ln, line) in text.lines().enumerate() {
        if line.starts_with('$') || line.trim().is_empty() {
            continue;
        }
        if line.starts_with('*') {
            let k = line.trim().to_ascii_uppercase();
            sec = if k == "*NODE" {
                Sec::Node
            } else if k == "*ELEMENT_SOLID" {
                Sec::Solid
            } else {
                Sec::None
            };
            continue;
        }
        match sec {
            Sec::Node => {
                let f = fields(line, &[8, 16, 16, 16]);
                if f.len() < 4 {
                    return Err(format!("line {}: a *NODE card needs nid, x, y, z", ln + 1));
                }
                let id: u64 = f[0].parse().map_err(|_| format!("line {}: bad node id", ln + 1))?;
                let mut p = [0.0; 3];
                for a in 0..3 {
                    let t = if f[a + 1].is_empty() { "0" } else { f[a + 1].as_str() };
                    p[a] = t.parse().map_err(|_| format!("line {}: bad coordinate {t:?}", ln + 1))?;
                }
                ids.insert(id, m.nodes.len() as u32);
                m.nodes.push(p);
            }
            Sec::Solid => {
                let f = fields(line, &[8; 10]);
                if f.len() < 10 {
                    return Err(format!("line {}: an *ELEMENT_SOLID card needs eid, pid and 8 nodes", ln + 1));
                }
                let mut e = [0u64; 8];
                for a in 0..8 {
                    e[a] = f[a + 2].parse().map_err(|_| format!("line {}: bad node id", ln + 1))?;
                }
                raw_elems.push(e);
            }
            Sec::None => {}
        }
    }
    for (k, e) in raw_elems.iter().enumerate() {
        let mut el = [0u32; 8];
        for a in 0..8 {
            el[a] = *ids.get(&e[a]).ok_or_else(|| format!("element {} refers to node {} which is not defined", k + 1, e[a]))?;
        }
        m.elements.push(el);
    }
    Ok(m)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn two() -> HexMesh {
        let mut nodes = Vec::new();
        for z in 0..2 {
            for y in 0..2 {
                for x in 0..3 {
                    nodes.push([x as f64 * 0.5 - 1e-7, y as f64 * 1.25, z as f64 * -3.0e-5]);
                }
            }
        }
        let id = |x: u32, y: u32, z: u32| x + 3 * y + 6 * z;
        let el = |x: u32| [id(x, 0, 0), id(x + 1, 0, 0), id(x + 1, 1, 0), id(x, 1, 0), id(x, 0, 1), id(x + 1, 0, 1), id(x + 1, 1, 1), id(x, 1, 1)];
        HexMesh { nodes, elements: vec![el(0), el(1)] }
    }

    #[test]
    fn round_trips() {
        let m = two();
        let (back, data) = parse_vtu(&to_vtu(&m, &[("scaled_jacobian", &[1.0, -0.25])])).unwrap();
        assert_eq!(back, m);
        assert_eq!(data, vec![("scaled_jacobian".to_string(), vec![1.0, -0.25])]);
        assert_eq!(parse_medit(&to_medit(&m)).unwrap(), m);
        let k = parse_lsdyna(&to_lsdyna(&m, "two", 1)).unwrap();
        assert_eq!(k.elements, m.elements);
        for (a, b) in k.nodes.iter().zip(&m.nodes) {
            for c in 0..3 {
                assert!((a[c] - b[c]).abs() <= 1e-8 * (1.0 + b[c].abs()), "{a:?} {b:?}");
            }
        }
        assert_eq!(e16(1.0).len(), 16);
        assert_eq!(e16(-9.999999999).trim(), "-1.00000000e+01");
        assert_eq!(e16(1.5e-7).trim(), "1.50000000e-07");
        assert!(parse_medit("MeshVersionFormatted 2\nDimension 3\nVertices\n1\n0 0 0 0\nHexahedra\n1\n1 2 3 4 5 6 7 8 1\nEnd\n").is_err());
        assert!(parse_lsdyna("*NODE\n1,0,0,0\n*ELEMENT_SOLID\n1,1,1,2,3,4,5,6,7,9\n").is_err());
    }
}

/// Write hex.vtu, hex.vtk (both with the cell data "scaled_jacobian"), hex.mesh and
/// hex.k (the names of [`crate::hex::report`]) into `dir` (which must exist), all in user coordinates.
/// `deck`: the part, material and analysis of hex.k.
pub fn write_hex_files(dir: &Path, r: &HexResult, deck: &DeckOptions) -> Result<()> {
    let sj: &[f64] = &r.scaled_jacobian;
    write_vtu(&dir.join(HEX_VTU), &r.mesh, &[("scaled_jacobian", sj)])?;
    write_vtk_legacy(&dir.join(HEX_VTK), &r.mesh, "sddpm hex mesh", &[("scaled_jacobian", sj)])?;
    write_medit(&dir.join(HEX_MESH), &r.mesh)?;
    write_text(&dir.join(HEX_K), to_lsdyna_deck(&r.mesh, "sddpm hex mesh", deck)?)?;
    Ok(())
}
