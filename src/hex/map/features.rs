//! Parametric mapping of the polycube onto the input: a surface map from the
//! polycube boundary onto the input surface, then the interior by harmonic
//! interpolation.
//!
//! Surface map (docs/hex.md has the same in prose):
//! 1. Polycube features (edges and corners of the boundary, from the outward
//!    normals of the boundary quads) are matched to the input's sharp features
//!    in the normalised frame, where polycube and input share their bounding box:
//!    a polycube corner goes to the nearest input corner within half a sub-voxel
//!    (one-to-one, nearest pairs first); a polycube edge chain goes to the input
//!    feature curve that is close to it along its whole length and roughly parallel.
//! 2. Every boundary node gets a start position: the closest point on its matched
//!    curve / its corner, or the closest point on the input surface among triangles
//!    that face the same way as the polycube face (a seed from the diffusion
//!    correspondence, when given, is added first).
//! 3. Relaxation on the surface in the working frame: tangential Laplacian moves with
//!    reprojection (curve nodes along their curve, corners fixed); this spreads the
//!    nodes and undoes folds of the closest-point start.
//! 4. Interior: the discrete harmonic map (uniform edge weights) with the boundary
//!    fixed, solved by preconditioned conjugate gradients; inversions that remain are
//!    for the optimisation stage to untangle.

use super::grid::LatticeHex;
use super::surface::Surface;
use super::topology::{Csr, HEX_FACES};
use crate::geometry::vec3::*;
use rayon::prelude::*;
use std::collections::HashMap;

/// What constrains a node.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Role {
    Interior,
    /// On the input surface, free to slide on it.
    Free,
    /// On input feature curve `c`.
    Curve(u32),
    /// Fixed at input vertex `v` (a feature corner).
    Corner(u32),
}

impl Role {
    pub fn on_boundary(self) -> bool {
        !matches!(self, Role::Interior)
    }
}

/// Bitmask of outward axis directions (+X,-X,+Y,-Y,+Z,-Z -> bits 0..5) of the boundary
/// quads around each node of a lattice hex mesh (0 for interior nodes).
pub fn normal_masks(h: &LatticeHex) -> Vec<u8> {
    let mut mask = vec![0u8; h.mesh.nodes.len()];
    let faces = boundary_faces_lattice(h);
    for (q, dir) in faces {
        for v in q {
            mask[v as usize] |= 1 << dir;
        }
    }
    mask
}

/// Boundary quads of a lattice hex mesh with their outward axis direction code.
pub fn boundary_faces_lattice(h: &LatticeHex) -> Vec<([u32; 4], u8)> {
    // face f of an element at lattice cell c is on the boundary when the element
    // across it does not exist
    let mut occupied: HashMap<[u32; 3], ()> = HashMap::with_capacity(h.elem_lattice.len());
    for c in &h.elem_lattice {
        occupied.insert(*c, ());
    }
    // HEX_FACES order: -Z, +Z, -Y, +X, +Y, -X
    const DIRS: [(i64, i64, i64, u8); 6] = [(0, 0, -1, 5), (0, 0, 1, 4), (0, -1, 0, 3), (1, 0, 0, 0), (0, 1, 0, 2), (-1, 0, 0, 1)];
    let mut out = Vec::new();
    for (e, c) in h.elem_lattice.iter().enumerate() {
        for (f, d) in DIRS.iter().enumerate() {
            let n = [c[0] as i64 + d.0, c[1] as i64 + d.1, c[2] as i64 + d.2];
            let inside = n.iter().all(|&v| v >= 0) && occupied.contains_key(&[n[0] as u32, n[1] as u32, n[2] as u32]);
            if !inside {
                let el = h.mesh.elements[e];
                out.push((HEX_FACES[f].map(|i| el[i]), d.3));
            }
        }
    }
    out
}

fn dir_vec(d: u8) -> [f64; 3] {
    let mut v = [0.0; 3];
    v[(d / 2) as usize] = if d % 2 == 0 { 1.0 } else { -1.0 };
    v
}

/// Key of a polycube edge chain: the lattice coordinates of its two end nodes in
/// sub-voxel units times 2^20 (level independent), sorted.
pub type ChainKey = ([u64; 3], [u64; 3]);

const KEY_SCALE: u64 = 1 << 20;

