//! The input surface as the hex stage uses it: closest-point projection (optionally
//! restricted to triangles facing a given way), sharp-feature curves and corners,
//! and projection onto a feature curve.

use crate::geometry::vec3::*;
use crate::geometry::{closest_point_on_triangle, Aabb, Bvh};
use crate::mesh::TriMesh;
use std::collections::HashMap;

/// A feature curve: a chain of sharp mesh edges (vertex ids of the input surface).
#[derive(Debug, Clone, PartialEq)]
pub struct Curve {
    pub vertices: Vec<u32>,
    pub closed: bool,
}

/// Sharp features of a triangle surface, found from dihedral angles.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Features {
    pub curves: Vec<Curve>,
    /// Feature corners (vertex ids): where sharp edges meet other than two by two,
    /// or where a chain turns sharply.
    pub corners: Vec<u32>,
}

/// The triangles on each edge of `mesh` (key: the edge's vertices, smaller first).
pub fn edge_triangles(mesh: &TriMesh) -> HashMap<(u32, u32), Vec<u32>> {
    let mut m: HashMap<(u32, u32), Vec<u32>> = HashMap::with_capacity(mesh.triangles.len() * 2);
    for (t, tri) in mesh.triangles.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (tri[k], tri[(k + 1) % 3]);
            m.entry((a.min(b), a.max(b))).or_default().push(t as u32);
        }
    }
    m
}

/// Unit normal of every triangle (zero for a degenerate one).
fn unit_normals(mesh: &TriMesh) -> Vec<[f64; 3]> {
    mesh        .triangles
        .iter()
        .map(|t| {
            let n = tri_normal(mesh.vertices[t[0] as usize], mesh.vertices[t[1] as usize], mesh.vertices[t[2] as usize]);
            let l = norm(n);
            if l > 0.0 {
                scale(n, 1.0 / l)
            } else {
                [0.0; 3]
            }
        })
        .collect()
}

/// Detect sharp edges (dihedral angle between the triangle normals above `angle_deg`)
/// on `mesh` and chain them into curves split at corners. A vertex is a corner when
/// its number of sharp edges is not 2, or when its two sharp edges turn by more than
/// `turn_deg`.
pub fn detect_features(mesh: &TriMesh, angle_deg: f64, turn_deg: f64) -> Features {
    let normals = unit_normals(mesh);
    let mut edge_tris: HashMap<[u32; 2], Vec<u32>> = HashMap::new();
    for (t, tri) in mesh.triangles.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (tri[k], tri[(k + 1) % 3]);
            edge_tris.entry(if a < b { [a, b] } else { [b, a] }).or_default().push(t as u32);
        }
    }
    let cos_sharp = angle_deg.to_radians().cos();
    let mut sharp: Vec<[u32; 2]> = edge_tris
        .iter()
        .filter(|(_, ts)| ts.len() != 2 || dot(normals[ts[0] as usize], normals[ts[1] as usize]) < cos_sharp)
        .map(|(e, _)| *e)
        .collect();
    sharp.sort_unstable();
    let nv = mesh.vertices.len();
    let mut adj: Vec<Vec<u32>> = vec![Vec::new(); nv];
    for e in &sharp {
        adj[e[0] as usize].push(e[1]);
        adj[e[1] as usize].push(e[0]);
    }
    let cos_turn = turn_deg.to_radians().cos();
    let mut is_corner = vec![false; nv];
    for v in 0..nv {
        let a = &adj[v];
        if a.is_empty() {
            continue;
        }
        if a.len() != 2 {
            is_corner[v] = true;
            continue;
        }
        let p = mesh.vertices[v];
        let d1 = sub(p, mesh.vertices[a[0] as usize]);
        let d2 = sub(mesh.vertices[a[1] as usize], p);
        let (l1, l2) = (norm(d1), norm(d2));
        if l1 > 0.0 && l2 > 0.0 && dot(d1, d2) / (l1 * l2) < cos_turn {
            is_corner[v] = true;
        }
    }
    // walk chains
    let mut used: HashMap<[u32; 2], bool> = sharp.iter().map(|e| (*e, false)).collect();
    let key = |a: u32, b: u32| if a < b { [a, b] } else { [b, a] };
    let mut curves = Vec::new();
    let walk = |start: u32, next: u32, used: &mut HashMap<[u32; 2], bool>| -> Curve {
        let mut vs = vec![start, next];
        used.insert(key(start, next), true);
        let (mut prev, mut cur) = (start, next);
        loop {
            if is_corner[cur as usize] || cur == start {
                break;
            }
            let n = adj[cur as usize].iter().copied().find(|&w| w != prev && !used[&key(cur, w)]);
            match n {
                Some(w) => {
                    used.insert(key(cur, w), true);
                    vs.push(w);
                    prev = cur;
                    cur = w;
                }
                None => break,
            }
        }
        let closed = vs.len() > 2 && vs.first() == vs.last();
        if closed {
            vs.pop();
        }
        Curve { vertices: vs, closed }
    };
    // chains that start at corners
    for v in 0..nv {
        if !is_corner[v] {
            continue;
        }
        for &w in &adj[v] {
            if !used[&key(v as u32, w)] {
                curves.push(walk(v as u32, w, &mut used));
            }
        }
    }
    // remaining closed loops
    for e in &sharp {
        if !used[e] {
            curves.push(walk(e[0], e[1], &mut used));
        }
    }
    let corners = (0..nv as u32).filter(|&v| is_corner[v as usize]).collect();
    Features { curves, corners }
}

