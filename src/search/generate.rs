//! Polycube generation: from an input surface and a context request to verified
//! candidate polycubes (user-guided mode here; the automated search lives in
//! `auto`). Every candidate keeps its occupancy pre-check, its verification report
//! and its diffusion output with the surface correspondence.

use super::inference::{occupancy_only, prepare, InferenceInput, Occupancy, DEFAULT_OVERSAMPLING};
use super::verify::{verify, VerificationReport, VerifyOptions};
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
    /// Ranking score of a diffused candidate, lower is better: `fit_mean`. The worst
    /// cell alone ties candidates that differ only in cells fitting better than the
    /// worst one, and the mean target PCD separates them no better; measured on 72
    /// held-in cases (BENCHMARKS.md, "Ranking verified candidates by the mean cell
    /// fit").
    pub score: Option<f64>,
    /// Verified by the second diffusion with the visible prior
    /// ([`PolycubeOptions::visible_retry`]); its output and report are that run's.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub visible_retry: bool,
    #[serde(skip)]
    pub input: Option<InferenceInput>,
    /// Diffusion output [3, 64, 96].
    #[serde(skip)]
    pub output: Option<Vec<f32>>,
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

/// Samples used by the cheap pre-check (a prefix of the shared samples).
pub const PRECHECK_SAMPLES: usize = 8192;

/// The occupancy pre-check of one context over the orientation search: the best
/// orientations (lowest surface fraction in empty cells, then fewest starved cells)
/// become candidates; only those that pass get their full inference tensor.
pub fn precheck(input: &PreparedInput, ctx: &Context, opts: &PolycubeOptions) -> Result<Vec<Candidate>> {
    let rots: Vec<AxisRotation> = match opts.orientations {
        OrientationSearch::Identity => vec![rotations()[0]],
        OrientationSearch::SignFlips => rotations()[..4].to_vec(),
        OrientationSearch::All => rotations().to_vec(),
    };
    let sub = &input.samples[..input.samples.len().min(PRECHECK_SAMPLES)];
    let mut scored: Vec<(usize, Occupancy)> = rots
        .iter()
        .enumerate()
        .filter_map(|(k, r)| occupancy_only(sub, ctx, *r, opts.min_occupied_fraction).map(|o| (k, o)))
        .collect();
    if scored.is_empty() {
        return Err(Error::InvalidContext(format!("{ctx}: no occupied cell")));
    }
    scored.sort_by(|a, b| {
        a.1.starved_cells.len().min(1).cmp(&b.1.starved_cells.len().min(1))
            .then(a.1.in_empty_cells.total_cmp(&b.1.in_empty_cells))
            .then(a.1.starved_cells.len().cmp(&b.1.starved_cells.len()))
            .then(a.0.cmp(&b.0))
    });
    let passes = |o: &Occupancy| o.in_empty_cells <= opts.max_in_empty_fraction && o.starved_cells.is_empty();
    // Among the orientations the occupancy allows, rank by geometric fit.
    let fit_sub = &input.samples[..input.samples.len().min(FIT_SAMPLES)];
    let target = polycube_samples(ctx, FIT_SAMPLES);
    let mut ranked: Vec<(usize, Occupancy, (f64, f64))> = scored
        .into_iter()
        .map(|(k, o)| {
            let f = if passes(&o) { worst_and_mean(&fit_score_cells(fit_sub, ctx, rots[k], &target, [1.0; 3])) } else { (f64::INFINITY, f64::INFINITY) };
            (k, o, f)
        })
        .collect();
    ranked.sort_by(|a, b| (!passes(&a.1)).cmp(&!passes(&b.1)).then(a.2 .0.total_cmp(&b.2 .0)).then(a.0.cmp(&b.0)));
    let n_pass = ranked.iter().filter(|(_, o, f)| passes(o) && f.0 <= opts.max_fit).count();
    let keep = if n_pass == 0 { 1 } else { n_pass.min(opts.orientations_per_context.max(1)) };
    let mut out = Vec::with_capacity(keep);
    for (k, occ, (fit, fit_mean)) in ranked.into_iter().take(keep) {
        let r = rots[k];
        let ok = passes(&occ) && fit <= opts.max_fit;
        out.push(Candidate {
            context: *ctx,
            labels: ctx.label_values(),
            rotation: r.name(),
            axis_rotation: r,
            occupancy: occ,
            fit,
            fit_mean,
            stage: if ok { Stage::Pending } else { Stage::Occupancy },
            report: None,
            refusal: None,
            visible_retry: false,
            fidelity: None,
            score: None,
            input: None,
            output: None,
        });
    }
    Ok(out)
}

