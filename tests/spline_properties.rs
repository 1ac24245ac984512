//! Properties of the TH-spline3D construction on small meshes built in code:
//! one cube, a 3x3x3 block, meshes with an extraordinary edge of valence 3 and 5.

use sddpm::error::NoProgress;
use sddpm::hex::HexMesh;
use sddpm::spline::{build_spline, check, BasisKind, Spline, SplineOptions};

#[path = "support/meshes.rs"]
mod meshes;

fn build(hex: &HexMesh, opts: &SplineOptions) -> Spline {
    build_spline(hex, None, opts, &mut NoProgress).expect("spline")
}

fn basic_checks(name: &str, sp: &Spline) {
    let pu = check::partition_of_unity(sp, 20, 7);
    assert!(pu.max_sum_error < 1e-12, "{name}: partition of unity error {}", pu.max_sum_error);
    assert!(pu.min_value >= -1e-14, "{name}: negative basis value {}", pu.min_value);
    let lin = check::linear_reproduction(sp, 10, 11);
    assert!(lin < 1e-11, "{name}: linear field error {lin}");
    let (rank, n) = check::independence_rank(sp);
    assert_eq!(rank, n, "{name}: basis is not linearly independent");
    let r = sp.report();
    assert!(r.min_jacobian > 0.0, "{name}: min Jacobian {}", r.min_jacobian);
    assert_eq!(r.negative_jacobian_elements, 0);
    // extraction operator columns sum to 1
    for e in 0..sp.num_elements() {
        let c = sp.extraction_operator(e).unwrap();
        let n = sp.element_basis(e).unwrap().len();
        for k in 0..64 {
            let s: f64 = (0..n).map(|r| c[r * 64 + k]).sum();
            assert!((s - 1.0).abs() < 1e-12, "{name}: column {k} of element {e} sums to {s}");
        }
    }
}

#[test]
fn spline_one_cube_is_trilinear() {
    let hex = meshes::block([1, 1, 1], [2.0, 1.0, 3.0]);
    let sp = build(&hex, &SplineOptions::default());
    assert_eq!(sp.num_basis(), 8);
    assert_eq!(sp.num_elements(), 1);
    basic_checks("cube", &sp);
    // the map is the trilinear map of the box
    let (x, j) = sp.evaluate(0, 0.25, 0.5, 0.75).unwrap();
    assert!((x[0] - 0.5).abs() < 1e-14 && (x[1] - 0.5).abs() < 1e-14 && (x[2] - 2.25).abs() < 1e-14);
    assert!((j[0][0] - 2.0).abs() < 1e-13 && (j[1][1] - 1.0).abs() < 1e-13 && (j[2][2] - 3.0).abs() < 1e-13);
    assert!((sp.report().min_scaled_jacobian - 1.0).abs() < 1e-12);
}

#[test]
fn spline_block_3x3x3_is_c2_everywhere() {
    let hex = meshes::block([3, 3, 3], [1.0, 1.0, 1.0]);
    let sp = build(&hex, &SplineOptions::default());
    assert_eq!(sp.num_basis(), 64);
    assert_eq!(sp.num_elements(), 27);
    basic_checks("block", &sp);
    // natural-end tensor B-spline with interpolated corners: the map is the identity
    for e in 0..27 {
        let (lo, hi) = {
            let (_, lo, hi) = sp.element_box(e).unwrap();
            (lo, hi)
        };
        let _ = (lo, hi);
        let (x, j) = sp.evaluate(e, 0.3, 0.6, 0.9).unwrap();
        let corner = hex.element_corners(e)[0];
        let expect = [corner[0] + 0.3 / 3.0, corner[1] + 0.6 / 3.0, corner[2] + 0.9 / 3.0];
        for i in 0..3 {
            assert!((x[i] - expect[i]).abs() < 1e-13, "element {e}: {x:?} vs {expect:?}");
            assert!((j[i][i] - 1.0 / 3.0).abs() < 1e-12);
        }
    }
    // every interior face is C2 (tensor-product rules everywhere, sharp cube edges)
    let all = |_: u32, _: u32| true;
    let c = check::continuity(&sp, 3, Some(&all));
    assert_eq!(c.regular.faces, 54);
    assert!(c.regular.max_jump[0] < 1e-12, "{:?}", c.regular);
    assert!(c.regular.max_jump[1] < 1e-11, "{:?}", c.regular);
    assert!(c.regular.max_jump[2] < 1e-10, "{:?}", c.regular);
}

fn ee_checks(valence: usize) {
    let hex = meshes::extraordinary_edge(valence, 2, 3);
    let sp = build(&hex, &SplineOptions::default());
    assert_eq!(sp.topology().extraordinary_edge_count(), 3, "the three axis edges");
    basic_checks(&format!("valence {valence}"), &sp);
    let c = check::continuity(&sp, 3, None);
    // C0 everywhere, C1/C2 broken only where the rules are not tensor products
    assert!(c.other.max_jump[0] < 1e-12, "valence {valence}: value jump {:?}", c.other);
    assert!(c.regular.max_jump[0] < 1e-12);
    assert!(c.other.faces_c1_broken > 0, "valence {valence}: expected C0-only faces at the extraordinary edge");
    // faces between elements whose vertices are all regular interior vertices are C2
    if c.regular.faces > 0 {
        assert!(c.regular.max_jump[2] < 1e-9, "{:?}", c.regular);
    }
}

