//! Local refinement (`FallbackOptions::local_refinement`): the fallback's best
//! lattice meshed again with the voxels around the points farthest from its mesh
//! split 3 x 3 x 3 with conforming transition elements ([`crate::hex::refine`]),
//! from three starts each round (the lattice, the fitted coarse mesh, and the
//! split voxels voxelised again at the fine size, [`carve_refined`]).

use super::composed::{make_well_composed, make_well_composed_where};
use super::lattices::{meshed, Lattice, Search};
use super::mesh::{mesh_lattice, Start};
use crate::error::{Progress, Result, SubProgress};
use crate::geometry::vec3::{add, scale};
use crate::geometry::voxel::betti;
use crate::geometry::VoxelGrid;
use crate::hex::frames::Frames;
use crate::hex::grid::lattice_hex;
use crate::hex::lattice::LatticePlanes;
use crate::hex::report::HexResult;
use crate::hex::stages::{MeshFigures, RefineStart};
use crate::hex::HexMesh;
use crate::mesh::TriMesh;

impl Search<'_> {
    /// Local refinement rounds on the best lattice (with its `planes`): each
    /// round adds the voxels around the points farthest from the last mesh to the
    /// boxes to split, meshes the refined lattice from its three starts and keeps
    /// the best of them; a round's mesh replaces the best when it ranks better.
    /// The rounds stop at `opts.max_elements` or once the best meets every goal.
    /// Returns why a round's re-voxelised start was skipped, per round that skipped it.
    pub fn refine_locally(&mut self, planes: Option<LatticePlanes>, progress: &mut dyn Progress) -> Result<Vec<String>> {
        let opts = self.opts;
        let mut carve_failed: Vec<String> = Vec::new();
        if !(opts.fallback.local_refinement > 0 && self.best.hausdorff_relative > 0.0) {
            return Ok(carve_failed);
        }
        let (lattice, _) = super::lattices::topology_lattice(&self.fr.sw.mesh, self.best_res, planes, self.genus, opts, &mut self.tried)?;
        let Some(lattice) = lattice else { return Ok(carve_failed) };
        let (fr, t_all, best_res, genus) = (self.fr, self.t_all, self.best_res, self.genus);
        let mut boxes: Vec<([u32; 3], [u32; 3])> = Vec::new();
        let mut from = self.best.mesh.clone();
        // the coarse lattice fitted to the surface, for the fitted start of every
        // round, and the fine voxels for the re-voxelised start
        let mut fit_cache = None;
        let fine_in = fine_voxels(&fr.sw.mesh, &lattice);
        for _ in 0..opts.fallback.local_refinement {
            if opts.goals.missed(&self.best) == 0 {
                break;
            }
            boxes.extend(far_boxes(&from, fr, &lattice, REFINE_FAR_SHARE));
            // boxes near one another as one: no cell between two, so the
            // closure of the marks does not spread (refine::merge_boxes)
            boxes = crate::hex::refine::merge_boxes(&boxes);
            // three meshes of the refined lattice, the best kept: its new nodes
            // started on the lattice (closest on hexgen_rod at first), on the
            // fitted coarse mesh (on hexgen_hepta the lattice start's fine
            // boundary nodes stay up to a coarse voxel off the surface and fold
            // there, these do not), and the split voxels voxelised again at the
            // fine size (carve_refined: the fine staircase instead of the coarse
            // one; hexgen_rod at 28 voxels 1,777 elements at 0.84 % where the
            // others give 1,741 at 1.10 %); BENCHMARKS.md "Local refinement"
            let mut sub = SubProgress { inner: progress, lo: 1.0 - self.share, hi: 1.0 };
            let a = mesh_lattice(lattice.clone(), best_res, Some((&boxes, Start::Lattice)), fr, opts, t_all, &mut sub)?;
            let mut starts = vec![start_figures(&a)];
            let b = mesh_lattice(lattice.clone(), best_res, Some((&boxes, Start::Fitted(&mut fit_cache))), fr, opts, t_all, &mut sub)?;
            starts.push(start_figures(&b));
            let mut r = if opts.goals.beats(&b, Some(&a)) { b } else { a };
            match carve_refined(&lattice.vol, &boxes, &fine_in, genus) {
                Ok(c) => {
                    let c = mesh_lattice(lattice.clone(), best_res, Some((&boxes, Start::Revoxelised(c))), fr, opts, t_all, &mut sub)?;
                    starts.push(start_figures(&c));
                    if opts.goals.beats(&c, Some(&r)) {
                        r = c;
                    }
                }
                Err(why) => carve_failed.push(why),
            }
            let mut m = meshed(best_res, &r);
            m.local_refinement_start = refinement_start(&r);
            m.local_refinement_starts = Some(starts);
            self.meshed.push(m);
            if r.quality.elements > opts.max_elements {
                break;
            }
            from = r.mesh.clone();
            if opts.goals.beats(&r, Some(&self.best)) {
                self.best = r;
            }
        }
        Ok(carve_failed)
    }
}

