//! A small isogeometric Poisson (steady heat conduction) solver on the spline:
//! -Δu = f in the volume, u = g on its boundary, Galerkin with the spline basis,
//! Gauss quadrature on every Bézier element, Dirichlet data by L2 projection on
//! the boundary, sparse Cholesky (faer) or Jacobi-preconditioned conjugate
//! gradients for large systems. It exists to show analysis suitability
//! (convergence rates), not to compete with LS-DYNA.

use super::bernstein::{self, NB};
use super::fit::boundary_faces;
use super::topology::other_dims;
use super::{det3, map_from_bezier, Spline};
use crate::error::{Error, Result};
use faer::linalg::solvers::Solve;
use faer::sparse::{SparseColMat, Triplet};
use rayon::prelude::*;
use serde::Serialize;

/// Linear solver choice.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum LinearSolver {
    /// Cholesky up to `direct_limit` unknowns, conjugate gradients above.
    Auto,
    Cholesky,
    ConjugateGradient,
}

#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PoissonOptions {
    /// Gauss points per direction for assembly (default 4).
    pub quadrature: usize,
    /// Gauss points per direction for error norms (default 5).
    pub error_quadrature: usize,
    pub solver: LinearSolver,
    /// Largest system solved directly under `Auto` (default 40000).
    pub direct_limit: usize,
    /// Relative residual of conjugate gradients (default 1e-10).
    pub cg_tolerance: f64,
    /// Conjugate-gradient iteration limit (default 20000).
    pub cg_max_iterations: usize,
}

impl Default for PoissonOptions {
    fn default() -> Self {
        PoissonOptions {
            quadrature: 4,
            error_quadrature: 5,
            solver: LinearSolver::Auto,
            direct_limit: 40_000,
            cg_tolerance: 1e-10,
            cg_max_iterations: 20_000,
        }
    }
}

/// The discrete solution: one coefficient per basis function.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PoissonSolution {
    pub coefficients: Vec<f64>,
    pub dofs: usize,
    /// Basis functions fixed by the Dirichlet data.
    pub boundary_dofs: usize,
    pub solver: String,
    pub iterations: usize,
    pub seconds: f64,
}

/// Error norms against an exact solution.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ErrorNorms {
    pub l2: f64,
    /// l2 / ||u||_L2
    pub l2_relative: f64,
    /// |u - u_h|_H1
    pub h1_semi: f64,
    /// Volume of the spline domain (by the same quadrature).
    pub volume: f64,
}

fn inv3(j: &[[f64; 3]; 3]) -> Option<[[f64; 3]; 3]> {
    let d = det3(j);
    if d.abs() <= f64::MIN_POSITIVE {
        return None;
    }
    let i = 1.0 / d;
    Some([
        [
            (j[1][1] * j[2][2] - j[1][2] * j[2][1]) * i,
            (j[0][2] * j[2][1] - j[0][1] * j[2][2]) * i,
            (j[0][1] * j[1][2] - j[0][2] * j[1][1]) * i,
        ],
        [
            (j[1][2] * j[2][0] - j[1][0] * j[2][2]) * i,
            (j[0][0] * j[2][2] - j[0][2] * j[2][0]) * i,
            (j[0][2] * j[1][0] - j[0][0] * j[1][2]) * i,
        ],
        [
            (j[1][0] * j[2][1] - j[1][1] * j[2][0]) * i,
            (j[0][1] * j[2][0] - j[0][0] * j[2][1]) * i,
            (j[0][0] * j[1][1] - j[0][1] * j[1][0]) * i,
        ],
    ])
}

/// Tensor Gauss rule on [0,1]^3: points and weights.
fn rule3(n: usize) -> Vec<([f64; 3], f64)> {
    let (x, w) = bernstein::gauss(n);
    let mut out = Vec::with_capacity(n * n * n);
    for (k, &c) in x.iter().enumerate() {
        for (j, &b) in x.iter().enumerate() {
            for (i, &a) in x.iter().enumerate() {
                out.push(([a, b, c], w[i] * w[j] * w[k]));
            }
        }
    }
    out
}

/// Per-element data at one quadrature point: physical point, weight x |det J|,
/// basis values and physical gradients (rows of the element).
struct QPoint {
    x: [f64; 3],
    wdet: f64,
    n: Vec<f64>,
    grad: Vec<[f64; 3]>,
}