/// Drop feature curves shorter than `min_length` or whose median dihedral angle is
/// below `min_median_angle` degrees (noise of coarse or organic tessellations, where
/// single edges cross the threshold but the surface has no crease) and keep as corners only the vertices where at least three kept
/// curves end, or two kept curves meet at a turn.
pub fn prune_features(mesh: &TriMesh, f: Features, min_length: f64, min_median_angle: f64) -> Features {
    // dihedral angle of every edge used by a curve
    let mut edge_tris: HashMap<[u32; 2], Vec<u32>> = HashMap::new();
    for (t, tri) in mesh.triangles.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (tri[k], tri[(k + 1) % 3]);
            edge_tris.entry(if a < b { [a, b] } else { [b, a] }).or_default().push(t as u32);
        }
    }
    let tri_n = |t: u32| {
        let tr = mesh.triangles[t as usize];
        let n = tri_normal(mesh.vertices[tr[0] as usize], mesh.vertices[tr[1] as usize], mesh.vertices[tr[2] as usize]);
        let l = norm(n);
        if l > 0.0 {
            scale(n, 1.0 / l)
        } else {
            n
        }
    };
    let median_angle = |c: &Curve| -> f64 {
        let n = c.vertices.len();
        let segs = if c.closed { n } else { n - 1 };
        let mut a: Vec<f64> = (0..segs)
            .map(|k| {
                let (u, v) = (c.vertices[k], c.vertices[(k + 1) % n]);
                match edge_tris.get(&if u < v { [u, v] } else { [v, u] }) {
                    Some(ts) if ts.len() == 2 => dot(tri_n(ts[0]), tri_n(ts[1])).clamp(-1.0, 1.0).acos().to_degrees(),
                    _ => 180.0,
                }
            })
            .collect();
        a.sort_by(|x, y| x.total_cmp(y));
        a[a.len() / 2]
    };
    let len = |c: &Curve| {
        let n = c.vertices.len();
        let segs = if c.closed { n } else { n - 1 };
        (0..segs).map(|k| norm(sub(mesh.vertices[c.vertices[(k + 1) % n] as usize], mesh.vertices[c.vertices[k] as usize]))).sum::<f64>()
    };
    let curves: Vec<Curve> =
        f.curves.into_iter().filter(|c| len(c) >= min_length && median_angle(c) >= min_median_angle).collect();
    let mut ends: HashMap<u32, usize> = HashMap::new();
    for c in curves.iter().filter(|c| !c.closed) {
        *ends.entry(c.vertices[0]).or_default() += 1;
        *ends.entry(*c.vertices.last().unwrap()).or_default() += 1;
    }
    let corners = f.corners.into_iter().filter(|v| ends.get(v).copied().unwrap_or(0) >= 2).collect();
    Features { curves, corners }
}

