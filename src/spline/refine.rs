//! Truncated hierarchical refinement on the Bézier representation.
//!
//! Refining a leaf splits it into 8 children; every basis function that lives
//! on it is re-expressed on the children by de Casteljau subdivision (exact, so
//! the spline and its space are unchanged). Then every Bézier node of level L
//! whose closure neighbourhood consists only of level-L leaves becomes a new
//! level-L Bernstein basis function B_q, and all other functions are truncated
//! there: their coefficient at q is removed (THB truncation: the coefficient of
//! a coarser function on the finer function B_q is exactly its Bézier
//! coefficient at q). Consequences, checked by the tests:
//! * partition of unity: the coefficients at q summed to 1 and B_q takes 1;
//! * non-negativity: truncation only zeroes coefficients;
//! * continuity: B_q vanishes on every face that does not contain q and q only
//!   touches leaves of its own level, so all functions stay C0; the refined
//!   space contains the unrefined one (nestedness by construction);
//! * linear independence: the new functions own coefficients nobody else has.
//! The control point of B_q is the current Bézier point at q, so refinement
//! does not move the geometry. The same mechanism adds the optional boundary
//! enrichment at level 0.

use super::bernstein::{self, NB};
use super::fit::{self, FitOptions};
use super::nodes::{self, NodeKey, LMAX};
use super::{BasisKind, Element, SparseOp, Spline};
use crate::error::{Error, Result};
use crate::geometry::SurfaceLocator;
use crate::mesh::TriMesh;
use serde::{Deserialize, Serialize};
use std::collections::{HashMap, HashSet};

/// Settings of automatic refinement (`Spline::refine_auto`, `SplineOptions::refine`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RefineOptions {
    /// Refine-and-fit passes (default 2).
    pub passes: usize,
    /// Boundary elements farther than this from the surface, relative to the
    /// surface's bounding-box diagonal, are candidates (default 0.002).
    pub tolerance: f64,
    /// At most this fraction of the boundary elements is refined per pass, the
    /// farthest first (default 0.1).
    pub fraction: f64,
    /// Deepest level produced (default 3, at most 10).
    pub max_level: u8,
}

impl Default for RefineOptions {
    fn default() -> Self {
        RefineOptions { passes: 2, tolerance: 0.002, fraction: 0.1, max_level: 3 }
    }
}

/// What a refinement did.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct RefineReport {
    /// Elements split.
    pub refined: usize,
    pub elements_before: usize,
    pub elements_after: usize,
    pub basis_before: usize,
    pub basis_after: usize,
    /// Automatic passes undone because they left a non-positive Jacobian.
    pub reverted_passes: usize,
    /// Boundary distance before / after (automatic refinement only).
    pub distance_before: Option<fit::SurfaceDistance>,
    pub distance_after: Option<fit::SurfaceDistance>,
}

/// Leaves of each root element.
fn leaves_by_root(sp: &Spline) -> Vec<Vec<u32>> {
    let mut out = vec![Vec::new(); sp.topo.ne];
    for (i, el) in sp.elems.iter().enumerate() {
        out[el.root as usize].push(i as u32);
    }
    out
}

