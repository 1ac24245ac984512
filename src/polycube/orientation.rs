//! The 24 proper rotations that map the grid's axes onto themselves (signed
//! permutation matrices with determinant +1). The PCA frame fixes the input's axes
//! only up to these, so candidates are tried in several of them.

/// A rotation as a signed permutation: new axis `a` = sign[a] * old axis perm[a].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
pub struct AxisRotation {
    pub perm: [usize; 3],
    pub sign: [i8; 3],
}

impl AxisRotation {
    pub const IDENTITY: AxisRotation = AxisRotation { perm: [0, 1, 2], sign: [1, 1, 1] };

    pub fn apply(&self, p: [f64; 3]) -> [f64; 3] {
        std::array::from_fn(|a| self.sign[a] as f64 * p[self.perm[a]])
    }

    pub fn apply_inverse(&self, q: [f64; 3]) -> [f64; 3] {
        let mut p = [0.0; 3];
        for a in 0..3 {
            p[self.perm[a]] = self.sign[a] as f64 * q[a];
        }
        p
    }

    /// Determinant of the matrix (+1 for the proper rotations).
    pub fn det(&self) -> i32 {
        let parity = {
            let p = self.perm;
            let mut inv = 0;
            for i in 0..3 {
                for j in i + 1..3 {
                    if p[i] > p[j] {
                        inv += 1;
                    }
                }
            }
            if inv % 2 == 0 {
                1
            } else {
                -1
            }
        };
        parity * self.sign.iter().map(|&s| s as i32).product::<i32>()
    }

    /// Short name, e.g. "+x+y+z" (identity) or "-y+x+z".
    pub fn name(&self) -> String {
        (0..3).map(|a| format!("{}{}", if self.sign[a] > 0 { '+' } else { '-' }, ['x', 'y', 'z'][self.perm[a]])).collect()
    }
}

/// All 24 proper rotations; index 0 is the identity, indices 1..4 keep the axis order
/// and flip two signs (the ambiguity PCA leaves when variances are distinct).
pub fn rotations() -> &'static [AxisRotation; 24] {
    static R: std::sync::OnceLock<[AxisRotation; 24]> = std::sync::OnceLock::new();
    R.get_or_init(|| {
        let perms = [[0, 1, 2], [0, 2, 1], [1, 0, 2], [1, 2, 0], [2, 0, 1], [2, 1, 0]];
        let mut v = Vec::with_capacity(24);
        for perm in perms {
            for s in 0..8 {
                let sign = [if s & 1 == 0 { 1 } else { -1 }, if s & 2 == 0 { 1 } else { -1 }, if s & 4 == 0 { 1 } else { -1 }];
                let r = AxisRotation { perm, sign };
                if r.det() == 1 {
                    v.push(r);
                }
            }
        }
        // identity first, then the sign flips that keep the axis order
        v.sort_by_key(|r| (r.perm != [0, 1, 2], r.sign.iter().filter(|&&s| s < 0).count()));
        v.try_into().unwrap()
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn twenty_four_distinct_proper_rotations() {
        let r = rotations();
        assert_eq!(r[0], AxisRotation::IDENTITY);
        for (i, a) in r.iter().enumerate() {
            assert_eq!(a.det(), 1);
            for b in &r[i + 1..] {
                assert_ne!(a, b);
            }
            let p = [0.3, -1.2, 2.5];
            let q = a.apply_inverse(a.apply(p));
            assert!((0..3).all(|k| (q[k] - p[k]).abs() < 1e-15));
        }
        assert!(r[1..4].iter().all(|a| a.perm == [0, 1, 2]));
    }
}
