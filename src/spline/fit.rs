//! Fitting the spline boundary to the input surface and measuring the distance.
//!
//! The fit moves only the control points of basis functions that do not vanish
//! on the boundary. It samples every boundary face of every leaf, takes the
//! closest surface point of each sample as its target (and, two-sided, every
//! surface vertex as the target of its closest spline-boundary point) and solves the
//! regularised least-squares problem
//!   min sum_s |X(s) - T(s)|^2 + lambda sum_i |P_i - P_i^0|^2,
//! lambda = `regularization` x the mean diagonal of the normal matrix, by a
//! sparse Cholesky factorisation (faer), a few times with new targets. If a fit
//! step would lower the minimum scaled Jacobian (3x3x3 Gauss points and a
//! 5x5x5 lattice with the corners) of the elements it touches below half its value before the fit (or below 0.1 when
//! that is lower), the step is halved until it does not.

use super::bernstein::{self, NB};
use super::{apply_rows, check, Spline};
use crate::error::{Error, Result};
use crate::geometry::{Aabb, SurfaceLocator};
use crate::mesh::TriMesh;
use serde::{Deserialize, Serialize};

/// Boundary fitting settings (part of `SplineOptions`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FitOptions {
    /// Fit when a surface is given (default true).
    pub enabled: bool,
    /// Closest-point / least-squares rounds (default 3).
    pub iterations: usize,
    /// Samples per direction on each boundary face of each element (default 4),
    /// also used for the distance measures (twice as many there).
    pub samples: usize,
    /// Tikhonov weight towards the current control points, relative to the mean
    /// diagonal of the normal matrix (default 1e-3).
    pub regularization: f64,
    /// Halvings of a fit step that would create a non-positive Jacobian (default 8).
    pub max_backtracks: usize,
    /// Also pull the spline boundary towards every surface vertex (its closest
    /// point on the sampled boundary), so that surface detail the boundary
    /// misses counts too (default true).
    pub two_sided: bool,
    /// Most surface vertices the two-sided term uses (default 100,000): a larger
    /// surface contributes every k-th vertex, k the smallest stride that keeps
    /// within the bound. Each vertex is a least-squares row over up to 64 basis
    /// functions; without the bound a 5,000,000-triangle input (2.5 million
    /// vertices) took 12.7 GB and 683 s in the fit on a shared machine
    /// (BENCHMARKS.md "Bad and pathological inputs").
    pub max_reverse_points: usize,
}

impl Default for FitOptions {
    fn default() -> Self {
        FitOptions { enabled: true, iterations: 3, samples: 4, regularization: 1e-3, max_backtracks: 8, two_sided: true, max_reverse_points: 100_000 }
    }
}

/// Distance between the spline boundary and a surface.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct SurfaceDistance {
    /// Largest distance from spline-boundary samples to the surface.
    pub max: f64,
    /// Root mean square of those distances, each sample weighted by the
    /// parameter area it stands for (so refined faces do not count more).
    pub rms: f64,
    /// Two-sided Hausdorff distance (also from the surface's vertices to the
    /// sampled spline boundary).
    pub hausdorff: f64,
    /// The same, relative to the surface's bounding-box diagonal.
    pub max_relative: f64,
    pub rms_relative: f64,
    pub hausdorff_relative: f64,
    /// Samples on the spline boundary.
    pub samples: usize,
}

/// Bounding-box diagonal of a surface.
pub fn diagonal(surf: &TriMesh) -> f64 {
    Aabb::of_points(&surf.vertices).diagonal()
}

/// Boundary faces of leaves: (leaf, dim, side).
pub fn boundary_faces(sp: &Spline) -> Vec<(usize, usize, usize)> {
    let mut out = Vec::new();
    for (i, el) in sp.elems.iter().enumerate() {
        let last = (1u32 << el.level) - 1;
        for d in 0..3 {
            for s in 0..2 {
                let touches = if s == 0 { el.origin[d] == 0 } else { el.origin[d] == last };
                if !touches {
                    continue;
                }
                let f = sp.topo.elem_faces[el.root as usize][d * 2 + s];
                if sp.topo.face_bquad[f as usize] != u32::MAX {
                    out.push((i, d, s));
                }
            }
        }
    }
    out
}

