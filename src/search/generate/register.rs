//! The fit of one cell after a local affine registration: the input's points in
//! the cell are moved by the affine map, near the identity, that brings them
//! closest to the cell's part of the assembly before the penalty Chamfer
//! distance is taken.
//!
//! A part that is twisted, tapered, bent or sheared is, over one cell, close to
//! an affine image of its undeformed shape, and the rigid in-context fit of
//! [`super::fit_score_cells`] scores such a cell against a template it no longer
//! lines up with: a twisted through-hole cube can fit a blind hole or a hole of
//! another axis better than its own. Registering the cell first takes out what an
//! affine map explains and leaves what it cannot (a missing, extra or
//! misdirected hole), which is what tells the labels apart. The map is kept near
//! the identity (a rotation of at most [`MAX_ROTATION_DEG`], stretches within
//! [`MAX_STRETCH`]), so that it cannot turn one label into another (a hole of
//! another axis is a quarter turn away, a blind hole of the opposite side half a
//! turn).

use super::fit::fit_penalty;
use super::FIT_TAU;
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use nalgebra::{Matrix3, Vector3};

/// Largest rotation (degrees) of the registration's polar part.
pub const MAX_ROTATION_DEG: f64 = 30.0;

/// Stretches (singular values of the linear part) stay within [1 / this, this].
pub const MAX_STRETCH: f64 = 1.5;

/// Registration iterations (closest points, then the weighted least-squares map).
pub const REGISTER_ITERATIONS: usize = 8;

/// Weight of the pull towards the identity, relative to the points' spread.
const IDENTITY_WEIGHT: f64 = 0.05;

/// Fewest input points of the cell for a registration (fewer: the plain fit).
const MIN_POINTS: usize = 16;

/// The penalty Chamfer distance between `p` and `q` (squared distances under
/// [`fit_penalty`], as [`super::fit_score_cells`] takes them), the mean of both
/// directions; infinite when either set is empty.
pub fn cell_chamfer(p: &[[f64; 3]], q: &[[f64; 3]]) -> f64 {
    if p.is_empty() || q.is_empty() {
        return f64::INFINITY;
    }
    let f = fit_penalty;
    let tp = ImmutableKdTree::new_from_slice(p).expect("non-empty");
    let tq = ImmutableKdTree::new_from_slice(q).expect("non-empty");
    let a: f64 = p.iter().map(|x| f(tq.query(x).nearest_one::<SquaredEuclidean<f64>>().execute().distance)).sum::<f64>() / p.len() as f64;
    let b: f64 = q.iter().map(|x| f(tp.query(x).nearest_one::<SquaredEuclidean<f64>>().execute().distance)).sum::<f64>() / q.len() as f64;
    0.5 * (a + b)
}

/// The cell fit of the input points `p` against the target points `q` (both of
/// one cell): the smaller of the plain [`cell_chamfer`] and the one after
/// [`register`].
pub fn registered_fit(p: &[[f64; 3]], q: &[[f64; 3]]) -> f64 {
    let plain = cell_chamfer(p, q);
    if p.len() < MIN_POINTS || q.len() < MIN_POINTS {
        return plain;
    }
    let (a, t) = register(p, q);
    let moved: Vec<[f64; 3]> = p.iter().map(|x| apply(&a, &t, *x)).collect();
    plain.min(cell_chamfer(&moved, q))
}

fn apply(a: &Matrix3<f64>, t: &Vector3<f64>, x: [f64; 3]) -> [f64; 3] {
    let y = a * Vector3::from(x) + t;
    [y.x, y.y, y.z]
}

/// The affine map x -> A x + t, near the identity, that brings `p` onto `q`:
/// iterated closest points in both directions, each pair weighted by
/// 1 / (1 + d^2 / FIT_TAU) so that the parts no map explains (a hole one set has
/// and the other lacks) pull little, then the weighted least-squares map with a
/// pull towards the identity. A step whose map leaves the allowed rotation or
/// stretch ends the iteration with the map before it.
pub fn register(p: &[[f64; 3]], q: &[[f64; 3]]) -> (Matrix3<f64>, Vector3<f64>) {
    let tq = ImmutableKdTree::new_from_slice(q).expect("non-empty");
    let mut a = Matrix3::identity();
    let mut t = Vector3::zeros();
    for _ in 0..REGISTER_ITERATIONS {
        let moved: Vec<[f64; 3]> = p.iter().map(|x| apply(&a, &t, *x)).collect();
        let tp = ImmutableKdTree::new_from_slice(&moved).expect("non-empty");
        // (source point, target point, weight)
        let mut pairs: Vec<(Vector3<f64>, Vector3<f64>, f64)> = Vec::with_capacity(p.len() + q.len());
        for (x, m) in p.iter().zip(&moved) {
            let nn = tq.query(m).nearest_one::<SquaredEuclidean<f64>>().execute();
            pairs.push((Vector3::from(*x), Vector3::from(q[nn.item as usize]), 1.0 / (1.0 + nn.distance / FIT_TAU)));
        }
        for y in q {
            let nn = tp.query(y).nearest_one::<SquaredEuclidean<f64>>().execute();
            pairs.push((Vector3::from(p[nn.item as usize]), Vector3::from(*y), 1.0 / (1.0 + nn.distance / FIT_TAU)));
        }
        let Some((a1, t1)) = weighted_affine(&pairs) else { break };
        if !near_identity(&a1) {
            break;
        }
        let change = (a1 - a).norm() + (t1 - t).norm();
        a = a1;
        t = t1;
        if change < 1e-6 {
            break;
        }
    }
    (a, t)
}

