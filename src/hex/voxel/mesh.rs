//! The hex mesh of one voxel lattice: its voxels as elements, the boundary nodes
//! fitted to the surface (those on the input's sharp features held there), or
//! for local refinement the lattice with some voxels split, then the quality
//! steps ([`crate::hex::quality::improve`]; with the feature sheets through
//! [`super::sheets`]).

use super::lattices::Lattice;
use super::local::Carved;
use crate::error::{check_progress, Error, Progress, Result};
use crate::geometry::vec3::{add, norm, scale, sub};
use crate::hex::fit::{fit_to_surface, relax_and_refit, FitStats};
use crate::hex::frames::Frames;
use crate::hex::grid::{boundary_faces_lattice, lattice_hex, normal_masks, LatticeHex};
use crate::hex::lattice::LatticePlanes;
use crate::hex::quality::{improve, summary, MapStage};
use crate::hex::report::{HexResult, LevelReport, MapMethod, SurfaceMapReport};
use crate::hex::stages::{LatticeDetails, RefineStart, RefinementDetails, Revoxelised, ThinWall};
use crate::hex::surface::Surface;
use crate::hex::work::{boundary_graph, Level, Role, Work};
use crate::hex::{topology, HexMesh, HexOptions};
use std::time::Instant;

/// The hex mesh of one lattice, or with `refine` of the lattice with the voxels in
/// those boxes split (local refinement): boundary nodes onto the surface, then
/// the usual quality steps ([`improve`]).
pub(super) fn mesh_lattice(
    Lattice { vol, planes, filled, thin_wall }: Lattice,
    res: usize,
    refine: Option<(&[([u32; 3], [u32; 3])], Start)>,
    fr: &Frames,
    opts: &HexOptions,
    t_all: Instant,
    progress: &mut dyn Progress,
) -> Result<HexResult> {
    let sw = &fr.sw;
    check_progress(progress, 0.2, "hex: voxel mapping")?;
    let t0 = Instant::now();
    let h = lattice_hex(&vol.grid, 0);
    // lattice coordinates -> the voxel lattice's corners in W
    let pos: Vec<[f64; 3]> = h.node_lattice.iter().map(|c| planes.to_world(c.map(|x| x as f64))).collect();
    let masks = normal_masks(&h);
    let role: Vec<Role> = masks.iter().map(|&m| if m != 0 { Role::Free } else { Role::Interior }).collect();
    let bquads: Vec<[u32; 4]> = boundary_faces_lattice(&h).into_iter().map(|(q, _)| q).collect();
    let coarse = HexMesh { nodes: pos, elements: h.mesh.elements.clone() };
    // the lattice fitted to the surface (not needed when a refined lattice starts
    // on the lattice; the same for every round of local refinement, so cached)
    let sizes: Vec<[f64; 3]> = h.elem_lattice.iter().map(|&c| planes.voxel_size(c)).collect();
    let fit = || fitted_work(coarse, role, &bquads, sizes, sw, opts);
    let (fitted, refine) = match refine {
        None => (Some(fit()), None),
        Some((boxes, Start::Fitted(cache))) => (Some(cache.get_or_insert_with(fit).clone()), Some((boxes, None))),
        Some((boxes, Start::Lattice)) => (None, Some((boxes, None))),
        Some((boxes, Start::Revoxelised(c))) => (None, Some((boxes, Some(c)))),
    };
    let (h, work, fit_stats, bquads, targets, refined) = match refine {
        Some((boxes, carved)) => refined_lattice(h, boxes, carved, fitted, &planes, sw, opts)?,
        None => {
            let (work, fit_stats) = fitted.expect("fitted above");
            let targets = work.target.clone();
            (h, work, fit_stats, bquads, targets, None)
        }
    };
    // boundary nodes held on the input's sharp features from the start (hold_features)
    let held = work.role.iter().filter(|r| matches!(r, Role::Corner(_) | Role::Curve(_))).count();
    let n = work.mesh.nodes.len();
    let inverted = summary(&work.mesh).inverted;
    let ne = work.mesh.elements.len();
    let levels = vec![LevelReport {
        level: 0,
        nodes: n,
        elements: ne,
        deviation: None,
        flipped_quads: 0,
        inverted,
        seconds: t0.elapsed().as_secs_f64(),
    }];
    let smap = SurfaceMapReport {
        method: MapMethod::Lattice,
        feature_curves: sw.features.curves.len(),
        feature_corners: sw.features.corners.len(),
        ..Default::default()
    };
    let lv = Level { h, pos: work.mesh.nodes, attach: work.attach, role: work.role, curve_nb: work.curve_nb, bquads, released_corners: Vec::new() };
    let lattice = LatticeDetails {
        voxel_resolution: res,
        voxel_size: vol.h / fr.sw_scale,
        voxels_filled_for_manifold: filled,
        feature_nodes_held: held,
        local_refinement: refined,
        // the lattice planes moved onto the input's faces, per axis (FallbackOptions::lattice_planes)
        planes_on_faces: (!planes.is_uniform()).then(|| planes.aligned.iter().map(Vec::len).collect()),
        // the lattice was repaired for a porous thin wall (topology_lattice)
        voxels_added_for_thin_walls: thin_wall.map(|(voxels, min_solid_fraction)| ThinWall { voxels, min_solid_fraction }),
        feature_sheets: None,
        resolutions_tried: None,
        lattices_meshed: None,
        revoxelisation_skipped: None,
    };
    let stage = MapStage { surface_map: smap, levels, fit: fit_stats, lattice: Some(lattice) };
    if opts.quality.feature_sheets && !sw.features.curves.is_empty() && held == 0 {
        super::sheets::with_sheets(lv, targets, stage, fr, opts, t_all, progress)
    } else {
        improve(lv, targets, stage, fr, opts, t_all, progress)
    }
}