/// Element parameters of sample (a, b) of an m x m grid on face (d, s); the
/// grid is cell-centred when `centred`, else includes the face's corners.
fn face_param(d: usize, s: usize, a: usize, b: usize, m: usize, centred: bool) -> [f64; 3] {
    let t = |i: usize| if centred { (i as f64 + 0.5) / m as f64 } else { i as f64 / (m - 1).max(1) as f64 };
    let [d1, d2] = super::topology::other_dims(d);
    let mut p = [0.0; 3];
    p[d] = s as f64;
    p[d1] = t(a);
    p[d2] = t(b);
    p
}

fn point_of(sp: &Spline, e: usize, p: [f64; 3]) -> [f64; 3] {
    let el = &sp.elems[e];
    let b = bernstein::values(p);
    let v = apply_rows(&el.op, &b);
    let mut x = [0.0; 3];
    for (r, &id) in el.basis.iter().enumerate() {
        let c = sp.ctrl[id as usize];
        for i in 0..3 {
            x[i] += v[r] * c[i];
        }
    }
    x
}

/// Distance measures between the spline boundary and the surface.
pub fn surface_distance(sp: &Spline, loc: &SurfaceLocator, surf: &TriMesh, samples: usize) -> SurfaceDistance {
    use rayon::prelude::*;
    let faces = boundary_faces(sp);
    let m = (2 * samples).max(3);
    let pts: Vec<[f64; 3]> = faces
        .par_iter()
        .flat_map_iter(|&(e, d, s)| {
            (0..m * m).map(move |k| point_of(sp, e, face_param(d, s, k % m, k / m, m, false)))
        })
        .collect();
    let dists: Vec<f64> = pts.par_iter().map(|&p| loc.closest(p).2).collect();
    let max = dists.iter().cloned().fold(0.0, f64::max);
    // area weights in parameter space: a level-L face is 4^-L of its root face
    let weights: Vec<f64> = faces
        .iter()
        .flat_map(|&(e, _, _)| std::iter::repeat(0.25f64.powi(sp.elems[e].level as i32)).take(m * m))
        .collect();
    let wsum: f64 = weights.iter().sum();
    let rms = (dists.iter().zip(&weights).map(|(d, w)| w * d * d).sum::<f64>() / wsum.max(f64::MIN_POSITIVE)).sqrt();
    // reverse direction: surface vertices to the triangulated spline boundary
    let tri = TriMesh { vertices: pts, triangles: face_grid_triangles(faces.len(), m) };
    let back = if tri.triangles.is_empty() {
        0.0
    } else {
        SurfaceLocator::new(&tri).max_distance(&surf.vertices)
    };
    let diag = diagonal(surf).max(f64::MIN_POSITIVE);
    let h = max.max(back);
    SurfaceDistance {
        max,
        rms,
        hausdorff: h,
        max_relative: max / diag,
        rms_relative: rms / diag,
        hausdorff_relative: h / diag,
        samples: dists.len(),
    }
}

/// Largest sample distance of every leaf that has a boundary face.
pub fn boundary_element_distances(sp: &Spline, loc: &SurfaceLocator, samples: usize) -> Vec<(usize, f64)> {
    use rayon::prelude::*;
    let faces = boundary_faces(sp);
    let m = samples.max(2) + 1;
    let per: Vec<(usize, f64)> = faces
        .par_iter()
        .map(|&(e, d, s)| {
            let mut worst: f64 = 0.0;
            for k in 0..m * m {
                let p = point_of(sp, e, face_param(d, s, k % m, k / m, m, false));
                worst = worst.max(loc.closest(p).2);
            }
            (e, worst)
        })
        .collect();
    let mut best = std::collections::HashMap::new();
    for (e, d) in per {
        let x = best.entry(e).or_insert(0.0f64);
        *x = x.max(d);
    }
    let mut v: Vec<(usize, f64)> = best.into_iter().collect();
    v.sort_unstable_by_key(|x| x.0);
    v
}

