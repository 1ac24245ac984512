//! A smooth registration of the input onto a candidate's polycube: the quadratic
//! map, near the identity, that brings the input's samples (in the candidate's
//! grid units, after the box map) closest to the polycube's surface.
//!
//! The box map only scales the input's bounding box onto the context's box. A
//! bent, twisted or tapered part then lies far from the polycube it is made of
//! (a bend of a few tens of degrees puts whole cells a cell away), and the rigid
//! fit refuses its right context before the model is asked, or the model is
//! given an input it was never trained to straighten. Bending (y + k x^2),
//! twisting (rotation angle linear along an axis: y - t x z, z + t x y, to first
//! order), tapering (y (1 + a x)), shear and anisotropic scaling are all
//! quadratic or lower in the coordinates, so one quadratic map per coordinate
//! (ten monomials about the samples' centroid) takes them out, while a hole a
//! label has and the input lacks, or a hole along another axis, is no quadratic
//! image of the input and keeps its distance. The map is found by iterated
//! closest points in both directions, each pair weighted by 1 / (1 + d^2 /
//! `WARP_TAU`) so that what no smooth map explains pulls little, with a ridge
//! pull towards the identity; a map that folds (Jacobian determinant at a sample
//! at most [`MIN_JACOBIAN`]) is not used.

use super::fit::fit_points;
use crate::context::Context;
use crate::geometry::SurfaceSample;
use crate::polycube::orientation::AxisRotation;
use crate::polycube::NUM_CELLS;
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use nalgebra::DMatrix;

/// Monomials of the map: 1, x, y, z, x^2, xy, xz, y^2, yz, z^2 (about the centre).
pub const MONOMIALS: usize = 10;

/// Registration iterations (closest points, then the weighted least squares).
pub const WARP_ITERATIONS: usize = 12;

/// Weight of a pair: 1 / (1 + d^2 / this) (squared grid units).
pub const WARP_TAU: f64 = 0.03;

/// Ridge weight of the quadratic terms, relative to the pairs' total weight
/// (grid units: a cell is 1).
pub const WARP_RIDGE: f64 = 0.01;

/// Ridge weight of the affine terms, relative to the quadratic terms' (an
/// affine stretch of the bounding box is cheap, a curvature less so).
pub const WARP_AFFINE_RIDGE: f64 = 0.05;

/// A map whose Jacobian determinant falls to this at a sample folds or nearly
/// so, and is not used.
pub const MIN_JACOBIAN: f64 = 0.3;

/// Fewest input and target points for a registration.
const MIN_POINTS: usize = 32;

/// x -> x + sum_k coef[k] m_k(x - centre), m the [`MONOMIALS`] monomials.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Warp {
    pub centre: [f64; 3],
    pub coef: [[f64; 3]; MONOMIALS],
}

fn monomials(d: [f64; 3]) -> [f64; MONOMIALS] {
    let [a, b, c] = d;
    [1.0, a, b, c, a * a, a * b, a * c, b * b, b * c, c * c]
}

impl Warp {
    /// The warped point.
    pub fn apply(&self, x: [f64; 3]) -> [f64; 3] {
        let m = monomials(std::array::from_fn(|a| x[a] - self.centre[a]));
        std::array::from_fn(|k| x[k] + (0..MONOMIALS).map(|j| self.coef[j][k] * m[j]).sum::<f64>())
    }

    /// The determinant of the map's Jacobian at `x`.
    pub fn jacobian_det(&self, x: [f64; 3]) -> f64 {
        let [a, b, c] = std::array::from_fn::<f64, 3, _>(|i| x[i] - self.centre[i]);
        // derivatives of the monomials along x, y, z
        let dm: [[f64; MONOMIALS]; 3] = [
            [0.0, 1.0, 0.0, 0.0, 2.0 * a, b, c, 0.0, 0.0, 0.0],
            [0.0, 0.0, 1.0, 0.0, 0.0, a, 0.0, 2.0 * b, c, 0.0],
            [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, a, 0.0, b, 2.0 * c],
        ];
        let j = nalgebra::Matrix3::from_fn(|k, d| f64::from(u8::from(k == d)) + (0..MONOMIALS).map(|m| self.coef[m][k] * dm[d][m]).sum::<f64>());
        j.determinant()
    }
}

