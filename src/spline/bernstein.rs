//! Cubic Bernstein polynomials on [0,1]^3, their derivatives, de Casteljau
//! subdivision and Gauss-Legendre rules.
//!
//! Index convention everywhere: Bernstein index `i + 4 j + 16 k`, `i` along the
//! first parametric direction u (VTK node 0 -> 1), `j` along v (0 -> 3), `k` along
//! w (0 -> 4).

/// Number of tricubic Bernstein polynomials.
pub const NB: usize = 64;

/// Bernstein index of (i, j, k).
#[inline]
pub fn bidx(i: usize, j: usize, k: usize) -> usize {
    i + 4 * j + 16 * k
}

/// (i, j, k) of a Bernstein index.
#[inline]
pub fn bijk(n: usize) -> [usize; 3] {
    [n % 4, (n / 4) % 4, n / 16]
}

/// Cubic Bernstein values and first and second derivatives at t.
pub fn cubic(t: f64) -> ([f64; 4], [f64; 4], [f64; 4]) {
    let s = 1.0 - t;
    let b = [s * s * s, 3.0 * t * s * s, 3.0 * t * t * s, t * t * t];
    let d = [-3.0 * s * s, 3.0 * s * s - 6.0 * t * s, 6.0 * t * s - 3.0 * t * t, 3.0 * t * t];
    let dd = [6.0 * s, -12.0 * s + 6.0 * t, 6.0 * s - 12.0 * t, 6.0 * t];
    (b, d, dd)
}

/// Tricubic Bernstein values at (u, v, w).
pub fn values(p: [f64; 3]) -> [f64; NB] {
    let (bu, _, _) = cubic(p[0]);
    let (bv, _, _) = cubic(p[1]);
    let (bw, _, _) = cubic(p[2]);
    let mut out = [0.0; NB];
    for k in 0..4 {
        for j in 0..4 {
            let vw = bv[j] * bw[k];
            for i in 0..4 {
                out[bidx(i, j, k)] = bu[i] * vw;
            }
        }
    }
    out
}

/// Tricubic Bernstein values and gradients (d/du, d/dv, d/dw) at (u, v, w).
pub fn values_and_gradients(p: [f64; 3]) -> ([f64; NB], [[f64; 3]; NB]) {
    let (bu, du, _) = cubic(p[0]);
    let (bv, dv, _) = cubic(p[1]);
    let (bw, dw, _) = cubic(p[2]);
    let mut val = [0.0; NB];
    let mut grad = [[0.0; 3]; NB];
    for k in 0..4 {
        for j in 0..4 {
            for i in 0..4 {
                let n = bidx(i, j, k);
                val[n] = bu[i] * bv[j] * bw[k];
                grad[n] = [du[i] * bv[j] * bw[k], bu[i] * dv[j] * bw[k], bu[i] * bv[j] * dw[k]];
            }
        }
    }
    (val, grad)
}

/// Values of the `order`-th partial derivative along direction `dir` (0, 1, 2) at p.
pub fn directional_derivative(p: [f64; 3], dir: usize, order: usize) -> [f64; NB] {
    let pick = |t: f64, d: bool| {
        let (b, db, ddb) = cubic(t);
        if !d {
            b
        } else {
            match order {
                0 => b,
                1 => db,
                _ => ddb,
            }
        }
    };
    let bu = pick(p[0], dir == 0);
    let bv = pick(p[1], dir == 1);
    let bw = pick(p[2], dir == 2);
    let mut out = [0.0; NB];
    for k in 0..4 {
        for j in 0..4 {
            for i in 0..4 {
                out[bidx(i, j, k)] = bu[i] * bv[j] * bw[k];
            }
        }
    }
    out
}

/// 1D de Casteljau split at 1/2: `SPLIT[c][r][s]` is the weight of parent
/// coefficient s in child c's coefficient r (c = 0 left half, 1 right half).
pub const SPLIT: [[[f64; 4]; 4]; 2] = [
    [
        [1.0, 0.0, 0.0, 0.0],
        [0.5, 0.5, 0.0, 0.0],
        [0.25, 0.5, 0.25, 0.0],
        [0.125, 0.375, 0.375, 0.125],
    ],
    [
        [0.125, 0.375, 0.375, 0.125],
        [0.0, 0.25, 0.5, 0.25],
        [0.0, 0.0, 0.5, 0.5],
        [0.0, 0.0, 0.0, 1.0],
    ],
];

