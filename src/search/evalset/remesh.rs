//! Connectivity edits of the evaluation set's meshes: uniform 1-to-4 refinement,
//! random edge splits, random points inserted inside triangles and random flips of
//! edges between coplanar triangles. None moves the surface: every new vertex
//! lies on an existing triangle (or edge), so the exact boundary stays exact.

use crate::geometry::vec3::{dot, norm, tri_normal};
use crate::mesh::TriMesh;
use rand::RngExt;
use rand_chacha::ChaCha8Rng;
use std::collections::HashMap;

fn key(a: u32, b: u32) -> (u32, u32) {
    (a.min(b), a.max(b))
}

fn lerp(a: [f64; 3], b: [f64; 3], t: f64) -> [f64; 3] {
    std::array::from_fn(|k| a[k] + t * (b[k] - a[k]))
}

/// Each triangle split into four at its edge midpoints (midpoints shared between
/// the two triangles of an edge), `levels` times.
pub fn refine(m: &TriMesh, levels: usize) -> TriMesh {
    let mut m = m.clone();
    for _ in 0..levels {
        let mut mid: HashMap<(u32, u32), u32> = HashMap::new();
        let mut verts = m.vertices.clone();
        let mut at = |a: u32, b: u32, verts: &mut Vec<[f64; 3]>| -> u32 {
            *mid.entry(key(a, b)).or_insert_with(|| {
                verts.push(lerp(verts[a as usize], verts[b as usize], 0.5));
                (verts.len() - 1) as u32
            })
        };
        let mut tris = Vec::with_capacity(m.triangles.len() * 4);
        for &[a, b, c] in &m.triangles {
            let (ab, bc, ca) = (at(a, b, &mut verts), at(b, c, &mut verts), at(c, a, &mut verts));
            tris.extend([[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]);
        }
        m = TriMesh { vertices: verts, triangles: tris };
    }
    m
}

/// Undirected edge -> the (up to two) triangles that use it.
fn edge_triangles(m: &TriMesh) -> HashMap<(u32, u32), Vec<usize>> {
    let mut e: HashMap<(u32, u32), Vec<usize>> = HashMap::new();
    for (t, tri) in m.triangles.iter().enumerate() {
        for k in 0..3 {
            e.entry(key(tri[k], tri[(k + 1) % 3])).or_default().push(t);
        }
    }
    e
}

/// Edges in a random order (sorted first, so that the order depends on the rng only).
fn shuffled_edges(e: &HashMap<(u32, u32), Vec<usize>>, rng: &mut ChaCha8Rng) -> Vec<(u32, u32)> {
    let mut v: Vec<(u32, u32)> = e.keys().copied().collect();
    v.sort_unstable();
    for i in (1..v.len()).rev() {
        let j = rng.random_range(0..=i);
        v.swap(i, j);
    }
    v
}

/// Split about `fraction` of the edges, each at a random point between 30 % and
/// 70 % of its length: the two triangles of a split edge become four. An edge is
/// split only when neither of its triangles was touched in this pass. Returns how
/// many edges were split.
pub fn split_edges(m: &mut TriMesh, fraction: f64, rng: &mut ChaCha8Rng) -> usize {
    let e = edge_triangles(m);
    let order = shuffled_edges(&e, rng);
    let want = (fraction * order.len() as f64).round() as usize;
    let mut touched = vec![false; m.triangles.len()];
    let mut done = 0;
    for (a, b) in order {
        if done >= want {
            break;
        }
        let ts = &e[&(a, b)];
        if ts.len() != 2 || ts.iter().any(|&t| touched[t]) {
            continue;
        }
        let t = rng.random_range(0.3..0.7);
        m.vertices.push(lerp(m.vertices[a as usize], m.vertices[b as usize], t));
        let p = (m.vertices.len() - 1) as u32;
        for &ti in ts {
            let tri = m.triangles[ti];
            // rotate so that the split edge is tri[0] -> tri[1]
            let k = (0..3).find(|&k| key(tri[k], tri[(k + 1) % 3]) == (a, b)).expect("edge of its triangle");
            let (u, v, w) = (tri[k], tri[(k + 1) % 3], tri[(k + 2) % 3]);
            m.triangles[ti] = [u, p, w];
            m.triangles.push([p, v, w]);
            touched[ti] = true;
        }
        done += 1;
    }
    done
}

/// Insert a point inside about `fraction` of the triangles (barycentric
/// coordinates each at least 0.15), each such triangle becoming three. Returns how
/// many points were inserted.
pub fn insert_points(m: &mut TriMesh, fraction: f64, rng: &mut ChaCha8Rng) -> usize {
    let n = m.triangles.len();
    let mut done = 0;
    for ti in 0..n {
        if rng.random::<f64>() >= fraction {
            continue;
        }
        let (r1, r2): (f64, f64) = (rng.random(), rng.random());
        let (s, t) = (r1.min(r2), r1.max(r2));
        // uniform on the simplex, then pulled towards the centroid
        let w = [s, t - s, 1.0 - t].map(|x| 0.15 + 0.55 * x);
        let [a, b, c] = m.triangles[ti];
        let (pa, pb, pc) = (m.vertices[a as usize], m.vertices[b as usize], m.vertices[c as usize]);
        m.vertices.push(std::array::from_fn(|k| w[0] * pa[k] + w[1] * pb[k] + w[2] * pc[k]));
        let p = (m.vertices.len() - 1) as u32;
        m.triangles[ti] = [a, b, p];
        m.triangles.push([b, c, p]);
        m.triangles.push([c, a, p]);
        done += 1;
    }
    done
}

/// Flip about `fraction` of the edges whose two triangles are coplanar and form a
/// strictly convex quad (the surface does not move), when the new diagonal is not
/// an edge already and neither triangle was touched in this pass. Returns how many
/// edges were flipped.
pub fn flip_coplanar(m: &mut TriMesh, fraction: f64, rng: &mut ChaCha8Rng) -> usize {
    let e = edge_triangles(m);
    let order = shuffled_edges(&e, rng);
    let mut touched = vec![false; m.triangles.len()];
    let mut edges: std::collections::HashSet<(u32, u32)> = e.keys().copied().collect();
    let mut done = 0;
    for (a, b) in order {
        if rng.random::<f64>() >= fraction {
            continue;
        }
        let ts = &e[&(a, b)];
        if ts.len() != 2 || ts.iter().any(|&t| touched[t]) {
            continue;
        }
        // t1 traverses a -> b, t2 b -> a
        let orient = |ti: usize| -> Option<(u32, u32, u32)> {
            let tri = m.triangles[ti];
            (0..3).find(|&k| tri[k] == a && tri[(k + 1) % 3] == b).map(|k| (tri[k], tri[(k + 1) % 3], tri[(k + 2) % 3]))
        };
        let (t1, t2) = match (orient(ts[0]), orient(ts[1])) {
            (Some(_), None) => (ts[0], ts[1]),
            (None, Some(_)) => (ts[1], ts[0]),
            _ => continue,
        };
        let c = orient(t1).expect("oriented").2;
        let tri2 = m.triangles[t2];
        let d = tri2.iter().copied().find(|&v| v != a && v != b).expect("third vertex");
        if c == d || edges.contains(&key(c, d)) {
            continue;
        }
        let p = |v: u32| m.vertices[v as usize];
        let (n1, n2) = (tri_normal(p(a), p(b), p(c)), tri_normal(p(b), p(a), p(d)));
        let (l1, l2) = (norm(n1), norm(n2));
        if l1 <= 0.0 || l2 <= 0.0 || dot(n1, n2) < (1.0 - 1e-9) * l1 * l2 {
            continue;
        }
        // new triangles c, a, d and d, b, c: same facing and not thin
        let (m1, m2) = (tri_normal(p(c), p(a), p(d)), tri_normal(p(d), p(b), p(c)));
        let thin = |n: [f64; 3], x: u32, y: u32, z: u32| {
            let longest = [(x, y), (y, z), (z, x)].iter().map(|&(u, v)| crate::geometry::vec3::dist2(p(u), p(v))).fold(0.0, f64::max);
            norm(n) < 0.05 * longest
        };
        if dot(m1, n1) <= 0.0 || dot(m2, n1) <= 0.0 || thin(m1, c, a, d) || thin(m2, d, b, c) {
            continue;
        }
        m.triangles[t1] = [c, a, d];
        m.triangles[t2] = [d, b, c];
        touched[t1] = true;
        touched[t2] = true;
        edges.remove(&(a, b));
        edges.insert(key(c, d));
        done += 1;
    }
    done
}