fn element_qpoints(sp: &Spline, e: usize, rule: &[([f64; 3], f64)]) -> Result<Vec<QPoint>> {
    let el = &sp.elems[e];
    let pb = sp.bezier_points_of(el);
    let dense = el.op.to_dense();
    let rows = el.basis.len();
    let mut out = Vec::with_capacity(rule.len());
    for &(p, w) in rule {
        let (b, g) = bernstein::values_and_gradients(p);
        let (x, j) = map_from_bezier(&pb, p);
        let d = det3(&j);
        let inv = inv3(&j).ok_or_else(|| Error::SplineFailed(format!("singular Jacobian in element {e}")))?;
        let mut n = vec![0.0; rows];
        let mut grad = vec![[0.0; 3]; rows];
        for r in 0..rows {
            let c = &dense[r * NB..(r + 1) * NB];
            let mut v = 0.0;
            let mut gp = [0.0; 3];
            for k in 0..NB {
                if c[k] != 0.0 {
                    v += c[k] * b[k];
                    for t in 0..3 {
                        gp[t] += c[k] * g[k][t];
                    }
                }
            }
            n[r] = v;
            // physical gradient: J^{-T} grad_xi
            grad[r] = [0, 1, 2].map(|i| inv[0][i] * gp[0] + inv[1][i] * gp[1] + inv[2][i] * gp[2]);
        }
        out.push(QPoint { x, wdet: w * d.abs(), n, grad });
    }
    Ok(out)
}

/// Basis functions that do not vanish on the boundary (non-zero coefficient on
/// a Bézier node of a boundary face).
fn boundary_functions(sp: &Spline) -> Vec<bool> {
    let mut on = vec![false; sp.num_basis()];
    for (e, d, s) in boundary_faces(sp) {
        let el = &sp.elems[e];
        for r in 0..el.op.rows() {
            let (c, v) = el.op.row(r);
            if c.iter().zip(v).any(|(&k, &x)| x != 0.0 && bernstein::bijk(k as usize)[d] == 3 * s) {
                on[el.basis[r] as usize] = true;
            }
        }
    }
    on
}

fn solve_spd(
    n: usize,
    trip: &[Triplet<usize, usize, f64>],
    rhs: Vec<f64>,
    opts: &PoissonOptions,
) -> Result<(Vec<f64>, String, usize)> {
    if n == 0 {
        return Ok((Vec::new(), "none".into(), 0));
    }
    let direct = match opts.solver {
        LinearSolver::Cholesky => true,
        LinearSolver::ConjugateGradient => false,
        LinearSolver::Auto => n <= opts.direct_limit,
    };
    if direct {
        let a = SparseColMat::<usize, f64>::try_new_from_triplets(n, n, trip)
            .map_err(|e| Error::SplineFailed(format!("assembly: {e:?}")))?;
        let llt = a
            .sp_cholesky(faer::Side::Lower)
            .map_err(|e| Error::SplineFailed(format!("Cholesky factorisation failed: {e:?}")))?;
        let mut b = faer::Mat::<f64>::from_fn(n, 1, |i, _| rhs[i]);
        llt.solve_in_place(b.as_mut());
        return Ok(((0..n).map(|i| b[(i, 0)]).collect(), "cholesky".into(), 1));
    }
    // Jacobi-preconditioned conjugate gradients on a CSR copy. (faer 0.24's
    // matrix-free CG reported a non-positive-definite operator on a plain SPD
    // tridiagonal test matrix here, so this small loop is used instead.)
    let csr = Csr::from_triplets(n, trip);
    let (x, it) = pcg(&csr, &rhs, opts.cg_tolerance, opts.cg_max_iterations)?;
    Ok((x, "cg-jacobi".into(), it))
}

/// Compressed sparse rows with summed duplicates.
struct Csr {
    ptr: Vec<usize>,
    col: Vec<u32>,
    val: Vec<f64>,
}

