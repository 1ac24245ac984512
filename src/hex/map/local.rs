//! Local refinement of the chosen level (`MapOptions::local_refinement`): where
//! the finished mesh is farthest from the input, the level's elements are split
//! 3 x 3 x 3 with conforming transition elements ([`crate::hex::refine`]) and the
//! new nodes are placed as the level's were: on the boundary by the inverse chart
//! maps (or the closest facing point under the projection), on a polycube edge
//! matched to a feature curve onto that curve, inside by the harmonic map. The
//! quality steps then run on the refined level. It refines where the distance
//! asks for it instead of a whole level, which multiplies every element by eight.

use super::levels::Placer;
use crate::geometry::vec3::*;
use crate::hex::fit::harmonic_interior;
use crate::hex::quality::summary;
use crate::hex::refine::{close_marks, in_boxes, interpolate_new_nodes, merge_boxes, refine_flags};
use crate::hex::surface::Surface;
use crate::hex::work::{quad_normals, Level, Role};
use crate::hex::{topology, HexMesh};
use rayon::prelude::*;
use std::collections::HashMap;

/// Points at least this share of the largest distance between the mesh and the
/// input count as far (the fallback's local refinement uses the same share,
/// measured there: BENCHMARKS.md "Local refinement").
pub(super) const FAR_SHARE: f64 = 0.8;

/// Boxes of lattice nodes of `lv` (inclusive) to split: around each of the
/// points `far` (working frame) the nodes one lattice step from its nearest
/// boundary node of the mapped level, added to `boxes` and merged with them
/// ([`merge_boxes`]: boxes closer than two steps become their bounding box, so
/// that every element's marked corners have a template and the marks do not
/// spread). Returns the marked nodes.
pub(super) fn mark_far(lv: &Level, far: &[[f64; 3]], boxes: &mut Vec<([u32; 3], [u32; 3])>) -> Vec<bool> {
    let h = &lv.h;
    let bnodes: Vec<usize> = (0..lv.pos.len()).filter(|&v| lv.role[v].on_boundary()).collect();
    if !bnodes.is_empty() {
        let nearest: Vec<usize> = far
            .par_iter()
            .map(|&p| *bnodes.iter().min_by(|&&a, &&b| dist2(lv.pos[a], p).total_cmp(&dist2(lv.pos[b], p))).expect("boundary nodes"))
            .collect();
        for v in nearest {
            let l = h.node_lattice[v];
            boxes.push((l.map(|c| c.saturating_sub(1)), std::array::from_fn(|a| (l[a] + 1).min(h.dims[a] as u32 - 1))));
        }
        *boxes = merge_boxes(boxes);
    }
    let mut marked: Vec<bool> = h.node_lattice.iter().map(|&p| in_boxes(p, boxes)).collect();
    close_marks(&h.mesh.elements, &mut marked);
    marked
}