#[test]
fn spline_extraordinary_edge_valence_3() {
    ee_checks(3);
}

#[test]
fn spline_extraordinary_edge_valence_5() {
    ee_checks(5);
}

#[test]
fn spline_regular_disk_is_c2_in_its_regular_interior() {
    // valence 4: the same construction gives a regular grid; faces between
    // elements with only regular interior vertices must be C2
    let hex = meshes::extraordinary_edge(4, 3, 5);
    let sp = build(&hex, &SplineOptions::default());
    assert_eq!(sp.topology().extraordinary_edge_count(), 0);
    basic_checks("valence 4", &sp);
    let c = check::continuity(&sp, 3, None);
    assert!(c.regular.faces > 0);
    assert!(c.regular.max_jump[1] < 1e-10 && c.regular.max_jump[2] < 1e-9, "{:?}", c.regular);
}

#[test]
fn spline_refinement_keeps_properties() {
    for (name, hex) in [
        ("block", meshes::block([3, 3, 3], [1.0, 1.0, 1.0])),
        ("valence 3", meshes::extraordinary_edge(3, 2, 3)),
        ("valence 5", meshes::extraordinary_edge(5, 1, 3)),
    ] {
        let mut sp = build(&hex, &SplineOptions::default());
        let before: Vec<[f64; 3]> = (0..sp.num_elements()).map(|e| sp.evaluate(e, 0.3, 0.7, 0.2).unwrap().0).collect();
        let n0 = sp.num_elements();
        sp.refine(&[0, 1, n0 - 1]).unwrap();
        // refine again inside the refined region and at its border
        let m = sp.num_elements();
        sp.refine(&[0, m - 1, 2]).unwrap();
        basic_checks(&format!("{name} refined"), &sp);
        assert!(sp.report().max_level == 2);
        assert!((0..sp.num_basis()).any(|i| matches!(sp.basis_kind(i), BasisKind::Bernstein { .. })));
        // the geometry did not move: element 3 (never refined) evaluates as before
        let x = sp.evaluate(3, 0.3, 0.7, 0.2).unwrap().0;
        for i in 0..3 {
            assert!((x[i] - before[3][i]).abs() < 1e-12);
        }
        let c = check::continuity(&sp, 3, None);
        assert!(c.other.max_jump[0] < 1e-12 && c.regular.max_jump[0] < 1e-12);
    }
}

#[test]
fn spline_boundary_enrichment_keeps_properties() {
    let hex = meshes::block([3, 3, 3], [1.0, 1.0, 1.0]);
    let opts = SplineOptions { boundary_enrichment: true, ..Default::default() };
    let sp = build(&hex, &opts);
    assert!(sp.num_basis() > 64);
    basic_checks("enriched block", &sp);
}

#[test]
fn spline_rejects_bad_input() {
    let mut hex = meshes::block([1, 1, 1], [1.0, 1.0, 1.0]);
    hex.elements[0][3] = 99;
    assert!(build_spline(&hex, None, &SplineOptions::default(), &mut NoProgress).is_err());
    let empty = HexMesh::default();
    assert!(build_spline(&empty, None, &SplineOptions::default(), &mut NoProgress).is_err());
    let hex = meshes::block([1, 1, 1], [1.0, 1.0, 1.0]);
    let sp = build(&hex, &SplineOptions::default());
    assert!(sp.evaluate(0, 1.5, 0.0, 0.0).is_err());
    assert!(sp.evaluate(3, 0.5, 0.0, 0.0).is_err());
    let mut sp2 = sp.clone();
    assert!(sp2.refine(&[7]).is_err());
}

#[test]
fn spline_report_gives_the_share_of_c2_faces() {
    // a regular block: every interior face is C2
    let sp = build(&meshes::block([3, 3, 3], [1.0, 1.0, 1.0]), &SplineOptions::default());
    let r = sp.report();
    assert_eq!((r.c2_faces, r.interior_faces), (54, 54), "{r:?}");
    assert_eq!(r.c2_face_share, 1.0);
    // an extraordinary edge of valence 5: the faces at it lose C2, the others keep it
    let sp = build(&meshes::extraordinary_edge(5, 2, 3), &SplineOptions::default());
    let r = sp.report();
    assert!(r.interior_faces > 0 && r.c2_faces < r.interior_faces, "{r:?}");
    assert!(r.c2_face_share > 0.0 && r.c2_face_share < 1.0, "{r:?}");
    let c = check::continuity(&sp, 2, None);
    assert_eq!(r.interior_faces - r.c2_faces, c.regular.faces_c2_broken + c.other.faces_c2_broken);
}