impl Csr {
    fn from_triplets(n: usize, trip: &[Triplet<usize, usize, f64>]) -> Csr {
        let mut count = vec![0usize; n + 1];
        for t in trip {
            count[t.row + 1] += 1;
        }
        for i in 0..n {
            count[i + 1] += count[i];
        }
        let mut fill = count.clone();
        let mut col = vec![0u32; trip.len()];
        let mut val = vec![0.0; trip.len()];
        for t in trip {
            let p = fill[t.row];
            col[p] = t.col as u32;
            val[p] = t.val;
            fill[t.row] += 1;
        }
        // sort each row and merge duplicates
        let mut ptr = vec![0usize; n + 1];
        let mut oc = Vec::with_capacity(trip.len());
        let mut ov = Vec::with_capacity(trip.len());
        for i in 0..n {
            let mut row: Vec<(u32, f64)> = (count[i]..count[i + 1]).map(|p| (col[p], val[p])).collect();
            row.sort_unstable_by_key(|x| x.0);
            for (c, v) in row {
                if oc.len() > ptr[i] && *oc.last().unwrap() == c {
                    *ov.last_mut().unwrap() += v;
                } else {
                    oc.push(c);
                    ov.push(v);
                }
            }
            ptr[i + 1] = oc.len();
        }
        Csr { ptr, col: oc, val: ov }
    }

    fn mul(&self, x: &[f64], y: &mut [f64]) {
        y.par_iter_mut().enumerate().for_each(|(i, yi)| {
            let mut s = 0.0;
            for p in self.ptr[i]..self.ptr[i + 1] {
                s += self.val[p] * x[self.col[p] as usize];
            }
            *yi = s;
        });
    }

    fn diag(&self) -> Vec<f64> {
        (0..self.ptr.len() - 1)
            .map(|i| {
                (self.ptr[i]..self.ptr[i + 1]).find(|&p| self.col[p] as usize == i).map(|p| self.val[p]).unwrap_or(0.0)
            })
            .collect()
    }
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.par_iter().zip(b).map(|(x, y)| x * y).sum()
}

/// Jacobi-preconditioned conjugate gradients from x = 0.
fn pcg(a: &Csr, b: &[f64], tol: f64, max_it: usize) -> Result<(Vec<f64>, usize)> {
    let n = b.len();
    let dinv: Vec<f64> = a.diag().iter().map(|&d| if d > 0.0 { 1.0 / d } else { 1.0 }).collect();
    let bn = dot(b, b).sqrt();
    let mut x = vec![0.0; n];
    if bn == 0.0 {
        return Ok((x, 0));
    }
    let mut r = b.to_vec();
    let mut z: Vec<f64> = r.iter().zip(&dinv).map(|(r, d)| r * d).collect();
    let mut p = z.clone();
    let mut rz = dot(&r, &z);
    let mut ap = vec![0.0; n];
    for it in 0..max_it {
        a.mul(&p, &mut ap);
        let pap = dot(&p, &ap);
        if pap <= 0.0 {
            return Err(Error::SplineFailed("conjugate gradients: the matrix is not positive definite".into()));
        }
        let alpha = rz / pap;
        x.par_iter_mut().zip(&p).for_each(|(x, p)| *x += alpha * p);
        r.par_iter_mut().zip(&ap).for_each(|(r, q)| *r -= alpha * q);
        if dot(&r, &r).sqrt() <= tol * bn {
            return Ok((x, it + 1));
        }
        z.par_iter_mut().zip(r.par_iter().zip(&dinv)).for_each(|(z, (r, d))| *z = r * d);
        let rz2 = dot(&r, &z);
        let beta = rz2 / rz;
        rz = rz2;
        p.par_iter_mut().zip(&z).for_each(|(p, z)| *p = z + beta * *p);
    }
    Err(Error::SplineFailed(format!(
        "conjugate gradients did not reach the relative residual {tol} in {max_it} iterations"
    )))
}

/// Solve -Δu = source in the spline volume with u = dirichlet on its boundary.
pub fn solve_poisson(
    sp: &Spline,
    source: impl Fn([f64; 3]) -> f64 + Sync,
    dirichlet: impl Fn([f64; 3]) -> f64 + Sync,
    opts: &PoissonOptions,
) -> Result<PoissonSolution> {
    let t0 = std::time::Instant::now();
    if !(1..=6).contains(&opts.quadrature) || !(1..=6).contains(&opts.error_quadrature) {
        return Err(Error::InvalidArgument("quadrature must be 1..=6 points per direction".into()));
    }
    let nb = sp.num_basis();
    let on_boundary = boundary_functions(sp);
    // Dirichlet data: L2 projection on the boundary faces
    let (bmap, cb) = dirichlet_projection(sp, &on_boundary, &dirichlet, opts)?;
    let nbd = cb.len();
    // the interior system with the boundary coefficients moved to the right-hand side
    let (imap, ci, solver, iterations) = interior_solution(sp, &on_boundary, &bmap, &cb, &source, opts)?;
    let mut coefficients = vec![0.0; nb];
    for i in 0..nb {
        coefficients[i] = if imap[i] != u32::MAX { ci[imap[i] as usize] } else { cb[bmap[i] as usize] };
    }
    Ok(PoissonSolution {
        coefficients,
        dofs: nb,
        boundary_dofs: nbd,
        solver,
        iterations,
        seconds: t0.elapsed().as_secs_f64(),
    })
}

