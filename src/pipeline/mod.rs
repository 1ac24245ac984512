//! The whole job, stage by stage, as one library call each: polycube generation from
//! a request (complete contexts, partial constraints, splitting ratios or the
//! automated search), then (in later stages) the hex mesh and the spline. The run
//! folder of the main job (report.json, report.html and every file) is written by
//! [`report`].

pub mod options;
pub mod report;
pub mod report_html;
pub mod size;

use crate::context::{Constraints, Context};
use crate::diffusion::Model;
use crate::error::{check_progress, Error, Progress, Result};
use crate::mesh::TriMesh;
use crate::search::auto::{auto_failure, generate_auto, AutoOptions, AutoReport, SplitRatios};
use crate::search::generate::{generate_from_contexts, PolycubeOptions, PolycubeResult};
use serde::{Deserialize, Serialize};

/// How the caller asks for a polycube.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum ContextRequest {
    /// Complete contexts (one or a stack).
    Contexts(Vec<Context>),
    /// Partial constraints, expanded to every valid context of the input's genus.
    Constraints(Constraints),
    /// The automated search over the full grid split by these ratios.
    Ratios(SplitRatios),
    /// The automated search over every occupied box.
    Auto,
}

/// Most contexts a constraint set may expand to before diffusion (after the genus filter).
pub const MAX_CONSTRAINT_CONTEXTS: usize = 4096;

/// Generate and verify polycubes for `mesh` (whose genus the mesh check measured).
/// On success the result has a chosen candidate; when nothing passes, the error is
/// `VerificationFailed` naming what failed (the result is returned alongside so that a
/// caller can still report every candidate).
pub fn generate_polycube(
    model: &Model,
    mesh: &TriMesh,
    genus: i64,
    request: &ContextRequest,
    opts: &PolycubeOptions,
    aopts: &AutoOptions,
    progress: &mut dyn Progress,
) -> Result<(PolycubeResult, Option<AutoReport>, Option<Error>)> {
    let mut progress = crate::error::MonotoneProgress::new(progress);
    let progress: &mut dyn Progress = &mut progress;
    match request {
        ContextRequest::Contexts(cs) => {
            let r = generate_from_contexts(model, mesh, genus, cs, opts, progress)?;
            let e = r.accepted().err();
            Ok((r, None, e))
        }
        ContextRequest::Constraints(c) => {
            let mut c = c.clone();
            if let Some(g) = c.genus {
                if g != genus {
                    return Err(Error::GenusMismatch { input: genus, context: g, detail: " (the constraints ask for that genus); no diffusion was run".into() });
                }
            }
            c.genus = Some(genus);
            let all = c.enumerate()?;
            if all.is_empty() {
                return Err(Error::InvalidContext(format!(
                    "no valid context satisfies the constraints with the input's genus {genus}; relax the counts or the allowed cells"
                )));
            }
            if all.len() > MAX_CONSTRAINT_CONTEXTS {
                return Err(Error::LimitExceeded(format!(
                    "the constraints expand to {} contexts (limit {MAX_CONSTRAINT_CONTEXTS}); fix more counts or cells",
                    all.len()
                )));
            }
            let r = generate_from_contexts(model, mesh, genus, &all, opts, progress)?;
            let e = r.accepted().err();
            Ok((r, None, e))
        }
        ContextRequest::Ratios(ratios) => {
            let (r, rep) = generate_auto(model, mesh, genus, Some(ratios), opts, aopts, progress)?;
            let e = auto_failure(&r, &rep);
            Ok((r, Some(rep), e))
        }
        ContextRequest::Auto => {
            let (r, rep) = generate_auto(model, mesh, genus, None, opts, aopts, progress)?;
            let e = auto_failure(&r, &rep);
            Ok((r, Some(rep), e))
        }
    }
}

// ------------------------------------------------------------------ the whole job

