//! The inference tensor: the aligned input mapped onto a candidate context's
//! normalised box, sampled, assigned to cells and laid out as the model expects,
//! with the correspondence (tensor slot -> point on the input surface) and the cheap
//! occupancy pre-check that rejects a context before any diffusion.

use crate::context::{context_frame, Context};
use crate::error::{Error, Result};
use crate::geometry::SurfaceSample;
use crate::polycube::orientation::AxisRotation;
use crate::polycube::primitive::{cell_coords, cell_index, Primitive, NUM_CELLS};
use crate::polycube::tensor::{layout, sort_order, BoxFrame, POINTS_PER_CELL};
use rand::RngExt;
use rand_chacha::ChaCha8Rng;
use serde::Serialize;

/// Default number of surface samples drawn per input (shared by all candidates):
/// 8 per tensor slot, so a cell holding 1/12 of the surface has ~4x what it needs.
pub const DEFAULT_OVERSAMPLING: usize = 8 * POINTS_PER_CELL * NUM_CELLS;

/// Per-axis affine map from the aligned input's bounding box onto the context's
/// normalised box (after the candidate's axis rotation).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct BoxMap {
    pub rotation: AxisRotation,
    pub src_lo: [f64; 3],
    pub src_hi: [f64; 3],
    pub dst_lo: [f64; 3],
    pub dst_hi: [f64; 3],
}

impl BoxMap {
    /// Aligned frame -> model's normalised frame.
    pub fn forward(&self, p: [f64; 3]) -> [f64; 3] {
        let r = self.rotation.apply(p);
        std::array::from_fn(|a| {
            let s = self.src_hi[a] - self.src_lo[a];
            let t = if s > 0.0 { (r[a] - self.src_lo[a]) / s } else { 0.5 };
            self.dst_lo[a] + t * (self.dst_hi[a] - self.dst_lo[a])
        })
    }

    /// Model's normalised frame -> aligned frame.
    pub fn inverse(&self, q: [f64; 3]) -> [f64; 3] {
        let r: [f64; 3] = std::array::from_fn(|a| {
            let d = self.dst_hi[a] - self.dst_lo[a];
            let t = if d > 0.0 { (q[a] - self.dst_lo[a]) / d } else { 0.5 };
            self.src_lo[a] + t * (self.src_hi[a] - self.src_lo[a])
        });
        self.rotation.apply_inverse(r)
    }
}

/// How the input's surface falls into the grid cells for one candidate.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Occupancy {
    /// Fraction of the input's surface area in each cell (sums to 1).
    pub area_fraction: [f64; NUM_CELLS],
    /// Surface fraction in cells the context leaves empty.
    pub in_empty_cells: f64,
    /// Occupied cells that receive less than `min_occupied_fraction` of the area.
    pub starved_cells: Vec<usize>,
}

/// One candidate ready for diffusion.
#[derive(Debug, Clone)]
pub struct InferenceInput {
    pub context: Context,
    pub frame: BoxFrame,
    pub map: BoxMap,
    /// [3, 64, 96] tensor x'_T: the samples after `map` and then `warp`.
    pub tensor: Vec<f32>,
    /// The registration applied after the box map (grid units), if any; the
    /// slots' samples and `map` are the input's own positions.
    pub warp: Option<crate::search::generate::warp::Warp>,
    /// For each tensor slot (cell n, point p -> n * 512 + p): the input surface sample
    /// (in the aligned frame) it came from; None in null cells.
    pub slots: Vec<Option<SurfaceSample>>,
    pub occupancy: Occupancy,
}

/// The normalised box of a context's occupied cells, as (lo, hi) in the model's frame.
pub fn context_box(ctx: &Context) -> Option<(BoxFrame, [f64; 3], [f64; 3])> {
    let frame = context_frame(ctx)?;
    let (lo, hi) = crate::polycube::assembly::occupied_cell_box(&ctx.labels)?;
    Some((frame, frame.to_normalised(lo.map(|v| v as f64)), frame.to_normalised(hi.map(|v| v as f64))))
}