/// Make Bernstein functions of the candidate nodes (leaf, Bézier index) whose
/// neighbourhood is all of the candidate's level; truncate the others there.
fn include_nodes(sp: &mut Spline, candidates: &[(u32, usize)]) {
    let by_root = leaves_by_root(sp);
    let existing: HashSet<(u8, NodeKey)> = sp
        .kinds
        .iter()
        .filter_map(|k| match k {
            BasisKind::Bernstein { level, key } => Some((*level, *key)),
            _ => None,
        })
        .collect();
    let mut seen: HashSet<(u8, NodeKey)> = HashSet::new();
    // (level, key, [(leaf, local index)])
    let mut includes: Vec<(u8, NodeKey, Vec<(u32, usize)>)> = Vec::new();
    for &(leaf, n) in candidates {
        let el = &sp.elems[leaf as usize];
        let level = el.level;
        let key = nodes::key_of(&sp.topo, el.root, el.node_pos(n));
        if existing.contains(&(level, key)) || !seen.insert((level, key)) {
            continue;
        }
        let mut owners = Vec::new();
        let mut ok = true;
        'outer: for (root, pos) in nodes::locate(&sp.topo, key) {
            for &l in &by_root[root as usize] {
                let other = &sp.elems[l as usize];
                if !other.contains(pos) {
                    continue;
                }
                if other.level != level {
                    ok = false;
                    break 'outer;
                }
                match other.node_at(pos) {
                    Some(m) => owners.push((l, m)),
                    None => {
                        ok = false;
                        break 'outer;
                    }
                }
            }
        }
        if ok && !owners.is_empty() {
            includes.push((level, key, owners));
        }
    }
    if includes.is_empty() {
        return;
    }
    // dense copies of the touched leaves
    let mut dense: HashMap<u32, (Vec<u32>, Vec<f64>)> = HashMap::new();
    for (_, _, owners) in &includes {
        for &(l, _) in owners {
            dense.entry(l).or_insert_with(|| {
                let el = &sp.elems[l as usize];
                (el.basis.clone(), el.op.to_dense())
            });
        }
    }
    for (level, key, owners) in includes {
        // control point: the current Bézier point at the node
        let (l0, m0) = owners[0];
        let (ids, d) = &dense[&l0];
        let mut p = [0.0; 3];
        for (r, &b) in ids.iter().enumerate() {
            let c = d[r * NB + m0];
            if c != 0.0 {
                let q = sp.ctrl[b as usize];
                for i in 0..3 {
                    p[i] += c * q[i];
                }
            }
        }
        let fid = sp.ctrl.len() as u32;
        sp.ctrl.push(p);
        sp.kinds.push(BasisKind::Bernstein { level, key });
        for (l, m) in owners {
            let (ids, d) = dense.get_mut(&l).unwrap();
            let rows = ids.len();
            for r in 0..rows {
                d[r * NB + m] = 0.0;
            }
            ids.push(fid);
            let mut row = vec![0.0; NB];
            row[m] = 1.0;
            d.extend_from_slice(&row);
        }
    }
    for (l, (ids, d)) in dense {
        let keep: Vec<usize> = (0..ids.len()).filter(|&r| d[r * NB..(r + 1) * NB].iter().any(|&x| x != 0.0)).collect();
        let mut nd = Vec::with_capacity(keep.len() * NB);
        let mut nids = Vec::with_capacity(keep.len());
        for &r in &keep {
            nids.push(ids[r]);
            nd.extend_from_slice(&d[r * NB..(r + 1) * NB]);
        }
        let el = &mut sp.elems[l as usize];
        el.op = SparseOp::from_dense(&nd, nids.len());
        el.basis = nids;
    }
    sp.compact();
}

/// Root-parameter position (in [0,1]^3) of node n of a leaf.
fn root_param(el: &Element, n: usize) -> [f64; 3] {
    el.node_pos(n).map(|x| x as f64 / nodes::R as f64)
}

/// Trilinear map of a root (control-mesh) element.
fn trilinear(sp: &Spline, root: u32, p: [f64; 3]) -> [f64; 3] {
    let el = &sp.topo.elements[root as usize];
    let mut x = [0.0; 3];
    for (c, &v) in el.iter().enumerate() {
        let b = super::topology::BITS_OF_VTK[c];
        let mut w = 1.0;
        for d in 0..3 {
            w *= if b[d] == 1 { p[d] } else { 1.0 - p[d] };
        }
        let q = sp.root_nodes[v as usize];
        for i in 0..3 {
            x[i] += w * q[i];
        }
    }
    x
}

