//! The map of one chart onto its polycube face: the chart's boundary loop onto the
//! face's boundary polygon (corner vertices onto the polycube corners, arc length
//! between them), the interior by a Tutte embedding (mean-value or uniform weights,
//! one sparse solve), then a count of the triangles that come out flipped or
//! without area (an ear: three vertices on one straight boundary run). On a
//! convex face (a rectangle) the embedding is bijective by Tutte's and Floater's
//! theorems; on a non-convex face (an L) it may fold, which the count shows.

use super::faces::{plane_coords, PolycubeFaces};
use super::topology::ChartTopology;
use super::TutteWeights;
use crate::error::{Error, Result};
use crate::geometry::vec3::*;
use crate::mesh::TriMesh;
use std::collections::HashMap;

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

/// Map the chart of face `f` (see the module docs). Errors name what stops the map:
/// a face with a hole (annuli are not supported), a chart that is not one loop, a
/// corner vertex that is missing or off the chart's boundary or out of order.
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
    if face.loops.len() != 1 {
        return Err(fail(format!(
            "face {name} has a hole ({} boundary loops): chart maps of faces with holes are not supported",
            face.loops.len()
        )));
    }
    let triangles: Vec<u32> = (0..labels.len() as u32).filter(|&t| labels[t as usize] as usize == f).collect();
    if triangles.is_empty() {
        return Err(fail(format!("face {name} has no chart")));
    }
    let chart_loop = chart_boundary(mesh, &triangles).map_err(|m| fail(format!("chart of face {name}: {m}")))?;
    // the face's corners in loop order with their positions
    let floop = &face.loops[0];
    let corner_at: HashMap<usize, usize> = pf.corners.iter().enumerate().map(|(c, k)| (k.vertex, c)).collect();
    let fcorners: Vec<usize> = floop.iter().filter_map(|v| corner_at.get(v).copied()).collect();
    let mut at_loop: Vec<usize> = Vec::with_capacity(fcorners.len());
    let pos_in_loop: HashMap<u32, usize> = chart_loop.iter().enumerate().map(|(i, &v)| (v, i)).collect();
    for &c in &fcorners {
        let v = topo.corners[c].ok_or_else(|| fail(format!("chart of face {name}: corner {c} has no input vertex")))?;
        let k = *pos_in_loop
            .get(&v)
            .ok_or_else(|| fail(format!("chart of face {name}: corner {c} (vertex {v}) is not on the chart's boundary")))?;
        at_loop.push(k);
    }
    // the corners must come in the face's cyclic order along the chart's loop
    let n = chart_loop.len();
    let rel: Vec<usize> = at_loop.iter().map(|&k| (k + n - at_loop[0]) % n).collect();
    if rel.windows(2).any(|w| w[1] <= w[0]) {
        return Err(fail(format!("chart of face {name}: its corners are not in the face's order along its boundary")));
    }
    // boundary positions: arc length between consecutive corners
    let mut fixed: HashMap<u32, [f64; 3]> = HashMap::new();
    let m = fcorners.len();
    for i in 0..m {
        let (k0, k1) = (at_loop[i], at_loop[(i + 1) % m]);
        let (a, b) = (pf.corners[fcorners[i]].position, pf.corners[fcorners[(i + 1) % m]].position);
        let run: Vec<u32> = (0..=((k1 + n - k0) % n)).map(|j| chart_loop[(k0 + j) % n]).collect();
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
    let (vertices, positions) = tutte(mesh, &triangles, &fixed, weights).map_err(|m| fail(format!("chart of face {name}: {m}")))?;
    let index: HashMap<u32, usize> = vertices.iter().enumerate().map(|(i, &v)| (v, i)).collect();
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
    Ok(ChartMap { face: f, vertices, positions, triangles, flipped, degenerate, convex: fcorners.len() == 4 })
}

/// The boundary of a chart as one loop of vertices, in the triangles' orientation.
fn chart_boundary(mesh: &TriMesh, triangles: &[u32]) -> std::result::Result<Vec<u32>, String> {
    let mut directed: HashMap<(u32, u32), u32> = HashMap::new();
    for &t in triangles {
        let tri = mesh.triangles[t as usize];
        for k in 0..3 {
            *directed.entry((tri[k], tri[(k + 1) % 3])).or_insert(0) += 1;
        }
    }
    let mut next: HashMap<u32, u32> = HashMap::new();
    for &(a, b) in directed.keys() {
        if !directed.contains_key(&(b, a)) && next.insert(a, b).is_some() {
            return Err(format!("its boundary passes vertex {a} twice (the chart is pinched there)"));
        }
    }
    let Some(&start) = next.keys().min() else {
        return Err("it has no boundary (a closed surface)".into());
    };
    let mut l = vec![start];
    let mut cur = next[&start];
    while cur != start {
        l.push(cur);
        cur = *next.get(&cur).ok_or_else(|| format!("its boundary is open at vertex {cur}"))?;
        if l.len() > next.len() {
            return Err("its boundary does not close".into());
        }
    }
    if l.len() != next.len() {
        return Err(format!("it has {} boundary edges off its main loop (not a disc)", next.len() - l.len()));
    }
    Ok(l)
}

/// Tutte embedding: every free vertex at the weighted mean of its neighbours, the
/// boundary fixed. Returns the chart's vertices and their positions.
fn tutte(
    mesh: &TriMesh,
    triangles: &[u32],
    fixed: &HashMap<u32, [f64; 3]>,
    weights: TutteWeights,
) -> std::result::Result<(Vec<u32>, Vec<[f64; 3]>), String> {
    use faer::linalg::solvers::Solve;
    use faer::sparse::{SparseColMat, Triplet};
    let mut vertices: Vec<u32> = triangles.iter().flat_map(|&t| mesh.triangles[t as usize]).collect();
    vertices.sort_unstable();
    vertices.dedup();
    let free: Vec<u32> = vertices.iter().copied().filter(|v| !fixed.contains_key(v)).collect();
    let row: HashMap<u32, usize> = free.iter().enumerate().map(|(i, &v)| (v, i)).collect();
    // weights w[(i, j)] of the directed edge i -> j
    let mut w: HashMap<(u32, u32), f64> = HashMap::new();
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
    let mut pos: HashMap<u32, [f64; 3]> = fixed.clone();
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
