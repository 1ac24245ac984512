//! The geometric fit score of a context against the input, and the refusal of a
//! context that a one-cell relabelling fits much better.

use super::*;

/// The fit score is a penalty Chamfer distance with this threshold (squared cell
/// units: 0.1 cell), so that a missing or extra hole, whose points lie 1/6 cell or
/// more from the other surface, weighs far more than a smooth deformation.
pub const FIT_TAU: f64 = 0.01;

/// The fit score's penalty of a squared distance `d`: `d` up to [`FIT_TAU`],
/// `d (1 + (d / FIT_TAU)^2)` above it.
pub fn fit_penalty(d: f64) -> f64 {
    if d <= FIT_TAU {
        d
    } else {
        d * (1.0 + (d / FIT_TAU).powi(2))
    }
}

/// Samples used by the geometric fit score.
pub const FIT_SAMPLES: usize = 2048;

/// `n` points uniform on the exact boundary of a context's assembly, in grid units,
/// each with the cell of the voxel it bounds.
pub fn polycube_samples(ctx: &Context, n: usize) -> Vec<([f64; 3], usize)> {
    let q = crate::polycube::boundary(&ctx.assemble());
    if q.quads.is_empty() {
        return Vec::new();
    }
    const POLYCUBE_SAMPLES_SEED: u64 = 0xf17;
    let mut rng = seeded_rng(POLYCUBE_SAMPLES_SEED, ctx.occupancy_mask() as u64);
    use rand::RngExt;
    (0..n)
        .map(|_| {
            let k = rng.random_range(0..q.quads.len());
            let f = q.quads[k].map(|i| q.vertices[i as usize]);
            let v = q.quad_voxel[k].0;
            let (u, w): (f64, f64) = (rng.random(), rng.random());
            let p = std::array::from_fn(|a| f[0][a] + u * (f[1][a] - f[0][a]) + w * (f[3][a] - f[0][a]));
            (p, crate::polycube::cell_index(v[0] / 3, v[1] / 3, v[2] / 3))
        })
        .collect()
}

/// Geometric fit of the input to a context (squared cell units; lower is better): the
/// input samples are mapped onto the context's box under `rotation` and compared with
/// the exact polycube surface `target` by a penalty Chamfer distance per cell (each
/// point's distance to the whole other set, averaged over the points of that cell);
/// the score is the worst cell's. A missing, extra or misdirected hole in one cell
/// shows up in full instead of being diluted by the other cells.
pub fn fit_score(samples: &[SurfaceSample], ctx: &Context, rotation: AxisRotation, target: &[([f64; 3], usize)]) -> f64 {
    fit_score_scaled(samples, ctx, rotation, target, [1.0; 3])
}

/// The per-cell values of [`fit_score_scaled`] (NaN for unoccupied cells, infinite
/// when the mapping or a cell's input is empty).
pub fn fit_score_cells(samples: &[SurfaceSample], ctx: &Context, rotation: AxisRotation, target: &[([f64; 3], usize)], scale: [f64; 3]) -> [f64; NUM_CELLS] {
    let Some((grid_in, cells_in)) = fit_points(samples, ctx, rotation, scale) else { return [f64::INFINITY; NUM_CELLS] };
    let tgt: Vec<[f64; 3]> = target.iter().map(|t| std::array::from_fn(|a| t.0[a] * scale[a])).collect();
    let tgt_cells: Vec<usize> = target.iter().map(|t| t.1).collect();
    super::warp::cell_fits(&grid_in, &cells_in, &tgt, &tgt_cells)
}

/// The input samples as [`fit_score_cells`] compares them: rotated by `rotation`,
/// their bounding box mapped onto the context's box, in grid units times `scale`
/// per axis, each with the cell it falls in. None when the context has no
/// occupied cell or there are no samples.
pub fn fit_points(samples: &[SurfaceSample], ctx: &Context, rotation: AxisRotation, scale: [f64; 3]) -> Option<(Vec<[f64; 3]>, Vec<usize>)> {
    let (frame, dlo, dhi) = crate::search::inference::context_box(ctx)?;
    let (glo, ghi) = crate::polycube::assembly::occupied_cell_box(&ctx.labels)?;
    if samples.is_empty() {
        return None;
    }
    let rotated: Vec<[f64; 3]> = samples.iter().map(|s| rotation.apply(s.point)).collect();
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for r in &rotated {
        for a in 0..3 {
            lo[a] = lo[a].min(r[a]);
            hi[a] = hi[a].max(r[a]);
        }
    }
    let map = crate::search::inference::BoxMap { rotation: AxisRotation::IDENTITY, src_lo: lo, src_hi: hi, dst_lo: dlo, dst_hi: dhi };
    let mapped: Vec<[f64; 3]> = rotated.iter().map(|r| map.forward(*r)).collect();
    let cells_in: Vec<usize> = mapped.iter().map(|q| crate::search::inference::cell_of(&frame, glo, ghi, &ctx.labels, *q)).collect();
    let grid_in: Vec<[f64; 3]> = mapped.iter().map(|q| frame.to_grid(*q)).map(|g| std::array::from_fn(|a| g[a] * scale[a])).collect();
    Some((grid_in, cells_in))
}