/// Points closer than this (grid units) to an occupied cell are counted in it even
/// when they fall into an empty neighbour: the polycube's surface lies exactly on
/// such cell faces, and a mapped input surface sits on or near them.
pub const CELL_SNAP: f64 = 0.15;

/// The cell a point of the model's frame falls into (clamped into the occupied box);
/// a point within `CELL_SNAP` of an occupied cell goes to that cell rather than to an
/// empty one.
pub fn cell_of(frame: &BoxFrame, lo: [usize; 3], hi: [usize; 3], labels: &[Primitive; NUM_CELLS], q: [f64; 3]) -> usize {
    let g = frame.to_grid(q);
    let clamp = |a: usize, v: f64| (v.floor().max(lo[a] as f64).min((hi[a] - 1) as f64)) as usize;
    let c: [usize; 3] = std::array::from_fn(|a| clamp(a, g[a]));
    let n = cell_index(c[0], c[1], c[2]);
    if labels[n] != Primitive::Null {
        return n;
    }
    let mut best = (f64::INFINITY, n);
    for dx in [-1i32, 0, 1] {
        for dy in [-1i32, 0, 1] {
            for dz in [-1i32, 0, 1] {
                let d = [dx, dy, dz];
                let cand: [usize; 3] = std::array::from_fn(|a| clamp(a, g[a] + d[a] as f64 * CELL_SNAP));
                let m = cell_index(cand[0], cand[1], cand[2]);
                if labels[m] == Primitive::Null {
                    continue;
                }
                // distance from g to cell m's box
                let dist: f64 = (0..3)
                    .map(|a| {
                        let (l, h) = (cand[a] as f64, cand[a] as f64 + 1.0);
                        (l - g[a]).max(0.0).max(g[a] - h)
                    })
                    .map(|v| v * v)
                    .sum::<f64>()
                    .sqrt();
                if dist <= CELL_SNAP * 1.7321 && dist < best.0 {
                    best = (dist, m);
                }
            }
        }
    }
    best.1
}

/// Area fractions per cell for a context's occupancy and a rotation, from (a subset
/// of) the samples: the cheap part of the pre-check, shared by every labelling of the
/// same occupied cells.
pub fn occupancy_only(samples: &[SurfaceSample], ctx: &Context, rotation: AxisRotation, min_occupied_fraction: f64) -> Option<Occupancy> {
    let (frame, dlo, dhi) = context_box(ctx)?;
    let (glo, ghi) = crate::polycube::assembly::occupied_cell_box(&ctx.labels)?;
    let mut slo = [f64::INFINITY; 3];
    let mut shi = [f64::NEG_INFINITY; 3];
    let rotated: Vec<[f64; 3]> = samples.iter().map(|s| rotation.apply(s.point)).collect();
    for r in &rotated {
        for a in 0..3 {
            slo[a] = slo[a].min(r[a]);
            shi[a] = shi[a].max(r[a]);
        }
    }
    let map = BoxMap { rotation: AxisRotation::IDENTITY, src_lo: slo, src_hi: shi, dst_lo: dlo, dst_hi: dhi };
    let mut count = [0usize; NUM_CELLS];
    for r in &rotated {
        count[cell_of(&frame, glo, ghi, &ctx.labels, map.forward(*r))] += 1;
    }
    let total = samples.len().max(1) as f64;
    let area_fraction: [f64; NUM_CELLS] = std::array::from_fn(|n| count[n] as f64 / total);
    let in_empty_cells = (0..NUM_CELLS).filter(|&n| ctx.labels[n] == Primitive::Null).map(|n| area_fraction[n]).sum();
    let occupied: Vec<usize> = ctx.occupied().collect();
    let expected = 1.0 / occupied.len() as f64;
    let starved_cells = occupied.iter().copied().filter(|&n| area_fraction[n] < min_occupied_fraction * expected).collect();
    Some(Occupancy { area_fraction, in_empty_cells, starved_cells })
}