use crate::error::SubProgress;
use crate::hex::{build_hex_mesh, Affine, HexInput, HexOptions, HexResult};
use crate::search::generate::Candidate;
use crate::spline::{build_spline, Spline, SplineOptions};
use std::time::Instant;

/// Options of [`run`]: one struct per stage, each with its documented defaults.
/// Every scalar option also has a name ("hex.quality.pillow", [`options`]): the C
/// API's options handle and the Python keyword arguments set them by name.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RunOptions {
    pub polycube: PolycubeOptions,
    pub auto: AutoOptions,
    pub hex: HexOptions,
    /// `None` stops after the hex mesh (the command line's `--no-spline`).
    pub spline: Option<SplineOptions>,
    /// When no candidate passes verification, mesh the diffused candidate with the best
    /// geometric fit anyway (GOCC passes first) instead of failing; the result says so
    /// (`RunResult::verified` false, report.json "polycube.verified_choice": false) and
    /// the diffusion correspondence is then not used to seed the surface map.
    /// Default true: the hex mesh and the spline are measured on their own (scaled
    /// Jacobian, Hausdorff distance), so an unverified polycube is a warning, not a
    /// wrong answer. Set false to refuse (VERIFICATION_FAILED).
    pub accept_unverified: bool,
    /// Refuse (MESHING_FAILED, naming the inverted elements) a hex mesh that still has
    /// inverted elements after quality improvement, instead of returning it with
    /// them counted in the report (default false).
    pub require_valid_hex: bool,
    /// How many candidates are meshed: the verified ones best score first or, when
    /// none verified, the unverified ones of [`fallback_order`]. The best hex mesh by
    /// [`crate::hex::QualityGoals::rank`] (fewest inverted elements, then fewest missed
    /// goals, then highest minimum scaled Jacobian) is kept; the builds stop at the
    /// first mesh that meets every goal of `hex.goals`.
    /// Default 4: a further candidate costs one more hex build (1.8-6.9 s at level 2
    /// in BENCHMARKS.md's hex table 1),
    /// spent only while the meshes so far are not good enough; BENCHMARKS.md ("Main
    /// job") measures what it rescues.
    pub hex_candidates: usize,
}

impl Default for RunOptions {
    fn default() -> Self {
        RunOptions {
            polycube: PolycubeOptions::default(),
            auto: AutoOptions::default(),
            hex: HexOptions::default(),
            spline: Some(SplineOptions::default()),
            accept_unverified: true,
            require_valid_hex: false,
            hex_candidates: 4,
        }
    }
}

/// One hex build of a verified candidate.
#[derive(Debug, Clone, Serialize)]
pub struct HexAttempt {
    /// Index into the polycube's candidates; None for the grid-based fallback
    /// ([`crate::hex::voxel`]), whose `context` reads "voxel N" ([`crate::hex::Domain`]).
    pub candidate: Option<usize>,
    pub context: String,
    pub min_scaled_jacobian: f64,
    pub mean_scaled_jacobian: f64,
    pub inverted: usize,
    pub hausdorff_relative: f64,
    /// How many of `HexOptions::goals` the mesh misses (0-3).
    pub goals_missed: usize,
    /// How far it falls short of them ([`crate::hex::QualityGoals::shortfall`]).
    pub goal_shortfall: f64,
    pub seconds: f64,
    /// Why the build failed: a candidate whose mesh could not be built, or a
    /// fallback with no lattice of the input's topology within
    /// `HexOptions::max_elements`. Its scaled-Jacobian, distance and shortfall
    /// figures are then NaN (null in report.json), `inverted` 0 and
    /// `goals_missed` 3.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub error: Option<String>,
    /// The surface maps meshed for this candidate, with their meshes' figures
    /// (`hex::SurfaceMap::Best`; empty for the fallback and the other settings).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub surface_maps: Vec<crate::hex::report::SurfaceMapTry>,
}