/// A point on a feature curve: segment index and parameter in [0, 1] along it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CurvePoint {
    pub segment: u32,
    pub t: f64,
    pub point: [f64; 3],
    pub distance: f64,
}

/// The surface in one frame, with a BVH and its features' positions.
#[derive(Debug, Clone)]
pub struct Surface {
    pub mesh: TriMesh,
    pub normals: Vec<[f64; 3]>,
    pub bvh: Bvh,
    pub features: Features,
    pub bbox: Aabb,
}

impl Surface {
    pub fn new(mesh: TriMesh, features: Features) -> Surface {
        let normals = unit_normals(&mesh);
        let bvh = Bvh::new(&mesh);
        let bbox = Aabb::of_points(&mesh.vertices);
        Surface { mesh, normals, bvh, features, bbox }
    }

    /// Squared distance from `p` to triangle `t`.
    pub fn dist2_to_triangle(&self, t: u32, p: [f64; 3]) -> f64 {
        let [a, b, c] = self.tri(t);
        dist2(p, closest_point_on_triangle(p, a, b, c).0)
    }

    /// The point of triangle `t` closest to `p`.
    pub fn closest_on_triangle(&self, t: u32, p: [f64; 3]) -> [f64; 3] {
        let [a, b, c] = self.tri(t);
        closest_point_on_triangle(p, a, b, c).0
    }

    fn tri(&self, t: u32) -> [[f64; 3]; 3] {
        self.mesh.triangles[t as usize].map(|v| self.mesh.vertices[v as usize])
    }

    /// Closest surface point: (point, triangle, distance).
    pub fn closest(&self, p: [f64; 3]) -> ([f64; 3], u32, f64) {
        let r = self.bvh.nearest(p, |t| {
            let [a, b, c] = self.tri(t);
            dist2(p, closest_point_on_triangle(p, a, b, c).0)
        });
        match r {
            Some((t, d2)) => {
                let [a, b, c] = self.tri(t);
                (closest_point_on_triangle(p, a, b, c).0, t, d2.sqrt())
            }
            None => (p, u32::MAX, f64::INFINITY),
        }
    }

    /// Closest point among triangles whose normal makes `n . normal >= min_cos` with the
    /// unit vector `n`; falls back to the unrestricted closest point when none qualifies.
    pub fn closest_facing(&self, p: [f64; 3], n: [f64; 3], min_cos: f64) -> ([f64; 3], u32, f64) {
        let r = self.bvh.nearest(p, |t| if dot(self.normals[t as usize], n) < min_cos { f64::INFINITY } else { self.dist2_to_triangle(t, p) });
        match r {
            Some((t, d2)) if d2.is_finite() => (self.closest_on_triangle(t, p), t, d2.sqrt()),
            _ => self.closest(p),
        }
    }

    /// Number of segments of curve `c`.
    pub fn curve_segments(&self, c: usize) -> usize {
        let cv = &self.features.curves[c];
        if cv.closed {
            cv.vertices.len()
        } else {
            cv.vertices.len() - 1
        }
    }

    /// End points of segment `s` of curve `c`.
    pub fn curve_segment(&self, c: usize, s: usize) -> ([f64; 3], [f64; 3]) {
        let cv = &self.features.curves[c];
        let a = cv.vertices[s];
        let b = cv.vertices[(s + 1) % cv.vertices.len()];
        (self.mesh.vertices[a as usize], self.mesh.vertices[b as usize])
    }

