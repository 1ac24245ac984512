//! Pillowing: one layer of hexahedra inserted under the whole boundary, so that no
//! element keeps two faces on the surface (elements along polycube edges mapped
//! onto smooth parts of the input would otherwise be flat there).
//!
//! Every boundary node v gets an inner copy v' that takes its place in the old
//! elements; each boundary quad (a, b, c, d), counter-clockwise seen from outside,
//! becomes the element [a', b', c', d', a, b, c, d]. Its bottom face a'b'c'd' then
//! has its right-hand normal pointing to the top face, which is the positive
//! orientation of VTK_HEXAHEDRON; the orientation is checked on the result (signed
//! volume and scaled Jacobian of every new element), not assumed.

use super::measure::{scaled_jacobian, QualitySummary, DEGENERATE};
use super::step::stage_report;
use crate::error::{check_progress, Error, Progress, Result};
use crate::geometry::vec3::*;
use crate::hex::stages::{Stage, StageDetails, StageReport};
use crate::hex::topology::{boundary_quads, hex_volume};
use crate::hex::work::{Role, Work};
use std::time::Instant;

/// The pillowing step (`QualityOptions::pillow`): [`pillow`] on the mapped mesh,
/// whose quality is `before`.
pub fn pillowing(work: &mut Work, before: QualitySummary, progress: &mut dyn Progress) -> Result<StageReport> {
    check_progress(progress, 0.55, "hex: pillowing")?;
    let t0 = Instant::now();
    let rep: PillowReport = pillow(work)?;
    Ok(stage_report(Stage::Pillowing, before, &work.mesh, t0, StageDetails::Pillowing(rep)))
}

/// What pillowing did.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize)]
pub struct PillowReport {
    pub boundary_quads: usize,
    pub nodes_added: usize,
    pub elements_added: usize,
    /// New elements whose orientation differs from the element that owned their
    /// boundary quad (a flipped node order): must be 0.
    pub flipped_elements: usize,
    /// New elements with negative signed volume (inherited from inverted mapped elements).
    pub negative_volume: usize,
    /// Smallest scaled Jacobian among the new elements.
    pub min_new_sj: f64,
    /// Inner copies pulled back towards the surface to keep old elements valid.
    pub nodes_pulled_back: usize,
}

