//! The polycube map, the method of this library: the accepted polycube's lattice
//! mesh mapped onto the input: a surface map from the
//! polycube boundary onto the input surface, then the interior by harmonic
//! interpolation.
//!
//! Surface map (docs/hex.md has the same in prose):
//! 1. Polycube features (edges and corners of the boundary, from the outward
//!    normals of the boundary quads) are matched to the input's sharp features
//!    in the normalised frame, where polycube and input share their bounding box:
//!    a polycube corner goes to the nearest input corner within half a sub-voxel
//!    (one-to-one, nearest pairs first); a polycube edge chain goes to the input
//!    feature curve that is close to it along its whole length and roughly parallel.
//! 2. Every boundary node gets a start position: the closest point on its matched
//!    curve / its corner, or the closest point on the input surface among triangles
//!    that face the same way as the polycube face (a seed from the diffusion
//!    correspondence, when given, is added first).
//! 3. Relaxation on the surface in the working frame: tangential Laplacian moves with
//!    reprojection (curve nodes along their curve, corners fixed); this spreads the
//!    nodes and undoes folds of the closest-point start.
//! 4. Interior: the discrete harmonic map (uniform edge weights) with the boundary
//!    fixed, solved by preconditioned conjugate gradients; inversions that remain are
//!    for the optimisation stage to untangle.
//!
//! [`build_hex_mesh`] maps the levels ([`levels`]), takes the one the stopping rule
//! picks and hands it to the quality steps ([`crate::hex::quality::improve`]).
//! By default it does so with the inverse chart maps and, when their mesh misses
//! a quality goal, with the projection above as well, keeping the better mesh;
//! a mesh that misses the distance goal alone is also built one level finer.
//! Feature matching is in [`features`], the start embedding in [`warp`], the
//! correspondence seed in [`correspondence`].

pub mod charts;
mod correspondence;
mod features;
mod levels;
mod local;
mod warp;

use crate::context::{context_frame, Context};
use crate::error::{check_progress, Error, Progress, Result, SubProgress};
use crate::geometry::{Aabb, Alignment};
use crate::hex::frame::Affine;
use crate::hex::frames::{working_frames, Frames};
use crate::hex::report::{MapMethod, SurfaceMapTry};
use crate::hex::quality::{improve, MapStage};
use crate::hex::distance::far_points;
use crate::hex::work::Level;
use crate::hex::{HexOptions, HexResult, QualityGoals, SurfaceMap};
use crate::mesh::TriMesh;
use crate::polycube::assembly::occupied_cell_box;
use std::time::Instant;

/// What the hex stage needs from the pipeline.
#[derive(Debug, Clone)]
pub struct HexInput {
    /// The input surface in the context's normalised frame (its aligned bounding box
    /// scaled per axis onto the box of the occupied cells, longest edge 2, centred).
    pub surface: TriMesh,
    /// The accepted polycube.
    pub context: Context,
    /// Diffusion correspondence: (point on the polycube surface, point on the input
    /// surface), both in the normalised frame. May be empty; used as a seed only.
    pub correspondence: Vec<([f64; 3], [f64; 3])>,
    /// Normalised frame -> user coordinates.
    pub to_user: Affine,
}

