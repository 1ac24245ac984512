//! The quality of a hex mesh ([`measure`]: the Verdict scaled Jacobian) and the
//! quality steps after the mapping, one per file, in their order:
//!
//! 1. pillowing ([`pillow`]): one layer of elements under the whole boundary;
//! 2. feature sheets ([`sheets`]; lattice meshes): a sheet under each surface
//!    patch, the paths between them onto the sharp curves;
//! 3. smoothing ([`untangle`]): the target mean-ratio energy of the corners;
//! 4. sharp-edge capture ([`capture`]);
//! 5. coverage ([`coverage`]): boundary nodes pinned to the input vertices the
//!    boundary misses;
//! 6. optimisation ([`jacobian`]): the max-min optimisation of the scaled
//!    Jacobian, its polish, the mean ascent of the interior ([`ascent`]) and the
//!    release of a folded boundary;
//! 7. recapture ([`capture`]): the capture again, re-optimised;
//! 8. boundary mean ascent ([`ascent`]).
//!
//! [`improve`] runs them on a mapped lattice mesh and returns the result in user
//! coordinates, never worse than the mapped mesh. [`step`] holds what the steps
//! share (their reports, the guard of the steps towards the input), [`smooth`]
//! and [`terms`] the node moves several of them use.

pub(crate) mod ascent;
pub(crate) mod capture;
pub(crate) mod coverage;
pub(crate) mod jacobian;
pub mod measure;
pub(crate) mod pillow;
pub(crate) mod sheets;
pub(crate) mod smooth;
pub(crate) mod step;
pub(crate) mod terms;
pub(crate) mod untangle;

pub use capture::CaptureStats;
pub use coverage::CoverStats;
pub use measure::*;
pub use pillow::PillowReport;
pub use sheets::SheetReport;

use crate::error::{check_progress, Progress, Result};
use crate::hex::distance::{hausdorff, Hausdorff};
use crate::hex::fit::{flipped_quads, FitStats};
use crate::hex::frames::Frames;
use crate::hex::report::{Domain, HexResult, LevelReport, Returned, SurfaceMapReport};
use crate::hex::stages::{LatticeDetails, MappingDetails, Stage, StageDetails, StageReport};
use crate::hex::topology::mesh_volume;
use crate::hex::work::{Level, Work};
use crate::hex::{HexMesh, HexOptions};
use std::time::Instant;

/// What the mapping hands to the quality steps besides the mapped mesh.
#[derive(Clone)]
pub(crate) struct MapStage {
    /// How the surface map was set up (its flipped quads are counted here).
    pub surface_map: SurfaceMapReport,
    /// The levels mapped (one for a voxel lattice).
    pub levels: Vec<LevelReport>,
    /// The fits that put the boundary on the surface.
    pub fit: Vec<FitStats>,
    /// The voxel lattice's details (None for the polycube map).
    pub lattice: Option<LatticeDetails>,
}