fn level_free(h: &LatticeHex, l: [u32; 3]) -> [u64; 3] {
    let f = KEY_SCALE / h.subdiv as u64;
    l.map(|v| v as u64 * f)
}

/// The chain through an edge node (2 mask bits): walk along the edge direction while
/// the mask stays the same; returns the key and the chain's axis.
pub fn chain_of(h: &LatticeHex, masks: &[u8], node: usize) -> Option<(ChainKey, usize)> {
    let m = masks[node];
    if m.count_ones() != 2 {
        return None;
    }
    let axes: Vec<usize> = (0..6).filter(|b| m & (1 << b) != 0).map(|b| b / 2).collect();
    if axes[0] == axes[1] {
        return None;
    }
    let axis = 3 - axes[0] - axes[1];
    let start = h.node_lattice[node];
    let mut ends = [[0u64; 3]; 2];
    for (k, step) in [-1i64, 1].iter().enumerate() {
        let mut p = start;
        loop {
            let nv = p[axis] as i64 + step;
            if nv < 0 {
                break;
            }
            let mut q = p;
            q[axis] = nv as u32;
            match h.node_at(q.map(|v| v as usize)) {
                Some(id) if masks[id as usize] == m => p = q,
                Some(id) if masks[id as usize] != 0 => {
                    p = q;
                    break;
                }
                _ => break,
            }
        }
        ends[k] = level_free(h, p);
    }
    ends.sort();
    Some(((ends[0], ends[1]), axis))
}

/// Matching of polycube features to input features (computed once, on level 0).
#[derive(Debug, Clone, Default)]
pub struct FeatureMatch {
    /// Polycube corner (level-free lattice key) -> input corner vertex.
    pub corners: HashMap<[u64; 3], u32>,
    /// Polycube edge chain -> input feature curve.
    pub chains: HashMap<ChainKey, u32>,
}

/// Match polycube corners and edge chains of a lattice mesh `h0` (level >= 1, so that
/// every polycube edge has an inner node) (node positions
/// `pos_n` in the normalised frame) with the features of `sn` (normalised frame).
/// `radius` is the matching distance (normalised units).
pub fn match_features(h0: &LatticeHex, pos_n: &[[f64; 3]], sn: &Surface, radius: f64) -> FeatureMatch {
    let masks = normal_masks(h0);
    let mut fm = FeatureMatch::default();
    // corners
    let mut pairs: Vec<(f64, usize, u32)> = Vec::new();
    for (v, &m) in masks.iter().enumerate() {
        if m.count_ones() < 3 {
            continue;
        }
        for &c in &sn.features.corners {
            let d = norm(sub(pos_n[v], sn.mesh.vertices[c as usize]));
            if d <= radius {
                pairs.push((d, v, c));
            }
        }
    }
    pairs.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)).then(a.2.cmp(&b.2)));
    let mut used_v = std::collections::HashSet::new();
    let mut used_c = std::collections::HashSet::new();
    for (_, v, c) in pairs {
        if used_v.contains(&v) || used_c.contains(&c) {
            continue;
        }
        used_v.insert(v);
        used_c.insert(c);
        fm.corners.insert(level_free(h0, h0.node_lattice[v]), c);
    }
    // chains
    let mut seen: HashMap<ChainKey, usize> = HashMap::new();
    for v in 0..masks.len() {
        if let Some((key, axis)) = chain_of(h0, &masks, v) {
            seen.entry(key).or_insert(axis);
        }
    }
    // chain end positions in N: ends are lattice nodes of h0
    let to_node = |k: [u64; 3]| -> Option<u32> {
        let f = KEY_SCALE / h0.subdiv as u64;
        h0.node_at(k.map(|v| (v / f) as usize))
    };
    let ncurves = sn.features.curves.len();
    let mut keys: Vec<(ChainKey, usize)> = seen.into_iter().collect();
    keys.sort();
    for (key, axis) in keys {
        let (Some(a), Some(b)) = (to_node(key.0), to_node(key.1)) else { continue };
        let (pa, pb) = (pos_n[a as usize], pos_n[b as usize]);
        let dir = {
            let mut d = [0.0; 3];
            d[axis] = 1.0;
            d
        };
        let samples: Vec<[f64; 3]> = (0..=8).map(|i| add(pa, scale(sub(pb, pa), i as f64 / 8.0))).collect();
        let mut best: Option<(f64, u32)> = None;
        for c in 0..ncurves {
            let mut sum = 0.0;
            let mut maxd: f64 = 0.0;
            let mut cos = 0.0;
            for s in &samples {
                let cp = sn.closest_on_curve(c, *s);
                sum += cp.distance;
                maxd = maxd.max(cp.distance);
                cos += dot(sn.curve_tangent(c, cp.segment), dir).abs();
            }
            let mean = sum / samples.len() as f64;
            cos /= samples.len() as f64;
            if mean <= radius && maxd <= 2.0 * radius && cos >= 0.6 && best.is_none_or(|b| mean < b.0) {
                best = Some((mean, c as u32));
            }
        }
        if let Some((_, c)) = best {
            fm.chains.insert(key, c);
        }
    }
    fm
}

