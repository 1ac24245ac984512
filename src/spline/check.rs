//! Measured properties of a spline: Jacobians at Gauss points, partition of
//! unity and non-negativity, reproduction of linear fields, continuity across
//! faces (derivative jumps) and linear independence.

use super::bernstein::{self, NB};
use super::nodes;
use super::{apply_rows, det3, map_from_bezier, scaled_det, Spline};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::Serialize;

/// Jacobian measures at n x n x n Gauss points of every element.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct JacobianSummary {
    pub min_det: f64,
    pub min_scaled: f64,
    /// Mean over elements of the element's minimum scaled Jacobian.
    pub mean_scaled: f64,
    pub negative_elements: usize,
    /// Per element: minimum scaled Jacobian at its Gauss points.
    #[serde(skip)]
    pub per_element: Vec<f64>,
}

fn element_gauss(sp: &Spline, e: usize, n: usize) -> (f64, f64) {
    let (x, _) = bernstein::gauss(n);
    let pb = sp.bezier_points_of(&sp.elems[e]);
    let mut md = f64::INFINITY;
    let mut ms = f64::INFINITY;
    for &a in &x {
        for &b in &x {
            for &c in &x {
                let (_, j) = map_from_bezier(&pb, [a, b, c]);
                md = md.min(det3(&j));
                ms = ms.min(scaled_det(&j));
            }
        }
    }
    (md, ms)
}

/// Jacobian determinant and scaled Jacobian at n^3 Gauss points of every element.
pub fn gauss_jacobians(sp: &Spline, n: usize) -> JacobianSummary {
    let per: Vec<(f64, f64)> = (0..sp.elems.len()).into_par_iter().map(|e| element_gauss(sp, e, n)).collect();
    let min_det = per.iter().map(|p| p.0).fold(f64::INFINITY, f64::min);
    let min_scaled = per.iter().map(|p| p.1).fold(f64::INFINITY, f64::min);
    let mean_scaled = per.iter().map(|p| p.1).sum::<f64>() / per.len().max(1) as f64;
    JacobianSummary {
        min_det,
        min_scaled,
        mean_scaled,
        negative_elements: per.iter().filter(|p| p.0 <= 0.0).count(),
        per_element: per.iter().map(|p| p.1).collect(),
    }
}

/// Minimum det J over the Gauss points of the listed elements.
pub fn min_det_of(sp: &Spline, elems: &[usize], n: usize) -> f64 {
    elems.par_iter().map(|&e| element_gauss(sp, e, n).0).reduce(|| f64::INFINITY, f64::min)
}

/// Minimum scaled Jacobian over the Gauss points of the listed elements.
pub fn min_scaled_of(sp: &Spline, elems: &[usize], n: usize) -> f64 {
    elems.par_iter().map(|&e| element_gauss(sp, e, n).1).reduce(|| f64::INFINITY, f64::min)
}

/// Minimum scaled Jacobian of one element over its 3x3x3 Gauss points and a
/// 5x5x5 lattice including corners, edges and faces (a stricter validity
/// check than the Gauss points alone: used by the fit and the repair).
pub fn element_strict(sp: &Spline, e: usize) -> f64 {
    let pb = sp.bezier_points_of(&sp.elems[e]);
    let mut ms = element_gauss(sp, e, 3).1;
    let t = [0.0, 0.25, 0.5, 0.75, 1.0];
    for &a in &t {
        for &b in &t {
            for &c in &t {
                let (_, j) = map_from_bezier(&pb, [a, b, c]);
                ms = ms.min(scaled_det(&j));
            }
        }
    }
    ms
}

/// `element_strict` minimised over the listed elements.
pub fn min_strict_of(sp: &Spline, elems: &[usize]) -> f64 {
    elems.par_iter().map(|&e| element_strict(sp, e)).reduce(|| f64::INFINITY, f64::min)
}

/// Partition of unity and non-negativity at random points of every element.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct UnityStats {
    pub points: usize,
    /// max |sum_i N_i - 1|
    pub max_sum_error: f64,
    /// min N_i (over functions that live on the element)
    pub min_value: f64,
}

