//! The geometric deformations of the evaluation set: maps of space (bending,
//! twisting, tapering, a linear map), displacement along vertex normals, Taubin
//! smoothing and a rigid motion with a uniform scale. Coordinates are grid units
//! until the rigid motion.

use crate::geometry::vec3::{add, norm, scale, tri_normal};
use crate::mesh::TriMesh;
use rand::RngExt;
use rand_chacha::ChaCha8Rng;

/// Bounding box centre and extents of the vertices.
pub fn extent(m: &TriMesh) -> ([f64; 3], [f64; 3]) {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for p in &m.vertices {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    (std::array::from_fn(|k| 0.5 * (lo[k] + hi[k])), std::array::from_fn(|k| hi[k] - lo[k]))
}

/// A longest axis of the box (uniformly among the axes within 1 % of the longest).
pub fn long_axis(size: [f64; 3], rng: &mut ChaCha8Rng) -> usize {
    let max = size.iter().copied().fold(0.0, f64::max);
    let axes: Vec<usize> = (0..3).filter(|&a| size[a] >= 0.99 * max).collect();
    axes[rng.random_range(0..axes.len())]
}

/// Bend about an axis: the part curved along `axis` in the plane of `axis` and
/// `towards` (the side the bend turns to: `sign`), through `angle` radians in all
/// over its length. The neutral fibre is the line through the box centre; every
/// slice across `axis` is turned rigidly about the bend's centre of curvature,
/// which lies outside the part (radius = length / angle >= length / 60 deg), so the
/// map is one to one.
pub fn bend(m: &mut TriMesh, axis: usize, towards: usize, sign: f64, angle: f64) {
    let (c, size) = extent(m);
    let r = size[axis] / angle;
    for p in m.vertices.iter_mut() {
        let u = p[axis] - c[axis];
        let w = sign * (p[towards] - c[towards]);
        let phi = u / r;
        let (s, co) = phi.sin_cos();
        p[axis] = c[axis] + (r - w) * s;
        p[towards] = c[towards] + sign * (r - (r - w) * co);
    }
}

/// Twist about `axis` (through the box centre): the slice at distance u from the
/// centre turned by `angle` u / length.
pub fn twist(m: &mut TriMesh, axis: usize, angle: f64) {
    let (c, size) = extent(m);
    let (a1, a2) = ((axis + 1) % 3, (axis + 2) % 3);
    for p in m.vertices.iter_mut() {
        let phi = angle * (p[axis] - c[axis]) / size[axis];
        let (s, co) = phi.sin_cos();
        let (x, y) = (p[a1] - c[a1], p[a2] - c[a2]);
        p[a1] = c[a1] + co * x - s * y;
        p[a2] = c[a2] + s * x + co * y;
    }
}

/// Taper along `axis`: the cross-section scaled by 1 + `rate` u / length about the
/// axis through the box centre (from 1 - rate/2 at one end to 1 + rate/2 at the other).
pub fn taper(m: &mut TriMesh, axis: usize, rate: f64) {
    let (c, size) = extent(m);
    for p in m.vertices.iter_mut() {
        let s = 1.0 + rate * (p[axis] - c[axis]) / size[axis];
        for k in (0..3).filter(|&k| k != axis) {
            p[k] = c[k] + s * (p[k] - c[k]);
        }
    }
}

/// The linear map `a` about the box centre.
pub fn linear(m: &mut TriMesh, a: &[[f64; 3]; 3]) {
    let (c, _) = extent(m);
    for p in m.vertices.iter_mut() {
        let d: [f64; 3] = std::array::from_fn(|k| p[k] - c[k]);
        *p = std::array::from_fn(|i| c[i] + a[i][0] * d[0] + a[i][1] * d[1] + a[i][2] * d[2]);
    }
}

/// Area-weighted unit vertex normals.
pub fn vertex_normals(m: &TriMesh) -> Vec<[f64; 3]> {
    let mut n = vec![[0.0; 3]; m.vertices.len()];
    for t in &m.triangles {
        let [a, b, c] = t.map(|i| m.vertices[i as usize]);
        let f = tri_normal(a, b, c);
        for &v in t {
            n[v as usize] = add(n[v as usize], f);
        }
    }
    n.iter().map(|v| scale(*v, 1.0 / norm(*v).max(1e-300))).collect()
}

/// Vertex neighbours (sorted, unique).
pub fn neighbours(m: &TriMesh) -> Vec<Vec<u32>> {
    let mut nb: Vec<Vec<u32>> = vec![Vec::new(); m.vertices.len()];
    for t in &m.triangles {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            nb[a as usize].push(b);
            nb[b as usize].push(a);
        }
    }
    for v in nb.iter_mut() {
        v.sort_unstable();
        v.dedup();
    }
    nb
}

