//! The map of one chart onto its polycube face: the chart's boundary loop(s) onto the
//! face's boundary polygon (corner vertices onto the polycube corners, arc length
//! between them), the interior by a Tutte embedding (mean-value or uniform weights,
//! one sparse solve), then a count of the triangles that come out flipped or
//! without area (an ear: three vertices on one straight boundary run). On a
//! convex face (a rectangle) the embedding is bijective by Tutte's and Floater's
//! theorems; on a non-convex face (an L) it may fold, which the count shows. A
//! rectangle with one rectangular hole is cut into four convex quadrilaterals
//! (outer corner to nearest inner corner), its chart along shortest interior paths
//! between the matching corner vertices, which are fixed on the cut segments.

use super::faces::{plane_coords, PolycubeFaces};
use super::topology::ChartTopology;
use super::TutteWeights;
use crate::error::{Error, Result};
use crate::geometry::vec3::*;
use crate::mesh::TriMesh;
use crate::geometry::{StableHashMap, StableHashSet};

/// One chart mapped onto its face.
#[derive(Debug, Clone)]
pub struct ChartMap {
    pub face: usize,
    /// The chart's input vertices.
    pub vertices: Vec<u32>,
    /// Their images on the face (normalised frame, in the face's plane).
    pub positions: Vec<[f64; 3]>,
    /// The chart's triangles (input triangle ids).
    pub triangles: Vec<u32>,
    /// Triangles whose image is flipped (negative signed area).
    pub flipped: usize,
    /// Triangles whose image has no area: those with their three vertices on one
    /// straight run of the boundary (a chart boundary that cuts off an ear).
    pub degenerate: usize,
    /// Is the face convex (the embedding is then bijective by construction)?
    pub convex: bool,
}

fn fail(msg: String) -> Error {
    Error::MeshingFailed(msg)
}

/// Map the chart of face `f` (see the module docs). A face with one rectangular
/// hole (the top of a through-hole cube) is cut into four convex quadrilaterals by
/// the segments from its outer corners to the nearest inner corners, and its chart
/// along shortest interior paths between the matching corner vertices. Errors name
/// what stops the map: another face with holes, a chart with other boundary loops
/// than its face, a corner vertex that is missing, off the chart's boundary or out
/// of order, a cut path that cannot be found.
pub fn map_chart(
    mesh: &TriMesh,
    pf: &PolycubeFaces,
    topo: &ChartTopology,
    labels: &[u32],
    f: usize,
    weights: TutteWeights,
) -> Result<ChartMap> {
    let face = &pf.faces[f];
    let name = pf.name(f);
    let corner_at: StableHashMap<usize, usize> = pf.corners.iter().enumerate().map(|(c, k)| (k.vertex, c)).collect();
    let fcorners: Vec<Vec<usize>> =
        face.loops.iter().map(|l| l.iter().filter_map(|v| corner_at.get(v).copied()).collect()).collect();
    let annulus = face.loops.len() == 2 && fcorners.iter().all(|c| c.len() == 4);
    if face.loops.len() != 1 && !annulus {
        return Err(fail(format!(
            "face {name} has {} boundary loops: chart maps are supported for discs and for rectangles with one rectangular hole",
            face.loops.len()
        )));
    }
    let triangles: Vec<u32> = (0..labels.len() as u32).filter(|&t| labels[t as usize] as usize == f).collect();
    if triangles.is_empty() {
        return Err(fail(format!("face {name} has no chart")));
    }
    let ctx = |m: String| fail(format!("chart of face {name}: {m}"));
    let loops = chart_boundary(mesh, &triangles).map_err(ctx)?;
    if loops.len() != face.loops.len() {
        return Err(ctx(format!("it has {} boundary loops, its face {}", loops.len(), face.loops.len())));
    }
    let vertex_of = |c: usize| topo.corners[c].ok_or_else(|| ctx(format!("corner {c} has no input vertex")));
    let mut fixed: StableHashMap<u32, [f64; 3]> = StableHashMap::default();
    for fc in &fcorners {
        let v0 = vertex_of(fc[0])?;
        let l = loops.iter().find(|l| l.contains(&v0)).ok_or_else(|| ctx(format!("corner {} (vertex {v0}) is not on the chart's boundary", fc[0])))?;
        fix_loop(mesh, pf, l, fc, &topo.corners, &mut fixed).map_err(ctx)?;
    }
    if annulus {
        let on_boundary: StableHashSet<u32> = loops.iter().flatten().copied().collect();
        let corner_vertices: Vec<u32> = fcorners.iter().flatten().filter_map(|&c| topo.corners[c]).collect();
        let mut blocked = on_boundary.clone();
        for &oc in &fcorners[0] {
            let po = pf.corners[oc].position;
            let ic = *fcorners[1].iter().min_by(|&&a, &&b| dist2(pf.corners[a].position, po).total_cmp(&dist2(pf.corners[b].position, po))).unwrap();
            let (vo, vi) = (vertex_of(oc)?, vertex_of(ic)?);
            let ends = |v: u32| near_corner(mesh, &loops, v, &corner_vertices);
            let path = cut_path(mesh, &triangles, &ends(vo), &ends(vi), &blocked)
                .ok_or_else(|| ctx(format!("no interior path from corner {oc} to corner {ic} to cut the annulus along")))?;
            let (a, b) = (fixed[&path[0]], fixed[path.last().unwrap()]);
            place_run(mesh, &path, a, b, &mut fixed);
            blocked.extend(path.iter().copied());
        }
    }
    let (vertices, positions) = tutte(mesh, &triangles, &fixed, weights).map_err(ctx)?;
    let index: StableHashMap<u32, usize> = vertices.iter().enumerate().map(|(i, &v)| (v, i)).collect();
    let eps = 1e-12 * face.area.abs().max(1e-300);
    let (mut flipped, mut degenerate) = (0, 0);
    for &t in &triangles {
        let q = mesh.triangles[t as usize].map(|v| plane_coords(face.dir, positions[index[&v]]));
        let a = (q[1][0] - q[0][0]) * (q[2][1] - q[0][1]) - (q[1][1] - q[0][1]) * (q[2][0] - q[0][0]);
        if a < -eps {
            flipped += 1;
        } else if a <= eps {
            degenerate += 1;
        }
    }
    let convex = annulus || fcorners[0].len() == 4;
    Ok(ChartMap { face: f, vertices, positions, triangles, flipped, degenerate, convex })
}