/// Replace non-positive-Jacobian leaves by the trilinear map of their root
/// element (see `SplineOptions::repair_jacobian`); returns the number of leaves
/// repaired. Stops after 50 rounds or when nothing changes.
pub(super) fn repair_jacobian(sp: &mut Spline) -> usize {
    let mut repaired: HashSet<usize> = HashSet::new();
    for _round in 0..50 {
        let bad: Vec<usize> = {
            use rayon::prelude::*;
            let sp_ref: &Spline = sp;
            (0..sp_ref.elems.len())
                .into_par_iter()
                .filter(|e| !repaired.contains(e) && super::check::element_strict(sp_ref, *e) <= 0.0)
                .collect()
        };
        if bad.is_empty() {
            break;
        }
        let cand: Vec<(u32, usize)> = bad.iter().flat_map(|&e| (0..NB).map(move |n| (e as u32, n))).collect();
        include_nodes(sp, &cand);
        // place the Bernstein functions of these nodes on the trilinear map
        let mut by_key: HashMap<(u8, NodeKey), usize> = HashMap::new();
        for (i, k) in sp.kinds.iter().enumerate() {
            if let BasisKind::Bernstein { level, key } = k {
                by_key.insert((*level, *key), i);
            }
        }
        for &e in &bad {
            let el = sp.elems[e].clone();
            for n in 0..NB {
                let key = nodes::key_of(&sp.topo, el.root, el.node_pos(n));
                if let Some(&f) = by_key.get(&(el.level, key)) {
                    sp.ctrl[f] = trilinear(sp, el.root, root_param(&el, n));
                }
            }
            repaired.insert(e);
        }
    }
    repaired.len()
}

/// Level-0 Bernstein enrichment of the two Bézier layers next to each boundary face.
pub(super) fn enrich_boundary(sp: &mut Spline) {
    let mut cand = Vec::new();
    for q in &sp.topo.bquads {
        let (e, d, s) = (q.elem, q.dim as usize, q.side as usize);
        for n in 0..NB {
            let ijk = bernstein::bijk(n);
            let near = if s == 0 { ijk[d] <= 1 } else { ijk[d] >= 2 };
            if near {
                cand.push((e, n));
            }
        }
    }
    include_nodes(sp, &cand);
}

/// Which Bézier nodes of the children become basis functions of the new level.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum NodeFilter {
    /// All includable nodes: the full tricubic C0 space on the refined region.
    All,
    /// Only nodes within the two Bézier layers next to a boundary face of the
    /// child: refines the boundary geometry (for fitting) at a fraction of the cost.
    BoundaryLayers,
}

/// Split the given leaves (no report update).
pub(super) fn refine_elements(sp: &mut Spline, ids: &[usize]) -> Result<usize> {
    refine_elements_with(sp, ids, NodeFilter::All)
}

pub(super) fn refine_elements_with(sp: &mut Spline, ids: &[usize], filter: NodeFilter) -> Result<usize> {
    let mut list: Vec<usize> = ids.to_vec();
    list.sort_unstable();
    list.dedup();
    for &e in &list {
        let el = sp.element(e)?;
        if el.level >= LMAX {
            return Err(Error::InvalidArgument(format!("element {e} is already at the deepest level {LMAX}")));
        }
    }
    let mut candidates = Vec::new();
    for &e in &list {
        let parent = sp.elems[e].clone();
        let dense = parent.op.to_dense();
        let rows = parent.basis.len();
        let mut child_slots = Vec::with_capacity(8);
        for c in 0..8usize {
            let cb = [c & 1, (c >> 1) & 1, (c >> 2) & 1];
            let mut cd = vec![0.0; rows * NB];
            for r in 0..rows {
                bernstein::subdivide(&dense[r * NB..(r + 1) * NB], cb, &mut cd[r * NB..(r + 1) * NB]);
            }
            // a non-zero polynomial cannot vanish on a child, but rounding can make tiny rows; keep all
            let child = Element {
                root: parent.root,
                level: parent.level + 1,
                origin: [0, 1, 2].map(|d| parent.origin[d] * 2 + cb[d] as u32),
                basis: parent.basis.clone(),
                op: SparseOp::from_dense(&cd, rows),
            };
            let slot = if c == 0 {
                sp.elems[e] = child;
                e
            } else {
                sp.elems.push(child);
                sp.elems.len() - 1
            };
            child_slots.push(slot);
        }
        for s in child_slots {
            match filter {
                NodeFilter::All => {
                    for n in 0..NB {
                        candidates.push((s as u32, n));
                    }
                }
                NodeFilter::BoundaryLayers => {
                    let el = &sp.elems[s];
                    let last = (1u32 << el.level) - 1;
                    for d in 0..3 {
                        for side in 0..2 {
                            let touches = if side == 0 { el.origin[d] == 0 } else { el.origin[d] == last };
                            let f = sp.topo.elem_faces[el.root as usize][d * 2 + side];
                            if !touches || sp.topo.face_bquad[f as usize] == u32::MAX {
                                continue;
                            }
                            for n in 0..NB {
                                let i = bernstein::bijk(n)[d];
                                if (side == 0 && i <= 1) || (side == 1 && i >= 2) {
                                    candidates.push((s as u32, n));
                                }
                            }
                        }
                    }
                }
            }
        }
    }
    // nodes of neighbouring leaves of the same level may become includable too
    // (they were on the border of the refined region before); they are nodes of
    // the new children as well, so the candidates above cover them.
    include_nodes(sp, &candidates);
    Ok(list.len())
}

