//! Triangle meshes: reading (OBJ, STL, OFF, arrays), welding, checks and measures.
//! The [`TriMesh`] type itself lives in [`crate::geometry`] (re-exported here).
//!
//! Loading reads a triangle soup, refuses non-finite coordinates and empty
//! meshes, welds coincident vertices within a tolerance relative to the
//! bounding-box diagonal, drops vertices no triangle uses and, only when asked,
//! re-orients a closed manifold consistently outward. Whether the surface can go
//! on to meshing is decided by [`TriMesh::check`] / [`TriMesh::validate`]; see
//! docs/mesh-checks.md for every default and check.

mod check;
mod intersect;
mod io;
mod weld;

pub use check::{Issue, IssueKind, MeshReport, Severity};
pub use intersect::self_intersections;
pub use io::Format;

pub use crate::geometry::TriMesh;

use crate::error::{Error, Result};
use std::path::Path;

/// Default weld tolerance, relative to the bounding-box diagonal.
pub const DEFAULT_WELD_TOLERANCE: f64 = 1e-9;

/// Most triangles an input may have (documented limit, docs/errors.md): above it a
/// mesh is refused with LIMIT_EXCEEDED from its header (binary STL, OFF) or right
/// after parsing (OBJ, ASCII STL), before any check. The
/// pipeline's own work is bounded by its samples and cells, so this limit is about
/// memory: a closed surface of 5 million triangles peaks at 2.8 GB while it is read,
/// welded and checked, the whole main job included (measured, docs/errors.md).
pub const MAX_TRIANGLES: usize = 5_000_000;
/// Largest coordinate magnitude accepted (documented limit): squared distances and
/// triple products of coordinates must stay finite in f64.
pub const MAX_COORDINATE: f64 = 1e100;
/// Smallest bounding-box diagonal accepted: signed volumes (cubes of lengths) must not
/// underflow.
pub const MIN_EXTENT: f64 = 1e-90;
/// Largest mesh file read (1 GiB), checked before reading a byte.
pub const MAX_FILE_BYTES: u64 = 1 << 30;

fn check_triangle_limit(n: usize, what: &str) -> Result<()> {
    if n > MAX_TRIANGLES {
        return Err(Error::LimitExceeded(format!("{what}: {n} triangles, more than the {MAX_TRIANGLES} an input may have; decimate it first")));
    }
    Ok(())
}

/// How a mesh is read.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct LoadOptions {
    /// Vertices closer than `weld_tolerance` x bounding-box diagonal are merged.
    /// 0 merges only exactly equal positions (+0 and -0 are equal); a negative
    /// value disables welding. Default [`DEFAULT_WELD_TOLERANCE`] (1e-9).
    pub weld_tolerance: f64,
    /// Drop vertices that no triangle uses (default true).
    pub remove_unreferenced: bool,
    /// Explicit repair, default false: re-orient every triangle of a closed
    /// edge-manifold surface consistently, each component outward (positive volume).
    pub repair_orientation: bool,
}

impl Default for LoadOptions {
    fn default() -> Self {
        LoadOptions { weld_tolerance: DEFAULT_WELD_TOLERANCE, remove_unreferenced: true, repair_orientation: false }
    }
}

/// What loading did to the data as read.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize)]
pub struct LoadStats {
    /// Format the file was read as (None for arrays).
    pub format: Option<&'static str>,
    pub vertices_read: usize,
    pub triangles_read: usize,
    /// Polygons with more than three corners split into triangle fans.
    pub polygons_split: usize,
    /// Absolute weld distance used (tolerance x diagonal).
    pub weld_distance: f64,
    /// Vertices merged into another one by welding.
    pub vertices_merged: usize,
    /// Vertices dropped because no triangle uses them.
    pub unreferenced_removed: usize,
    /// Triangles flipped by `repair_orientation`.
    pub triangles_flipped: usize,
}

impl TriMesh {
    /// Signed volume enclosed by the triangles (divergence theorem; positive for a
    /// closed, outward-oriented surface).
    pub fn signed_volume(&self) -> f64 {
        (0..self.triangles.len()).map(|t| check::signed_volume_of(self, t)).sum()
    }