/// Fix the vertices of one chart boundary loop: the corner vertices of `fc` (corner
/// ids in the face loop's order) onto their corners, the vertices between two
/// corners by arc length on the straight edge between them.
fn fix_loop(
    mesh: &TriMesh,
    pf: &PolycubeFaces,
    chart_loop: &[u32],
    fc: &[usize],
    corners: &[Option<u32>],
    fixed: &mut StableHashMap<u32, [f64; 3]>,
) -> std::result::Result<(), String> {
    let pos_in_loop: StableHashMap<u32, usize> = chart_loop.iter().enumerate().map(|(i, &v)| (v, i)).collect();
    let mut at_loop: Vec<usize> = Vec::with_capacity(fc.len());
    for &c in fc {
        let v = corners[c].ok_or_else(|| format!("corner {c} has no input vertex"))?;
        let k = *pos_in_loop.get(&v).ok_or_else(|| format!("corner {c} (vertex {v}) is not on the chart's boundary"))?;
        at_loop.push(k);
    }
    // the corners must come in the face's cyclic order along the chart's loop
    let n = chart_loop.len();
    let rel: Vec<usize> = at_loop.iter().map(|&k| (k + n - at_loop[0]) % n).collect();
    if rel.windows(2).any(|w| w[1] <= w[0]) {
        return Err("its corners are not in the face's order along its boundary".into());
    }
    let m = fc.len();
    for i in 0..m {
        let (k0, k1) = (at_loop[i], at_loop[(i + 1) % m]);
        let (a, b) = (pf.corners[fc[i]].position, pf.corners[fc[(i + 1) % m]].position);
        let steps = if m == 1 { n } else { (k1 + n - k0) % n };
        let run: Vec<u32> = (0..=steps).map(|j| chart_loop[(k0 + j) % n]).collect();
        place_run(mesh, &run, a, b, fixed);
    }
    Ok(())
}

/// Place the vertices of a run of input vertices on the segment a-b by arc length.
fn place_run(mesh: &TriMesh, run: &[u32], a: [f64; 3], b: [f64; 3], fixed: &mut StableHashMap<u32, [f64; 3]>) {
    let lens: Vec<f64> = run.windows(2).map(|w| norm(sub(mesh.vertices[w[1] as usize], mesh.vertices[w[0] as usize]))).collect();
    let total: f64 = lens.iter().sum();
    let mut acc = 0.0;
    for (j, &v) in run.iter().enumerate() {
        let t = if total > 0.0 { acc / total } else { j as f64 / (run.len() - 1).max(1) as f64 };
        fixed.insert(v, add(a, scale(sub(b, a), t)));
        if j < lens.len() {
            acc += lens[j];
        }
    }
}

