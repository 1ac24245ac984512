//! File readers: OBJ (tobj), STL (binary through stl_io, ASCII in f64), OFF.
//!
//! Every reader returns a triangle soup: positions as written in the file and
//! triangles indexing them. Polygons with more than three corners are split
//! into a fan from their first corner. Welding and validation happen later,
//! in `mesh::TriMesh::load`.

use crate::error::{Error, Result};
use std::path::Path;

/// What a reader produced before welding.
#[derive(Debug, Default, Clone)]
pub(crate) struct Soup {
    pub vertices: Vec<[f64; 3]>,
    pub triangles: Vec<[u32; 3]>,
    /// Polygons with more than three corners that were split into fans.
    pub polygons_split: usize,
}

/// The file formats the library reads.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    Obj,
    Stl,
    Off,
}

impl Format {
    /// The format named by a path's extension (case-insensitive), if any.
    pub fn from_extension(path: &Path) -> Option<Format> {
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        match ext.as_str() {
            "obj" => Some(Format::Obj),
            "stl" => Some(Format::Stl),
            "off" => Some(Format::Off),
            _ => None,
        }
    }

    /// Guess the format from the first bytes of a file (used when the extension says nothing).
    pub fn sniff(bytes: &[u8]) -> Option<Format> {
        if is_binary_stl(bytes) {
            return Some(Format::Stl);
        }
        let head = &bytes[..bytes.len().min(4096)];
        let text = String::from_utf8_lossy(head);
        let first = text
            .lines()
            .map(str::trim)
            .find(|l| !l.is_empty() && !l.starts_with('#'))?;
        let word = first.split_whitespace().next().unwrap_or("");
        if word.ends_with("OFF") && word.len() <= 6 {
            return Some(Format::Off);
        }
        if word == "solid" {
            return Some(Format::Stl);
        }
        let obj_keywords = ["v", "vt", "vn", "f", "o", "g", "s", "mtllib", "usemtl"];
        if text
            .lines()
            .filter_map(|l| l.split_whitespace().next())
            .any(|w| obj_keywords.contains(&w))
        {
            return Some(Format::Obj);
        }
        None
    }
}

pub(crate) fn read_file(path: &Path) -> Result<(Vec<u8>, Format)> {
    let shown = path.display();
    let len = std::fs::metadata(path).map_err(|e| Error::io(&shown, e))?.len();
    if len > super::MAX_FILE_BYTES {
        return Err(Error::LimitExceeded(format!(
            "{shown}: the file has {len} bytes, more than the {} bytes a mesh file may have (about {} triangles)",
            super::MAX_FILE_BYTES,
            super::MAX_TRIANGLES
        )));
    }
    // A binary STL says how many triangles it holds in its first 84 bytes: one over
    // the limit is refused before the rest of the file is read.
    if len >= 84 {
        use std::io::Read;
        let mut head = [0u8; 84];
        let mut f = std::fs::File::open(path).map_err(|e| Error::io(&shown, e))?;
        f.read_exact(&mut head).map_err(|e| Error::io(&shown, e))?;
        if let Some(n) = binary_stl_count(&head, len) {
            super::check_triangle_limit(n as usize, &shown.to_string())?;
        }
    }
    let bytes = std::fs::read(path).map_err(|e| Error::io(&shown, e))?;
    let format = Format::from_extension(path)
        .or_else(|| Format::sniff(&bytes))
        .ok_or_else(|| {
            Error::parse(&shown, "unknown mesh format: expected .obj, .stl or .off (by extension or content)")
        })?;
    Ok((bytes, format))
}

pub(crate) fn parse(bytes: &[u8], format: Format, shown: &str) -> Result<Soup> {
    match format {
        Format::Obj => parse_obj(bytes, shown),
        Format::Stl => parse_stl(bytes, shown),
        Format::Off => parse_off(bytes, shown),
    }
}

// ---------------------------------------------------------------- OBJ

fn parse_obj(bytes: &[u8], shown: &str) -> Result<Soup> {
    let opts = tobj::LoadOptions {
        single_index: false,
        triangulate: true,
        ignore_points: true,
        ignore_lines: true,
    };
    let mut reader = std::io::Cursor::new(bytes);
    // Materials never matter here: do not open .mtl files.
    let (models, _materials) = tobj::load_obj_buf(&mut reader, &opts, |_| Err(tobj::LoadError::OpenFileFailed))
        .map_err(|e| Error::parse(shown, format!("not a readable OBJ file: {e}")))?;
    let mut soup = Soup::default();
    for model in &models {
        let m = &model.mesh;
        let base = soup.vertices.len() as u64;
        if m.positions.len() % 3 != 0 {
            return Err(Error::parse(shown, "OBJ positions are not triples"));
        }
        soup.vertices.extend(m.positions.chunks_exact(3).map(|p| [p[0], p[1], p[2]]));
        let nv = m.positions.len() as u64 / 3;
        for t in m.indices.chunks(3) {
            if t.len() != 3 {
                return Err(Error::parse(shown, "OBJ face list is not made of triangles"));
            }
            let mut tri = [0u32; 3];
            for k in 0..3 {
                let i = t[k] as u64;
                if i >= nv {
                    return Err(Error::parse(shown, format!("OBJ face refers to vertex {} of {}", i + 1, nv)));
                }
                tri[k] = index_u32(base + i, shown)?;
            }
            soup.triangles.push(tri);
        }
    }
    Ok(soup)
}

