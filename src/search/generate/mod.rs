//! Polycube generation: from an input surface and a context request to verified
//! candidate polycubes (user-guided mode here; the automated search lives in
//! `auto`). Every candidate keeps its occupancy pre-check, its verification report
//! and its diffusion output with the surface correspondence.

use super::inference::{occupancy_only, prepare, InferenceInput, Occupancy, DEFAULT_OVERSAMPLING};
use super::verify::{verify_cells, VerificationReport, VerifyOptions};
use crate::context::Context;
use crate::diffusion::Model;
use crate::diffusion::sample::{reverse_diffusion, SamplerOptions};
use crate::error::{check_progress, Error, Progress, Result};
use crate::geometry::orient::{align_axes, FrameChoice};
use crate::geometry::rng::seeded_rng;
use crate::geometry::{sample_surface, Alignment, SurfaceSample};
use crate::mesh::TriMesh;
use crate::polycube::orientation::{rotations, AxisRotation};
use crate::polycube::tensor::{unlayout, POINTS_PER_CELL};
use crate::polycube::{Primitive, NUM_CELLS};
use serde::{Deserialize, Serialize};
use std::time::Instant;

mod diffuse;
mod fit;
mod precheck;
pub mod register;
pub mod warp;
#[cfg(test)]
mod tests;

pub use precheck::{PRECHECK_SAMPLES, precheck, precheck_in, lay_out, without_fit_limit, limit_fit};
pub use fit::{FIT_TAU, FIT_SAMPLES, polycube_samples, fit_points, fit_score, fit_score_cells, fit_score_scaled, worst_and_mean, best_neighbour, refuse_worse_than_neighbours};
pub use diffuse::{diffuse_and_verify, generate_from_contexts, finish};

/// Which of the 24 grid-preserving rotations of the aligned input are tried.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
pub enum OrientationSearch {
    /// Only the frame as aligned.
    Identity,
    /// The aligned frame and its three sign flips (axis order kept).
    SignFlips,
    /// All 24 proper rotations of the grid's axes.
    #[default]
    All,
}

/// Start step of [`PolycubeOptions::visible_retry`]'s diffusion (BENCHMARKS.md, "The
/// visible prior": 50 / 100 / 150 / 200 measured on held-in seed 1000, 100 best).
pub const VISIBLE_RETRY_START_STEP: usize = 100;

/// Options of polycube generation, with documented defaults.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct PolycubeOptions {
    pub sampler: SamplerOptions,
    pub verify: VerifyOptions,
    pub orientations: OrientationSearch,
    /// Pre-check: the largest fraction of the input's surface allowed in cells the
    /// context leaves empty (default 0.03).
    pub max_in_empty_fraction: f64,
    /// Pre-check: an occupied cell must receive at least this fraction of its fair share
    /// (1 / occupied cells) of the surface (default 0.2).
    pub min_occupied_fraction: f64,
    /// Orientations kept per context after the pre-check (best first; default 1).
    pub orientations_per_context: usize,
    /// Pre-check: the largest geometric fit score (penalty Chamfer distance, squared
    /// cell units, between the mapped input and the context's exact polycube surface)
    /// a candidate may have to be diffused (default 0.05).
    pub max_fit: f64,
    /// Pre-check: candidates whose fit is within this factor of the input's best fit
    /// are diffused even above `max_fit` (default 2). `max_fit` was set on synthetic
    /// cells; real parts (round holes, fillets, unequal cells) fit no template that
    /// well (BENCHMARKS.md "Main job": 0.08 for a torus, 0.1-0.3 for pinion, eight and
    /// three-hole block), and refusing every candidate of an input before diffusion
    /// would leave verification nothing to decide. 0 turns the relative rule off.
    pub relative_fit: f64,
    /// The relative rule admits no fit above this (default 0.5: measured between the
    /// worst fit of a right context on the test meshes, 0.28 for the eight's two
    /// through holes, and the 0.67 of a blind hole asked of a plain box).
    pub relative_fit_cap: f64,
    /// Pre-check: measure each candidate's fit after a quadratic registration of
    /// the box-mapped input onto its polycube as well ([`warp`]), keep the lower of
    /// the two fits, and lay the input out for diffusion after the registration
    /// when it fits better (default true: a bent, twisted or tapered part fits its
    /// right context again, a missing or misplaced hole still does not).
    pub warp_fit: bool,
    /// Pre-check of a caller's context (user-guided mode): refused when changing one
    /// occupied cell's label to another of the same genus fits the input this many
    /// times better ([`best_neighbour`]; default 1.5, 0 turns it off). Measured
    /// (BENCHMARKS.md, "Discrimination"): the true context's fit over its best
    /// one-cell alternative is at most 1.034 on 256 held-in synthetic cases and at
    /// most 1.000 for the contexts the automated mode verifies on the ten test meshes
    /// that get one; wrong genus-consistent contexts that the other pre-checks pass
    /// are above 1.5 in 112 of 135 trials.
    pub neighbour_fit_ratio: f64,
    /// A candidate whose output fails verification is diffused again with the
    /// visible prior (`SamplerOptions::visible_prior`, the template attention without
    /// the faces a cell shares with an occupied neighbour, from step
    /// [`VISIBLE_RETRY_START_STEP`]) and verified with `VerifyOptions::visible_coverage`;
    /// passing there verifies it (`Candidate::visible_retry`). Only the template
    /// estimate has a prior: default false, true in [`PolycubeOptions::template`],
    /// where with the mean-cell-fit score it lifts the automated recovery on
    /// held-in assemblies (docs/history/context-search.md, "Ranking verified
    /// candidates by the mean cell fit": seed 5000, 24 cases per group, 22 / 18 / 10
    /// -> 23 / 21 / 16 of 24 for simple / medium / complex) for about a quarter more
    /// time in the medium and complex groups. No effect when the sampler already
    /// uses the visible prior.
    pub visible_retry: bool,
    /// Surface samples drawn from the input (shared by every candidate).
    pub oversampling: usize,
    /// Seed of sampling and diffusion.
    pub seed: u64,
}

