//! The levels of the polycube map: the polycube's lattice mesh at level 0, 1, ...
//! mapped onto the input (steps 2-4 of [`super`]), each level prolonged from the
//! one before, until the stopping rule picks one.

use super::charts::{segment_and_map, ChartInverse, ChartOptions};
use super::correspondence::Correspondence;
use super::features::{match_features, match_placed_features, roles, FeatureMatch};
use super::warp::{fit_warp, Warp, WarpReport};
use super::HexInput;
use crate::context::context_frame;
use crate::error::{check_progress, Progress, Result};
use crate::geometry::vec3::*;
use crate::geometry::VoxelGrid;
use crate::hex::fit::{fit_to_surface, flipped_quads, harmonic_interior, relax_and_refit, FitStats};
use crate::hex::frame::Affine;
use crate::hex::frames::Frames;
use crate::hex::grid::{boundary_faces_lattice, lattice_hex, prolong, LatticeHex};
use crate::hex::quality::summary;
use crate::hex::quality::untangle::untangle;
use crate::hex::report::{LevelReport, MapMethod, SurfaceMapReport};
use crate::hex::surface::Surface;
use crate::hex::work::{boundary_graph, quad_normals, Level, Role, Work};
use crate::hex::{topology, HexMesh, HexOptions, SurfaceMap};
use crate::mesh::TriMesh;
use crate::polycube::assembly::occupied_cell_box;
use crate::polycube::tensor::BoxFrame;
use rayon::prelude::*;
use std::time::Instant;

/// The chosen level of the map and what the report says about the map.
pub(super) struct Mapped {
    pub level: Level,
    /// Target boxes of the level's elements ([`element_targets`]).
    pub targets: Vec<[f64; 3]>,
    pub surface_map: SurfaceMapReport,
    pub levels: Vec<LevelReport>,
    /// The fit statistics of every fit on the way.
    pub fit: Vec<FitStats>,
    /// How the level's nodes were placed, for nodes added later ([`super::local`]).
    pub placer: Placer,
}

/// What places a node of the polycube's domain on the input as the levels'
/// nodes were placed: the polycube's frame, the start embedding (fitted planes)
/// and the working frame, and the inverse chart maps when they are the surface map.
#[derive(Clone)]
pub(super) struct Placer {
    pub frame: BoxFrame,
    pub warp: Warp,
    pub to_w: Affine,
    pub charts: Option<ChartInverse>,
}

impl Placer {
    /// The start embedding of a domain point `g` (grid units) in the working frame.
    pub fn embed(&self, g: [f64; 3]) -> [f64; 3] {
        self.to_w.apply(self.warp.apply(g))
    }
}

/// What every level is mapped from: the polycube's frame and start embedding,
/// the feature match and the correspondence seed, in the working frame `to_w`.
struct Start<'a> {
    frame: BoxFrame,
    warp: Warp,
    to_w: Affine,
    corr: Option<Correspondence>,
    fm: FeatureMatch,
    sw: &'a Surface,
    relax_iterations: usize,
    /// The inverse chart maps, when they are the surface map.
    charts: Option<ChartInverse>,
}