    /// Read an OBJ, STL (ASCII or binary) or OFF file, chosen by extension or,
    /// failing that, by content; then weld and clean as `opts` says.
    /// Unreadable files give `Error::Io` / `Error::Parse`; empty meshes and
    /// non-finite coordinates give `Error::InvalidMesh`. Other defects are left
    /// for [`TriMesh::check`].
    pub fn load(path: impl AsRef<Path>, opts: &LoadOptions) -> Result<TriMesh> {
        // (limits: MAX_FILE_BYTES before reading, MAX_TRIANGLES from the header or after parsing)
        Self::load_with_stats(path, opts).map(|(m, _)| m)
    }

    /// [`TriMesh::load`], also returning what loading did.
    pub fn load_with_stats(path: impl AsRef<Path>, opts: &LoadOptions) -> Result<(TriMesh, LoadStats)> {
        let path = path.as_ref();
        let shown = path.display().to_string();
        let (bytes, format) = io::read_file(path)?;
        Self::from_bytes_with_stats(&bytes, Some(format), &shown, opts)
    }

    /// A mesh from the bytes of an OBJ / STL / OFF file held in memory; `format` None
    /// sniffs it from the content; `name` is what messages call it.
    pub fn from_bytes(bytes: &[u8], format: Option<Format>, name: &str, opts: &LoadOptions) -> Result<TriMesh> {
        Self::from_bytes_with_stats(bytes, format, name, opts).map(|(m, _)| m)
    }

    /// [`TriMesh::from_bytes`], also returning what loading did.
    pub fn from_bytes_with_stats(bytes: &[u8], format: Option<Format>, name: &str, opts: &LoadOptions) -> Result<(TriMesh, LoadStats)> {
        if bytes.len() as u64 > MAX_FILE_BYTES {
            return Err(Error::LimitExceeded(format!("{name}: {} bytes, more than the {MAX_FILE_BYTES} a mesh file may have", bytes.len())));
        }
        let shown = name.to_string();
        let format = format
            .or_else(|| Format::sniff(bytes))
            .ok_or_else(|| Error::parse(&shown, "unknown mesh format: expected OBJ, STL or OFF content"))?;
        let soup = io::parse(bytes, format, &shown)?;
        check_triangle_limit(soup.triangles.len(), &shown)?;
        let mut stats = LoadStats {
            format: Some(match format {
                Format::Obj => "obj",
                Format::Stl => "stl",
                Format::Off => "off",
            }),
            polygons_split: soup.polygons_split,
            ..Default::default()
        };
        let mesh = TriMesh { vertices: soup.vertices, triangles: soup.triangles };
        let mesh = mesh.prepare(opts, &mut stats).map_err(|e| match e {
            Error::InvalidMesh(m) => Error::InvalidMesh(format!("{shown}: {m}")),
            e => e,
        })?;
        Ok((mesh, stats))
    }

    /// Build a mesh from flat arrays: `xyz` holds 3 coordinates per vertex,
    /// `tri` 3 vertex indices per triangle (u32, or i64 through [`TriIndex`]).
    /// Lengths not divisible by 3 and indices out of range are `InvalidArgument`.
    pub fn from_arrays<I: TriIndex>(xyz: &[f64], tri: &[I], opts: &LoadOptions) -> Result<TriMesh> {
        Self::from_arrays_with_stats(xyz, tri, opts).map(|(m, _)| m)
    }

