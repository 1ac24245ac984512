//! The inverse of the chart maps: a point of a polycube face (normalised frame)
//! onto the input surface, by locating it in the chart's embedded triangulation
//! (a uniform grid over the embedded triangles) and interpolating the input
//! triangle's vertices with its barycentric coordinates. Where every chart maps
//! without a flipped triangle this is a bijection from the polycube's boundary
//! onto the input surface; points on a polycube edge or corner get the same image
//! from each of their faces, because neighbouring charts place their shared
//! boundary by the same arc length between the same corner vertices.

use super::faces::plane_coords;
use crate::geometry::StableHashMap;
use super::{ChartMap, Charts};
use crate::geometry::vec3::*;
use crate::mesh::TriMesh;

/// Largest distance (normalised units) of a point from a face for it to count as
/// on that face.
const ON_FACE: f64 = 1e-9;

/// A point of the input surface found for a polycube point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Located {
    /// The polycube face whose chart holds it.
    pub face: usize,
    /// The input triangle.
    pub triangle: u32,
    /// The point on the input (normalised frame).
    pub point: [f64; 3],
}

/// Point location in one chart's embedding.
#[derive(Debug, Clone)]
struct ChartGrid {
    /// Embedded triangles: input triangle id and the 2D corners with their input vertices.
    tris: Vec<(u32, [[f64; 2]; 3], [u32; 3])>,
    lo: [f64; 2],
    cell: [f64; 2],
    n: usize,
    cells: Vec<Vec<u32>>,
}

impl ChartGrid {
    fn new(mesh: &TriMesh, map: &ChartMap, dir: u8) -> ChartGrid {
        let index: StableHashMap<u32, usize> = map.vertices.iter().enumerate().map(|(i, &v)| (v, i)).collect();
        let mut tris = Vec::with_capacity(map.triangles.len());
        for &t in &map.triangles {
            let tri = mesh.triangles[t as usize];
            let q = tri.map(|v| plane_coords(dir, map.positions[index[&v]]));
            let a = (q[1][0] - q[0][0]) * (q[2][1] - q[0][1]) - (q[1][1] - q[0][1]) * (q[2][0] - q[0][0]);
            // triangles without area (ears) cover nothing their neighbours do not
            if a.abs() > 1e-14 {
                tris.push((t, q, tri));
            }
        }
        let mut lo = [f64::INFINITY; 2];
        let mut hi = [f64::NEG_INFINITY; 2];
        for (_, q, _) in &tris {
            for p in q {
                for a in 0..2 {
                    lo[a] = lo[a].min(p[a]);
                    hi[a] = hi[a].max(p[a]);
                }
            }
        }
        let n = ((tris.len() as f64).sqrt().ceil() as usize).clamp(1, 256);
        let cell = [0usize, 1].map(|a| ((hi[a] - lo[a]) / n as f64).max(1e-12));
        let mut cells = vec![Vec::new(); n * n];
        for (i, (_, q, _)) in tris.iter().enumerate() {
            let r = |a: usize, f: fn(f64, f64) -> f64, init: f64| q.iter().map(|p| p[a]).fold(init, f);
            let (x0, x1) = (r(0, f64::min, f64::INFINITY), r(0, f64::max, f64::NEG_INFINITY));
            let (y0, y1) = (r(1, f64::min, f64::INFINITY), r(1, f64::max, f64::NEG_INFINITY));
            let (i0, i1) = (Self::slot(x0 - 1e-9, lo[0], cell[0], n), Self::slot(x1 + 1e-9, lo[0], cell[0], n));
            let (j0, j1) = (Self::slot(y0 - 1e-9, lo[1], cell[1], n), Self::slot(y1 + 1e-9, lo[1], cell[1], n));
            for j in j0..=j1 {
                for k in i0..=i1 {
                    cells[j * n + k].push(i as u32);
                }
            }
        }
        ChartGrid { tris, lo, cell, n, cells }
    }

    fn slot(x: f64, lo: f64, cell: f64, n: usize) -> usize {
        (((x - lo) / cell).floor().max(0.0) as usize).min(n - 1)
    }

    /// The triangle that holds `p` best (largest smallest barycentric coordinate)
    /// among `cands`, with its barycentric coordinates.
    fn best<I: Iterator<Item = usize>>(&self, p: [f64; 2], cands: I) -> Option<(usize, [f64; 3])> {
        let mut best: Option<(usize, [f64; 3], f64)> = None;
        for i in cands {
            let q = self.tris[i].1;
            let d = (q[1][0] - q[0][0]) * (q[2][1] - q[0][1]) - (q[1][1] - q[0][1]) * (q[2][0] - q[0][0]);
            let l1 = ((q[2][0] - q[0][0]) * (p[1] - q[0][1]) - (q[2][1] - q[0][1]) * (p[0] - q[0][0])) / -d;
            let l2 = ((q[1][0] - q[0][0]) * (p[1] - q[0][1]) - (q[1][1] - q[0][1]) * (p[0] - q[0][0])) / d;
            let b = [1.0 - l1 - l2, l1, l2];
            let m = b[0].min(b[1]).min(b[2]);
            if best.as_ref().is_none_or(|x| m > x.2) {
                best = Some((i, b, m));
            }
        }
        best.map(|(i, b, _)| (i, b))
    }