/// Roles of the nodes of a lattice hex mesh under a feature match, and for curve
/// nodes their neighbours along the curve.
pub fn roles(h: &LatticeHex, fm: &FeatureMatch) -> (Vec<Role>, Vec<Vec<u32>>) {
    let masks = normal_masks(h);
    let n = h.mesh.nodes.len();
    let mut role = vec![Role::Interior; n];
    let mut chain_axis: Vec<Option<(u32, usize)>> = vec![None; n];
    for v in 0..n {
        let m = masks[v];
        if m == 0 {
            continue;
        }
        role[v] = Role::Free;
        if m.count_ones() >= 3 {
            if let Some(&c) = fm.corners.get(&level_free(h, h.node_lattice[v])) {
                role[v] = Role::Corner(c);
            }
        } else if let Some((key, axis)) = chain_of(h, &masks, v) {
            if let Some(&c) = fm.chains.get(&key) {
                role[v] = Role::Curve(c);
                chain_axis[v] = Some((c, axis));
            }
        }
    }
    // unmatched polycube corners on a matched chain follow that chain's curve
    let mut curve_nb: Vec<Vec<u32>> = vec![Vec::new(); n];
    let nb_lattice = |v: usize| -> Vec<(u32, usize)> {
        let l = h.node_lattice[v];
        let mut out = Vec::new();
        for a in 0..3 {
            for s in [-1i64, 1] {
                let x = l[a] as i64 + s;
                if x < 0 {
                    continue;
                }
                let mut q = l.map(|v| v as usize);
                q[a] = x as usize;
                if let Some(id) = h.node_at(q) {
                    out.push((id, a));
                }
            }
        }
        out
    };
    for v in 0..n {
        if masks[v].count_ones() >= 3 && role[v] == Role::Free {
            let mut found = None;
            for (w, a) in nb_lattice(v) {
                if let Some((c, ax)) = chain_axis[w as usize] {
                    if ax == a {
                        found = Some(c);
                        break;
                    }
                }
            }
            if let Some(c) = found {
                role[v] = Role::Curve(c);
            }
        }
    }
    for v in 0..n {
        if let Role::Curve(c) = role[v] {
            for (w, a) in nb_lattice(v) {
                let along = match chain_axis[v] {
                    Some((_, ax)) => ax == a,
                    None => chain_axis[w as usize].is_some_and(|(_, ax)| ax == a),
                };
                if !along {
                    continue;
                }
                match role[w as usize] {
                    Role::Curve(cw) if cw == c => curve_nb[v].push(w),
                    Role::Corner(_) => curve_nb[v].push(w),
                    _ => {}
                }
            }
        }
    }
    (role, curve_nb)
}

/// Nearest-neighbour displacement field from the diffusion correspondence
/// (polycube point -> input point, normalised frame), on a bucket grid.
#[derive(Debug, Clone)]
pub struct Correspondence {
    src: Vec<[f64; 3]>,
    disp: Vec<[f64; 3]>,
    lo: [f64; 3],
    cell: f64,
    dims: [usize; 3],
    buckets: Vec<Vec<u32>>,
}

