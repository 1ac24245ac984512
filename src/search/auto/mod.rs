//! The automated mode: genus-guided context generation.
//!
//! 1. The temporary volume of the aligned input ([`crate::geometry::voxel`]), split
//!    into subregions ([`volume::subregions`]), each with its genus.
//! 2. For each occupied box (1..3 cells along X, 1..2 along Y and Z; coarsest
//!    first; each also with its boundaries where the part's outline changes,
//!    the input warped so that they fall on the equal grid, [`splits`]; or only
//!    the full 3x2x2 grid split by the caller's ratios): split the
//!    aligned bounding box into subregions, measure each one's genus (on
//!    majority-filtered voxels) and openings ([`openings`]), and take its
//!    feasible labels (empty -> null; genus 0 -> cube, the six BHC and the three THC; genus 1 ->
//!    the three THC; genus >= 2 -> the box cannot hold the input).
//! 3. Local stage: each subregion's feasible labels are ranked, those its openings
//!    carry first (`opening_labels`), by their fit in the
//!    box (the input against the box's assembly with that label in the cell and
//!    cubes elsewhere, the cell's own term: [`rank::in_context_fits`]); the best labels
//!    are diffused as single cells on the subregion's surface (the input's samples
//!    inside it plus samples on the faces where the subregion is cut out of the
//!    solid) and verified (GOCC + TCV), all in one batch.
//! 4. Global stage: products of the kept labels whose assembly is valid and has the
//!    input's genus are ranked by geometric fit averaged over their cells; the best
//!    ones pass the occupancy pre-check and the fit limit (against the best of all
//!    boxes, compared in a length common to them, [`rank::box_scale`]), are
//!    diffused in one batch and verified (a
//!    failing one a second time with the visible prior; a cell whose subregion
//!    shows its label's hole is judged against labels of the input's genus only,
//!    `VerifyOptions::same_genus_rivals`); of the verified candidates, the one
//!    with the fewest cells whose label their subregion's openings do not carry
//!    (with `opening_labels`), then the lowest mean cell fit, is chosen.
//!
//! By concern: the temporary volume and its subregions ([`volume`]); the boxes'
//! boundaries fitted to the part ([`splits`]); each box's
//! subregions, feasible labels and candidate assemblies ([`boxes`]); the fits that
//! rank labels, candidates and boxes ([`rank`]); the local stage (`local.rs`); the
//! boxes tried in order with the global stage (`global.rs`).

pub mod boxes;
pub mod frames;
mod global;
mod local;
pub mod openings;
pub mod rank;
pub mod splits;
pub mod volume;

use super::generate::{finish, prepare_input, Candidate, OrientationSearch, PolycubeOptions, PolycubeResult, PolycubeTimings, PreparedInput, Stage, FIT_SAMPLES};
use crate::diffusion::Model;
use crate::error::{check_progress, Error, Progress, Result};
use crate::geometry::SurfaceSample;
use crate::mesh::TriMesh;
use crate::polycube::orientation::AxisRotation;
use serde::{Deserialize, Serialize};
use std::time::Instant;
use volume::{Subregion, TemporaryVolume};

/// Splitting ratios: fractions of the aligned bounding box along X (up to 3 parts),
/// Y (up to 2) and Z (up to 2).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SplitRatios {
    pub x: Vec<f64>,
    pub y: Vec<f64>,
    pub z: Vec<f64>,
}

impl SplitRatios {
    pub fn equal(nx: usize, ny: usize, nz: usize) -> Self {
        SplitRatios { x: vec![1.0; nx], y: vec![1.0; ny], z: vec![1.0; nz] }
    }

    /// Parse "X1,X2,X3:Y1,Y2:Z1,Z2".
    pub fn parse(s: &str) -> Result<Self> {
        let parts: Vec<&str> = s.split(':').collect();
        let bad = || Error::InvalidArgument(format!("splitting ratios are X1[,X2[,X3]]:Y1[,Y2]:Z1[,Z2] (positive numbers), got '{s}'"));
        if parts.len() != 3 {
            return Err(bad());
        }
        let axis = |t: &str, max: usize| -> Result<Vec<f64>> {
            let v: Vec<f64> = t.split(',').map(|x| x.trim().parse::<f64>().map_err(|_| bad())).collect::<Result<_>>()?;
            if v.is_empty() || v.len() > max || v.iter().any(|x| !(x.is_finite() && *x > 0.0)) {
                return Err(bad());
            }
            Ok(v)
        };
        Ok(SplitRatios { x: axis(parts[0], 3)?, y: axis(parts[1], 2)?, z: axis(parts[2], 2)? })
    }