/// Insert one pillow layer under the boundary of `w.mesh`.
pub fn pillow(w: &mut Work) -> Result<PillowReport> {
    let bq = boundary_quads(&w.mesh).map_err(Error::MeshingFailed)?;
    let n0 = w.mesh.nodes.len();
    let mut copy = vec![u32::MAX; n0];
    let mut bnodes = Vec::new();
    for q in &bq {
        for &v in &q.nodes {
            if copy[v as usize] == u32::MAX {
                copy[v as usize] = (n0 + bnodes.len()) as u32;
                bnodes.push(v);
            }
        }
    }
    // inner copy target: straight below the node along the boundary normal, half as
    // deep as the thinnest element under the node's boundary quads (thickness = from
    // the boundary face's centroid to the centroid of the opposite face)
    let mut nrm = vec![[0.0; 3]; n0];
    let mut depth = vec![f64::INFINITY; n0];
    const OPPOSITE: [usize; 6] = [1, 0, 4, 5, 2, 3];
    for q in &bq {
        let p = q.nodes.map(|i| w.mesh.nodes[i as usize]);
        let nq = cross(sub(p[2], p[0]), sub(p[3], p[1]));
        let el = w.mesh.elements[q.element as usize];
        let opp = crate::hex::topology::HEX_FACES[OPPOSITE[q.face as usize]].map(|i| w.mesh.nodes[el[i] as usize]);
        let cf = scale(p.iter().fold([0.0; 3], |a, x| add(a, *x)), 0.25);
        let co = scale(opp.iter().fold([0.0; 3], |a, x| add(a, *x)), 0.25);
        let thick = norm(sub(cf, co));
        for &v in &q.nodes {
            nrm[v as usize] = add(nrm[v as usize], nq);
            depth[v as usize] = depth[v as usize].min(0.5 * thick);
        }
    }
    let targets: Vec<[f64; 3]> = bnodes
        .iter()
        .map(|&v| {
            let x = w.mesh.nodes[v as usize];
            let l = norm(nrm[v as usize]);
            let d = depth[v as usize];
            if l > 0.0 && d.is_finite() {
                sub(x, scale(nrm[v as usize], d / l))
            } else {
                x
            }
        })
        .collect();
    let owner_sign: Vec<f64> = bq.iter().map(|q| hex_volume(&w.mesh.element_corners(q.element as usize)).signum()).collect();
    let quality_before: Vec<f64> = (0..w.mesh.elements.len()).map(|e| scaled_jacobian(&w.mesh.element_corners(e))).collect();
    let mut alpha = vec![1.0f64; bnodes.len()];
    for (k, &v) in bnodes.iter().enumerate() {
        let x = w.mesh.nodes[v as usize];
        w.mesh.nodes.push(add(x, scale(sub(targets[k], x), alpha[k])));
        w.role.push(Role::Interior);
        w.attach.push(u32::MAX);
        w.curve_nb.push(Vec::new());
    }
    for el in w.mesh.elements.iter_mut() {
        for v in el.iter_mut() {
            let c = copy[*v as usize];
            if c != u32::MAX {
                *v = c;
            }
        }
    }
    let first_new = w.mesh.elements.len();
    let has_targets = w.target.len() == first_new;
    // axis of each local edge of a hex face: (face corner 0 -> 1, 0 -> 3, normal)
    const UNIT: [[i32; 3]; 8] = [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]];
    let axis_of = |i: usize, j: usize| (0..3).find(|&a| UNIT[i][a] != UNIT[j][a]).unwrap_or(0);
    for q in &bq {
        let [a, b, c, d] = q.nodes;
        w.mesh.elements.push([copy[a as usize], copy[b as usize], copy[c as usize], copy[d as usize], a, b, c, d]);
        if has_targets {
            let f = crate::hex::topology::HEX_FACES[q.face as usize];
            let t = w.target[q.element as usize];
            let (au, av) = (axis_of(f[0], f[1]), axis_of(f[0], f[3]));
            let aw = 3 - au - av;
            w.target.push([t[au], t[av], 0.5 * t[aw]]);
        }
    }
    // keep every element valid where it can be: pull inner copies back towards the
    // surface while an old element got inverted by the shrink or a new one is inverted
    let mut pulled = std::collections::HashSet::new();
    for _round in 0..8 {
        let mut bad = Vec::new();
        for (e, el) in w.mesh.elements.iter().enumerate() {
            let now = scaled_jacobian(&w.mesh.element_corners(e));
            let a = if now == DEGENERATE { -1.0 } else { now };
            let b = if e < first_new {
                let before = quality_before[e];
                if before == DEGENERATE {
                    -1.0
                } else {
                    before
                }
            } else {
                1.0
            };
            if a <= 0.0 && b > 0.0 {
                bad.extend(el.iter().copied().filter(|&i| i as usize >= n0));
            }
        }
        if bad.is_empty() {
            break;
        }
        bad.sort_unstable();
        bad.dedup();
        for i in bad {
            let k = i as usize - n0;
            alpha[k] *= 0.5;
            let x = w.mesh.nodes[bnodes[k] as usize];
            w.mesh.nodes[i as usize] = add(x, scale(sub(targets[k], x), alpha[k]));
            pulled.insert(k);
        }
    }
    let mut rep = PillowReport {
        boundary_quads: bq.len(),
        nodes_added: bnodes.len(),
        elements_added: bq.len(),
        flipped_elements: 0,
        negative_volume: 0,
        min_new_sj: f64::INFINITY,
        nodes_pulled_back: pulled.len(),
    };
    for e in first_new..w.mesh.elements.len() {
        let p = w.mesh.element_corners(e);
        let v = hex_volume(&p);
        if v < 0.0 {
            rep.negative_volume += 1;
        }
        if v.signum() != owner_sign[e - first_new] && owner_sign[e - first_new] != 0.0 {
            rep.flipped_elements += 1;
        }
        let s = scaled_jacobian(&p);
        rep.min_new_sj = rep.min_new_sj.min(if s == DEGENERATE { -1.0 } else { s });
    }
    w.rebuild();
    Ok(rep)
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::hex::grid::lattice_hex;
    use crate::hex::quality::element_qualities;
    use crate::polycube::{assemble, Primitive};

    /// The work of a lattice mesh: boundary nodes free, interior nodes interior.
    pub(crate) fn work_of(h: &crate::hex::grid::LatticeHex) -> Work {
        let n = h.mesh.nodes.len();
        let bq = boundary_quads(&h.mesh).unwrap();
        let mut role = vec![Role::Interior; n];
        for q in &bq {
            for &v in &q.nodes {
                role[v as usize] = Role::Free;
            }
        }
        let mut w = Work {
            mesh: h.mesh.clone(),
            role,
            attach: vec![u32::MAX; n],
            curve_nb: vec![Vec::new(); n],
            bgraph: Default::default(),
            nbr: Default::default(),
            n2e: Default::default(),
            target: vec![[1.0; 3]; h.mesh.elements.len()],
        };
        w.rebuild();
        w
    }

    #[test]
    fn pillowing_keeps_orientation() {
        for p in [Primitive::Cube, Primitive::ThcZ, Primitive::BhcPx] {
            let mut l = [Primitive::Null; 12];
            l[0] = p;
            l[1] = Primitive::Cube;
            let h = lattice_hex(&assemble(&l), 1);
            let mut w = work_of(&h);
            let rep = pillow(&mut w).unwrap();
            assert_eq!(rep.flipped_elements, 0, "{p:?}");
            assert_eq!(rep.negative_volume, 0, "{p:?}");
            let q = element_qualities(&w.mesh);
            let bad: Vec<usize> = (0..q.len()).filter(|&e| q[e] <= 0.0).collect();
            assert!(bad.is_empty(), "{p:?}: {} inverted, e.g. {:?}", bad.len(), bad.first().map(|&e| w.mesh.element_corners(e)));
            assert!(rep.min_new_sj > 0.15, "{p:?} {}", rep.min_new_sj);
            assert_eq!(w.mesh.elements.len(), h.mesh.elements.len() + rep.boundary_quads);
        }
    }
}