/// The boundary vertices a cut may end at near corner vertex `v`: `v` itself and up
/// to three loop vertices either side (not past another corner), each with a cost
/// of four times its distance along the loop, so the corner is preferred and a
/// neighbour is taken where the corner has no interior neighbour.
fn near_corner(mesh: &TriMesh, loops: &[Vec<u32>], v: u32, corners: &[u32]) -> Vec<(u32, f64)> {
    let mut out = vec![(v, 0.0)];
    let Some(l) = loops.iter().find(|l| l.contains(&v)) else { return out };
    let n = l.len();
    let k = l.iter().position(|&x| x == v).unwrap();
    for step in [1, n - 1] {
        let (mut acc, mut prev) = (0.0, v);
        for j in 1..=3usize.min(n / 2) {
            let u = l[(k + step * j) % n];
            if corners.contains(&u) {
                break;
            }
            acc += norm(sub(mesh.vertices[u as usize], mesh.vertices[prev as usize]));
            out.push((u, 4.0 * acc));
            prev = u;
        }
    }
    out
}

/// Shortest edge path within the chart's triangles from one of `sources` to one of
/// `targets` (each with a start or end cost) through vertices that are not `blocked`.
fn cut_path(
    mesh: &TriMesh,
    triangles: &[u32],
    sources: &[(u32, f64)],
    targets: &[(u32, f64)],
    blocked: &StableHashSet<u32>,
) -> Option<Vec<u32>> {
    use std::cmp::Reverse;
    use std::collections::BinaryHeap;
    let mut adj: StableHashMap<u32, Vec<u32>> = StableHashMap::default();
    for &t in triangles {
        let tri = mesh.triangles[t as usize];
        for k in 0..3 {
            adj.entry(tri[k]).or_default().push(tri[(k + 1) % 3]);
            adj.entry(tri[(k + 1) % 3]).or_default().push(tri[k]);
        }
    }
    let target: StableHashMap<u32, f64> = targets.iter().copied().collect();
    let source: StableHashSet<u32> = sources.iter().map(|s| s.0).collect();
    let mut dist: StableHashMap<u32, f64> = StableHashMap::default();
    let mut prev: StableHashMap<u32, u32> = StableHashMap::default();
    let mut heap = BinaryHeap::new();
    for &(s, c) in sources {
        dist.insert(s, c);
        heap.push((Reverse(c.to_bits()), s));
    }
    while let Some((Reverse(dk), v)) = heap.pop() {
        let d = f64::from_bits(dk);
        if d > dist[&v] {
            continue;
        }
        if target.contains_key(&v) {
            let mut path = vec![v];
            while let Some(&p) = prev.get(path.last().unwrap()) {
                path.push(p);
            }
            path.reverse();
            return Some(path);
        }
        if !source.contains(&v) && blocked.contains(&v) {
            continue;
        }
        for &u in adj.get(&v).into_iter().flatten() {
            let end = target.get(&u).copied();
            // the path runs through interior vertices; a boundary-to-boundary step
            // is allowed only from a source straight to a target
            if end.is_none() && blocked.contains(&u) {
                continue;
            }
            let nd = d + norm(sub(mesh.vertices[u as usize], mesh.vertices[v as usize])) + end.unwrap_or(0.0);
            if dist.get(&u).is_none_or(|&old| nd < old) {
                dist.insert(u, nd);
                prev.insert(u, v);
                heap.push((Reverse(nd.to_bits()), u));
            }
        }
    }
    None
}

/// The boundary loops of a chart, in the triangles' orientation.
fn chart_boundary(mesh: &TriMesh, triangles: &[u32]) -> std::result::Result<Vec<Vec<u32>>, String> {
    let mut directed: StableHashMap<(u32, u32), u32> = StableHashMap::default();
    for &t in triangles {
        let tri = mesh.triangles[t as usize];
        for k in 0..3 {
            *directed.entry((tri[k], tri[(k + 1) % 3])).or_insert(0) += 1;
        }
    }
    let mut next: StableHashMap<u32, u32> = StableHashMap::default();
    for &(a, b) in directed.keys() {
        if !directed.contains_key(&(b, a)) && next.insert(a, b).is_some() {
            return Err(format!("its boundary passes vertex {a} twice (the chart is pinched there)"));
        }
    }
    if next.is_empty() {
        return Err("it has no boundary (a closed surface)".into());
    }
    let mut starts: Vec<u32> = next.keys().copied().collect();
    starts.sort_unstable();
    let mut seen: StableHashSet<u32> = StableHashSet::default();
    let mut loops = Vec::new();
    for s in starts {
        if seen.contains(&s) {
            continue;
        }
        let mut l = vec![s];
        seen.insert(s);
        let mut cur = next[&s];
        while cur != s {
            if !seen.insert(cur) {
                return Err("its boundary does not close".into());
            }
            l.push(cur);
            cur = *next.get(&cur).ok_or_else(|| format!("its boundary is open at vertex {cur}"))?;
        }
        loops.push(l);
    }
    Ok(loops)
}

