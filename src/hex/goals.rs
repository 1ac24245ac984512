//! The quality goals of a finished mesh and the ranking of meshes by them (the
//! candidates' meshes, the fallback's lattices, the feature-sheet variants).

use super::report::HexResult;
use serde::{Deserialize, Serialize};

/// Quality targets of a finished mesh.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct QualityGoals {
    /// Smallest acceptable minimum scaled Jacobian (default 0.3).
    pub min_scaled_jacobian: f64,
    /// Smallest acceptable mean scaled Jacobian (default 0.85).
    pub mean_scaled_jacobian: f64,
    /// Largest acceptable two-sided Hausdorff distance between the mesh boundary and
    /// the input, relative to the bounding-box diagonal (default 0.01).
    pub hausdorff: f64,
}

impl Default for QualityGoals {
    fn default() -> Self {
        QualityGoals { min_scaled_jacobian: 0.3, mean_scaled_jacobian: 0.85, hausdorff: 0.01 }
    }
}

impl QualityGoals {
    /// How many of the three goals `r` misses (a mesh with inverted elements misses
    /// the minimum one whatever the threshold).
    pub fn missed(&self, r: &HexResult) -> usize {
        let q = &r.quality;
        [q.inverted > 0 || !(q.min >= self.min_scaled_jacobian), !(q.mean >= self.mean_scaled_jacobian), !(r.hausdorff_relative <= self.hausdorff)]
            .iter()
            .filter(|&&m| m)
            .count()
    }

    /// Does `r` miss a scaled-Jacobian goal (an inverted element, the minimum or
    /// the mean), whatever its distance?
    pub fn misses_scaled_jacobian(&self, r: &HexResult) -> bool {
        r.quality.inverted > 0 || r.quality.min < self.min_scaled_jacobian || r.quality.mean < self.mean_scaled_jacobian
    }

    /// How far a mesh with these figures falls short of the goals: the sum over the
    /// three of the miss relative to the goal (0 for a goal met): (goal - min) /
    /// goal, (goal - mean) / goal, (distance - goal) / goal. A mesh with inverted
    /// elements falls short of the minimum goal by at least 1.
    pub fn shortfall_of(&self, inverted: usize, min: f64, mean: f64, hausdorff: f64) -> f64 {
        // a NaN figure misses by the most; a goal that is not positive counts nothing
        let rel = |miss: f64, goal: f64| {
            if !(goal > 0.0) {
                0.0
            } else if miss.is_nan() {
                f64::INFINITY
            } else {
                (miss / goal).max(0.0)
            }
        };
        let mut m = rel(self.min_scaled_jacobian - min, self.min_scaled_jacobian);
        if inverted > 0 {
            m = m.max(1.0);
        }
        m + rel(self.mean_scaled_jacobian - mean, self.mean_scaled_jacobian) + rel(hausdorff - self.hausdorff, self.hausdorff)
    }

    /// [`QualityGoals::shortfall_of`] of a mesh.
    pub fn shortfall(&self, r: &HexResult) -> f64 {
        self.shortfall_of(r.quality.inverted, r.quality.min, r.quality.mean, r.hausdorff_relative)
    }

    /// Ranking key of a mesh, smaller is better: inverted elements, goals missed,
    /// how far it falls short of them ([`QualityGoals::shortfall`]; a mesh at 2.4 %
    /// of a 1.5 % distance goal ranks below one at 0.94 % with a minimum of 0.28
    /// for a 0.3 goal), then the minimum scaled Jacobian (higher first).
    pub fn rank(&self, r: &HexResult) -> (usize, usize, f64, f64) {
        (r.quality.inverted, self.missed(r), self.shortfall(r), -r.quality.min)
    }

    /// Is `r` better than `best` by [`QualityGoals::rank`]?
    pub fn beats(&self, r: &HexResult, best: Option<&HexResult>) -> bool {
        best.is_none_or(|b| self.rank(r).partial_cmp(&self.rank(b)) == Some(std::cmp::Ordering::Less))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::context::Context;
    use crate::geometry::trimesh::tests::box_mesh;
    use crate::hex::{build_hex_mesh, Affine, HexInput, HexOptions};

    #[test]
    fn meshes_missing_as_many_goals_rank_by_how_far_they_miss() {
        let input = HexInput {
            surface: box_mesh([-1.0; 3], [1.0; 3]),
            context: Context::parse("cube,0,0,0,0,0,0,0,0,0,0,0").unwrap(),
            correspondence: vec![],
            to_user: Affine::similarity(1.0, [0.0; 3]),
        };
        let mut opts = HexOptions::default();
        opts.map.level = Some(1);
        let r = build_hex_mesh(&input, &opts, &mut crate::error::NoProgress).unwrap();
        let with = |min: f64, mean: f64, inverted: usize, h: f64| {
            let mut m = r.clone();
            (m.quality.min, m.quality.mean, m.quality.inverted, m.hausdorff_relative) = (min, mean, inverted, h);
            m
        };
        // cgal_spool's lattices with a 1.5 % distance goal (measured): 24 voxels at
        // 2.44 % with min 0.389, 65 voxels at 0.94 % with min 0.281; each misses one
        let goals = QualityGoals { hausdorff: 0.015, ..Default::default() };
        let (coarse, fine) = (with(0.389, 0.95, 0, 0.0244), with(0.281, 0.95, 0, 0.0094));
        assert_eq!((goals.missed(&coarse), goals.missed(&fine)), (1, 1));
        assert!((goals.shortfall(&coarse) - (0.0244 - 0.015) / 0.015).abs() < 1e-12);
        assert!((goals.shortfall(&fine) - (0.3 - 0.281) / 0.3).abs() < 1e-12);
        assert!(goals.beats(&fine, Some(&coarse)) && !goals.beats(&coarse, Some(&fine)));
        // meeting every goal: the higher minimum wins, as before
        let (a, b) = (with(0.5, 0.9, 0, 0.009), with(0.6, 0.86, 0, 0.0099));
        assert_eq!(goals.shortfall(&a), 0.0);
        assert!(goals.beats(&b, Some(&a)));
        // inverted elements first, however close the rest; then goals missed
        let inverted = with(-0.01, 0.95, 1, 0.001);
        assert!(goals.shortfall(&inverted) >= 1.0);
        assert!(goals.beats(&with(0.1, 0.5, 0, 0.5), Some(&inverted)));
        assert!(goals.beats(&with(0.29, 0.9, 0, 0.001), Some(&with(0.31, 0.84, 0, 0.02))));
        // a NaN figure ranks last among meshes missing as many goals
        assert!(goals.shortfall(&with(0.5, 0.9, 0, f64::NAN)).is_infinite());
        assert!(goals.beats(&with(0.5, 0.9, 0, 0.9), Some(&with(0.5, 0.9, 0, f64::NAN))));
    }
}
