//! Feature sheets: one sheet of hexahedra inserted under each surface patch of a
//! pillowed lattice mesh, so that its boundary can follow the input's sharp curves
//! where they run diagonally across the lattice.
//!
//! The boundary quads of a lattice mesh meet a sharp curve along a staircase path:
//! seen on one face of the curve, a quad at a convex step has two consecutive path
//! edges, and with its three path nodes on a straight curve it is flat (the
//! capture steps therefore leave such nodes off the curve, and the mesh rounds the
//! edge). Labelling every boundary quad with the input patch it lies on (patches:
//! the input's triangles split by its sharp curves) and inserting, under each
//! patch's quads, a sheet of hexahedra (the pillowing of that patch's layer
//! elements against the rest of the mesh) gives every node on the path between
//! two labels exactly one edge into each patch, like a pillow layer does for every
//! boundary node; the path's nodes then go onto the curve between the two patches
//! (or onto the feature corner where three labels meet) and are held there, and
//! the elements along the curve share its dihedral angle two by two.
//!
//! The node copies of a sheet are made per face-connected group of the patch's
//! elements around the node, so that patches touching only along an edge or at a
//! node still give a conforming mesh; the result is checked (every face on one or
//! two elements) and the step is undone when it is not.

use super::map::Role;
use super::optimize::Work;
use super::surface::Surface;
use super::topology::{boundary_quads, hex_volume, HEX_FACES};
use crate::error::{Error, Result};
use crate::geometry::vec3::*;
use crate::geometry::UnionFind;
use std::collections::HashMap;

/// The sheets go under the quads within this many rings of a path (one ring:
/// hexgen_rod at 28 voxels 1,927 elements at 0.68 %; the whole patch: 2,495 at
/// 0.67 %; BENCHMARKS.md "Feature sheets").
const SHEET_BAND: usize = 1;

/// Laplacian passes that give the sheets a thickness before the smoothing, over
/// the new nodes and the old ones within SETTLE_RING edges of a path (hexgen_hepta
/// at 12 voxels: 8 elements inverted after the smoothing with the new nodes only,
/// 1 with the first ring).
const SETTLE_ITERATIONS: usize = 10;
const SETTLE_RING: usize = 1;

/// What the feature sheets did.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize)]
pub struct SheetReport {
    /// Input patches (triangles split by the sharp curves).
    pub patches: usize,
    /// Boundary quads whose label the clean-up changed (isolated quads and islands).
    pub labels_changed: usize,
    /// Patches that got a sheet (those whose quads border another label).
    pub sheets: usize,
    /// Boundary nodes where labels meet (the paths), and those put on a feature
    /// curve / a feature corner; the rest stay free on the surface (a path between
    /// two patches no sharp curve separates, or too far from it).
    pub path_nodes: usize,
    pub curve_nodes: usize,
    pub corner_nodes: usize,
    pub nodes_added: usize,
    pub elements_added: usize,
    /// The nodes held at feature corners: (node, index of the corner in the
    /// surface's feature corners); node numbers of the mesh this stage returns,
    /// which the later stages keep.
    pub corners_held: Vec<[u32; 2]>,
    /// Feature corners the caller asked not to hold a node at.
    pub corners_released: usize,
    /// Corners where a face narrower than the option's angle kept the lattice's
    /// quads out of its sheet.
    pub narrow_corners: usize,
    /// Input patches narrower than the lattice merged into a neighbour.
    pub narrow_patches_merged: usize,
    /// New elements with a negative signed volume right after the insertion (zero
    /// thickness counts as neither): the smoothing that follows untangles them.
    pub negative_volume: usize,
}

/// The path node nearest `x` within `reach` with at least `min_labels` labels
/// that `keep` accepts (the first of equally near ones).
fn nearest_path_node(path: &[u32], node_labels: &[Vec<u32>], nodes: &[[f64; 3]], x: [f64; 3], reach: f64, min_labels: usize, keep: impl Fn(u32) -> bool) -> Option<u32> {
    path.iter()
        .copied()
        .filter(|&v| node_labels[v as usize].len() >= min_labels && keep(v))
        .map(|v| (v, norm(sub(nodes[v as usize], x))))
        .filter(|&(_, d)| d <= reach)
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(v, _)| v)
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