/// A lattice mesh's working state, its fit's statistics, its boundary quads and
/// its elements' target boxes, and for local refinement what was refined.
type Fitted = (LatticeHex, Work, Vec<FitStats>, Vec<[u32; 4]>, Vec<[f64; 3]>, Option<RefinementDetails>);

/// Local refinement: the lattice `h` with the voxels in `boxes` split (or the
/// re-voxelised split voxels `carved`), started from the lattice, or from the
/// fitted coarse mesh (`fitted`: `Start::Fitted`), each new node where its
/// cell's trilinear map of the fitted corners puts it, so its boundary nodes
/// have only the rest of the way to go; then fitted to the surface.
fn refined_lattice(
    mut h: LatticeHex,
    boxes: &[([u32; 3], [u32; 3])],
    carved: Option<Carved>,
    fitted: Option<CoarseFit>,
    planes: &LatticePlanes,
    sw: &Surface,
    opts: &HexOptions,
) -> Result<Fitted> {
    let start = if carved.is_some() { RefineStart::Revoxelised } else if fitted.is_some() { RefineStart::FittedCoarseMesh } else { RefineStart::Lattice };
    let (r, revoxelised) = match carved {
        Some(c) => {
            let j = Revoxelised { empty_voxels_split: c.empty_split, fine_voxels_removed: c.fine_removed, fine_voxels_filled: c.fine_filled };
            (c.refined, Some(j))
        }
        None => (crate::hex::refine::refine_boxes(&h.node_lattice, &h.mesh.elements, boxes), None),
    };
    let refined = RefinementDetails { boxes: boxes.to_vec(), elements_split: r.split, transition_elements: r.transitions, start, revoxelised };
    let (start, mut fit_stats) = match fitted {
        Some((coarse_fit, fit_stats)) => {
            let from_fit = crate::hex::refine::interpolate_new_nodes(&r, &h.node_lattice, &h.mesh.elements, &h.elem_lattice, &coarse_fit.mesh.nodes)
                .map_err(|e| Error::Internal(format!("local refinement: {e}")))?;
            (from_fit, fit_stats)
        }
        None => (r.nodes.iter().map(|&x| planes.to_world(x)).collect(), Vec::new()),
    };
    // target boxes: each element's shape on the lattice
    let targets: Vec<[f64; 3]> = r
        .elements
        .iter()
        .map(|el| {
            let d = |k: usize| norm(sub(planes.to_world(r.nodes[el[k] as usize]), planes.to_world(r.nodes[el[0] as usize])));
            [d(1), d(3), d(4)]
        })
        .collect();
    let mesh = HexMesh { nodes: r.nodes, elements: r.elements };
    let bquads: Vec<[u32; 4]> = topology::boundary_quads(&mesh).map_err(|e| Error::Internal(format!("local refinement: {e}")))?.into_iter().map(|q| q.nodes).collect();
    let mut role = vec![Role::Interior; mesh.nodes.len()];
    for &v in bquads.iter().flatten() {
        role[v as usize] = Role::Free;
    }
    let (work, f) = fitted_work(HexMesh { nodes: start, elements: mesh.elements.clone() }, role, &bquads, targets.clone(), sw, opts);
    fit_stats.extend(f);
    h.mesh = mesh;
    Ok((h, work, fit_stats, bquads, targets, Some(refined)))
}