    pub fn dims(&self) -> [usize; 3] {
        [self.x.len(), self.y.len(), self.z.len()]
    }
}

/// Options of the automated mode, with documented defaults.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct AutoOptions {
    /// Voxels along the longest edge of the temporary volume (default 48).
    pub resolution: usize,
    /// A subregion filled less than this is empty (null) (default 0.04).
    pub min_fill: f64,
    /// A subregion filled less than this may also be null (default 0.15): the
    /// global stage tries both (a warped part bulges a few percent into a cell its
    /// polycube leaves empty; an occupied cell is filled 0.6 or more, a through hole
    /// included).
    pub null_fill: f64,
    /// Labels kept per subregion after the in-context fit (default 5; 3 lost the
    /// true label of a deformed cell more often and recovered 24 of 72 tuning
    /// cases where 5 recovers 27 and 7 also 27, slower: BENCHMARKS.md "Labels
    /// kept per subregion").
    pub local_keep: usize,
    /// Run the local single-cell diffusion + verification (default true).
    pub local_diffusion: bool,
    /// Global candidates diffused at most (best geometric fit first; default 16).
    pub max_global: usize,
    /// A finer box is preferred only when its fit beats the coarsest acceptable box's
    /// by this factor (default 0.8).
    pub finer_box_factor: f64,
    /// Boxes tried (best first) before giving up (default 2); a box none of whose
    /// candidates passes the pre-check and the fit limit is passed over and not
    /// counted.
    pub max_boxes: usize,
    /// Sampler steps of the local single-cell diffusion (default 25).
    pub local_steps: usize,
    /// Also choose the subregions' labels jointly on the global fit (coordinate
    /// descent over the cells, every feasible label, from the local ranking; see
    /// [`rank::joint_labels`]) and add the valid assemblies of the input's genus it visits
    /// to the box's candidates (default false: measured in BENCHMARKS.md "Context
    /// search", not yet on the real meshes).
    pub joint_labels: bool,
    /// Rank a subregion's labels by the in-context fit after a local affine
    /// registration of the cell (`search::generate::register`: twisted, tapered,
    /// bent or sheared cells fit their own label again) instead of the rigid fit
    /// (default false: on the tuning families it keeps the true label more often
    /// but recovers no more parts, BENCHMARKS.md "Label ranking with cell
    /// registration").
    pub register_cells: bool,
    /// Rank first, among a subregion's feasible labels, those whose hole its
    /// voxels show ([`openings`]: a hole through it along the label's axis, a
    /// blind hole opening on the label's face, or no opening for the cube), then
    /// the others, each part by the in-context fit; and among the verified
    /// candidates, those with the fewest cells whose label the openings do not
    /// carry come first (`Candidate::openings_missed`) (default true).
    pub opening_labels: bool,
    /// Also analyse the boxes with three cells along X with the grid's X along
    /// the input's Y and along its Z ([`frames`]), when no box of the aligned
    /// frame has a candidate within the fit limit: a part whose row of three
    /// cells is not its longest side has no box in the aligned frame (default
    /// false: with the registration it recovers 53 of 72 tuning cases against
    /// 49, none lost, but changes no case of the reported families and costs
    /// them one to two seconds a part: BENCHMARKS.md "Boxes in the other
    /// frames").
    pub axis_frames: bool,
    /// Also analyse each box of the aligned frame with its cell boundaries where
    /// the outline of the part's cross-section changes ([`splits`]: a channel's sides, a
    /// shoulder), the input warped so that they fall on the equal grid, when they
    /// are at least [`splits::MIN_SHIFT`] of the box away from the equal split's
    /// (default true: BENCHMARKS.md "Boxes compared in one length, splits
    /// fitted to the part").
    pub fitted_splits: bool,
}

impl Default for AutoOptions {
    fn default() -> Self {
        AutoOptions { resolution: 48, min_fill: 0.04, null_fill: 0.15, local_keep: 5, local_diffusion: true, max_global: 16, finer_box_factor: 0.8, max_boxes: 2, local_steps: 25, joint_labels: false, register_cells: false, opening_labels: true, axis_frames: false, fitted_splits: true }
    }
}

