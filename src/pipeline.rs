//! The whole job, stage by stage, as one library call each: polycube generation from
//! a request (complete contexts, partial constraints, splitting ratios or the
//! automated search), then (in later stages) the hex mesh and the spline.

use crate::context::auto::{auto_failure, generate_auto, AutoOptions, AutoReport, SplitRatios};
use crate::context::generate::{generate_from_contexts, PolycubeOptions, PolycubeResult};
use crate::context::{Constraints, Context};
use crate::diffusion::Model;
use crate::error::{check_progress, Error, Progress, Result};
use crate::mesh::TriMesh;
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

use crate::context::generate::Candidate;
use crate::error::SubProgress;
use crate::hex::{build_hex_mesh, Affine, HexInput, HexOptions, HexResult};
use crate::spline::{build_spline, Spline, SplineOptions};
use std::time::Instant;

/// Options of [`run`]: one struct per stage, each with its documented defaults.
#[derive(Debug, Clone, PartialEq)]
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
    /// How many verified candidates (best score first) are meshed; the one whose hex
    /// mesh has the fewest inverted elements, then the highest minimum scaled Jacobian,
    /// is kept (default 2: a second candidate costs one more hex build and often
    /// rescues an orientation whose map folds).
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
            hex_candidates: 2,
        }
    }
}

/// One hex build of a verified candidate.
#[derive(Debug, Clone, Serialize)]
pub struct HexAttempt {
    pub candidate: usize,
    pub context: String,
    pub min_scaled_jacobian: f64,
    pub inverted: usize,
    pub hausdorff_relative: f64,
    pub seconds: f64,
}

