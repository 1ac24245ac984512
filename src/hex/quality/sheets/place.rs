//! The path nodes onto the input's feature corners and curves between their
//! patches, and the settling of the new sheets before the smoothing.

use super::labels::{nearest_path_node, Paths};
use super::patches::{pair_curves, Patches};
use super::{SheetReport, SETTLE_ITERATIONS, SETTLE_RING};
use crate::geometry::vec3::*;
use crate::hex::surface::{CurvePoint, Surface};
use crate::hex::work::{Role, Work};
use std::collections::HashMap;

/// Corners first: each feature corner (not `released`, still held after the
/// patch merge) to the nearest path node within `reach`, preferring a node where
/// three labels or more meet; then every other path node onto the nearest curve
/// between two of its labels within `reach`, with its path neighbours on the
/// same curve (or at a corner) as its curve neighbours. Counted in `rep`.
#[allow(clippy::too_many_arguments)]
pub(super) fn onto_features(
    w: &mut Work,
    sw: &Surface,
    edge_tris: &HashMap<(u32, u32), Vec<u32>>,
    patches: &Patches,
    paths: &Paths,
    reach: f64,
    released: &[u32],
    rep: &mut SheetReport,
) {
    let (path, node_labels) = (&paths.nodes, &paths.node_labels);
    // curves by the pair of patches on their two sides
    let pair_curves = pair_curves(sw, edge_tris, &patches.tri_patch);
    // corners first: each feature corner to the nearest path node within reach,
    // preferring a node where three labels or more meet
    let mut taken: HashMap<u32, u32> = HashMap::new();
    let mut taken_at: Vec<[f64; 3]> = Vec::new();
    for (ci, &k) in sw.features.corners.iter().enumerate() {
        if released.contains(&(ci as u32)) {
            rep.corners_released += 1;
            continue;
        }
        if !patches.corner_held_ok[ci] {
            continue;
        }
        let cx = sw.mesh.vertices[k as usize];
        // corners closer together than two thirds of the reach (a face too small for
        // the lattice): the first only
        if taken_at.iter().any(|&p| norm(sub(p, cx)) < reach / 1.5) {
            continue;
        }
        let best = |min_labels: usize| nearest_path_node(path, node_labels, &w.mesh.nodes, cx, reach, min_labels, |v| !taken.contains_key(&v));
        if let Some(v) = best(3).or_else(|| best(2)) {
            taken.insert(v, k);
            taken_at.push(cx);
            rep.corners_held.push([v, ci as u32]);
        }
    }
    for &v in path {
        let vi = v as usize;
        if let Some(&k) = taken.get(&v) {
            w.role[vi] = Role::Corner(k);
            w.mesh.nodes[vi] = sw.mesh.vertices[k as usize];
            w.attach[vi] = u32::MAX;
            rep.corner_nodes += 1;
            continue;
        }
        let x = w.mesh.nodes[vi];
        let labs = &node_labels[vi];
        let mut best: Option<(usize, CurvePoint)> = None;
        for i in 0..labs.len() {
            for j in i + 1..labs.len() {
                let key = (labs[i].min(labs[j]), labs[i].max(labs[j]));
                for &c in pair_curves.get(&key).map(|v| &v[..]).unwrap_or(&[]) {
                    let cp = sw.closest_on_curve(c, x);
                    if best.as_ref().is_none_or(|b| cp.distance < b.1.distance) {
                        best = Some((c, cp));
                    }
                }
            }
        }
        match best {
            Some((c, cp)) if cp.distance <= reach => {
                w.role[vi] = Role::Curve(c as u32);
                w.mesh.nodes[vi] = cp.point;
                w.attach[vi] = u32::MAX;
                rep.curve_nodes += 1;
            }
            _ => {}
        }
    }
    for &v in path {
        let Role::Curve(c) = w.role[v as usize] else { continue };
        w.curve_nb[v as usize] = paths
            .nb
            .get(&v)
            .map(|nb| nb.iter().copied().filter(|&u| matches!(w.role[u as usize], Role::Corner(_)) || w.role[u as usize] == Role::Curve(c)).collect())
            .unwrap_or_default();
    }
}

/// The new nodes (from `n0`, of the patches `copy_patch`), and the old ones next
/// to a path, where their neighbours put them (Laplacian; free boundary nodes
/// back onto their own patch), so that the sheets get a thickness before the
/// untangling smoothing.
pub(super) fn settle(w: &mut Work, sw: &Surface, tri_patch: &[u32], paths: &Paths, copy_patch: &[u32], n0: usize) {
    let n1 = w.mesh.nodes.len();
    let mut patch_of = vec![u32::MAX; n1];
    for v in n0..n1 {
        patch_of[v] = copy_patch[v - n0];
    }
    for v in 0..n0 {
        if let [l] = paths.node_labels[v][..] {
            patch_of[v] = l;
        }
    }
    let mut movable: Vec<bool> = (0..n1).map(|v| v >= n0).collect();
    let mut front: Vec<u32> = paths.nodes.clone();
    for _ in 0..SETTLE_RING {
        let mut next = Vec::new();
        for &v in &front {
            for &u in w.nbr.of(v as usize) {
                if !movable[u as usize] && matches!(w.role[u as usize], Role::Free | Role::Interior) {
                    movable[u as usize] = true;
                    next.push(u);
                }
            }
        }
        front = next;
    }
    for _ in 0..SETTLE_ITERATIONS {
        for v in (0..n1).filter(|&v| movable[v]) {
            let nb = w.nbr.of(v);
            if nb.is_empty() {
                continue;
            }
            let avg = scale(nb.iter().fold([0.0; 3], |a, &u| add(a, w.mesh.nodes[u as usize])), 1.0 / nb.len() as f64);
            w.mesh.nodes[v] = match (w.role[v], patch_of[v]) {
                // onto the node's own patch (a point nearer the other face would put
                // it across the curve)
                (Role::Free, p) if p != u32::MAX => match sw.bvh.nearest(avg, |t| if tri_patch[t as usize] == p { sw.dist2_to_triangle(t, avg) } else { f64::INFINITY }) {
                    Some((t, d2)) if d2.is_finite() => sw.closest_on_triangle(t, avg),
                    _ => sw.closest(avg).0,
                },
                (Role::Free, _) => sw.closest(avg).0,
                _ => avg,
            };
            if w.role[v] == Role::Free {
                w.attach[v] = u32::MAX;
            }
        }
    }
}