/// Map the levels of `input`'s polycube onto its surface (`mesh_n`: the surface in
/// the caller's frame, outward oriented; `fr`: the working frames) and choose one
/// by the stopping rule (docs/hex.md "Levels").
pub(super) fn map_levels(input: &HexInput, mesh_n: TriMesh, fr: &Frames, opts: &HexOptions, progress: &mut dyn Progress) -> Result<Mapped> {
    let grid = input.context.assemble();
    let (mut start, warp_report) = start(input, mesh_n, &grid, fr, opts);
    let why = if matches!(opts.map.surface_map, SurfaceMap::Charts | SurfaceMap::Best) {
        match chart_inverse(input) {
            Ok(ci) => {
                start.charts = Some(ci);
                start.fm = chart_feature_match(&grid, &start, fr);
                None
            }
            Err(why) => Some(why),
        }
    } else {
        None
    };
    let smap = SurfaceMapReport {
        method: if start.charts.is_some() { MapMethod::Charts } else { MapMethod::Projection },
        why,
        feature_curves: fr.sw.features.curves.len(),
        feature_corners: fr.sw.features.corners.len(),
        matched_corners: start.fm.corners.len(),
        matched_chains: start.fm.chains.len(),
        correspondence_pairs: start.corr.as_ref().map(|_| input.correspondence.len()).unwrap_or(0),
        planes_fitted: warp_report.planes_fitted,
        max_plane_shift: warp_report.max_shift,
        flipped_quads: 0,
        tried: Vec::new(),
    };
    let max_level = opts.map.level.unwrap_or(opts.map.max_level);
    let min_level = opts.map.level.unwrap_or(opts.map.min_level.min(max_level));
    let mut levels: Vec<LevelReport> = Vec::new();
    let mut fit_stats: Vec<FitStats> = Vec::new();
    let mut prev: Option<Level> = None;
    let mut chosen: Option<Level> = None;
    for l in 0..=max_level {
        let t0 = Instant::now();
        check_progress(progress, 0.05 + 0.45 * l as f64 / (max_level + 1) as f64, &format!("hex: mapping level {l}"))?;
        let (cur, interp) = map_level(&grid, l, prev.as_ref(), &start, &mut fit_stats);
        let rep = LevelReport {
            level: l,
            nodes: cur.pos.len(),
            elements: cur.h.mesh.elements.len(),
            deviation: None,
            flipped_quads: flipped_quads(start.sw, &cur.pos, &cur.bquads),
            inverted: summary(&HexMesh { nodes: cur.pos.clone(), elements: cur.h.mesh.elements.clone() }).inverted,
            seconds: t0.elapsed().as_secs_f64(),
        };
        // the stopping rule for the previous level
        if let (Some(pv), Some(interp)) = (prev.as_ref(), interp.as_ref()) {
            let stop = stopping_rule(pv, &cur, interp, &rep, &mut levels, fr, opts);
            if opts.map.level.is_none() && pv.h.level >= min_level && stop {
                levels.push(rep);
                chosen = prev.take();
                break;
            }
        }
        levels.push(rep);
        let next_elements = cur.h.mesh.elements.len() * 8;
        let last = l == max_level || (opts.map.level.is_none() && l >= min_level && next_elements > opts.max_elements);
        if last {
            chosen = Some(cur);
            break;
        }
        prev = Some(cur);
    }
    let level = chosen.expect("a level is chosen");
    let targets = element_targets(&level.h, &start.warp, &start.to_w);
    let placer = Placer { frame: start.frame, warp: start.warp, to_w: start.to_w, charts: start.charts };
    Ok(Mapped { level, targets, surface_map: smap, levels, fit: fit_stats, placer })
}

/// The frame, the start embedding (the polycube's sub-voxel planes fitted to the
/// input, or the uniform lattice when the correspondence seeds the map) and the
/// feature match every level is mapped from.
fn start<'a>(input: &HexInput, mesh_n: TriMesh, grid: &VoxelGrid, fr: &'a Frames, opts: &HexOptions) -> (Start<'a>, WarpReport) {
    let frame: BoxFrame = context_frame(&input.context).expect("valid context has cells");
    // the surface in the caller's (normalised) frame, with the same features, for
    // the polycube's plane fit and feature matching
    let sn = Surface::new(mesh_n, fr.sw.features.clone());
    let corr = if opts.map.use_correspondence { Correspondence::new(&input.correspondence) } else { None };
    let (warp, warp_report) = if opts.map.fit_planes && corr.is_none() {
        let h0 = lattice_hex(grid, 0);
        let cells = occupied_cell_box(&input.context.labels).expect("occupied");
        fit_warp(&h0, &frame, cells, &sn)
    } else {
        (Warp::uniform(&frame), WarpReport::default())
    };
    // features are matched on level 1, where every polycube edge has an inner node
    let h1 = lattice_hex(grid, 1);
    let pos_n1: Vec<[f64; 3]> = h1.mesh.nodes.iter().map(|&g| warp.apply(g)).collect();
    let radius = 0.5 * frame.scale / 3.0;
    let fm: FeatureMatch = match_features(&h1, &pos_n1, &sn, radius);
    drop(h1);
    let start = Start { frame, warp, to_w: fr.to_w, corr, fm, sw: &fr.sw, relax_iterations: opts.surface.relax_iterations, charts: None };
    (start, warp_report)
}