impl Default for PolycubeOptions {
    fn default() -> Self {
        PolycubeOptions {
            sampler: SamplerOptions::default(),
            verify: VerifyOptions::default(),
            orientations: OrientationSearch::All,
            max_in_empty_fraction: 0.03,
            min_occupied_fraction: 0.2,
            orientations_per_context: 1,
            max_fit: 0.05,
            relative_fit: 2.0,
            relative_fit_cap: 0.5,
            warp_fit: true,
            neighbour_fit_ratio: 1.5,
            visible_retry: false,
            oversampling: DEFAULT_OVERSAMPLING,
            seed: 0,
        }
    }
}

impl PolycubeOptions {
    /// The options that go with the baseline generator, the closed-form template
    /// estimate ([`crate::diffusion::Model::template`]): its sampler
    /// ([`SamplerOptions::template`]), its TCV threshold
    /// ([`super::verify::TAU_CD_TEMPLATE`]), TCV's coverage over the whole template (its
    /// output carries the faces shared with neighbours), and the second diffusion
    /// with the visible prior for a candidate that fails.
    pub fn template() -> Self {
        let mut o = PolycubeOptions { sampler: SamplerOptions::template(), visible_retry: true, ..Default::default() };
        o.verify.visible_coverage = false;
        o.verify.tau_cd = super::verify::TAU_CD_TEMPLATE;
        o
    }

    /// The default options for a model: [`PolycubeOptions::template`] for a
    /// generator that samples with the template estimate, else the defaults.
    pub fn for_model(model: &Model) -> Self {
        if model.net.is_template(SamplerOptions::template().kernel_gate) && model.net.field().is_none() {
            Self::template()
        } else {
            Self::default()
        }
    }
}

/// How far a candidate got.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Stage {
    /// Passed the pre-check, not diffused yet.
    Pending,
    /// Refused by the occupancy pre-check (no diffusion).
    Occupancy,
    /// Diffused, failed GOCC.
    Gocc,
    /// Passed GOCC, failed TCV.
    Tcv,
    /// Passed both.
    Verified,
}

