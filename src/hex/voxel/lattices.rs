//! The fallback's lattices: a voxel lattice with the input's topology at a
//! resolution ([`topology_lattice`]), and the search over resolutions that the
//! fallback runs ([`Search`]): the first lattice with the input's topology,
//! finer ones while the best mesh misses the goals, coarser ones while the best
//! meets them with room, and the kept lattice with its planes on the input's faces.

use super::composed::make_well_composed;
use super::mesh::mesh_lattice;
use super::VOXEL_MAX_RESOLUTION;
use crate::error::{Error, Progress, Result, SubProgress};
use crate::geometry::voxel::betti;
use crate::geometry::VoxelGrid;
use crate::hex::frames::Frames;
use crate::hex::lattice::LatticePlanes;
use crate::hex::report::HexResult;
use crate::hex::stages::LatticeMeshed;
use crate::hex::HexOptions;
use crate::mesh::TriMesh;
use std::time::Instant;

/// The fallback's search over lattices: what it tried, what it meshed, the best
/// mesh so far and its resolution.
pub(super) struct Search<'a> {
    pub fr: &'a Frames,
    pub opts: &'a HexOptions,
    /// The input's genus.
    pub genus: i64,
    pub t_all: Instant,
    /// Every topology check ([`topology_lattice`]), for report.json.
    pub tried: Vec<String>,
    /// Every lattice meshed, in order.
    pub meshed: Vec<LatticeMeshed>,
    pub best: HexResult,
    pub best_res: usize,
    /// The share of the progress range each mesh gets.
    pub share: f64,
}

/// The figures of a lattice's mesh for report.json's "lattices_meshed".
pub(super) fn meshed(resolution: usize, r: &HexResult) -> LatticeMeshed {
    LatticeMeshed {
        resolution,
        elements: r.quality.elements,
        min_scaled_jacobian: r.quality.min,
        mean_scaled_jacobian: r.quality.mean,
        hausdorff_relative: r.hausdorff_relative,
        planes_on_faces: None,
        local_refinement_start: None,
        local_refinement_starts: None,
    }
}

/// The first lattice: the coarsest from `opts.fallback.resolution` (doubling)
/// with the input's topology, and its resolution; MESHING_FAILED when none up to
/// [`VOXEL_MAX_RESOLUTION`] within `opts.max_elements` has it.
pub(super) fn first_lattice(fr: &Frames, genus: i64, opts: &HexOptions, tried: &mut Vec<String>) -> Result<(Lattice, usize)> {
    let mut res = opts.fallback.resolution.clamp(2, VOXEL_MAX_RESOLUTION);
    loop {
        let (lattice, fits) = topology_lattice(&fr.sw.mesh, res, None, genus, opts, tried)?;
        if let Some(l) = lattice {
            return Ok((l, res));
        }
        if res >= VOXEL_MAX_RESOLUTION || !fits {
            return Err(Error::MeshingFailed(format!(
                "voxel meshing: no lattice of at most {VOXEL_MAX_RESOLUTION} voxels along the longest edge and {} elements has the input's topology (1 component, no cavity, genus {genus}); tried {}",
                opts.max_elements,
                tried.join("; ")
            )));
        }
        res = (res * 2).min(VOXEL_MAX_RESOLUTION);
    }
}