/// A lattice mesh's working state with its boundary nodes fitted to the surface
/// (fit, relax, refit), and the fit's statistics.
pub(super) fn fitted_work(mesh: HexMesh, role: Vec<Role>, bquads: &[[u32; 4]], target: Vec<[f64; 3]>, sw: &Surface, opts: &HexOptions) -> (Work, Vec<FitStats>) {
    let n = mesh.nodes.len();
    let e = topology::edges(&mesh);
    let mut work = Work {
        nbr: topology::node_neighbours(n, &e),
        n2e: topology::node_elements(&mesh),
        mesh,
        role,
        attach: vec![u32::MAX; n],
        curve_nb: vec![Vec::new(); n],
        bgraph: boundary_graph(n, bquads),
        target,
    };
    hold_features(&mut work, sw, bquads);
    let mut fit_stats = vec![fit_to_surface(&mut work, sw, bquads, opts.surface.relax_iterations, 0.2)];
    relax_and_refit(&mut work, sw, bquads, opts.surface.relax_iterations, &mut fit_stats);
    (work, fit_stats)
}

/// Boundary nodes that lie on the input's sharp features before the fit (an input
/// whose faces fall on lattice planes, like the square torus at 24 voxels) are held
/// there: a node at a feature corner becomes a corner node, a node on a feature
/// curve a curve node that slides along it, its neighbours along the curve those of
/// its boundary neighbours on the same curve (or at a corner) whose edge to it lies
/// on the curve. Without it the fit's tangential spreading pulls them off and
/// rounds the edges the lattice had exactly (the square torus at 24 voxels: corners
/// 1.2 voxels off after the fit, 1.20 % from the input in the end). Only when
/// every feature corner has a node on it (the input's features all on the
/// lattice); "on" is within 1e-9 of the working frame's size 2. The held nodes are
/// those whose role is a corner or a curve.
fn hold_features(w: &mut Work, sw: &Surface, bquads: &[[u32; 4]]) {
    const ON: f64 = 1e-9;
    let corners: Vec<([f64; 3], u32)> = sw.features.corners.iter().map(|&c| (sw.mesh.vertices[c as usize], c)).collect();
    let curves: Vec<(usize, crate::geometry::bvh::Aabb)> = (0..sw.features.curves.len())
        .map(|c| {
            let b = (0..sw.curve_segments(c)).fold(crate::geometry::bvh::Aabb::EMPTY, |b, s| {
                let (p, q) = sw.curve_segment(c, s);
                b.grow(p).grow(q)
            });
            (c, b)
        })
        .collect();
    let bnodes: std::collections::BTreeSet<u32> = bquads.iter().flatten().copied().collect();
    // only when every feature corner has a node on it: where some do not (the
    // corners where cinolib_cube_minus_sphere's sphere cuts the cube's edges), nodes
    // held on the rest of the curves cannot follow them there (30 voxels: 0.87 ->
    // 1.22 %), and the capture steps do better
    if !corners.iter().all(|(p, _)| bnodes.iter().any(|&v| w.role[v as usize] == Role::Free && norm(sub(w.mesh.nodes[v as usize], *p)) <= ON)) {
        return;
    }
    let on_curve = |x: [f64; 3]| -> Vec<usize> { curves.iter().filter(|(_, b)| b.dist2(x) <= ON * ON).map(|&(c, _)| c).filter(|&c| sw.closest_on_curve(c, x).distance <= ON).collect() };
    for &v in &bnodes {
        let v = v as usize;
        if w.role[v] != Role::Free {
            continue;
        }
        let x = w.mesh.nodes[v];
        if let Some(&(_, c)) = corners.iter().find(|(p, _)| norm(sub(*p, x)) <= ON) {
            w.role[v] = Role::Corner(c);
            continue;
        }
        if let [c] = on_curve(x)[..] {
            w.role[v] = Role::Curve(c as u32);
        }
    }
    for &v in &bnodes {
        let v = v as usize;
        let Role::Curve(c) = w.role[v] else { continue };
        let x = w.mesh.nodes[v];
        let nb: Vec<u32> = w
            .bgraph
            .of(v)
            .iter()
            .copied()
            .filter(|&u| matches!(w.role[u as usize], Role::Corner(_)) || w.role[u as usize] == Role::Curve(c))
            .filter(|&u| sw.closest_on_curve(c as usize, scale(add(x, w.mesh.nodes[u as usize]), 0.5)).distance <= ON)
            .collect();
        w.curve_nb[v] = nb;
        w.attach[v] = u32::MAX;
    }
}

/// A lattice fitted to the surface, with the fit's statistics ([`fitted_work`]).
pub(super) type CoarseFit = (Work, Vec<FitStats>);

/// Where a locally refined lattice's mesh starts.
pub(super) enum Start<'a> {
    /// Every node on the lattice.
    Lattice,
    /// The new nodes on the fitted coarse mesh, which the cache keeps for the
    /// next round.
    Fitted(&'a mut Option<CoarseFit>),
    /// The split voxels voxelised again ([`carve_refined`]), on the lattice.
    Revoxelised(Carved),
}
