//! Polycube generation: from an input surface and a context request to verified
//! candidate polycubes (user-guided mode here; the automated search lives in
//! `auto`). Every candidate keeps its occupancy pre-check, its verification report
//! and its diffusion output with the surface correspondence.

use super::Context;
use crate::diffusion::sample::{reverse_diffusion, SamplerOptions};
use crate::diffusion::Model;
use crate::error::{check_progress, Error, Progress, Result};
use crate::geometry::orient::{align_axes, FrameChoice};
use crate::geometry::{sample_surface, Alignment, SurfaceSample};
use crate::mesh::TriMesh;
use crate::polycube::dataset::item_rng;
use crate::polycube::inference::{prepare, InferenceInput, Occupancy, DEFAULT_OVERSAMPLING};
use crate::polycube::orientation::{rotations, AxisRotation};
use crate::polycube::tensor::{unlayout, POINTS_PER_CELL};
use crate::polycube::NUM_CELLS;
use crate::verify::{chamfer, verify, VerificationReport, VerifyOptions};
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
            oversampling: DEFAULT_OVERSAMPLING,
            seed: 0,
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
    pub stage: Stage,
    pub report: Option<VerificationReport>,
    /// Mean squared distance between the output and the input samples it started
    /// from (model frame); lower means the polycube stayed closer to the input.
    pub fidelity: Option<f64>,
    /// Ranking score (lower is better): mean target PCD + fidelity.
    pub score: Option<f64>,
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
        } else if let Some(c) = self.candidates.first() {
            s.push_str(&format!(
                "; first: {} leaves {:.1}% of the surface in empty cells",
                c.context,
                100.0 * c.occupancy.in_empty_cells
            ));
        }
        s.push_str("; revise the context or use the automated mode (--auto)");
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
}

pub fn prepare_input(mesh: &TriMesh, opts: &PolycubeOptions) -> Result<PreparedInput> {
    let (alignment, frame) = align_axes(mesh)?;
    let mut rng = item_rng(opts.seed, 0x5a3f);
    let samples = sample_surface(&alignment.mesh, opts.oversampling.max(POINTS_PER_CELL), &mut rng);
    if samples.is_empty() {
        return Err(Error::InvalidMesh("the surface has no area to sample".into()));
    }
    Ok(PreparedInput { alignment, frame, samples })
}

/// The occupancy pre-check of one context over the orientation search: returns the
/// best orientations (lowest surface fraction in empty cells) as candidates.
pub fn precheck(input: &PreparedInput, ctx: &Context, opts: &PolycubeOptions) -> Result<Vec<Candidate>> {
    let rots: Vec<AxisRotation> = match opts.orientations {
        OrientationSearch::Identity => vec![rotations()[0]],
        OrientationSearch::SignFlips => rotations()[..4].to_vec(),
        OrientationSearch::All => rotations().to_vec(),
    };
    let mut all = Vec::with_capacity(rots.len());
    for (k, r) in rots.iter().enumerate() {
        let mut rng = item_rng(opts.seed ^ 0x9e37, k as u64);
        let inp = prepare(&input.samples, ctx, *r, opts.min_occupied_fraction, &mut rng)?;
        let ok = inp.occupancy.in_empty_cells <= opts.max_in_empty_fraction && inp.occupancy.starved_cells.is_empty();
        let stage = if ok { Stage::Pending } else { Stage::Occupancy };
        all.push(Candidate {
            context: *ctx,
            labels: ctx.label_values(),
            rotation: r.name(),
            axis_rotation: *r,
            occupancy: inp.occupancy.clone(),
            stage,
            report: None,
            fidelity: None,
            score: None,
            input: Some(inp),
            output: None,
        });
    }
    // Best orientations first: fewest surface in empty cells, then starved cells.
    all.sort_by(|a, b| {
        (a.stage == Stage::Occupancy)
            .cmp(&(b.stage == Stage::Occupancy))
            .then(a.occupancy.in_empty_cells.total_cmp(&b.occupancy.in_empty_cells))
            .then(a.occupancy.starved_cells.len().cmp(&b.occupancy.starved_cells.len()))
    });
    let keep = opts.orientations_per_context.max(1);
    let passing = all.iter().filter(|c| c.stage != Stage::Occupancy).count();
    all.truncate(if passing > 0 { keep.min(passing) } else { 1 });
    for c in all.iter_mut() {
        if c.stage == Stage::Occupancy {
            c.input = None; // nothing to diffuse
        }
    }
    Ok(all)
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
        c.output = Some(out.tensors[k].clone());
        let pairs = c.correspondence();
        let fid = pairs.iter().map(|(a, b)| (0..3).map(|j| (a[j] - b[j]).powi(2)).sum::<f64>()).sum::<f64>() / pairs.len().max(1) as f64;
        c.fidelity = Some(fid);
        c.score = Some(rep.mean_target_pcd + fid);
        c.report = Some(rep);
    }
    timings.verification += t0.elapsed().as_secs_f64();
    Ok(())
}

/// Symmetric Chamfer distance between a candidate's output and its input samples.
pub fn output_input_chamfer(c: &Candidate) -> Option<f64> {
    let pairs = c.correspondence();
    if pairs.is_empty() {
        return None;
    }
    let a: Vec<[f64; 3]> = pairs.iter().map(|p| p.0).collect();
    let b: Vec<[f64; 3]> = pairs.iter().map(|p| p.1).collect();
    Some(chamfer(&a, &b))
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
        cands.extend(precheck(&input, c, opts)?);
    }
    timings.precheck = t0.elapsed().as_secs_f64();
    diffuse_and_verify(model, &mut cands, opts, progress, &mut timings)?;
    timings.total = t_all.elapsed().as_secs_f64();
    Ok(finish(input, input_genus, "user", cands, timings))
}

/// Rank the verified candidates and build the result.
pub fn finish(input: PreparedInput, input_genus: i64, source: &'static str, cands: Vec<Candidate>, timings: PolycubeTimings) -> PolycubeResult {
    let chosen = cands
        .iter()
        .enumerate()
        .filter(|(_, c)| c.stage == Stage::Verified && c.output.is_some())
        .min_by(|a, b| a.1.score.unwrap_or(f64::INFINITY).total_cmp(&b.1.score.unwrap_or(f64::INFINITY)))
        .map(|(i, _)| i);
    PolycubeResult { input_genus, source, alignment: input.alignment, frame: input.frame, candidates: cands, chosen, timings }
}
