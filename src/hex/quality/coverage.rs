//! The coverage step (`QualityOptions::pin_uncovered`): boundary nodes pinned to
//! the input vertices the mesh boundary misses.

use super::capture::{pull_nodes, put_back};
use super::step::{fit_step_kept, guarded_fit_step};
use crate::geometry::vec3::*;
use crate::hex::stages::{Stage, StageDetails, StageReport};
use crate::hex::surface::Surface;
use crate::hex::work::{quad_normals, Role, Work};
use crate::hex::HexOptions;
use rayon::prelude::*;

/// The coverage step (with `QualityOptions::pin_uncovered` and a distance goal):
/// [`cover_uncovered_vertices`] for the input vertices farther than
/// `pin_uncovered` times the distance goal, kept by [`fit_step_kept`].
pub fn coverage(work: &mut Work, sw: &Surface, opts: &HexOptions) -> Option<StageReport> {
    if !(opts.quality.pin_uncovered > 0.0 && opts.goals.hausdorff > 0.0) {
        return None;
    }
    let tol = opts.quality.pin_uncovered * opts.goals.hausdorff * sw.bbox.diagonal();
    let kept = |b: &_, a: &_, h0, h1| fit_step_kept(b, a, h0, h1, &opts.goals, false);
    guarded_fit_step(work, sw, opts, Stage::Coverage, kept, StageDetails::Coverage, |w, floor| {
        let st = cover_uncovered_vertices(w, sw, tol, opts.surface.relax_iterations, floor);
        (st.uncovered > 0, st.pinned > 0, st)
    })
}

/// What [`cover_uncovered_vertices`] did.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize)]
pub struct CoverStats {
    /// Input vertices farther than the tolerance from the boundary.
    pub uncovered: usize,
    /// Of those, the ones a boundary node reached and now stays on.
    pub pinned: usize,
    pub rounds: usize,
    pub moves_accepted: usize,
}

/// Pin boundary nodes to the input vertices the mesh boundary misses.
///
/// The fit pulls every boundary node onto its nearest surface point, which bounds
/// the distance from the mesh to the surface but not back: a rim or a thin lip
/// that no node is nearest to stays uncovered (cgal_spool's recessed end). Every
/// input vertex farther than `tol` from the boundary (as four triangles per quad)
/// gets, farthest first, its nearest free boundary node (one node per vertex),
/// which is pulled towards it over `rounds` rounds in steps that keep every element
/// valid and no worse than min(before, `floor`) (interior nodes smoothed between
/// rounds). A node that reaches its vertex becomes `Role::Corner` of it, so the
/// later stages keep it there; one that does not goes back onto the surface where
/// it stands (when that keeps its elements valid) and stays free.
pub fn cover_uncovered_vertices(w: &mut Work, sw: &Surface, tol: f64, rounds: usize, floor: f64) -> CoverStats {
    let mut st = CoverStats::default();
    let hb = crate::hex::distance::boundary_trimesh(&w.mesh);
    if hb.triangles.is_empty() {
        return st;
    }
    let loc = crate::geometry::SurfaceLocator::new(&hb);
    let mut far: Vec<(f64, usize)> = sw.mesh.vertices.par_iter().enumerate().map(|(i, &p)| (loc.closest(p).2, i)).filter(|&(d, _)| d > tol).collect();
    far.sort_by(|a, b| b.0.total_cmp(&a.0));
    st.uncovered = far.len();
    let free: Vec<usize> = (0..w.mesh.nodes.len()).filter(|&v| w.role[v] == Role::Free).collect();
    // outward normals of the boundary nodes and of the input's vertices (every
    // incident triangle's): a node is pulled only to a vertex on a side of the
    // input facing like it, never across a thin part to the far side
    let bq: Vec<[u32; 4]> = crate::hex::topology::boundary_quads(&w.mesh).unwrap_or_default().into_iter().map(|q| q.nodes).collect();
    let node_n = quad_normals(w.mesh.nodes.len(), &bq, &w.mesh.nodes);
    let mut vert_tris: Vec<Vec<u32>> = vec![Vec::new(); sw.mesh.vertices.len()];
    for (t, tri) in sw.mesh.triangles.iter().enumerate() {
        for &i in tri {
            vert_tris[i as usize].push(t as u32);
        }
    }
    let facing = |v: usize, i: usize| {
        let n = node_n[v];
        let l = norm(n);
        l > 0.0 && vert_tris[i].iter().any(|&t| dot(sw.normal(t), n) > 0.5 * l)
    };
    let mut taken = std::collections::HashSet::new();
    let mut pins: Vec<(usize, usize)> = Vec::new(); // (node, input vertex)
    for (_, i) in far {
        let p = sw.mesh.vertices[i];
        let best = free
            .iter()
            .filter(|v| !taken.contains(*v) && facing(**v, i))
            .map(|&v| (dist2(w.mesh.nodes[v], p), v))
            .min_by(|a, b| a.0.total_cmp(&b.0));
        if let Some((_, v)) = best {
            taken.insert(v);
            pins.push((v, i));
        }
    }
    if pins.is_empty() {
        return st;
    }
    // the pinned nodes leave the surface on their way: no projection for them meanwhile
    for &(v, i) in &pins {
        w.role[v] = Role::Corner(i as u32);
    }
    let start: Vec<([f64; 3], u32)> = pins.iter().map(|&(v, _)| (w.mesh.nodes[v], w.attach[v])).collect();
    let reach = 1e-3 * tol;
    let moves: Vec<(usize, [f64; 3])> = pins.iter().map(|&(v, i)| (v, sw.mesh.vertices[i])).collect();
    (st.rounds, st.moves_accepted) = pull_nodes(w, sw, &moves, rounds, floor, reach);
    for (k, &(v, i)) in pins.iter().enumerate() {
        let x = w.mesh.nodes[v];
        if norm(sub(sw.mesh.vertices[i], x)) <= reach {
            w.mesh.nodes[v] = sw.mesh.vertices[i];
            w.attach[v] = u32::MAX;
            st.pinned += 1;
            continue;
        }
        // not reached: back where it started on the surface if that keeps its
        // elements valid, else onto the surface where it stands
        w.role[v] = Role::Free;
        put_back(w, sw, v, start[k], floor);
    }
    st
}