/// [`fit_score`] with the grid coordinates multiplied by `scale` per axis before the
/// distances are taken: with the part's cell widths over a common length as the
/// scale, fits of boxes with different cell counts become comparable (a single
/// stretched cell is not favoured over three cells of the same part just because its
/// cell is three times longer). The worst cell of [`fit_score_cells`].
pub fn fit_score_scaled(samples: &[SurfaceSample], ctx: &Context, rotation: AxisRotation, target: &[([f64; 3], usize)], scale: [f64; 3]) -> f64 {
    worst_and_mean(&fit_score_cells(samples, ctx, rotation, target, scale)).0
}

/// The worst and the mean of per-cell fits ([`fit_score_cells`]; NaN cells are
/// unoccupied); both infinite when a cell's fit is.
pub fn worst_and_mean(cells: &[f64; NUM_CELLS]) -> (f64, f64) {
    if cells.iter().any(|c| c.is_infinite()) {
        return (f64::INFINITY, f64::INFINITY);
    }
    let occupied: Vec<f64> = cells.iter().copied().filter(|c| !c.is_nan()).collect();
    let worst = occupied.iter().fold(0.0, |w: f64, c| w.max(*c));
    let mean = if occupied.is_empty() { 0.0 } else { occupied.iter().sum::<f64>() / occupied.len() as f64 };
    (worst, mean)
}

/// The best-fitting one-cell alternative of a candidate's context: every occupied cell
/// given every other non-null label whose assembly stays valid with the same genus,
/// fitted under the candidate's orientation as the candidate was (the same box since
/// the occupancy is unchanged; after the registration when the candidate's fit was,
/// [`super::warp::candidate_fit`]). Returns (cell, label, fit) of the best one, or None when
/// the context has no such alternative.
pub fn best_neighbour(input: &PreparedInput, c: &Candidate) -> Option<(usize, Primitive, f64)> {
    let genus = c.context.validity().genus?;
    let fit_sub = &input.samples[..input.samples.len().min(FIT_SAMPLES)];
    let mut alts = Vec::new();
    for n in c.context.occupied() {
        for &l in &Primitive::ALL[1..] {
            if l == c.context.labels[n] {
                continue;
            }
            let mut w = c.context;
            w.labels[n] = l;
            if w.validity().genus == Some(genus) {
                alts.push((n, l, w));
            }
        }
    }
    use rayon::prelude::*;
    alts.par_iter()
        .map(|(n, l, w)| (*n, *l, super::warp::candidate_fit(fit_sub, w, c.axis_rotation, &polycube_samples(w, FIT_SAMPLES), c.warped).0 .0))
        .min_by(|a, b| a.2.total_cmp(&b.2))
}

/// The neighbour test of the pre-check: a pending candidate whose fit is more than
/// `ratio` times the fit of its best one-cell alternative ([`best_neighbour`]) is
/// refused (stage `Occupancy`) with the cell, both labels and both fits in its
/// `refusal`. `ratio <= 0` turns the test off.
pub fn refuse_worse_than_neighbours(input: &PreparedInput, cands: &mut [Candidate], ratio: f64) {
    if !(ratio > 0.0) {
        return;
    }
    for c in cands.iter_mut().filter(|c| c.stage == Stage::Pending) {
        let Some((n, l, f)) = best_neighbour(input, c) else { continue };
        if c.fit > ratio * f {
            let [x, y, z] = crate::polycube::cell_coords(n);
            c.refusal = Some(format!(
                "cell {n} ({x}, {y}, {z}): the context fits the input {:.1}x better with {} in this cell than with the given {} (geometric fit {:.4} against {:.4}, squared cell units; refused above {ratio}x)",
                c.fit / f,
                l.name(),
                c.context.labels[n].name(),
                f,
                c.fit
            ));
            c.stage = Stage::Occupancy;
            c.input = None;
        }
    }
}
