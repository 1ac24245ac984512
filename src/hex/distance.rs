//! Two-sided Hausdorff distance between the boundary of a hex mesh and a triangle
//! surface, measured on samples: the hex side on a 5 x 5 grid of points of every
//! bilinear boundary quad, the surface side at every vertex, every edge midpoint and
//! area-uniform random samples (seeded), each point's exact distance to the other
//! side (the hex boundary as four triangles per quad around the quad centre).

use super::topology::boundary_quads;
use super::HexMesh;
use crate::geometry::vec3::*;
use crate::geometry::{sample_surface, Aabb, SurfaceLocator};
use crate::mesh::TriMesh;
use rand::SeedableRng;
use rayon::prelude::*;

/// Distances in the units of the inputs and relative to the surface's bounding-box diagonal.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize)]
pub struct Hausdorff {
    /// max over the hex boundary of the distance to the surface
    pub hex_to_surface: f64,
    /// max over the surface of the distance to the hex boundary
    pub surface_to_hex: f64,
    /// max of the two
    pub distance: f64,
    /// `distance` / bounding-box diagonal of the surface
    pub relative: f64,
    /// mean of the hex-to-surface distances, relative to the diagonal
    pub mean_relative: f64,
}

/// The boundary of a hex mesh as triangles (4 per quad, around the quad centre).
pub fn boundary_trimesh(m: &HexMesh) -> TriMesh {
    let bq = boundary_quads(m).unwrap_or_default();
    let mut t = TriMesh { vertices: m.nodes.clone(), triangles: Vec::with_capacity(4 * bq.len()) };
    for q in bq {
        let c = scale(q.nodes.iter().fold([0.0; 3], |a, &i| add(a, m.nodes[i as usize])), 0.25);
        let ci = t.vertices.len() as u32;
        t.vertices.push(c);
        for k in 0..4 {
            t.triangles.push([q.nodes[k], q.nodes[(k + 1) % 4], ci]);
        }
    }
    t
}

/// Two-sided Hausdorff distance between the boundary of `hex` and `surface`, with
/// `samples` extra random points on the surface (seed fixed).
pub fn hausdorff(hex: &HexMesh, surface: &TriMesh, samples: usize) -> Hausdorff {
    let diag = Aabb::of_points(&surface.vertices).diagonal();
    let bq = boundary_quads(hex).unwrap_or_default();
    if bq.is_empty() || surface.triangles.is_empty() {
        return Hausdorff { relative: f64::INFINITY, distance: f64::INFINITY, ..Default::default() };
    }
    let sloc = SurfaceLocator::new(surface);
    let hb = boundary_trimesh(hex);
    let hloc = SurfaceLocator::new(&hb);
    const G: usize = 5;
    let hex_pts: Vec<[f64; 3]> = bq
        .iter()
        .flat_map(|q| {
            let p = q.nodes.map(|i| hex.nodes[i as usize]);
            (0..G * G).map(move |k| {
                let (u, v) = ((k % G) as f64 / (G - 1) as f64, (k / G) as f64 / (G - 1) as f64);
                let a = add(scale(p[0], 1.0 - u), scale(p[1], u));
                let b = add(scale(p[3], 1.0 - u), scale(p[2], u));
                add(scale(a, 1.0 - v), scale(b, v))
            })
        })
        .collect();
    let d_hex: Vec<f64> = hex_pts.par_iter().map(|&p| sloc.closest(p).2).collect();
    let mut surf_pts: Vec<[f64; 3]> = surface.vertices.clone();
    for t in &surface.triangles {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            if a < b {
                surf_pts.push(scale(add(surface.vertices[a as usize], surface.vertices[b as usize]), 0.5));
            }
        }
    }
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
    surf_pts.extend(sample_surface(surface, samples, &mut rng).into_iter().map(|s| s.point));
    let d_surf: Vec<f64> = surf_pts.par_iter().map(|&p| hloc.closest(p).2).collect();
    let h1 = d_hex.iter().copied().fold(0.0, f64::max);
    let h2 = d_surf.iter().copied().fold(0.0, f64::max);
    let d = h1.max(h2);
    Hausdorff {
        hex_to_surface: h1,
        surface_to_hex: h2,
        distance: d,
        relative: d / diag,
        mean_relative: d_hex.iter().sum::<f64>() / d_hex.len() as f64 / diag,
    }
}

/// The points where `mesh` (user coordinates) is farthest from the input of
/// `fr`, in the working frame: input vertices and boundary nodes of the mesh at
/// least `frac` times the largest such distance away (the two one-sided
/// distances of the Hausdorff distance, at vertices and nodes), or at least
/// `at_most` (working-frame units) away when that is less. Empty when the mesh
/// lies on the input.
pub fn far_points(mesh: &HexMesh, fr: &super::frames::Frames, frac: f64, at_most: f64) -> Vec<[f64; 3]> {
    let Some(u_to_w) = fr.w_to_u.inverse() else { return Vec::new() };
    let hw = HexMesh { nodes: mesh.nodes.iter().map(|&p| u_to_w.apply(p)).collect(), elements: mesh.elements.clone() };
    let hb = boundary_trimesh(&hw);
    let hloc = SurfaceLocator::new(&hb);
    let mut pts: Vec<([f64; 3], f64)> = fr.sw.mesh.vertices.par_iter().map(|&p| (p, hloc.closest(p).2)).collect();
    let bnodes: std::collections::BTreeSet<u32> = boundary_quads(&hw).unwrap_or_default().iter().flat_map(|q| q.nodes).collect();
    let bnodes: Vec<u32> = bnodes.into_iter().collect();
    pts.par_extend(bnodes.par_iter().map(|&v| (hw.nodes[v as usize], fr.sw.closest(hw.nodes[v as usize]).2)));
    let dmax = pts.iter().map(|p| p.1).fold(0.0, f64::max);
    if !(dmax > 0.0) {
        return Vec::new();
    }
    let limit = (frac * dmax).min(at_most);
    pts.into_iter().filter(|p| p.1 >= limit).map(|p| p.0).collect()
}