/// Everything [`run`] produced.
pub struct RunResult {
    pub polycube: PolycubeResult,
    pub auto: Option<AutoReport>,
    /// Index (into `polycube.candidates`) of the candidate that was meshed and kept.
    pub candidate: usize,
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
pub fn hex_input(result: &PolycubeResult, cand: &Candidate, mesh: &TriMesh) -> Result<HexInput> {
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
    let mut seconds = Vec::new();
    let t0 = Instant::now();
    let (pr, auto, err) = {
        let mut sub = SubProgress { inner: progress, lo: 0.0, hi: 0.5 };
        generate_polycube(model, mesh, genus, request, &opts.polycube, &opts.auto, &mut sub)?
    };
    seconds.push(("polycube".to_string(), t0.elapsed().as_secs_f64()));
    let verification_error = err.as_ref().map(|e| e.to_string());
    let mut hex_opts = opts.hex.clone();
    let mut order: Vec<usize>;
    let mut pr = pr;
    if let Some(e) = err {
        if !(opts.accept_unverified && matches!(e, Error::VerificationFailed(_))) {
            return Err(e);
        }
        let i = match fallback_candidate(&pr) {
            Some(i) => i,
            None => {
                // nothing was diffused (every candidate refused by the pre-check): lay
                // out the best-fitting one without diffusion (the hex stage then works
                // from the geometry alone)
                prepare_fallback(&mut pr, mesh, &opts.polycube, genus).ok_or(e)?
            }
        };
        order = vec![i];
        hex_opts.use_correspondence = false;
    } else {
        order = ranked_verified(&pr);
    }
    order.truncate(opts.hex_candidates.max(1));
    let verified = verification_error.is_none();
    let (candidate, attempts, hex) = build_hex_for_polycube(&pr, &order, mesh, &hex_opts, progress)?;
    seconds.push(("hex".to_string(), t0.elapsed().as_secs_f64() - seconds[0].1));
    if opts.require_valid_hex && hex.quality.inverted > 0 {
        let bad: Vec<String> = hex.scaled_jacobian.iter().enumerate().filter(|(_, &q)| !(q > 0.0)).take(5).map(|(e, q)| format!("{e} ({q:.3})")).collect();
        return Err(Error::MeshingFailed(format!(
            "{} of {} hex elements are inverted after quality improvement (first: element {}) for polycube {}{}; try another context or splitting ratios, or a fixed --level",
            hex.quality.inverted,
            hex.quality.elements,
            bad.join(", element "),
            pr.candidates[candidate].context,
            if verified { "" } else { " (unverified)" }
        )));
    }
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
    Ok(RunResult { polycube: pr, auto, candidate, hex_attempts: attempts, verified, verification_error, hex, spline, seconds })
}

/// Verified candidates, the chosen one first, then by score.
pub fn ranked_verified(pr: &PolycubeResult) -> Vec<usize> {
    let mut order: Vec<usize> = (0..pr.candidates.len()).filter(|&i| pr.candidates[i].stage == crate::context::generate::Stage::Verified).collect();
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

/// The diffused candidate to mesh when none passed verification: GOCC passes first,
/// then the best geometric fit of the input to the polycube.
pub fn fallback_candidate(pr: &PolycubeResult) -> Option<usize> {
    use crate::context::generate::Stage;
    (0..pr.candidates.len())
        .filter(|&i| pr.candidates[i].input.is_some() && matches!(pr.candidates[i].stage, Stage::Tcv | Stage::Gocc | Stage::Verified))
        .min_by(|&a, &b| {
            let (ca, cb) = (&pr.candidates[a], &pr.candidates[b]);
            ((ca.stage == Stage::Gocc) as u8, ca.fit).partial_cmp(&((cb.stage == Stage::Gocc) as u8, cb.fit)).unwrap_or(std::cmp::Ordering::Equal)
        })
}

/// When the pre-check refused every candidate: give the best-fitting candidate of the
/// input's genus its inference input (the map of the input into the polycube's box),
/// without diffusion, and return its index; None when there is no such candidate.
pub fn prepare_fallback(pr: &mut PolycubeResult, mesh: &TriMesh, opts: &PolycubeOptions, genus: i64) -> Option<usize> {
    let best = (0..pr.candidates.len())
        .filter(|&i| pr.candidates[i].context.validity().genus == Some(genus))
        .min_by(|&a, &b| pr.candidates[a].fit.total_cmp(&pr.candidates[b].fit))?;
    if pr.candidates[best].input.is_none() {
        let input = crate::context::generate::prepare_input(mesh, opts).ok()?;
        let c = &pr.candidates[best];
        let mut rng = crate::polycube::dataset::item_rng(opts.seed ^ 0x9e37, 0xfa11);
        let inp = crate::polycube::inference::prepare(&input.samples, &c.context, c.axis_rotation, 0.0, &mut rng).ok()?;
        pr.candidates[best].input = Some(inp);
    }
    Some(best)
}

/// Mesh the candidates `order` (indices into `pr.candidates`) and keep the best mesh:
/// fewest inverted elements, then highest minimum scaled Jacobian; stops early once a
/// mesh has no inverted element and a minimum scaled Jacobian of at least 0.3.
/// Progress: 50-85 % of the caller's range.
pub fn build_hex_for_polycube(
    pr: &PolycubeResult,
    order: &[usize],
    mesh: &TriMesh,
    hex_opts: &HexOptions,
    progress: &mut dyn Progress,
) -> Result<(usize, Vec<HexAttempt>, HexResult)> {
    let mut best: Option<(usize, HexResult)> = None;
    let mut attempts = Vec::new();
    let n = order.len();
    let mut last_err = None;
    for (k, &ci) in order.iter().enumerate() {
        let cand = &pr.candidates[ci];
        let input = hex_input(&pr, cand, mesh)?;
        let th = Instant::now();
        let mut sub = SubProgress { inner: progress, lo: 0.5 + 0.35 * k as f64 / n as f64, hi: 0.5 + 0.35 * (k + 1) as f64 / n as f64 };
        let r = match build_hex_mesh(&input, hex_opts, &mut sub) {
            Ok(r) => r,
            Err(e @ Error::Cancelled(_)) => return Err(e),
            Err(e) => {
                last_err = Some(e);
                continue;
            }
        };
        attempts.push(HexAttempt {
            candidate: ci,
            context: cand.context.names(),
            min_scaled_jacobian: r.quality.min,
            inverted: r.quality.inverted,
            hausdorff_relative: r.hausdorff_relative,
            seconds: th.elapsed().as_secs_f64(),
        });
        let better = match &best {
            None => true,
            Some((_, b)) => (r.quality.inverted, -r.quality.min) < (b.quality.inverted, -b.quality.min),
        };
        if better {
            best = Some((ci, r));
        }
        if best.as_ref().is_some_and(|(_, b)| b.quality.inverted == 0 && b.quality.min >= 0.3) {
            break; // good enough: do not spend another build
        }
    }
    match best {
        Some((candidate, hex)) => Ok((candidate, attempts, hex)),
        None => Err(last_err.unwrap_or_else(|| Error::Internal("no candidate to mesh".into()))),
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