/// Lay out the inference input (all samples mapped onto the context's box, see
/// [`prepare`]) of every pending candidate that has none yet: called after the fit
/// limit ([`limit_fit`]), so that the candidates it refuses are never laid out.
/// The candidate's occupancy becomes the one measured on all samples.
pub fn lay_out(input: &PreparedInput, cands: &mut [Candidate], opts: &PolycubeOptions) -> Result<()> {
    for c in cands.iter_mut().filter(|c| c.stage == Stage::Pending && c.input.is_none()) {
        let k = rotations().iter().position(|r| *r == c.axis_rotation).unwrap_or(0);
        const LAYOUT_SEED: u64 = 0x9e37;
        let mut rng = seeded_rng(opts.seed ^ LAYOUT_SEED, k as u64);
        let t = prepare(&input.samples, &c.context, c.axis_rotation, opts.min_occupied_fraction, &mut rng)?;
        c.occupancy = t.occupancy.clone();
        c.input = Some(t);
    }
    Ok(())
}

/// The options of a pre-check that refuses on occupancy only (the fit limit is
/// applied over all of an input's candidates by [`limit_fit`]).
pub fn without_fit_limit(opts: &PolycubeOptions) -> PolycubeOptions {
    let mut o = opts.clone();
    o.max_fit = f64::INFINITY;
    o
}

/// The pre-check's fit limit over all of an input's candidates: a candidate that
/// passed the occupancy test is diffused when its fit is at most `max_fit` or at
/// most `relative_fit` times the best fit among them (and at most
/// `relative_fit_cap`); the others are refused
/// (stage `Occupancy`, their fit in the report).
/// `best_elsewhere`: the best fit of candidates prechecked apart from these (the
/// automated mode's other occupied boxes), so that a box whose every context fits
/// far worse than another box's best is not diffused on its own terms.
pub fn limit_fit(cands: &mut [Candidate], opts: &PolycubeOptions, best_elsewhere: f64) {
    let best = cands.iter().filter(|c| c.stage == Stage::Pending).map(|c| c.fit).fold(best_elsewhere, f64::min);
    let rel = if opts.relative_fit > 0.0 && best.is_finite() { (opts.relative_fit * best).min(opts.relative_fit_cap) } else { 0.0 };
    let limit = opts.max_fit.max(rel);
    for c in cands.iter_mut().filter(|c| c.stage == Stage::Pending) {
        if !(c.fit <= limit) {
            c.stage = Stage::Occupancy;
            c.input = None;
        }
    }
}

/// The fit score is a penalty Chamfer distance with this threshold (squared cell
/// units: 0.1 cell), so that a missing or extra hole, whose points lie 1/6 cell or
/// more from the other surface, weighs far more than a smooth deformation.
pub const FIT_TAU: f64 = 0.01;

/// Samples used by the geometric fit score.
pub const FIT_SAMPLES: usize = 2048;

/// `n` points uniform on the exact boundary of a context's assembly, in grid units,
/// each with the cell of the voxel it bounds.
pub fn polycube_samples(ctx: &Context, n: usize) -> Vec<([f64; 3], usize)> {
    let q = crate::polycube::boundary(&ctx.assemble());
    if q.quads.is_empty() {
        return Vec::new();
    }
    const POLYCUBE_SAMPLES_SEED: u64 = 0xf17;
    let mut rng = seeded_rng(POLYCUBE_SAMPLES_SEED, ctx.occupancy_mask() as u64);
    use rand::RngExt;
    (0..n)
        .map(|_| {
            let k = rng.random_range(0..q.quads.len());
            let f = q.quads[k].map(|i| q.vertices[i as usize]);
            let v = q.quad_voxel[k].0;
            let (u, w): (f64, f64) = (rng.random(), rng.random());
            let p = std::array::from_fn(|a| f[0][a] + u * (f[1][a] - f[0][a]) + w * (f[3][a] - f[0][a]));
            (p, crate::polycube::cell_index(v[0] / 3, v[1] / 3, v[2] / 3))
        })
        .collect()
}