/// Everything [`run`] produced.
pub struct RunResult {
    pub polycube: PolycubeResult,
    pub auto: Option<AutoReport>,
    /// Index (into `polycube.candidates`) of the candidate that was meshed and kept;
    /// for a grid-based fallback mesh, the best polycube attempt's, or None when no
    /// candidate was formed (a part the grid cannot hold).
    pub candidate: Option<usize>,
    pub hex_attempts: Vec<HexAttempt>,
    /// False when the meshed candidate did not pass verification (`accept_unverified`).
    pub verified: bool,
    /// The verification error that `accept_unverified` overrode.
    pub verification_error: Option<String>,
    pub hex: HexResult,
    /// The spline fitted to the input surface (None with `spline: None`).
    pub spline: Option<Spline>,
    /// Wall-clock seconds per stage ("polycube", "hex", "spline").
    pub seconds: Vec<(String, f64)>,
    /// The options of the run (report.json "options"; the quality goals of
    /// report.html's marks).
    pub options: RunOptions,
}

/// The affine map equal to `f` (which must be affine), read off at four points.
fn affine_of(f: impl Fn([f64; 3]) -> [f64; 3]) -> Affine {
    let t = f([0.0; 3]);
    let cols: [[f64; 3]; 3] = std::array::from_fn(|a| {
        let mut e = [0.0; 3];
        e[a] = 1.0;
        let p = f(e);
        std::array::from_fn(|i| p[i] - t[i])
    });
    Affine { m: std::array::from_fn(|i| std::array::from_fn(|j| cols[j][i])), t }
}

/// The hex stage's input for a diffused candidate: the user's surface in the
/// candidate's normalised frame (alignment, then the candidate's box map, rotation
/// included), the diffusion correspondence and the way back to user coordinates.
fn hex_input(result: &PolycubeResult, cand: &Candidate, mesh: &TriMesh) -> Result<HexInput> {
    let inp = cand
        .input
        .as_ref()
        .ok_or_else(|| Error::InvalidArgument(format!("candidate {} was never diffused", cand.context)))?;
    let tr = &result.alignment.transform;
    let map = &inp.map;
    let to_norm = affine_of(|p| map.forward(tr.apply(p)));
    let to_user = to_norm
        .inverse()
        .ok_or_else(|| Error::Internal(format!("the frame map of {} is singular", cand.context)))?;
    let surface = TriMesh { vertices: mesh.vertices.iter().map(|&p| to_norm.apply(p)).collect(), triangles: mesh.triangles.clone() };
    Ok(HexInput { surface, context: cand.context.clone(), correspondence: cand.correspondence(), to_user })
}

/// The main job: polycube (any request), hex mesh of the best verified candidate(s),
/// spline fitted to the input. Progress: polycube 0-50 %, hex 50-85 %, spline 85-100 %.
pub fn run(
    model: &Model,
    mesh: &TriMesh,
    genus: i64,
    request: &ContextRequest,
    opts: &RunOptions,
    progress: &mut dyn Progress,
) -> Result<RunResult> {
    // every option is checked before any work
    opts.validate()?;
    let mut progress = crate::error::MonotoneProgress::new(progress);
    let progress: &mut dyn Progress = &mut progress;
    let mut seconds = Vec::new();
    let t0 = Instant::now();
    let (mut pr, auto, err) = {
        let mut sub = SubProgress { inner: progress, lo: 0.0, hi: 0.5 };
        generate_polycube(model, mesh, genus, request, &opts.polycube, &opts.auto, &mut sub)?
    };
    seconds.push(("polycube".to_string(), t0.elapsed().as_secs_f64()));
    let hs = {
        let mut sub = SubProgress { inner: progress, lo: 0.5, hi: 0.85 };
        mesh_polycube(&mut pr, err, mesh, opts, &mut sub)?
    };
    let HexStage { candidate, attempts, verified, verification_error, hex } = hs;
    seconds.push(("hex".to_string(), t0.elapsed().as_secs_f64() - seconds[0].1));
    let spline = match &opts.spline {
        Some(so) => {
            let t2 = Instant::now();
            let mut sub = SubProgress { inner: progress, lo: 0.85, hi: 1.0 };
            let s = build_spline(&hex.mesh, Some(mesh), so, &mut sub)?;
            seconds.push(("spline".to_string(), t2.elapsed().as_secs_f64()));
            Some(s)
        }
        None => None,
    };
    check_progress(progress, 1.0, "done")?;
    Ok(RunResult { polycube: pr, auto, candidate, hex_attempts: attempts, verified, verification_error, hex, spline, seconds, options: opts.clone() })
}