/// The quality steps and the result, from the mapped mesh `lv` (with its
/// elements' target boxes `targets`, in the working frame of `fr`): the steps of
/// the module docs in their order, the Hausdorff distance, and the mesh back in
/// user coordinates; the mapped mesh is returned instead when the steps end
/// below its minimum (`QualityOptions::keep_better_mapped`).
pub(crate) fn improve(lv: Level, targets: Vec<[f64; 3]>, map: MapStage, fr: &Frames, opts: &HexOptions, t_all: Instant, progress: &mut dyn Progress) -> Result<HexResult> {
    let sw = &fr.sw;
    let level = lv.h.level;
    let domain = match &map.lattice {
        Some(l) => Domain::Voxel { resolution: l.voxel_resolution },
        None => Domain::Polycube,
    };
    let MapStage { mut surface_map, levels, fit, lattice } = map;
    // ---- mapped mesh ----
    let mut work = Work {
        mesh: HexMesh { nodes: lv.pos.clone(), elements: lv.h.mesh.elements.clone() },
        role: lv.role.clone(),
        attach: lv.attach.clone(),
        curve_nb: lv.curve_nb.clone(),
        bgraph: Default::default(),
        nbr: Default::default(),
        n2e: Default::default(),
        target: targets,
    };
    work.rebuild();
    surface_map.flipped_quads = flipped_quads(sw, &work.mesh.nodes, &lv.bquads);
    let mapped = work.mesh.clone();
    let q_mapped = summary(&mapped);
    let mapping = MappingDetails { level, flipped_boundary_quads: surface_map.flipped_quads, fit, lattice };
    let mut stages = vec![StageReport {
        stage: Stage::Mapping,
        before: QualitySummary::default(),
        after: q_mapped,
        nodes: mapped.nodes.len(),
        elements: mapped.elements.len(),
        seconds: levels.iter().map(|l| l.seconds).sum(),
        details: StageDetails::Mapping(mapping),
    }];
    // ---- the steps ----
    let q = &opts.quality;
    if q.pillow {
        stages.push(pillow::pillowing(&mut work, q_mapped, progress)?);
    }
    let (sheets, smoothed) = sheets::sheets_step(&mut work, sw, &lv.released_corners, q, progress)?;
    stages.extend(sheets);
    check_progress(progress, 0.6, "hex: smoothing")?;
    stages.push(match smoothed {
        Some(st) => st,
        None => untangle::smoothing(&mut work, sw, q.smooth_iterations),
    });
    stages.extend(capture::capture(&mut work, sw, opts));
    stages.extend(coverage::coverage(&mut work, sw, opts));
    stages.push(jacobian::optimisation(&mut work, sw, fr.diag_w, q, progress)?);
    stages.extend(capture::recapture(&mut work, sw, opts, progress)?);
    stages.extend(ascent::boundary_ascent(&mut work, sw, opts, progress)?);
    let q_final = summary(&work.mesh);

    // ---- never worse than the mapped mesh ----
    let mut mapped_u = mapped.clone();
    to_user(&mut mapped_u, fr);
    let (mut out, returned) = if q_final.min >= q_mapped.min || !q.keep_better_mapped { (work.mesh, Returned::Optimised) } else { (mapped, Returned::Mapped) };
    check_progress(progress, 0.96, "hex: distances")?;
    let haus_w = hausdorff(&out, &sw.mesh, opts.hausdorff_samples);
    let s_inv = 1.0 / fr.sw_scale;
    let haus = Hausdorff {
        hex_to_surface: haus_w.hex_to_surface * s_inv,
        surface_to_hex: haus_w.surface_to_hex * s_inv,
        distance: haus_w.distance * s_inv,
        ..haus_w
    };
    to_user(&mut out, fr);
    let input_volume = sw.mesh.signed_volume() * s_inv.powi(3);
    let volume = mesh_volume(&out);
    let sj = element_qualities(&out);
    let quality = summarize(&sj);
    check_progress(progress, 1.0, "hex: done")?;
    Ok(HexResult {
        mesh: out,
        mapped: mapped_u,
        level,
        histogram: histogram(&sj, 20),
        scaled_jacobian: sj,
        quality,
        hausdorff: haus,
        hausdorff_relative: haus.relative,
        volume,
        input_volume,
        levels,
        surface_map,
        stages,
        returned,
        domain,
        seconds_total: t_all.elapsed().as_secs_f64(),
    })
}

/// A mesh of the working frame in user coordinates (mirrored back, its elements'
/// node order with it, when the working frame is mirrored).
fn to_user(m: &mut HexMesh, fr: &Frames) {
    for p in m.nodes.iter_mut() {
        *p = fr.w_to_u.apply(*p);
    }
    if fr.mirror {
        for e in m.elements.iter_mut() {
            *e = [e[4], e[5], e[6], e[7], e[0], e[1], e[2], e[3]];
        }
    }
}
