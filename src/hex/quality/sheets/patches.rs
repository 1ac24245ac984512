//! The input's patches (its triangles split by the sharp curves), the narrow
//! ones merged into a neighbour, the feature corners still held after the
//! merge, and the curves between each pair of patches.

use crate::geometry::vec3::*;
use crate::geometry::UnionFind;
use crate::hex::surface::Surface;
use std::collections::HashMap;

/// The patch of every input triangle after the merge of the narrow ones.
pub(super) struct Patches {
    pub tri_patch: Vec<u32>,
    pub count: usize,
    /// Patches merged into a neighbour.
    pub merged: usize,
    /// Per feature corner: whether a node may still be held there (all when no
    /// patch was merged, else those the merge left between as many patches as
    /// before, or between three or more).
    pub corner_held_ok: Vec<bool>,
}

/// The patches of `sw`, those narrower than `narrow_width` merged ([`merge_narrow_patches`]; 0: none).
pub(super) fn patches(sw: &Surface, edge_tris: &HashMap<(u32, u32), Vec<u32>>, narrow_width: f64) -> Patches {
    let (tri_patch0, np0) = triangle_patches(sw);
    let merge = (narrow_width > 0.0).then(|| merge_narrow_patches(sw, edge_tris, &tri_patch0, np0, narrow_width)).filter(|m| m.2 > 0);
    // the feature corners still held: all when no patch was merged, else those
    // the merge left between as many patches as before, or between three or more
    let corner_held_ok: Vec<bool> = match &merge {
        None => vec![true; sw.features.corners.len()],
        Some((tri_patch, _, _)) => {
            let index: HashMap<u32, usize> = sw.features.corners.iter().enumerate().map(|(i, &k)| (k, i)).collect();
            let mut around: Vec<(Vec<u32>, Vec<u32>)> = vec![(Vec::new(), Vec::new()); index.len()];
            for (t, tri) in sw.mesh.triangles.iter().enumerate() {
                for x in tri {
                    if let Some(&i) = index.get(x) {
                        let (before, after) = &mut around[i];
                        if !before.contains(&tri_patch0[t]) {
                            before.push(tri_patch0[t]);
                        }
                        if !after.contains(&tri_patch[t]) {
                            after.push(tri_patch[t]);
                        }
                    }
                }
            }
            sw.features.corners.iter().map(|k| {
                let (before, after) = &around[index[k]];
                after.len() >= 3 || after.len() == before.len()
            }).collect()
        }
    };
    let (tri_patch, count, merged) = merge.unwrap_or((tri_patch0, np0, 0));
    Patches { tri_patch, count, merged, corner_held_ok }
}

/// The feature curves by the pair of patches on their two sides.
pub(super) fn pair_curves(sw: &Surface, edge_tris: &HashMap<(u32, u32), Vec<u32>>, tri_patch: &[u32]) -> HashMap<(u32, u32), Vec<usize>> {
    let mut pair_curves: HashMap<(u32, u32), Vec<usize>> = HashMap::new();
    for (c, cv) in sw.features.curves.iter().enumerate() {
        let mut pairs = std::collections::BTreeSet::new();
        let k = cv.vertices.len();
        let segs = if cv.closed { k } else { k.saturating_sub(1) };
        for s in 0..segs {
            let (a, b) = (cv.vertices[s], cv.vertices[(s + 1) % k]);
            if let Some(ts) = edge_tris.get(&(a.min(b), a.max(b))) {
                if let [t0, t1] = ts[..] {
                    let (p0, p1) = (tri_patch[t0 as usize], tri_patch[t1 as usize]);
                    if p0 != p1 {
                        pairs.insert((p0.min(p1), p0.max(p1)));
                    }
                }
            }
        }
        for pr in pairs {
            pair_curves.entry(pr).or_default().push(c);
        }
    }
    pair_curves
}