/// Insert the feature sheets into a pillowed mesh (every boundary quad on its own
/// element) whose boundary nodes lie on the surface, and put the nodes of the
/// paths between patch labels onto the curves between them. `reach`: how far (in
/// the working frame) a path node may be from its curve or corner to be put on it.
/// No node is held at the feature corners listed in `released` (indices into
/// `sw.features.corners`; the nodes there go onto one of the corner's curves).
/// A face whose angle at a held corner is below `narrow_deg` degrees keeps the
/// lattice's quads there, out of its sheet (0: none). A patch narrower than
/// `narrow_width` (a length in the working frame) is merged into a neighbour
/// first ([`merge_narrow_patches`]; 0: none).
/// Leaves `w` unchanged and returns an error when the mesh is not pillowed or
/// the result would not be conforming.
pub fn feature_sheets(w: &mut Work, sw: &Surface, reach: f64, released: &[u32], narrow_deg: f64, narrow_width: f64) -> Result<SheetReport> {
    let mut rep = SheetReport::default();
    let edge_tris = super::surface::edge_triangles(&sw.mesh);
    let (tri_patch0, np0) = triangle_patches(sw);
    let merge = (narrow_width > 0.0).then(|| merge_narrow_patches(sw, &edge_tris, &tri_patch0, np0, narrow_width)).filter(|m| m.2 > 0);
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
    let (tri_patch, np, merged) = merge.unwrap_or((tri_patch0, np0, 0));
    rep.patches = np;
    rep.narrow_patches_merged = merged;
    if np < 2 {
        return Ok(rep);
    }
    let bq = boundary_quads(&w.mesh).map_err(Error::MeshingFailed)?;
    let ne0 = w.mesh.elements.len();
    // every boundary quad on its own element (a pillowed mesh)
    let mut owner = vec![u32::MAX; ne0];
    for (k, q) in bq.iter().enumerate() {
        if owner[q.element as usize] != u32::MAX {
            return Err(Error::MeshingFailed(format!("feature sheets: element {} has two boundary faces (pillow first)", q.element)));
        }
        owner[q.element as usize] = k as u32;
    }
    // ---- labels: the patch of the input the quad faces and is nearest to ----
    let centroid = |q: &[u32; 4]| scale(q.iter().fold([0.0; 3], |a, &i| add(a, w.mesh.nodes[i as usize])), 0.25);
    let mut label: Vec<u32> = bq
        .iter()
        .map(|q| {
            let p = q.nodes.map(|i| w.mesh.nodes[i as usize]);
            let n = cross(sub(p[2], p[0]), sub(p[3], p[1]));
            let l = norm(n);
            let (_, t, _) = if l > 0.0 { sw.closest_facing(centroid(&q.nodes), scale(n, 1.0 / l), 0.5) } else { sw.closest(centroid(&q.nodes)) };
            tri_patch[t as usize]
        })
        .collect();
    // quads across each boundary edge
    let mut edge_q: HashMap<(u32, u32), Vec<u32>> = HashMap::with_capacity(bq.len() * 2);
    for (k, q) in bq.iter().enumerate() {
        for i in 0..4 {
            let (a, b) = (q.nodes[i], q.nodes[(i + 1) % 4]);
            edge_q.entry((a.min(b), a.max(b))).or_default().push(k as u32);
        }
    }
    let qnb: Vec<Vec<u32>> = bq
        .iter()
        .enumerate()
        .map(|(k, q)| {
            (0..4)
                .filter_map(|i| {
                    let (a, b) = (q.nodes[i], q.nodes[(i + 1) % 4]);
                    edge_q[&(a.min(b), a.max(b))].iter().copied().find(|&o| o != k as u32)
                })
                .collect()
        })
        .collect();
    rep.labels_changed = clean_labels(&mut label, &qnb);
    // ---- the paths: boundary nodes whose quads carry two labels or more ----
    let n0 = w.mesh.nodes.len();
    let mut node_labels: Vec<Vec<u32>> = vec![Vec::new(); n0];
    for (k, q) in bq.iter().enumerate() {
        for &v in &q.nodes {
            let l = &mut node_labels[v as usize];
            if !l.contains(&label[k]) {
                l.push(label[k]);
            }
        }
    }
    let path: Vec<u32> = (0..n0 as u32).filter(|&v| node_labels[v as usize].len() >= 2).collect();
    rep.path_nodes = path.len();
    if path.is_empty() {
        return Ok(rep);
    }
    // path edges: boundary edges between quads of two labels
    let path_nb: HashMap<u32, Vec<u32>> = {
        let mut m: HashMap<u32, Vec<u32>> = HashMap::new();
        for (&(a, b), qs) in &edge_q {
            if qs.len() == 2 && label[qs[0] as usize] != label[qs[1] as usize] {
                m.entry(a).or_default().push(b);
                m.entry(b).or_default().push(a);
            }
        }
        m
    };
    let saved = w.clone();
    // ---- one sheet per patch that borders another label ----
    let mut el_label = vec![u32::MAX; ne0];
    // only the quads within SHEET_BAND rings of a path
    let mut ring = vec![usize::MAX; bq.len()];
    let mut front: Vec<usize> = (0..bq.len()).filter(|&k| bq[k].nodes.iter().any(|&v| node_labels[v as usize].len() >= 2)).collect();
    for &k in &front {
        ring[k] = 1;
    }
    let mut r = 1;
    while !front.is_empty() && r < SHEET_BAND {
        r += 1;
        let mut next = Vec::new();
        for &k in &front {
            for &o in &qnb[k] {
                if ring[o as usize] == usize::MAX && label[o as usize] == label[k] {
                    ring[o as usize] = r;
                    next.push(o as usize);
                }
            }
        }
        front = next;
    }
    for (k, q) in bq.iter().enumerate() {
        if ring[k] <= SHEET_BAND {
            el_label[q.element as usize] = label[k];
        }
    }
    // ---- narrow faces at the corners: one quad, not two ----
    // At the path node nearest each feature corner (three labels meet there; the
    // node the corner goes onto below), the elements under the quads of a face
    // whose angle at the corner is below `narrow_deg` stay out of that face's
    // sheet: the face keeps the lattice's quad(s) at the corner, spanning its
    // whole angle, where the sheet would give it exactly two of half the angle
    // each (hexgen_rod's 52-60 degree faces at its four concave corners: elements
    // at 0.24-0.28, below the minimum goal; 0.37-0.40 with them out)
    if narrow_deg > 0.0 {
        for (ci, &k) in sw.features.corners.iter().enumerate() {
            if released.contains(&(ci as u32)) || !corner_held_ok[ci] {
                continue;
            }
            let cx = sw.mesh.vertices[k as usize];
            let Some(v) = nearest_path_node(&path, &node_labels, &w.mesh.nodes, cx, reach, 3, |_| true) else {
                continue;
            };
            // each patch's angle at the corner: the sum of its triangles' angles there
            let mut angle: HashMap<u32, f64> = HashMap::new();
            for (t, tri) in sw.mesh.triangles.iter().enumerate() {
                if let Some(i) = tri.iter().position(|&x| x == k) {
                    let a = sub(sw.mesh.vertices[tri[(i + 1) % 3] as usize], cx);
                    let b = sub(sw.mesh.vertices[tri[(i + 2) % 3] as usize], cx);
                    let c = (dot(a, b) / (norm(a) * norm(b))).clamp(-1.0, 1.0);
                    *angle.entry(tri_patch[t]).or_default() += c.acos().to_degrees();
                }
            }
            let mut out = false;
            for (qi, q) in bq.iter().enumerate().filter(|(_, q)| q.nodes.contains(&v)) {
                if angle.get(&label[qi]).is_some_and(|&a| a < narrow_deg) {
                    el_label[q.element as usize] = u32::MAX;
                    out = true;
                }
            }
            rep.narrow_corners += out as usize;
        }
    }
    let mut bordering: Vec<u32> = path.iter().flat_map(|&v| node_labels[v as usize].iter().copied()).collect();
    bordering.sort_unstable();
    bordering.dedup();
    let mut copy_patch: Vec<u32> = Vec::new();
    for &p in &bordering {
        let in_s: Vec<bool> = (0..w.mesh.elements.len()).map(|e| e < ne0 && el_label[e] == p).collect();
        let (nodes, elements, negative) = insert_sheet(w, &in_s);
        copy_patch.resize(w.mesh.nodes.len() - n0, p);
        rep.nodes_added += nodes;
        rep.elements_added += elements;
        rep.negative_volume += negative;
        rep.sheets += 1;
    }
    if let Err(e) = boundary_quads(&w.mesh) {
        *w = saved;
        return Err(Error::MeshingFailed(format!("feature sheets: {e}")));
    }
    // ---- the path nodes onto the curves and corners ----
    // curves by the pair of patches on their two sides
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
    // corners first: each feature corner to the nearest path node within reach,
    // preferring a node where three labels or more meet
    let mut taken: HashMap<u32, u32> = HashMap::new();
    let mut taken_at: Vec<[f64; 3]> = Vec::new();
    for (ci, &k) in sw.features.corners.iter().enumerate() {
        if released.contains(&(ci as u32)) {
            rep.corners_released += 1;
            continue;
        }
        if !corner_held_ok[ci] {
            continue;
        }
        let cx = sw.mesh.vertices[k as usize];
        // corners closer together than two thirds of the reach (a face too small for
        // the lattice): the first only
        if taken_at.iter().any(|&p| norm(sub(p, cx)) < reach / 1.5) {
            continue;
        }
        let best = |min_labels: usize| nearest_path_node(&path, &node_labels, &w.mesh.nodes, cx, reach, min_labels, |v| !taken.contains_key(&v));
        if let Some(v) = best(3).or_else(|| best(2)) {
            taken.insert(v, k);
            taken_at.push(cx);
            rep.corners_held.push([v, ci as u32]);
        }
    }
    for &v in &path {
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
        let mut best: Option<(usize, super::surface::CurvePoint)> = None;
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
    for &v in &path {
        let Role::Curve(c) = w.role[v as usize] else { continue };
        w.curve_nb[v as usize] = path_nb
            .get(&v)
            .map(|nb| nb.iter().copied().filter(|&u| matches!(w.role[u as usize], Role::Corner(_)) || w.role[u as usize] == Role::Curve(c)).collect())
            .unwrap_or_default();
    }
    w.rebuild();
    // the new nodes, and the old ones next to a path, where their neighbours put
    // them (Laplacian; free boundary nodes back onto their own patch), so that
    // the sheets get a thickness before the untangling smoothing
    let n1 = w.mesh.nodes.len();
    let mut patch_of = vec![u32::MAX; n1];
    for v in n0..n1 {
        patch_of[v] = copy_patch[v - n0];
    }
    for v in 0..n0 {
        if let [l] = node_labels[v][..] {
            patch_of[v] = l;
        }
    }
    let mut movable: Vec<bool> = (0..n1).map(|v| v >= n0).collect();
    let mut front: Vec<u32> = path.clone();
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
    Ok(rep)
}

/// Label clean-up: a quad none of whose neighbours shares its label takes the most
/// common neighbouring label, and every label keeps only its largest edge-connected
/// region (an input patch is connected), the rest taking their neighbours' labels.
/// Returns how many labels changed.
fn clean_labels(label: &mut [u32], qnb: &[Vec<u32>]) -> usize {
    let before = label.to_vec();
    let majority = |label: &[u32], k: usize| -> Option<u32> {
        let mut count: Vec<(u32, usize)> = Vec::new();
        for &o in &qnb[k] {
            let l = label[o as usize];
            if l == label[k] {
                continue;
            }
            match count.iter_mut().find(|c| c.0 == l) {
                Some(c) => c.1 += 1,
                None => count.push((l, 1)),
            }
        }
        count.into_iter().max_by_key(|c| (c.1, std::cmp::Reverse(c.0))).map(|c| c.0)
    };
    for _ in 0..4 {
        let mut changed = false;
        for k in 0..label.len() {
            if qnb[k].iter().all(|&o| label[o as usize] != label[k]) {
                if let Some(l) = majority(label, k) {
                    label[k] = l;
                    changed = true;
                }
            }
        }
        if !changed {
            break;
        }
    }
    for _ in 0..8 {
        // regions: edge-connected quads of one label
        let mut region = vec![u32::MAX; label.len()];
        let mut size: Vec<usize> = Vec::new();
        let mut region_label: Vec<u32> = Vec::new();
        for s in 0..label.len() {
            if region[s] != u32::MAX {
                continue;
            }
            let r = size.len() as u32;
            let mut stack = vec![s];
            region[s] = r;
            let mut n = 0;
            while let Some(k) = stack.pop() {
                n += 1;
                for &o in &qnb[k] {
                    if region[o as usize] == u32::MAX && label[o as usize] == label[s] {
                        region[o as usize] = r;
                        stack.push(o as usize);
                    }
                }
            }
            size.push(n);
            region_label.push(label[s]);
        }
        let mut largest: HashMap<u32, u32> = HashMap::new();
        for r in 0..size.len() {
            let e = largest.entry(region_label[r]).or_insert(r as u32);
            if size[r] > size[*e as usize] {
                *e = r as u32;
            }
        }
        let mut changed = false;
        for k in 0..label.len() {
            if largest[&label[k]] != region[k] {
                if let Some(l) = majority(label, k) {
                    label[k] = l;
                    changed = true;
                }
            }
        }
        if !changed {
            break;
        }
    }
    label.iter().zip(&before).filter(|(a, b)| a != b).count()
}

/// Pillow the elements flagged in `in_s` against the rest of the mesh: every
/// interior face between a flagged and an unflagged element gets a new element,
/// its nodes on the flagged side copies that the flagged elements take (one copy
/// per face-connected group of flagged elements around the node). Copies of
/// boundary nodes are free boundary nodes, moved a quarter of the way to their
/// group's centre. Returns the nodes and elements added and how many new elements
/// have a negative volume.
fn insert_sheet(w: &mut Work, in_s: &[bool]) -> (usize, usize, usize) {
    let ne = w.mesh.elements.len();
    let key = |f: [u32; 4]| {
        let mut k = f;
        k.sort_unstable();
        k
    };
    let mut faces: HashMap<[u32; 4], Vec<(u32, u8)>> = HashMap::new();
    for e in (0..ne).filter(|&e| in_s[e]) {
        for (f, lf) in HEX_FACES.iter().enumerate() {
            faces.entry(key(lf.map(|i| w.mesh.elements[e][i]))).or_default().push((e as u32, f as u8));
        }
    }
    // faces of flagged elements shared with an unflagged one: the sheet
    let mut sheet: Vec<(u32, u8)> = Vec::new();
    let mut other: HashMap<[u32; 4], ()> = HashMap::new();
    for (e, el) in w.mesh.elements.iter().enumerate() {
        if in_s[e] {
            continue;
        }
        for lf in HEX_FACES.iter() {
            let k = key(lf.map(|i| el[i]));
            if faces.contains_key(&k) {
                other.insert(k, ());
            }
        }
    }
    for (k, fs) in &faces {
        if fs.len() == 1 && other.contains_key(k) {
            sheet.push(fs[0]);
        }
    }
    sheet.sort_unstable();
    let mut on_sheet = vec![false; w.mesh.nodes.len()];
    for &(e, f) in &sheet {
        for i in HEX_FACES[f as usize] {
            on_sheet[w.mesh.elements[e as usize][i] as usize] = true;
        }
    }
    // groups: (element, node) slots of flagged elements at sheet nodes, joined
    // across faces two flagged elements share
    let mut slot: HashMap<(u32, u32), usize> = HashMap::new();
    let mut slots: Vec<(u32, u32)> = Vec::new();
    for e in (0..ne).filter(|&e| in_s[e]) {
        for &v in &w.mesh.elements[e] {
            if on_sheet[v as usize] {
                slot.insert((e as u32, v), slots.len());
                slots.push((e as u32, v));
            }
        }
    }
    let mut uf = UnionFind::new(slots.len());
    for (k, fs) in &faces {
        if let [(e1, _), (e2, _)] = fs[..] {
            for &v in k {
                if let (Some(&a), Some(&b)) = (slot.get(&(e1, v)), slot.get(&(e2, v))) {
                    uf.union(a as u32, b as u32);
                }
            }
        }
    }
    // one copy per group
    let n0 = w.mesh.nodes.len();
    let mut copy_of_root: HashMap<u32, u32> = HashMap::new();
    let mut group_sum: Vec<([f64; 3], usize)> = Vec::new();
    let mut copy_of_slot = vec![0u32; slots.len()];
    for s in 0..slots.len() {
        let r = uf.find(s as u32);
        let (e, v) = slots[s];
        let c = *copy_of_root.entry(r).or_insert_with(|| {
            let id = (n0 + group_sum.len()) as u32;
            group_sum.push(([0.0; 3], 0));
            w.mesh.nodes.push(w.mesh.nodes[v as usize]);
            w.role.push(if w.role[v as usize].on_boundary() { Role::Free } else { Role::Interior });
            w.attach.push(u32::MAX);
            w.curve_nb.push(Vec::new());
            id
        });
        copy_of_slot[s] = c;
        let cen = scale(w.mesh.element_corners(e as usize).iter().fold([0.0; 3], |a, x| add(a, *x)), 0.125);
        let g = &mut group_sum[(c as usize) - n0];
        g.0 = add(g.0, cen);
        g.1 += 1;
    }
    // the new elements, on the original nodes of each sheet face (before the
    // flagged elements take the copies)
    let has_targets = w.target.len() == ne;
    let mut negative = 0;
    let mut new_elements = Vec::with_capacity(sheet.len());
    for &(e, f) in &sheet {
        let el = w.mesh.elements[e as usize];
        let top = HEX_FACES[f as usize].map(|i| el[i]);
        let bottom = top.map(|v| copy_of_slot[slot[&(e, v)]]);
        new_elements.push(([bottom[0], bottom[1], bottom[2], bottom[3], top[0], top[1], top[2], top[3]], e, f));
    }
    for s in 0..slots.len() {
        let (e, v) = slots[s];
        for x in w.mesh.elements[e as usize].iter_mut() {
            if *x == v {
                *x = copy_of_slot[s];
            }
        }
    }
    for (c, (sum, k)) in group_sum.iter().enumerate() {
        let id = n0 + c;
        let x = w.mesh.nodes[id];
        w.mesh.nodes[id] = add(x, scale(sub(scale(*sum, 1.0 / *k as f64), x), 0.25));
    }
    const UNIT: [[i32; 3]; 8] = [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]];
    let axis_of = |i: usize, j: usize| (0..3).find(|&a| UNIT[i][a] != UNIT[j][a]).unwrap_or(0);
    for (el, e, f) in &new_elements {
        w.mesh.elements.push(*el);
        if has_targets {
            let fl = HEX_FACES[*f as usize];
            let t = w.target[*e as usize];
            let (au, av) = (axis_of(fl[0], fl[1]), axis_of(fl[0], fl[3]));
            w.target.push([t[au], t[av], 0.5 * t[3 - au - av]]);
        }
        if hex_volume(&el.map(|i| w.mesh.nodes[i as usize])) < 0.0 {
            negative += 1;
        }
    }
    w.rebuild();
    (group_sum.len(), new_elements.len(), negative)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::hex::{build_voxel_hex_mesh, Affine, HexOptions};
    use crate::mesh::TriMesh;

    /// A 6 x 4 x 3 box of unit voxels' faces, turned so that none of its edges
    /// runs along a lattice axis.
    fn turned_box() -> TriMesh {
        let m = crate::geometry::trimesh::tests::voxels([6, 4, 3], |_, _, _| true);
        let (a, b) = (25f64.to_radians(), 15f64.to_radians());
        let v = m
            .vertices
            .iter()
            .map(|p| {
                // about z by a, then about x by b
                let q = [p[0] * a.cos() - p[1] * a.sin(), p[0] * a.sin() + p[1] * a.cos(), p[2]];
                [q[0], q[1] * b.cos() - q[2] * b.sin(), q[1] * b.sin() + q[2] * b.cos()]
            })
            .collect();
        TriMesh { vertices: v, triangles: m.triangles }
    }

    /// A unit cube whose edge along x at y = z = 1 is cut by a 45-degree chamfer
    /// `c` deep on both faces (`c` * sqrt 2 wide).
    fn chamfered_cube(c: f64) -> TriMesh {
        let vertices = vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
            [1.0, 0.0, 1.0],
            [0.0, 1.0 - c, 1.0],
            [1.0, 1.0 - c, 1.0],
            [0.0, 1.0, 1.0 - c],
            [1.0, 1.0, 1.0 - c],
        ];
        let faces: [&[u32]; 7] = [&[0, 3, 8, 6, 4], &[1, 5, 7, 9, 2], &[0, 4, 5, 1], &[0, 1, 2, 3], &[3, 2, 9, 8], &[4, 6, 7, 5], &[8, 9, 7, 6]];
        let mut triangles = Vec::new();
        for f in faces {
            for k in 1..f.len() - 1 {
                let t = [f[0], f[k], f[k + 1]];
                let p = t.map(|i| vertices[i as usize]);
                let n = cross(sub(p[1], p[0]), sub(p[2], p[0]));
                let out = sub(scale(add(add(p[0], p[1]), p[2]), 1.0 / 3.0), [0.5; 3]);
                triangles.push(if dot(n, out) > 0.0 { t } else { [t[0], t[2], t[1]] });
            }
        }
        TriMesh { vertices, triangles }
    }

    #[test]
    fn a_chamfer_narrower_than_the_limit_joins_a_neighbouring_face() {
        let mesh = chamfered_cube(0.05);
        let sw = Surface::new(mesh.clone(), crate::hex::surface::detect_features(&mesh, 40.0, 45.0));
        let (tp, np) = triangle_patches(&sw);
        assert_eq!(np, 7);
        // the chamfer: 0.0707 wide, twice its area over its perimeter 0.066
        let chamfer = tp[tp.len() - 1];
        let et = crate::hex::surface::edge_triangles(&mesh);
        let (merged, n, k) = merge_narrow_patches(&sw, &et, &tp, np, 0.1);
        assert_eq!((n, k), (6, 1));
        // into the y = 1 face (triangles 10, 11) or the z = 1 face (12, 13), which
        // share as much of its boundary and are as steep to it
        let c = merged[merged.len() - 1];
        assert!(c == merged[10] || c == merged[12], "{merged:?}");
        assert_ne!(merged[10], merged[12]);
        // the six faces of the cube keep a patch each
        let mut faces = merged[..14].to_vec();
        faces.sort_unstable();
        faces.dedup();
        assert_eq!(faces.len(), 6);
        // a limit under its width: nothing merged
        let (same, n, k) = merge_narrow_patches(&sw, &et, &tp, np, 0.05);
        assert_eq!((n, k), (7, 0));
        assert_eq!(same.iter().filter(|&&p| p == same[same.len() - 1]).count(), tp.iter().filter(|&&p| p == chamfer).count());
    }

    #[test]
    fn a_turned_box_keeps_its_edges_and_corners_with_the_sheets() {
        let mesh = turned_box();
        let one = |sheets: bool| HexOptions { voxel_resolution: 12, voxel_refinements: 0, feature_sheets: sheets, ..Default::default() };
        let id = Affine::similarity(1.0, [0.0; 3]);
        let plain = build_voxel_hex_mesh(&mesh, &id, 0, &one(false), &mut crate::error::NoProgress).unwrap();
        let r = build_voxel_hex_mesh(&mesh, &id, 0, &one(true), &mut crate::error::NoProgress).unwrap();
        let st = r.stages.iter().find(|s| s.stage == "feature sheets").expect("a feature-sheets stage");
        let d = &st.details;
        assert_eq!(d["patches"], 6, "{d}");
        assert_eq!(d["sheets"], 6, "{d}");
        assert_eq!(d["kept"], true, "{d}");
        assert_eq!(d["corner_nodes"], 8, "{d}");
        assert!(d["curve_nodes"].as_u64().unwrap() > 12, "{d}");
        assert_eq!(r.quality.inverted, 0, "{:?}", r.quality);
        assert!(r.quality.min > 0.2, "{:?}", r.quality);
        // the box's corners are nodes of the result
        let corners = [[0.0, 0.0, 0.0], [6.0, 0.0, 0.0], [0.0, 4.0, 0.0], [6.0, 4.0, 3.0]];
        let turned = turned_box();
        for c in corners {
            let k = crate::geometry::trimesh::tests::voxels([6, 4, 3], |_, _, _| true).vertices.iter().position(|p| *p == c).unwrap();
            let x = turned.vertices[k];
            let near = r.mesh.nodes.iter().map(|p| norm(sub(*p, x))).fold(f64::INFINITY, f64::min);
            assert!(near < 1e-9, "corner {c:?}: nearest node {near}");
        }
        // closer to the input than without the sheets, by more than a third
        assert!(r.hausdorff_relative < 0.67 * plain.hausdorff_relative, "{} vs {}", r.hausdorff_relative, plain.hausdorff_relative);
        let v = mesh.signed_volume();
        assert!((r.volume - v).abs() < 0.01 * v, "{} vs {v}", r.volume);
    }

    /// The voxel fallback's mesh of hexgen_rod with these options.
    fn rod_lattice(opts: &HexOptions) -> crate::hex::HexResult {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/meshes/hexgen_rod.obj");
        let mesh = TriMesh::load(&path, &crate::mesh::LoadOptions::default()).unwrap();
        let genus = mesh.validate().unwrap().genus.unwrap();
        build_voxel_hex_mesh(&mesh, &Affine::similarity(1.0, [0.0; 3]), genus, opts, &mut crate::error::NoProgress).unwrap()
    }

    #[test]
    fn the_rod_meets_every_goal_at_36_voxels_with_every_corner_held() {
        // hexgen_rod at 36 voxels with the coverage step: plain 1.10 % away; with
        // the sheets, its four concave corners (where the small end's step meets
        // the shoulder) have a face of 52-60 degrees, which the sheets split into
        // two quads: elements at 0.24, and the corners had to be released (0.485 %).
        // With those faces' lattice quads kept out of their sheets every corner is
        // held within the minimum goal, and the first mesh meets every goal
        // (0.47 %; HexGen's rod: 0.48 % at 1,280 elements; BENCHMARKS.md "One quad
        // for a narrow face at a corner"), where the fallback without the sheets
        // needed 48 voxels (5,723 elements)
        let opts = HexOptions { voxel_resolution: 36, voxel_refinements: 0, pin_uncovered: 0.6, ..Default::default() };
        let r = rod_lattice(&opts);
        let note = &r.stages[0].details["feature_sheets"];
        assert_eq!((&note["compared"], &note["kept"]), (&serde_json::json!(false), &serde_json::json!(true)), "{note}");
        assert_eq!(opts.goals.missed(&r), 0, "{:?} {}", r.quality, r.hausdorff_relative);
        // within a tenth of HexGen's 0.48 % (one lattice's trajectory carries
        // about a tenth of noise, "Lattice placement at HexGen's counts")
        assert!(r.hausdorff_relative < 0.0053, "{}", r.hausdorff_relative);
        assert!(r.quality.elements < 5_723, "{}", r.quality.elements);
        let st = r.stages.iter().find(|s| s.stage == "feature sheets").unwrap();
        let d = &st.details;
        // the rod has 8 feature corners, all held; 4 with a narrow face
        assert_eq!((d["kept"].as_bool(), d["corner_nodes"].as_u64(), d["narrow_corners"].as_u64()), (Some(true), Some(8), Some(4)), "{d}");
        let held: Vec<[u32; 2]> = serde_json::from_value(d["corners_held"].clone()).unwrap();
        for [v, _] in held {
            let worst = r.mesh.elements.iter().zip(&r.scaled_jacobian).filter(|(el, _)| el.contains(&v)).map(|(_, &q)| q).fold(f64::INFINITY, f64::min);
            assert!(worst >= opts.goals.min_scaled_jacobian, "corner node {v} at {:?}: an element at {worst}", r.mesh.nodes[v as usize]);
        }
    }

    #[test]
    fn the_rod_at_33_voxels_releases_every_corner_when_the_concave_ones_leave_it_short() {
        // hexgen_rod at 33 voxels, default options (the main job's lattice until
        // the twenty-seventh session): the sheets' mesh misses the minimum at the
        // 4 concave corners; with those released it is valid but 1.06 % away;
        // with all 8 released 0.93 %, every goal met (BENCHMARKS.md "Releasing
        // every corner when the corners at fault are not enough")
        // (the narrow corner faces off: with them the concave corners are held
        // within the minimum goal and nothing is released, "One quad for a narrow
        // face at a corner")
        let opts = HexOptions { voxel_resolution: 33, voxel_refinements: 0, narrow_corner_faces: 0.0, ..Default::default() };
        let r = rod_lattice(&opts);
        let note = &r.stages[0].details["feature_sheets"];
        assert_eq!((note["corners_released"].as_u64(), note["corners_released_all"].as_u64()), (Some(4), Some(8)), "{note}");
        // the targeted release missed a goal (that is why every corner was tried)
        let rel = &note["released"];
        let missed = rel["inverted"].as_u64() != Some(0)
            || rel["min_scaled_jacobian"].as_f64().unwrap() < opts.goals.min_scaled_jacobian
            || rel["mean_scaled_jacobian"].as_f64().unwrap() < opts.goals.mean_scaled_jacobian
            || rel["hausdorff_relative"].as_f64().unwrap() > opts.goals.hausdorff;
        assert!(missed, "{note}");
        assert_eq!(note["chosen"], "released_all", "{note}");
        assert_eq!(opts.goals.missed(&r), 0, "{:?} {}", r.quality, r.hausdorff_relative);
        let st = r.stages.iter().find(|s| s.stage == "feature sheets").unwrap();
        assert_eq!((st.details["kept"].as_bool(), st.details["corner_nodes"].as_u64()), (Some(true), Some(0)), "{}", st.details);
    }

    #[test]
    fn the_sheets_of_hepta_are_kept_through_the_inversions_at_20_voxels() {
        // hexgen_hepta's 45-degree chamfers are narrower than a voxel at 20: the
        // two sheets of a chamfer meet and the smoothing leaves 13 elements
        // inverted (until the twenty-seventh session the sheets were undone
        // there); the steps after it untangle them, and with the corners whose
        // elements stay below the minimum goal released every goal but the
        // distance is met, much closer than without the sheets (1.07 % against
        // 1.71 %, BENCHMARKS.md "Feature sheets through the inversions")
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/meshes/hexgen_hepta.obj");
        let mesh = TriMesh::load(&path, &crate::mesh::LoadOptions::default()).unwrap();
        // (the uniform lattice only, on which these figures were measured)
        let one = |sheets: bool| HexOptions { voxel_resolution: 20, voxel_refinements: 0, feature_sheets: sheets, lattice_planes: 0.0, ..Default::default() };
        let id = Affine::similarity(1.0, [0.0; 3]);
        let plain = build_voxel_hex_mesh(&mesh, &id, 0, &one(false), &mut crate::error::NoProgress).unwrap();
        let r = build_voxel_hex_mesh(&mesh, &id, 0, &one(true), &mut crate::error::NoProgress).unwrap();
        let st = r.stages.iter().find(|s| s.stage == "feature sheets").expect("a feature-sheets stage");
        assert_eq!(st.details["kept"], true, "{}", st.details);
        let note = &r.stages[0].details["feature_sheets"];
        assert_eq!((&note["compared"], &note["chosen"]), (&serde_json::json!(true), &serde_json::json!("released")), "{note}");
        assert_eq!(r.quality.inverted, 0, "{:?}", r.quality);
        assert!(r.quality.min >= one(true).goals.min_scaled_jacobian && r.quality.mean >= one(true).goals.mean_scaled_jacobian, "{:?}", r.quality);
        assert!(r.hausdorff_relative < 0.8 * plain.hausdorff_relative, "{} vs {}", r.hausdorff_relative, plain.hausdorff_relative);
    }

    #[test]
    fn hepta_keeps_its_sheets_at_12_voxels_with_its_chamfers_merged() {
        // with the 45- and 51-degree curves followed (feature_median_angle 40),
        // hexgen_hepta at 12 voxels has 21 patches, its chamfers and ledges
        // 0.59-0.70 of the lattice's spacing wide; merged into their neighbours,
        // the sheets hold and the mesh comes within the distance goal (without
        // the merge: min 0.05, 2.92 %, the plain mesh chosen; BENCHMARKS.md
        // "Narrow patches merged")
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/meshes/hexgen_hepta.obj");
        let mesh = TriMesh::load(&path, &crate::mesh::LoadOptions::default()).unwrap();
        let opts = HexOptions { voxel_resolution: 12, voxel_refinements: 0, feature_median_angle: 40.0, pin_uncovered: 0.6, ..Default::default() };
        let r = build_voxel_hex_mesh(&mesh, &Affine::similarity(1.0, [0.0; 3]), 0, &opts, &mut crate::error::NoProgress).unwrap();
        let st = r.stages.iter().find(|s| s.stage == "feature sheets").expect("a feature-sheets stage");
        assert!(st.details["narrow_patches_merged"].as_u64().unwrap() >= 4, "{}", st.details);
        let note = &r.stages[0].details["feature_sheets"];
        assert_eq!(note["chosen"], "with", "{note}");
        assert_eq!(r.quality.inverted, 0, "{:?}", r.quality);
        assert!(r.quality.min >= opts.goals.min_scaled_jacobian, "{:?}", r.quality);
        let without = note["without"]["hausdorff_relative"].as_f64().unwrap();
        assert!(r.hausdorff_relative <= opts.goals.hausdorff && r.hausdorff_relative < 0.5 * without, "{} vs {without}", r.hausdorff_relative);
    }

    #[test]
    fn a_sheet_under_half_a_box_keeps_the_mesh_conforming() {
        // a 2 x 1 x 1 block of unit hexes, the first flagged: one sheet face (the
        // shared face), its four nodes copied; the new element sits between
        let mesh = super::super::HexMesh {
            nodes: (0..12).map(|i| [(i % 3) as f64, ((i / 3) % 2) as f64, (i / 6) as f64]).collect(),
            elements: vec![[0, 1, 4, 3, 6, 7, 10, 9], [1, 2, 5, 4, 7, 8, 11, 10]],
        };
        let mut w = Work {
            mesh: mesh.clone(),
            role: vec![Role::Free; 12],
            attach: vec![u32::MAX; 12],
            curve_nb: vec![Vec::new(); 12],
            bgraph: Default::default(),
            nbr: Default::default(),
            n2e: Default::default(),
            target: vec![[1.0; 3]; 2],
        };
        w.rebuild();
        let (nodes, elements, negative) = insert_sheet(&mut w, &[true, false]);
        assert_eq!((nodes, elements, negative), (4, 1, 0));
        assert_eq!(w.mesh.elements.len(), 3);
        let bq = boundary_quads(&w.mesh).unwrap();
        // 10 boundary faces of the block, plus the new element's 4 sides
        assert_eq!(bq.len(), 14);
        // the flagged element took the copies, the other kept the originals, and
        // every element is positive (the copies moved a quarter of the way into
        // the flagged element)
        assert!(w.mesh.elements[0].iter().filter(|&&v| v >= 12).count() == 4 && w.mesh.elements[1].iter().all(|&v| v < 12));
        assert!((0..3).all(|e| hex_volume(&w.mesh.element_corners(e)) > 0.0));
        assert_eq!(w.role[12..], [Role::Free; 4]);
    }
}