/// The boundary functions' coefficients: the L2 projection of `dirichlet` on the
/// boundary faces. Returns (function -> boundary index, u32::MAX for interior
/// functions; the coefficients by boundary index).
fn dirichlet_projection(sp: &Spline, on_boundary: &[bool], dirichlet: &(impl Fn([f64; 3]) -> f64 + Sync), opts: &PoissonOptions) -> Result<(Vec<u32>, Vec<f64>)> {
    let nb = sp.num_basis();
    let mut bmap = vec![u32::MAX; nb];
    let mut bids = Vec::new();
    for (i, &b) in on_boundary.iter().enumerate() {
        if b {
            bmap[i] = bids.len() as u32;
            bids.push(i);
        }
    }
    let faces = boundary_faces(sp);
    let (gx, gw) = bernstein::gauss(opts.quadrature);
    let per_face: Vec<(Vec<Triplet<usize, usize, f64>>, Vec<(usize, f64)>)> = faces
        .par_iter()
        .map(|&(e, d, s)| {
            let el = &sp.elems[e];
            let pb = sp.bezier_points_of(el);
            let dense = el.op.to_dense();
            let [d1, d2] = other_dims(d);
            let mut m = Vec::new();
            let mut r = Vec::new();
            for (ia, &a) in gx.iter().enumerate() {
                for (ib, &b) in gx.iter().enumerate() {
                    let mut p = [0.0; 3];
                    p[d] = s as f64;
                    p[d1] = a;
                    p[d2] = b;
                    let (x, j) = map_from_bezier(&pb, p);
                    let t1 = [j[0][d1], j[1][d1], j[2][d1]];
                    let t2 = [j[0][d2], j[1][d2], j[2][d2]];
                    let c = crate::geometry::vec3::cross(t1, t2);
                    let da = crate::geometry::vec3::norm(c) * gw[ia] * gw[ib];
                    let bv = bernstein::values(p);
                    let g = dirichlet(x);
                    let vals: Vec<(usize, f64)> = (0..el.basis.len())
                        .filter_map(|rr| {
                            let bi = el.basis[rr] as usize;
                            if bmap[bi] == u32::MAX {
                                return None;
                            }
                            let v: f64 = (0..NB).map(|k| dense[rr * NB + k] * bv[k]).sum();
                            (v != 0.0).then_some((bmap[bi] as usize, v))
                        })
                        .collect();
                    for &(i, vi) in &vals {
                        r.push((i, da * g * vi));
                        for &(j2, vj) in &vals {
                            m.push(Triplet::new(i, j2, da * vi * vj));
                        }
                    }
                }
            }
            (m, r)
        })
        .collect();
    let nbd = bids.len();
    let mut mt = Vec::new();
    let mut mr = vec![0.0; nbd];
    for (m, r) in per_face {
        mt.extend(m);
        for (i, v) in r {
            mr[i] += v;
        }
    }
    let opts_direct = PoissonOptions { solver: LinearSolver::Auto, ..opts.clone() };
    let (cb, _, _) = solve_spd(nbd, &mt, mr, &opts_direct)?;
    Ok((bmap, cb))
}

