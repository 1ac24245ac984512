//! Self-intersection test.
//!
//! Broad phase: a BVH over the triangles' bounding boxes (geometry::Bvh); every
//! pair whose boxes overlap goes to the narrow phase, in parallel.
//! Narrow phase: a conservative float filter (the two triangles' projections
//! along s's normal are separated by an edge line, see `separated_in_projection`),
//! then Shewchuk's exact orientation predicates (crate `robust`):
//! - non-coplanar pairs cross when an edge of one passes strictly through the
//!   other (its ends strictly on both sides of the other's plane and the
//!   crossing point strictly inside the triangle). Pairs that share a vertex are
//!   covered by the same rule: edges at the shared vertex never pass strictly.
//! - coplanar pairs overlap when two edges cross properly, a corner of one lies
//!   strictly inside the other, or (sharing a corner) an edge leaving the shared
//!   corner runs into the other; two coplanar triangles sharing an edge overlap
//!   when they lie on the same side of it (a fold).
//!   Contacts that only touch (a corner on a face, edges meeting) are not counted.
//!   Triangles of zero area are skipped (the check reports them separately).

use super::TriMesh;
use crate::geometry::vec3::*;
use crate::geometry::{Aabb, Bvh};
use rayon::prelude::*;
use robust::{orient2d, orient3d, Coord, Coord3D};

fn c3(p: [f64; 3]) -> Coord3D<f64> {
    Coord3D { x: p[0], y: p[1], z: p[2] }
}

fn o3(a: [f64; 3], b: [f64; 3], c: [f64; 3], d: [f64; 3]) -> f64 {
    orient3d(c3(a), c3(b), c3(c), c3(d))
}

fn sgn(x: f64) -> i8 {
    if x > 0.0 {
        1
    } else if x < 0.0 {
        -1
    } else {
        0
    }
}

/// Pairs (s, t), s < t, of triangles that cross, sorted; at most `limit` pairs
/// are returned (the search stops once it has found them).
pub fn self_intersections(mesh: &TriMesh, limit: usize) -> Vec<(u32, u32)> {
    let nv = mesh.vertices.len();
    let nt = mesh.triangles.len();
    let ok = |t: usize| {
        let tri = mesh.triangles[t];
        tri.iter().all(|&v| (v as usize) < nv)
            && tri[0] != tri[1]
            && tri[1] != tri[2]
            && tri[0] != tri[2]
            && norm(tri_normal(mesh.vertices[tri[0] as usize], mesh.vertices[tri[1] as usize], mesh.vertices[tri[2] as usize])) > 0.0
    };
    let boxes: Vec<Aabb> = (0..nt)
        .map(|t| if ok(t) { Aabb::of_points(&mesh.triangles[t].map(|v| mesh.vertices[v as usize])) } else { Aabb::EMPTY })
        .collect();
    let bvh = Bvh::from_boxes(&boxes);
    let found = std::sync::atomic::AtomicUsize::new(0);
    let mut pairs: Vec<(u32, u32)> = (0..nt)
        .into_par_iter()
        .filter(|&s| boxes[s].min[0] <= boxes[s].max[0])
        .flat_map_iter(|s| {
            let mut out = Vec::new();
            if found.load(std::sync::atomic::Ordering::Relaxed) >= limit {
                return out;
            }
            bvh.for_each_overlap(&boxes[s], |t| {
                if (t as usize) > s && triangles_cross(mesh, s, t as usize) {
                    out.push((s as u32, t));
                }
            });
            found.fetch_add(out.len(), std::sync::atomic::Ordering::Relaxed);
            out
        })
        .collect();
    pairs.sort_unstable();
    pairs.truncate(limit);
    pairs
}

/// Whether triangles s and t of the mesh cross (see the module docs).
/// Orientations at shared corners are known to be zero and are not computed
/// (exact predicates are slow precisely on exact zeros).
pub(crate) fn triangles_cross(mesh: &TriMesh, s: usize, t: usize) -> bool {
    let ts = mesh.triangles[s];
    let tt = mesh.triangles[t];
    cross_pair(ts.map(|v| mesh.vertices[v as usize]), tt.map(|v| mesh.vertices[v as usize]), ts, tt, true)
}