    /// Locate `p` (2D face coordinates): the input triangle and barycentric
    /// coordinates (clamped to the triangle), or None when `p` is off the chart.
    fn locate(&self, p: [f64; 2]) -> Option<(u32, [u32; 3], [f64; 3])> {
        let tol = 1e-7;
        let (k, j) = (Self::slot(p[0], self.lo[0], self.cell[0], self.n), Self::slot(p[1], self.lo[1], self.cell[1], self.n));
        let mut found = self.best(p, self.cells[j * self.n + k].iter().map(|&i| i as usize));
        let inside = |f: &Option<(usize, [f64; 3])>| f.is_some_and(|(_, b)| b.iter().all(|&x| x >= -tol));
        if !inside(&found) {
            found = self.best(p, 0..self.tris.len());
        }
        let (i, b) = found?;
        if b.iter().any(|&x| x < -1e-5) {
            return None;
        }
        let mut b = b.map(|x| x.max(0.0));
        let s: f64 = b.iter().sum();
        b = b.map(|x| x / s);
        Some((self.tris[i].0, self.tris[i].2, b))
    }
}

/// The inverse of every chart map of a polycube (see the module docs).
#[derive(Debug, Clone)]
pub struct ChartInverse {
    surface: TriMesh,
    faces: super::PolycubeFaces,
    /// Per polycube corner: its position and input vertex.
    corners: Vec<([f64; 3], u32)>,
    grids: Vec<ChartGrid>,
}

impl ChartInverse {
    /// The inverse of `charts` (computed on `surface`). Err says why there is none:
    /// the charts do not match the polycube's faces, a chart does not map, or a
    /// chart's map has flipped triangles (it is then not bijective).
    pub fn new(surface: &TriMesh, charts: &Charts) -> std::result::Result<ChartInverse, String> {
        if let Err(e) = charts.segmentation.check() {
            return Err(e.to_string());
        }
        let pf = &charts.faces;
        let mut grids = Vec::with_capacity(charts.maps.len());
        for (f, m) in charts.maps.iter().enumerate() {
            let m = m.as_ref().map_err(|e| e.to_string())?;
            if m.flipped > 0 {
                return Err(format!("the chart of face {} maps with {} flipped triangles", pf.name(f), m.flipped));
            }
            grids.push(ChartGrid::new(surface, m, pf.faces[f].dir));
        }
        let mut corners = Vec::with_capacity(pf.corners.len());
        for (c, k) in pf.corners.iter().enumerate() {
            let v = charts.segmentation.corners[c].ok_or_else(|| format!("polycube corner {c} has no input vertex"))?;
            corners.push((k.position, v));
        }
        Ok(ChartInverse { surface: surface.clone(), faces: pf.clone(), corners, grids })
    }

    /// The polycube faces `p` (normalised frame) lies on.
    pub fn faces_at(&self, p: [f64; 3]) -> Vec<usize> {
        (0..self.faces.faces.len())
            .filter(|&f| {
                let face = &self.faces.faces[f];
                (p[face.dir as usize / 2] - face.plane).abs() <= ON_FACE && self.faces.distance(f, p) <= ON_FACE
            })
            .collect()
    }

    /// The input point of the polycube point `p` (normalised frame), or None when
    /// `p` is not on the polycube's boundary. A polycube corner goes to its input
    /// vertex; a point on several faces to its image in the chart that holds it
    /// best (the images agree up to rounding).
    pub fn locate(&self, p: [f64; 3]) -> Option<Located> {
        let faces = self.faces_at(p);
        if let Some(&(_, v)) = self.corners.iter().find(|(q, _)| norm(sub(*q, p)) <= ON_FACE) {
            let t = self.surface.triangles.iter().position(|t| t.contains(&v)).unwrap_or(0) as u32;
            return Some(Located { face: *faces.first()?, triangle: t, point: self.surface.vertices[v as usize] });
        }
        let mut best: Option<(Located, f64)> = None;
        for f in faces {
            let dir = self.faces.faces[f].dir;
            let Some((t, tri, b)) = self.grids[f].locate(plane_coords(dir, p)) else { continue };
            let m = b[0].min(b[1]).min(b[2]);
            let point = (0..3).fold([0.0; 3], |acc, k| add(acc, scale(self.surface.vertices[tri[k] as usize], b[k])));
            if best.as_ref().is_none_or(|x| m > x.1) {
                best = Some((Located { face: f, triangle: t, point }, m));
            }
        }
        best.map(|x| x.0)
    }
}