/// Geometric fit of the input to a context (squared cell units; lower is better): the
/// input samples are mapped onto the context's box under `rotation` and compared with
/// the exact polycube surface `target` by a penalty Chamfer distance per cell (each
/// point's distance to the whole other set, averaged over the points of that cell);
/// the score is the worst cell's. A missing, extra or misdirected hole in one cell
/// shows up in full instead of being diluted by the other cells.
pub fn fit_score(samples: &[SurfaceSample], ctx: &Context, rotation: AxisRotation, target: &[([f64; 3], usize)]) -> f64 {
    fit_score_scaled(samples, ctx, rotation, target, [1.0; 3])
}

/// The per-cell values of [`fit_score_scaled`] (NaN for unoccupied cells, infinite
/// when the mapping or a cell's input is empty).
pub fn fit_score_cells(samples: &[SurfaceSample], ctx: &Context, rotation: AxisRotation, target: &[([f64; 3], usize)], scale: [f64; 3]) -> [f64; NUM_CELLS] {
    use kiddo::{ImmutableKdTree, SquaredEuclidean};
    let Some((frame, dlo, dhi)) = crate::search::inference::context_box(ctx) else { return [f64::INFINITY; NUM_CELLS] };
    let (glo, ghi) = crate::polycube::assembly::occupied_cell_box(&ctx.labels).unwrap();
    let rotated: Vec<[f64; 3]> = samples.iter().map(|s| rotation.apply(s.point)).collect();
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for r in &rotated {
        for a in 0..3 {
            lo[a] = lo[a].min(r[a]);
            hi[a] = hi[a].max(r[a]);
        }
    }
    let map = crate::search::inference::BoxMap { rotation: AxisRotation::IDENTITY, src_lo: lo, src_hi: hi, dst_lo: dlo, dst_hi: dhi };
    let mapped: Vec<[f64; 3]> = rotated.iter().map(|r| map.forward(*r)).collect();
    if mapped.is_empty() || target.is_empty() {
        return [f64::INFINITY; NUM_CELLS];
    }
    let cells_in: Vec<usize> = mapped.iter().map(|q| crate::search::inference::cell_of(&frame, glo, ghi, &ctx.labels, *q)).collect();
    let scaled = |p: [f64; 3]| -> [f64; 3] { std::array::from_fn(|a| p[a] * scale[a]) };
    let grid_in: Vec<[f64; 3]> = mapped.iter().map(|q| scaled(frame.to_grid(*q))).collect();
    let tgt: Vec<[f64; 3]> = target.iter().map(|t| scaled(t.0)).collect();
    let t_in = ImmutableKdTree::new_from_slice(&grid_in).expect("non-empty");
    let t_tg = ImmutableKdTree::new_from_slice(&tgt).expect("non-empty");
    let f = |d: f64| if d <= FIT_TAU { d } else { d * (1.0 + (d / FIT_TAU).powi(2)) };
    let mut sum_in = [0.0f64; NUM_CELLS];
    let mut n_in = [0usize; NUM_CELLS];
    for (p, &c) in grid_in.iter().zip(&cells_in) {
        sum_in[c] += f(t_tg.query(p).nearest_one::<SquaredEuclidean<f64>>().execute().distance);
        n_in[c] += 1;
    }
    let mut sum_tg = [0.0f64; NUM_CELLS];
    let mut n_tg = [0usize; NUM_CELLS];
    for (p, (_, c)) in tgt.iter().zip(target) {
        sum_tg[*c] += f(t_in.query(p).nearest_one::<SquaredEuclidean<f64>>().execute().distance);
        n_tg[*c] += 1;
    }
    let mut cells = [f64::NAN; NUM_CELLS];
    for c in 0..NUM_CELLS {
        if n_tg[c] == 0 {
            continue;
        }
        let a = if n_in[c] > 0 { sum_in[c] / n_in[c] as f64 } else { f64::INFINITY };
        cells[c] = 0.5 * (a + sum_tg[c] / n_tg[c] as f64);
    }
    cells
}