/// What the hex stage of the main job made of a polycube result ([`mesh_polycube`]).
pub struct HexStage {
    /// Index (into the polycube's candidates) of the candidate whose mesh was kept
    /// (for the grid-based fallback: the best polycube attempt's, or the first; None
    /// when there was no candidate to mesh).
    pub candidate: Option<usize>,
    /// Every hex build, in order.
    pub attempts: Vec<HexAttempt>,
    /// False when the mesh does not come from a verified candidate's polycube.
    pub verified: bool,
    /// Why the mesh is not a verified polycube's (None when it is).
    pub verification_error: Option<String>,
    pub hex: HexResult,
}

/// The hex stage of the main job, shared by [`run`], the C API
/// (sddpm_hex_mesh_build) and so the Python package: the candidates to mesh in
/// their one order ([`hex_order`]), the best mesh of them and of the grid-based
/// fallback ([`build_hex_for_polycube`]), and the checks of `opts.require_valid_hex`.
/// `err` is the refusal [`generate_polycube`] returned with `pr`; the candidates
/// the order lays out without diffusion are added to `pr`. Progress over 0-1.
pub fn mesh_polycube(pr: &mut PolycubeResult, err: Option<Error>, mesh: &TriMesh, opts: &RunOptions, progress: &mut dyn Progress) -> Result<HexStage> {
    opts.validate()?;
    let mut progress = crate::error::MonotoneProgress::new(progress);
    let progress: &mut dyn Progress = &mut progress;
    let verification_error = err.as_ref().map(|e| e.to_string());
    let mut hex_opts = opts.hex.clone();
    if err.is_some() {
        // nothing verified: an unverified candidate's diffusion output is not a
        // correspondence to seed the surface map with
        hex_opts.map.use_correspondence = false;
    }
    let order = hex_order(pr, err, opts)?;
    let (candidate, attempts, hex) = build_hex_for_polycube(pr, &order, mesh, &hex_opts, progress)?;
    let voxel = !hex.from_polycube();
    let verified = !voxel && candidate.is_some_and(|c| pr.candidates[c].stage == crate::search::generate::Stage::Verified);
    let polycube_meshes = attempts.iter().any(|a| a.candidate.is_some());
    let verification_error = match (verified, verification_error) {
        (true, _) => None,
        // nothing to mesh from a polycube: the polycube stage's refusal says why
        (false, Some(e)) if voxel && !polycube_meshes => Some(format!(
            "no polycube was meshed: {e}; the mesh comes from the grid-based fallback ({}: min scaled Jacobian {:.3}, mean {:.3}, Hausdorff {:.2} %)",
            hex.domain,
            hex.quality.min,
            hex.quality.mean,
            100.0 * hex.hausdorff_relative
        )),
        (false, _) if voxel => Some(format!(
            "no polycube candidate's hex mesh met the quality goals (best: {}); the mesh comes from the grid-based fallback ({}: min scaled Jacobian {:.3}, mean {:.3}, Hausdorff {:.2} %), which ranks better, not from the polycube",
            attempts
                .iter()
                .filter(|a| a.candidate.is_some() && a.error.is_none())
                .min_by(|a, b| a.rank().partial_cmp(&b.rank()).unwrap_or(std::cmp::Ordering::Equal))
                .map(|a| a.describe())
                .unwrap_or_else(|| "no mesh".into()),
            hex.domain,
            hex.quality.min,
            hex.quality.mean,
            100.0 * hex.hausdorff_relative
        )),
        (false, Some(e)) => Some(e),
        (false, None) => Some(format!(
            "the hex meshes of the verified candidates ranked below (inverted elements, then quality goals missed) the mesh of unverified candidate {}",
            candidate.map(|c| pr.candidates[c].context.to_string()).unwrap_or_default()
        )),
    };
    if opts.require_valid_hex && hex.quality.inverted > 0 {
        let bad: Vec<String> = hex.scaled_jacobian.iter().enumerate().filter(|(_, &q)| !(q > 0.0)).take(5).map(|(e, q)| format!("{e} ({q:.3})")).collect();
        return Err(Error::MeshingFailed(format!(
            "{} of {} hex elements are inverted after quality improvement (first: element {}) for polycube {}{}; try another context or splitting ratios, or a fixed --level",
            hex.quality.inverted,
            hex.quality.elements,
            bad.join(", element "),
            candidate.map(|c| pr.candidates[c].context.to_string()).unwrap_or_else(|| "(none: grid-based fallback)".into()),
            if verified { "" } else { " (unverified)" }
        )));
    }
    Ok(HexStage { candidate, attempts, verified, verification_error, hex })
}