/// The weighted least-squares affine map of the pairs with the pull towards the
/// identity: A = (C_qp + l I)(C_pp + l I)^-1 with the centred weighted
/// covariances and l = IDENTITY_WEIGHT times the mean variance of the sources.
fn weighted_affine(pairs: &[(Vector3<f64>, Vector3<f64>, f64)]) -> Option<(Matrix3<f64>, Vector3<f64>)> {
    let w: f64 = pairs.iter().map(|p| p.2).sum();
    if !(w > 0.0) {
        return None;
    }
    let pm = pairs.iter().fold(Vector3::zeros(), |s, p| s + p.0 * p.2) / w;
    let qm = pairs.iter().fold(Vector3::zeros(), |s, p| s + p.1 * p.2) / w;
    let mut cpp = Matrix3::zeros();
    let mut cqp = Matrix3::zeros();
    for (x, y, wi) in pairs {
        let (dx, dy) = (x - pm, y - qm);
        cpp += dx * dx.transpose() * *wi;
        cqp += dy * dx.transpose() * *wi;
    }
    cpp /= w;
    cqp /= w;
    let l = IDENTITY_WEIGHT * cpp.trace() / 3.0;
    let a = (cqp + Matrix3::identity() * l) * (cpp + Matrix3::identity() * l).try_inverse()?;
    let t = qm - a * pm;
    Some((a, t))
}

/// Whether the linear part is within the allowed rotation and stretches (and
/// keeps the orientation).
fn near_identity(a: &Matrix3<f64>) -> bool {
    if !(a.determinant() > 0.0) {
        return false;
    }
    let svd = a.svd(true, true);
    let (Some(u), Some(vt)) = (svd.u, svd.v_t) else { return false };
    if svd.singular_values.iter().any(|&s| !(s <= MAX_STRETCH && s >= 1.0 / MAX_STRETCH)) {
        return false;
    }
    let r = u * vt;
    if r.determinant() < 0.0 {
        return false;
    }
    let cos = ((r.trace() - 1.0) / 2.0).clamp(-1.0, 1.0);
    cos.acos().to_degrees() <= MAX_ROTATION_DEG
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Points on the unit cube's surface, with or without a square through hole along z.
    fn cube_points(hole: bool) -> Vec<[f64; 3]> {
        let n = 24;
        let mut out = Vec::new();
        for i in 0..n {
            for j in 0..n {
                let (u, v) = ((i as f64 + 0.5) / n as f64, (j as f64 + 0.5) / n as f64);
                for face in 0..6 {
                    let (ax, side) = (face / 2, (face % 2) as f64);
                    let mut p = [0.0; 3];
                    p[ax] = side;
                    p[(ax + 1) % 3] = u;
                    p[(ax + 2) % 3] = v;
                    let in_hole = hole && (p[0] - 0.5).abs() < 0.25 && (p[1] - 0.5).abs() < 0.25;
                    if !(in_hole && ax == 2) {
                        out.push(p);
                    }
                }
                if hole {
                    // the hole's four walls
                    let (s, z) = (0.25 + 0.5 * u, v);
                    out.extend([[0.25, s, z], [0.75, s, z], [s, 0.25, z], [s, 0.75, z]]);
                }
            }
        }
        out
    }

    fn sheared(p: &[[f64; 3]], k: f64, turn_deg: f64) -> Vec<[f64; 3]> {
        let (s, c) = turn_deg.to_radians().sin_cos();
        p.iter().map(|x| [c * x[0] - s * x[1] + k * x[2], s * x[0] + c * x[1], 1.2 * x[2]]).collect()
    }

    #[test]
    fn a_sheared_turned_cell_fits_its_own_shape_again() {
        let (cube, thc) = (cube_points(false), cube_points(true));
        let moved = sheared(&thc, 0.2, 15.0);
        let plain = cell_chamfer(&moved, &thc);
        let reg = registered_fit(&moved, &thc);
        assert!(reg < 0.2 * plain, "registered {reg:.5} against plain {plain:.5}");
        // and the right label stays ahead of the wrong one
        assert!(reg < registered_fit(&moved, &cube), "{reg:.5} {:.5}", registered_fit(&moved, &cube));
    }

    #[test]
    fn the_registration_cannot_turn_a_hole_into_another_axis() {
        // a through hole along x against the template of one along z
        let thc = cube_points(true);
        let along_x: Vec<[f64; 3]> = thc.iter().map(|p| [p[2], p[1], 1.0 - p[0]]).collect();
        let (a, _) = register(&along_x, &thc);
        assert!(near_identity(&a));
        assert!(registered_fit(&along_x, &thc) > 4.0 * registered_fit(&thc, &thc) + 1e-4);
    }
}