/// Build the inference tensor of one candidate from surface samples of the aligned
/// input (drawn once per input with [`crate::geometry::sample_surface`]).
pub fn prepare(
    samples: &[SurfaceSample],
    ctx: &Context,
    rotation: AxisRotation,
    warp: Option<&crate::search::generate::warp::Warp>,
    min_occupied_fraction: f64,
    rng: &mut ChaCha8Rng,
) -> Result<InferenceInput> {
    if samples.is_empty() {
        return Err(Error::InvalidArgument("no surface samples to lay out".into()));
    }
    let (frame, dlo, dhi) =
        context_box(ctx).ok_or_else(|| Error::InvalidContext("the context has no occupied cell".into()))?;
    let (glo, ghi) = crate::polycube::assembly::occupied_cell_box(&ctx.labels).unwrap();
    let mut slo = [f64::INFINITY; 3];
    let mut shi = [f64::NEG_INFINITY; 3];
    for s in samples {
        let r = rotation.apply(s.point);
        for a in 0..3 {
            slo[a] = slo[a].min(r[a]);
            shi[a] = shi[a].max(r[a]);
        }
    }
    let map = BoxMap { rotation, src_lo: slo, src_hi: shi, dst_lo: dlo, dst_hi: dhi };
    let mut per_cell: Vec<Vec<usize>> = vec![Vec::new(); NUM_CELLS];
    // the tensor holds the samples after the registration, if any (in grid units)
    let mapped: Vec<[f64; 3]> = samples
        .iter()
        .map(|s| {
            let q = map.forward(s.point);
            warp.map_or(q, |w| frame.to_normalised(w.apply(frame.to_grid(q))))
        })
        .collect();
    for (i, q) in mapped.iter().enumerate() {
        per_cell[cell_of(&frame, glo, ghi, &ctx.labels, *q)].push(i);
    }
    let total = samples.len() as f64;
    let area_fraction: [f64; NUM_CELLS] = std::array::from_fn(|n| per_cell[n].len() as f64 / total);
    let in_empty_cells: f64 = (0..NUM_CELLS).filter(|&n| ctx.labels[n] == Primitive::Null).map(|n| area_fraction[n]).sum();
    let occupied: Vec<usize> = ctx.occupied().collect();
    let expected = 1.0 / occupied.len() as f64;
    let starved_cells: Vec<usize> =
        occupied.iter().copied().filter(|&n| area_fraction[n] < min_occupied_fraction * expected).collect();

    let mut cells: Vec<Vec<[f32; 3]>> = vec![Vec::new(); NUM_CELLS];
    let mut slots: Vec<Option<SurfaceSample>> = vec![None; NUM_CELLS * POINTS_PER_CELL];
    for &n in &occupied {
        let mut pick: Vec<usize> = per_cell[n].clone();
        if pick.is_empty() {
            // No surface in this cell: take the samples closest to the cell's centre.
            let [i, j, k] = cell_coords(n);
            let c = frame.to_normalised([i as f64 + 0.5, j as f64 + 0.5, k as f64 + 0.5]);
            let mut idx: Vec<usize> = (0..mapped.len()).collect();
            idx.sort_by(|&a, &b| dist2(mapped[a], c).total_cmp(&dist2(mapped[b], c)));
            pick = idx.into_iter().take(POINTS_PER_CELL).collect();
        }
        if pick.len() >= POINTS_PER_CELL {
            // A seeded partial Fisher-Yates shuffle picks 512 without repetition.
            for i in 0..POINTS_PER_CELL {
                let j = rng.random_range(i..pick.len());
                pick.swap(i, j);
            }
            pick.truncate(POINTS_PER_CELL);
        } else {
            let have = pick.len();
            while pick.len() < POINTS_PER_CELL {
                pick.push(pick[rng.random_range(0..have)]);
            }
        }
        let pts: Vec<[f32; 3]> = pick.iter().map(|&i| mapped[i].map(|v| v as f32)).collect();
        let order = sort_order(&pts);
        cells[n] = order.iter().map(|&o| pts[o]).collect();
        for (p, &o) in order.iter().enumerate() {
            slots[n * POINTS_PER_CELL + p] = Some(samples[pick[o]]);
        }
    }
    Ok(InferenceInput {
        context: *ctx,
        frame,
        map,
        tensor: layout(&cells),
        warp: warp.copied(),
        slots,
        occupancy: Occupancy { area_fraction, in_empty_cells, starved_cells },
    })
}