impl HexInput {
    /// The mapping DESIGN.md "Inference" fixes: the PCA-aligned input's bounding box
    /// scaled per axis onto the normalised box of the context's occupied cells.
    /// Returns the input and the affine map aligned frame -> normalised frame.
    pub fn from_alignment(al: &Alignment, context: Context) -> Result<(HexInput, Affine)> {
        let frame = context_frame(&context)
            .ok_or_else(|| Error::InvalidContext("the context has no occupied cell".into()))?;
        let (lo, hi) = occupied_cell_box(&context.labels).expect("occupied");
        let blo = frame.to_normalised(lo.map(|v| v as f64));
        let bhi = frame.to_normalised(hi.map(|v| v as f64));
        let bb = Aabb::of_points(&al.mesh.vertices);
        let size = bb.size();
        if size.iter().any(|s| !(*s > 0.0)) {
            return Err(Error::InvalidMesh(format!("the aligned input is flat (bounding box {size:?})")));
        }
        let s: [f64; 3] = std::array::from_fn(|a| (bhi[a] - blo[a]) / size[a]);
        let t: [f64; 3] = std::array::from_fn(|a| blo[a] - s[a] * bb.min[a]);
        let a_to_n = Affine::diagonal(s, t);
        let n_to_a = a_to_n.inverse().expect("positive scales");
        let a_to_u = Affine::from_transform(&al.transform.inverse());
        let surface = TriMesh { vertices: al.mesh.vertices.iter().map(|&p| a_to_n.apply(p)).collect(), triangles: al.mesh.triangles.clone() };
        Ok((HexInput { surface, context, correspondence: Vec::new(), to_user: a_to_u.after(&n_to_a) }, a_to_n))
    }

    /// PCA-align a user mesh (geometry::align) and map it as [`HexInput::from_alignment`] does.
    pub fn from_user_mesh(mesh: &TriMesh, context: Context) -> Result<HexInput> {
        let al = crate::geometry::align(mesh)?;
        Ok(Self::from_alignment(&al, context)?.0)
    }
}


/// Build the all-hex mesh of `input` (see the module docs and docs/hex.md).
pub fn build_hex_mesh(input: &HexInput, opts: &HexOptions, progress: &mut dyn Progress) -> Result<HexResult> {
    let t_all = Instant::now();
    check_input(input, opts)?;
    check_progress(progress, 0.0, "hex: setup")?;
    let (fr, mesh_n) = working_frames(&input.surface, &input.to_user, opts)?;
    let mut sub = SubProgress { inner: progress, lo: 0.0, hi: 0.8 };
    let m = if opts.map.surface_map == SurfaceMap::Best {
        best_map(input, mesh_n.clone(), &fr, opts, t_all, &mut sub)?
    } else {
        map_and_improve(input, mesh_n.clone(), &fr, opts, t_all, &mut sub)?
    };
    let mut sub = SubProgress { inner: progress, lo: 0.8, hi: 1.0 };
    finer_for_distance(m, input, mesh_n, &fr, opts, t_all, &mut sub)
}

/// A finished polycube mesh and, when local refinement is on, the mapped level
/// it was improved from.
struct Meshed {
    r: HexResult,
    base: Option<Base>,
}

/// A mapped level before the quality steps: what local refinement starts from.
struct Base {
    level: Level,
    stage: MapStage,
    placer: levels::Placer,
}

/// [`SurfaceMap::Best`]: the charts first; the projection as well when their mesh
/// misses a goal (and the charts did map: otherwise the first mesh already is the
/// projection's); the mesh that ranks better by the goals is returned.
fn best_map(input: &HexInput, mesh_n: TriMesh, fr: &Frames, opts: &HexOptions, t_all: Instant, progress: &mut dyn Progress) -> Result<Meshed> {
    let mut o = opts.clone();
    o.map.surface_map = SurfaceMap::Charts;
    let t = Instant::now();
    let mut sub = SubProgress { inner: progress, lo: 0.0, hi: 0.5 };
    let mut charts = map_and_improve(input, mesh_n.clone(), fr, &o, t_all, &mut sub)?;
    let charts_s = t.elapsed().as_secs_f64();
    if opts.goals.missed(&charts.r) == 0 || charts.r.surface_map.method != MapMethod::Charts {
        charts.r.surface_map.tried = vec![tried_map(&charts.r, charts_s, true, &opts.goals)];
        return Ok(charts);
    }
    o.map.surface_map = SurfaceMap::Projection;
    let t = Instant::now();
    let mut sub = SubProgress { inner: progress, lo: 0.5, hi: 1.0 };
    let projection = map_and_improve(input, mesh_n, fr, &o, t_all, &mut sub)?;
    let projection_s = t.elapsed().as_secs_f64();
    let keep_projection = opts.goals.beats(&projection.r, Some(&charts.r));
    let tried = vec![tried_map(&charts.r, charts_s, !keep_projection, &opts.goals), tried_map(&projection.r, projection_s, keep_projection, &opts.goals)];
    let mut m = if keep_projection { projection } else { charts };
    m.r.surface_map.tried = tried;
    m.r.seconds_total = t_all.elapsed().as_secs_f64();
    Ok(m)
}