/// Triangles p (corner ids ts) and q (ids tt) cross; `filter` runs the float
/// pre-filter first (it never changes the answer, only the cost).
fn cross_pair(p: [[f64; 3]; 3], q: [[f64; 3]; 3], ts: [u32; 3], tt: [u32; 3], filter: bool) -> bool {
    // shared corners: in_q[i] = index in t of s's corner i
    let in_q: [Option<usize>; 3] = ts.map(|v| tt.iter().position(|&w| w == v));
    let in_p: [Option<usize>; 3] = tt.map(|v| ts.iter().position(|&w| w == v));
    let mut shared = [(0usize, 0usize); 3];
    let mut n_shared = 0;
    for (i, q_index) in in_q.iter().enumerate() {
        if let Some(j) = *q_index {
            shared[n_shared] = (i, j);
            n_shared += 1;
        }
    }
    let shared = &shared[..n_shared];
    if n_shared == 3 {
        return true; // the same triangle twice
    }
    if filter && separated_in_projection(p, q, &in_q, &in_p) {
        return false;
    }
    let oq: [i8; 3] = std::array::from_fn(|j| if in_p[j].is_some() { 0 } else { sgn(o3(p[0], p[1], p[2], q[j])) });
    let (pos, neg) = signs(&oq, &in_p);
    if pos == 0 || neg == 0 {
        if pos + neg > 0 {
            return false; // t meets s's plane at most in the shared corners
        }
        return coplanar_overlap(p, q, shared);
    }
    if n_shared == 2 {
        return false; // sharing an edge and not coplanar
    }
    let op: [i8; 3] = std::array::from_fn(|i| if in_q[i].is_some() { 0 } else { sgn(o3(q[0], q[1], q[2], p[i])) });
    let (pos, neg) = signs(&op, &in_q);
    if pos == 0 || neg == 0 {
        return false;
    }
    for i in 0..3 {
        let j = (i + 1) % 3;
        if oq[i] * oq[j] < 0 && segment_through(q[i], q[j], p) {
            return true;
        }
        if op[i] * op[j] < 0 && segment_through(p[i], p[j], q) {
            return true;
        }
    }
    false
}

/// Cheap, conservative float filter run before the exact predicates: project
/// both triangles along the dominant axis of s's normal and look for an edge
/// line of one that has the other triangle strictly on its far side (beyond a
/// margin of 1e-10 of the extent), except for shared corners lying exactly on
/// that edge. The projections then meet at most in shared corners, so the
/// triangles can only touch there: no crossing.
fn separated_in_projection(p: [[f64; 3]; 3], q: [[f64; 3]; 3], in_q: &[Option<usize>; 3], in_p: &[Option<usize>; 3]) -> bool {
    let n = tri_normal(p[0], p[1], p[2]);
    let (u, v) = if n[0].abs() >= n[1].abs() && n[0].abs() >= n[2].abs() {
        (1, 2)
    } else if n[1].abs() >= n[2].abs() {
        (2, 0)
    } else {
        (0, 1)
    };
    let a2 = p.map(|x| [x[u], x[v]]);
    let b2 = q.map(|x| [x[u], x[v]]);
    let mut lo = [f64::INFINITY; 2];
    let mut hi = [f64::NEG_INFINITY; 2];
    for x in a2.iter().chain(b2.iter()) {
        for k in 0..2 {
            lo[k] = lo[k].min(x[k]);
            hi[k] = hi[k].max(x[k]);
        }
    }
    let extent = (hi[0] - lo[0]).max(hi[1] - lo[1]);
    // edges of X against triangle Y; `shared_y[k]` = index in X of Y's corner k
    let try_edges = |x: &[[f64; 2]; 3], y: &[[f64; 2]; 3], shared_y: &[Option<usize>; 3]| {
        (0..3).any(|i| {
            let (i1, i2) = ((i + 1) % 3, (i + 2) % 3);
            let d = [x[i1][0] - x[i][0], x[i1][1] - x[i][1]];
            let a = [-d[1], d[0]];
            let side = |w: [f64; 2]| a[0] * (w[0] - x[i][0]) + a[1] * (w[1] - x[i][1]);
            let margin = 1e-10 * (a[0].abs() + a[1].abs()) * extent;
            let s3 = side(x[i2]);
            if s3.abs() <= margin {
                return false;
            }
            (0..3).all(|k| match shared_y[k] {
                Some(j) => j == i || j == i1,
                None => side(y[k]) * s3.signum() < -margin,
            })
        })
    };
    try_edges(&a2, &b2, in_p) || try_edges(&b2, &a2, in_q)
}

/// Counts of strictly positive and negative orientations among unshared corners.
fn signs(o: &[i8; 3], shared: &[Option<usize>; 3]) -> (usize, usize) {
    let free = (0..3).filter(|&k| shared[k].is_none());
    (free.clone().filter(|&k| o[k] > 0).count(), free.filter(|&k| o[k] < 0).count())
}

/// Segment ab (already known to have its ends strictly on both sides of the
/// triangle's plane) passes strictly through the interior of triangle t.
fn segment_through(a: [f64; 3], b: [f64; 3], t: [[f64; 3]; 3]) -> bool {
    let s0 = sgn(o3(a, b, t[0], t[1]));
    let s1 = sgn(o3(a, b, t[1], t[2]));
    let s2 = sgn(o3(a, b, t[2], t[0]));
    s0 != 0 && s0 == s1 && s1 == s2
}