/// The quadratic map, near the identity, that brings `p` onto `q` (see the
/// module docs); None when there are too few points, a least-squares system is
/// singular, or the map folds at one of `p`.
pub fn register_warp(p: &[[f64; 3]], q: &[[f64; 3]]) -> Option<Warp> {
    if p.len() < MIN_POINTS || q.len() < MIN_POINTS {
        return None;
    }
    let n = p.len() as f64;
    let centre: [f64; 3] = std::array::from_fn(|a| p.iter().map(|x| x[a]).sum::<f64>() / n);
    let tq = ImmutableKdTree::new_from_slice(q).expect("non-empty");
    let mut w = Warp { centre, coef: [[0.0; 3]; MONOMIALS] };
    for _ in 0..WARP_ITERATIONS {
        let moved: Vec<[f64; 3]> = p.iter().map(|x| w.apply(*x)).collect();
        let tp = ImmutableKdTree::new_from_slice(&moved).expect("non-empty");
        let mut ata = DMatrix::<f64>::zeros(MONOMIALS, MONOMIALS);
        let mut atb = DMatrix::<f64>::zeros(MONOMIALS, 3);
        let mut total = 0.0;
        let mut add = |x: [f64; 3], y: [f64; 3], d2: f64| {
            let wt = 1.0 / (1.0 + d2 / WARP_TAU);
            let m = monomials(std::array::from_fn(|a| x[a] - centre[a]));
            total += wt;
            for i in 0..MONOMIALS {
                for j in 0..MONOMIALS {
                    ata[(i, j)] += wt * m[i] * m[j];
                }
                for k in 0..3 {
                    atb[(i, k)] += wt * m[i] * (y[k] - x[k]);
                }
            }
        };
        for (x, m) in p.iter().zip(&moved) {
            let nn = tq.query(m).nearest_one::<SquaredEuclidean<f64>>().execute();
            add(*x, q[nn.item as usize], nn.distance);
        }
        for y in q {
            let nn = tp.query(y).nearest_one::<SquaredEuclidean<f64>>().execute();
            add(p[nn.item as usize], *y, nn.distance);
        }
        for i in 1..MONOMIALS {
            ata[(i, i)] += WARP_RIDGE * total * if i < 4 { WARP_AFFINE_RIDGE } else { 1.0 };
        }
        let sol = ata.lu().solve(&atb)?;
        let mut next = w;
        for i in 0..MONOMIALS {
            for k in 0..3 {
                next.coef[i][k] = sol[(i, k)];
            }
        }
        let change: f64 = (0..MONOMIALS).flat_map(|i| (0..3).map(move |k| (i, k))).map(|(i, k)| (next.coef[i][k] - w.coef[i][k]).abs()).sum();
        w = next;
        if change < 1e-6 {
            break;
        }
    }
    p.iter().all(|x| w.jacobian_det(*x) > MIN_JACOBIAN).then_some(w)
}

/// Per-cell penalty Chamfer fits of points `p` (grid units, each with its cell)
/// against `target` (points with cells), as [`super::fit_score_cells`] takes them.
pub fn cell_fits(p: &[[f64; 3]], cells: &[usize], target: &[[f64; 3]], target_cells: &[usize]) -> [f64; NUM_CELLS] {
    if p.is_empty() || target.is_empty() {
        return [f64::INFINITY; NUM_CELLS];
    }
    let f = super::fit::fit_penalty;
    let t_in = ImmutableKdTree::new_from_slice(p).expect("non-empty");
    let t_tg = ImmutableKdTree::new_from_slice(target).expect("non-empty");
    let mut sum_in = [0.0f64; NUM_CELLS];
    let mut n_in = [0usize; NUM_CELLS];
    for (x, &c) in p.iter().zip(cells) {
        sum_in[c] += f(t_tg.query(x).nearest_one::<SquaredEuclidean<f64>>().execute().distance);
        n_in[c] += 1;
    }
    let mut sum_tg = [0.0f64; NUM_CELLS];
    let mut n_tg = [0usize; NUM_CELLS];
    for (y, &c) in target.iter().zip(target_cells) {
        sum_tg[c] += f(t_in.query(y).nearest_one::<SquaredEuclidean<f64>>().execute().distance);
        n_tg[c] += 1;
    }
    let mut out = [f64::NAN; NUM_CELLS];
    for c in 0..NUM_CELLS {
        if n_tg[c] == 0 {
            continue;
        }
        let a = if n_in[c] > 0 { sum_in[c] / n_in[c] as f64 } else { f64::INFINITY };
        out[c] = 0.5 * (a + sum_tg[c] / n_tg[c] as f64);
    }
    out
}

