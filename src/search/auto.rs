//! The automated mode: genus-guided context generation.
//!
//! 1. The temporary volume of the aligned input ([`crate::geometry::voxel`]), split
//!    into subregions ([`subregions`]), each with its genus.
//! 2. For each occupied box (1..3 cells along X, 1..2 along Y and Z; coarsest
//!    first; or only the full 3x2x2 grid split by the caller's ratios): split the
//!    aligned bounding box into subregions, measure each one's genus, and take its
//!    feasible labels (empty -> null; genus 0 -> cube, the six BHC and the three THC; genus 1 ->
//!    the three THC; genus >= 2 -> the box cannot hold the input).
//! 3. Local stage: each subregion's feasible labels are ranked by their fit in the
//!    box (the input against the box's assembly with that label in the cell and
//!    cubes elsewhere, the cell's own term: [`in_context_fits`]); the best labels
//!    are diffused as single cells on the subregion's surface (the input's samples
//!    inside it plus samples on the faces where the subregion is cut out of the
//!    solid) and verified (GOCC + TCV), all in one batch.
//! 4. Global stage: products of the kept labels whose assembly is valid and has the
//!    input's genus are ranked by geometric fit averaged over their cells; the best
//!    ones pass the occupancy pre-check, are diffused in one batch and verified (a
//!    failing one a second time with the visible prior); the verified candidate
//!    with the lowest mean cell fit is chosen.

use super::generate::{
    diffuse_and_verify, finish, lay_out, fit_score_cells, fit_score_scaled, limit_fit, polycube_samples, precheck, worst_and_mean, prepare_input, without_fit_limit, Candidate, OrientationSearch,
    PolycubeOptions, PolycubeResult, PolycubeTimings, PreparedInput, Stage, FIT_SAMPLES,
};
use crate::context::Context;
use crate::diffusion::Model;
use crate::error::{check_progress, Error, Progress, Result};
use crate::geometry::rng::seeded_rng;
use crate::geometry::voxel::{betti, voxelize, VoxelVolume};
use crate::geometry::{SurfaceSample, VoxelGrid};
use crate::mesh::TriMesh;
use crate::polycube::orientation::AxisRotation;
use crate::polycube::{Family, Primitive, NUM_CELLS};
use rand::RngExt;
use serde::{Deserialize, Serialize};
use std::time::Instant;

/// What the automated mode measured for one subregion.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Subregion {
    /// Cell index of the subregion in the grid.
    pub cell: usize,
    /// Box in the aligned frame.
    pub lo: [f64; 3],
    pub hi: [f64; 3],
    /// Fraction of the subregion box that is solid.
    pub fill: f64,
    /// Solid components (26-connected), sealed cavities, tunnels (genus).
    pub components: usize,
    pub cavities: usize,
    pub genus: i64,
    /// The subregion is (almost) empty: label null.
    pub empty: bool,
}

/// Split points of one axis from ratios (fractions summing to 1).
pub fn split_points(lo: f64, hi: f64, ratios: &[f64]) -> Vec<f64> {
    let total: f64 = ratios.iter().sum();
    let mut v = vec![lo];
    let mut acc = 0.0;
    for r in ratios {
        acc += r / total;
        v.push(lo + acc * (hi - lo));
    }
    *v.last_mut().unwrap() = hi;
    v
}

/// Analyse the subregions of a volume split at `xs`, `ys`, `zs` (split points along each axis).
pub fn subregions(vol: &VoxelVolume, xs: &[f64], ys: &[f64], zs: &[f64], min_fill: f64) -> Vec<Subregion> {
    let mut out = Vec::new();
    let [nx, ny, nz] = vol.grid.dims;
    for (k, zw) in zs.windows(2).enumerate() {
        for (j, yw) in ys.windows(2).enumerate() {
            for (i, xw) in xs.windows(2).enumerate() {
                let lo = [xw[0], yw[0], zw[0]];
                let hi = [xw[1], yw[1], zw[1]];
                let r = |a: usize, v: f64, n: usize| (((v - vol.lo[a]) / vol.h).round().max(0.0) as usize).min(n);
                let (x0, x1) = (r(0, lo[0], nx), r(0, hi[0], nx));
                let (y0, y1) = (r(1, lo[1], ny), r(1, hi[1], ny));
                let (z0, z1) = (r(2, lo[2], nz), r(2, hi[2], nz));
                let dims = [x1.saturating_sub(x0).max(1), y1.saturating_sub(y0).max(1), z1.saturating_sub(z0).max(1)];
                let mut g = VoxelGrid::empty(dims);
                for z in z0..z1 {
                    for y in y0..y1 {
                        for x in x0..x1 {
                            let v = vol.grid.occ[vol.grid.idx(x, y, z)];
                            let ix = g.idx(x - x0, y - y0, z - z0);
                            g.occ[ix] = v;
                        }
                    }
                }
                let fill = g.count() as f64 / g.occ.len() as f64;
                let (b0, b2, b1) = betti(&g);
                out.push(Subregion {
                    cell: crate::polycube::cell_index(i, j, k),
                    lo,
                    hi,
                    fill,
                    components: b0,
                    cavities: b2,
                    genus: b1,
                    empty: fill < min_fill,
                });
            }
        }
    }
    out
}

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
    /// Labels kept per subregion after the local fit (default 3).
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
    /// [`joint_labels`]) and add the valid assemblies of the input's genus it visits
    /// to the box's candidates (default false: measured in BENCHMARKS.md "Context
    /// search", not yet on the real meshes).
    pub joint_labels: bool,
}

impl Default for AutoOptions {
    fn default() -> Self {
        AutoOptions { resolution: 48, min_fill: 0.04, null_fill: 0.15, local_keep: 3, local_diffusion: true, max_global: 16, finer_box_factor: 0.8, max_boxes: 2, local_steps: 25, joint_labels: false }
    }
}

/// The local stage's record of one subregion.
#[derive(Debug, Clone, Serialize)]
pub struct LocalResult {
    pub subregion: Subregion,
    /// (label, in-context geometric fit, see [`in_context_fits`]) of every feasible
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
    pub ratios: SplitRatios,
    pub locals: Vec<LocalResult>,
    /// Global candidates with the input's genus (before the cap).
    pub candidates: usize,
    /// Best global geometric fit (squared cell units of this box).
    pub best_fit: Option<f64>,
    /// The same candidate's fit in squared units of a common length (the cell of a
    /// 12-cell split of the part's bounding box by volume), which ranks the boxes:
    /// see [`box_scale`].
    pub best_fit_common: Option<f64>,
    /// Candidates added by the joint label search (`AutoOptions::joint_labels`).
    pub joint_candidates: usize,
    /// Why this box cannot hold the input, if it cannot.
    pub refused: Option<String>,
}