/// [`fit_score`] with the grid coordinates multiplied by `scale` per axis before the
/// distances are taken: with the part's cell widths over a common length as the
/// scale, fits of boxes with different cell counts become comparable (a single
/// stretched cell is not favoured over three cells of the same part just because its
/// cell is three times longer). The worst cell of [`fit_score_cells`].
pub fn fit_score_scaled(samples: &[SurfaceSample], ctx: &Context, rotation: AxisRotation, target: &[([f64; 3], usize)], scale: [f64; 3]) -> f64 {
    worst_and_mean(&fit_score_cells(samples, ctx, rotation, target, scale)).0
}

/// The worst and the mean of per-cell fits ([`fit_score_cells`]; NaN cells are
/// unoccupied); both infinite when a cell's fit is.
pub fn worst_and_mean(cells: &[f64; NUM_CELLS]) -> (f64, f64) {
    if cells.iter().any(|c| c.is_infinite()) {
        return (f64::INFINITY, f64::INFINITY);
    }
    let occupied: Vec<f64> = cells.iter().copied().filter(|c| !c.is_nan()).collect();
    let worst = occupied.iter().fold(0.0, |w: f64, c| w.max(*c));
    let mean = if occupied.is_empty() { 0.0 } else { occupied.iter().sum::<f64>() / occupied.len() as f64 };
    (worst, mean)
}

/// The best-fitting one-cell alternative of a candidate's context: every occupied cell
/// given every other non-null label whose assembly stays valid with the same genus,
/// fitted under the candidate's orientation ([`fit_score`], the same box since the
/// occupancy is unchanged). Returns (cell, label, fit) of the best one, or None when
/// the context has no such alternative.
pub fn best_neighbour(input: &PreparedInput, c: &Candidate) -> Option<(usize, Primitive, f64)> {
    let genus = c.context.validity().genus?;
    let fit_sub = &input.samples[..input.samples.len().min(FIT_SAMPLES)];
    let mut alts = Vec::new();
    for n in c.context.occupied() {
        for &l in &Primitive::ALL[1..] {
            if l == c.context.labels[n] {
                continue;
            }
            let mut w = c.context;
            w.labels[n] = l;
            if w.validity().genus == Some(genus) {
                alts.push((n, l, w));
            }
        }
    }
    use rayon::prelude::*;
    alts.par_iter()
        .map(|(n, l, w)| (*n, *l, fit_score(fit_sub, w, c.axis_rotation, &polycube_samples(w, FIT_SAMPLES))))
        .min_by(|a, b| a.2.total_cmp(&b.2))
}

/// The neighbour test of the pre-check: a pending candidate whose fit is more than
/// `ratio` times the fit of its best one-cell alternative ([`best_neighbour`]) is
/// refused (stage `Occupancy`) with the cell, both labels and both fits in its
/// `refusal`. `ratio <= 0` turns the test off.
pub fn refuse_worse_than_neighbours(input: &PreparedInput, cands: &mut [Candidate], ratio: f64) {
    if !(ratio > 0.0) {
        return;
    }
    for c in cands.iter_mut().filter(|c| c.stage == Stage::Pending) {
        let Some((n, l, f)) = best_neighbour(input, c) else { continue };
        if c.fit > ratio * f {
            let [x, y, z] = crate::polycube::cell_coords(n);
            c.refusal = Some(format!(
                "cell {n} ({x}, {y}, {z}): the context fits the input {:.1}x better with {} in this cell than with the given {} (geometric fit {:.4} against {:.4}, squared cell units; refused above {ratio}x)",
                c.fit / f,
                l.name(),
                c.context.labels[n].name(),
                f,
                c.fit
            ));
            c.stage = Stage::Occupancy;
            c.input = None;
        }
    }
}