/// Coefficients of one tricubic polynomial (64 Bernstein coefficients of the
/// parent) restricted to child `c` = (cx, cy, cz) in {0,1}^3, as Bernstein
/// coefficients of the child.
pub fn subdivide(parent: &[f64], child: [usize; 3], out: &mut [f64]) {
    debug_assert!(parent.len() == NB && out.len() == NB);
    let mut t1 = [0.0; NB];
    let mut t2 = [0.0; NB];
    let s0 = &SPLIT[child[0]];
    let s1 = &SPLIT[child[1]];
    let s2 = &SPLIT[child[2]];
    // along u
    for k in 0..4 {
        for j in 0..4 {
            for r in 0..4 {
                let mut acc = 0.0;
                for s in 0..4 {
                    acc += s0[r][s] * parent[bidx(s, j, k)];
                }
                t1[bidx(r, j, k)] = acc;
            }
        }
    }
    // along v
    for k in 0..4 {
        for i in 0..4 {
            for r in 0..4 {
                let mut acc = 0.0;
                for s in 0..4 {
                    acc += s1[r][s] * t1[bidx(i, s, k)];
                }
                t2[bidx(i, r, k)] = acc;
            }
        }
    }
    // along w
    for j in 0..4 {
        for i in 0..4 {
            for r in 0..4 {
                let mut acc = 0.0;
                for s in 0..4 {
                    acc += s2[r][s] * t2[bidx(i, j, s)];
                }
                out[bidx(i, j, r)] = acc;
            }
        }
    }
}

/// Gauss-Legendre points on [0, 1] and weights (summing to 1) for n = 1..=6.
pub fn gauss(n: usize) -> (Vec<f64>, Vec<f64>) {
    let (x, w): (Vec<f64>, Vec<f64>) = match n {
        1 => (vec![0.0], vec![2.0]),
        2 => {
            let a = 1.0 / 3f64.sqrt();
            (vec![-a, a], vec![1.0, 1.0])
        }
        3 => {
            let a = (3.0f64 / 5.0).sqrt();
            (vec![-a, 0.0, a], vec![5.0 / 9.0, 8.0 / 9.0, 5.0 / 9.0])
        }
        4 => {
            let a = (3.0 / 7.0 - 2.0 / 7.0 * (6.0f64 / 5.0).sqrt()).sqrt();
            let b = (3.0 / 7.0 + 2.0 / 7.0 * (6.0f64 / 5.0).sqrt()).sqrt();
            let wa = (18.0 + 30f64.sqrt()) / 36.0;
            let wb = (18.0 - 30f64.sqrt()) / 36.0;
            (vec![-b, -a, a, b], vec![wb, wa, wa, wb])
        }
        5 => {
            let a = 1.0 / 3.0 * (5.0 - 2.0 * (10.0f64 / 7.0).sqrt()).sqrt();
            let b = 1.0 / 3.0 * (5.0 + 2.0 * (10.0f64 / 7.0).sqrt()).sqrt();
            let w0 = 128.0 / 225.0;
            let wa = (322.0 + 13.0 * 70f64.sqrt()) / 900.0;
            let wb = (322.0 - 13.0 * 70f64.sqrt()) / 900.0;
            (vec![-b, -a, 0.0, a, b], vec![wb, wa, w0, wa, wb])
        }
        _ => {
            // n = 6
            let p = [0.2386191860831969, 0.6612093864662645, 0.9324695142031521];
            let q = [0.4679139345726910, 0.3607615730481386, 0.1713244923791704];
            (
                vec![-p[2], -p[1], -p[0], p[0], p[1], p[2]],
                vec![q[2], q[1], q[0], q[0], q[1], q[2]],
            )
        }
    };
    (x.iter().map(|t| 0.5 * (t + 1.0)).collect(), w.iter().map(|v| 0.5 * v).collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn partition_and_subdivision() {
        let v = values([0.3, 0.7, 0.1]);
        assert!((v.iter().sum::<f64>() - 1.0).abs() < 1e-14);
        // subdividing a random polynomial then evaluating the child agrees with the parent
        let parent: Vec<f64> = (0..64).map(|n| ((n * 37 % 11) as f64) - 5.0).collect();
        let mut child = vec![0.0; 64];
        subdivide(&parent, [1, 0, 1], &mut child);
        let p = [0.25, 0.6, 0.9];
        let q = [0.5 + 0.5 * p[0], 0.5 * p[1], 0.5 + 0.5 * p[2]];
        let a: f64 = values(p).iter().zip(&child).map(|(b, c)| b * c).sum();
        let b: f64 = values(q).iter().zip(&parent).map(|(b, c)| b * c).sum();
        assert!((a - b).abs() < 1e-12);
        let (x, w) = gauss(4);
        let int: f64 = x.iter().zip(&w).map(|(x, w)| w * x.powi(7)).sum();
        assert!((int - 1.0 / 8.0).abs() < 1e-14);
    }
}