/// What the automated mode measured beyond the candidates.
#[derive(Debug, Clone, Serialize)]
pub struct AutoReport {
    /// Voxels along the longest side of the temporary volume (`AutoOptions::resolution`,
    /// doubled while the volume misses the surface's, see [`VOLUME_TOLERANCE`]).
    pub resolution: usize,
    pub volume_tetrahedra: usize,
    pub volume: f64,
    pub surface_volume: f64,
    pub volume_relative_error: f64,
    pub boxes: Vec<BoxResult>,
    pub chosen_box: Option<[usize; 3]>,
}

/// The labels a subregion can take: null when empty; by its genus (0: cube, the
/// six BHC and the three THC; 1: the three THC) otherwise, with null too when it is filled less than
/// `null_fill`; a genus of 2 or more refuses the box unless the subregion is that
/// thin.
fn feasible(sub: &Subregion, null_fill: f64) -> std::result::Result<Vec<Primitive>, String> {
    if sub.empty {
        return Ok(vec![Primitive::Null]);
    }
    let thin = sub.fill < null_fill;
    let mut v: Vec<Primitive> = match sub.genus {
        // a through hole whose far end a neighbouring cell closes is a blind hole
        // in the subregion (measured genus 0): the through holes stay feasible, and
        // the assembly's genus decides (complex 0 of BENCHMARKS.md "In-context label
        // ranking": its THC+Z cell under a solid neighbour measured genus 0)
        0 => Primitive::solids().collect(),
        1 => Primitive::solids().filter(|p| p.family() == Family::Thc).collect(),
        _ if thin => Vec::new(),
        g => return Err(format!("subregion of cell {} has genus {g}; one cell holds at most one hole", sub.cell)),
    };
    if thin {
        v.push(Primitive::Null);
    }
    Ok(v)
}