/// Fit the boundary control points (see the module documentation).
pub fn fit_boundary_with(sp: &mut Spline, loc: &SurfaceLocator, surf: &TriMesh, fo: &FitOptions) -> Result<()> {
    if fo.samples == 0 || !(fo.regularization.is_finite() && fo.regularization > 0.0) {
        return Err(Error::InvalidArgument("fit samples must be >= 1 and regularization > 0".into()));
    }
    let faces = boundary_faces(sp);
    if faces.is_empty() || fo.iterations == 0 {
        return Ok(());
    }
    let rows = forward_rows(sp, &faces, fo.samples);
    let sys = FitSystem::new(sp, rows, fo);
    for _ in 0..fo.iterations {
        let p0: Vec<[f64; 3]> = sys.unknowns.iter().map(|&i| sp.ctrl[i as usize]).collect();
        let targets = forward_targets(sp, &sys.rows, loc);
        // reverse rows: every surface vertex pulls the closest point of the
        // (sampled, triangulated) spline boundary towards it
        let rev = if fo.two_sided { reverse_rows(sp, &faces, 2 * fo.samples, surf, fo, &sys.local) } else { Vec::new() };
        let solution = sys.solve(&targets, &rev, &p0)?;
        sys.apply_with_backtracking(sp, &p0, &solution, fo);
    }
    Ok(())
}

/// Two triangles per cell of `n_faces` grids of `k` x `k` points each, the points
/// numbered face by face, row by row (the sampled boundary's triangulation).
fn face_grid_triangles(n_faces: usize, k: usize) -> Vec<[u32; 3]> {
    let mut t = Vec::with_capacity(2 * n_faces * k.saturating_sub(1).pow(2));
    for fi in 0..n_faces {
        let base = (fi * k * k) as u32;
        for b in 0..k.saturating_sub(1) {
            for a in 0..k - 1 {
                let i0 = base + (b * k + a) as u32;
                let (i1, i2, i3) = (i0 + 1, i0 + 1 + k as u32, i0 + k as u32);
                t.push([i0, i1, i2]);
                t.push([i0, i2, i3]);
            }
        }
    }
    t
}

/// One least-squares row: the basis functions (ids) and their values at a point.
type Row = (Vec<u32>, Vec<f64>);

/// The forward rows: `m` x `m` samples on every boundary face.
fn forward_rows(sp: &Spline, faces: &[(usize, usize, usize)], m: usize) -> Vec<Row> {
    use rayon::prelude::*;
    faces
        .par_iter()
        .flat_map_iter(|&(e, d, s)| {
            let el = &sp.elems[e];
            (0..m * m).map(move |k| {
                let p = face_param(d, s, k % m, k / m, m, true);
                let b = bernstein::values(p);
                let v = apply_rows(&el.op, &b);
                let mut ids = Vec::new();
                let mut vals = Vec::new();
                for (r, &x) in v.iter().enumerate() {
                    if x.abs() > 1e-13 {
                        ids.push(el.basis[r]);
                        vals.push(x);
                    }
                }
                (ids, vals)
            })
        })
        .collect()
}

/// The unknowns of the fit (functions of the rows), their Tikhonov weight and the
/// elements they touch with the quality floor of each.
struct FitSystem {
    rows: Vec<Row>,
    /// Global function id -> unknown index (u32::MAX: not an unknown).
    local: Vec<u32>,
    unknowns: Vec<u32>,
    lambda: f64,
    touched: Vec<usize>,
    floor: Vec<f64>,
}

impl FitSystem {
    fn new(sp: &Spline, rows: Vec<Row>, fo: &FitOptions) -> FitSystem {
        let mut local = vec![u32::MAX; sp.ctrl.len()];
        let mut unknowns: Vec<u32> = Vec::new();
        for (ids, _) in &rows {
            for &i in ids {
                if local[i as usize] == u32::MAX {
                    local[i as usize] = unknowns.len() as u32;
                    unknowns.push(i);
                }
            }
        }
        let n = unknowns.len();
        // Tikhonov weight from the forward rows (fixed over the iterations)
        let mut diag = vec![0.0; n];
        for (ids, vals) in &rows {
            for (a, &ia) in ids.iter().enumerate() {
                diag[local[ia as usize] as usize] += vals[a] * vals[a];
            }
        }
        let lambda = fo.regularization * diag.iter().sum::<f64>() / n.max(1) as f64;
        // elements touched by the unknowns (for the Jacobian safeguard)
        let touched: Vec<usize> = (0..sp.elems.len())
            .filter(|&e| sp.elems[e].basis.iter().any(|&b| local[b as usize] != u32::MAX))
            .collect();
        // quality floor per element: the fit may lower an element's minimum scaled
        // Jacobian to half its value (at most to 0.1), never below
        let floor: Vec<f64> = {
            use rayon::prelude::*;
            let spr: &Spline = sp;
            touched
                .par_iter()
                .map(|&e| {
                    let b = check::element_strict(spr, e);
                    if b > 0.0 {
                        (0.5 * b).min(0.1)
                    } else {
                        b
                    }
                })
                .collect()
        };
        FitSystem { rows, local, unknowns, lambda, touched, floor }
    }

