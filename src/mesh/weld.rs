//! Welding of coincident vertices.
//!
//! Vertices are visited in index order. Each one joins the lowest-numbered
//! earlier *representative* within distance `dist` (Euclidean), found through a
//! uniform grid of cell size `dist`; if there is none it becomes a
//! representative itself. The result is deterministic and does not chain: a
//! vertex is compared with representatives only. With `dist == 0` only exactly
//! equal positions merge (+0.0 equals -0.0).

use super::TriMesh;
use std::collections::HashMap;

/// Weld in place; returns the number of vertices merged away. Triangles are
/// re-indexed; vertices that were merged into another one are dropped, the
/// others keep their relative order.
pub(crate) fn weld(mesh: &mut TriMesh, dist: f64) -> usize {
    let n = mesh.vertices.len();
    let mut rep_of = vec![0u32; n]; // old index -> new index
    let mut kept: Vec<[f64; 3]> = Vec::with_capacity(n);
    if dist > 0.0 {
        let lo = crate::geometry::Aabb::of_points(&mesh.vertices).min;
        let cell = |p: &[f64; 3]| -> [i64; 3] { std::array::from_fn(|k| ((p[k] - lo[k]) / dist).floor() as i64) };
        let d2 = dist * dist;
        let mut grid: HashMap<[i64; 3], Vec<u32>> = HashMap::with_capacity(n);
        for (i, p) in mesh.vertices.iter().enumerate() {
            let c = cell(p);
            let mut best: Option<u32> = None;
            for dx in -1..=1 {
                for dy in -1..=1 {
                    for dz in -1..=1 {
                        if let Some(list) = grid.get(&[c[0] + dx, c[1] + dy, c[2] + dz]) {
                            for &r in list {
                                let q = &kept[r as usize];
                                let dd = (p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2);
                                if dd <= d2 && best.is_none_or(|b| r < b) {
                                    best = Some(r);
                                }
                            }
                        }
                    }
                }
            }
            rep_of[i] = match best {
                Some(r) => r,
                None => {
                    let r = kept.len() as u32;
                    kept.push(*p);
                    grid.entry(c).or_default().push(r);
                    r
                }
            };
        }
    } else {
        // exact: key on the bit patterns with -0.0 folded onto +0.0
        let key = |p: &[f64; 3]| -> [u64; 3] { std::array::from_fn(|k| (p[k] + 0.0).to_bits()) };
        let mut seen: HashMap<[u64; 3], u32> = HashMap::with_capacity(n);
        for (i, p) in mesh.vertices.iter().enumerate() {
            rep_of[i] = *seen.entry(key(p)).or_insert_with(|| {
                kept.push(*p);
                kept.len() as u32 - 1
            });
        }
    }
    let merged = n - kept.len();
    mesh.vertices = kept;
    for t in &mut mesh.triangles {
        for v in t.iter_mut() {
            *v = rep_of[*v as usize];
        }
    }
    merged
}