/// Diffuse and verify the candidates that passed the pre-check (batched).
pub fn diffuse_and_verify(
    model: &Model,
    cands: &mut [Candidate],
    opts: &PolycubeOptions,
    progress: &mut dyn Progress,
    timings: &mut PolycubeTimings,
) -> Result<()> {
    let idx: Vec<usize> = (0..cands.len()).filter(|&i| cands[i].stage == Stage::Pending && cands[i].input.is_some()).collect();
    if idx.is_empty() {
        return Ok(());
    }
    let inputs: Vec<Vec<f32>> = idx.iter().map(|&i| cands[i].input.as_ref().unwrap().tensor.clone()).collect();
    let ctxs: Vec<Context> = idx.iter().map(|&i| cands[i].context).collect();
    let t0 = Instant::now();
    let out = reverse_diffusion(model, &inputs, &ctxs, &opts.sampler, progress)?;
    timings.diffusion += t0.elapsed().as_secs_f64();
    let t0 = Instant::now();
    for (k, &i) in idx.iter().enumerate() {
        let c = &mut cands[i];
        let inp = c.input.as_ref().unwrap();
        let rep = verify(&out.tensors[k], &c.context, &inp.frame, &opts.verify);
        c.stage = if !rep.gocc_pass {
            Stage::Gocc
        } else if !rep.tcv_pass {
            Stage::Tcv
        } else {
            Stage::Verified
        };
        c.score = Some(c.fit_mean);
        c.set_output(out.tensors[k].clone(), rep);
    }
    timings.verification += t0.elapsed().as_secs_f64();
    if opts.visible_retry && !opts.sampler.visible_prior {
        visible_retry(model, cands, &idx, opts, progress, timings)?;
    }
    Ok(())
}

/// The second opinion of [`PolycubeOptions::visible_retry`]: the candidates of `idx`
/// that failed verification are diffused again with the visible prior (start step
/// [`VISIBLE_RETRY_START_STEP`]) and verified with visible coverage; one that passes
/// is verified, with that output and report (its score, the mean cell fit, does not
/// depend on the output).
fn visible_retry(model: &Model, cands: &mut [Candidate], idx: &[usize], opts: &PolycubeOptions, progress: &mut dyn Progress, timings: &mut PolycubeTimings) -> Result<()> {
    let again: Vec<usize> = idx.iter().copied().filter(|&i| cands[i].stage != Stage::Verified).collect();
    if again.is_empty() {
        return Ok(());
    }
    let inputs: Vec<Vec<f32>> = again.iter().map(|&i| cands[i].input.as_ref().unwrap().tensor.clone()).collect();
    let ctxs: Vec<Context> = again.iter().map(|&i| cands[i].context).collect();
    let sampler = SamplerOptions { visible_prior: true, start_step: VISIBLE_RETRY_START_STEP, ..opts.sampler.clone() };
    let verify_opts = VerifyOptions { visible_coverage: true, ..opts.verify.clone() };
    let t0 = Instant::now();
    let out = reverse_diffusion(model, &inputs, &ctxs, &sampler, progress)?;
    timings.diffusion += t0.elapsed().as_secs_f64();
    let t0 = Instant::now();
    for (k, &i) in again.iter().enumerate() {
        let c = &mut cands[i];
        let rep = verify(&out.tensors[k], &c.context, &c.input.as_ref().unwrap().frame, &verify_opts);
        if rep.passed {
            c.stage = Stage::Verified;
            c.set_output(out.tensors[k].clone(), rep);
            c.visible_retry = true;
        }
    }
    timings.verification += t0.elapsed().as_secs_f64();
    Ok(())
}

/// User-guided mode with complete contexts (one or a stack). `input_genus` is the
/// genus the mesh check measured. A context of another genus is refused before any
/// diffusion.
pub fn generate_from_contexts(
    model: &Model,
    mesh: &TriMesh,
    input_genus: i64,
    contexts: &[Context],
    opts: &PolycubeOptions,
    progress: &mut dyn Progress,
) -> Result<PolycubeResult> {
    let t_all = Instant::now();
    check_contexts(contexts, input_genus)?;
    let mut timings = PolycubeTimings::default();
    let t0 = Instant::now();
    let input = prepare_input(mesh, opts)?;
    timings.align = t0.elapsed().as_secs_f64();
    check_progress(progress, 0.0, "occupancy pre-check")?;
    let t0 = Instant::now();
    let mut cands = Vec::new();
    for c in contexts {
        cands.extend(precheck(&input, c, &without_fit_limit(opts))?);
    }
    limit_fit(&mut cands, opts, f64::INFINITY);
    refuse_worse_than_neighbours(&input, &mut cands, opts.neighbour_fit_ratio);
    lay_out(&input, &mut cands, opts)?;
    timings.precheck = t0.elapsed().as_secs_f64();
    diffuse_and_verify(model, &mut cands, opts, progress, &mut timings)?;
    timings.total = t_all.elapsed().as_secs_f64();
    Ok(finish(input, input_genus, "user", cands, timings, model.generator_name(opts.sampler.kernel_gate)))
}