    /// The regularised normal equations of one round (forward rows to `targets`,
    /// reverse rows to their surface points, Tikhonov pull to `p0`), solved by sparse
    /// Cholesky: the new positions of the unknowns, one row each.
    fn solve(&self, targets: &[[f64; 3]], rev: &[(Vec<u32>, Vec<f64>, [f64; 3])], p0: &[[f64; 3]]) -> Result<faer::Mat<f64>> {
        use faer::linalg::solvers::Solve;
        use faer::sparse::{SparseColMat, Triplet};
        let (local, lambda, n) = (&self.local, self.lambda, self.unknowns.len());
        let rows = &self.rows;
        let mut trip: Vec<Triplet<usize, usize, f64>> = Vec::new();
        let mut rhs = faer::Mat::<f64>::zeros(n, 3);
        let all = rows.iter().zip(targets).map(|((i, v), t)| (i, v, t)).chain(rev.iter().map(|(i, v, t)| (i, v, t)));
        for (ids, vals, t) in all {
            for (a, &ia) in ids.iter().enumerate() {
                let la = local[ia as usize] as usize;
                for j in 0..3 {
                    rhs[(la, j)] += vals[a] * t[j];
                }
                for (b, &ib) in ids.iter().enumerate() {
                    let lb = local[ib as usize] as usize;
                    if lb <= la {
                        trip.push(Triplet::new(la, lb, vals[a] * vals[b]));
                    }
                }
            }
        }
        for (l, p) in p0.iter().enumerate() {
            trip.push(Triplet::new(l, l, lambda));
            for j in 0..3 {
                rhs[(l, j)] += lambda * p[j];
            }
        }
        let a = SparseColMat::<usize, f64>::try_new_from_triplets(n, n, &trip)
            .map_err(|e| Error::SplineFailed(format!("fit matrix: {e:?}")))?;
        let llt = a
            .sp_cholesky(faer::Side::Lower)
            .map_err(|e| Error::SplineFailed(format!("fit factorisation: {e:?}")))?;
        llt.solve_in_place(rhs.as_mut());
        Ok(rhs)
    }

    /// Move the unknowns to `solution` with per-function step lengths, halved on the
    /// functions of every element that would fall below its floor; after the last
    /// halving a round that still breaks an element is dropped.
    fn apply_with_backtracking(&self, sp: &mut Spline, p0: &[[f64; 3]], rhs: &faer::Mat<f64>, fo: &FitOptions) {
        use rayon::prelude::*;
        let (local, unknowns, touched, floor, n) = (&self.local, &self.unknowns, &self.touched, &self.floor, self.unknowns.len());
        let mut alpha = vec![1.0f64; n];
        for round in 0..=fo.max_backtracks {
            for (l, &i) in unknowns.iter().enumerate() {
                let p = p0[l];
                sp.ctrl[i as usize] = [0, 1, 2].map(|j| p[j] + alpha[l] * (rhs[(l, j)] - p[j]));
            }
            let bad: Vec<usize> = {
                let spr: &Spline = sp;
                (0..touched.len())
                    .into_par_iter()
                    .filter(|&t| check::element_strict(spr, touched[t]) < floor[t])
                    .map(|t| touched[t])
                    .collect()
            };
            if bad.is_empty() {
                break;
            }
            let last = round == fo.max_backtracks;
            for &e in &bad {
                for &b in &sp.elems[e].basis {
                    let l = local[b as usize];
                    if l != u32::MAX {
                        alpha[l as usize] = if last { 0.0 } else { alpha[l as usize] * 0.5 };
                    }
                }
            }
            if last {
                for (l, &i) in unknowns.iter().enumerate() {
                    let p = p0[l];
                    sp.ctrl[i as usize] = [0, 1, 2].map(|j| p[j] + alpha[l] * (rhs[(l, j)] - p[j]));
                }
                // mixing moved and reverted points could still break an element:
                // then drop the whole round
                let spr: &Spline = sp;
                let still = (0..touched.len())
                    .into_par_iter()
                    .any(|t| check::element_strict(spr, touched[t]) < floor[t]);
                if still {
                    for (l, &i) in unknowns.iter().enumerate() {
                        sp.ctrl[i as usize] = p0[l];
                    }
                }
            }
        }
    }
}