impl Correspondence {
    /// None when there are no usable pairs (non-finite pairs are dropped).
    pub fn new(pairs: &[([f64; 3], [f64; 3])]) -> Option<Correspondence> {
        let good: Vec<&([f64; 3], [f64; 3])> =
            pairs.iter().filter(|(a, b)| a.iter().chain(b.iter()).all(|v| v.is_finite())).collect();
        if good.len() < 8 {
            return None;
        }
        let src: Vec<[f64; 3]> = good.iter().map(|p| p.0).collect();
        let disp: Vec<[f64; 3]> = good.iter().map(|p| sub(p.1, p.0)).collect();
        let bb = crate::geometry::Aabb::of_points(&src);
        let size = bb.size();
        let vol = (size[0].max(1e-9)) * (size[1].max(1e-9)) * (size[2].max(1e-9));
        let cell = (vol / (src.len() as f64 / 4.0)).cbrt().max(1e-6);
        let dims = size.map(|s| ((s / cell).floor() as usize + 1).min(256));
        let mut buckets = vec![Vec::new(); dims[0] * dims[1] * dims[2]];
        let lo = bb.min;
        for (i, p) in src.iter().enumerate() {
            let c: [usize; 3] = std::array::from_fn(|a| (((p[a] - lo[a]) / cell).floor().max(0.0) as usize).min(dims[a] - 1));
            buckets[c[0] + dims[0] * (c[1] + dims[1] * c[2])].push(i as u32);
        }
        Some(Correspondence { src, disp, lo, cell, dims, buckets })
    }

    /// Inverse-distance weighted displacement of the k nearest pairs.
    pub fn displacement(&self, p: [f64; 3], k: usize) -> [f64; 3] {
        let c: [i64; 3] = std::array::from_fn(|a| ((p[a] - self.lo[a]) / self.cell).floor() as i64);
        let mut found: Vec<(f64, u32)> = Vec::new();
        let mut r = 0i64;
        loop {
            for z in c[2] - r..=c[2] + r {
                for y in c[1] - r..=c[1] + r {
                    for x in c[0] - r..=c[0] + r {
                        let on_shell = (x - c[0]).abs() == r || (y - c[1]).abs() == r || (z - c[2]).abs() == r;
                        if !on_shell {
                            continue;
                        }
                        if x < 0 || y < 0 || z < 0 {
                            continue;
                        }
                        let (xu, yu, zu) = (x as usize, y as usize, z as usize);
                        if xu >= self.dims[0] || yu >= self.dims[1] || zu >= self.dims[2] {
                            continue;
                        }
                        for &i in &self.buckets[xu + self.dims[0] * (yu + self.dims[1] * zu)] {
                            found.push((dist2(p, self.src[i as usize]), i));
                        }
                    }
                }
            }
            // every point within distance r * cell has been seen
            let reach = (r as f64) * self.cell;
            found.sort_by(|a, b| a.0.total_cmp(&b.0));
            if found.len() >= k && found[k - 1].0.sqrt() <= reach {
                break;
            }
            if r as usize > self.dims.iter().copied().max().unwrap_or(1) + 2 {
                break;
            }
            r += 1;
        }
        found.truncate(k);
        let mut w_sum = 0.0;
        let mut acc = [0.0; 3];
        for (d2, i) in found {
            let w = 1.0 / (d2 + 1e-12);
            w_sum += w;
            acc = add(acc, scale(self.disp[i as usize], w));
        }
        if w_sum > 0.0 {
            scale(acc, 1.0 / w_sum)
        } else {
            [0.0; 3]
        }
    }
}

/// Surface attachment of a boundary node: its triangle on the surface.
pub type Attach = u32;

/// Area-weighted normals of the boundary quads at each node (zero for interior nodes).
pub fn quad_normals(n: usize, quads: &[[u32; 4]], pos: &[[f64; 3]]) -> Vec<[f64; 3]> {
    let mut nn = vec![[0.0; 3]; n];
    for q in quads {
        let p = q.map(|i| pos[i as usize]);
        let nq = cross(sub(p[2], p[0]), sub(p[3], p[1]));
        for &v in q {
            nn[v as usize] = add(nn[v as usize], nq);
        }
    }
    for v in nn.iter_mut() {
        let l = norm(*v);
        if l > 0.0 {
            *v = scale(*v, 1.0 / l);
        }
    }
    nn
}

