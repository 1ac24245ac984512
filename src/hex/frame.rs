//! Affine maps between the frames of the hex stage:
//! grid units (polycube lattice) -> normalised frame N (context box, longest edge 2)
//! -> user coordinates U. The meshing itself works in W, a similarity of U
//! (bounding box centred, longest edge 2), because the scaled Jacobian is invariant
//! under similarities but not under the per-axis scaling between N and U.

use serde::{Deserialize, Serialize};

/// p -> m p + t (m by rows).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Affine {
    pub m: [[f64; 3]; 3],
    pub t: [f64; 3],
}

impl Affine {
    pub const IDENTITY: Affine = Affine { m: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]], t: [0.0; 3] };

    pub fn apply(&self, p: [f64; 3]) -> [f64; 3] {
        std::array::from_fn(|i| self.m[i][0] * p[0] + self.m[i][1] * p[1] + self.m[i][2] * p[2] + self.t[i])
    }

    pub fn apply_linear(&self, v: [f64; 3]) -> [f64; 3] {
        std::array::from_fn(|i| self.m[i][0] * v[0] + self.m[i][1] * v[1] + self.m[i][2] * v[2])
    }

    /// self after other: p -> self(other(p)).
    pub fn after(&self, other: &Affine) -> Affine {
        let m = std::array::from_fn(|i| std::array::from_fn(|j| (0..3).map(|k| self.m[i][k] * other.m[k][j]).sum()));
        Affine { m, t: self.apply(other.t) }
    }

    pub fn det(&self) -> f64 {
        let m = self.m;
        m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
    }

    /// The inverse map; None when singular or not finite.
    pub fn inverse(&self) -> Option<Affine> {
        let d = self.det();
        if !(d.abs() > 1e-300) || !d.is_finite() {
            return None;
        }
        let m = self.m;
        let inv = [
            [
                (m[1][1] * m[2][2] - m[1][2] * m[2][1]) / d,
                (m[0][2] * m[2][1] - m[0][1] * m[2][2]) / d,
                (m[0][1] * m[1][2] - m[0][2] * m[1][1]) / d,
            ],
            [
                (m[1][2] * m[2][0] - m[1][0] * m[2][2]) / d,
                (m[0][0] * m[2][2] - m[0][2] * m[2][0]) / d,
                (m[0][2] * m[1][0] - m[0][0] * m[1][2]) / d,
            ],
            [
                (m[1][0] * m[2][1] - m[1][1] * m[2][0]) / d,
                (m[0][1] * m[2][0] - m[0][0] * m[2][1]) / d,
                (m[0][0] * m[1][1] - m[0][1] * m[1][0]) / d,
            ],
        ];
        let a = Affine { m: inv, t: [0.0; 3] };
        let t = a.apply_linear(self.t);
        Some(Affine { m: inv, t: [-t[0], -t[1], -t[2]] })
    }

    /// Uniform scale s then translation: p -> s p + t.
    pub fn similarity(s: f64, t: [f64; 3]) -> Affine {
        Affine { m: [[s, 0.0, 0.0], [0.0, s, 0.0], [0.0, 0.0, s]], t }
    }

    /// Per-axis scale then translation.
    pub fn diagonal(s: [f64; 3], t: [f64; 3]) -> Affine {
        Affine { m: [[s[0], 0.0, 0.0], [0.0, s[1], 0.0], [0.0, 0.0, s[2]]], t }
    }

    /// From the library's similarity `Transform` (user -> aligned).
    pub fn from_transform(tr: &crate::geometry::Transform) -> Affine {
        let r = tr.rotation;
        Affine { m: std::array::from_fn(|i| std::array::from_fn(|j| tr.scale * r[i][j])), t: tr.translation }
    }

    pub fn is_finite(&self) -> bool {
        self.m.iter().flatten().chain(self.t.iter()).all(|v| v.is_finite())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inverse_and_compose() {
        let a = Affine { m: [[2.0, 1.0, 0.0], [0.0, 3.0, 0.5], [0.1, 0.0, 1.0]], t: [1.0, -2.0, 0.5] };
        let b = a.inverse().unwrap();
        let p = [0.3, -0.7, 2.0];
        let q = b.apply(a.apply(p));
        for k in 0..3 {
            assert!((p[k] - q[k]).abs() < 1e-12);
        }
        let c = b.after(&a);
        let r = c.apply(p);
        for k in 0..3 {
            assert!((p[k] - r[k]).abs() < 1e-12);
        }
    }
}