/// The level `lv` with its elements whose corners are all `marked` split 3 x 3 x 3
/// and transition elements around them, the new nodes placed by `placer` on `sw`;
/// with the refined elements' target boxes (their shape in the start embedding)
/// and the number of elements split. Err says why it cannot be refined.
pub(super) fn refine_level(lv: &Level, marked: &[bool], placer: &Placer, sw: &Surface) -> Result<(Level, Vec<[f64; 3]>, usize), String> {
    let h = &lv.h;
    let r = refine_flags(&h.node_lattice, &h.mesh.elements, marked);
    let n_old = h.node_lattice.len();
    let n = r.nodes.len();
    // lattice units -> grid units (one cell = 3 sub-voxels of `subdiv` elements)
    let per_cell = (3 * h.subdiv) as f64;
    let grid = |x: [f64; 3]| x.map(|c| c / per_cell);
    let pos = interpolate_new_nodes(&r, &h.node_lattice, &h.mesh.elements, &h.elem_lattice, &lv.pos)?;
    let mut m = HexMesh { nodes: pos, elements: r.elements };
    let bquads: Vec<[u32; 4]> = topology::boundary_quads(&m).map_err(|e| e.to_string())?.into_iter().map(|q| q.nodes).collect();
    // the old nodes keep their roles (the refinement does not move the boundary)
    let mut role = lv.role.clone();
    role.resize(n, Role::Interior);
    for &v in bquads.iter().flatten() {
        if v as usize >= n_old {
            role[v as usize] = Role::Free;
        }
    }
    let curve_nb = split_curves(lv, &r.nodes, &mut role);
    let mut attach = lv.attach.clone();
    attach.resize(n, u32::MAX);
    let nrm = quad_normals(n, &bquads, &m.nodes);
    let placed: Vec<Option<([f64; 3], u32)>> = (n_old..n)
        .into_par_iter()
        .map(|v| {
            if !role[v].on_boundary() {
                return None;
            }
            let charted = placer.charts.as_ref().and_then(|ci| ci.locate(placer.frame.to_normalised(grid(r.nodes[v]))));
            let (q, t) = match charted {
                Some(l) => (placer.to_w.apply(l.point), l.triangle),
                None => {
                    let (q, t, _) = sw.closest_facing(m.nodes[v], nrm[v], 0.0);
                    (q, t)
                }
            };
            Some(match role[v] {
                Role::Curve(c) => (sw.closest_on_curve(c as usize, q).point, u32::MAX),
                _ => (q, t),
            })
        })
        .collect();
    for (i, p) in placed.into_iter().enumerate() {
        if let Some((q, t)) = p {
            m.nodes[n_old + i] = q;
            attach[n_old + i] = t;
        }
    }
    // inside: the interpolated positions or the harmonic map, whichever is better
    let nbr = topology::node_neighbours(n, &topology::edges(&m));
    let mut harm = m.nodes.clone();
    harmonic_interior(&nbr, &role, &mut harm, 1e-9, 5000);
    let q_interp = summary(&m);
    let interp = std::mem::replace(&mut m.nodes, harm);
    let q_harm = summary(&m);
    if (q_interp.inverted, -q_interp.min) < (q_harm.inverted, -q_harm.min) {
        m.nodes = interp;
    }
    let targets: Vec<[f64; 3]> = m
        .elements
        .iter()
        .map(|el| {
            let e = |k: usize| placer.embed(grid(r.nodes[el[k] as usize]));
            let o = e(0);
            [1, 3, 4].map(|k| norm(sub(e(k), o)).max(1e-12))
        })
        .collect();
    let mut hl = h.clone();
    hl.mesh = HexMesh { nodes: r.nodes.iter().map(|&x| grid(x)).collect(), elements: m.elements };
    let level = Level { h: hl, pos: m.nodes, attach, role, curve_nb, bquads, released_corners: lv.released_corners.clone() };
    Ok((level, targets, r.split))
}

/// The curve neighbours of the refined level: a level edge between two nodes on
/// one feature curve (curve neighbours, or a curve node and a corner) that was
/// split in three puts its two new nodes on that curve, between its ends. Sets
/// those nodes' roles in `role`; `nodes` are the refinement's nodes in lattice
/// units (the level's first, in its order).
fn split_curves(lv: &Level, nodes: &[[f64; 3]], role: &mut [Role]) -> Vec<Vec<u32>> {
    let n_old = lv.pos.len();
    // template points lie on twelfths of a lattice step
    let key = |x: [f64; 3]| x.map(|c| (c * 12.0).round() as i64);
    let index: HashMap<[i64; 3], u32> = nodes.iter().enumerate().skip(n_old).map(|(i, &x)| (key(x), i as u32)).collect();
    let mut nb = lv.curve_nb.clone();
    nb.resize(nodes.len(), Vec::new());
    for u in 0..n_old {
        let Role::Curve(c) = lv.role[u] else { continue };
        for &w in &lv.curve_nb[u] {
            let w = w as usize;
            // a pair of curve nodes once (from its lower end); a corner from the curve's side
            if matches!(lv.role[w], Role::Curve(_)) && w < u {
                continue;
            }
            let (a, b) = (nodes[u], nodes[w]);
            let at = |t: f64| add(a, scale(sub(b, a), t));
            let (Some(&i1), Some(&i2)) = (index.get(&key(at(1.0 / 3.0))), index.get(&key(at(2.0 / 3.0)))) else { continue };
            role[i1 as usize] = Role::Curve(c);
            role[i2 as usize] = Role::Curve(c);
            for x in nb[u].iter_mut().filter(|x| **x as usize == w) {
                *x = i1;
            }
            for x in nb[w].iter_mut().filter(|x| **x as usize == u) {
                *x = i2;
            }
            nb[i1 as usize] = vec![u as u32, i2];
            nb[i2 as usize] = vec![i1, w as u32];
        }
    }
    nb
}