/// One candidate polycube.
#[derive(Debug, Clone, Serialize)]
pub struct Candidate {
    #[serde(serialize_with = "ser_ctx")]
    pub context: Context,
    pub labels: [u8; NUM_CELLS],
    pub rotation: String,
    #[serde(skip)]
    pub axis_rotation: AxisRotation,
    pub occupancy: Occupancy,
    /// Geometric fit of the mapped input to the exact polycube (squared cell units):
    /// the worst cell's ([`fit_score`]). The pre-check's limits apply to it.
    pub fit: f64,
    /// The mean over the occupied cells of the same per-cell fits
    /// ([`fit_score_cells`]); the ranking score of a diffused candidate.
    pub fit_mean: f64,
    pub stage: Stage,
    /// Why the pre-check refused a candidate whose occupancy and fit passed (a
    /// one-cell alternative of the context fits the input far better).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub refusal: Option<String>,
    pub report: Option<VerificationReport>,
    /// Mean squared distance between the output and the input samples it started
    /// from (model frame); lower means the polycube stayed closer to the input.
    pub fidelity: Option<f64>,
    /// Ranking score of a diffused candidate, lower is better: `fit_mean` (after
    /// `openings_missed`, see [`finish`]). The worst
    /// cell alone ties candidates that differ only in cells fitting better than the
    /// worst one, and the mean target PCD separates them no better; measured on 72
    /// held-in cases (BENCHMARKS.md, "Ranking verified candidates by the mean cell
    /// fit").
    pub score: Option<f64>,
    /// Verified by the second diffusion with the visible prior
    /// ([`PolycubeOptions::visible_retry`]); its output and report are that run's.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub visible_retry: bool,
    /// The quadratic registration of the input onto this candidate's polycube
    /// ([`warp`]) that its fit was measured after and its inference input is laid
    /// out with; None: the box map alone.
    #[serde(skip)]
    pub warp: Option<warp::Warp>,
    /// Whether the fit and the inference input are those after the registration.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub warped: bool,
    /// The cells (bit n for cell n) whose input shows the label's hole, which
    /// TCV then decides among the labels of the context's genus
    /// ([`crate::search::verify::VerifyOptions::same_genus_rivals`]); set by the
    /// automated mode from its subregions' openings, 0 elsewhere.
    #[serde(skip_serializing_if = "is_zero")]
    pub holes_shown: u16,
    /// Occupied cells whose label the input's openings there do not carry (a
    /// hole the cell does not show, or a cube where it shows one); set by the
    /// automated mode with `AutoOptions::opening_labels`, 0 elsewhere. Among the
    /// verified candidates the fewest come first, then the score.
    #[serde(skip_serializing_if = "is_zero")]
    pub openings_missed: u8,
    #[serde(skip)]
    pub input: Option<InferenceInput>,
    /// Diffusion output [3, 64, 96].
    #[serde(skip)]
    pub output: Option<Vec<f32>>,
}

fn is_zero<T: Default + PartialEq>(v: &T) -> bool {
    *v == T::default()
}

fn ser_ctx<S: serde::Serializer>(c: &Context, s: S) -> std::result::Result<S::Ok, S::Error> {
    s.serialize_str(&c.names())
}

impl Candidate {
    /// Keep a diffusion output and its verification; the fidelity is measured on it.
    fn set_output(&mut self, output: Vec<f32>, report: VerificationReport) {
        self.output = Some(output);
        let pairs = self.correspondence();
        self.fidelity = Some(pairs.iter().map(|(a, b)| (0..3).map(|j| (a[j] - b[j]).powi(2)).sum::<f64>()).sum::<f64>() / pairs.len().max(1) as f64);
        self.report = Some(report);
    }

    /// Pairs (point of the polycube output, input surface sample it came from), both in
    /// the model frame; only occupied cells' slots.
    pub fn correspondence(&self) -> Vec<([f64; 3], [f64; 3])> {
        let (Some(inp), Some(out)) = (&self.input, &self.output) else { return Vec::new() };
        let blocks = unlayout(out);
        let mut v = Vec::new();
        for n in 0..NUM_CELLS {
            for p in 0..POINTS_PER_CELL {
                if let Some(s) = inp.slots[n * POINTS_PER_CELL + p] {
                    v.push((blocks[n][p].map(|x| x as f64), inp.map.forward(s.point)));
                }
            }
        }
        v
    }
}

/// Timings of the polycube stage, seconds.
#[derive(Debug, Clone, Default, Serialize)]
pub struct PolycubeTimings {
    pub align: f64,
    pub precheck: f64,
    pub diffusion: f64,
    pub verification: f64,
    pub total: f64,
}