fn coplanar_overlap(p: [[f64; 3]; 3], q: [[f64; 3]; 3], shared: &[(usize, usize)]) -> bool {
    // project away the dominant axis of p's normal
    let n = tri_normal(p[0], p[1], p[2]);
    let drop = if n[0].abs() >= n[1].abs() && n[0].abs() >= n[2].abs() {
        0
    } else if n[1].abs() >= n[2].abs() {
        1
    } else {
        2
    };
    let (u, v) = match drop {
        0 => (1, 2),
        1 => (2, 0),
        _ => (0, 1),
    };
    let pr = |x: [f64; 3]| Coord { x: x[u], y: x[v] };
    let a = p.map(pr);
    let b = q.map(pr);
    let o = |x: Coord<f64>, y: Coord<f64>, z: Coord<f64>| sgn(orient2d(x, y, z));
    let inside = |tri: &[Coord<f64>; 3], x: Coord<f64>| {
        let s0 = o(tri[0], tri[1], x);
        let s1 = o(tri[1], tri[2], x);
        let s2 = o(tri[2], tri[0], x);
        s0 != 0 && s0 == s1 && s1 == s2
    };
    if shared.len() == 2 {
        // fold over the shared edge: the two free corners on the same side of it
        let (i0, j0) = shared[0];
        let (i1, _) = shared[1];
        let pi = 3 - i0 - i1;
        let qj = 3 - j0 - shared[1].1;
        let side_p = o(a[i0], a[i1], a[pi]);
        let side_q = o(a[i0], a[i1], b[qj]);
        return side_p != 0 && side_p == side_q;
    }
    // proper edge crossings
    for i in 0..3 {
        for j in 0..3 {
            let (a0, a1) = (a[i], a[(i + 1) % 3]);
            let (b0, b1) = (b[j], b[(j + 1) % 3]);
            let d1 = o(a0, a1, b0);
            let d2 = o(a0, a1, b1);
            let d3 = o(b0, b1, a0);
            let d4 = o(b0, b1, a1);
            if d1 * d2 < 0 && d3 * d4 < 0 {
                return true;
            }
        }
    }
    // a corner strictly inside the other
    let is_shared_p = |i: usize| shared.iter().any(|s| s.0 == i);
    let is_shared_q = |j: usize| shared.iter().any(|s| s.1 == j);
    if (0..3).any(|j| !is_shared_q(j) && inside(&a, b[j])) || (0..3).any(|i| !is_shared_p(i) && inside(&b, a[i])) {
        return true;
    }
    // sharing one corner: an edge leaving it runs into the other triangle's angle
    if let Some(&(i, j)) = shared.first() {
        let mid = |x: Coord<f64>, y: Coord<f64>| Coord { x: 0.5 * (x.x + y.x), y: 0.5 * (x.y + y.y) };
        for k in 1..3 {
            if inside(&a, mid(b[j], b[(j + k) % 3])) || inside(&b, mid(a[i], a[(i + k) % 3])) {
                return true;
            }
        }
    }
    false
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};

    /// The float filter never changes the exact answer: random pairs on a
    /// coarse integer grid (many coplanar, touching and shared-corner cases).
    #[test]
    fn filter_agrees_with_exact_predicates() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        let pts: Vec<[f64; 3]> = (0..40)
            .map(|_| [rng.random_range(0..4) as f64, rng.random_range(0..4) as f64, rng.random_range(0..3) as f64 * 0.5])
            .collect();
        let (mut crossing, mut filtered) = (0, 0);
        for _ in 0..200_000 {
            let ts: [u32; 3] = std::array::from_fn(|_| rng.random_range(0..pts.len() as u32));
            let mut tt: [u32; 3] = std::array::from_fn(|_| rng.random_range(0..pts.len() as u32));
            // share corners often
            for k in 0..3 {
                if rng.random_range(0..3) == 0 {
                    tt[k] = ts[rng.random_range(0..3)];
                }
            }
            if ts[0] == ts[1] || ts[1] == ts[2] || ts[0] == ts[2] || tt[0] == tt[1] || tt[1] == tt[2] || tt[0] == tt[2] {
                continue;
            }
            let p = ts.map(|v| pts[v as usize]);
            let q = tt.map(|v| pts[v as usize]);
            if norm(tri_normal(p[0], p[1], p[2])) == 0.0 || norm(tri_normal(q[0], q[1], q[2])) == 0.0 {
                continue;
            }
            let exact = cross_pair(p, q, ts, tt, false);
            assert_eq!(cross_pair(p, q, ts, tt, true), exact, "{ts:?} {tt:?} {p:?} {q:?}");
            assert_eq!(cross_pair(q, p, tt, ts, true), exact, "symmetry {ts:?} {tt:?}");
            crossing += exact as usize;
            let in_q: [Option<usize>; 3] = ts.map(|v| tt.iter().position(|&w| w == v));
            let in_p: [Option<usize>; 3] = tt.map(|v| ts.iter().position(|&w| w == v));
            filtered += separated_in_projection(p, q, &in_q, &in_p) as usize;
        }
        assert!(crossing > 1000 && filtered > 1000, "crossing {crossing}, filtered {filtered}");
    }
}
