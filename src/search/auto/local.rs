//! The local stage of the automated mode (step 3): each kept label of a
//! subregion diffused as a single cell on the subregion's surface and verified, a
//! box's all in one batch; the box's global candidates then keep the labels that
//! passed.

use super::super::generate::{diffuse_and_verify, lay_out, precheck, Candidate, OrientationSearch, PolycubeTimings, PreparedInput, Stage};
use super::boxes::BoxWork;
use super::volume::Subregion;
use super::{LocalResult, Run};
use crate::context::Context;
use crate::diffusion::Model;
use crate::error::{Progress, Result};
use crate::geometry::rng::seeded_rng;
use crate::geometry::voxel::VoxelVolume;
use crate::geometry::SurfaceSample;
use crate::polycube::{Primitive, NUM_CELLS};
use rand::RngExt;
use std::collections::HashSet;

/// A single-cell diffusion of the local stage.
pub(super) struct LocalJob {
    /// The subregion's index in the box's `locals`.
    pub local: usize,
    pub cell: usize,
    pub label: Primitive,
    pub samples: Vec<SurfaceSample>,
}

/// The local stage of one box: its jobs diffused and verified in one batch
/// (`progress` from 0 to 1), the labels that passed recorded in `locals`, and the
/// box's candidates filtered by them ([`keep_locally_verified`]).
pub(super) fn local_stage(run: &Run, model: &Model, work: &mut BoxWork, locals: &mut [LocalResult], progress: &mut dyn Progress, timings: &mut PolycubeTimings) -> Result<()> {
    if work.local_jobs.is_empty() {
        return Ok(());
    }
    let verified = diffuse_cells(run, model, &work.local_jobs, progress, timings)?;
    for (job, passed) in work.local_jobs.iter().zip(verified) {
        if passed {
            locals[job.local].verified.push(job.label.name().to_string());
        }
    }
    keep_locally_verified(&mut work.cands, locals, &work.joint_found);
    Ok(())
}

/// Diffuse and verify each job's label as a single cell on its subregion's
/// samples; whether each passed.
fn diffuse_cells(run: &Run, model: &Model, jobs: &[LocalJob], progress: &mut dyn Progress, timings: &mut PolycubeTimings) -> Result<Vec<bool>> {
    let (input, opts) = (run.input, run.opts);
    let mut lc: Vec<Candidate> = Vec::with_capacity(jobs.len());
    for job in jobs {
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
    let mut local_opts = opts.clone();
    local_opts.sampler.steps = run.aopts.local_steps;
    diffuse_and_verify(model, &mut lc, &local_opts, progress, timings)?;
    Ok((0..jobs.len()).map(|k| lc[k].stage == Stage::Verified).collect())
}

/// Keep only global candidates whose local labels passed, or are their
/// subregion's best geometric fit (a subregion where no label passed keeps its
/// kept labels and is named if the global stage fails). The best fit stays
/// because a single cell cut out of a part can fail TCV under its true label
/// while a rotated variant passes (BENCHMARKS.md "Main job": the three-hole
/// block's middle cell passed THC+X only, which no genus-3 row can use).
fn keep_locally_verified(cands: &mut Vec<(Context, f64)>, locals: &[LocalResult], joint: &HashSet<[Primitive; NUM_CELLS]>) {
    let unfiltered = cands.clone();
    cands.retain(|(ctx, _)| {
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
    if cands.is_empty() {
        *cands = unfiltered;
    }
}

/// Samples of a subregion: the input's samples inside its box and samples on the
/// faces where the box cuts the solid, so that the subregion's surface is closed.
pub(super) fn subregion_samples(input: &PreparedInput, vol: &VoxelVolume, sub: &Subregion, bb_lo: [f64; 3], bb_hi: [f64; 3], seed: u64) -> Vec<SurfaceSample> {
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