/// The patch of every input triangle: connected components across the edges that
/// are on no feature curve.
pub fn triangle_patches(sw: &Surface) -> (Vec<u32>, usize) {
    let m = &sw.mesh;
    let mut sharp = std::collections::HashSet::new();
    for c in &sw.features.curves {
        let k = c.vertices.len();
        let segs = if c.closed { k } else { k.saturating_sub(1) };
        for s in 0..segs {
            let (a, b) = (c.vertices[s], c.vertices[(s + 1) % k]);
            sharp.insert((a.min(b), a.max(b)));
        }
    }
    let mut edge_tri: HashMap<(u32, u32), u32> = HashMap::with_capacity(m.triangles.len() * 2);
    let mut uf = UnionFind::new(m.triangles.len());
    for (t, tri) in m.triangles.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (tri[k], tri[(k + 1) % 3]);
            let key = (a.min(b), a.max(b));
            if sharp.contains(&key) {
                continue;
            }
            if let Some(&u) = edge_tri.get(&key) {
                uf.union(u, t as u32);
            } else {
                edge_tri.insert(key, t as u32);
            }
        }
    }
    uf.labels()
}

/// Merge every patch narrower than `width` (twice its area over its perimeter:
/// a strip's width, a disc's radius) into the neighbour it shares the most
/// boundary with, weighted by how alike their normals are (a chamfer or a ledge
/// narrower than the lattice gets no label region of its own, whose two sheets
/// would meet). Narrowest first; a narrow patch prefers a neighbour that is not.
/// Returns the merged patch of every triangle, the patch count and how many were
/// merged.
/// `edge_tris`: the triangles on each edge of the surface (surface::edge_triangles).
pub fn merge_narrow_patches(sw: &Surface, edge_tris: &HashMap<(u32, u32), Vec<u32>>, tri_patch: &[u32], np: usize, width: f64) -> (Vec<u32>, usize, usize) {
    let m = &sw.mesh;
    let mut area = vec![0.0; np];
    let mut normal = vec![[0.0; 3]; np];
    for (t, tri) in m.triangles.iter().enumerate() {
        let p = tri.map(|i| m.vertices[i as usize]);
        let n = cross(sub(p[1], p[0]), sub(p[2], p[0]));
        let pi = tri_patch[t] as usize;
        area[pi] += 0.5 * norm(n);
        normal[pi] = add(normal[pi], n);
    }
    let mut perim = vec![0.0; np];
    let mut shared: HashMap<(u32, u32), f64> = HashMap::new();
    for (&(a, b), ts) in edge_tris {
        if let [t0, t1] = ts[..] {
            let (p, q) = (tri_patch[t0 as usize], tri_patch[t1 as usize]);
            if p != q {
                let l = norm(sub(m.vertices[a as usize], m.vertices[b as usize]));
                perim[p as usize] += l;
                perim[q as usize] += l;
                *shared.entry((p.min(q), p.max(q))).or_default() += l;
            }
        }
    }
    let wid: Vec<f64> = (0..np).map(|p| if perim[p] > 0.0 { 2.0 * area[p] / perim[p] } else { f64::INFINITY }).collect();
    let narrow: Vec<bool> = wid.iter().map(|&x| x < width).collect();
    let mut order: Vec<usize> = (0..np).filter(|&p| narrow[p]).collect();
    order.sort_by(|&a, &b| wid[a].total_cmp(&wid[b]));
    let mut uf = UnionFind::new(np);
    let unit = |v: [f64; 3]| {
        let l = norm(v);
        if l > 0.0 { scale(v, 1.0 / l) } else { v }
    };
    let mut merged = 0;
    for &p in &order {
        let mut best: Option<(bool, f64, usize)> = None;
        for (&(a, b), &l) in &shared {
            let q = if a as usize == p { b as usize } else if b as usize == p { a as usize } else { continue };
            let score = l * (1.0 + dot(unit(normal[p]), unit(normal[q])));
            let key = (!narrow[q], score, q);
            if best.is_none_or(|b| (key.0, key.1) > (b.0, b.1)) {
                best = Some(key);
            }
        }
        if let Some((_, _, q)) = best {
            if uf.union(p as u32, q as u32) {
                merged += 1;
            }
        }
    }
    let (label, n) = uf.labels();
    (tri_patch.iter().map(|&p| label[p as usize]).collect(), n, merged)
}