/// Samples of a subregion: the input's samples inside its box and samples on the
/// faces where the box cuts the solid, so that the subregion's surface is closed.
fn subregion_samples(input: &PreparedInput, vol: &VoxelVolume, sub: &Subregion, bb_lo: [f64; 3], bb_hi: [f64; 3], seed: u64) -> Vec<SurfaceSample> {
    let eps = 1e-9;
    let inside = |p: [f64; 3]| (0..3).all(|a| p[a] >= sub.lo[a] - eps && p[a] <= sub.hi[a] + eps);
    let mut v: Vec<SurfaceSample> = input.samples.iter().filter(|s| inside(s.point)).copied().collect();
    let area_per_sample = input.area / input.samples.len().max(1) as f64;
    let mut rng = seeded_rng(seed, sub.cell as u64);
    let g = &vol.grid;
    for a in 0..3 {
        for (plane, is_cut) in [(sub.lo[a], sub.lo[a] > bb_lo[a] + eps), (sub.hi[a], sub.hi[a] < bb_hi[a] - eps)] {
            if !is_cut {
                continue;
            }
            // voxels adjacent to the plane on the subregion's side
            let layer = (((plane - vol.lo[a]) / vol.h).round() as i64 - if plane == sub.lo[a] { 0 } else { 1 }).max(0) as usize;
            if layer >= g.dims[a] {
                continue;
            }
            let (u, w) = ((a + 1) % 3, (a + 2) % 3);
            for j in 0..g.dims[u] {
                for k in 0..g.dims[w] {
                    let mut p = [0usize; 3];
                    p[a] = layer;
                    p[u] = j;
                    p[w] = k;
                    if !g.occ[g.idx(p[0], p[1], p[2])] {
                        continue;
                    }
                    let c = vol.voxel_centre(p[0], p[1], p[2]);
                    if c[u] < sub.lo[u] || c[u] > sub.hi[u] || c[w] < sub.lo[w] || c[w] > sub.hi[w] {
                        continue;
                    }
                    let expected = vol.h * vol.h / area_per_sample;
                    let n = expected.floor() as usize + usize::from(rng.random::<f64>() < expected.fract());
                    for _ in 0..n {
                        let mut q = c;
                        q[a] = plane;
                        q[u] += (rng.random::<f64>() - 0.5) * vol.h;
                        q[w] += (rng.random::<f64>() - 0.5) * vol.h;
                        v.push(SurfaceSample { point: q, triangle: u32::MAX, bary: [0.0; 3] });
                    }
                }
            }
        }
    }
    v
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
    let surface_volume = input.alignment.mesh.check().volume.abs();
    let (vol, resolution) = temporary_volume(&input.alignment.mesh, aopts.resolution, surface_volume)?;
    let bb = crate::geometry::Aabb::of_points(&input.alignment.mesh.vertices);
    let ratio = vol.volume() / surface_volume.max(f64::MIN_POSITIVE);
    if !(THIN_PART_FRACTION..=1.0 / THIN_PART_FRACTION).contains(&ratio) {
        // The finest lattice still misses most of the solid, or a wall thinner than
        // a voxel fills whole voxels: the subregions' fills and genera would
        // describe the lattice, not the part. Say why instead.
        let e = bb.size();
        let (thin, long) = (e.iter().copied().fold(f64::INFINITY, f64::min), e.iter().copied().fold(0.0, f64::max));
        return Err(Error::VerificationFailed(format!(
            "automated mode: the temporary volume at {resolution} voxels along the longest side holds {:.3e} of the surface's volume {:.3e} ({:.1} %): the part is thinner than a voxel (thinnest bounding-box extent {:.3e}, {:.1e} of the longest {:.3e}), so its subregions cannot be measured; give a context (--labels) or constraints instead",
            vol.volume(),
            surface_volume,
            100.0 * ratio,
            thin,
            thin / long.max(f64::MIN_POSITIVE),
            long
        )));
    }
    let mut report = AutoReport {
        resolution,
        volume_tetrahedra: vol.tetrahedra(),
        volume: vol.volume(),
        surface_volume,
        volume_relative_error: (vol.volume() - surface_volume).abs() / surface_volume.max(1e-300),
        boxes: Vec::new(),
        chosen_box: None,
    };
    let shapes: Vec<SplitRatios> = match ratios {
        Some(r) => vec![r.clone()],
        None => {
            let mut v = Vec::new();
            for nx in 1..=3 {
                for ny in 1..=2 {
                    for nz in 1..=2 {
                        v.push(SplitRatios::equal(nx, ny, nz));
                    }
                }
            }
            v.sort_by_key(|r| {
                let d = r.dims();
                (d[0] * d[1] * d[2], std::cmp::Reverse(d[0]), std::cmp::Reverse(d[1]))
            });
            v
        }
    };
    // Per box: global candidates ranked by fit.
    let mut per_box: Vec<Vec<(Context, f64)>> = Vec::new();
    let mut joint_lists: Vec<Option<(Vec<usize>, Vec<Vec<Primitive>>)>> = Vec::new();
    let mut local_jobs: Vec<LocalJob> = Vec::new();
    let fit_sub = &input.samples[..input.samples.len().min(FIT_SAMPLES)];
    let t0 = Instant::now();
    for (bi, r) in shapes.iter().enumerate() {
        check_progress(progress, 0.05 + 0.25 * bi as f64 / shapes.len() as f64, "subregions")?;
        let xs = split_points(bb.min[0], bb.max[0], &r.x);
        let ys = split_points(bb.min[1], bb.max[1], &r.y);
        let zs = split_points(bb.min[2], bb.max[2], &r.z);
        let subs = subregions(&vol, &xs, &ys, &zs, aopts.min_fill);
        let mut br = BoxResult { dims: r.dims(), ratios: r.clone(), locals: Vec::new(), candidates: 0, best_fit: None, best_fit_common: None, joint_candidates: 0, refused: None };
        let mut options: Vec<Vec<Primitive>> = Vec::new();
        // every feasible label of each subregion, best in-context fit first
        let mut full: Vec<Vec<Primitive>> = Vec::new();
        let mut labels_of: Vec<Vec<Primitive>> = Vec::with_capacity(subs.len());
        for sub in &subs {
            match feasible(sub, aopts.null_fill) {
                Ok(l) => labels_of.push(l),
                Err(e) => {
                    br.refused = Some(e);
                    break;
                }
            }
        }
        if br.refused.is_none() {
            let scores = in_context_fits(fit_sub, &subs, &labels_of);
            for (si, sub) in subs.iter().enumerate() {
                let labels = &labels_of[si];
                let mut lr = LocalResult { subregion: sub.clone(), fits: Vec::new(), kept: Vec::new(), verified: Vec::new() };
                if labels[..] == [Primitive::Null] {
                    lr.kept.push("null".into());
                    full.push(labels.clone());
                    options.push(labels.clone());
                    br.locals.push(lr);
                    continue;
                }
                let mut scored: Vec<(Primitive, f64)> = labels.iter().copied().zip(scores[si].iter().copied()).filter(|(p, _)| *p != Primitive::Null).collect();
                scored.sort_by(|a, b| a.1.total_cmp(&b.1));
                let may_be_null = labels.contains(&Primitive::Null);
                full.push(scored.iter().map(|(p, _)| *p).chain(may_be_null.then_some(Primitive::Null)).collect());
                lr.fits = scored.iter().map(|(p, f)| (p.name().to_string(), *f)).collect();
                let mut kept: Vec<Primitive> = scored.iter().take(aopts.local_keep.max(1)).map(|(p, _)| *p).collect();
                if aopts.local_diffusion {
                    let samples = subregion_samples(&input, &vol, sub, bb.min, bb.max, opts.seed);
                    for &p in &kept {
                        local_jobs.push(LocalJob { boxi: bi, local: br.locals.len(), cell: sub.cell, label: p, samples: samples.clone() });
                    }
                }
                if may_be_null {
                    kept.push(Primitive::Null);
                }
                lr.kept = kept.iter().map(|p| p.name().to_string()).collect();
                options.push(kept);
                br.locals.push(lr);
            }
        }
        if br.refused.is_none() {
            trim_to_budget(&mut options, &mut br.locals, MAX_COMBINATIONS);
            local_jobs.retain(|j| j.boxi != bi || options[j.local].contains(&j.label));
        }
        joint_lists.push(if br.refused.is_none() { Some((br.locals.iter().map(|l| l.subregion.cell).collect::<Vec<usize>>(), full)) } else { None });
        let mut cands: Vec<(Context, f64)> = Vec::new();
        if br.refused.is_none() {
            // Cells of the box sit at grid cells (0..nx, 0..ny, 0..nz); the rest are null.
            let cells: Vec<usize> = br.locals.iter().map(|l| l.subregion.cell).collect();
            let mut combos: Vec<[Primitive; NUM_CELLS]> = vec![[Primitive::Null; NUM_CELLS]];
            for (ci, opts_c) in options.iter().enumerate() {
                let mut next = Vec::with_capacity(combos.len() * opts_c.len());
                for c in &combos {
                    for &p in opts_c {
                        let mut c2 = *c;
                        c2[cells[ci]] = p;
                        next.push(c2);
                    }
                }
                combos = next;
                if combos.len() > MAX_COMBINATIONS {
                    br.refused = Some(format!("{} label combinations; use --ratios with fewer cells", combos.len()));
                    combos.clear();
                    break;
                }
            }
            for l in combos {
                let ctx = Context::new(l);
                if ctx.occupied().next().is_none() {
                    continue;
                }
                let g = ctx.assemble();
                // a valid solid's genus is 1 - its Euler characteristic: an assembly
                // that says another genus needs no full check (most of a box's
                // products; the check was a third of a genus-1 part's search)
                if 1 - crate::polycube::assembly::euler_solid(&g) != input_genus {
                    continue;
                }
                let v = crate::polycube::assembly::check(&g);
                if v.valid && v.genus == Some(input_genus) {
                    cands.push((ctx, 0.0));
                }
            }
            br.candidates = cands.len();
            if cands.is_empty() && br.refused.is_none() {
                let genera: Vec<String> = br.locals.iter().map(|l| format!("cell {}: {}", l.subregion.cell, if l.subregion.empty { "empty".to_string() } else { format!("genus {}", l.subregion.genus) })).collect();
                br.refused = Some(format!("no valid assembly of the subregions' labels has genus {input_genus} ({})", genera.join(", ")));
            }
        }
        per_box.push(cands);
        report.boxes.push(br);
    }
    timings.precheck += t0.elapsed().as_secs_f64();

    // Global fit of every candidate (cheap); order the boxes: the coarsest box whose
    // best fit is not beaten by a finer one by `finer_box_factor`, then the rest by fit.
    check_progress(progress, 0.3, "global candidates")?;
    let mut joint_found: Vec<std::collections::HashSet<[Primitive; NUM_CELLS]>> = vec![Default::default(); per_box.len()];
    for (bi, cands) in per_box.iter_mut().enumerate() {
        // Thousands of candidates for a genus-0 part (a box: 22,000 over the 12
        // boxes): the fits are independent, so they run on every core. (Ranking them
        // on a coarse fit first was tried and lost a complex part's true solid:
        // BENCHMARKS.md "Global fits in parallel".)
        use rayon::prelude::*;
        //
        // Each candidate keeps its worst cell's fit (the fit limits apply to it) and
        // the box's candidates are ordered by the mean cell fit, the ranking score of
        // `Candidate::score`: the worst cell ties candidates that differ in better-
        // fitting cells, and which of them made the `max_global` cut was arbitrary
        // (BENCHMARKS.md "Ranking verified candidates by the mean cell fit").
        let fits: Vec<(f64, f64)> = cands.par_iter().map(|(ctx, _)| worst_and_mean(&fit_score_cells(fit_sub, ctx, AxisRotation::IDENTITY, &polycube_samples(ctx, FIT_SAMPLES), [1.0; 3]))).collect();
        let mut keyed: Vec<((Context, f64), f64)> = cands.drain(..).zip(fits).map(|((ctx, _), (worst, mean))| ((ctx, worst), mean)).collect();
        if aopts.joint_labels {
            if let Some((cells, lists)) = &joint_lists[bi] {
                let found = joint_labels(fit_sub, cells, lists, input_genus, JOINT_SWEEPS);
                let before = keyed.len();
                for (ctx, _) in found {
                    joint_found[bi].insert(ctx.labels);
                    if !keyed.iter().any(|((c, _), _)| c.labels == ctx.labels) {
                        let (worst, mean) = worst_and_mean(&fit_score_cells(fit_sub, &ctx, AxisRotation::IDENTITY, &polycube_samples(&ctx, FIT_SAMPLES), [1.0; 3]));
                        keyed.push(((ctx, worst), mean));
                    }
                }
                report.boxes[bi].joint_candidates = keyed.len() - before;
                if keyed.len() > before {
                    report.boxes[bi].refused = None;
                }
            }
        }
        // Boxes are compared in a common unit: the best of the box's few best-fitting
        // candidates (worst cell), measured with the box's cell widths scaled to that unit.
        keyed.sort_by(|a, b| a.0 .1.total_cmp(&b.0 .1));
        report.boxes[bi].best_fit = keyed.first().map(|c| c.0 .1);
        let scale = box_scale(bb.size(), report.boxes[bi].dims);
        report.boxes[bi].best_fit_common = keyed
            .iter()
            .take(aopts.local_keep.max(1) * 2)
            .map(|((ctx, _), _)| fit_score_scaled(fit_sub, ctx, AxisRotation::IDENTITY, &polycube_samples(ctx, FIT_SAMPLES), scale))
            .min_by(f64::total_cmp);
        // then the box's candidates in ranking order (stable: worst cell among equals)
        keyed.sort_by(|a, b| a.1.total_cmp(&b.1));
        cands.extend(keyed.into_iter().map(|(c, _)| c));
    }
    let best_overall = report.boxes.iter().filter_map(|b| b.best_fit).fold(f64::INFINITY, f64::min);
    let common = |bi: usize| report.boxes[bi].best_fit_common.unwrap_or(f64::INFINITY);
    let mut order: Vec<usize> = Vec::new();
    for (bi, cands) in per_box.iter().enumerate() {
        if !cands.is_empty() {
            match order.first() {
                None => order.push(bi),
                Some(&c) => {
                    if common(bi) < aopts.finer_box_factor * common(c) {
                        order.insert(0, bi);
                    } else {
                        order.push(bi);
                    }
                }
            }
        }
    }
    if order.len() > 1 {
        let first = order[0];
        order[1..].sort_by(|&a, &b| common(a).total_cmp(&common(b)));
        debug_assert_eq!(order[0], first);
    }
    if order.is_empty() {
        let mut why: Vec<String> = report.boxes.iter().filter_map(|b| b.refused.as_ref().map(|r| format!("{}x{}x{}: {r}", b.dims[0], b.dims[1], b.dims[2]))).collect();
        why.truncate(6);
        return Err(Error::VerificationFailed(format!(
            "automated mode found no context of genus {input_genus}: {}; try splitting ratios that put each hole in its own cell, e.g. --ratios {}",
            why.join("; "),
            suggest_ratios(&vol, bb.min, bb.max)
        )));
    }
    // Try the boxes in that order (at most `max_boxes`) until one yields a verified polycube.
    let mut all_global: Vec<Candidate> = Vec::new();
    let mut attempt = 0usize;
    // candidates of the boxes passed over, kept when no box is tried at all (the
    // main job can still mesh the best-fitting of them, see pipeline::fallback_order)
    let mut passed_over: Vec<Candidate> = Vec::new();
    let mut o_global = opts.clone();
    o_global.orientations = OrientationSearch::Identity;
    for &cb in order.iter() {
        if attempt >= aopts.max_boxes.max(1) {
            break;
        }
        // A box none of whose candidates the fit limit would admit (they all fit far
        // worse than another box's best) is passed over without using up an attempt
        // or running its local stage.
        let mut probe: Vec<Candidate> = Vec::new();
        for (ctx, _) in per_box[cb].iter().take(aopts.max_global.max(1)) {
            probe.extend(precheck(&input, ctx, &without_fit_limit(&o_global))?);
        }
        // the pre-check verdicts, reused by the global stage for the contexts the
        // local filter keeps (the fit limit is applied again to the final set)
        let prechecked = probe.clone();
        limit_fit(&mut probe, &o_global, best_overall);
        if !probe.iter().any(|c| c.stage == Stage::Pending) {
            passed_over.extend(probe);
            if report.boxes[cb].refused.is_none() {
                report.boxes[cb].refused = Some(format!("no candidate passes the occupancy pre-check and the fit limit (best fit {:.4}, best of all boxes {best_overall:.4})", report.boxes[cb].best_fit.unwrap_or(f64::INFINITY)));
            }
            continue;
        }
        let span = 0.35 + 0.6 * attempt as f64 / aopts.max_boxes.max(1) as f64;
        attempt += 1;
        report.chosen_box = Some(report.boxes[cb].dims);
        // Local single-cell diffusion + verification for this box's kept labels (one batch).
        let jobs: Vec<&LocalJob> = local_jobs.iter().filter(|j| j.boxi == cb).collect();
        if !jobs.is_empty() {
            let mut lc: Vec<Candidate> = Vec::with_capacity(jobs.len());
            for job in &jobs {
                // The local cell sits at its own grid position (all 120 single-cell
                // configurations are in the training set).
                let mut l = [Primitive::Null; NUM_CELLS];
                l[job.cell] = job.label;
                let ctx = Context::new(l);
                let one = PreparedInput { alignment: input.alignment.clone(), frame: input.frame, samples: job.samples.clone(), area: input.area };
                let mut o = opts.clone();
                o.orientations = OrientationSearch::Identity;
                o.max_fit = f64::INFINITY;
                o.max_in_empty_fraction = 1.0;
                o.min_occupied_fraction = 0.0;
                let mut c = precheck(&one, &ctx, &o)?;
                lay_out(&one, &mut c, &o)?;
                lc.extend(c);
            }
            let mut sub_progress = |f: f64, s: &str| progress.report(span + 0.2 * f, s);
            let mut local_opts = opts.clone();
            local_opts.sampler.steps = aopts.local_steps;
            diffuse_and_verify(model, &mut lc, &local_opts, &mut sub_progress, &mut timings)?;
            for (k, job) in jobs.iter().enumerate() {
                if lc[k].stage == Stage::Verified {
                    report.boxes[cb].locals[job.local].verified.push(job.label.name().to_string());
                }
            }
            // Keep only global candidates whose local labels passed, or are their
            // subregion's best geometric fit (a subregion where no label passed keeps its
            // kept labels and is named if the global stage fails). The best fit stays
            // because a single cell cut out of a part can fail TCV under its true label
            // while a rotated variant passes (BENCHMARKS.md "Main job": the three-hole
            // block's middle cell passed THC+X only, which no genus-3 row can use).
            let locals = &report.boxes[cb].locals;
            let unfiltered = per_box[cb].clone();
            let joint = &joint_found[cb];
            per_box[cb].retain(|(ctx, _)| {
                // the joint search chose its labels on the global fit; the local
                // results do not overrule it
                joint.contains(&ctx.labels) || locals.iter().all(|l| {
                    let lab = ctx.labels[l.subregion.cell];
                    lab == Primitive::Null
                        || l.verified.is_empty()
                        || l.verified.iter().any(|v| v == lab.name())
                        || l.fits.first().is_some_and(|f| f.0 == lab.name())
                })
            });
            // A box whose local results leave no assembly of the input's genus keeps its
            // candidates unfiltered: single-cell verification of a real part is a weaker
            // test than the global one (the three-hole block's middle cell fits and
            // passes THC+X, its row needs THC+Z: BENCHMARKS.md "Main job").
            if per_box[cb].is_empty() {
                per_box[cb] = unfiltered;
            }
        }
        let mut global: Vec<Candidate> = Vec::new();
        let o = &o_global;
        for (ctx, _) in per_box[cb].iter().take(aopts.max_global.max(1)) {
            let known: Vec<Candidate> = prechecked.iter().filter(|c| c.context.labels == ctx.labels).cloned().collect();
            if known.is_empty() {
                global.extend(precheck(&input, ctx, &without_fit_limit(o))?);
            } else {
                global.extend(known);
            }
        }
        limit_fit(&mut global, o, best_overall);
        lay_out(&input, &mut global, o)?;
        let mut sub_progress = |f: f64, s: &str| progress.report(span + 0.2 + 0.4 * f / aopts.max_boxes.max(1) as f64, s);
        diffuse_and_verify(model, &mut global, opts, &mut sub_progress, &mut timings)?;
        let done = global.iter().any(|c| c.stage == Stage::Verified);
        all_global.extend(global);
        if done {
            break;
        }
    }
    if attempt == 0 {
        all_global = passed_over;
    }
    timings.total = t_all.elapsed().as_secs_f64();
    let result = finish(input, input_genus, "auto", all_global, timings, model.generator_name(opts.sampler.kernel_gate));
    Ok((result, report))
}