/// The candidates to mesh, best first, at most `opts.hex_candidates`: the verified
/// ones ([`ranked_verified`]), then, with `opts.accept_unverified`, the unverified
/// ones of [`fallback_order`] for the remaining builds. Without a verified
/// candidate, `err` (the polycube's refusal) is returned unless
/// `opts.accept_unverified` and it is a VERIFICATION_FAILED with something to mesh.
pub fn hex_order(pr: &mut PolycubeResult, err: Option<Error>, opts: &RunOptions) -> Result<Vec<usize>> {
    let k = opts.hex_candidates.max(1);
    let mut order = match err {
        Some(e) if !(opts.accept_unverified && matches!(e, Error::VerificationFailed(_))) => return Err(e),
        Some(e) => {
            // the diffused candidates by fit, then refused ones laid out without
            // diffusion (the hex stage then works from the geometry alone)
            let order = fallback_order(pr, &opts.polycube, k);
            // nothing to mesh from a polycube (no candidate was formed: a part the
            // grid cannot hold): the grid-based fallback alone, when it is on
            if order.is_empty() && !opts.hex.fallback.enabled {
                return Err(e);
            }
            order
        }
        None => {
            let mut order = ranked_verified(pr);
            // verified candidates first; when their meshes fold, the unverified ones
            // (by fit) get the remaining builds, as in a run where nothing verified
            if opts.accept_unverified && order.len() < k {
                for i in fallback_order(pr, &opts.polycube, k) {
                    if !order.contains(&i) {
                        order.push(i);
                    }
                }
            }
            if order.is_empty() {
                return Err(pr.accepted().err().unwrap_or_else(|| Error::VerificationFailed("no candidate to mesh".into())));
            }
            order
        }
    };
    order.truncate(k);
    Ok(order)
}

/// Verified candidates, the chosen one first, then by score.
fn ranked_verified(pr: &PolycubeResult) -> Vec<usize> {
    let mut order: Vec<usize> = (0..pr.candidates.len()).filter(|&i| pr.candidates[i].stage == crate::search::generate::Stage::Verified).collect();
    order.sort_by(|&a, &b| {
        let sa = pr.candidates[a].score.unwrap_or(f64::INFINITY);
        let sb = pr.candidates[b].score.unwrap_or(f64::INFINITY);
        sa.total_cmp(&sb)
    });
    if let Some(c) = pr.chosen {
        order.retain(|&i| i != c);
        order.insert(0, c);
    }
    order
}