    /// [`TriMesh::from_arrays`], also returning what loading did.
    pub fn from_arrays_with_stats<I: TriIndex>(xyz: &[f64], tri: &[I], opts: &LoadOptions) -> Result<(TriMesh, LoadStats)> {
        if xyz.len() % 3 != 0 {
            return Err(Error::InvalidArgument(format!("coordinate array length {} is not a multiple of 3", xyz.len())));
        }
        if tri.len() % 3 != 0 {
            return Err(Error::InvalidArgument(format!("triangle array length {} is not a multiple of 3", tri.len())));
        }
        check_triangle_limit(tri.len() / 3, "the triangle array")?;
        let nv = xyz.len() / 3;
        if nv > u32::MAX as usize {
            return Err(Error::LimitExceeded(format!("{nv} vertices: at most 2^32 - 1 are supported")));
        }
        let vertices: Vec<[f64; 3]> = xyz.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
        let mut triangles = Vec::with_capacity(tri.len() / 3);
        for (t, c) in tri.chunks_exact(3).enumerate() {
            let mut out = [0u32; 3];
            for k in 0..3 {
                out[k] = c[k].to_index(nv).ok_or_else(|| {
                    Error::InvalidArgument(format!(
                        "triangle {t} refers to vertex {} but there are {nv} vertices",
                        c[k].shown()
                    ))
                })?;
            }
            triangles.push(out);
        }
        let mut stats = LoadStats::default();
        let mesh = TriMesh { vertices, triangles }.prepare(opts, &mut stats)?;
        Ok((mesh, stats))
    }

    /// Shared tail of every loader: refuse what cannot be measured, weld, clean, repair.
    fn prepare(mut self, opts: &LoadOptions, stats: &mut LoadStats) -> Result<TriMesh> {
        if !opts.weld_tolerance.is_finite() && opts.weld_tolerance != f64::NEG_INFINITY {
            return Err(Error::InvalidArgument(format!("weld tolerance {} is not a number below infinity", opts.weld_tolerance)));
        }
        stats.vertices_read = self.vertices.len();
        stats.triangles_read = self.triangles.len();
        if self.triangles.is_empty() {
            return Err(Error::InvalidMesh(format!("empty mesh: no triangles ({} vertices)", self.vertices.len())));
        }
        let bad: Vec<usize> = (0..self.vertices.len())
            .filter(|&i| !self.vertices[i].iter().all(|c| c.is_finite()))
            .collect();
        if let Some(&first) = bad.first() {
            let p = self.vertices[first];
            return Err(Error::InvalidMesh(format!(
                "non-finite coordinates: {} vertices; first vertex {first} = ({}, {}, {})",
                bad.len(),
                p[0],
                p[1],
                p[2]
            )));
        }
        // used vertices only: an unreferenced stray point must not decide the scale
        let mut used = vec![false; self.vertices.len()];
        for t in &self.triangles {
            for &v in t {
                if let Some(u) = used.get_mut(v as usize) {
                    *u = true;
                }
            }
        }
        if let Some(i) = (0..self.vertices.len()).find(|&i| used[i] && self.vertices[i].iter().any(|c| c.abs() > MAX_COORDINATE)) {
            let p = self.vertices[i];
            return Err(Error::LimitExceeded(format!(
                "vertex {i} at ({:e}, {:e}, {:e}) has a coordinate of magnitude above {MAX_COORDINATE:e}, the largest the library handles (squared distances must stay finite); rescale the model",
                p[0], p[1], p[2]
            )));
        }
        let used_pts: Vec<[f64; 3]> = (0..self.vertices.len()).filter(|&i| used[i]).map(|i| self.vertices[i]).collect();
        // the longest bounding-box edge (no squares: they would underflow here)
        let extent = crate::geometry::Aabb::of_points(&used_pts).size().iter().copied().fold(0.0, f64::max);
        if extent > 0.0 && extent < MIN_EXTENT {
            return Err(Error::LimitExceeded(format!(
                "the longest bounding-box edge is {extent:e}, below {MIN_EXTENT:e}, the smallest the library handles (volumes would underflow); rescale the model"
            )));
        }
        if opts.weld_tolerance >= 0.0 {
            let diag = crate::geometry::Aabb::of_points(&self.vertices).diagonal();
            stats.weld_distance = opts.weld_tolerance * diag;
            stats.vertices_merged = weld::weld(&mut self, stats.weld_distance);
        }
        if opts.remove_unreferenced {
            stats.unreferenced_removed = self.remove_unreferenced();
        }
        if opts.repair_orientation {
            stats.triangles_flipped = self.repair_orientation();
        }
        Ok(self)
    }

