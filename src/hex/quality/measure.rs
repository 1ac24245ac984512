//! The Verdict hex scaled Jacobian (as VTK's vtkMeshQuality computes it): VTK node
//! order, the 8 corner tetrahedra plus the principal axes at the centre, each
//! determinant normalised by its three edge lengths, the minimum of the nine.

use crate::hex::HexMesh;

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn add(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

/// Corner (i; j, k, l) triples of Verdict's hex corner Jacobians.
pub const CORNERS: [[usize; 4]; 8] = [
    [0, 1, 3, 4],
    [1, 2, 0, 5],
    [2, 3, 1, 6],
    [3, 0, 2, 7],
    [4, 7, 5, 0],
    [5, 4, 6, 1],
    [6, 5, 7, 2],
    [7, 6, 4, 3],
];

/// Value Verdict returns when an edge or axis has (near) zero length.
pub const DEGENERATE: f64 = f64::MAX;

fn normalised_det(a: [f64; 3], b: [f64; 3], c: [f64; 3]) -> Option<f64> {
    let (la, lb, lc) = (dot(a, a), dot(b, b), dot(c, c));
    if la <= f64::MIN_POSITIVE || lb <= f64::MIN_POSITIVE || lc <= f64::MIN_POSITIVE {
        return None;
    }
    Some(dot(a, cross(b, c)) / (la * lb * lc).sqrt())
}

/// Scaled Jacobian of one hexahedron, in [-1, 1] (1 for a cube); DEGENERATE when an
/// edge or principal axis has zero length, as in Verdict.
pub fn scaled_jacobian(p: &[[f64; 3]; 8]) -> f64 {
    let x1 = add(add(sub(p[1], p[0]), sub(p[2], p[3])), add(sub(p[5], p[4]), sub(p[6], p[7])));
    let x2 = add(add(sub(p[3], p[0]), sub(p[2], p[1])), add(sub(p[7], p[4]), sub(p[6], p[5])));
    let x3 = add(add(sub(p[4], p[0]), sub(p[5], p[1])), add(sub(p[6], p[2]), sub(p[7], p[3])));
    let mut m = match normalised_det(x1, x2, x3) {
        Some(v) => v,
        None => return DEGENERATE,
    };
    for c in CORNERS {
        let o = p[c[0]];
        match normalised_det(sub(p[c[1]], o), sub(p[c[2]], o), sub(p[c[3]], o)) {
            Some(v) => m = m.min(v),
            None => return DEGENERATE,
        }
    }
    m.clamp(-1.0, 1.0)
}

/// Summary of the element qualities of a mesh.
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize, serde::Deserialize)]
pub struct QualitySummary {
    pub elements: usize,
    pub min: f64,
    pub mean: f64,
    pub max: f64,
    /// Elements with scaled Jacobian <= 0 (or degenerate).
    pub inverted: usize,
}

/// Per-element scaled Jacobians.
pub fn element_qualities(m: &HexMesh) -> Vec<f64> {
    (0..m.elements.len()).map(|e| scaled_jacobian(&m.element_corners(e))).collect()
}

pub fn summarize(q: &[f64]) -> QualitySummary {
    if q.is_empty() {
        return QualitySummary::default();
    }
    let mut s = QualitySummary { elements: q.len(), min: f64::INFINITY, mean: 0.0, max: f64::NEG_INFINITY, inverted: 0 };
    for &v in q {
        let v = if v == DEGENERATE { -1.0 } else { v };
        s.min = s.min.min(v);
        s.max = s.max.max(v);
        s.mean += v;
        if v <= 0.0 {
            s.inverted += 1;
        }
    }
    s.mean /= q.len() as f64;
    s
}

/// The summary of a mesh's element qualities.
pub fn summary(m: &HexMesh) -> QualitySummary {
    summarize(&element_qualities(m))
}

/// Histogram of scaled Jacobians over `bins` equal bins of [-1, 1].
pub fn histogram(q: &[f64], bins: usize) -> Vec<usize> {
    let mut h = vec![0usize; bins];
    for &v in q {
        let v = if v == DEGENERATE { -1.0 } else { v };
        let b = (((v + 1.0) / 2.0) * bins as f64).floor() as isize;
        h[b.clamp(0, bins as isize - 1) as usize] += 1;
    }
    h
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit() -> [[f64; 3]; 8] {
        crate::hex::HexMesh::unit_cube().element_corners(0)
    }

    #[test]
    fn unit_cube_is_one_and_scaling_keeps_it() {
        assert!((scaled_jacobian(&unit()) - 1.0).abs() < 1e-15);
        let stretched = unit().map(|p| [3.0 * p[0], 0.5 * p[1], 7.0 * p[2]]);
        assert!((scaled_jacobian(&stretched) - 1.0).abs() < 1e-12);
    }

    #[test]
    fn sheared_hex_by_hand() {
        // Shear the top face by s along x: corner 0 has a=(1,0,0), b=(0,1,0), c=(s,0,1):
        // det = 1, |c| = sqrt(1+s^2) -> 1/sqrt(1+s^2); every corner gives the same.
        let s = 0.75;
        let mut p = unit();
        for v in p.iter_mut().skip(4) {
            v[0] += s;
        }
        let want = 1.0 / (1.0f64 + s * s).sqrt();
        assert!((scaled_jacobian(&p) - want).abs() < 1e-12, "{} vs {want}", scaled_jacobian(&p));
    }

    #[test]
    fn flipped_node_order_is_negative() {
        let p = unit();
        let flipped = [p[4], p[5], p[6], p[7], p[0], p[1], p[2], p[3]];
        assert!((scaled_jacobian(&flipped) + 1.0).abs() < 1e-12);
        let mut collapsed = unit();
        collapsed[6] = collapsed[2];
        assert_eq!(scaled_jacobian(&collapsed), DEGENERATE);
        let s = summarize(&[1.0, -1.0, DEGENERATE, 0.5]);
        assert_eq!(s.inverted, 2);
        assert_eq!(histogram(&[1.0, -1.0, 0.0], 4), vec![1, 0, 1, 1]);
    }
}