/// The in-context fit of every feasible label of every subregion: the input's
/// samples against the box's assembly with that label in the subregion's cell and
/// a cube in every other occupied cell, the subregion's own cell's term of
/// [`fit_score_cells`]. (The sum over all cells is worse: the other cells' missing
/// holes give large penalties that vary with the label next to them and drown the
/// cell's own difference.) Unlike a fit of the subregion alone, whose cut faces are
/// far from every single-cell template and leave the labels tied (BHC directions
/// within 10 %), it sees the subregion where the global stage will: on the medium
/// synthetic cases the true label ranks first in every cell (BHC directions 0.004
/// against 0.01 and more; BENCHMARKS.md "Context search").
/// `scores[i][k]` belongs to `labels[i][k]`; null labels get NaN.
pub fn in_context_fits(samples: &[SurfaceSample], subs: &[Subregion], labels: &[Vec<Primitive>]) -> Vec<Vec<f64>> {
    use rayon::prelude::*;
    // cells that may be null (thin subregions) are null in the others' assemblies
    let mut base = [Primitive::Null; NUM_CELLS];
    for (sub, l) in subs.iter().zip(labels) {
        if !l.contains(&Primitive::Null) {
            base[sub.cell] = Primitive::Cube;
        }
    }
    let jobs: Vec<(usize, usize)> = labels.iter().enumerate().flat_map(|(i, l)| l.iter().enumerate().filter(|(_, p)| **p != Primitive::Null).map(move |(k, _)| (i, k))).collect();
    let vals: Vec<f64> = jobs
        .par_iter()
        .map(|&(i, k)| {
            let mut l = base;
            l[subs[i].cell] = labels[i][k];
            let ctx = Context::new(l);
            let per = fit_score_cells(samples, &ctx, AxisRotation::IDENTITY, &polycube_samples(&ctx, FIT_SAMPLES), [1.0; 3]);
            per[subs[i].cell]
        })
        .collect();
    let mut out: Vec<Vec<f64>> = labels.iter().map(|l| vec![f64::NAN; l.len()]).collect();
    for (&(i, k), v) in jobs.iter().zip(vals) {
        out[i][k] = v;
    }
    out
}