/// Each forward row's target: the closest surface point to the row's current point.
fn forward_targets(sp: &Spline, rows: &[Row], loc: &SurfaceLocator) -> Vec<[f64; 3]> {
    use rayon::prelude::*;
    rows
        .par_iter()
        .map(|(ids, vals)| {
            let mut x = [0.0; 3];
            for (k, &i) in ids.iter().enumerate() {
                let c = sp.ctrl[i as usize];
                for j in 0..3 {
                    x[j] += vals[k] * c[j];
                }
            }
            loc.closest(x).0
        })
        .collect()
}

/// The reverse rows: every (strided) surface vertex with the closest point of the
/// spline boundary sampled `kf` x `kf` per face and triangulated.
fn reverse_rows(sp: &Spline, faces: &[(usize, usize, usize)], kf: usize, surf: &TriMesh, fo: &FitOptions, local: &[u32]) -> Vec<(Vec<u32>, Vec<f64>, [f64; 3])> {
    use rayon::prelude::*;
    let spr = sp;
    let params: Vec<(usize, [f64; 3])> = faces
        .iter()
        .flat_map(|&(e, d, s)| (0..kf * kf).map(move |k| (e, face_param(d, s, k % kf, k / kf, kf, false))))
        .collect();
    let tri = TriMesh { vertices: params.par_iter().map(|&(e, p)| point_of(spr, e, p)).collect(), triangles: face_grid_triangles(faces.len(), kf) };
    let bl = SurfaceLocator::new(&tri);
    let stride = surf.vertices.len().div_ceil(fo.max_reverse_points.max(1)).max(1);
    surf
        .vertices
        .par_iter()
        .step_by(stride)
        .filter_map(|&q| {
            let c = bl.closest_detailed(q)?;
            let t = tri.triangles[c.triangle as usize];
            let e = params[t[0] as usize].0;
            let mut p = [0.0; 3];
            for (k, &vi) in t.iter().enumerate() {
                for d in 0..3 {
                    p[d] += c.bary[k] * params[vi as usize].1[d];
                }
            }
            let el = &spr.elems[e];
            let v = apply_rows(&el.op, &bernstein::values(p));
            let mut ids = Vec::new();
            let mut vals = Vec::new();
            for (r, &x) in v.iter().enumerate() {
                if x.abs() > 1e-13 && local[el.basis[r] as usize] != u32::MAX {
                    ids.push(el.basis[r]);
                    vals.push(x);
                }
            }
            (!ids.is_empty()).then_some((ids, vals, q))
        })
        .collect()
}

impl Spline {
    /// Fit the boundary to a surface (see `FitOptions`); returns the distance after.
    pub fn fit_boundary(&mut self, surface: &TriMesh, fo: &FitOptions) -> Result<SurfaceDistance> {
        if surface.triangles.is_empty() {
            return Err(Error::InvalidArgument("the target surface has no triangles".into()));
        }
        let loc = SurfaceLocator::new(surface);
        fit_boundary_with(self, &loc, surface, fo)?;
        let d = surface_distance(self, &loc, surface, fo.samples);
        self.report.fitting_after = Some(d.clone());
        self.update_report();
        Ok(d)
    }

    /// Distance from the spline boundary to a surface (no change to the spline).
    pub fn distance_to(&self, surface: &TriMesh, samples: usize) -> Result<SurfaceDistance> {
        if surface.triangles.is_empty() {
            return Err(Error::InvalidArgument("the target surface has no triangles".into()));
        }
        let loc = SurfaceLocator::new(surface);
        Ok(surface_distance(self, &loc, surface, samples.max(1)))
    }
}

#[allow(dead_code)]
const _N: usize = NB;