/// Automatic refinement where the boundary is farthest from the surface.
pub(super) fn refine_auto_with(
    sp: &mut Spline,
    surf: &TriMesh,
    loc: &SurfaceLocator,
    ro: &RefineOptions,
    fo: &FitOptions,
) -> Result<RefineReport> {
    if !(ro.tolerance.is_finite() && ro.tolerance >= 0.0) || !(ro.fraction > 0.0 && ro.fraction <= 1.0) {
        return Err(Error::InvalidArgument(format!(
            "refinement tolerance must be >= 0 and fraction in (0, 1]; got {} and {}",
            ro.tolerance, ro.fraction
        )));
    }
    if ro.max_level > LMAX {
        return Err(Error::InvalidArgument(format!("max_level must be at most {LMAX}")));
    }
    let mut rep = RefineReport {
        elements_before: sp.num_elements(),
        basis_before: sp.num_basis(),
        distance_before: Some(fit::surface_distance(sp, loc, surf, fo.samples)),
        ..Default::default()
    };
    let diag = fit::diagonal(surf);
    for _ in 0..ro.passes {
        let per = fit::boundary_element_distances(sp, loc, fo.samples.max(2));
        let nb = per.len();
        let mut cand: Vec<(usize, f64)> = per
            .into_iter()
            .filter(|&(e, d)| d > ro.tolerance * diag && sp.elems[e].level < ro.max_level)
            .collect();
        if cand.is_empty() {
            break;
        }
        cand.sort_by(|a, b| b.1.total_cmp(&a.1));
        let k = ((nb as f64 * ro.fraction).ceil() as usize).max(1).min(cand.len());
        let ids: Vec<usize> = cand[..k].iter().map(|c| c.0).collect();
        let saved = sp.clone();
        let n = refine_elements_with(sp, &ids, NodeFilter::BoundaryLayers)?;
        if fo.enabled {
            fit::fit_boundary_with(sp, loc, surf, fo)?;
        }
        // the fit checks a lattice of points; if the finer Gauss points of the
        // refined elements still find a fold, undo this pass and stop
        if super::check::gauss_jacobians(sp, 3).negative_elements > 0 {
            *sp = saved;
            rep.reverted_passes += 1;
            break;
        }
        rep.refined += n;
    }
    rep.elements_after = sp.num_elements();
    rep.basis_after = sp.num_basis();
    rep.distance_after = Some(fit::surface_distance(sp, loc, surf, fo.samples));
    Ok(rep)
}

impl Spline {
    /// Refine the given elements (ids of the current leaves) by one level with
    /// truncated hierarchical refinement. Element e keeps its id for its first
    /// child (u, v, w all in the lower half); the other 7 children are appended.
    pub fn refine(&mut self, elements: &[usize]) -> Result<RefineReport> {
        let mut rep = RefineReport { elements_before: self.num_elements(), basis_before: self.num_basis(), ..Default::default() };
        rep.refined = refine_elements(self, elements)?;
        rep.elements_after = self.num_elements();
        rep.basis_after = self.num_basis();
        self.update_report();
        Ok(rep)
    }

    /// Refine boundary elements where the spline boundary is farthest from the
    /// surface, refitting after each pass (see `RefineOptions`).
    pub fn refine_auto(&mut self, surface: &TriMesh, ro: &RefineOptions, fo: &FitOptions) -> Result<RefineReport> {
        if surface.triangles.is_empty() {
            return Err(Error::InvalidArgument("the target surface has no triangles".into()));
        }
        let loc = SurfaceLocator::new(surface);
        let rep = refine_auto_with(self, surface, &loc, ro, fo)?;
        self.report.refined_elements += rep.refined;
        self.report.fitting_after = rep.distance_after.clone();
        self.update_report();
        Ok(rep)
    }
}
