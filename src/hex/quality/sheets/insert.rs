//! The sheets themselves: which elements go into each patch's sheet, the
//! narrow faces kept out of their sheet at the corners, and the insertion (the
//! pillowing of each patch's elements against the rest of the mesh).

use super::labels::{nearest_path_node, Labels, Paths};
use super::patches::Patches;
use super::{SheetReport, SHEET_BAND};
use crate::geometry::vec3::*;
use crate::geometry::UnionFind;
use crate::hex::surface::Surface;
use crate::hex::topology::{hex_volume, BoundaryQuad, HEX_FACES};
use crate::hex::work::{Role, Work};
use std::collections::HashMap;

/// The patch whose sheet each of the first `ne0` elements goes into (u32::MAX:
/// none): the elements under the quads within [`SHEET_BAND`] rings of a path.
pub(super) fn sheet_elements(bq: &[BoundaryQuad], labels: &Labels, paths: &Paths, ne0: usize) -> Vec<u32> {
    let (label, qnb, node_labels) = (&labels.label, &labels.qnb, &paths.node_labels);
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
    el_label
}

/// Narrow faces at the corners: one quad, not two. At the path node nearest each
/// feature corner (three labels meet there; the node the corner goes onto
/// later), the elements under the quads of a face whose angle at the corner is
/// below `narrow_deg` stay out of that face's sheet (`el_label`): the face keeps
/// the lattice's quad(s) at the corner, spanning its whole angle, where the sheet
/// would give it exactly two of half the angle each (hexgen_rod's 52-60 degree
/// faces at its four concave corners: elements at 0.24-0.28, below the minimum
/// goal; 0.37-0.40 with them out). Returns the corners where a face was kept out.
#[allow(clippy::too_many_arguments)]
pub(super) fn narrow_corner_faces(
    el_label: &mut [u32],
    w: &Work,
    sw: &Surface,
    bq: &[BoundaryQuad],
    labels: &Labels,
    paths: &Paths,
    patches: &Patches,
    reach: f64,
    released: &[u32],
    narrow_deg: f64,
) -> usize {
    let (label, tri_patch) = (&labels.label, &patches.tri_patch);
    let mut narrow_corners = 0;
    for (ci, &k) in sw.features.corners.iter().enumerate() {
        if released.contains(&(ci as u32)) || !patches.corner_held_ok[ci] {
            continue;
        }
        let cx = sw.mesh.vertices[k as usize];
        let Some(v) = nearest_path_node(&paths.nodes, &paths.node_labels, &w.mesh.nodes, cx, reach, 3, |_| true) else {
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
        narrow_corners += out as usize;
    }
    narrow_corners
}

/// One sheet per patch that borders another label ([`insert_sheet`] of the
/// elements `el_label` gives it), counted in `rep`. Returns the patch of every
/// new node (indices from `n0`, the node count before).
pub(super) fn insert_sheets(w: &mut Work, el_label: &[u32], paths: &Paths, n0: usize, rep: &mut SheetReport) -> Vec<u32> {
    let ne0 = el_label.len();
    let mut bordering: Vec<u32> = paths.nodes.iter().flat_map(|&v| paths.node_labels[v as usize].iter().copied()).collect();
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
    copy_patch
}

/// Pillow the elements flagged in `in_s` against the rest of the mesh: every
/// interior face between a flagged and an unflagged element gets a new element,
/// its nodes on the flagged side copies that the flagged elements take (one copy
/// per face-connected group of flagged elements around the node). Copies of
/// boundary nodes are free boundary nodes, moved a quarter of the way to their
/// group's centre. Returns the nodes and elements added and how many new elements
/// have a negative volume.
pub(super) fn insert_sheet(w: &mut Work, in_s: &[bool]) -> (usize, usize, usize) {
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