pub fn partition_of_unity(sp: &Spline, per_element: usize, seed: u64) -> UnityStats {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut st = UnityStats { min_value: f64::INFINITY, ..Default::default() };
    for el in &sp.elems {
        for _ in 0..per_element {
            let p = [rng.random::<f64>(), rng.random::<f64>(), rng.random::<f64>()];
            let v = apply_rows(&el.op, &bernstein::values(p));
            let s: f64 = v.iter().sum();
            st.max_sum_error = st.max_sum_error.max((s - 1.0).abs());
            st.min_value = st.min_value.min(v.iter().cloned().fold(f64::INFINITY, f64::min));
            st.points += 1;
        }
    }
    st
}

/// Largest error of reproducing the affine field f(x) = a + b.x: coefficients
/// f(P_i) at the control points, compared with f(X(xi)) at random points.
pub fn linear_reproduction(sp: &Spline, per_element: usize, seed: u64) -> f64 {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let (a, b) = (0.3, [1.7, -0.6, 2.2]);
    let f = |x: [f64; 3]| a + b[0] * x[0] + b[1] * x[1] + b[2] * x[2];
    let coef: Vec<f64> = sp.ctrl.iter().map(|&p| f(p)).collect();
    let mut err: f64 = 0.0;
    for el in &sp.elems {
        let pb = sp.bezier_points_of(el);
        for _ in 0..per_element {
            let p = [rng.random::<f64>(), rng.random::<f64>(), rng.random::<f64>()];
            let v = apply_rows(&el.op, &bernstein::values(p));
            let uh: f64 = v.iter().zip(&el.basis).map(|(v, &i)| v * coef[i as usize]).sum();
            let (x, _) = map_from_bezier(&pb, p);
            err = err.max((uh - f(x)).abs());
        }
    }
    err
}

/// Jumps of the normal derivatives of orders 0, 1, 2 across one class of faces.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct JumpStats {
    pub faces: usize,
    /// Largest jump over faces, sample points and basis functions, per order.
    pub max_jump: [f64; 3],
    /// Faces whose largest jump of order 1 (2) exceeds 1e-9.
    pub faces_c1_broken: usize,
    pub faces_c2_broken: usize,
}

/// Continuity measured across interior faces between level-0 elements, split
/// into "regular" faces (both elements have only regular interior vertices,
/// see `Topology::is_regular_interior_vertex`, or lie in a boundary region whose
/// rules are tensor products) and the others.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct ContinuityStats {
    pub regular: JumpStats,
    pub other: JumpStats,
}

/// Per-order jump of every basis function at `samples^2` points of the face
/// between leaves e1 and e2 (level 0 only).
fn face_jumps(sp: &Spline, e1: usize, d1: usize, s1: usize, e2: usize, samples: usize) -> Option<[f64; 3]> {
    let (a, b) = (&sp.elems[e1], &sp.elems[e2]);
    if a.level != 0 || b.level != 0 {
        return None;
    }
    let [t1, t2] = super::topology::other_dims(d1);
    let mut jumps = [0.0f64; 3];
    for ia in 0..samples {
        for ib in 0..samples {
            // grid points k/8 are exact on the node grid
            let ta = (ia + 1) as f64 / (samples + 1) as f64;
            let tb = (ib + 1) as f64 / (samples + 1) as f64;
            let q = |t: f64| ((t * 8.0).round() / 8.0).clamp(0.125, 0.875);
            let mut p = [0.0; 3];
            p[d1] = s1 as f64;
            p[t1] = q(ta);
            p[t2] = q(tb);
            let p2 = nodes::map_face_point(&sp.topo, a.root, p, b.root)?;
            let d2 = (0..3).find(|&d| p2[d] == 0.0 || p2[d] == 1.0)?;
            let s2 = p2[d2] as usize;
            let sign1: f64 = if s1 == 1 { 1.0 } else { -1.0 };
            let sign2: f64 = if s2 == 0 { 1.0 } else { -1.0 };
            for (order, jump) in jumps.iter_mut().enumerate() {
                let ba = bernstein::directional_derivative(p, d1, order);
                let bb = bernstein::directional_derivative(p2, d2, order);
                let va = apply_rows(&a.op, &ba);
                let vb = apply_rows(&b.op, &bb);
                let fa = sign1.powi(order as i32);
                let fb = sign2.powi(order as i32);
                let mut vals: std::collections::HashMap<u32, f64> = std::collections::HashMap::new();
                for (r, &id) in a.basis.iter().enumerate() {
                    *vals.entry(id).or_insert(0.0) += fa * va[r];
                }
                for (r, &id) in b.basis.iter().enumerate() {
                    *vals.entry(id).or_insert(0.0) -= fb * vb[r];
                }
                for v in vals.values() {
                    *jump = jump.max(v.abs());
                }
            }
        }
    }
    Some(jumps)
}