    /// Closest point of curve `c` to `p`.
    pub fn closest_on_curve(&self, c: usize, p: [f64; 3]) -> CurvePoint {
        self.closest_on_curve_segments(c, 0..self.curve_segments(c), p)
    }

    /// Closest point to `p` on the segments `segments` of curve `c` (distance
    /// infinite for an empty range).
    pub fn closest_on_curve_segments(&self, c: usize, segments: std::ops::Range<usize>, p: [f64; 3]) -> CurvePoint {
        let mut best = CurvePoint { segment: 0, t: 0.0, point: p, distance: f64::INFINITY };
        for s in segments {
            let (a, b) = self.curve_segment(c, s);
            let ab = sub(b, a);
            let l2 = dot(ab, ab);
            let t = if l2 > 0.0 { (dot(sub(p, a), ab) / l2).clamp(0.0, 1.0) } else { 0.0 };
            let q = add(a, scale(ab, t));
            let d = norm(sub(p, q));
            if d < best.distance {
                best = CurvePoint { segment: s as u32, t, point: q, distance: d };
            }
        }
        best
    }

    /// Unit tangent of curve `c` at a segment.
    pub fn curve_tangent(&self, c: usize, segment: u32) -> [f64; 3] {
        let (a, b) = self.curve_segment(c, segment as usize);
        let d = sub(b, a);
        let l = norm(d);
        if l > 0.0 {
            scale(d, 1.0 / l)
        } else {
            [0.0; 3]
        }
    }

    /// Surface normal of triangle t.
    pub fn normal(&self, t: u32) -> [f64; 3] {
        self.normals.get(t as usize).copied().unwrap_or([0.0; 3])
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::geometry::trimesh::tests::box_mesh;

    #[test]
    fn box_features() {
        let m = box_mesh([0.0; 3], [1.0, 2.0, 3.0]);
        let f = detect_features(&m, 35.0, 45.0);
        assert_eq!(f.corners.len(), 8);
        assert_eq!(f.curves.len(), 12);
        assert!(f.curves.iter().all(|c| c.vertices.len() == 2 && !c.closed));
        let s = Surface::new(m, f);
        let (q, _, d) = s.closest([0.5, 1.0, -1.0]);
        assert!((d - 1.0).abs() < 1e-12 && q[2].abs() < 1e-12);
        let (q, _, _) = s.closest_facing([0.5, 1.0, 0.1], [0.0, -1.0, 0.0], 0.5);
        assert!(q[1].abs() < 1e-12);
    }
}

impl Surface {
    /// Intersections of the line `origin + t * e_axis` (t in [-reach, reach]) with the
    /// surface: (t, triangle) for every crossed triangle.
    pub fn axis_line_hits(&self, origin: [f64; 3], axis: usize, reach: f64) -> Vec<(f64, u32)> {
        let mut lo = origin;
        let mut hi = origin;
        lo[axis] -= reach;
        hi[axis] += reach;
        let bb = Aabb { min: lo, max: hi };
        let mut out = Vec::new();
        let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
        self.bvh.for_each_overlap(&bb, |tri_id| {
            let [a, b, c] = self.tri(tri_id);
            // 2D point-in-triangle in the (u, v) plane, then the axis coordinate
            let d = (b[u] - a[u]) * (c[v] - a[v]) - (c[u] - a[u]) * (b[v] - a[v]);
            if d.abs() < 1e-300 {
                return;
            }
            let (pu, pv) = (origin[u] - a[u], origin[v] - a[v]);
            let l1 = (pu * (c[v] - a[v]) - pv * (c[u] - a[u])) / d;
            let l2 = ((b[u] - a[u]) * pv - (b[v] - a[v]) * pu) / d;
            let l0 = 1.0 - l1 - l2;
            if l0 < 0.0 || l1 < 0.0 || l2 < 0.0 {
                return;
            }
            let x = l0 * a[axis] + l1 * b[axis] + l2 * c[axis];
            let t = x - origin[axis];
            if t.abs() <= reach {
                out.push((t, tri_id));
            }
        });
        out
    }
}