    /// Explicit repair: make the orientation of a closed, edge-manifold surface
    /// consistent (a breadth-first walk over shared edges from the lowest
    /// triangle of each component) and then each component outward (positive
    /// signed volume). Returns the number of triangles flipped. Components that
    /// are open, non-manifold or non-orientable are left as they are (the check
    /// reports them).
    pub fn repair_orientation(&mut self) -> usize {
        let topo = check::EdgeTable::new(self);
        let nt = self.triangles.len();
        // adjacency through manifold edges: (neighbour, same_direction)
        let mut adj: Vec<Vec<(u32, bool)>> = vec![Vec::new(); nt];
        let mut bad_tri = vec![false; nt];
        for e in &topo.edges {
            let inc = topo.incidences(e);
            if inc.len() != 2 {
                for &(t, _) in inc {
                    bad_tri[t as usize] = true;
                }
                continue;
            }
            let (a, da) = inc[0];
            let (b, db) = inc[1];
            let same = da == db;
            adj[a as usize].push((b, same));
            adj[b as usize].push((a, same));
        }
        let mut flip = vec![false; nt];
        let mut seen = vec![false; nt];
        let mut flipped = 0;
        for seed in 0..nt {
            if seen[seed] || self.is_collapsed(seed) {
                continue;
            }
            let mut comp = vec![seed];
            seen[seed] = true;
            let mut head = 0;
            let mut ok = true;
            while head < comp.len() {
                let t = comp[head];
                head += 1;
                ok &= !bad_tri[t];
                for &(n, same) in &adj[t] {
                    let want = flip[t] ^ same;
                    if !seen[n as usize] {
                        seen[n as usize] = true;
                        flip[n as usize] = want;
                        comp.push(n as usize);
                    } else if flip[n as usize] != want {
                        ok = false; // non-orientable
                    }
                }
            }
            if !ok {
                continue;
            }
            let mut vol = 0.0;
            for &t in &comp {
                let v = check::signed_volume_of(self, t);
                vol += if flip[t] { -v } else { v };
            }
            let outward_flip = vol < 0.0;
            for &t in &comp {
                if flip[t] ^ outward_flip {
                    self.triangles[t].swap(1, 2);
                    flipped += 1;
                }
            }
        }
        flipped
    }

    fn is_collapsed(&self, t: usize) -> bool {
        let [a, b, c] = self.triangles[t];
        a == b || b == c || a == c
    }

    /// Measure and check the surface; see [`MeshReport`].
    pub fn check(&self) -> MeshReport {
        check::check(self)
    }

    /// Check and refuse a surface that cannot go on to meshing with
    /// `Error::InvalidMesh` naming what is wrong and where.
    pub fn validate(&self) -> Result<MeshReport> {
        let report = self.check();
        match report.to_error() {
            Some(e) => Err(e),
            None => Ok(report),
        }
    }
}

/// Integer types accepted as triangle indices by [`TriMesh::from_arrays`].
pub trait TriIndex: Copy {
    /// The index as u32 if it addresses one of `nv` vertices.
    fn to_index(self, nv: usize) -> Option<u32>;
    fn shown(self) -> String;
}

impl TriIndex for u32 {
    fn to_index(self, nv: usize) -> Option<u32> {
        ((self as usize) < nv).then_some(self)
    }
    fn shown(self) -> String {
        self.to_string()
    }
}

impl TriIndex for i64 {
    fn to_index(self, nv: usize) -> Option<u32> {
        (self >= 0 && (self as u64) < nv as u64).then_some(self as u32)
    }
    fn shown(self) -> String {
        self.to_string()
    }
}

impl TriIndex for usize {
    fn to_index(self, nv: usize) -> Option<u32> {
        (self < nv).then_some(self as u32)
    }
    fn shown(self) -> String {
        self.to_string()
    }
}

#[cfg(test)]
pub(crate) mod tests;
