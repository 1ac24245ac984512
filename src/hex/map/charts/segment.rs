//! Segmentation of the input surface into charts, one per polycube face: a seed
//! labelling (the nearest face among those facing the triangle's dominant normal
//! direction, or the face the diffusion correspondence points to), then iterated
//! conditional modes on an energy of normal fidelity, distance to the face and an
//! edge-length weighted boundary term that is cheap along sharp input edges.

use super::faces::{dir_normal, PolycubeFaces};
use super::ChartOptions;
use crate::geometry::vec3::*;
use crate::mesh::TriMesh;
use crate::geometry::StableHashMap;

/// Triangle adjacency and per-triangle geometry of the input.
#[derive(Debug, Clone)]
pub struct TriGraph {
    pub normals: Vec<[f64; 3]>,
    pub centroids: Vec<[f64; 3]>,
    pub areas: Vec<f64>,
    /// For each triangle: (neighbour, shared edge weight in the boundary term, edge length).
    pub neighbours: Vec<Vec<(u32, f64, f64)>>,
    /// Mean edge length.
    pub mean_edge: f64,
}

impl TriGraph {
    /// Adjacency across manifold edges; `sharp_angle` (degrees) sets how fast the
    /// boundary term falls with the dihedral angle: weight exp(-(angle/sharp_angle)^2).
    pub fn new(mesh: &TriMesh, sharp_angle: f64) -> TriGraph {
        let n = mesh.triangles.len();
        let p = |i: u32| mesh.vertices[i as usize];
        let mut normals = Vec::with_capacity(n);
        let mut centroids = Vec::with_capacity(n);
        let mut areas = Vec::with_capacity(n);
        for t in &mesh.triangles {
            let c = cross(sub(p(t[1]), p(t[0])), sub(p(t[2]), p(t[0])));
            let l = norm(c);
            areas.push(l / 2.0);
            normals.push(if l > 0.0 { scale(c, 1.0 / l) } else { [0.0; 3] });
            centroids.push(scale(add(add(p(t[0]), p(t[1])), p(t[2])), 1.0 / 3.0));
        }
        let mut by_edge: StableHashMap<(u32, u32), Vec<u32>> = StableHashMap::with_capacity_and_hasher(n * 2, Default::default());
        for (i, t) in mesh.triangles.iter().enumerate() {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                by_edge.entry((a.min(b), a.max(b))).or_default().push(i as u32);
            }
        }
        let mut neighbours = vec![Vec::new(); n];
        let (mut total, mut count) = (0.0, 0usize);
        let theta0 = sharp_angle.to_radians().max(1e-6);
        for (&(a, b), ts) in &by_edge {
            let len = norm(sub(p(a), p(b)));
            total += len;
            count += 1;
            if ts.len() != 2 {
                continue;
            }
            let (s, t) = (ts[0] as usize, ts[1] as usize);
            let angle = dot(normals[s], normals[t]).clamp(-1.0, 1.0).acos();
            let w = (-(angle / theta0).powi(2)).exp();
            neighbours[s].push((t as u32, w, len));
            neighbours[t].push((s as u32, w, len));
        }
        let mean_edge = if count > 0 { total / count as f64 } else { 1.0 };
        TriGraph { normals, centroids, areas, neighbours, mean_edge }
    }
}

/// Dominant direction code of a normal (0..6 = +X,-X,+Y,-Y,+Z,-Z).
pub fn dominant_dir(n: [f64; 3]) -> u8 {
    let a = (0..3).max_by(|&i, &j| n[i].abs().total_cmp(&n[j].abs())).unwrap();
    (2 * a + usize::from(n[a] < 0.0)) as u8
}

/// Data term of assigning triangle `t` to face `f`.
fn data_cost(g: &TriGraph, pf: &PolycubeFaces, opts: &ChartOptions, t: usize, f: usize) -> f64 {
    let d = dir_normal(pf.faces[f].dir);
    (1.0 - dot(g.normals[t], d)) + opts.distance_weight * pf.distance(f, g.centroids[t])
}

