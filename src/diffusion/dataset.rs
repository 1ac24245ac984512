//! The training set of the paper: all 120 single-cell configurations, the 10 full
//! grids and 4,870 random assemblies, seed 42 (DESIGN.md, "Point tensor").
//!
//! Choices the paper leaves open, recorded here and in docs/polycube.md:
//! - a random assembly draws its occupied count m uniformly in 1..=11, then its cell
//!   set uniformly among the occupancy patterns of m cells that are valid solids when
//!   filled with cubes (face-connected, no edge or corner contact: the patterns a
//!   valid context can have), then each occupied cell's category uniformly in 1..=10;
//! - every sample has its own generator, seeded from (seed, sample index), so the set
//!   is the same whatever the number of threads.

use crate::context::{context_frame, valid_cube_occupancies, Context};
use crate::geometry::rng::seeded_rng;
use crate::polycube::assembly::{boundary, shared_faces, single};
use crate::polycube::primitive::{cell_coords, Primitive, NUM_CELLS};
use crate::polycube::tensor::{layout, sort_order, POINTS_PER_CELL};
use rand::RngExt;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

/// How the data set is made.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct DatasetConfig {
    /// Seed of the whole set (default 42).
    pub seed: u64,
    /// Number of random assemblies (default 4,870).
    pub random: usize,
    /// Half-width of the scale factor s ~ U(1 - j, 1 + j) (default 0.01).
    pub scale_jitter: f64,
}

impl Default for DatasetConfig {
    fn default() -> Self {
        DatasetConfig { seed: 42, random: 4870, scale_jitter: 0.01 }
    }
}

/// One training sample.
#[derive(Debug, Clone)]
pub struct Sample {
    pub context: Context,
    pub scale: f32,
    /// [3, 64, 96] tensor.
    pub tensor: Vec<f32>,
}

/// Boundary quads of each standalone primitive in cell-local coordinates [0,1]^3
/// (index = label; the null entry is empty).
pub fn template_quads() -> &'static Vec<Vec<[[f64; 3]; 4]>> {
    static T: std::sync::OnceLock<Vec<Vec<[[f64; 3]; 4]>>> = std::sync::OnceLock::new();
    T.get_or_init(|| {
        Primitive::ALL
            .iter()
            .map(|&p| {
                if p == Primitive::Null {
                    return Vec::new();
                }
                let q = boundary(&single(p));
                q.quads.iter().map(|f| f.map(|v| q.vertices[v as usize])).collect()
            })
            .collect()
    })
}

/// `n` points uniform by area on primitive `p`'s surface, in cell-local coordinates.
pub fn sample_primitive(p: Primitive, n: usize, rng: &mut ChaCha8Rng) -> Vec<[f64; 3]> {
    sample_primitive_visible(p, 0, n, rng)
}

/// `n` points uniform by area on the part of primitive `p`'s surface off the cell
/// faces `shared` names (bit 2a: the face at the low end of axis a, bit 2a + 1: the
/// high end; see [`shared_faces`]), in cell-local coordinates. A primitive with
/// nothing left (impossible for the ten solids: a cell has at most six shared faces,
/// and its hole walls are never on a face) gives no points.
pub fn sample_primitive_visible(p: Primitive, shared: u8, n: usize, rng: &mut ChaCha8Rng) -> Vec<[f64; 3]> {
    let quads: Vec<&[[f64; 3]; 4]> = template_quads()[p.label() as usize]
        .iter()
        .filter(|q| {
            !(0..3).any(|a| {
                (shared >> (2 * a) & 1 == 1 && q.iter().all(|v| v[a] == 0.0)) || (shared >> (2 * a + 1) & 1 == 1 && q.iter().all(|v| v[a] == 1.0))
            })
        })
        .collect();
    if quads.is_empty() {
        return Vec::new();
    }
    // All quads are squares of the same size: uniform over quads is uniform by area.
    (0..n)
        .map(|_| {
            let q = quads[rng.random_range(0..quads.len())];
            let (u, w): (f64, f64) = (rng.random(), rng.random());
            let mut x = [0.0; 3];
            for a in 0..3 {
                x[a] = q[0][a] + u * (q[1][a] - q[0][a]) + w * (q[3][a] - q[0][a]);
            }
            x
        })
        .collect()
}

/// [`sample_cells`] with each cell's primitive sampled off the faces it shares with
/// occupied neighbours ([`sample_primitive_visible`]): the part of the assembled
/// surface a cell can carry.
pub fn sample_cells_visible(ctx: &Context, scale: f64, rng: &mut ChaCha8Rng) -> Vec<Vec<[f32; 3]>> {
    sample_cells_of(ctx, scale, rng, true)
}

/// Sample the point sets of a context as DESIGN.md fixes them: per occupied cell,
/// 512 points uniform on its primitive's surface at its grid position, normalised by
/// the occupied box and multiplied by `scale`; each cell sorted lexicographically.
pub fn sample_cells(ctx: &Context, scale: f64, rng: &mut ChaCha8Rng) -> Vec<Vec<[f32; 3]>> {
    sample_cells_of(ctx, scale, rng, false)
}

