//! The nonzero-mean forward process of DDPM-Polycube (DESIGN.md, "Diffusion"):
//!
//! x_t = sqrt(ab_t) x_0 + sqrt(1 - ab_t) z + Q_t q,
//! Q_t = sum_{k=1..t} sqrt((1 - a_k) prod_{i=k+1..t} a_i),
//!
//! i.e. every forward step adds noise of mean q: x_t = sqrt(a_t) x_{t-1} + sqrt(b_t) (z_t + q).
//! Steps are 1-based (t = 1..T); index 0 of the arrays stands for t = 0 (a_0 = 1).

use serde::{Deserialize, Serialize};

/// Schedule parameters stored with every weights file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ScheduleConfig {
    /// Number of diffusion steps T (reference 500).
    pub steps: usize,
    /// beta_1 (reference 1e-4).
    pub beta_start: f64,
    /// beta_T (reference 0.02).
    pub beta_end: f64,
    /// The mean field q, one constant per channel (x, y, z).
    pub q: [f64; 3],
}

impl Default for ScheduleConfig {
    fn default() -> Self {
        // q: a small constant drift of +0.01 per step-noise unit on every channel, so that
        // Q_T q (about 0.14 at T = 500) is a visible but modest shift of x_T.
        ScheduleConfig { steps: 500, beta_start: 1e-4, beta_end: 0.02, q: [0.01; 3] }
    }
}

/// Precomputed coefficients.
#[derive(Debug, Clone)]
pub struct Schedule {
    pub config: ScheduleConfig,
    /// beta_t, t = 0..=T (beta_0 = 0).
    pub beta: Vec<f64>,
    /// alpha_t = 1 - beta_t.
    pub alpha: Vec<f64>,
    /// alpha-bar_t = prod_{i<=t} alpha_i (alpha-bar_0 = 1).
    pub alpha_bar: Vec<f64>,
    /// Q_t (Q_0 = 0).
    pub qcoef: Vec<f64>,
}

impl Schedule {
    pub fn new(config: ScheduleConfig) -> Self {
        let t_max = config.steps;
        let mut beta = vec![0.0; t_max + 1];
        for (t, b) in beta.iter_mut().enumerate().skip(1) {
            *b = if t_max == 1 {
                config.beta_start
            } else {
                config.beta_start + (config.beta_end - config.beta_start) * (t - 1) as f64 / (t_max - 1) as f64
            };
        }
        let alpha: Vec<f64> = beta.iter().map(|b| 1.0 - b).collect();
        let mut alpha_bar = vec![1.0; t_max + 1];
        let mut qcoef = vec![0.0; t_max + 1];
        for t in 1..=t_max {
            alpha_bar[t] = alpha_bar[t - 1] * alpha[t];
            // Q_t = sqrt(a_t) Q_{t-1} + sqrt(1 - a_t)  (the recursion of the sum above)
            qcoef[t] = alpha[t].sqrt() * qcoef[t - 1] + (1.0 - alpha[t]).sqrt();
        }
        Schedule { config, beta, alpha, alpha_bar, qcoef }
    }

    pub fn steps(&self) -> usize {
        self.config.steps
    }

    /// Q_t evaluated directly from its defining sum (for tests).
    pub fn qcoef_direct(&self, t: usize) -> f64 {
        (1..=t)
            .map(|k| {
                let prod: f64 = ((k + 1)..=t).map(|i| self.alpha[i]).product();
                ((1.0 - self.alpha[k]) * prod).sqrt()
            })
            .sum()
    }

    /// q' of the reverse step: sqrt(1 - ab_t) / sqrt(1 - a_t) q (per channel).
    pub fn q_prime(&self, t: usize) -> [f64; 3] {
        let f = (1.0 - self.alpha_bar[t]).sqrt() / (1.0 - self.alpha[t]).sqrt();
        self.config.q.map(|q| f * q)
    }

    /// Forward sample on plain arrays (channels-first [3, H*W] per item): x_t from x_0 and z.
    pub fn forward_sample(&self, x0: &[f32], z: &[f32], t: usize, out: &mut [f32]) {
        let n = x0.len() / 3;
        let (a, s) = (self.alpha_bar[t].sqrt(), (1.0 - self.alpha_bar[t]).sqrt());
        for c in 0..3 {
            let shift = self.qcoef[t] * self.config.q[c];
            for i in c * n..(c + 1) * n {
                out[i] = (a * x0[i] as f64 + s * z[i] as f64 + shift) as f32;
            }
        }
    }