/// The seed labelling (see the module docs). `corr` maps input points to polycube
/// points (the diffusion correspondence, may be empty).
pub fn seed(g: &TriGraph, pf: &PolycubeFaces, corr: &[([f64; 3], [f64; 3])]) -> Vec<u32> {
    let lookup = PointLookup::new(corr);
    (0..g.normals.len())
        .map(|t| {
            let d = dominant_dir(g.normals[t]);
            let c = g.centroids[t];
            // the point the correspondence gives, else the centroid itself
            let q = lookup.as_ref().map(|l| l.polycube_point(c)).unwrap_or(c);
            let cand = pf.faces_with_dir(d).min_by(|&a, &b| pf.distance(a, q).total_cmp(&pf.distance(b, q)));
            let any = || (0..pf.faces.len()).min_by(|&a, &b| pf.distance(a, c).total_cmp(&pf.distance(b, c))).unwrap_or(0);
            cand.unwrap_or_else(any) as u32
        })
        .collect()
}

/// Iterated conditional modes: each triangle takes, among its own label and its
/// neighbours', the one of least data + boundary cost; sweeps until nothing changes
/// or `opts.iterations` sweeps. Returns the number of sweeps.
pub fn optimise(g: &TriGraph, pf: &PolycubeFaces, opts: &ChartOptions, labels: &mut [u32]) -> usize {
    let lambda = opts.smoothness / g.mean_edge.max(1e-12);
    for sweep in 0..opts.iterations {
        let mut changed = 0;
        for t in 0..labels.len() {
            let mut options: Vec<u32> = vec![labels[t]];
            for &(u, _, _) in &g.neighbours[t] {
                if !options.contains(&labels[u as usize]) {
                    options.push(labels[u as usize]);
                }
            }
            if options.len() == 1 {
                continue;
            }
            let cost = |f: u32| {
                let boundary: f64 = g.neighbours[t]
                    .iter()
                    .filter(|&&(u, _, _)| labels[u as usize] != f)
                    .map(|&(_, w, len)| w * len)
                    .sum();
                data_cost(g, pf, opts, t, f as usize) + lambda * boundary
            };
            let best = options.iter().copied().min_by(|&a, &b| cost(a).total_cmp(&cost(b))).unwrap();
            if best != labels[t] && cost(best) < cost(labels[t]) - 1e-12 {
                labels[t] = best;
                changed += 1;
            }
        }
        if changed == 0 {
            return sweep + 1;
        }
    }
    opts.iterations
}

/// Connected components of the triangles with label `f` (across manifold edges).
pub fn components(g: &TriGraph, labels: &[u32], f: u32) -> Vec<Vec<u32>> {
    let mut seen = vec![false; labels.len()];
    let mut out = Vec::new();
    for s in 0..labels.len() {
        if labels[s] != f || seen[s] {
            continue;
        }
        let mut comp = vec![s as u32];
        seen[s] = true;
        let mut k = 0;
        while k < comp.len() {
            let t = comp[k] as usize;
            k += 1;
            for &(u, _, _) in &g.neighbours[t] {
                if labels[u as usize] == f && !seen[u as usize] {
                    seen[u as usize] = true;
                    comp.push(u);
                }
            }
        }
        out.push(comp);
    }
    out
}

/// Make every chart connected: all components of a label but the one of largest
/// area go, one at a time from the smallest, to the neighbouring label they share
/// the longest boundary with. Returns the number of islands moved.
pub fn remove_islands(g: &TriGraph, labels: &mut [u32], faces: usize) -> usize {
    let mut moved = 0;
    for _ in 0..1000 {
        let mut islands: Vec<(f64, Vec<u32>)> = Vec::new();
        for f in 0..faces as u32 {
            let comps = components(g, labels, f);
            if comps.len() < 2 {
                continue;
            }
            let area = |c: &Vec<u32>| c.iter().map(|&t| g.areas[t as usize]).sum::<f64>();
            let keep = (0..comps.len()).max_by(|&a, &b| area(&comps[a]).total_cmp(&area(&comps[b]))).unwrap();
            for (i, c) in comps.into_iter().enumerate() {
                if i != keep {
                    islands.push((area(&c), c));
                }
            }
        }
        if islands.is_empty() {
            break;
        }
        islands.sort_by(|a, b| a.0.total_cmp(&b.0));
        // move the smallest island; the others are recomputed (moves merge them)
        let (_, island) = islands.swap_remove(0);
        let own = labels[island[0] as usize];
        let mut shared: StableHashMap<u32, f64> = StableHashMap::default();
        for &t in &island {
            for &(u, _, len) in &g.neighbours[t as usize] {
                let l = labels[u as usize];
                if l != own {
                    *shared.entry(l).or_insert(0.0) += len;
                }
            }
        }
        let Some((&to, _)) = shared.iter().max_by(|a, b| a.1.total_cmp(b.1).then(b.0.cmp(a.0))) else {
            continue;
        };
        for &t in &island {
            labels[t as usize] = to;
        }
        moved += 1;
    }
    moved
}