fn dist2(a: [f64; 3], b: [f64; 3]) -> f64 {
    (a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::sample_surface;
    use crate::geometry::rng::seeded_rng;
    use crate::polycube::tensor::{unlayout, TENSOR_LEN};
    use crate::polycube::{assemble, boundary};

    #[test]
    fn exact_polycube_input_lands_in_its_cells() {
        let ctx = Context::parse("THC+Z,cube,0,0,BHC+X,0,0,0,0,0,0,0").unwrap();
        // The input: the polycube's own surface, normalised like an aligned input.
        let mut m = boundary(&assemble(&ctx.labels)).to_trimesh();
        let frame = context_frame(&ctx).unwrap();
        for v in m.vertices.iter_mut() {
            *v = frame.to_normalised(*v);
        }
        let mut rng = seeded_rng(1, 0);
        let samples = sample_surface(&m, DEFAULT_OVERSAMPLING, &mut rng);
        let inp = prepare(&samples, &ctx, AxisRotation::IDENTITY, None, 0.25, &mut rng).unwrap();
        assert_eq!(inp.tensor.len(), TENSOR_LEN);
        assert!(inp.occupancy.in_empty_cells < 1e-12);
        assert!(inp.occupancy.starved_cells.is_empty());
        let cells = unlayout(&inp.tensor);
        for n in 0..NUM_CELLS {
            let occupied = ctx.labels[n] != Primitive::Null;
            for (p, q) in cells[n].iter().enumerate() {
                let slot = inp.slots[n * POINTS_PER_CELL + p];
                assert_eq!(slot.is_some(), occupied);
                if let Some(s) = slot {
                    // The slot's source sample maps exactly to the tensor point, and lies in cell n.
                    let f = inp.map.forward(s.point);
                    assert!((0..3).all(|a| (f[a] as f32 - q[a]).abs() < 1e-6));
                    let g = frame.to_grid(f);
                    let [i, j, k] = cell_coords(n);
                    assert!(g[0] >= i as f64 - 1e-9 && g[0] <= i as f64 + 1.0 + 1e-9);
                    assert!(g[1] >= j as f64 - 1e-9 && g[1] <= j as f64 + 1.0 + 1e-9);
                    assert!(g[2] >= k as f64 - 1e-9 && g[2] <= k as f64 + 1.0 + 1e-9);
                    // and the source sample is on the input surface
                    let t = m.triangles[s.triangle as usize].map(|v| m.vertices[v as usize]);
                    let b: [f64; 3] = std::array::from_fn(|a| s.bary[0] * t[0][a] + s.bary[1] * t[1][a] + s.bary[2] * t[2][a]);
                    assert!((0..3).all(|a| (b[a] - s.point[a]).abs() < 1e-12));
                } else {
                    assert_eq!(*q, [0.0; 3]);
                }
            }
        }
        // A context that leaves a surface-carrying cell empty is caught by the pre-check.
        let wrong = Context::parse("THC+Z,0,0,0,BHC+X,0,0,0,0,0,0,0").unwrap();
        let w = prepare(&samples, &wrong, AxisRotation::IDENTITY, None, 0.25, &mut rng);
        let in_empty = w.unwrap().occupancy.in_empty_cells;
        assert!(in_empty > 0.15, "{in_empty}");
        // The map round-trips.
        let p = [0.1, -0.2, 0.05];
        let q = inp.map.inverse(inp.map.forward(p));
        assert!((0..3).all(|a| (q[a] - p[a]).abs() < 1e-12));
    }
}