fn sample_cells_of(ctx: &Context, scale: f64, rng: &mut ChaCha8Rng, visible: bool) -> Vec<Vec<[f32; 3]>> {
    let frame = match context_frame(ctx) {
        Some(f) => f,
        None => return vec![Vec::new(); NUM_CELLS],
    };
    (0..NUM_CELLS)
        .map(|n| {
            let p = ctx.labels[n];
            if p == Primitive::Null {
                return Vec::new();
            }
            let [i, j, k] = cell_coords(n);
            let shared = if visible { shared_faces(&ctx.labels, n) } else { 0 };
            let pts: Vec<[f32; 3]> = sample_primitive_visible(p, shared, POINTS_PER_CELL, rng)
                .into_iter()
                .map(|x| {
                    let g = [x[0] + i as f64, x[1] + j as f64, x[2] + k as f64];
                    frame.to_normalised(g).map(|v| (v * scale) as f32)
                })
                .collect();
            let order = sort_order(&pts);
            order.into_iter().map(|o| pts[o]).collect()
        })
        .collect()
}

/// The ordered list of the data set's contexts (120 single-cell, 10 full-grid, random).
pub fn contexts(cfg: &DatasetConfig) -> Vec<Context> {
    let mut out = Vec::with_capacity(130 + cfg.random);
    for n in 0..NUM_CELLS {
        for p in Primitive::solids() {
            let mut l = [Primitive::Null; NUM_CELLS];
            l[n] = p;
            out.push(Context::new(l));
        }
    }
    for p in Primitive::solids() {
        out.push(Context::new([p; NUM_CELLS]));
    }
    let valid = valid_cube_occupancies();
    let by_size: Vec<Vec<u16>> = (0..=NUM_CELLS)
        .map(|m| (1u16..4096).filter(|&mask| valid[mask as usize] && mask.count_ones() as usize == m).collect())
        .collect();
    // the random assemblies draw from one stream past every per-sample one
    const RANDOM_ASSEMBLY_STREAM: u64 = u64::MAX;
    let mut rng = seeded_rng(cfg.seed, RANDOM_ASSEMBLY_STREAM);
    for _ in 0..cfg.random {
        let m = rng.random_range(1..=11usize);
        let masks = &by_size[m];
        let mask = masks[rng.random_range(0..masks.len())];
        let mut l = [Primitive::Null; NUM_CELLS];
        for (n, slot) in l.iter_mut().enumerate() {
            if mask >> n & 1 == 1 {
                *slot = Primitive::ALL[rng.random_range(1..=10usize)];
            }
        }
        out.push(Context::new(l));
    }
    out
}

/// Generate the whole set (parallel, deterministic).
pub fn generate(cfg: &DatasetConfig) -> Vec<Sample> {
    let ctxs = contexts(cfg);
    ctxs.par_iter()
        .enumerate()
        .map(|(i, ctx)| {
            let mut rng = seeded_rng(cfg.seed, i as u64);
            let s = 1.0 + cfg.scale_jitter * (2.0 * rng.random::<f64>() - 1.0);
            let cells = sample_cells(ctx, s, &mut rng);
            Sample { context: *ctx, scale: s as f32, tensor: layout(&cells) }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::polycube::tensor::{unlayout, TENSOR_LEN};

    #[test]
    fn dataset_shape_and_determinism() {
        let cfg = DatasetConfig { random: 20, ..Default::default() };
        let a = generate(&cfg);
        assert_eq!(a.len(), 150);
        let b = generate(&cfg);
        for (x, y) in a.iter().zip(&b) {
            assert_eq!(x.context, y.context);
            assert_eq!(x.tensor, y.tensor);
        }
        // Single-cell configurations first: cell 0 with label 1..10, then cell 1 ...
        assert_eq!(a[0].context.labels[0], Primitive::Cube);
        assert_eq!(a[10].context.labels[1], Primitive::Cube);
        assert_eq!(a[129].context.labels, [Primitive::BhcMy; 12]);
        for s in &a {
            assert_eq!(s.tensor.len(), TENSOR_LEN);
            assert!((0.99..=1.01).contains(&s.scale));
            let cells = unlayout(&s.tensor);
            let mut lo = [f32::MAX; 3];
            let mut hi = [f32::MIN; 3];
            for n in 0..NUM_CELLS {
                let occupied = s.context.labels[n] != Primitive::Null;
                for (i, p) in cells[n].iter().enumerate() {
                    if !occupied {
                        assert_eq!(*p, [0.0; 3]);
                        continue;
                    }
                    for a in 0..3 {
                        lo[a] = lo[a].min(p[a]);
                        hi[a] = hi[a].max(p[a]);
                    }
                    if i > 0 {
                        assert!(cells[n][i - 1][0] <= p[0]);
                    }
                }
            }
            // Longest edge of the occupied box is 2 * s; the box is centred.
            let longest = (0..3).map(|a| hi[a] - lo[a]).fold(0.0, f32::max);
            assert!((longest - 2.0 * s.scale).abs() < 0.05, "{longest}");
            for a in 0..3 {
                assert!((lo[a] + hi[a]).abs() < 0.05);
            }
        }
    }

    #[test]
    fn random_contexts_are_valid_occupancies() {
        let cfg = DatasetConfig { random: 500, ..Default::default() };
        let ctxs = contexts(&cfg);
        let valid = valid_cube_occupancies();
        let mut sizes = [0usize; 13];
        for c in &ctxs[130..] {
            assert!(valid[c.occupancy_mask() as usize]);
            sizes[c.occupancy_mask().count_ones() as usize] += 1;
        }
        assert_eq!(sizes[0], 0);
        assert_eq!(sizes[12], 0);
        assert!(sizes[1..12].iter().all(|&s| s > 20), "{sizes:?}");
    }
}