fn index_u32(i: u64, shown: &str) -> Result<u32> {
    u32::try_from(i).map_err(|_| Error::parse(shown, "more than 2^32 - 1 vertices"))
}

// ---------------------------------------------------------------- STL

/// A binary STL is recognised by its size, 84 + 50 n bytes with n the count at
/// offset 80, whatever its 80-byte header says (many binary files start with "solid").
pub(crate) fn is_binary_stl(bytes: &[u8]) -> bool {
    binary_stl_count(bytes, bytes.len() as u64).is_some()
}

/// The triangle count at offset 80 of a file starting with `head` (at least 84
/// bytes; None if shorter).
fn declared_stl_count(head: &[u8]) -> Option<u64> {
    head.get(80..84).map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]) as u64)
}

/// The count of a binary STL of `len` bytes starting with `head`, if the size
/// formula 84 + 50 n holds.
fn binary_stl_count(head: &[u8], len: u64) -> Option<u64> {
    declared_stl_count(head).filter(|&n| 84 + 50 * n == len)
}

fn starts_with_solid(bytes: &[u8]) -> bool {
    let trimmed = bytes.iter().position(|b| !b.is_ascii_whitespace()).map(|i| &bytes[i..]).unwrap_or(&[]);
    trimmed.starts_with(b"solid")
}

fn parse_stl(bytes: &[u8], shown: &str) -> Result<Soup> {
    if is_binary_stl(bytes) || (!starts_with_solid(bytes) && bytes.len() >= 84) {
        parse_stl_binary(bytes, shown)
    } else if starts_with_solid(bytes) {
        parse_stl_ascii(bytes, shown)
    } else {
        Err(Error::parse(shown, format!("not an STL file ({} bytes, no \"solid\" header)", bytes.len())))
    }
}

fn parse_stl_binary(bytes: &[u8], shown: &str) -> Result<Soup> {
    if let Some(n) = declared_stl_count(bytes) {
        super::check_triangle_limit(n as usize, shown)?;
    }
    // stl_io decides ASCII vs binary from a leading "solid "; our caller already
    // decided (by the size formula), so hand it a copy whose header cannot look ASCII.
    let mut data = bytes.to_vec();
    data[..5].copy_from_slice(b"BINAR");
    let mut cursor = std::io::Cursor::new(data);
    let reader = stl_io::create_stl_reader(&mut cursor)
        .map_err(|e| Error::parse(shown, format!("not a readable binary STL file: {e}")))?;
    let mut soup = Soup::default();
    for (k, t) in reader.enumerate() {
        let t = t.map_err(|e| Error::parse(shown, format!("binary STL triangle {k}: {e}")))?;
        let base = index_u32(soup.vertices.len() as u64, shown)?;
        for v in t.vertices.iter() {
            soup.vertices.push([v[0] as f64, v[1] as f64, v[2] as f64]);
        }
        soup.triangles.push([base, base + 1, base + 2]);
    }
    Ok(soup)
}

/// ASCII STL read in f64 (stl_io reads f32): `solid`, then `facet normal` /
/// `outer loop` / three or more `vertex x y z` / `endloop` / `endfacet`, `endsolid`.
/// Several solids in one file are read one after the other.
fn parse_stl_ascii(bytes: &[u8], shown: &str) -> Result<Soup> {
    let text = std::str::from_utf8(bytes).map_err(|_| Error::parse(shown, "ASCII STL is not valid UTF-8 text"))?;
    let mut soup = Soup::default();
    let mut loop_verts: Vec<[f64; 3]> = Vec::new();
    let mut in_loop = false;
    for (lineno, line) in text.lines().enumerate() {
        let mut words = line.split_whitespace();
        let Some(key) = words.next() else { continue };
        let err = |what: &str| Error::parse(shown, format!("line {}: {what}", lineno + 1));
        match key {
            "solid" | "endsolid" | "facet" | "endfacet" => {}
            "outer" => {
                in_loop = true;
                loop_verts.clear();
            }
            "vertex" => {
                if !in_loop {
                    return Err(err("vertex outside an outer loop"));
                }
                let mut p = [0.0; 3];
                for c in p.iter_mut() {
                    *c = words
                        .next()
                        .and_then(|w| w.parse::<f64>().ok())
                        .ok_or_else(|| err("vertex needs three numbers"))?;
                }
                loop_verts.push(p);
            }
            "endloop" => {
                if loop_verts.len() < 3 {
                    return Err(err("facet with fewer than three vertices"));
                }
                push_polygon_fan(&mut soup, &loop_verts, shown)?;
                in_loop = false;
            }
            _ => return Err(err(&format!("unexpected keyword {key:?}"))),
        }
    }
    if in_loop {
        return Err(Error::parse(shown, "ASCII STL ends inside a facet"));
    }
    Ok(soup)
}

