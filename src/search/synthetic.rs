//! Held-in synthetic inputs for measuring the model and the context search: valid
//! assemblies drawn from a seed other than the training seed, their exact surface
//! subdivided, deformed by a smooth random warp, then rotated, scaled and moved.
//! None of these shapes is in the training set (which holds exact, axis-aligned,
//! normalised primitive samples).

use crate::context::{valid_cube_occupancies, Context};
use crate::geometry::rng::seeded_rng;
use crate::mesh::TriMesh;
use crate::polycube::assembly::{assemble, boundary, check};
use crate::polycube::primitive::{Primitive, NUM_CELLS};
use rand::RngExt;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use std::collections::HashMap;

/// How a synthetic case is made.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default)]
pub struct SyntheticOptions {
    /// Each boundary quad (1/3 cell) is split into `subdivide` x `subdivide`.
    pub subdivide: usize,
    /// Amplitude of the warp, in cell units.
    pub warp_amplitude: f64,
    /// Number of sine modes of the warp.
    pub warp_modes: usize,
    /// Spatial frequency of the modes, in cycles per cell.
    pub warp_frequency: f64,
    /// Apply a uniformly random rotation (SO(3)); otherwise keep the grid axes.
    pub random_rotation: bool,
}

impl Default for SyntheticOptions {
    fn default() -> Self {
        SyntheticOptions { subdivide: 3, warp_amplitude: 0.04, warp_modes: 3, warp_frequency: 0.35, random_rotation: true }
    }
}

/// A valid context with `min..=max` occupied cells (uniform count, then uniform cells
/// among valid occupancy patterns, then uniform labels, redrawn until the assembly is
/// a valid solid).
pub fn random_valid_context(rng: &mut ChaCha8Rng, min: usize, max: usize) -> Context {
    let valid = valid_cube_occupancies();
    loop {
        let m = rng.random_range(min.max(1)..=max.min(NUM_CELLS));
        let masks: Vec<u16> = (1u16..4096).filter(|&k| valid[k as usize] && k.count_ones() as usize == m).collect();
        let mask = masks[rng.random_range(0..masks.len())];
        let mut l = [Primitive::Null; NUM_CELLS];
        for (n, slot) in l.iter_mut().enumerate() {
            if mask >> n & 1 == 1 {
                *slot = Primitive::ALL[rng.random_range(1..=10usize)];
            }
        }
        if check(&assemble(&l)).valid {
            return Context::new(l);
        }
    }
}

/// The exact surface of a context, each lattice quad split `s` x `s`, in grid units.
pub fn subdivided_surface(ctx: &Context, s: usize) -> TriMesh {
    let q = boundary(&assemble(&ctx.labels));
    let s = s.max(1);
    let mut ids: HashMap<[i64; 3], u32> = HashMap::new();
    let mut m = TriMesh::default();
    let fine = (3 * s) as f64;
    let mut vid = |m: &mut TriMesh, p: [f64; 3]| -> u32 {
        let key = p.map(|v| (v * fine).round() as i64);
        *ids.entry(key).or_insert_with(|| {
            m.vertices.push(key.map(|k| k as f64 / fine));
            (m.vertices.len() - 1) as u32
        })
    };
    for quad in &q.quads {
        let c = quad.map(|i| q.vertices[i as usize]);
        let at = |u: usize, v: usize| -> [f64; 3] {
            let (fu, fv) = (u as f64 / s as f64, v as f64 / s as f64);
            std::array::from_fn(|a| c[0][a] + fu * (c[1][a] - c[0][a]) + fv * (c[3][a] - c[0][a]))
        };
        for v in 0..s {
            for u in 0..s {
                let a = vid(&mut m, at(u, v));
                let b = vid(&mut m, at(u + 1, v));
                let cc = vid(&mut m, at(u + 1, v + 1));
                let d = vid(&mut m, at(u, v + 1));
                m.triangles.push([a, b, cc]);
                m.triangles.push([a, cc, d]);
            }
        }
    }
    m
}