/// Most label combinations (products of the kept labels) enumerated per box.
pub const MAX_COMBINATIONS: usize = 20_000;

/// Keep the product of the subregions' kept labels within `budget`: while it is
/// larger, drop the kept label whose in-context fit is worst relative to its
/// cell's best (the least plausible alternative of all cells; a cell keeps at
/// least its best label, and null stays where it is allowed). A full 3 x 2 x 2
/// box of genus-0 cells keeps 3^12 = 531,441 products otherwise, which refused
/// every part of seven or more cells.
fn trim_to_budget(options: &mut [Vec<Primitive>], locals: &mut [LocalResult], budget: usize) {
    loop {
        let product: f64 = options.iter().map(|o| o.len().max(1) as f64).product();
        if product <= budget as f64 {
            break;
        }
        // (cell, fit of its worst kept label over its best)
        let pick = (0..options.len())
            .filter_map(|i| {
                let k = options[i].iter().filter(|p| **p != Primitive::Null).count();
                let fits = &locals[i].fits;
                (k >= 2 && fits.len() >= k).then(|| (i, fits[k - 1].1 / fits[0].1.max(1e-12)))
            })
            .max_by(|a, b| a.1.total_cmp(&b.1));
        let Some((i, _)) = pick else { break };
        // a cell's kept labels are its best-ranked ones, in the order of its fits,
        // so the worst kept label is the last non-null one
        let Some(drop) = options[i].iter().rev().find(|p| **p != Primitive::Null).copied() else { break };
        options[i].retain(|p| *p != drop);
        locals[i].kept.retain(|n| n != drop.name());
    }
}

/// Most sweeps of [`joint_labels`] over the cells.
pub const JOINT_SWEEPS: usize = 4;