fn push_polygon_fan(soup: &mut Soup, corners: &[[f64; 3]], shown: &str) -> Result<()> {
    let base = index_u32(soup.vertices.len() as u64, shown)?;
    soup.vertices.extend_from_slice(corners);
    for k in 1..corners.len() as u32 - 1 {
        soup.triangles.push([base, base + k, base + k + 1]);
    }
    if corners.len() > 3 {
        soup.polygons_split += 1;
    }
    Ok(())
}

// ---------------------------------------------------------------- OFF

/// OFF (also COFF, NOFF, CNOFF, STOFF...): header keyword, then `nv nf ne`, then
/// nv lines whose first three numbers are the position (normals, colours and
/// texture coordinates after them are ignored), then nf lines `n i0 .. i(n-1)`
/// (a colour after the indices is ignored). `#` starts a comment. Binary OFF is refused.
fn parse_off(bytes: &[u8], shown: &str) -> Result<Soup> {
    let text = std::str::from_utf8(bytes).map_err(|_| Error::parse(shown, "OFF file is not valid UTF-8 text"))?;
    let mut lines = text
        .lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l.split('#').next().unwrap_or("").trim()))
        .filter(|(_, l)| !l.is_empty());
    let (hline, header) = lines.next().ok_or_else(|| Error::parse(shown, "empty OFF file"))?;
    let mut words: Vec<&str> = header.split_whitespace().collect();
    let keyword = words.remove(0);
    if !keyword.ends_with("OFF") {
        return Err(Error::parse(shown, format!("line {hline}: OFF header expected, found {keyword:?}")));
    }
    if keyword.starts_with('n') || keyword.contains("4") {
        return Err(Error::parse(shown, format!("line {hline}: {keyword} (not 3-D) is not supported")));
    }
    if words.first() == Some(&"BINARY") {
        return Err(Error::parse(shown, "binary OFF is not supported"));
    }
    // Counts may follow the keyword on the same line.
    let (cline, counts): (usize, Vec<&str>) = if words.is_empty() {
        let (n, l) = lines.next().ok_or_else(|| Error::parse(shown, "OFF file ends before its counts"))?;
        (n, l.split_whitespace().collect())
    } else {
        (hline, words)
    };
    let count = |k: usize| -> Result<usize> {
        counts
            .get(k)
            .and_then(|w| w.parse::<usize>().ok())
            .ok_or_else(|| Error::parse(shown, format!("line {cline}: expected 'vertices faces edges' counts")))
    };
    let (nv, nf) = (count(0)?, count(1)?);
    // Guard the allocations against absurd counts from a corrupt header.
    let max_items = bytes.len() / 2 + 1;
    if nv > max_items || nf > max_items {
        return Err(Error::parse(shown, format!("line {cline}: counts {nv} vertices / {nf} faces exceed what the file can hold")));
    }
    // every face is at least one triangle: a header over the limit is refused before parsing
    super::check_triangle_limit(nf, shown)?;
    let mut soup = Soup { vertices: Vec::with_capacity(nv), ..Default::default() };
    for k in 0..nv {
        let (n, l) = lines
            .next()
            .ok_or_else(|| Error::parse(shown, format!("OFF file ends after {k} of {nv} vertices")))?;
        let mut p = [0.0; 3];
        let mut it = l.split_whitespace();
        for c in p.iter_mut() {
            *c = it
                .next()
                .and_then(|w| w.parse::<f64>().ok())
                .ok_or_else(|| Error::parse(shown, format!("line {n}: vertex {k} needs three numbers")))?;
        }
        soup.vertices.push(p);
    }
    for k in 0..nf {
        let (n, l) = lines
            .next()
            .ok_or_else(|| Error::parse(shown, format!("OFF file ends after {k} of {nf} faces")))?;
        let mut it = l.split_whitespace().map(|w| w.parse::<u64>());
        let bad = || Error::parse(shown, format!("line {n}: face {k} is not 'n i0 .. i(n-1)' with indices below {nv}"));
        let m = it.next().and_then(|r| r.ok()).ok_or_else(bad)? as usize;
        if m < 3 {
            return Err(Error::parse(shown, format!("line {n}: face {k} has {m} corners")));
        }
        let mut idx = Vec::with_capacity(m);
        for _ in 0..m {
            let i = it.next().and_then(|r| r.ok()).ok_or_else(bad)?;
            if i >= nv as u64 {
                return Err(bad());
            }
            idx.push(i as u32);
        }
        for j in 1..m - 1 {
            soup.triangles.push([idx[0], idx[j], idx[j + 1]]);
        }
        if m > 3 {
            soup.polygons_split += 1;
        }
    }
    Ok(soup)
}