    /// One reverse step of DESIGN.md on plain arrays:
    /// x_{t-1} = (x_t - b_t / sqrt(1 - ab_t) (eps + q')) / sqrt(a_t) + sigma_t z, sigma_t^2 = b_t,
    /// no noise at t = 1. `z` may be None for the mean only.
    pub fn reverse_step(&self, xt: &[f32], eps: &[f32], t: usize, z: Option<&[f32]>, out: &mut [f32]) {
        let n = xt.len() / 3;
        let b = self.beta[t];
        let k = b / (1.0 - self.alpha_bar[t]).sqrt();
        let inv = 1.0 / self.alpha[t].sqrt();
        let qp = self.q_prime(t);
        let sigma = if t > 1 { b.sqrt() } else { 0.0 };
        for c in 0..3 {
            for i in c * n..(c + 1) * n {
                let mut v = (xt[i] as f64 - k * (eps[i] as f64 + qp[c])) * inv;
                if let Some(z) = z {
                    v += sigma * z[i] as f64;
                }
                out[i] = v as f32;
            }
        }
    }

    /// A deterministic (DDIM, eta = 0) step from t to s < t on the mean-shifted variable
    /// y_t = x_t - Q_t q, which follows a standard DDPM: used by the strided sampler.
    pub fn ddim_step(&self, xt: &[f32], eps: &[f32], t: usize, s: usize, out: &mut [f32]) {
        let n = xt.len() / 3;
        let (abt, abs) = (self.alpha_bar[t], self.alpha_bar[s]);
        for c in 0..3 {
            let (qt, qs) = (self.qcoef[t] * self.config.q[c], self.qcoef[s] * self.config.q[c]);
            for i in c * n..(c + 1) * n {
                let y = xt[i] as f64 - qt;
                let e = eps[i] as f64;
                let x0 = (y - (1.0 - abt).sqrt() * e) / abt.sqrt();
                let ys = abs.sqrt() * x0 + (1.0 - abs).sqrt() * e;
                out[i] = (ys + qs) as f32;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_distr::{Distribution, StandardNormal};

    #[test]
    fn qcoef_matches_its_sum() {
        let s = Schedule::new(ScheduleConfig::default());
        for t in [1, 2, 10, 100, 250, 499, 500] {
            let d = s.qcoef_direct(t);
            assert!((s.qcoef[t] - d).abs() < 1e-9 * d.max(1.0), "t={t}: {} vs {d}", s.qcoef[t]);
        }
        assert!((s.beta[1] - 1e-4).abs() < 1e-15 && (s.beta[500] - 0.02).abs() < 1e-15);
    }

    #[test]
    fn forward_then_exact_reverse_returns_the_input() {
        // One forward step x_t = sqrt(a_t) x_{t-1} + sqrt(b_t)(z + q); the reverse step of
        // DESIGN.md with the true noise eps and no added noise inverts it exactly when
        // eps is the noise of the one-step marginal, i.e. at t = 1 (ab_1 = a_1).
        let s = Schedule::new(ScheduleConfig::default());
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let n = 3 * 64;
        let x0: Vec<f32> = (0..n).map(|_| StandardNormal.sample(&mut rng)).collect();
        let z: Vec<f32> = (0..n).map(|_| StandardNormal.sample(&mut rng)).collect();
        let mut xt = vec![0f32; n];
        s.forward_sample(&x0, &z, 1, &mut xt);
        let mut back = vec![0f32; n];
        s.reverse_step(&xt, &z, 1, None, &mut back);
        for i in 0..n {
            assert!((back[i] - x0[i]).abs() < 1e-5, "{} vs {}", back[i], x0[i]);
        }
        // At any t, the DDIM step to 0 with the true noise recovers x_0 exactly.
        for t in [2, 50, 500] {
            s.forward_sample(&x0, &z, t, &mut xt);
            s.ddim_step(&xt, &z, t, 0, &mut back);
            for i in 0..n {
                assert!((back[i] - x0[i]).abs() < 2e-3, "t={t}: {} vs {}", back[i], x0[i]);
            }
        }
    }
}