/// Joint choice of the subregions' labels on the global fit: starting from each
/// subregion's best local label, each sweep visits the cells in turn and gives each
/// the feasible label that lowers the sum of the per-cell fits (a sum, not the worst
/// cell, so that a change in any cell counts), the others fixed; stops when a sweep
/// changes nothing or after `sweeps`. Returns every visited context that is a
/// valid assembly of the input's genus, with its (worst-cell) fit. Unlike the
/// product of the locally kept labels, it does not depend on the local ranking of
/// labels whose local fits are tied (a cell cut out of an assembly is far from every
/// single-cell template; BENCHMARKS.md "Context search").
pub fn joint_labels(samples: &[SurfaceSample], cells: &[usize], lists: &[Vec<Primitive>], input_genus: i64, sweeps: usize) -> Vec<(Context, f64)> {
    let mut labels = [Primitive::Null; NUM_CELLS];
    for (c, l) in cells.iter().zip(lists) {
        labels[*c] = l.first().copied().unwrap_or(Primitive::Null);
    }
    let mut seen: std::collections::HashMap<[Primitive; NUM_CELLS], f64> = std::collections::HashMap::new();
    let mut found: Vec<(Context, f64)> = Vec::new();
    let mut eval = |l: [Primitive; NUM_CELLS], found: &mut Vec<(Context, f64)>| -> f64 {
        if let Some(&v) = seen.get(&l) {
            return v;
        }
        let ctx = Context::new(l);
        let v = if ctx.occupied().next().is_none() {
            f64::INFINITY
        } else {
            let per = fit_score_cells(samples, &ctx, AxisRotation::IDENTITY, &polycube_samples(&ctx, FIT_SAMPLES), [1.0; 3]);
            let sum: f64 = per.iter().filter(|c| !c.is_nan()).sum();
            let validity = ctx.validity();
            if sum.is_finite() && validity.valid && validity.genus == Some(input_genus) {
                found.push((ctx, per.iter().filter(|c| !c.is_nan()).fold(0.0, |w: f64, c| w.max(*c))));
            }
            sum
        };
        seen.insert(l, v);
        v
    };
    let mut current = eval(labels, &mut found);
    for _ in 0..sweeps {
        let mut changed = false;
        for (c, list) in cells.iter().zip(lists) {
            for &p in list {
                if p == labels[*c] {
                    continue;
                }
                let mut l = labels;
                l[*c] = p;
                let v = eval(l, &mut found);
                if v < current {
                    (current, labels) = (v, l);
                    changed = true;
                }
            }
        }
        if !changed {
            break;
        }
    }
    found
}

/// Per-axis factors that turn a box's grid (cell) units into a length common to
/// every box: the part's extent along an axis over the box's cell count there,
/// divided by the edge of a cube holding 1/12 of the bounding box's volume. A bar
/// three times as long as it is thick measures the same in a 1-cell box (one
/// stretched cell) and in a 3-cell box (three cube cells).
pub fn box_scale(size: [f64; 3], dims: [usize; 3]) -> [f64; 3] {
    let s = size.map(|x| x.max(1e-12));
    let h = (s[0] * s[1] * s[2] / NUM_CELLS as f64).cbrt();
    std::array::from_fn(|a| s[a] / dims[a] as f64 / h)
}

/// The temporary volume misses the surface's volume by at most this fraction, or
/// its resolution is doubled (the test meshes are within 5 % at 48 voxels; a thin
/// wall, like the 12:1 tube of trimesh_round at 48, holds no voxel centre at all).
pub const VOLUME_TOLERANCE: f64 = 0.1;
/// A temporary volume holding less than this fraction of the surface's volume, or
/// more than its inverse, at the finest resolution allowed means walls thinner
/// than a voxel: the automated mode refuses with the reason instead of measuring
/// subregions of a lattice that does not describe the part.
pub const THIN_PART_FRACTION: f64 = 0.5;
/// The doubling stops at this many voxels along the longest side ...
pub const MAX_RESOLUTION: usize = 384;
/// ... or at this many voxels in the bounding grid.
pub const MAX_VOXELS: usize = 4_000_000;

/// The voxel volume at `resolution`, refined by doubling while it misses the
/// surface volume by more than [`VOLUME_TOLERANCE`] (within [`MAX_RESOLUTION`] and
/// [`MAX_VOXELS`]); returns the volume and the resolution used.
fn temporary_volume(mesh: &TriMesh, resolution: usize, surface_volume: f64) -> Result<(VoxelVolume, usize)> {
    let mut res = resolution;
    let mut vol = voxelize(mesh, res)?;
    let size = crate::geometry::Aabb::of_points(&mesh.vertices).size();
    let longest = size[0].max(size[1]).max(size[2]);
    let voxels = |r: usize| -> f64 { size.iter().map(|s| (s / longest * r as f64).ceil().max(1.0)).product() };
    while (vol.volume() - surface_volume).abs() > VOLUME_TOLERANCE * surface_volume && res * 2 <= MAX_RESOLUTION && voxels(res * 2) <= MAX_VOXELS as f64 {
        res *= 2;
        vol = voxelize(mesh, res)?;
    }
    Ok((vol, res))
}