/// Start positions of the boundary nodes in the normalised frame, returned in the
/// working frame together with the triangle each lies on (u32::MAX for curve/corner nodes).
pub fn initial_boundary(
    pos_n: &[[f64; 3]],
    role: &[Role],
    masks: &[u8],
    sn: &Surface,
    sw: &Surface,
    corr: Option<&Correspondence>,
    to_w: &super::frame::Affine,
) -> (Vec<[f64; 3]>, Vec<Attach>) {
    let res: Vec<([f64; 3], Attach)> = (0..pos_n.len())
        .into_par_iter()
        .map(|v| {
            let mut u = pos_n[v];
            if let Some(c) = corr {
                if role[v] != Role::Interior {
                    u = add(u, c.displacement(u, 8));
                }
            }
            match role[v] {
                Role::Interior => (to_w.apply(pos_n[v]), u32::MAX),
                Role::Corner(c) => (sw.mesh.vertices[c as usize], u32::MAX),
                Role::Curve(c) => {
                    let cp = sn.closest_on_curve(c as usize, u);
                    (sw.curve_eval(c as usize, cp.segment, cp.t), u32::MAX)
                }
                Role::Free => {
                    let mut nrm = [0.0; 3];
                    for b in 0..6 {
                        if masks[v] & (1 << b) != 0 {
                            nrm = add(nrm, dir_vec(b));
                        }
                    }
                    let l = norm(nrm);
                    let (q, t, _) = if l > 0.0 { sn.closest_facing(u, scale(nrm, 1.0 / l), 0.0) } else { sn.closest(u) };
                    (to_w.apply(q), t)
                }
            }
        })
        .collect();
    res.into_iter().unzip()
}

/// Boundary adjacency (edges of boundary quads).
pub fn boundary_graph(n: usize, quads: &[[u32; 4]]) -> Csr {
    let mut pairs: Vec<(u32, u32)> = Vec::with_capacity(quads.len() * 8);
    for q in quads {
        for k in 0..4 {
            let (a, b) = (q[k], q[(k + 1) % 4]);
            pairs.push((a, b));
            pairs.push((b, a));
        }
    }
    pairs.sort_unstable();
    pairs.dedup();
    Csr::from_pairs(n, pairs.into_iter())
}

/// Move a boundary node from `x` (on triangle `tri`) by the tangential part of `d`,
/// then back onto the surface / its curve. Returns the new position and triangle.
pub fn slide(sw: &Surface, role: Role, x: [f64; 3], tri: Attach, d: [f64; 3]) -> ([f64; 3], Attach) {
    match role {
        Role::Interior => (add(x, d), tri),
        Role::Corner(_) => (x, tri),
        Role::Curve(c) => {
            let cp = sw.closest_on_curve(c as usize, add(x, d));
            (cp.point, u32::MAX)
        }
        Role::Free => {
            let n = if tri != u32::MAX { sw.normal(tri) } else { sw.normal(sw.closest(x).1) };
            let dt = sub(d, scale(n, dot(d, n)));
            let (q, t, _) = sw.closest_facing(add(x, dt), n, 0.0);
            (q, t)
        }
    }
}

/// Tangential Laplacian relaxation of the boundary nodes on the surface (Jacobi
/// iterations with damping `lambda`).
pub fn relax_boundary(
    sw: &Surface,
    role: &[Role],
    curve_nb: &[Vec<u32>],
    bgraph: &Csr,
    pos: &mut [[f64; 3]],
    attach: &mut [Attach],
    iterations: usize,
    lambda: f64,
) {
    let nodes: Vec<usize> = (0..pos.len()).filter(|&v| matches!(role[v], Role::Free | Role::Curve(_))).collect();
    for _ in 0..iterations {
        let upd: Vec<([f64; 3], Attach)> = nodes
            .par_iter()
            .map(|&v| {
                let nb: &[u32] = match role[v] {
                    Role::Curve(_) => &curve_nb[v],
                    _ => bgraph.of(v),
                };
                if nb.is_empty() {
                    return (pos[v], attach[v]);
                }
                let avg = scale(nb.iter().fold([0.0; 3], |a, &w| add(a, pos[w as usize])), 1.0 / nb.len() as f64);
                slide(sw, role[v], pos[v], attach[v], scale(sub(avg, pos[v]), lambda))
            })
            .collect();
        for (k, &v) in nodes.iter().enumerate() {
            pos[v] = upd[k].0;
            attach[v] = upd[k].1;
        }
    }
}