/// Rank the verified candidates and build the result.
pub fn finish(input: PreparedInput, input_genus: i64, source: &'static str, cands: Vec<Candidate>, timings: PolycubeTimings, generator: String) -> PolycubeResult {
    let chosen = cands
        .iter()
        .enumerate()
        .filter(|(_, c)| c.stage == Stage::Verified && c.output.is_some())
        .min_by(|a, b| a.1.score.unwrap_or(f64::INFINITY).total_cmp(&b.1.score.unwrap_or(f64::INFINITY)))
        .map(|(i, _)| i);
    PolycubeResult { input_genus, source, alignment: input.alignment, frame: input.frame, candidates: cands, chosen, timings, generator, samples: std::sync::Arc::new(input.samples) }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cand(fit: f64, stage: Stage) -> Candidate {
        Candidate {
            context: Context::parse("THC+Z,0,0,0,0,0,0,0,0,0,0,0").unwrap(),
            labels: [0; NUM_CELLS],
            rotation: String::new(),
            axis_rotation: rotations()[0],
            occupancy: Occupancy { area_fraction: [0.0; NUM_CELLS], in_empty_cells: 0.0, starved_cells: Vec::new() },
            fit,
            fit_mean: fit,
            stage,
            report: None,
            refusal: None,
            visible_retry: false,
            fidelity: None,
            score: None,
            input: None,
            output: None,
        }
    }

    #[test]
    fn fit_limit_is_absolute_or_relative_to_the_best_candidate() {
        let stages = |c: &[Candidate]| c.iter().map(|c| c.stage).collect::<Vec<_>>();
        // a real part: nothing under max_fit; the best and those within 2x are diffused
        let mut c = vec![cand(0.083, Stage::Pending), cand(0.15, Stage::Pending), cand(0.17, Stage::Pending), cand(f64::INFINITY, Stage::Occupancy)];
        limit_fit(&mut c, &PolycubeOptions::default(), f64::INFINITY);
        assert_eq!(stages(&c), [Stage::Pending, Stage::Pending, Stage::Occupancy, Stage::Occupancy]);
        // the relative rule off: max_fit alone refuses them all
        let mut c = vec![cand(0.083, Stage::Pending), cand(0.15, Stage::Pending)];
        limit_fit(&mut c, &PolycubeOptions { relative_fit: 0.0, ..Default::default() }, f64::INFINITY);
        assert_eq!(stages(&c), [Stage::Occupancy, Stage::Occupancy]);
        // a good fit: max_fit admits up to 0.05 even beyond 2x the best
        let mut c = vec![cand(0.004, Stage::Pending), cand(0.04, Stage::Pending), cand(0.06, Stage::Pending)];
        limit_fit(&mut c, &PolycubeOptions::default(), f64::INFINITY);
        assert_eq!(stages(&c), [Stage::Pending, Stage::Pending, Stage::Occupancy]);
        // another box fits far better: these are judged against its best
        let mut c = vec![cand(1.05, Stage::Pending), cand(1.06, Stage::Pending)];
        limit_fit(&mut c, &PolycubeOptions::default(), 0.28);
        assert_eq!(stages(&c), [Stage::Occupancy, Stage::Occupancy]);
        // ... but never above the cap
        let mut c = vec![cand(0.45, Stage::Pending), cand(0.6, Stage::Pending), cand(0.67, Stage::Pending)];
        limit_fit(&mut c, &PolycubeOptions::default(), f64::INFINITY);
        assert_eq!(stages(&c), [Stage::Pending, Stage::Occupancy, Stage::Occupancy]);
        // a NaN fit is never admitted
        let mut c = vec![cand(f64::NAN, Stage::Pending)];
        limit_fit(&mut c, &PolycubeOptions::default(), f64::INFINITY);
        assert_eq!(stages(&c), [Stage::Occupancy]);
    }

    #[test]
    fn only_candidates_the_fit_limit_admits_are_laid_out() {
        // a through-hole cube input; contexts with the hole (fit) and without (refused)
        let truth = Context::parse("THC+Z,0,0,0,0,0,0,0,0,0,0,0").unwrap();
        let mesh = crate::polycube::boundary(&truth.assemble()).to_trimesh();
        let opts = PolycubeOptions::default();
        let input = prepare_input(&mesh, &opts).unwrap();
        let mut cands = Vec::new();
        for c in ["THC+X,0,0,0,0,0,0,0,0,0,0,0", "THC+Z,0,0,0,0,0,0,0,0,0,0,0", "Cube,0,0,0,0,0,0,0,0,0,0,0", "Cube,Cube,0,0,0,0,0,0,0,0,0,0"] {
            cands.extend(precheck(&input, &Context::parse(c).unwrap(), &without_fit_limit(&opts)).unwrap());
        }
        // the pre-check lays out nothing
        assert!(cands.iter().all(|c| c.input.is_none()));
        limit_fit(&mut cands, &opts, f64::INFINITY);
        lay_out(&input, &mut cands, &opts).unwrap();
        let pending = cands.iter().filter(|c| c.stage == Stage::Pending).count();
        assert!(pending >= 1 && pending < cands.len(), "{:?}", cands.iter().map(|c| (c.context.to_string(), c.fit, c.stage)).collect::<Vec<_>>());
        for c in &cands {
            // laid out exactly when admitted, with the occupancy of all samples
            assert_eq!(c.input.is_some(), c.stage == Stage::Pending, "{} {:?}", c.context, c.stage);
            if let Some(i) = &c.input {
                assert_eq!(i.occupancy.area_fraction, c.occupancy.area_fraction);
            }
        }
    }

    #[test]
    fn the_visible_retry_verifies_a_true_context_the_whole_prior_refuses() {
        // held-in case 26 of `eval-model --cases 96 --min 4 --max 12 --seed 7000`: with
        // the whole-primitive prior its BHC-X cell comes out nearer THC+X (BENCHMARKS.md
        // "TCV centring"); the visible prior's output passes ("The visible prior")
        // (the template estimate, the only generator with a prior)
        let (truth, mesh) = crate::search::synthetic::cases(7000, 27, 4, 12, &Default::default()).swap_remove(26);
        let model = Model::template();
        let g = truth.validity().genus.unwrap();
        let no_retry = PolycubeOptions { visible_retry: false, ..PolycubeOptions::template() };
        let plain = generate_from_contexts(&model, &mesh, g, &[truth], &no_retry, &mut crate::error::NoProgress).unwrap();
        assert_eq!(plain.candidates[0].stage, Stage::Tcv);
        assert!(plain.chosen.is_none() && !plain.candidates[0].visible_retry);
        // on in the template estimate's options
        let r = generate_from_contexts(&model, &mesh, g, &[truth], &PolycubeOptions::template(), &mut crate::error::NoProgress).unwrap();
        let c = &r.candidates[0];
        assert_eq!(c.stage, Stage::Verified);
        assert!(c.visible_retry && r.chosen.is_some());
        assert!(c.report.as_ref().unwrap().passed);
        // the ranking score is the mean cell fit, whichever run verified it
        assert_eq!(c.score, Some(c.fit_mean));
        assert_eq!(c.score, plain.candidates[0].score);
    }

    #[test]
    fn worst_and_mean_skip_unoccupied_cells_and_keep_an_infinite_one() {
        let mut cells = [f64::NAN; NUM_CELLS];
        cells[0] = 0.01;
        cells[5] = 0.05;
        cells[7] = 0.03;
        let (w, m) = worst_and_mean(&cells);
        assert_eq!(w, 0.05);
        assert!((m - 0.03).abs() < 1e-15);
        cells[3] = f64::INFINITY;
        assert_eq!(worst_and_mean(&cells), (f64::INFINITY, f64::INFINITY));
        assert_eq!(worst_and_mean(&[f64::NAN; NUM_CELLS]), (0.0, 0.0));
    }

    #[test]
    fn the_mean_cell_fit_separates_contexts_the_worst_cell_ties() {
        // held-in recovery cases (`cargo run --release --example recovery -- 24 5000`,
        // medium group seed 5001 case 10, complex group seed 5002 case 2), the truth and
        // a wrong context that both verified in the automated run, in its working frame:
        // they differ in one cell that fits better than the worst one, so the worst
        // cell ties them (to 1e-3) and the mean ranks the truth first
        for (seed, min, max, case, truth, wrong) in [
            (5001, 4, 6, 10, "BHC-Y,BHC-Z,THC+Z,0,cube,cube,BHC-X,0,0,0,0,0", "BHC-Y,BHC-Z,THC+Z,0,cube,cube,BHC-Y,0,0,0,0,0"),
            (5002, 7, 12, 2, "THC+Y,THC+Z,THC+Z,cube,0,BHC-Z,THC+Y,0,0,THC+X,0,cube", "THC+Y,THC+Z,THC+Z,cube,0,BHC-Z,THC+Y,0,0,THC+Y,0,cube"),
        ] {
            let (_, mesh) = crate::search::synthetic::cases(seed, case + 1, min, max, &Default::default()).swap_remove(case);
            let input = prepare_input(&mesh, &PolycubeOptions::default()).unwrap();
            let fit_sub = &input.samples[..input.samples.len().min(FIT_SAMPLES)];
            let fits = |c: &str| {
                let c = Context::parse(c).unwrap();
                worst_and_mean(&fit_score_cells(fit_sub, &c, rotations()[0], &polycube_samples(&c, FIT_SAMPLES), [1.0; 3]))
            };
            let (t, w) = (fits(truth), fits(wrong));
            assert!((t.0 - w.0).abs() < 1e-3 * t.0, "{seed}/{case}: worst {} vs {}", t.0, w.0);
            assert!(t.1 < 0.97 * w.1, "{seed}/{case}: mean {} vs {}", t.1, w.1);
        }
    }

    #[test]
    fn a_context_one_label_from_a_far_better_fit_is_refused_and_named() {
        // held-in synthetic cases (the generator's seed 7000, never trained on): the
        // true context is never refused; a wrong genus-consistent one that the
        // occupancy and fit tests pass is refused in most cases, with the cell and
        // both labels named
        let opts = PolycubeOptions::default();
        let (mut reached, mut refused) = (0, 0);
        for (i, (truth, mesh)) in crate::search::synthetic::cases(7000, 24, 1, 3, &Default::default()).into_iter().enumerate() {
            let input = prepare_input(&mesh, &opts).unwrap();
            let mut t = precheck(&input, &truth, &without_fit_limit(&opts)).unwrap();
            limit_fit(&mut t, &opts, f64::INFINITY);
            assert_eq!(t[0].stage, Stage::Pending, "case {i} {truth}");
            refuse_worse_than_neighbours(&input, &mut t, opts.neighbour_fit_ratio);
            assert_eq!(t[0].stage, Stage::Pending, "case {i} {truth}: {:?}", t[0].refusal);
            let Some(w) = crate::search::eval::wrong_context(&truth, i as u64) else { continue };
            let mut c = precheck(&input, &w, &without_fit_limit(&opts)).unwrap();
            limit_fit(&mut c, &opts, f64::INFINITY);
            if c[0].stage != Stage::Pending {
                continue;
            }
            reached += 1;
            refuse_worse_than_neighbours(&input, &mut c, opts.neighbour_fit_ratio);
            if let Some(why) = &c[0].refusal {
                refused += 1;
                assert_eq!(c[0].stage, Stage::Occupancy);
                // the cell named, with its given label (the best one-cell fix under the
                // wrong context's own orientation: usually, not always, the changed cell)
                let n: usize = why.strip_prefix("cell ").and_then(|r| r.split(' ').next()).and_then(|k| k.parse().ok()).expect(why);
                assert!(why.contains(&format!("than with the given {}", w.labels[n].name())), "case {i}: {why}");
            }
            // off: never refused
            let mut c = precheck(&input, &w, &without_fit_limit(&opts)).unwrap();
            limit_fit(&mut c, &opts, f64::INFINITY);
            refuse_worse_than_neighbours(&input, &mut c, 0.0);
            assert!(c[0].refusal.is_none());
        }
        assert!(reached >= 8 && 2 * refused > reached, "{refused} of {reached} refused");
    }
}