/// Is every vertex of the element in a configuration where the rules are
/// tensor-product B-spline rules (regular interior vertex)?
fn regular_element(sp: &Spline, root: u32) -> bool {
    sp.topo.elements[root as usize].iter().all(|&v| sp.topo.is_regular_interior_vertex(v as usize))
}

/// Measure derivative jumps across all interior faces of level-0 leaves.
/// `regular_override` classifies faces as regular when given (for example on a
/// block whose boundary rules are tensor products, every face is regular).
pub fn continuity(sp: &Spline, samples: usize, regular_override: Option<&(dyn Fn(u32, u32) -> bool + Sync)>) -> ContinuityStats {
    let mut leaf_of_root = vec![usize::MAX; sp.topo.ne];
    for (i, el) in sp.elems.iter().enumerate() {
        if el.level == 0 {
            leaf_of_root[el.root as usize] = i;
        }
    }
    let faces: Vec<(u32, usize, usize, u32)> = sp
        .topo
        .faces
        .iter()
        .filter(|f| f.elems.len() == 2)
        .map(|f| (f.elems[0].0, f.elems[0].1 as usize, f.elems[0].2 as usize, f.elems[1].0))
        .collect();
    let res: Vec<(bool, Option<[f64; 3]>)> = faces
        .par_iter()
        .map(|&(r1, d1, s1, r2)| {
            let (l1, l2) = (leaf_of_root[r1 as usize], leaf_of_root[r2 as usize]);
            if l1 == usize::MAX || l2 == usize::MAX {
                return (false, None);
            }
            let regular = match regular_override {
                Some(f) => f(r1, r2),
                None => regular_element(sp, r1) && regular_element(sp, r2),
            };
            (regular, face_jumps(sp, l1, d1, s1, l2, samples))
        })
        .collect();
    let mut st = ContinuityStats::default();
    for (regular, j) in res {
        let Some(j) = j else { continue };
        let t = if regular { &mut st.regular } else { &mut st.other };
        t.faces += 1;
        for k in 0..3 {
            t.max_jump[k] = t.max_jump[k].max(j[k]);
        }
        if j[1] > 1e-9 {
            t.faces_c1_broken += 1;
        }
        if j[2] > 1e-9 {
            t.faces_c2_broken += 1;
        }
    }
    st
}

/// Numerical rank of the basis (rank of the matrix of all elements' Bézier
/// coefficients; full rank = linearly independent) and the number of functions.
/// Dense SVD: meant for small meshes.
pub fn independence_rank(sp: &Spline) -> (usize, usize) {
    let n = sp.ctrl.len();
    let rows = sp.elems.len() * NB;
    let mut g = nalgebra::DMatrix::<f64>::zeros(n, n);
    // Gram matrix of the coefficient matrix M (rows = element x Bernstein index)
    for el in &sp.elems {
        let d = el.op.to_dense();
        let k = el.basis.len();
        for a in 0..k {
            for b in 0..k {
                let mut s = 0.0;
                for c in 0..NB {
                    s += d[a * NB + c] * d[b * NB + c];
                }
                g[(el.basis[a] as usize, el.basis[b] as usize)] += s;
            }
        }
    }
    let _ = rows;
    let ev = nalgebra::SymmetricEigen::new(g).eigenvalues;
    let max = ev.iter().cloned().fold(0.0, f64::max);
    let rank = ev.iter().filter(|&&x| x > max * 1e-12).count();
    (rank, n)
}