/// The local stage's record of one subregion.
#[derive(Debug, Clone, Serialize)]
pub struct LocalResult {
    pub subregion: Subregion,
    /// (label, in-context geometric fit, see [`rank::in_context_fits`]) of every feasible
    /// label, best first.
    pub fits: Vec<(String, f64)>,
    /// Labels that went on to the global stage.
    pub kept: Vec<String>,
    /// Labels that passed local verification.
    pub verified: Vec<String>,
}

/// The record of one occupied box.
#[derive(Debug, Clone, Serialize)]
pub struct BoxResult {
    pub dims: [usize; 3],
    /// The frame the box splits, as the rotation from the aligned input into it
    /// ("+x+y+z": the aligned frame; "+y+z+x": the grid's X along the input's Y;
    /// "+z+x+y": along its Z; see [`frames`]).
    pub frame: String,
    pub ratios: SplitRatios,
    /// The box's boundaries are fitted to the part ([`splits`]; `ratios` says
    /// where): its subregions, fits and candidates are those of the input warped
    /// so that they fall on the equal grid.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub fitted: bool,
    pub locals: Vec<LocalResult>,
    /// Global candidates with the input's genus (before the cap).
    pub candidates: usize,
    /// Best global geometric fit (squared cell units of this box).
    pub best_fit: Option<f64>,
    /// The same candidate's fit in squared units of a common length (the cell of a
    /// 12-cell split of the part's bounding box by volume), which ranks the boxes:
    /// see [`rank::box_scale`].
    pub best_fit_common: Option<f64>,
    /// Candidates added by the joint label search (`AutoOptions::joint_labels`).
    pub joint_candidates: usize,
    /// Why this box cannot hold the input, if it cannot.
    pub refused: Option<String>,
}

impl BoxResult {
    /// The box's cells and, outside the aligned frame, the input's axis along the
    /// grid's X: "3x2x2", "3x2x2 (X along the input's Y)".
    pub fn name(&self) -> String {
        let along = match frames::FRAMES.iter().position(|r| r.name() == self.frame) {
            Some(1) => " (X along the input's Y)",
            Some(2) => " (X along the input's Z)",
            _ => "",
        };
        let fitted = if self.fitted { " (splits fitted to the part)" } else { "" };
        format!("{}x{}x{}{along}{fitted}", self.dims[0], self.dims[1], self.dims[2])
    }
}

/// What the automated mode measured beyond the candidates.
#[derive(Debug, Clone, Serialize)]
pub struct AutoReport {
    /// Voxels along the longest side of the temporary volume (`AutoOptions::resolution`,
    /// doubled while the volume misses the surface's, see [`volume::VOLUME_TOLERANCE`]).
    pub resolution: usize,
    pub volume_tetrahedra: usize,
    pub volume: f64,
    pub surface_volume: f64,
    pub volume_relative_error: f64,
    pub boxes: Vec<BoxResult>,
    pub chosen_box: Option<[usize; 3]>,
    /// The frame of the box last tried ([`BoxResult::frame`]).
    pub chosen_frame: Option<String>,
    /// Whether the box last tried has splits fitted to the part ([`BoxResult::fitted`]).
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub chosen_fitted: bool,
    /// Why no candidate was formed at all (no occupied box and labelling of the grid
    /// holds the input's genus and subregions); None when some box had candidates.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub no_candidate: Option<String>,
}

/// What every step of one automated run reads, in one frame ([`frames`]).
struct Run<'a> {
    /// The aligned input turned into this frame (the boxes, the fits and the
    /// local stage read it).
    input: &'a PreparedInput,
    volume: &'a TemporaryVolume,
    /// The input's samples the fits use (the first [`FIT_SAMPLES`]).
    fit_sub: &'a [SurfaceSample],
    /// The aligned input, which the global stage diffuses and verifies ...
    aligned: &'a PreparedInput,
    /// ... with its candidates in this rotation (aligned point -> this frame).
    frame: AxisRotation,
    /// The input's genus.
    genus: i64,
    opts: &'a PolycubeOptions,
    aopts: &'a AutoOptions,
    /// The options of the global stage: `opts` in the input's frame only.
    global: PolycubeOptions,
}