/// Everything polycube generation produced.
#[derive(Debug, Clone, Serialize)]
pub struct PolycubeResult {
    pub input_genus: i64,
    pub source: &'static str,
    #[serde(skip)]
    pub alignment: Alignment,
    pub frame: FrameChoice,
    pub candidates: Vec<Candidate>,
    /// Index of the chosen candidate (verified, best score).
    pub chosen: Option<usize>,
    pub timings: PolycubeTimings,
    /// The generator that made the outputs: the learned weights' name, or
    /// "template" for the closed-form template estimate (`Model::generator_name`).
    pub generator: String,
    /// The aligned input's surface samples ([`PreparedInput::samples`]) the
    /// candidates were laid out from, kept so that a candidate refused before
    /// layout can be laid out later (the main job's fallback order) without
    /// aligning and sampling the input again.
    #[serde(skip)]
    pub samples: std::sync::Arc<Vec<SurfaceSample>>,
}

impl PolycubeResult {
    pub fn verified(&self) -> impl Iterator<Item = &Candidate> {
        self.candidates.iter().filter(|c| c.stage == Stage::Verified)
    }

    /// The chosen candidate, or the error that explains why there is none.
    pub fn accepted(&self) -> Result<&Candidate> {
        match self.chosen {
            Some(i) => Ok(&self.candidates[i]),
            None => Err(Error::VerificationFailed(self.failure_summary())),
        }
    }

    fn failure_summary(&self) -> String {
        let diffused = self.candidates.iter().filter(|c| c.stage != Stage::Occupancy && c.stage != Stage::Pending).count();
        let mut s = format!(
            "none of {} candidate(s) passed ({} refused by the occupancy pre-check, {} failed GOCC, {} failed TCV)",
            self.candidates.len(),
            self.candidates.len() - diffused,
            self.candidates.iter().filter(|c| c.stage == Stage::Gocc).count(),
            self.candidates.iter().filter(|c| c.stage == Stage::Tcv).count()
        );
        if let Some(c) = self.candidates.iter().find(|c| c.report.is_some()) {
            if let Some(r) = c.report.as_ref().and_then(|r| r.reason.clone()) {
                s.push_str(&format!("; first: {} -> {r}", c.context));
            }
        } else if let Some(c) = self.candidates.iter().find(|c| c.refusal.is_some()) {
            s.push_str(&format!("; first: {} -> {}", c.context, c.refusal.as_deref().unwrap_or_default()));
        } else if let Some(c) = self.candidates.first() {
            s.push_str(&format!(
                "; first: {} leaves {:.1}% of the surface in empty cells, {} starved cell(s), geometric fit {:.4} (squared cell units)",
                c.context,
                100.0 * c.occupancy.in_empty_cells,
                c.occupancy.starved_cells.len(),
                c.fit
            ));
        }
        if self.source == "user" {
            s.push_str("; revise the context or use the automated mode (--auto)");
        }
        s
    }
}

/// Checks a caller's contexts before any diffusion: valid assemblies whose genus is the input's.
pub fn check_contexts(contexts: &[Context], input_genus: i64) -> Result<()> {
    if contexts.is_empty() {
        return Err(Error::InvalidArgument("no context given".into()));
    }
    for (i, c) in contexts.iter().enumerate() {
        let v = c.validity();
        if !v.valid {
            return Err(Error::InvalidContext(format!("context {i} ({c}): {}", v.reason.unwrap_or_default())));
        }
        let g = v.genus.unwrap();
        if g != input_genus {
            return Err(Error::GenusMismatch {
                input: input_genus,
                context: g,
                detail: format!(" (context {i}: {c}); no diffusion was run"),
            });
        }
    }
    Ok(())
}

/// Prepared input shared by all candidates of one surface.
pub struct PreparedInput {
    pub alignment: Alignment,
    pub frame: FrameChoice,
    pub samples: Vec<SurfaceSample>,
    /// Surface area of the aligned mesh.
    pub area: f64,
}

pub fn prepare_input(mesh: &TriMesh, opts: &PolycubeOptions) -> Result<PreparedInput> {
    let (alignment, frame) = align_axes(mesh)?;
    const INPUT_SAMPLES_STREAM: u64 = 0x5a3f;
    let mut rng = seeded_rng(opts.seed, INPUT_SAMPLES_STREAM);
    let samples = sample_surface(&alignment.mesh, opts.oversampling.max(POINTS_PER_CELL), &mut rng);
    if samples.is_empty() {
        return Err(Error::InvalidMesh("the surface has no area to sample".into()));
    }
    let area = crate::geometry::surface_moments(&alignment.mesh).area;
    Ok(PreparedInput { alignment, frame, samples, area })
}