/// The interior functions' coefficients: the stiffness system assembled element by
/// element with the boundary coefficients `cb` on the right-hand side. Returns
/// (function -> interior index, u32::MAX for boundary functions; the solution; the
/// solver used; its iterations).
#[allow(clippy::type_complexity)]
fn interior_solution(
    sp: &Spline,
    on_boundary: &[bool],
    bmap: &[u32],
    cb: &[f64],
    source: &(impl Fn([f64; 3]) -> f64 + Sync),
    opts: &PoissonOptions,
) -> Result<(Vec<u32>, Vec<f64>, String, usize)> {
    let nb = sp.num_basis();
    let mut imap = vec![u32::MAX; nb];
    let mut nfree = 0usize;
    for i in 0..nb {
        if !on_boundary[i] {
            imap[i] = nfree as u32;
            nfree += 1;
        }
    }
    let rule = rule3(opts.quadrature);
    let per_elem: Vec<Result<(Vec<Triplet<usize, usize, f64>>, Vec<(usize, f64)>)>> = (0..sp.num_elements())
        .into_par_iter()
        .map(|e| {
            let el = &sp.elems[e];
            let qp = element_qpoints(sp, e, &rule)?;
            let k = el.basis.len();
            let mut ke = vec![0.0; k * k];
            let mut fe = vec![0.0; k];
            for q in &qp {
                let f = source(q.x);
                for a in 0..k {
                    fe[a] += q.wdet * f * q.n[a];
                    let ga = q.grad[a];
                    for b in 0..k {
                        let gb = q.grad[b];
                        ke[a * k + b] += q.wdet * (ga[0] * gb[0] + ga[1] * gb[1] + ga[2] * gb[2]);
                    }
                }
            }
            let mut t = Vec::new();
            let mut r = Vec::new();
            for a in 0..k {
                let ia = el.basis[a] as usize;
                if imap[ia] == u32::MAX {
                    continue;
                }
                let la = imap[ia] as usize;
                let mut rhs = fe[a];
                for b in 0..k {
                    let ib = el.basis[b] as usize;
                    if imap[ib] == u32::MAX {
                        rhs -= ke[a * k + b] * cb[bmap[ib] as usize];
                    } else {
                        t.push(Triplet::new(la, imap[ib] as usize, ke[a * k + b]));
                    }
                }
                r.push((la, rhs));
            }
            Ok((t, r))
        })
        .collect();
    let mut kt = Vec::new();
    let mut kr = vec![0.0; nfree];
    for pe in per_elem {
        let (t, r) = pe?;
        kt.extend(t);
        for (i, v) in r {
            kr[i] += v;
        }
    }
    let (ci, solver, iterations) = solve_spd(nfree, &kt, kr, opts)?;
    Ok((imap, ci, solver, iterations))
}

impl PoissonSolution {
    /// u_h at (u, v, w) of element e.
    pub fn value(&self, sp: &Spline, e: usize, u: f64, v: f64, w: f64) -> Result<f64> {
        let (ids, vals) = sp.basis_values(e, u, v, w)?;
        Ok(ids.iter().zip(&vals).map(|(&i, &x)| x * self.coefficients[i as usize]).sum())
    }

    /// L2 and H1-seminorm errors against the exact solution and its gradient.
    pub fn errors(
        &self,
        sp: &Spline,
        exact: impl Fn([f64; 3]) -> f64 + Sync,
        exact_grad: impl Fn([f64; 3]) -> [f64; 3] + Sync,
        opts: &PoissonOptions,
    ) -> Result<ErrorNorms> {
        let rule = rule3(opts.error_quadrature);
        let parts: Vec<Result<[f64; 4]>> = (0..sp.num_elements())
            .into_par_iter()
            .map(|e| {
                let el = &sp.elems[e];
                let qp = element_qpoints(sp, e, &rule)?;
                let mut acc = [0.0; 4];
                for q in &qp {
                    let mut uh = 0.0;
                    let mut gh = [0.0; 3];
                    for (r, &id) in el.basis.iter().enumerate() {
                        let c = self.coefficients[id as usize];
                        uh += c * q.n[r];
                        for t in 0..3 {
                            gh[t] += c * q.grad[r][t];
                        }
                    }
                    let u = exact(q.x);
                    let g = exact_grad(q.x);
                    acc[0] += q.wdet * (uh - u) * (uh - u);
                    acc[1] += q.wdet * u * u;
                    acc[2] += q.wdet * ((gh[0] - g[0]).powi(2) + (gh[1] - g[1]).powi(2) + (gh[2] - g[2]).powi(2));
                    acc[3] += q.wdet;
                }
                Ok(acc)
            })
            .collect();
        let mut s = [0.0; 4];
        for p in parts {
            let p = p?;
            for i in 0..4 {
                s[i] += p[i];
            }
        }
        Ok(ErrorNorms {
            l2: s[0].sqrt(),
            l2_relative: (s[0] / s[1].max(f64::MIN_POSITIVE)).sqrt(),
            h1_semi: s[2].sqrt(),
            volume: s[3],
        })
    }

    /// L2 error against the exact solution.
    pub fn l2_error(&self, sp: &Spline, exact: impl Fn([f64; 3]) -> f64 + Sync, opts: &PoissonOptions) -> Result<f64> {
        Ok(self.errors(sp, exact, |_| [0.0; 3], opts)?.l2)
    }
}