/// Where a locally refined mesh started (its lattice details' `local_refinement.start`).
fn refinement_start(r: &HexResult) -> Option<RefineStart> {
    r.lattice().and_then(|l| l.local_refinement.as_ref()).map(|d| d.start)
}

/// The figures a mesh is ranked by, with the start of a locally refined mesh.
pub(super) fn start_figures(r: &HexResult) -> MeshFigures {
    MeshFigures {
        start: refinement_start(r),
        elements: r.quality.elements,
        inverted: r.quality.inverted,
        min_scaled_jacobian: r.quality.min,
        mean_scaled_jacobian: r.quality.mean,
        hausdorff_relative: r.hausdorff_relative,
    }
}

/// Local refinement: the points at least this share of the largest distance
/// between a mesh and the input get their voxels split. Measured on hexgen_rod at
/// 24 voxels (1,001 elements, 2.09 %) with the lattice start alone (commit
/// f2d6be2), elements and distance after each round: 0.6: 2,831 / 0.88 %, 9,859 /
/// 0.67 %; 0.7: 1,171 / 1.65 %, 2,257 / 1.25 %, 16,799 / 0.65 %; 0.8: 1,171 /
/// 1.65 %, 2,527 / 0.94 %, 2,769 / 0.69 % (BENCHMARKS.md "Local refinement").
const REFINE_FAR_SHARE: f64 = 0.8;

/// Boxes of lattice nodes around the points where `mesh` (user coordinates) is
/// farthest from the input ([`crate::hex::distance::far_points`] with `frac`),
/// each the voxel it lies in, within the lattice.
pub(super) fn far_boxes(mesh: &HexMesh, fr: &Frames, lattice: &Lattice, frac: f64) -> Vec<([u32; 3], [u32; 3])> {
    let dims = lattice.vol.grid.dims;
    crate::hex::distance::far_points(mesh, fr, frac, f64::INFINITY)
        .iter()
        .map(|p| {
            let c = lattice.planes.to_lattice(*p);
            (
                std::array::from_fn(|a| c[a].floor().clamp(0.0, dims[a] as f64 - 1.0) as u32),
                std::array::from_fn(|a| (c[a].floor() + 1.0).clamp(1.0, dims[a] as f64) as u32),
            )
        })
        .collect()
}

/// A locally refined lattice whose split voxels are voxelised again at a third of
/// the voxel size ([`carve_refined`]), in lattice units (nodes) and VTK order.
#[derive(Clone, Debug)]
pub(super) struct Carved {
    pub refined: crate::hex::refine::Refined,
    /// Empty voxels inside the boxes that were split to take the solid's fine voxels.
    pub empty_split: usize,
    /// Fine voxels of split voxels left out (outside the surface) and filled to
    /// keep the fine solid well-composed.
    pub fine_removed: usize,
    pub fine_filled: usize,
}

/// The voxels of `mesh` on `vol`'s lattice split 3 x 3 x 3 (the same for every
/// round of local refinement).
pub(super) fn fine_voxels(mesh: &TriMesh, lattice: &Lattice) -> VoxelGrid {
    let vol = &lattice.vol;
    crate::geometry::voxel::voxelize_on(&lattice.planes.warped(mesh), vol.lo, vol.h / 3.0, vol.grid.dims.map(|d| 3 * d))
}

