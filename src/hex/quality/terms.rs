//! The nine Verdict terms of a hex element (the eight corner determinants and the
//! principal axes, each normalised by its edge lengths) with their gradients
//! with respect to one node, and the soft minimum of such terms: the search
//! direction of the max-min optimisation and of the mean ascent.

use super::measure::CORNERS;
use crate::hex::work::Work;
use crate::geometry::vec3::*;

/// Value and gradient (w.r.t. the position of local node `m`) of one normalised
/// determinant term with vectors a, b, c whose coefficients of node m are `alpha`.
#[inline]
fn term_grad(a: [f64; 3], b: [f64; 3], c: [f64; 3], alpha: [f64; 3]) -> Option<(f64, [f64; 3])> {
    let (la, lb, lc) = (dot(a, a), dot(b, b), dot(c, c));
    if la <= 1e-300 || lb <= 1e-300 || lc <= 1e-300 {
        return None;
    }
    let s = 1.0 / (la * lb * lc).sqrt();
    let bc = cross(b, c);
    let t = dot(a, bc) * s;
    let ga = sub(scale(bc, s), scale(a, t / la));
    let gb = sub(scale(cross(c, a), s), scale(b, t / lb));
    let gc = sub(scale(cross(a, b), s), scale(c, t / lc));
    let g = add(add(scale(ga, alpha[0]), scale(gb, alpha[1])), scale(gc, alpha[2]));
    Some((t, g))
}

/// The nine Verdict terms of an element with node index m (0..8) and their gradients
/// w.r.t. node m (zero for the terms that do not involve it).
fn element_terms(p: &[[f64; 3]; 8], m: usize, out: &mut Vec<(f64, [f64; 3])>) {
    for c in CORNERS {
        let alpha = if c[0] == m {
            [-1.0, -1.0, -1.0]
        } else if c[1] == m {
            [1.0, 0.0, 0.0]
        } else if c[2] == m {
            [0.0, 1.0, 0.0]
        } else if c[3] == m {
            [0.0, 0.0, 1.0]
        } else {
            [0.0; 3]
        };
        let o = p[c[0]];
        if let Some(r) = term_grad(sub(p[c[1]], o), sub(p[c[2]], o), sub(p[c[3]], o), alpha) {
            out.push(r);
        } else {
            out.push((-1.0, [0.0; 3]));
        }
    }
    let x1 = add(add(sub(p[1], p[0]), sub(p[2], p[3])), add(sub(p[5], p[4]), sub(p[6], p[7])));
    let x2 = add(add(sub(p[3], p[0]), sub(p[2], p[1])), add(sub(p[7], p[4]), sub(p[6], p[5])));
    let x3 = add(add(sub(p[4], p[0]), sub(p[5], p[1])), add(sub(p[6], p[2]), sub(p[7], p[3])));
    let s1 = if matches!(m, 1 | 2 | 5 | 6) { 1.0 } else { -1.0 };
    let s2 = if matches!(m, 2 | 3 | 6 | 7) { 1.0 } else { -1.0 };
    let s3 = if m >= 4 { 1.0 } else { -1.0 };
    if let Some(r) = term_grad(x1, x2, x3, [s1, s2, s3]) {
        out.push(r);
    } else {
        out.push((-1.0, [0.0; 3]));
    }
}

/// Gradient of the soft minimum (temperature 1/beta) of all terms of the elements of v.
pub fn softmin_gradient(w: &Work, v: u32, beta: f64, buf: &mut Vec<(f64, [f64; 3])>) -> [f64; 3] {
    buf.clear();
    for &e in w.n2e.of(v as usize) {
        let el = w.mesh.elements[e as usize];
        let p: [[f64; 3]; 8] = std::array::from_fn(|k| w.mesh.nodes[el[k] as usize]);
        let m = el.iter().position(|&x| x == v).unwrap();
        element_terms(&p, m, buf);
    }
    softmin_of(buf, beta)
}

/// Gradient of the soft minimum (temperature 1/beta) of terms given with their gradients.
fn softmin_of(terms: &[(f64, [f64; 3])], beta: f64) -> [f64; 3] {
    let tmin = terms.iter().map(|t| t.0).fold(f64::INFINITY, f64::min);
    let mut g = [0.0; 3];
    let mut ws = 0.0;
    for (t, gt) in terms.iter() {
        let wt = (-beta * (t - tmin)).exp();
        ws += wt;
        g = add(g, scale(*gt, wt));
    }
    if ws > 0.0 {
        scale(g, 1.0 / ws)
    } else {
        g
    }
}

/// Gradient, w.r.t. local node `m`, of the soft minimum (temperature 1/beta) of the
/// nine Verdict terms of one element.
pub fn element_softmin_gradient(p: &[[f64; 3]; 8], m: usize, beta: f64, buf: &mut Vec<(f64, [f64; 3])>) -> [f64; 3] {
    buf.clear();
    element_terms(p, m, buf);
    softmin_of(buf, beta)
}
