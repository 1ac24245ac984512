//! Polycube features matched to the input's sharp features (steps 1 and 2 of the
//! surface map, [`super`]): polycube corners and edge chains of a lattice mesh,
//! from the outward normals of its boundary quads, and the roles they give the
//! nodes of every level.

use crate::hex::grid::{normal_masks, LatticeHex};
use crate::hex::surface::Surface;
use crate::hex::work::Role;
use crate::geometry::vec3::*;
use crate::geometry::{StableHashMap, StableHashSet};

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
    pub corners: StableHashMap<[u64; 3], u32>,
    /// Polycube edge chain -> input feature curve.
    pub chains: StableHashMap<ChainKey, u32>,
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
    let mut used_v = StableHashSet::default();
    let mut used_c = StableHashSet::default();
    for (_, v, c) in pairs {
        if used_v.contains(&v) || used_c.contains(&c) {
            continue;
        }
        used_v.insert(v);
        used_c.insert(c);
        fm.corners.insert(level_free(h0, h0.node_lattice[v]), c);
    }
    // chains
    let mut seen: StableHashMap<ChainKey, usize> = StableHashMap::default();
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

/// Matching of polycube corners and edge chains to the input's feature corners
/// and curves from a lattice mesh `h` (level >= 1) already placed on the surface
/// `sw` (`pos`, e.g. by the inverse chart maps, which put the polycube's corners
/// on input vertices and its edges on chart boundaries): a corner placed on a
/// feature corner is matched to it, a chain whose inner nodes all lie on one
/// feature curve to that curve; `eps` is the distance that counts as on it.
pub fn match_placed_features(h: &LatticeHex, pos: &[[f64; 3]], sw: &Surface, eps: f64) -> FeatureMatch {
    let masks = normal_masks(h);
    let mut fm = FeatureMatch::default();
    let mut chains: StableHashMap<ChainKey, Vec<usize>> = StableHashMap::default();
    for (v, &m) in masks.iter().enumerate() {
        if m.count_ones() >= 3 {
            let on = sw.features.corners.iter().find(|&&c| norm(sub(pos[v], sw.mesh.vertices[c as usize])) <= eps);
            if let Some(&c) = on {
                fm.corners.insert(level_free(h, h.node_lattice[v]), c);
            }
        } else if let Some((key, _)) = chain_of(h, &masks, v) {
            chains.entry(key).or_default().push(v);
        }
    }
    for (key, nodes) in chains {
        let on_curve = (0..sw.features.curves.len()).find(|&c| nodes.iter().all(|&v| sw.closest_on_curve(c, pos[v]).distance <= eps));
        if let Some(c) = on_curve {
            fm.chains.insert(key, c as u32);
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