/// Move ears: a triangle that borders one other chart across two of its edges and
/// its own chart across the third goes to that other chart (its three vertices
/// would lie on one straight run of its face's boundary and map to a triangle
/// without area). A chart's last triangle stays. Returns the number moved.
pub fn remove_ears(g: &TriGraph, labels: &mut [u32], faces: usize) -> usize {
    let mut size = vec![0usize; faces];
    for &l in labels.iter() {
        size[l as usize] += 1;
    }
    let mut moved = 0;
    for _ in 0..16 {
        let mut changed = 0;
        for t in 0..labels.len() {
            let nb = &g.neighbours[t];
            let own = labels[t];
            if nb.len() != 3 || size[own as usize] <= 1 {
                continue;
            }
            let others: Vec<u32> = nb.iter().map(|&(u, _, _)| labels[u as usize]).filter(|&l| l != own).collect();
            if others.len() == 2 && others[0] == others[1] {
                labels[t] = others[0];
                size[own as usize] -= 1;
                size[others[0] as usize] += 1;
                changed += 1;
            }
        }
        moved += changed;
        if changed == 0 {
            break;
        }
    }
    moved
}

/// Input point -> polycube point by the nearest correspondence pair (bucket grid).
struct PointLookup {
    pairs: Vec<([f64; 3], [f64; 3])>,
    lo: [f64; 3],
    cell: f64,
    dims: [usize; 3],
    buckets: Vec<Vec<u32>>,
}

impl PointLookup {
    fn new(corr: &[([f64; 3], [f64; 3])]) -> Option<PointLookup> {
        let pairs: Vec<([f64; 3], [f64; 3])> = corr
            .iter()
            .filter(|(a, b)| a.iter().chain(b.iter()).all(|v| v.is_finite()))
            .map(|&(pc, inp)| (inp, pc))
            .collect();
        if pairs.len() < 8 {
            return None;
        }
        let pts: Vec<[f64; 3]> = pairs.iter().map(|p| p.0).collect();
        let bb = crate::geometry::Aabb::of_points(&pts);
        let size = bb.size();
        let cell = (size.iter().fold(0.0f64, |m, &s| m.max(s)) / (pairs.len() as f64).cbrt()).max(1e-6);
        let dims = size.map(|s| ((s / cell).floor() as usize + 1).min(128));
        let mut buckets = vec![Vec::new(); dims[0] * dims[1] * dims[2]];
        let lo = bb.min;
        for (i, p) in pts.iter().enumerate() {
            let c: [usize; 3] = std::array::from_fn(|a| (((p[a] - lo[a]) / cell).floor().max(0.0) as usize).min(dims[a] - 1));
            buckets[c[0] + dims[0] * (c[1] + dims[1] * c[2])].push(i as u32);
        }
        Some(PointLookup { pairs, lo, cell, dims, buckets })
    }

    fn polycube_point(&self, p: [f64; 3]) -> [f64; 3] {
        let c: [i64; 3] = std::array::from_fn(|a| (((p[a] - self.lo[a]) / self.cell).floor() as i64).clamp(0, self.dims[a] as i64 - 1));
        let mut best = (f64::INFINITY, 0u32);
        let maxr = *self.dims.iter().max().unwrap() as i64;
        for r in 0..=maxr {
            for z in (c[2] - r).max(0)..=(c[2] + r).min(self.dims[2] as i64 - 1) {
                for y in (c[1] - r).max(0)..=(c[1] + r).min(self.dims[1] as i64 - 1) {
                    for x in (c[0] - r).max(0)..=(c[0] + r).min(self.dims[0] as i64 - 1) {
                        if (x - c[0]).abs() != r && (y - c[1]).abs() != r && (z - c[2]).abs() != r {
                            continue;
                        }
                        let b = &self.buckets[x as usize + self.dims[0] * (y as usize + self.dims[1] * z as usize)];
                        for &i in b {
                            let d = dist2(self.pairs[i as usize].0, p);
                            if d < best.0 {
                                best = (d, i);
                            }
                        }
                    }
                }
            }
            // a point in a shell beyond r is at least r cells away
            if best.0.is_finite() && best.0.sqrt() <= r as f64 * self.cell {
                break;
            }
        }
        self.pairs[best.1 as usize].1
    }
}