impl Search<'_> {
    /// Mesh `lattice` at `res` within the progress range `lo..hi` and record it.
    fn mesh(&mut self, lattice: Lattice, res: usize, progress: &mut dyn Progress, lo: f64, hi: f64) -> Result<HexResult> {
        let mut sub = SubProgress { inner: progress, lo, hi };
        let r = mesh_lattice(lattice, res, None, self.fr, self.opts, self.t_all, &mut sub)?;
        self.meshed.push(meshed(res, &r));
        Ok(r)
    }

    /// While the best mesh misses the goals, up to `opts.fallback.refinements`
    /// finer lattices, each finer by the ratio of the measured Hausdorff distance
    /// to its goal (1.25x to 2x), within `opts.max_elements`, as long as each
    /// ranks better than the best before by [`crate::hex::QualityGoals::rank`] (one
    /// that ranks worse and misses the distance goal too gets one more lattice:
    /// 1.5x finer than it when it folded, twice the best's resolution when it was
    /// valid; [`next_resolution`]).
    pub fn refine(&mut self, progress: &mut dyn Progress) -> Result<()> {
        let opts = self.opts;
        // the lattice the next step starts from: the best so far, or the finer one that
        // ranked worse while missing the distance goal too (folded or farther)
        let mut last = LastLattice::Best { res: self.best_res, hausdorff: self.best.hausdorff_relative };
        for k in 1..=opts.fallback.refinements {
            if opts.goals.missed(&self.best) == 0 || last.res() >= VOXEL_MAX_RESOLUTION {
                break;
            }
            let mut next = next_resolution(last, self.best_res, opts.goals.hausdorff).min(VOXEL_MAX_RESOLUTION);
            // a finer lattice can cut a thin wall the coarser one kept (trimesh_round:
            // genus 1 at 96 voxels, not at 120): try further 1.25x steps within the budget
            let lattice = loop {
                let (lattice, fits) = topology_lattice(&self.fr.sw.mesh, next, None, self.genus, opts, &mut self.tried)?;
                if lattice.is_some() || !fits || next >= VOXEL_MAX_RESOLUTION {
                    break lattice;
                }
                next = ((next as f64 * 1.25).ceil() as usize).min(VOXEL_MAX_RESOLUTION);
            };
            let Some(lattice) = lattice else { break };
            let r = self.mesh(lattice, next, progress, self.share * k as f64, self.share * (k + 1) as f64)?;
            if !opts.goals.beats(&r, Some(&self.best)) {
                // finer ranked worse. When it misses the distance goal as well, one more
                // lattice: after one that folded, a wall thinner than its voxels is
                // still cut (cgal_spool's lip, 0.011-0.026 thick: a quarter of a
                // 24-voxel lattice's voxel, half of a 48's, whose mesh folds there; 72
                // voxels meet every goal); after a valid one that came out farther, the
                // distance was not monotone ([`next_resolution`]). Otherwise, or after a
                // second worse one, stop: a still finer lattice costs 2-8x more and is
                // no surer to help.
                if !matches!(last, LastLattice::Best { .. }) || !(r.hausdorff_relative > opts.goals.hausdorff) {
                    break;
                }
                let folded = r.quality.inverted > 0 || !(r.quality.min >= opts.goals.min_scaled_jacobian);
                last = if folded { LastLattice::Folded { res: next } } else { LastLattice::Farther { res: next } };
                continue;
            }
            last = LastLattice::Best { res: next, hausdorff: r.hausdorff_relative };
            self.best = r;
            self.best_res = next;
        }
        Ok(())
    }

    /// The steps of [`Search::refine`] overshoot where the distance falls faster than the voxel size
    /// (rockerarm at 24 / 32 / 36 / 40 / 42 / 48 voxels: 1.83 / 1.24 / 1.11 / 0.79 /
    /// 0.75 / 0.82 %): when the kept lattice meets every goal with its distance
    /// below the goal by 5 % or more and a coarser lattice missed the distance goal,
    /// the resolution where the distance would be 95 % of the goal is predicted
    /// from the two (a power law through both points) and, when it is at least 10 %
    /// coarser, meshed and kept if it meets every goal too (fewer elements). Repeated
    /// from the lattice kept (up to COARSER_STEPS times): a predicted lattice that
    /// meets every goal with room again is followed by a still coarser one, one
    /// that misses the distance goal narrows the next prediction from below; one
    /// that misses a scaled-Jacobian goal ends the search.
    pub fn coarser(&mut self, progress: &mut dyn Progress) -> Result<()> {
        let opts = self.opts;
        let goal = opts.goals.hausdorff;
        for _ in 0..COARSER_STEPS {
            let (best, best_res) = (&self.best, self.best_res);
            let below = self.meshed.iter().filter(|m| m.resolution < best_res && m.hausdorff_relative > goal).max_by_key(|m| m.resolution).cloned();
            let Some(b) = below.filter(|_| opts.goals.missed(best) == 0 && best.hausdorff_relative < 0.95 * goal && best.hausdorff_relative > 0.0) else { break };
            let slope = (b.hausdorff_relative / best.hausdorff_relative).ln() / (best_res as f64 / b.resolution as f64).ln();
            let predicted = (best_res as f64 * (best.hausdorff_relative / (0.95 * goal)).powf(1.0 / slope)).ceil() as usize;
            if !(slope.is_finite() && slope > 0.0 && predicted > b.resolution && predicted * 10 <= best_res * 9) || self.meshed.iter().any(|m| m.resolution == predicted) {
                break;
            }
            let (lattice, _) = topology_lattice(&self.fr.sw.mesh, predicted, None, self.genus, opts, &mut self.tried)?;
            let Some(lattice) = lattice else { break };
            let r = self.mesh(lattice, predicted, progress, 1.0 - self.share, 1.0)?;
            if opts.goals.missed(&r) == 0 {
                self.best = r;
                self.best_res = predicted;
            } else if opts.goals.misses_scaled_jacobian(&r) {
                break;
            }
        }
        Ok(())
    }

    /// The kept lattice again with its planes moved onto the input's large
    /// axis-parallel faces (`FallbackOptions::lattice_planes`), kept when it
    /// ranks better. Returns the planes of the kept lattice (None: uniform).
    pub fn planes_on_faces(&mut self, progress: &mut dyn Progress) -> Result<Option<LatticePlanes>> {
        let mut best_planes = None;
        let on_faces = LatticePlanes::aligned(&self.fr.sw.mesh, self.best_res, self.opts.fallback.lattice_planes)?;
        if !on_faces.is_uniform() {
            let (lattice, _) = topology_lattice(&self.fr.sw.mesh, self.best_res, Some(on_faces.clone()), self.genus, self.opts, &mut self.tried)?;
            if let Some(lattice) = lattice {
                let r = self.mesh(lattice, self.best_res, progress, 1.0 - self.share, 1.0)?;
                if let Some(m) = self.meshed.last_mut() {
                    m.planes_on_faces = Some(true);
                }
                if self.opts.goals.beats(&r, Some(&self.best)) {
                    self.best = r;
                    best_planes = Some(on_faces);
                }
            }
        }
        Ok(best_planes)
    }
}