impl<'a> Run<'a> {
    /// The run of one frame: `input` and `volume` turned into it, `aligned` the
    /// input the global stage diffuses in the rotation `frame`.
    #[allow(clippy::too_many_arguments)]
    fn new(input: &'a PreparedInput, volume: &'a TemporaryVolume, aligned: &'a PreparedInput, frame: AxisRotation, genus: i64, opts: &'a PolycubeOptions, aopts: &'a AutoOptions, global: &PolycubeOptions) -> Run<'a> {
        Run { input, volume, fit_sub: &input.samples[..input.samples.len().min(FIT_SAMPLES)], aligned, frame, genus, opts, aopts, global: global.clone() }
    }
}

/// Run the automated mode (all boxes, or the full grid split by `ratios`).
pub fn generate_auto(
    model: &Model,
    mesh: &TriMesh,
    input_genus: i64,
    ratios: Option<&SplitRatios>,
    opts: &PolycubeOptions,
    aopts: &AutoOptions,
    progress: &mut dyn Progress,
) -> Result<(PolycubeResult, AutoReport)> {
    let t_all = Instant::now();
    let mut timings = PolycubeTimings::default();
    let t0 = Instant::now();
    let input = prepare_input(mesh, opts)?;
    timings.align = t0.elapsed().as_secs_f64();
    check_progress(progress, 0.02, "temporary volume")?;
    let volume = volume::measure(&input, aopts)?;
    let mut report = AutoReport::of_volume(&volume);
    let mut global_opts = opts.clone();
    global_opts.orientations = OrientationSearch::Identity;
    let run_in = |inp, vol, frame| Run::new(inp, vol, &input, frame, input_genus, opts, aopts, &global_opts);
    let base = run_in(&input, &volume, frames::FRAMES[0]);
    let t0 = Instant::now();
    // The aligned frame's boxes first; the other frames' (only when the boxes are
    // the automated mode's own: the caller's ratios split the aligned frame) only
    // when none of those has a candidate within the fit limit, since each frame's
    // three-cell boxes hold thousands of candidates to rank.
    let (aligned_shapes, other_shapes): (Vec<_>, Vec<_>) = boxes::box_shapes(ratios, if aopts.axis_frames { frames::FRAMES.len() } else { 1 }).into_iter().partition(|(f, _)| *f == 0);
    let mut runs = vec![base];
    let mut boxes = boxes::analyse_boxes(&runs, &aligned_shapes, (0.05, 0.2), &mut report, progress)?;
    rank::rank_candidates(&runs, &mut boxes, 0, &mut report);
    let fits = report.boxes.iter().any(|b| b.best_fit.is_some_and(|f| f <= opts.max_fit));
    let more = !fits && !other_shapes.is_empty();
    let turned: Vec<PreparedInput> = if more { frames::FRAMES[1..].iter().map(|r| frames::in_frame(&input, *r)).collect() } else { Vec::new() };
    let volumes: Vec<TemporaryVolume> = turned.iter().map(|t| volume::measure(t, aopts)).collect::<Result<_>>()?;
    for ((inp, vol), frame) in turned.iter().zip(&volumes).zip(&frames::FRAMES[1..]) {
        runs.push(run_in(inp, vol, *frame));
    }
    if more {
        let from = boxes.len();
        boxes.extend(boxes::analyse_boxes(&runs, &other_shapes, (0.2, 0.3), &mut report, progress)?);
        rank::rank_candidates(&runs, &mut boxes, from, &mut report);
    }
    // the aligned frame's boxes with splits fitted to the part, one warped input
    // per distinct warp
    let warps: Vec<(splits::AxisWarp, Vec<[usize; 3]>)> = if ratios.is_none() && aopts.fitted_splits { fitted_warps(&volume, &aligned_shapes) } else { Vec::new() };
    let warped: Vec<PreparedInput> = warps.iter().map(|(w, _)| splits::warp_input(&input, w)).collect();
    let warped_volumes: Vec<TemporaryVolume> = warped.iter().map(|t| volume::measure(t, aopts)).collect::<Result<_>>()?;
    if !warps.is_empty() {
        let from = boxes.len();
        let mut shapes = Vec::new();
        for ((inp, vol), (_, dims)) in warped.iter().zip(&warped_volumes).zip(&warps) {
            shapes.extend(dims.iter().map(|d| (runs.len(), SplitRatios::equal(d[0], d[1], d[2]))));
            runs.push(Run::new(inp, vol, inp, frames::FRAMES[0], input_genus, opts, aopts, &global_opts));
        }
        let first_run = runs.len() - warps.len();
        boxes.extend(boxes::analyse_boxes(&runs, &shapes, (0.3, 0.35), &mut report, progress)?);
        for (b, w) in report.boxes[from..].iter_mut().zip(&boxes[from..]) {
            b.fitted = true;
            b.ratios = warps[w.frame - first_run].0.ratios();
        }
        rank::rank_candidates(&runs, &mut boxes, from, &mut report);
    }
    if more || !warps.is_empty() {
        boxes::sort_boxes(&mut boxes, &mut report.boxes);
    }
    timings.precheck += t0.elapsed().as_secs_f64();
    check_progress(progress, 0.3, "global candidates")?;
    // no box with a candidate is not an error here: the result has no candidate and
    // [`auto_failure`] names why, so that the main job can still mesh the part with
    // the grid-based fallback
    let candidates = match rank::box_order(&runs[0], &boxes, &report) {
        Ok(order) => global::try_boxes(&runs, model, &mut boxes, &order, &mut report, progress, &mut timings)?,
        Err(Error::VerificationFailed(why)) => {
            report.no_candidate = Some(why);
            Vec::new()
        }
        Err(e) => return Err(e),
    };
    timings.total = t_all.elapsed().as_secs_f64();
    let result = finish(input, input_genus, "auto", candidates, timings, model.generator_name(opts.sampler.kernel_gate));
    Ok((result, report))
}

/// The distinct warps of the boxes of `shapes` (the aligned frame's) whose
/// boundaries fitted to the part differ from the equal split ([`splits::fitted_box`]),
/// each with the dims of its boxes.
fn fitted_warps(volume: &TemporaryVolume, shapes: &[(usize, SplitRatios)]) -> Vec<(splits::AxisWarp, Vec<[usize; 3]>)> {
    let changes = splits::outline_changes(&volume.clean, volume.vol.lo, volume.vol.h);
    let mut out: Vec<(splits::AxisWarp, Vec<[usize; 3]>)> = Vec::new();
    for (_, r) in shapes {
        let dims = r.dims();
        let Some(inner) = splits::fitted_box(&changes, &volume.bb, dims) else { continue };
        let w = splits::AxisWarp::new(&volume.bb, &inner);
        match out.iter_mut().find(|(x, _)| *x == w) {
            Some((_, d)) => d.push(dims),
            None => out.push((w, vec![dims])),
        }
    }
    out
}

impl AutoReport {
    /// The record of the box last tried (its dims and frame), if any.
    pub fn chosen(&self) -> Option<&BoxResult> {
        self.boxes.iter().find(|b| Some(b.dims) == self.chosen_box && Some(&b.frame) == self.chosen_frame.as_ref() && b.fitted == self.chosen_fitted)
    }