/// The diffused candidates to mesh when none passed verification, best first: those
/// that passed GOCC before those that failed it, then by the geometric fit of the
/// input to the polycube.
fn fallback_candidates(pr: &PolycubeResult) -> Vec<usize> {
    use crate::search::generate::Stage;
    let mut v: Vec<usize> = (0..pr.candidates.len())
        .filter(|&i| pr.candidates[i].input.is_some() && matches!(pr.candidates[i].stage, Stage::Tcv | Stage::Gocc | Stage::Verified))
        .collect();
    v.sort_by(|&a, &b| {
        let (ca, cb) = (&pr.candidates[a], &pr.candidates[b]);
        ((ca.stage == Stage::Gocc) as u8, ca.fit).partial_cmp(&((cb.stage == Stage::Gocc) as u8, cb.fit)).unwrap_or(std::cmp::Ordering::Equal)
    });
    v
}

/// Lay out candidate `i`'s inference input without diffusion when it has none
/// (refused by the pre-check), from the input samples the polycube result keeps;
/// false when that fails.
fn prepare_candidate_input(pr: &mut PolycubeResult, opts: &PolycubeOptions, i: usize) -> bool {
    if pr.candidates[i].input.is_some() {
        return true;
    }
    let c = &pr.candidates[i];
    const RELAYOUT_SEED: u64 = 0x9e37;
    const RELAYOUT_STREAM: u64 = 0xfa11;
    let mut rng = crate::geometry::rng::seeded_rng(opts.seed ^ RELAYOUT_SEED, RELAYOUT_STREAM);
    match crate::search::inference::prepare(&pr.samples, &c.context, c.axis_rotation, c.warp.as_ref(), 0.0, &mut rng) {
        Ok(inp) => {
            pr.candidates[i].input = Some(inp);
            true
        }
        Err(_) => false,
    }
}

/// Up to `k` candidates to mesh when none passed verification, best first: the
/// diffused ones ([`fallback_candidates`]), then the candidates of the input's genus
/// that the pre-check refused, by geometric fit, laid out without diffusion. The hex
/// stage does not use the diffusion output of an unverified candidate, so a refused
/// candidate is as good a start as a diffused one; this lets a plain shape whose fit
/// the pre-check judged poor (a cube where the fit preferred a blind hole) still be
/// meshed when the better-fitting ones fold.
fn fallback_order(pr: &mut PolycubeResult, opts: &PolycubeOptions, k: usize) -> Vec<usize> {
    let genus = pr.input_genus;
    use crate::polycube::Primitive;
    let all_cube = |c: &crate::context::Context| c.occupied().all(|n| c.labels[n] == Primitive::Cube);
    // a genus-0 input without an all-cube candidate keeps one slot for it (below)
    let cube_slot = genus == 0 && k > 1 && !pr.candidates.iter().any(|c| all_cube(&c.context));
    let room = if cube_slot { k - 1 } else { k };
    let mut order = fallback_candidates(pr);
    order.truncate(room);
    if order.len() < room {
        let mut rest: Vec<usize> = (0..pr.candidates.len())
            .filter(|&i| pr.candidates[i].input.is_none() && pr.candidates[i].context.validity().genus == Some(genus))
            .collect();
        rest.sort_by(|&a, &b| pr.candidates[a].fit.total_cmp(&pr.candidates[b].fit));
        for i in rest {
            if order.len() >= room {
                break;
            }
            if prepare_candidate_input(pr, opts, i) {
                order.push(i);
            }
        }
    }
    // a genus-0 input can always start from plain cubes: when no candidate is all
    // cubes, the best-fitting candidate's cells relabelled as cubes is the last resort
    // (the automated mode keeps only the best-fitting labels per subregion, which for
    // a block with a recess are all blind holes)
    if cube_slot {
        let best = (0..pr.candidates.len())
            .filter(|&i| pr.candidates[i].context.validity().genus == Some(0))
            .min_by(|&a, &b| pr.candidates[a].fit.total_cmp(&pr.candidates[b].fit));
        if let Some(b) = best {
            let mut c = pr.candidates[b].clone();
            for n in 0..crate::polycube::NUM_CELLS {
                if c.context.labels[n] != Primitive::Null {
                    c.context.labels[n] = Primitive::Cube;
                }
            }
            if c.context.validity().genus == Some(0) {
                c.labels = c.context.label_values();
                c.fit = f64::INFINITY; // not measured
                c.stage = crate::search::generate::Stage::Occupancy;
                c.report = None;
                c.fidelity = None;
                c.score = None;
                c.input = None;
                c.output = None;
                pr.candidates.push(c);
                let i = pr.candidates.len() - 1;
                if prepare_candidate_input(pr, opts, i) {
                    order.push(i);
                } else {
                    pr.candidates.pop();
                }
            }
        }
    }
    order
}

