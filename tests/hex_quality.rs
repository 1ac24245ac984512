//! The Verdict hex scaled Jacobian against hand-computed values.

use sddpm::hex::quality::{histogram, scaled_jacobian, summarize, DEGENERATE};

const UNIT: [[f64; 3]; 8] =
    [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 1.0], [1.0, 1.0, 1.0], [0.0, 1.0, 1.0]];

#[test]
fn unit_cube_is_one() {
    assert!((scaled_jacobian(&UNIT) - 1.0).abs() < 1e-15);
    // any rotation, translation and scale of it too
    let (c, s) = (0.3f64.cos(), 0.3f64.sin());
    let moved = UNIT.map(|p| [2.5 * (c * p[0] - s * p[1]) + 7.0, 2.5 * (s * p[0] + c * p[1]) - 1.0, 2.5 * p[2] + 3.0]);
    assert!((scaled_jacobian(&moved) - 1.0).abs() < 1e-12);
}

#[test]
fn tapered_hex_by_hand() {
    // top face shrunk to [0.25, 0.75]^2: corner 0 has a = (1,0,0), b = (0,1,0),
    // c = (0.25, 0.25, 1): det 1, |c| = sqrt(1.125); corner 4 has a = (0,0.5,0),
    // b = (0.5,0,0), c = (-0.25,-0.25,-1): det 0.25 over 0.25 sqrt(1.125); the centre
    // axes (3,0,0), (0,3,0), (0,0,4) give 1. Minimum 1 / sqrt(1.125).
    let mut p = UNIT;
    for v in p.iter_mut().skip(4) {
        v[0] = 0.25 + 0.5 * v[0];
        v[1] = 0.25 + 0.5 * v[1];
    }
    assert!((scaled_jacobian(&p) - 1.0 / 1.125f64.sqrt()).abs() < 1e-12);
}

#[test]
fn one_corner_pulled_by_hand() {
    // node 6 moved to (2,2,2): corner 6 has a = (-1,-2,-1), b = (-2,-1,-1),
    // c = (-1,-1,-2): det 4, lengths sqrt(6) each -> 4 / 6^1.5 = 2 / (3 sqrt 6);
    // corners 2, 5, 7 give 2 / sqrt(6), the centre 112 / 27^1.5.
    let mut p = UNIT;
    p[6] = [2.0, 2.0, 2.0];
    let want = 2.0 / (3.0 * 6f64.sqrt());
    assert!((scaled_jacobian(&p) - want).abs() < 1e-12, "{}", scaled_jacobian(&p));
}

#[test]
fn inverted_and_degenerate() {
    let flipped = [UNIT[4], UNIT[5], UNIT[6], UNIT[7], UNIT[0], UNIT[1], UNIT[2], UNIT[3]];
    assert!((scaled_jacobian(&flipped) + 1.0).abs() < 1e-12);
    // node 6 pushed through the bottom face: corner 6 turns negative
    let mut p = UNIT;
    p[6] = [0.4, 0.4, -0.5];
    assert!(scaled_jacobian(&p) < 0.0);
    let mut d = UNIT;
    d[1] = d[0];
    assert_eq!(scaled_jacobian(&d), DEGENERATE);
    let s = summarize(&[1.0, 0.5, -0.2, DEGENERATE]);
    assert_eq!((s.inverted, s.elements), (2, 4));
    assert_eq!(s.min, -1.0);
    assert_eq!(histogram(&[1.0, 0.5, -0.2, DEGENERATE], 4), vec![1, 1, 0, 2]);
}