/// Displace every vertex along its normal by a value uniform in [-amplitude,
/// amplitude], the values first averaged with their neighbours' `smoothing` times
/// (each pass: half the own value, half the neighbours' mean).
pub fn normal_noise(m: &mut TriMesh, amplitude: f64, smoothing: usize, rng: &mut ChaCha8Rng) {
    let normals = vertex_normals(m);
    let nb = neighbours(m);
    let mut d: Vec<f64> = (0..m.vertices.len()).map(|_| rng.random_range(-amplitude..=amplitude)).collect();
    for _ in 0..smoothing {
        d = (0..d.len())
            .map(|v| {
                let n = &nb[v];
                let mean = if n.is_empty() { d[v] } else { n.iter().map(|&u| d[u as usize]).sum::<f64>() / n.len() as f64 };
                0.5 * d[v] + 0.5 * mean
            })
            .collect();
    }
    for (p, (n, dv)) in m.vertices.iter_mut().zip(normals.iter().zip(&d)) {
        *p = add(*p, scale(*n, *dv));
    }
}

/// Taubin smoothing (umbrella operator): `steps` pairs of a shrinking step
/// `lambda` and an inflating step `mu` (< -lambda), which rounds sharp edges and
/// corners while keeping the volume nearly unchanged.
pub fn taubin(m: &mut TriMesh, steps: usize, lambda: f64, mu: f64) {
    let nb = neighbours(m);
    let pass = |m: &mut TriMesh, f: f64| {
        let old = m.vertices.clone();
        for (v, p) in m.vertices.iter_mut().enumerate() {
            let n = &nb[v];
            if n.is_empty() {
                continue;
            }
            let mean: [f64; 3] = std::array::from_fn(|k| n.iter().map(|&u| old[u as usize][k]).sum::<f64>() / n.len() as f64);
            *p = std::array::from_fn(|k| p[k] + f * (mean[k] - p[k]));
        }
    };
    for _ in 0..steps {
        pass(m, lambda);
        pass(m, mu);
    }
}

/// A uniformly distributed unit quaternion (w, x, y, z) (Shoemake's subgroup
/// algorithm, from three uniform numbers).
pub fn random_quaternion(rng: &mut ChaCha8Rng) -> [f64; 4] {
    let (u1, u2, u3): (f64, f64, f64) = (rng.random(), rng.random(), rng.random());
    let tau = std::f64::consts::TAU;
    let (a, b) = ((1.0 - u1).sqrt(), u1.sqrt());
    [b * (tau * u3).cos(), a * (tau * u2).sin(), a * (tau * u2).cos(), b * (tau * u3).sin()]
}

/// The rotation matrix of a unit quaternion (w, x, y, z).
pub fn quaternion_matrix(q: [f64; 4]) -> [[f64; 3]; 3] {
    let [w, x, y, z] = q;
    [
        [w * w + x * x - y * y - z * z, 2.0 * (x * y - w * z), 2.0 * (x * z + w * y)],
        [2.0 * (x * y + w * z), w * w - x * x + y * y - z * z, 2.0 * (y * z - w * x)],
        [2.0 * (x * z - w * y), 2.0 * (y * z + w * x), w * w - x * x - y * y + z * z],
    ]
}

/// p -> s R p + t.
pub fn rigid_motion(m: &mut TriMesh, q: [f64; 4], s: f64, t: [f64; 3]) {
    let r = quaternion_matrix(q);
    for p in m.vertices.iter_mut() {
        let o = *p;
        *p = std::array::from_fn(|i| s * (r[i][0] * o[0] + r[i][1] * o[1] + r[i][2] * o[2]) + t[i]);
    }
}