/// How many coarser lattices the fallback tries after one that meets every goal
/// with room (hexgen_rod: 48 voxels at 0.66 %, then 38 at 0.63 %, then 33 at 0.75 %).
pub(super) const COARSER_STEPS: usize = 3;

/// The fallback's last lattice, which the next resolution is chosen from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum LastLattice {
    /// The best mesh so far, at this distance from the input.
    Best { res: usize, hausdorff: f64 },
    /// Finer than the best, ranked worse and folded (inverted elements or a
    /// minimum below the goal): it still cuts a feature thinner than its voxels.
    Folded { res: usize },
    /// Finer than the best, ranked worse, valid but farther from the input.
    Farther { res: usize },
}

impl LastLattice {
    pub(super) fn res(self) -> usize {
        match self {
            LastLattice::Best { res, .. } | LastLattice::Folded { res } | LastLattice::Farther { res } => res,
        }
    }
}

/// The next, finer resolution of the fallback's refinement (before the topology
/// check and the cap at [`VOXEL_MAX_RESOLUTION`]), from the last lattice, the best
/// lattice's resolution and the distance goal.
pub(super) fn next_resolution(last: LastLattice, best_res: usize, goal: f64) -> usize {
    match last {
        LastLattice::Best { res, hausdorff } => {
            // Hausdorff falls about linearly with the voxel size (measured: 24 -> 48
            // halves it on rod, pinion, rockerarm, bust, hepta), so aim a tenth below the goal
            let ratio = 1.1 * hausdorff / goal; // NaN for a NaN goal or distance
            let factor = if ratio.is_nan() { 2.0 } else { ratio.clamp(1.25, 2.0) };
            (res as f64 * factor).ceil() as usize
        }
        // a smaller step than the distance would ask for (cgal_spool: 24 voxels cut
        // a thin lip, 48 fold on it, 72 meet every goal)
        LastLattice::Folded { res } => (res as f64 * 1.5).ceil() as usize,
        // the distance is not monotone in the resolution (hepta with the sharp-edge
        // capture: 1.33 % at 24 voxels, 1.67 % at 36, 0.72 % at 48): the largest
        // step from the best, or 1.25x past the farther lattice
        LastLattice::Farther { res } => (best_res * 2).max((res as f64 * 1.25).ceil() as usize),
    }
}

