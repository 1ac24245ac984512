//! The IGA Poisson solver: patch test, cubic reproduction with boundary
//! enrichment, convergence on a regular block, decreasing error on an
//! unstructured mesh, agreement of the direct and iterative solvers.

use sddpm::spline::iga::{solve_poisson, LinearSolver, PoissonOptions};
use sddpm::spline::{Spline, SplineOptions};

#[path = "support/meshes.rs"]
mod meshes;

fn exact(x: [f64; 3]) -> f64 {
    (1.1 * x[0]).sin() * (0.7 * x[1] + 0.3).cos() * (0.9 * x[2]).exp()
}
fn grad(x: [f64; 3]) -> [f64; 3] {
    let (a, b, c) = ((1.1 * x[0]).sin(), (0.7 * x[1] + 0.3).cos(), (0.9 * x[2]).exp());
    [1.1 * (1.1 * x[0]).cos() * b * c, -0.7 * a * (0.7 * x[1] + 0.3).sin() * c, 0.9 * a * b * c]
}
fn source(x: [f64; 3]) -> f64 {
    (1.21 + 0.49 - 0.81) * exact(x)
}

#[test]
fn spline_poisson_patch_test_linear_field() {
    // affine fields are reproduced exactly on any mesh (isoparametric, partition of unity)
    let lin = |x: [f64; 3]| 1.0 + 2.0 * x[0] - x[1] + 3.0 * x[2];
    for hex in [meshes::block([3, 3, 3], [1.0, 2.0, 1.0]), meshes::extraordinary_edge(5, 2, 3)] {
        let sp = Spline::construct(&hex, &SplineOptions::default()).unwrap();
        let po = PoissonOptions::default();
        let sol = solve_poisson(&sp, |_| 0.0, lin, &po).unwrap();
        let e = sol.errors(&sp, lin, |_| [2.0, -1.0, 3.0], &po).unwrap();
        assert!(e.l2 < 1e-9 && e.h1_semi < 1e-8, "{e:?}");
    }
}

#[test]
fn spline_poisson_cubic_is_exact_with_boundary_enrichment() {
    let u = |x: [f64; 3]| x[0] * x[0] * x[1] + x[2] * x[2] * x[2] - x[0] * x[1] * x[2];
    let g = |x: [f64; 3]| [2.0 * x[0] * x[1] - x[1] * x[2], x[0] * x[0] - x[0] * x[2], 3.0 * x[2] * x[2] - x[0] * x[1]];
    let f = |x: [f64; 3]| -(2.0 * x[1] + 6.0 * x[2]);
    let hex = meshes::block([3, 3, 3], [1.0, 1.0, 1.0]);
    let po = PoissonOptions::default();
    let enriched = Spline::construct(&hex, &SplineOptions { boundary_enrichment: true, ..Default::default() }).unwrap();
    let e = solve_poisson(&enriched, f, u, &po).unwrap().errors(&enriched, u, g, &po).unwrap();
    assert!(e.l2 < 1e-9, "enriched: {e:?}");
    // the natural end condition cannot represent x^2 y exactly
    let natural = Spline::construct(&hex, &SplineOptions::default()).unwrap();
    let e2 = solve_poisson(&natural, f, u, &po).unwrap().errors(&natural, u, g, &po).unwrap();
    assert!(e2.l2 > 1e-6, "natural: {e2:?}");
}

#[test]
fn spline_poisson_converges_at_tricubic_rate_on_a_block() {
    let po = PoissonOptions::default();
    let mut errs = Vec::new();
    for n in [3usize, 6, 12] {
        let hex = meshes::block([n, n, n], [1.0, 1.0, 1.0]);
        let sp = Spline::construct(&hex, &SplineOptions { boundary_enrichment: true, ..Default::default() }).unwrap();
        let sol = solve_poisson(&sp, source, exact, &po).unwrap();
        errs.push(sol.errors(&sp, exact, grad, &po).unwrap().l2);
    }
    let r1 = (errs[0] / errs[1]).log2();
    let r2 = (errs[1] / errs[2]).log2();
    assert!(r2 > 3.5 && r2 > r1 - 0.1, "L2 rates {r1:.2} {r2:.2} ({errs:?})");
}

#[test]
fn spline_poisson_error_decreases_on_unstructured_meshes() {
    let po = PoissonOptions::default();
    for valence in [3usize, 5] {
        let mut hex = meshes::extraordinary_edge(valence, 1, 3);
        let mut prev = f64::INFINITY;
        for _ in 0..2 {
            let sp = Spline::construct(&hex, &SplineOptions::default()).unwrap();
            let e = solve_poisson(&sp, source, exact, &po).unwrap().errors(&sp, exact, grad, &po).unwrap();
            assert!(e.l2 < prev / 3.0, "valence {valence}: {} then {}", prev, e.l2);
            prev = e.l2;
            hex = meshes::subdivide(&hex);
        }
        // THB refinement of every element also reduces the error
        let mut sp = Spline::construct(&meshes::extraordinary_edge(valence, 1, 3), &SplineOptions::default()).unwrap();
        let e0 = solve_poisson(&sp, source, exact, &po).unwrap().l2_error(&sp, exact, &po).unwrap();
        let all: Vec<usize> = (0..sp.num_elements()).collect();
        sp.refine(&all).unwrap();
        let e1 = solve_poisson(&sp, source, exact, &po).unwrap().l2_error(&sp, exact, &po).unwrap();
        assert!(e1 < e0 / 10.0, "valence {valence}: refinement {e0} -> {e1}");
    }
}

#[test]
fn spline_poisson_direct_and_iterative_agree() {
    let hex = meshes::extraordinary_edge(5, 2, 3);
    let mut sp = Spline::construct(&hex, &SplineOptions::default()).unwrap();
    sp.refine(&[0, 5]).unwrap();
    let a = solve_poisson(&sp, source, exact, &PoissonOptions { solver: LinearSolver::Cholesky, ..Default::default() }).unwrap();
    let b = solve_poisson(&sp, source, exact, &PoissonOptions { solver: LinearSolver::ConjugateGradient, cg_tolerance: 1e-13, ..Default::default() }).unwrap();
    assert_eq!(b.solver, "cg-jacobi");
    let d = a.coefficients.iter().zip(&b.coefficients).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max);
    assert!(d < 1e-8, "max coefficient difference {d}");
}