/// Level `l` of the map: level 0 from the start embedding, a later one prolonged
/// from the level before (`prev`). Also returns the prolonged positions (None on
/// level 0), which the stopping rule measures.
fn map_level(grid: &VoxelGrid, l: u32, prev: Option<&Level>, s: &Start, fit_stats: &mut Vec<FitStats>) -> (Level, Option<Vec<[f64; 3]>>) {
    let sw = s.sw;
    let h = lattice_hex(grid, l);
    let (role, curve_nb) = roles(&h, &s.fm);
    let bquads: Vec<[u32; 4]> = boundary_faces_lattice(&h).into_iter().map(|(q, _)| q).collect();
    let bgraph = boundary_graph(h.mesh.nodes.len(), &bquads);
    let n = h.mesh.nodes.len();
    let mut work = Work {
        mesh: HexMesh { nodes: Vec::new(), elements: h.mesh.elements.clone() },
        role: role.clone(),
        attach: vec![u32::MAX; n],
        curve_nb: curve_nb.clone(),
        bgraph,
        nbr: Default::default(),
        n2e: Default::default(),
        target: element_targets(&h, &s.warp, &s.to_w),
    };
    let e = topology::edges(&h.mesh);
    work.nbr = topology::node_neighbours(n, &e);
    work.n2e = topology::node_elements(&h.mesh);
    if let Some(ci) = s.charts.as_ref() {
        let interp = prev.map(|pv| prolong(&pv.h, &pv.pos, &h));
        chart_start(&mut work, &h, ci, s, interp.as_deref());
        let level = Level { h, pos: work.mesh.nodes, attach: work.attach, role, curve_nb, bquads, released_corners: Vec::new() };
        return (level, interp);
    }
    let interp = match prev {
        None => {
            // the polycube itself (plus the correspondence seed) in the working frame
            work.mesh.nodes = h
                .mesh
                .nodes
                .iter()
                .map(|&g| match s.corr.as_ref() {
                    Some(c) => {
                        let u = s.frame.to_normalised(g);
                        s.to_w.apply(add(u, c.displacement(u, 8)))
                    }
                    None => s.to_w.apply(s.warp.apply(g)),
                })
                .collect();
            let f = fit_to_surface(&mut work, sw, &bquads, s.relax_iterations, 0.2);
            fit_stats.push(f);
            relax_and_refit(&mut work, sw, &bquads, s.relax_iterations, fit_stats);
            None
        }
        Some(pv) => {
            let interp = prolong(&pv.h, &pv.pos, &h);
            prolonged_start(&mut work, &interp, &bquads, sw);
            if l <= 1 {
                // the coarse levels define the surface map: fit and spread
                let f = fit_to_surface(&mut work, sw, &bquads, s.relax_iterations / 2, 0.2);
                fit_stats.push(f);
                relax_and_refit(&mut work, sw, &bquads, s.relax_iterations, fit_stats);
            } else {
                // finer levels inherit it: only the interior is evened out
                untangle(&mut work, sw, 3, |v| role[v] == Role::Interior);
            }
            Some(interp)
        }
    };
    let level = Level { h, pos: work.mesh.nodes, attach: work.attach, role, curve_nb, bquads, released_corners: Vec::new() };
    (level, interp)
}

/// The feature match under the chart maps: level 1 placed by them (every polycube
/// edge has an inner node there), its corners and chains matched to the feature
/// corners and curves they landed on, so that the quality steps keep those nodes
/// on the input's corners and sharp curves instead of sliding them off.
fn chart_feature_match(grid: &VoxelGrid, s: &Start, fr: &Frames) -> FeatureMatch {
    let (l1, _) = map_level(grid, 1, None, s, &mut Vec::new());
    match_placed_features(&l1.h, &l1.pos, s.sw, 1e-7 * fr.diag_w)
}

/// The segmentation and chart maps of `input`, inverted; Err says why they cannot
/// be the surface map (a chart that does not match its face, does not map or maps
/// with flipped triangles).
fn chart_inverse(input: &HexInput) -> std::result::Result<ChartInverse, String> {
    let charts = segment_and_map(input, &ChartOptions::default()).map_err(|e| e.to_string())?;
    ChartInverse::new(&input.surface, &charts)
}

/// A level mapped by the charts: every boundary node at the inverse chart map of
/// its point on the polycube (the closest surface point in the rare case that no
/// chart holds it), the interior by the harmonic map from the prolonged positions
/// `interp` (the warped lattice on level 0).
fn chart_start(work: &mut Work, h: &LatticeHex, ci: &ChartInverse, s: &Start, interp: Option<&[[f64; 3]]>) {
    let mut pos: Vec<[f64; 3]> = match interp {
        Some(p) => p.to_vec(),
        None => h.mesh.nodes.iter().map(|&g| s.to_w.apply(s.warp.apply(g))).collect(),
    };
    let (frame, to_w, sw, role) = (&s.frame, &s.to_w, s.sw, &work.role);
    let placed: Vec<Option<([f64; 3], u32)>> = h
        .mesh
        .nodes
        .par_iter()
        .enumerate()
        .map(|(v, &g)| {
            if !role[v].on_boundary() {
                return None;
            }
            Some(match ci.locate(frame.to_normalised(g)) {
                Some(l) => (to_w.apply(l.point), l.triangle),
                None => {
                    let (q, t, _) = sw.closest(pos[v]);
                    (q, t)
                }
            })
        })
        .collect();
    for (v, p) in placed.into_iter().enumerate() {
        if let Some((q, t)) = p {
            pos[v] = q;
            work.attach[v] = t;
        }
    }
    harmonic_interior(&work.nbr, &work.role, &mut pos, 1e-9, 5000);
    work.mesh.nodes = pos;
}