/// A deformed, rotated, scaled and translated copy of the context's surface.
pub fn synthetic_mesh(ctx: &Context, opts: &SyntheticOptions, rng: &mut ChaCha8Rng) -> TriMesh {
    let mut m = subdivided_surface(ctx, opts.subdivide);
    let two_pi = std::f64::consts::TAU;
    let modes: Vec<([f64; 3], [f64; 3], f64)> = (0..opts.warp_modes)
        .map(|_| {
            let dir = unit(rng);
            let amp = unit(rng).map(|v| v * opts.warp_amplitude * rng.random_range(0.5..1.0));
            let freq = dir.map(|v| v * opts.warp_frequency * two_pi);
            (freq, amp, rng.random_range(0.0..two_pi))
        })
        .collect();
    for p in m.vertices.iter_mut() {
        let q = *p;
        for (f, a, ph) in &modes {
            let s = (f[0] * q[0] + f[1] * q[1] + f[2] * q[2] + ph).sin();
            for k in 0..3 {
                p[k] += a[k] * s;
            }
        }
    }
    let rot = if opts.random_rotation { random_rotation(rng) } else { [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]] };
    let scale = rng.random_range(0.5..2.0);
    let shift: [f64; 3] = std::array::from_fn(|_| rng.random_range(-5.0..5.0));
    for p in m.vertices.iter_mut() {
        let q = *p;
        *p = std::array::from_fn(|i| scale * (rot[i][0] * q[0] + rot[i][1] * q[1] + rot[i][2] * q[2]) + shift[i]);
    }
    m
}

fn unit(rng: &mut ChaCha8Rng) -> [f64; 3] {
    loop {
        let v: [f64; 3] = std::array::from_fn(|_| StandardNormal.sample(rng));
        let n = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        if n > 1e-6 {
            return v.map(|x| x / n);
        }
    }
}

/// A uniformly random rotation matrix (from a random unit quaternion).
pub fn random_rotation(rng: &mut ChaCha8Rng) -> [[f64; 3]; 3] {
    let q: [f64; 4] = loop {
        let v: [f64; 4] = std::array::from_fn(|_| StandardNormal.sample(rng));
        let n = v.iter().map(|x| x * x).sum::<f64>().sqrt();
        if n > 1e-6 {
            break v.map(|x| x / n);
        }
    };
    let [w, x, y, z] = q;
    [
        [1.0 - 2.0 * (y * y + z * z), 2.0 * (x * y - w * z), 2.0 * (x * z + w * y)],
        [2.0 * (x * y + w * z), 1.0 - 2.0 * (x * x + z * z), 2.0 * (y * z - w * x)],
        [2.0 * (x * z - w * y), 2.0 * (y * z + w * x), 1.0 - 2.0 * (x * x + y * y)],
    ]
}

/// Complexity groups of the paper's scalability table (occupied cells).
pub const GROUPS: [(&str, usize, usize); 3] = [("simple", 1, 3), ("medium", 4, 6), ("complex", 7, 12)];

/// `n` cases of a group: (true context, mesh), from `seed` (never 42, the training seed).
pub fn cases(seed: u64, n: usize, min: usize, max: usize, opts: &SyntheticOptions) -> Vec<(Context, TriMesh)> {
    (0..n)
        .map(|i| {
            let mut rng = seeded_rng(seed, i as u64);
            let ctx = random_valid_context(&mut rng, min, max);
            let m = synthetic_mesh(&ctx, opts, &mut rng);
            (ctx, m)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn synthetic_meshes_are_closed_with_the_context_genus() {
        for (ctx, m) in cases(7, 6, 1, 6, &SyntheticOptions::default()) {
            let g = ctx.validity().genus.unwrap();
            // Euler characteristic of the welded surface.
            let mut edges = std::collections::HashSet::new();
            for t in &m.triangles {
                for e in 0..3 {
                    let (a, b) = (t[e], t[(e + 1) % 3]);
                    edges.insert((a.min(b), a.max(b)));
                }
            }
            let chi = m.vertices.len() as i64 - edges.len() as i64 + m.triangles.len() as i64;
            assert_eq!(chi, 2 - 2 * g, "{ctx}");
        }
    }
}