/// Discrete harmonic interior (uniform edge weights) with the boundary nodes fixed:
/// preconditioned conjugate gradients from the current positions. Returns the
/// iteration count.
pub fn harmonic_interior(nbr: &Csr, role: &[Role], pos: &mut [[f64; 3]], tol: f64, max_iter: usize) -> usize {
    let n = pos.len();
    let inner: Vec<usize> = (0..n).filter(|&v| role[v] == Role::Interior).collect();
    if inner.is_empty() {
        return 0;
    }
    let mut slot = vec![u32::MAX; n];
    for (k, &v) in inner.iter().enumerate() {
        slot[v] = k as u32;
    }
    let m = inner.len();
    let deg: Vec<f64> = inner.iter().map(|&v| nbr.of(v).len() as f64).collect();
    // rhs = sum of boundary neighbours
    let mut iters = 0;
    for axis in 0..3 {
        let b: Vec<f64> = inner
            .par_iter()
            .map(|&v| nbr.of(v).iter().filter(|&&w| slot[w as usize] == u32::MAX).map(|&w| pos[w as usize][axis]).sum())
            .collect();
        let apply = |x: &[f64], y: &mut [f64]| {
            y.par_iter_mut().enumerate().for_each(|(k, yk)| {
                let v = inner[k];
                let mut s = deg[k] * x[k];
                for &w in nbr.of(v) {
                    let j = slot[w as usize];
                    if j != u32::MAX {
                        s -= x[j as usize];
                    }
                }
                *yk = s;
            });
        };
        let mut x: Vec<f64> = inner.iter().map(|&v| pos[v][axis]).collect();
        let mut r = vec![0.0; m];
        apply(&x, &mut r);
        for k in 0..m {
            r[k] = b[k] - r[k];
        }
        let bnorm = b.iter().map(|v| v * v).sum::<f64>().sqrt().max(1e-300);
        let mut z: Vec<f64> = (0..m).map(|k| r[k] / deg[k]).collect();
        let mut p = z.clone();
        let mut rz: f64 = r.iter().zip(&z).map(|(a, b)| a * b).sum();
        let mut ap = vec![0.0; m];
        let mut it = 0;
        while it < max_iter {
            let rn = r.iter().map(|v| v * v).sum::<f64>().sqrt();
            if rn <= tol * bnorm {
                break;
            }
            apply(&p, &mut ap);
            let pap: f64 = p.iter().zip(&ap).map(|(a, b)| a * b).sum();
            if !(pap > 0.0) {
                break;
            }
            let alpha = rz / pap;
            for k in 0..m {
                x[k] += alpha * p[k];
                r[k] -= alpha * ap[k];
            }
            for k in 0..m {
                z[k] = r[k] / deg[k];
            }
            let rz2: f64 = r.iter().zip(&z).map(|(a, b)| a * b).sum();
            let beta = rz2 / rz;
            rz = rz2;
            for k in 0..m {
                p[k] = z[k] + beta * p[k];
            }
            it += 1;
        }
        iters = iters.max(it);
        for (k, &v) in inner.iter().enumerate() {
            pos[v][axis] = x[k];
        }
    }
    iters
}

/// A per-axis piecewise-linear map from grid units to the normalised frame through the
/// sub-voxel planes (grid coordinate k / 3): the polycube's start embedding. The
/// uniform warp is the context frame itself; [`fit_warp`] moves the inner planes
/// towards the input so that, e.g., a through-hole of the polycube starts where the
/// input's hole is.
#[derive(Debug, Clone, PartialEq)]
pub struct Warp {
    /// planes[a][k]: normalised coordinate of grid coordinate k / 3 along axis a.
    pub planes: [Vec<f64>; 3],
}

impl Warp {
    pub fn uniform(frame: &crate::polycube::tensor::BoxFrame) -> Warp {
        let lat = crate::polycube::primitive::LATTICE;
        Warp {
            planes: std::array::from_fn(|a| {
                (0..=lat[a]).map(|k| (k as f64 / 3.0 - frame.centre[a]) * frame.scale).collect()
            }),
        }
    }