    /// The report of a run on `volume`, before any box.
    fn of_volume(volume: &TemporaryVolume) -> AutoReport {
        let (vol, surface_volume) = (&volume.vol, volume.surface_volume);
        AutoReport {
            resolution: volume.resolution,
            volume_tetrahedra: vol.tetrahedra(),
            volume: vol.volume(),
            surface_volume,
            volume_relative_error: (vol.volume() - surface_volume).abs() / surface_volume.max(1e-300),
            boxes: Vec::new(),
            chosen_box: None,
            chosen_frame: None,
            chosen_fitted: false,
            no_candidate: None,
        }
    }
}

/// Candidates a refusal names ([`nearest_candidates`]).
pub const NEAREST_NAMED: usize = 3;

/// What a caller can give instead when the automated mode verifies nothing.
pub const WHAT_TO_GIVE: &str = "give the context you expect (--labels L, e.g. one named above), constraints you know (--constraints FILE: counts of cubes, THCs and BHCs, allowed cells), or splitting ratios that put each hole in its own cell (--ratios X1,X2,X3:Y1,Y2:Z1,Z2)";

/// Where a candidate stopped, in words.
fn stopped(c: &Candidate) -> String {
    let why = || c.report.as_ref().and_then(|r| r.reason.clone()).unwrap_or_default();
    match c.stage {
        Stage::Verified => "verified".into(),
        Stage::Tcv => format!("passed GOCC, failed TCV: {}", why()),
        Stage::Gocc => format!("failed GOCC: {}", why()),
        Stage::Pending => "not diffused".into(),
        Stage::Occupancy => match &c.refusal {
            Some(r) => format!("refused by the pre-check: {r}"),
            // nothing in empty cells and no starved cell: the occupancy passed
            None if c.occupancy.in_empty_cells == 0.0 && c.occupancy.starved_cells.is_empty() => "refused before diffusion by the fit limit".into(),
            None => format!(
                "refused before diffusion by the occupancy pre-check or the fit limit ({:.1} % of the surface in empty cells, {} starved cell(s))",
                100.0 * c.occupancy.in_empty_cells,
                c.occupancy.starved_cells.len()
            ),
        },
    }
}

/// The `n` candidates of a run nearest to verifying, furthest stage first
/// (TCV failed, then GOCC failed, then refused before diffusion), then best mean
/// cell fit: each named by its context, its fits (worst cell and mean, squared
/// cell units) and where it stopped.
pub fn nearest_candidates(result: &PolycubeResult, n: usize) -> Vec<String> {
    let rank = |s: Stage| match s {
        Stage::Verified => 0,
        Stage::Tcv => 1,
        Stage::Gocc => 2,
        Stage::Pending => 3,
        Stage::Occupancy => 4,
    };
    let mut v: Vec<&Candidate> = result.candidates.iter().collect();
    v.sort_by(|a, b| rank(a.stage).cmp(&rank(b.stage)).then(a.fit_mean.total_cmp(&b.fit_mean)));
    // one entry per context (a context may be tried in several placements)
    let mut seen: Vec<[u8; crate::polycube::NUM_CELLS]> = Vec::new();
    v.retain(|c| {
        let new = !seen.contains(&c.labels);
        seen.push(c.labels);
        new
    });
    v.iter().take(n).map(|c| format!("{} (fit {:.4}, mean {:.4}; {})", c.context, c.fit, c.fit_mean, stopped(c))).collect()
}

/// The nearest candidates and what the caller can give, appended to a refusal.
fn nearest_and_what_to_give(result: &PolycubeResult) -> String {
    let near = nearest_candidates(result, NEAREST_NAMED);
    let near = if near.is_empty() { "no candidate was formed".to_string() } else { format!("nearest candidates: {}", near.join("; ")) };
    format!("{near}. To go on, {WHAT_TO_GIVE}")
}

/// The error of an automated run in which no global candidate passed: names the
/// subregions whose local verification failed, the candidates nearest to
/// verifying ([`nearest_candidates`]) and what the caller can give instead.
pub fn auto_failure(result: &PolycubeResult, report: &AutoReport) -> Option<Error> {
    if result.chosen.is_some() {
        return None;
    }
    if let Some(why) = &report.no_candidate {
        return Some(Error::VerificationFailed(why.clone()));
    }
    let Some(b) = report.chosen() else {
        // no box was tried: every box was refused or passed over
        // boxes that had candidates (passed over on the fit limit) first
        let mut boxes: Vec<&BoxResult> = report.boxes.iter().filter(|b| b.refused.is_some()).collect();
        boxes.sort_by_key(|b| b.candidates == 0);
        let mut why: Vec<String> = boxes.iter().filter_map(|b| b.refused.as_ref().map(|r| format!("{}: {r}", b.name()))).collect();
        why.truncate(6);
        return Some(Error::VerificationFailed(format!(
            "automated mode diffused no candidate: no occupied box has one that passes the occupancy pre-check and the fit limit ({}); the part may not be a polycube of the 3x2x2 grid; {}",
            why.join("; "),
            nearest_and_what_to_give(result)
        )));
    };
    let failed: Vec<String> = b
        .locals
        .iter()
        .filter(|l| !l.subregion.empty && l.verified.is_empty())
        .map(|l| format!("cell {} (genus {}, best fit {})", l.subregion.cell, l.subregion.genus, l.fits.first().map(|f| f.0.as_str()).unwrap_or("-")))
        .collect();
    let base = match result.accepted() {
        Err(Error::VerificationFailed(m)) => m,
        _ => String::new(),
    };
    Some(Error::VerificationFailed(format!(
        "{base}; box {}: {}; {}",
        b.name(),
        if failed.is_empty() { "every subregion passed local verification".to_string() } else { format!("local verification failed in {}", failed.join(", ")) },
        nearest_and_what_to_give(result)
    )))
}

#[cfg(test)]
mod tests;