/// A lattice with the input's topology: its voxels, how many were filled to make it
/// well-composed, and, when a porous thin wall was repaired, how many voxels were
/// added and the least solid fraction they have.
#[derive(Clone)]
pub(super) struct Lattice {
    /// The voxels on the uniform lattice `vol.lo + i * vol.h` of the warped surface
    /// (the surface itself when `planes` is uniform).
    pub vol: crate::geometry::voxel::VoxelVolume,
    pub planes: LatticePlanes,
    pub filled: usize,
    pub thin_wall: Option<(usize, f32)>,
}

/// A voxel lattice of the working-frame surface at `res` voxels along the longest
/// edge, made well-composed: Some when it has the input's topology within the
/// element budget. The bool says whether a finer lattice could still fit the budget.
/// `planes`: the lattice's planes (None: the uniform lattice of `res`).
pub(super) fn topology_lattice(mesh: &TriMesh, res: usize, planes: Option<LatticePlanes>, genus: i64, opts: &HexOptions, tried: &mut Vec<String>) -> Result<(Option<Lattice>, bool)> {
    let planes = match planes {
        Some(p) => p,
        None => LatticePlanes::uniform(mesh, res)?,
    };
    let lm = planes.warped(mesh);
    let label = if planes.is_uniform() { res.to_string() } else { format!("{res} (planes on faces)") };
    let mut vol = crate::geometry::voxel::VoxelVolume { lo: planes.lo, h: planes.h, grid: crate::geometry::voxel::voxelize_on(&lm, planes.lo, planes.h, planes.dims()) };
    let centre_occ = vol.grid.occ.clone();
    let filled = make_well_composed(&mut vol.grid);
    let (b0, b2, b1) = betti(&vol.grid);
    let n = vol.grid.count();
    tried.push(format!("{label}: {n} voxels, {b0} component(s), {b2} cavit(ies), genus {b1}"));
    let fits = n * 8 <= opts.max_elements;
    if b0 == 1 && b2 == 0 && b1 == genus && n <= opts.max_elements {
        return Ok((Some(Lattice { vol, planes, filled, thin_wall: None }), fits));
    }
    if b0 == 1 && b2 == 0 && b1 > genus {
        // One piece with extra tunnels: a wall thinner than a voxel passes between
        // the voxel centres and leaves holes in the voxel solid (hexgen_joint: genus
        // 2 at 24 voxels, 5 at 48, for 1). Add every voxel at least 0.375, then
        // 0.25, then 0.125 full (the wall's among them; elsewhere these only thicken
        // the staircase by part-full voxels, which the fit pulls back onto the
        // surface) until the topology is the input's. A solid in pieces
        // (trimesh_round's tube wall below 188 voxels) is too coarse as a whole:
        // filling would make a wall of squeezed one-voxel elements; it is refined.
        let frac = crate::geometry::voxel::solid_fractions(&lm, &vol, 4);
        let centre_count = centre_occ.iter().filter(|&&o| o).count();
        for tau in [0.375f32, 0.25, 0.125] {
            let mut g = VoxelGrid { dims: vol.grid.dims, occ: centre_occ.iter().zip(&frac).map(|(&o, &f)| o || f >= tau).collect() };
            let added = g.count() - centre_count;
            let f2 = make_well_composed(&mut g);
            let (b0, b2, b1) = betti(&g);
            let n = g.count();
            tried.push(format!("{label} with voxels >= {tau} solid (+{added}): {n} voxels, {b0} component(s), {b2} cavit(ies), genus {b1}"));
            if b0 == 1 && b2 == 0 && b1 == genus && n <= opts.max_elements {
                vol.grid = g;
                return Ok((Some(Lattice { vol, planes, filled: f2, thin_wall: Some((added, tau)) }), n * 8 <= opts.max_elements));
            }
        }
    }
    Ok((None, fits))
}