/// The per-cell fits of the box-mapped samples `grid` (grid units) against the
/// polycube points `q` (with cells `qc`) after the quadratic registration
/// ([`register_warp`]), with the map; None when no map was found. The samples
/// are given to the cells where they land after the map.
fn warped_fit(grid: &[[f64; 3]], ctx: &Context, q: &[[f64; 3]], qc: &[usize]) -> Option<(Warp, [f64; NUM_CELLS])> {
    let w = register_warp(grid, q)?;
    let (frame, _, _) = crate::search::inference::context_box(ctx)?;
    let (glo, ghi) = crate::polycube::assembly::occupied_cell_box(&ctx.labels)?;
    let moved: Vec<[f64; 3]> = grid.iter().map(|x| w.apply(*x)).collect();
    let cells: Vec<usize> = moved.iter().map(|g| crate::search::inference::cell_of(&frame, glo, ghi, &ctx.labels, frame.to_normalised(*g))).collect();
    Some((w, cell_fits(&moved, &cells, q, qc)))
}

/// A candidate's fit (worst cell, mean over the cells) of the input under
/// `rotation` against the context's polycube `target`: the rigid fit of
/// [`super::fit_score_cells`] or, with `warp` and when it is lower, the fit
/// after the registration, with the map. The samples are box-mapped once for
/// both.
pub fn candidate_fit(samples: &[SurfaceSample], ctx: &Context, rotation: AxisRotation, target: &[([f64; 3], usize)], warp: bool) -> ((f64, f64), Option<Warp>) {
    let infinite = ((f64::INFINITY, f64::INFINITY), None);
    let Some((grid, cells)) = fit_points(samples, ctx, rotation, [1.0; 3]) else { return infinite };
    if target.is_empty() {
        return infinite;
    }
    let q: Vec<[f64; 3]> = target.iter().map(|t| t.0).collect();
    let qc: Vec<usize> = target.iter().map(|t| t.1).collect();
    let rigid = super::worst_and_mean(&cell_fits(&grid, &cells, &q, &qc));
    if !warp {
        return (rigid, None);
    }
    match warped_fit(&grid, ctx, &q, &qc) {
        Some((w, fits)) if super::worst_and_mean(&fits).0 < rigid.0 => (super::worst_and_mean(&fits), Some(w)),
        _ => (rigid, None),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::search::generate::polycube_samples;

    fn split(t: &[([f64; 3], usize)]) -> (Vec<[f64; 3]>, Vec<usize>) {
        (t.iter().map(|x| x.0).collect(), t.iter().map(|x| x.1).collect())
    }

    fn worst(c: &[f64; NUM_CELLS]) -> f64 {
        super::super::worst_and_mean(c).0
    }

    #[test]
    fn a_bent_and_twisted_row_registers_onto_its_polycube() {
        let ctx = Context::parse("cube,cube,cube,0,0,0,0,0,0,0,0,0").unwrap();
        let (q, qc) = split(&polycube_samples(&ctx, 4096));
        // bend along y and twist about x (first order), both quadratic in the coordinates
        let p: Vec<[f64; 3]> = q.iter().map(|x| [x[0], x[1] + 0.35 * (x[0] - 1.5).powi(2) + 0.1 * (x[0] - 1.5) * (x[2] - 0.5), x[2] - 0.1 * (x[0] - 1.5) * (x[1] - 0.5)]).collect();
        let rigid = worst(&cell_fits(&p, &qc, &q, &qc));
        let w = register_warp(&p, &q).expect("a map that does not fold");
        let moved: Vec<[f64; 3]> = p.iter().map(|x| w.apply(*x)).collect();
        let warped = worst(&cell_fits(&moved, &qc, &q, &qc));
        // within the pre-check's absolute fit limit (PolycubeOptions::max_fit, 0.05)
        assert!(warped < 0.01 * rigid && warped < 0.05, "rigid {rigid}, after the registration {warped}");
    }

    #[test]
    fn the_registration_cannot_make_a_hole_the_input_lacks() {
        let cube = Context::parse("cube,0,0,0,0,0,0,0,0,0,0,0").unwrap();
        let (p, pc) = split(&polycube_samples(&cube, 4096));
        let right = {
            let w = register_warp(&p, &p).expect("the identity");
            let moved: Vec<[f64; 3]> = p.iter().map(|x| w.apply(*x)).collect();
            worst(&cell_fits(&moved, &pc, &p, &pc))
        };
        for wrong in ["THC+Z", "THC+X", "BHC+Y", "BHC-Z"] {
            let ctx = Context::parse(&format!("{wrong},0,0,0,0,0,0,0,0,0,0,0")).unwrap();
            let (q, qc) = split(&polycube_samples(&ctx, 4096));
            let fit = match register_warp(&p, &q) {
                Some(w) => worst(&cell_fits(&p.iter().map(|x| w.apply(*x)).collect::<Vec<_>>(), &pc, &q, &qc)),
                None => f64::INFINITY,
            };
            assert!(fit > 10.0 * right.max(1e-4), "{wrong}: a plain cube fits {fit} after the registration (its own template {right})");
        }
    }
}