/// A mesh that misses the distance goal alone (no inverted element, minimum and
/// mean met) is refined where it is far from the input: first locally
/// ([`local`]: up to `map.local_refinement` rounds, each splitting the level's
/// elements around the points farthest from the last mesh), then, when that
/// still misses a goal, one level finer than the stopping rule's. A finer level
/// shortens the chords between boundary nodes, which is what the distance
/// measures, while it does not mend badly shaped elements. Neither with a level
/// the caller fixed; no mesh past `max_elements`, no level above
/// `map.max_level`, no locally refined mesh with as many elements as the finer
/// level would have. The mesh that ranks best by the goals is returned; every
/// mesh built is listed in `surface_map.tried`.
fn finer_for_distance(m: Meshed, input: &HexInput, mesh_n: TriMesh, fr: &Frames, opts: &HexOptions, t_all: Instant, progress: &mut dyn Progress) -> Result<HexResult> {
    let goals = &opts.goals;
    let only_distance = |r: &HexResult| !goals.misses_scaled_jacobian(r) && !(r.hausdorff_relative <= goals.hausdorff);
    let Meshed { r, base } = m;
    let next = r.level + 1;
    let finer_allowed = next <= opts.map.max_level && r.quality.elements.saturating_mul(8) <= opts.max_elements;
    if opts.map.level.is_some() || !only_distance(&r) || (opts.map.local_refinement == 0 && !finer_allowed) {
        return Ok(r);
    }
    let mut tried = r.surface_map.tried.clone();
    if tried.is_empty() {
        tried.push(tried_map(&r, r.seconds_total, true, goals));
    }
    let mut best = r;
    let keep = |r: HexResult, entry: SurfaceMapTry, best: &mut HexResult, tried: &mut Vec<SurfaceMapTry>| {
        if entry.kept {
            tried.iter_mut().for_each(|t| t.kept = false);
            *best = r;
        }
        tried.push(entry);
    };
    // local refinement, round by round from the last mesh
    let mut boxes = Vec::new();
    let mut marked_n = 0;
    let mut from = best.mesh.clone();
    for _ in 0..base.as_ref().map_or(0, |_| opts.map.local_refinement) {
        let base = base.as_ref().expect("kept when local refinement is on");
        if goals.missed(&best) == 0 {
            break;
        }
        // the points beyond half the goal's distance as well: the whole region
        // near or past the goal, not only its farthest part
        let far = far_points(&from, fr, local::FAR_SHARE, 0.5 * goals.hausdorff * fr.diag_w);
        let marked = local::mark_far(&base.level, &far, &mut boxes);
        let n = marked.iter().filter(|&&m| m).count();
        if n == marked_n {
            break;
        }
        marked_n = n;
        let t = Instant::now();
        let (lv, targets, split) = local::refine_level(&base.level, &marked, &base.placer, &fr.sw).map_err(|e| Error::Internal(format!("local refinement of the polycube map: {e}")))?;
        // no more elements than the level one finer has (eight times the
        // level's): a far region that covers a quarter of the level or more is
        // a job for the finer level, which keeps the lattice's structure
        let elements = lv.h.mesh.elements.len();
        if elements > opts.max_elements || elements >= 8 * base.level.h.mesh.elements.len() {
            break;
        }
        let refined = improve(lv, targets, base.stage.clone(), fr, opts, t_all, progress)?;
        from = refined.mesh.clone();
        let mut entry = tried_map(&refined, t.elapsed().as_secs_f64(), goals.beats(&refined, Some(&best)), goals);
        entry.split_elements = split;
        keep(refined, entry, &mut best, &mut tried);
    }
    // one level finer, when a goal is still missed
    if goals.missed(&best) > 0 && finer_allowed {
        let mut o = opts.clone();
        o.map.level = Some(next);
        o.map.surface_map = if best.surface_map.method == MapMethod::Charts { SurfaceMap::Charts } else { SurfaceMap::Projection };
        let t = Instant::now();
        let finer = map_and_improve(input, mesh_n, fr, &o, t_all, progress)?.r;
        let entry = tried_map(&finer, t.elapsed().as_secs_f64(), goals.beats(&finer, Some(&best)), goals);
        keep(finer, entry, &mut best, &mut tried);
    }
    best.surface_map.tried = tried;
    best.seconds_total = t_all.elapsed().as_secs_f64();
    Ok(best)
}