/// Where the grid-based fallback's share of the hex stage's progress starts.
const FALLBACK_FROM: f64 = 5.0 / 7.0;

/// Mesh the candidates `order` (indices into `pr.candidates`) and keep the best mesh
/// by [`crate::hex::QualityGoals::rank`] (fewest inverted elements, then fewest
/// missed goals, then highest minimum scaled Jacobian); stops early once a mesh meets
/// every goal of `hex_opts.goals`. When the best polycube mesh still misses one (with
/// a fixed `hex_opts.map.level`: when it keeps inverted elements), the grid-based
/// fallback is also built (if `hex_opts.fallback.enabled`) and kept when it ranks
/// better. Progress over 0-1: the candidates, then (from [`FALLBACK_FROM`]) the fallback.
fn build_hex_for_polycube(
    pr: &PolycubeResult,
    order: &[usize],
    mesh: &TriMesh,
    hex_opts: &HexOptions,
    progress: &mut dyn Progress,
) -> Result<(Option<usize>, Vec<HexAttempt>, HexResult)> {
    let goals = &hex_opts.goals;
    let mut best: Option<(Option<usize>, HexResult)> = None;
    let mut attempts = Vec::new();
    let n = order.len();
    let mut last_err = None;
    for (k, &ci) in order.iter().enumerate() {
        let cand = &pr.candidates[ci];
        let input = hex_input(&pr, cand, mesh)?;
        let th = Instant::now();
        let span = if hex_opts.fallback.enabled { FALLBACK_FROM } else { 1.0 };
        let mut sub = SubProgress { inner: progress, lo: span * k as f64 / n as f64, hi: span * (k + 1) as f64 / n as f64 };
        let r = match build_hex_mesh(&input, &size::for_polycube(hex_opts, &cand.context, mesh), &mut sub) {
            Ok(r) => r,
            Err(e @ Error::Cancelled(_)) => return Err(e),
            Err(e) => {
                attempts.push(HexAttempt::failed(Some(ci), cand.context.names(), &e, th));
                last_err = Some(e);
                continue;
            }
        };
        attempts.push(HexAttempt::of(Some(ci), cand.context.names(), &r, goals, th));
        if goals.beats(&r, best.as_ref().map(|(_, b)| b)) {
            best = Some((Some(ci), r));
        }
        if best.as_ref().is_some_and(|(_, b)| goals.missed(b) == 0) {
            break; // good enough: do not spend another build
        }
    }
    // no polycube mesh meets the goals (or none could be built): the grid-based
    // fallback; with a level the caller fixed, only when every mesh folds (the
    // caller asked for that polycube refinement, not for the best mesh of any kind)
    let short = best.as_ref().is_none_or(|(_, b)| if hex_opts.map.level.is_some() { b.quality.inverted > 0 } else { goals.missed(b) > 0 });
    if hex_opts.fallback.enabled && short {
        let th = Instant::now();
        let mut sub = SubProgress { inner: progress, lo: FALLBACK_FROM, hi: 1.0 };
        let identity = Affine::similarity(1.0, [0.0; 3]);
        match crate::hex::build_voxel_hex_mesh(mesh, &identity, pr.input_genus, &size::for_lattice(hex_opts, mesh), &mut sub) {
            Ok(r) => {
                attempts.push(HexAttempt::of(None, r.domain.to_string(), &r, goals, th));
                if goals.beats(&r, best.as_ref().map(|(_, b)| b)) {
                    // the candidate index stays the best polycube attempt's (or the first)
                    let ci = best.as_ref().and_then(|(c, _)| *c).or(order.first().copied());
                    best = Some((ci, r));
                }
            }
            Err(e @ Error::Cancelled(_)) => return Err(e),
            Err(e) => {
                // reported with the attempts (and in the run's warning when a
                // polycube mesh that misses the goals is kept)
                attempts.push(HexAttempt::failed(None, "voxel".into(), &e, th));
                if best.is_none() {
                    last_err = Some(e);
                }
            }
        }
    }
    match best {
        Some((candidate, hex)) => Ok((candidate, attempts, hex)),
        None => Err(last_err.unwrap_or_else(|| Error::Internal("no candidate to mesh".into()))),
    }
}