/// A finer level's start: its boundary nodes from the prolonged positions
/// `interp` onto their corner, curve or the surface, the interior the prolonged
/// positions or the harmonic map, whichever is better.
fn prolonged_start(work: &mut Work, interp: &[[f64; 3]], bquads: &[[u32; 4]], sw: &Surface) {
    let n = interp.len();
    let nrm = quad_normals(n, bquads, interp);
    let mut pos = interp.to_vec();
    for v in 0..n {
        match work.role[v] {
            Role::Interior => {}
            Role::Corner(c) => pos[v] = sw.mesh.vertices[c as usize],
            Role::Curve(c) => pos[v] = sw.closest_on_curve(c as usize, interp[v]).point,
            Role::Free => {
                let (q, t, _) = sw.closest_facing(interp[v], nrm[v], 0.0);
                pos[v] = q;
                work.attach[v] = t;
            }
        }
    }
    // interior: the prolonged positions or the harmonic map, whichever is better
    let mut harm = pos.clone();
    harmonic_interior(&work.nbr, &work.role, &mut harm, 1e-9, 5000);
    work.mesh.nodes = pos;
    let q_pro = summary(&work.mesh);
    let keep = std::mem::replace(&mut work.mesh.nodes, harm);
    let q_harm = summary(&work.mesh);
    if (q_pro.inverted, -q_pro.min) < (q_harm.inverted, -q_harm.min) {
        work.mesh.nodes = keep;
    }
}

/// The stopping rule's measure of the previous level `pv` (recorded in the last
/// entry of `levels`) from the current level `cur` and its prolonged positions,
/// and whether it says to stop at `pv`: the chord height is within the
/// threshold, it no longer shrinks, or the finer level folds the map.
fn stopping_rule(pv: &Level, cur: &Level, interp: &[[f64; 3]], rep: &LevelReport, levels: &mut [LevelReport], fr: &Frames, opts: &HexOptions) -> bool {
    // chord height: how far the linearly interpolated boundary midpoints are from
    // the surface their mapped counterparts lie on
    let dev: f64 = cur
        .h
        .node_lattice
        .par_iter()
        .enumerate()
        .filter(|(v, lat)| cur.role[*v].on_boundary() && lat.iter().any(|c| c % 2 == 1))
        .map(|(v, _)| fr.sw.closest(interp[v]).2)
        .reduce(|| 0.0, f64::max);
    let dev = dev / fr.diag_w;
    let k = levels.len() - 1;
    levels[k].deviation = Some(dev);
    // a measure that no longer shrinks means refining does not resolve what is
    // left (sharp features no polycube edge follows): stop there as well
    let stalled = k >= 1 && levels[k - 1].deviation.is_some_and(|d0| dev > opts.map.stall_ratio * d0);
    // refining must not fold the map: a finer level whose share of flipped
    // boundary quads is above twice this one's plus 0.2 % is not taken
    let frac = |f: usize, q: usize| f as f64 / q.max(1) as f64;
    let folds = frac(rep.flipped_quads, cur.bquads.len()) > 2.0 * frac(levels[k].flipped_quads, pv.bquads.len()) + 0.002;
    dev <= opts.map.threshold || stalled || folds
}

/// Target boxes of the elements of a lattice mesh: their start shape (the warped
/// lattice) in the working frame, as edge lengths along the element axes.
fn element_targets(h: &LatticeHex, warp: &Warp, to_w: &Affine) -> Vec<[f64; 3]> {
    let col: [f64; 3] = std::array::from_fn(|a| (0..3).map(|i| to_w.m[i][a] * to_w.m[i][a]).sum::<f64>().sqrt());
    h.elem_lattice
        .iter()
        .map(|&c| {
            let ext = warp.element_extent(c, h.subdiv);
            std::array::from_fn(|a| (ext[a] * col[a]).max(1e-12))
        })
        .collect()
}
