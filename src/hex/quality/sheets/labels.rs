//! The labels of the boundary quads (the input patch each faces and is nearest
//! to, cleaned up) and the paths between them: the boundary nodes whose quads
//! carry two labels or more.

use crate::geometry::vec3::*;
use crate::hex::surface::Surface;
use crate::hex::topology::BoundaryQuad;
use crate::hex::work::Work;
use std::collections::HashMap;

/// The boundary quads' labels and their neighbourhoods.
pub(super) struct Labels {
    /// Per boundary quad: its patch.
    pub label: Vec<u32>,
    /// The quads across each boundary edge.
    pub edge_q: HashMap<(u32, u32), Vec<u32>>,
    /// Per boundary quad: the quads across its edges.
    pub qnb: Vec<Vec<u32>>,
    /// Labels the clean-up changed ([`clean_labels`]).
    pub changed: usize,
}

/// Label every boundary quad `bq` of `w` with the patch (`tri_patch`) of the input
/// it faces and is nearest to, then clean the labels up ([`clean_labels`]).
pub(super) fn label_quads(w: &Work, sw: &Surface, bq: &[BoundaryQuad], tri_patch: &[u32]) -> Labels {
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
    let changed = clean_labels(&mut label, &qnb);
    Labels { label, edge_q, qnb, changed }
}

/// The paths between the labels of the `n0` nodes' quads.
pub(super) struct Paths {
    /// Per node: the labels of its boundary quads.
    pub node_labels: Vec<Vec<u32>>,
    /// The nodes with two labels or more.
    pub nodes: Vec<u32>,
    /// Path edges: boundary edges between quads of two labels, per node.
    pub nb: HashMap<u32, Vec<u32>>,
}

/// The paths of the labelled boundary quads `bq` of a mesh of `n0` nodes.
pub(super) fn paths(bq: &[BoundaryQuad], labels: &Labels, n0: usize) -> Paths {
    let label = &labels.label;
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
    // path edges: boundary edges between quads of two labels
    let path_nb: HashMap<u32, Vec<u32>> = {
        let mut m: HashMap<u32, Vec<u32>> = HashMap::new();
        for (&(a, b), qs) in &labels.edge_q {
            if qs.len() == 2 && label[qs[0] as usize] != label[qs[1] as usize] {
                m.entry(a).or_default().push(b);
                m.entry(b).or_default().push(a);
            }
        }
        m
    };
    Paths { node_labels, nodes: path, nb: path_nb }
}

/// The path node nearest `x` within `reach` with at least `min_labels` labels
/// that `keep` accepts (the first of equally near ones).
pub(super) fn nearest_path_node(path: &[u32], node_labels: &[Vec<u32>], nodes: &[[f64; 3]], x: [f64; 3], reach: f64, min_labels: usize, keep: impl Fn(u32) -> bool) -> Option<u32> {
    path.iter()
        .copied()
        .filter(|&v| node_labels[v as usize].len() >= min_labels && keep(v))
        .map(|v| (v, norm(sub(nodes[v as usize], x))))
        .filter(|&(_, d)| d <= reach)
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(v, _)| v)
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