/// The error of an automated run in which no global candidate passed: names the
/// subregions whose local verification failed and suggests ratios.
pub fn auto_failure(result: &PolycubeResult, report: &AutoReport) -> Option<Error> {
    if result.chosen.is_some() {
        return None;
    }
    let Some(b) = report.boxes.iter().find(|b| Some(b.dims) == report.chosen_box) else {
        // no box was tried: every box was refused or passed over
        // boxes that had candidates (passed over on the fit limit) first
        let mut boxes: Vec<&BoxResult> = report.boxes.iter().filter(|b| b.refused.is_some()).collect();
        boxes.sort_by_key(|b| b.candidates == 0);
        let mut why: Vec<String> = boxes.iter().filter_map(|b| b.refused.as_ref().map(|r| format!("{}x{}x{}: {r}", b.dims[0], b.dims[1], b.dims[2]))).collect();
        why.truncate(6);
        return Some(Error::VerificationFailed(format!(
            "automated mode diffused no candidate: no occupied box has one that passes the occupancy pre-check and the fit limit ({}); the part may not be a polycube of the 3x2x2 grid, or try splitting ratios (--ratios X1,X2,X3:Y1,Y2:Z1,Z2)",
            why.join("; ")
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
        "{base}; box {}x{}x{}: {}; try other splitting ratios (--ratios X1,X2,X3:Y1,Y2:Z1,Z2) that put each hole in its own cell",
        b.dims[0],
        b.dims[1],
        b.dims[2],
        if failed.is_empty() { "every subregion passed local verification".to_string() } else { format!("local verification failed in {}", failed.join(", ")) }
    )))
}

/// A single-cell diffusion of the local stage.
struct LocalJob {
    boxi: usize,
    local: usize,
    cell: usize,
    label: Primitive,
    samples: Vec<SurfaceSample>,
}

/// Ratios that split the solid where it is thinnest along X (a heuristic for the error message).
pub fn suggest_ratios(vol: &VoxelVolume, lo: [f64; 3], hi: [f64; 3]) -> String {
    let g = &vol.grid;
    let nx = g.dims[0];
    let mut col = vec![0usize; nx];
    for z in 0..g.dims[2] {
        for y in 0..g.dims[1] {
            for x in 0..nx {
                if g.occ[g.idx(x, y, z)] {
                    col[x] += 1;
                }
            }
        }
    }
    // two cuts at the thinnest slabs in the middle thirds
    let thin = |a: usize, b: usize| (a..b.max(a + 1)).min_by_key(|&i| col[i.min(nx - 1)]).unwrap_or(a);
    let c1 = thin(nx / 6, nx / 2);
    let c2 = thin(nx / 2, 5 * nx / 6);
    let w = hi[0] - lo[0];
    let x1 = ((c1 as f64 + 0.5) * vol.h + vol.lo[0] - lo[0]) / w;
    let x2 = ((c2 as f64 + 0.5) * vol.h + vol.lo[0] - lo[0]) / w;
    format!("{:.2},{:.2},{:.2}:1,1:1,1", x1, (x2 - x1).max(0.05), (1.0 - x2).max(0.05))
}


#[cfg(test)]
mod tests {
    use super::*;
    use crate::search::generate::fit_score;

    /// A closed box [0, a] x [0, b] x [0, c], 12 outward triangles.
    fn box_mesh(a: f64, b: f64, c: f64) -> TriMesh {
        let vertices = (0..8).map(|i| [if i & 1 == 1 { a } else { 0.0 }, if i & 2 == 2 { b } else { 0.0 }, if i & 4 == 4 { c } else { 0.0 }]).collect();
        let quads = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]];
        let triangles = quads.iter().flat_map(|q: &[u32; 4]| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]]).collect();
        TriMesh { vertices, triangles }
    }

    #[test]
    fn a_thin_part_gets_a_finer_temporary_volume() {
        // a 12 x 1 x 0.15 plate: at 48 voxels along 12 (h = 0.25) its thickness holds
        // no voxel centre; doubling reaches a volume within the tolerance
        let m = box_mesh(12.0, 1.0, 0.15);
        let exact = 12.0 * 0.15;
        assert!(m.check().volume.abs() > 0.99 * exact);
        let coarse = voxelize(&m, 48).unwrap();
        assert!((coarse.volume() - exact).abs() > VOLUME_TOLERANCE * exact, "coarse volume {}", coarse.volume());
        let (v, res) = temporary_volume(&m, 48, exact).unwrap();
        assert!(res > 48 && res <= MAX_RESOLUTION, "resolution {res}");
        assert!((v.volume() - exact).abs() <= VOLUME_TOLERANCE * exact, "volume {} at {res}", v.volume());
        // a cube is within the tolerance at once: no refinement
        let c = box_mesh(1.0, 1.0, 1.0);
        assert_eq!(temporary_volume(&c, 48, 1.0).unwrap().1, 48);
    }

    #[test]
    fn a_part_thinner_than_a_voxel_is_refused_with_the_reason() {
        // 1 x 1 x 1e-4: thinner than a voxel even at MAX_RESOLUTION (1/384)
        let m = box_mesh(1.0, 1.0, 1e-4);
        let model = crate::diffusion::Model::default_model().unwrap();
        let e = generate_auto(&model, &m, 0, None, &PolycubeOptions::default(), &AutoOptions::default(), &mut crate::error::NoProgress).unwrap_err();
        assert_eq!(e.status(), crate::error::Status::VerificationFailed);
        let msg = e.to_string();
        assert!(msg.contains("thinner than a voxel") && msg.contains("--labels"), "{msg}");
    }

    #[test]
    fn box_scale_measures_every_box_in_the_same_length() {
        // a 3 x 1 x 1 bar: one stretched cell and three cube cells both become
        // cells of the bar's thickness (12-cell volume cube edge = (3/12)^(1/3))
        let h = (3.0f64 / 12.0).cbrt();
        let one = box_scale([3.0, 1.0, 1.0], [1, 1, 1]);
        let three = box_scale([3.0, 1.0, 1.0], [3, 1, 1]);
        for a in 0..3 {
            assert!((three[a] - 1.0 / h).abs() < 1e-12, "{three:?}");
        }
        assert!((one[0] - 3.0 / h).abs() < 1e-12 && (one[1] - 1.0 / h).abs() < 1e-12, "{one:?}");
    }

    /// The fit samples of a context's exact surface, in the working frame.
    fn exact_samples(ctx: &Context) -> Vec<SurfaceSample> {
        let mesh = crate::polycube::boundary(&ctx.assemble()).to_trimesh();
        let input = prepare_input(&mesh, &PolycubeOptions::default()).unwrap();
        input.samples[..input.samples.len().min(FIT_SAMPLES)].to_vec()
    }

    #[test]
    fn a_three_cell_bar_fits_its_own_box_better_than_one_stretched_cell() {
        // BHC+Y, THC+Z, BHC+Y in a row: in cell units of each box, the single
        // stretched THC shrinks the blind holes below the fit's penalty threshold
        // and the comparison favoured it; in the common unit the true box wins
        let truth = Context::parse("BHC+Y,THC+Z,BHC+Y,0,0,0,0,0,0,0,0,0").unwrap();
        let samples = exact_samples(&truth);
        let fit_sub = &samples[..];
        let best = |ctx: &Context, dims: [usize; 3]| {
            crate::polycube::orientation::rotations()
                .iter()
                .map(|r| {
                    let pts: Vec<[f64; 3]> = fit_sub.iter().map(|s| r.apply(s.point)).collect();
                    let size = crate::geometry::Aabb::of_points(&pts).size();
                    fit_score_scaled(fit_sub, ctx, *r, &polycube_samples(ctx, FIT_SAMPLES), box_scale(size, dims))
                })
                .fold(f64::INFINITY, f64::min)
        };
        let own = best(&truth, [3, 1, 1]);
        let stretched = ["THC+X", "THC+Y", "THC+Z"]
            .iter()
            .map(|l| best(&Context::parse(&format!("{l},0,0,0,0,0,0,0,0,0,0,0")).unwrap(), [1, 1, 1]))
            .fold(f64::INFINITY, f64::min);
        assert!(own < AutoOptions::default().finer_box_factor * stretched, "own box {own}, one stretched cell {stretched}");
    }

    #[test]
    fn joint_labels_find_the_assembly_whatever_the_local_ranking() {
        // a 3 x 1 x 1 bar with a blind hole at each end and a through hole in the
        // middle; every cell's labels are listed worst first, as tied local fits can
        // order them, and the joint search still finds the assembly
        let truth = Context::parse("BHC-X,THC+Z,BHC+X,0,0,0,0,0,0,0,0,0").unwrap();
        let fit_sub = &exact_samples(&truth)[..];
        // put the samples in the grid's orientation (the working frame may permute axes)
        let tgt = polycube_samples(&truth, FIT_SAMPLES);
        let r = *crate::polycube::orientation::rotations().iter().min_by(|a, b| fit_score(fit_sub, &truth, **a, &tgt).total_cmp(&fit_score(fit_sub, &truth, **b, &tgt))).unwrap();
        let samples: Vec<SurfaceSample> = fit_sub.iter().map(|s| SurfaceSample { point: r.apply(s.point), ..*s }).collect();
        let solid: Vec<Primitive> = Primitive::solids().filter(|p| p.family() != Family::Thc).collect();
        let through: Vec<Primitive> = Primitive::solids().filter(|p| p.family() == Family::Thc).collect();
        let worst_first = |ps: &[Primitive], truth: Primitive| -> Vec<Primitive> {
            let mut v: Vec<Primitive> = ps.iter().copied().filter(|p| *p != truth).collect();
            v.push(truth);
            v
        };
        let lists = vec![worst_first(&solid, truth.labels[0]), worst_first(&through, truth.labels[1]), worst_first(&solid, truth.labels[2])];
        let found = joint_labels(&samples, &[0, 1, 2], &lists, 1, JOINT_SWEEPS);
        let best = found.iter().min_by(|a, b| a.1.total_cmp(&b.1)).expect("a genus-1 assembly");
        assert!(crate::polycube::assembly::congruent(&best.0.assemble(), &truth.assemble()), "best {} ({:.4}) of {}", best.0, best.1, found.len());
        assert!(best.1 < 0.01, "fit {}", best.1);
        // the product of the best 3 local labels per cell would not contain it
        assert!(lists.iter().any(|l| !l[..3].contains(l.last().unwrap())));
    }

    fn subregion(cell: usize, fill: f64, genus: i64) -> Subregion {
        Subregion { cell, lo: [0.0; 3], hi: [1.0; 3], fill, components: 1, cavities: 0, genus, empty: fill < AutoOptions::default().min_fill }
    }

    #[test]
    fn in_context_fits_rank_every_true_blind_hole_first() {
        // four blind holes opening four different ways in a 2 x 2 x 1 block: the
        // direction of each is what the subregion-alone fit could not tell apart
        let truth = Context::parse("BHC-X,BHC-Y,0,BHC+Z,BHC+X,0,0,0,0,0,0,0").unwrap();
        assert!(truth.validity().valid);
        let fit_sub = &exact_samples(&truth)[..];
        let tgt = polycube_samples(&truth, FIT_SAMPLES);
        let r = *crate::polycube::orientation::rotations().iter().min_by(|a, b| fit_score(fit_sub, &truth, **a, &tgt).total_cmp(&fit_score(fit_sub, &truth, **b, &tgt))).unwrap();
        let samples: Vec<SurfaceSample> = fit_sub.iter().map(|s| SurfaceSample { point: r.apply(s.point), ..*s }).collect();
        let subs: Vec<Subregion> = [0, 1, 3, 4].iter().map(|&c| subregion(c, 0.9, 0)).collect();
        let labels: Vec<Vec<Primitive>> = subs.iter().map(|s| feasible(s, 0.15).unwrap()).collect();
        let scores = in_context_fits(&samples, &subs, &labels);
        for (i, sub) in subs.iter().enumerate() {
            let best = (0..labels[i].len()).min_by(|&a, &b| scores[i][a].total_cmp(&scores[i][b])).unwrap();
            assert_eq!(labels[i][best], truth.labels[sub.cell], "cell {}: {:?}", sub.cell, labels[i].iter().zip(&scores[i]).collect::<Vec<_>>());
        }
    }

    #[test]
    fn a_thin_subregion_may_be_null() {
        let o = AutoOptions::default();
        // thin: null is one of the labels, and a thin sliver of genus 2 is only null
        let thin = feasible(&subregion(5, 0.08, 0), o.null_fill).unwrap();
        assert!(thin.contains(&Primitive::Null) && thin.contains(&Primitive::Cube), "{thin:?}");
        assert_eq!(feasible(&subregion(5, 0.08, 2), o.null_fill).unwrap(), vec![Primitive::Null]);
        // filled: no null, and genus 2 refuses the box naming the cell
        let full = feasible(&subregion(5, 0.8, 1), o.null_fill).unwrap();
        assert!(!full.contains(&Primitive::Null) && full.len() == 3, "{full:?}");
        let e = feasible(&subregion(5, 0.8, 2), o.null_fill).unwrap_err();
        assert!(e.contains("cell 5") && e.contains("genus 2"), "{e}");
        // empty: null only
        assert_eq!(feasible(&subregion(5, 0.01, 1), o.null_fill).unwrap(), vec![Primitive::Null]);
    }

    #[test]
    fn a_full_box_is_trimmed_to_the_budget_keeping_every_cells_best_label() {
        // twelve genus-0 cells with three kept labels each: 3^12 products
        let names = ["BHC+X", "BHC-Y", "cube"];
        let mut options: Vec<Vec<Primitive>> = Vec::new();
        let mut locals: Vec<LocalResult> = Vec::new();
        for c in 0..NUM_CELLS {
            // cell c's alternatives are (2 + c) and (3 + c) times worse than its best
            let fits: Vec<(String, f64)> = names.iter().enumerate().map(|(k, n)| (n.to_string(), if k == 0 { 0.01 } else { 0.01 * (k + 1 + c) as f64 })).collect();
            options.push(names.iter().map(|n| Primitive::parse(n).unwrap()).collect());
            locals.push(LocalResult { subregion: subregion(c, 0.9, 0), fits, kept: names.iter().map(|n| n.to_string()).collect(), verified: Vec::new() });
        }
        // one thin cell that may also be null
        options[0].push(Primitive::Null);
        locals[0].kept.push("null".into());
        trim_to_budget(&mut options, &mut locals, MAX_COMBINATIONS);
        let product: usize = options.iter().map(|o| o.len()).product();
        assert!(product <= MAX_COMBINATIONS && product > MAX_COMBINATIONS / 3, "{product}");
        for (o, l) in options.iter().zip(&locals) {
            assert_eq!(o[0], Primitive::BhcPx, "every cell keeps its best label");
            assert_eq!(o.len(), l.kept.len());
        }
        assert!(options[0].contains(&Primitive::Null));
        // the least plausible alternatives (the last cells') went first
        assert!(options[NUM_CELLS - 1].len() <= options[1].len(), "{:?}", options.iter().map(|o| o.len()).collect::<Vec<_>>());
    }
}