/// Local refinement with re-voxelisation: the lattice's voxels in `boxes` (boxes of
/// lattice nodes; with the empty voxels whose corners all lie in a box) are split
/// 3 x 3 x 3 with conforming transitions around them ([`crate::hex::refine`]), and of
/// their fine voxels only those inside the surface (`fine_in`, [`fine_voxels`]; made well-composed
/// by filling fine voxels of split voxels) are kept: the refined region follows
/// the surface at the fine voxel size instead of keeping the coarse staircase. Err
/// (why) when the fine solid cannot be made well-composed within the split voxels
/// or does not have the input's topology (one component, no cavity, `genus`).
pub(super) fn carve_refined(vol: &crate::geometry::voxel::VoxelVolume, boxes: &[([u32; 3], [u32; 3])], fine_in: &VoxelGrid, genus: i64) -> std::result::Result<Carved, String> {
    let dims = vol.grid.dims;
    let in_box = |p: [u32; 3]| crate::hex::refine::in_boxes(p, boxes);
    let mut all = vol.grid.clone();
    let mut empty_split = 0;
    for z in 0..dims[2] {
        for y in 0..dims[1] {
            for x in 0..dims[0] {
                let i = all.idx(x, y, z);
                if !all.occ[i] && (0..8u32).all(|k| in_box([x as u32 + (k & 1), y as u32 + (k >> 1 & 1), z as u32 + (k >> 2 & 1)])) {
                    all.occ[i] = true;
                    empty_split += 1;
                }
            }
        }
    }
    let h = lattice_hex(&all, 0);
    let mut marked: Vec<bool> = h.node_lattice.iter().map(|&p| in_box(p)).collect();
    crate::hex::refine::close_marks(&h.mesh.elements, &mut marked);
    // the voxels split 3 x 3 x 3 (every corner marked)
    let mut split = VoxelGrid::empty(dims);
    for (el, c) in h.mesh.elements.iter().zip(&h.elem_lattice) {
        let i = split.idx(c[0] as usize, c[1] as usize, c[2] as usize);
        if el.iter().all(|&v| marked[v as usize]) {
            split.occ[i] = true;
        } else if !vol.grid.occ[i] {
            return Err("an empty voxel joined the refinement without being split".into());
        }
    }
    let fdims = dims.map(|d| 3 * d);
    let mut fine = VoxelGrid::empty(fdims);
    let mut fine_removed = 0;
    for c in &h.elem_lattice {
        let is_split = split.occ[split.idx(c[0] as usize, c[1] as usize, c[2] as usize)];
        for k in 0..27usize {
            let f = [3 * c[0] as usize + k % 3, 3 * c[1] as usize + k / 3 % 3, 3 * c[2] as usize + k / 9];
            let i = fine.idx(f[0], f[1], f[2]);
            fine.occ[i] = !is_split || fine_in.occ[i];
            fine_removed += usize::from(!fine.occ[i]);
        }
    }
    let fine_filled = make_well_composed_where(&mut fine, &|f| split.occ[split.idx(f[0] / 3, f[1] / 3, f[2] / 3)]);
    if make_well_composed(&mut fine.clone()) > 0 {
        return Err("the fine voxels cannot be made well-composed within the split voxels".into());
    }
    let (b0, b2, b1) = betti(&fine);
    if !(b0 == 1 && b2 == 0 && b1 == genus) {
        return Err(format!("the fine voxel solid has {b0} component(s), {b2} cavit(ies), genus {b1} (input: genus {genus})"));
    }
    let mut r = crate::hex::refine::refine_flags(&h.node_lattice, &h.mesh.elements, &marked);
    let fine_occ = |p: [f64; 3]| {
        let c = p.map(|x| x.floor() as usize);
        if split.occ[split.idx(c[0], c[1], c[2])] {
            let f = p.map(|x| (3.0 * x).floor() as usize);
            fine.occ[fine.idx(f[0], f[1], f[2])]
        } else {
            true
        }
    };
    r.elements.retain(|el| {
        let mut m = [0.0; 3];
        for &v in el {
            m = add(m, r.nodes[v as usize]);
        }
        fine_occ(scale(m, 0.125))
    });
    // drop the nodes no element uses
    let mut id = vec![u32::MAX; r.nodes.len()];
    let mut nodes = Vec::new();
    for el in &mut r.elements {
        for v in el.iter_mut() {
            if id[*v as usize] == u32::MAX {
                id[*v as usize] = nodes.len() as u32;
                nodes.push(r.nodes[*v as usize]);
            }
            *v = id[*v as usize];
        }
    }
    r.nodes = nodes;
    Ok(Carved { refined: r, empty_split, fine_removed: fine_removed - fine_filled, fine_filled })
}