impl HexAttempt {
    /// The ranking key of [`crate::hex::QualityGoals::rank`] from the recorded figures.
    fn rank(&self) -> (usize, usize, f64, f64) {
        (self.inverted, self.goals_missed, self.goal_shortfall, -self.min_scaled_jacobian)
    }

    /// The attempt's figures in words, its context readable ("THC+Z at (0,0,0)").
    fn describe(&self) -> String {
        format!(
            "{}: {} inverted, min scaled Jacobian {:.3}, mean {:.3}, Hausdorff {:.2} %",
            Context::parse(&self.context).map(|c| c.describe()).unwrap_or_else(|_| self.context.clone()),
            self.inverted,
            self.min_scaled_jacobian,
            self.mean_scaled_jacobian,
            100.0 * self.hausdorff_relative
        )
    }

    fn of(candidate: Option<usize>, context: String, r: &HexResult, goals: &crate::hex::QualityGoals, started: Instant) -> Self {
        HexAttempt {
            candidate,
            context,
            min_scaled_jacobian: r.quality.min,
            mean_scaled_jacobian: r.quality.mean,
            inverted: r.quality.inverted,
            hausdorff_relative: r.hausdorff_relative,
            goals_missed: goals.missed(r),
            goal_shortfall: goals.shortfall(r),
            seconds: started.elapsed().as_secs_f64(),
            error: None,
            surface_maps: r.surface_map.tried.clone(),
        }
    }

    /// A build that failed with `e`.
    fn failed(candidate: Option<usize>, context: String, e: &Error, started: Instant) -> Self {
        HexAttempt {
            candidate,
            context,
            min_scaled_jacobian: f64::NAN,
            mean_scaled_jacobian: f64::NAN,
            inverted: 0,
            hausdorff_relative: f64::NAN,
            goals_missed: 3,
            goal_shortfall: f64::NAN,
            seconds: started.elapsed().as_secs_f64(),
            error: Some(e.to_string()),
            surface_maps: Vec::new(),
        }
    }
}

/// The polycube of a diffused candidate in the user's coordinates (grid -> model frame
/// -> aligned frame -> user), as a triangle mesh whose vertices are those of the
/// assembly's boundary quads.
pub fn polycube_user_mesh(result: &PolycubeResult, c: &Candidate) -> TriMesh {
    let mut m = crate::polycube::boundary(&c.context.assemble()).to_trimesh();
    if let Some(inp) = &c.input {
        for v in m.vertices.iter_mut() {
            let q = inp.frame.to_normalised(*v);
            let a = inp.map.inverse(q);
            *v = result.alignment.transform.apply_inverse(a);
        }
    }
    m
}