/// Map the levels with `opts`' surface map and run the quality steps on the chosen one.
fn map_and_improve(input: &HexInput, mesh_n: TriMesh, fr: &Frames, opts: &HexOptions, t_all: Instant, progress: &mut dyn Progress) -> Result<Meshed> {
    let mapped = levels::map_levels(input, mesh_n, fr, opts, progress)?;
    let stage = MapStage { surface_map: mapped.surface_map, levels: mapped.levels, fit: mapped.fit, lattice: None };
    // the level before the quality steps, only for local refinement
    let base = (opts.map.local_refinement > 0).then(|| Base { level: mapped.level.clone(), stage: stage.clone(), placer: mapped.placer });
    let r = improve(mapped.level, mapped.targets, stage, fr, opts, t_all, progress)?;
    Ok(Meshed { r, base })
}

/// The report entry of one surface map's finished mesh.
fn tried_map(r: &HexResult, seconds: f64, kept: bool, goals: &QualityGoals) -> SurfaceMapTry {
    SurfaceMapTry {
        method: r.surface_map.method,
        level: r.level,
        elements: r.quality.elements,
        inverted: r.quality.inverted,
        min_scaled_jacobian: r.quality.min,
        mean_scaled_jacobian: r.quality.mean,
        hausdorff_relative: r.hausdorff_relative,
        goals_missed: goals.missed(r),
        seconds,
        kept,
        split_elements: 0,
    }
}

/// The checks of [`build_hex_mesh`]: a valid polycube, a surface with triangles,
/// finite coordinates and indices in range, valid options, an invertible frame.
fn check_input(input: &HexInput, opts: &HexOptions) -> Result<()> {
    let validity = input.context.validity();
    if !validity.valid {
        return Err(Error::InvalidContext(format!(
            "the polycube is not a valid solid: {}",
            validity.reason.unwrap_or_default()
        )));
    }
    if input.surface.triangles.is_empty() {
        return Err(Error::InvalidArgument("the input surface has no triangles".into()));
    }
    if input.surface.vertices.iter().flatten().any(|v| !v.is_finite()) || !input.to_user.is_finite() {
        return Err(Error::InvalidArgument("non-finite coordinate in the hex stage input".into()));
    }
    if input.surface.triangles.iter().flatten().any(|&i| i as usize >= input.surface.vertices.len()) {
        return Err(Error::InvalidArgument("a triangle refers to a vertex that does not exist".into()));
    }
    opts.validate()?;
    if input.to_user.inverse().is_none() {
        return Err(Error::InvalidArgument("the map to user coordinates is singular".into()));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::geometry::trimesh::tests::box_mesh;

    #[test]
    fn unit_box_maps_to_a_perfect_grid() {
        let ctx = Context::parse("cube,0,0,0,0,0,0,0,0,0,0,0").unwrap();
        let input = HexInput {
            surface: box_mesh([-1.0; 3], [1.0; 3]),
            context: ctx,
            correspondence: vec![],
            to_user: Affine::similarity(0.5, [0.5; 3]),
        };
        let mut opts = HexOptions::default();
        opts.map.level = Some(1);
        let r = build_hex_mesh(&input, &opts, &mut crate::error::NoProgress).unwrap();
        assert!((r.stages[0].after.min - 1.0).abs() < 1e-12);
        assert!(r.quality.min >= r.stages[0].after.min);
    }
}