    /// Grid units -> normalised frame.
    pub fn apply(&self, g: [f64; 3]) -> [f64; 3] {
        std::array::from_fn(|a| {
            let p = &self.planes[a];
            let s = g[a] * 3.0;
            let k = (s.floor().max(0.0) as usize).min(p.len() - 2);
            let f = s - k as f64;
            p[k] + f * (p[k + 1] - p[k])
        })
    }

    /// Normalised extent along each axis of the element at lattice cell `c` of a
    /// lattice with `subdiv` elements per sub-voxel.
    pub fn element_extent(&self, c: [u32; 3], subdiv: usize) -> [f64; 3] {
        std::array::from_fn(|a| {
            let k = (c[a] as usize / subdiv).min(self.planes[a].len() - 2);
            (self.planes[a][k + 1] - self.planes[a][k]) / subdiv as f64
        })
    }
}

/// What [`fit_warp`] measured per axis: the planes moved and by how much at most
/// (normalised units).
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize)]
pub struct WarpReport {
    pub planes_fitted: usize,
    pub max_shift: f64,
}

/// Fit the inner sub-voxel planes of the occupied box to the input: for every level-0
/// boundary quad lying on a plane, the line through its centre along the plane's
/// normal meets the input surface; the nearest crossing whose triangle faces the same
/// way gives that quad's wish, the plane moves to the median wish. Planes without
/// boundary quads are interpolated; the box planes stay; the order is kept with a gap
/// of at least a quarter of the uniform spacing.
pub fn fit_warp(h0: &LatticeHex, frame: &crate::polycube::tensor::BoxFrame, box_cells: ([usize; 3], [usize; 3]), sn: &Surface) -> (Warp, WarpReport) {
    let uni = Warp::uniform(frame);
    let mut wishes: [Vec<Vec<f64>>; 3] = std::array::from_fn(|a| vec![Vec::new(); uni.planes[a].len()]);
    for (q, dir) in boundary_faces_lattice(h0) {
        let axis = (dir / 2) as usize;
        let sign = if dir % 2 == 0 { 1.0 } else { -1.0 };
        let k = h0.node_lattice[q[0] as usize][axis] as usize;
        let c = scale(q.iter().fold([0.0; 3], |acc, &v| add(acc, uni.apply(h0.mesh.nodes[v as usize]))), 0.25);
        let hits = sn.axis_line_hits(c, axis, 4.0);
        let best = hits
            .into_iter()
            .filter(|(_, t)| sn.normal(*t)[axis] * sign > 0.3)
            .min_by(|a, b| a.0.abs().total_cmp(&b.0.abs()));
        if let Some((t, _)) = best {
            wishes[axis][k].push(c[axis] + t);
        }
    }
    let mut rep = WarpReport::default();
    let mut planes = uni.planes.clone();
    for a in 0..3 {
        let (k_lo, k_hi) = (3 * box_cells.0[a], 3 * box_cells.1[a]);
        let def = &uni.planes[a];
        let mut fixed = vec![false; def.len()];
        fixed[k_lo] = true;
        fixed[k_hi] = true;
        for k in k_lo + 1..k_hi {
            let w = &mut wishes[a][k];
            if w.is_empty() {
                continue;
            }
            w.sort_by(|x, y| x.total_cmp(y));
            planes[a][k] = w[w.len() / 2];
            fixed[k] = true;
            rep.planes_fitted += 1;
        }
        // interpolate the free planes between fixed ones
        let mut k = k_lo;
        while k < k_hi {
            let mut k1 = k + 1;
            while !fixed[k1] {
                k1 += 1;
            }
            for j in k + 1..k1 {
                let f = (def[j] - def[k]) / (def[k1] - def[k]);
                planes[a][j] = planes[a][k] + f * (planes[a][k1] - planes[a][k]);
            }
            k = k1;
        }
        // keep the order with a minimum gap
        let gap = 0.25 * (def[1] - def[0]);
        for k in k_lo + 1..k_hi {
            planes[a][k] = planes[a][k].max(planes[a][k - 1] + gap);
        }
        for k in (k_lo + 1..k_hi).rev() {
            planes[a][k] = planes[a][k].min(planes[a][k + 1] - gap);
        }
        for k in k_lo..=k_hi {
            rep.max_shift = rep.max_shift.max((planes[a][k] - def[k]).abs());
        }
    }
    (Warp { planes }, rep)
}