/// Tutte embedding: every free vertex at the weighted mean of its neighbours, the
/// boundary fixed. Returns the chart's vertices and their positions.
fn tutte(
    mesh: &TriMesh,
    triangles: &[u32],
    fixed: &StableHashMap<u32, [f64; 3]>,
    weights: TutteWeights,
) -> std::result::Result<(Vec<u32>, Vec<[f64; 3]>), String> {
    use faer::linalg::solvers::Solve;
    use faer::sparse::{SparseColMat, Triplet};
    let mut vertices: Vec<u32> = triangles.iter().flat_map(|&t| mesh.triangles[t as usize]).collect();
    vertices.sort_unstable();
    vertices.dedup();
    let free: Vec<u32> = vertices.iter().copied().filter(|v| !fixed.contains_key(v)).collect();
    let row: StableHashMap<u32, usize> = free.iter().enumerate().map(|(i, &v)| (v, i)).collect();
    // weights w[(i, j)] of the directed edge i -> j
    let mut w: StableHashMap<(u32, u32), f64> = StableHashMap::default();
    let p = |v: u32| mesh.vertices[v as usize];
    for &t in triangles {
        let tri = mesh.triangles[t as usize];
        for k in 0..3 {
            let (i, j, l) = (tri[k], tri[(k + 1) % 3], tri[(k + 2) % 3]);
            match weights {
                TutteWeights::Uniform => {
                    w.insert((i, j), 1.0);
                    w.insert((j, i), 1.0);
                }
                TutteWeights::MeanValue => {
                    // angle at i in this triangle, shared by edges i-j and i-l
                    let (a, b) = (sub(p(j), p(i)), sub(p(l), p(i)));
                    let (la, lb) = (norm(a), norm(b));
                    if la <= 0.0 || lb <= 0.0 {
                        return Err(format!("triangle {t} has a zero-length edge"));
                    }
                    let ang = (dot(a, b) / (la * lb)).clamp(-1.0, 1.0).acos();
                    let h = (ang / 2.0).tan();
                    *w.entry((i, j)).or_insert(0.0) += h / la;
                    *w.entry((i, l)).or_insert(0.0) += h / lb;
                }
            }
        }
    }
    let n = free.len();
    let mut pos: StableHashMap<u32, [f64; 3]> = fixed.clone();
    if n > 0 {
        let mut trip: Vec<Triplet<usize, usize, f64>> = Vec::new();
        let mut rhs = faer::Mat::<f64>::zeros(n, 3);
        let mut diag = vec![0.0; n];
        for (&(i, j), &wij) in &w {
            let Some(&r) = row.get(&i) else { continue };
            diag[r] += wij;
            match row.get(&j) {
                Some(&c) => trip.push(Triplet::new(r, c, -wij)),
                None => {
                    let q = fixed[&j];
                    for a in 0..3 {
                        rhs[(r, a)] += wij * q[a];
                    }
                }
            }
        }
        for (r, d) in diag.iter().enumerate() {
            if !(*d > 0.0) {
                return Err(format!("vertex {} has no positive weight", free[r]));
            }
            trip.push(Triplet::new(r, r, *d));
        }
        let a = SparseColMat::<usize, f64>::try_new_from_triplets(n, n, &trip).map_err(|e| format!("Tutte matrix: {e:?}"))?;
        let lu = a.sp_lu().map_err(|e| format!("Tutte factorisation: {e:?}"))?;
        lu.solve_in_place(rhs.as_mut());
        for (r, &v) in free.iter().enumerate() {
            let q = [rhs[(r, 0)], rhs[(r, 1)], rhs[(r, 2)]];
            if !q.iter().all(|c| c.is_finite()) {
                return Err("the Tutte solve gave non-finite positions".into());
            }
            pos.insert(v, q);
        }
    }
    let positions = vertices.iter().map(|v| pos[v]).collect();
    Ok((vertices, positions))
}
