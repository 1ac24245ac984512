//! Each box of the automated mode (step 2 and the local ranking of step 3): the
//! aligned bounding box split into the box's subregions, their feasible labels
//! ranked by their in-context fit, and the products of the kept labels that are
//! valid assemblies of the input's genus, the box's global candidates.

use super::local::{subregion_samples, LocalJob};
use super::rank::in_context_fits;
use super::volume::{split_points, subregions, Subregion};
use super::{AutoReport, BoxResult, LocalResult, Run, SplitRatios};
use crate::context::Context;
use crate::error::{check_progress, Progress, Result};
use crate::polycube::{Family, Primitive, NUM_CELLS};
use std::collections::HashSet;

/// What the search keeps of one box between its stages (its record is a
/// [`BoxResult`] of the report).
pub(super) struct BoxWork {
    /// The global candidates with their worst-cell fit (0 until ranked), best
    /// first once ranked.
    pub cands: Vec<(Context, f64)>,
    /// The cells and every feasible label of each, best in-context fit first, for
    /// the joint label search (none when the box is refused).
    pub joint: Option<(Vec<usize>, Vec<Vec<Primitive>>)>,
    /// The contexts the joint label search found.
    pub joint_found: HashSet<[Primitive; NUM_CELLS]>,
    /// The local stage's single-cell diffusions.
    pub local_jobs: Vec<LocalJob>,
    /// The frame (index into the runs, [`super::frames::FRAMES`]) the box splits.
    pub frame: usize,
}

/// The boxes tried, each with its frame (an index of [`super::frames::FRAMES`]):
/// the caller's split, or every box of 1..3 x 1..2 x 1..2 equal cells of the
/// aligned frame and, in each of the `frames - 1` other frames, those with three
/// cells along X (the others are boxes of the aligned frame turned); fewest cells
/// first, a box's other frames right after it.
pub(super) fn box_shapes(ratios: Option<&SplitRatios>, frames: usize) -> Vec<(usize, SplitRatios)> {
    match ratios {
        Some(r) => vec![(0, r.clone())],
        None => {
            let mut v = Vec::new();
            for nx in 1..=3 {
                for ny in 1..=2 {
                    for nz in 1..=2 {
                        for f in 0..frames.max(1) {
                            if f == 0 || nx == 3 {
                                v.push((f, SplitRatios::equal(nx, ny, nz)));
                            }
                        }
                    }
                }
            }
            v.sort_by_key(|(f, r)| box_key(r.dims(), *f));
            v
        }
    }
}

/// The order of the boxes: fewest cells first, then more cells along X, then
/// along Y, then the frame.
fn box_key(d: [usize; 3], frame: usize) -> (usize, std::cmp::Reverse<usize>, std::cmp::Reverse<usize>, usize) {
    (d[0] * d[1] * d[2], std::cmp::Reverse(d[0]), std::cmp::Reverse(d[1]), frame)
}

/// Put the boxes and their records in the order of [`box_shapes`] (fewest cells
/// first, a box's other frames right after it), which [`super::rank::box_order`]
/// reads as coarsest first.
pub(super) fn sort_boxes(boxes: &mut Vec<BoxWork>, records: &mut Vec<BoxResult>) {
    let mut pairs: Vec<(BoxWork, BoxResult)> = boxes.drain(..).zip(records.drain(..)).collect();
    pairs.sort_by_key(|(w, r)| box_key(r.dims, w.frame));
    for (w, r) in pairs {
        boxes.push(w);
        records.push(r);
    }
}

/// Analyse every box of `shapes` in its frame's run ([`analyse_box`]), recording
/// each in `report`; progress goes through `span`.
pub(super) fn analyse_boxes(runs: &[Run], shapes: &[(usize, SplitRatios)], span: (f64, f64), report: &mut AutoReport, progress: &mut dyn Progress) -> Result<Vec<BoxWork>> {
    let mut boxes = Vec::with_capacity(shapes.len());
    for (bi, (f, r)) in shapes.iter().enumerate() {
        check_progress(progress, span.0 + (span.1 - span.0) * bi as f64 / shapes.len() as f64, "subregions")?;
        let (br, mut work) = analyse_box(&runs[*f], r);
        work.frame = *f;
        report.boxes.push(br);
        boxes.push(work);
    }
    Ok(boxes)
}

/// One box: its subregions, their feasible labels ranked and kept, and the valid
/// assemblies of the input's genus among the products of the kept labels; the
/// record says why the box cannot hold the input, if it cannot.
fn analyse_box(run: &Run, r: &SplitRatios) -> (BoxResult, BoxWork) {
    let bb = &run.volume.bb;
    let xs = split_points(bb.min[0], bb.max[0], &r.x);
    let ys = split_points(bb.min[1], bb.max[1], &r.y);
    let zs = split_points(bb.min[2], bb.max[2], &r.z);
    let subs = subregions(&run.volume.vol, &run.volume.clean, &xs, &ys, &zs, run.aopts.min_fill);
    let mut br = BoxResult { dims: r.dims(), frame: run.frame.name(), ratios: r.clone(), fitted: false, locals: Vec::new(), candidates: 0, best_fit: None, best_fit_common: None, joint_candidates: 0, refused: None };
    let mut work = BoxWork { cands: Vec::new(), joint: None, joint_found: HashSet::new(), local_jobs: Vec::new(), frame: 0 };
    let labels_of = match subs.iter().map(|sub| feasible(sub, run.aopts.null_fill)).collect::<std::result::Result<Vec<_>, String>>() {
        Ok(l) => l,
        Err(e) => {
            br.refused = Some(e);
            return (br, work);
        }
    };
    let (mut options, full) = rank_labels(run, &subs, &labels_of, &mut br.locals, &mut work.local_jobs);
    trim_to_budget(&mut options, &mut br.locals, MAX_COMBINATIONS);
    work.local_jobs.retain(|j| options[j.local].contains(&j.label));
    // Cells of the box sit at grid cells (0..nx, 0..ny, 0..nz); the rest are null.
    let cells: Vec<usize> = br.locals.iter().map(|l| l.subregion.cell).collect();
    work.joint = Some((cells.clone(), full));
    match assemblies(&cells, &options, run.genus) {
        Err(e) => br.refused = Some(e),
        Ok(cands) => {
            br.candidates = cands.len();
            if cands.is_empty() {
                let genera: Vec<String> = br.locals.iter().map(|l| format!("cell {}: {}", l.subregion.cell, if l.subregion.empty { "empty".to_string() } else { format!("genus {}", l.subregion.genus) })).collect();
                br.refused = Some(format!("no valid assembly of the subregions' labels has genus {} ({})", run.genus, genera.join(", ")));
            }
            work.cands = cands;
        }
    }
    (br, work)
}

/// The labels a subregion can take: null when empty; by its genus (0: cube, the
/// six BHC and the three THC; 1: the three THC) otherwise, with null too when it is filled less than
/// `null_fill`; a genus of 2 or more refuses the box unless the subregion is that
/// thin.
pub(super) fn feasible(sub: &Subregion, null_fill: f64) -> std::result::Result<Vec<Primitive>, String> {
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

/// Rank each subregion's feasible labels by their in-context fit and keep the
/// best `local_keep` of them (and null where the subregion may be null), recording
/// each subregion in `locals` and queueing the kept labels' single-cell diffusions
/// in `jobs` (with `local_diffusion`). Returns the kept labels and every feasible
/// label, best first, of each subregion.
fn rank_labels(run: &Run, subs: &[Subregion], labels_of: &[Vec<Primitive>], locals: &mut Vec<LocalResult>, jobs: &mut Vec<LocalJob>) -> (Vec<Vec<Primitive>>, Vec<Vec<Primitive>>) {
    let aopts = run.aopts;
    let mut options: Vec<Vec<Primitive>> = Vec::new();
    // every feasible label of each subregion, best in-context fit first
    let mut full: Vec<Vec<Primitive>> = Vec::new();
    let scores = in_context_fits(run.fit_sub, subs, labels_of, aopts.register_cells);
    for (si, sub) in subs.iter().enumerate() {
        let labels = &labels_of[si];
        let mut lr = LocalResult { subregion: sub.clone(), fits: Vec::new(), kept: Vec::new(), verified: Vec::new() };
        if labels[..] == [Primitive::Null] {
            lr.kept.push("null".into());
            full.push(labels.clone());
            options.push(labels.clone());
            locals.push(lr);
            continue;
        }
        let mut scored: Vec<(Primitive, f64)> = labels.iter().copied().zip(scores[si].iter().copied()).filter(|(p, _)| *p != Primitive::Null).collect();
        scored.sort_by(|a, b| a.1.total_cmp(&b.1));
        if aopts.opening_labels {
            // stable: each part keeps the order of the fit
            scored.sort_by_key(|(p, _)| !sub.openings.carries(*p));
        }
        let may_be_null = labels.contains(&Primitive::Null);
        full.push(scored.iter().map(|(p, _)| *p).chain(may_be_null.then_some(Primitive::Null)).collect());
        lr.fits = scored.iter().map(|(p, f)| (p.name().to_string(), *f)).collect();
        let mut kept: Vec<Primitive> = scored.iter().take(aopts.local_keep.max(1)).map(|(p, _)| *p).collect();
        if aopts.local_diffusion {
            let samples = subregion_samples(run.input, &run.volume.vol, sub, run.volume.bb.min, run.volume.bb.max, run.opts.seed);
            for &p in &kept {
                jobs.push(LocalJob { local: locals.len(), cell: sub.cell, label: p, samples: samples.clone() });
            }
        }
        if may_be_null {
            kept.push(Primitive::Null);
        }
        lr.kept = kept.iter().map(|p| p.name().to_string()).collect();
        options.push(kept);
        locals.push(lr);
    }
    (options, full)
}

/// Each cell's best labels that the trim to the budget removes only after every
/// cell's lower-ranked ones: with five labels kept, a box of seven or more cells
/// exceeds the budget, and a trim by fit ratio alone dropped third-ranked true
/// labels that three kept labels never lost (BENCHMARKS.md "Labels kept per
/// subregion").
pub const TRIM_PROTECTED: usize = 3;

/// Most label combinations (products of the kept labels) enumerated per box.
pub const MAX_COMBINATIONS: usize = 20_000;

/// Keep the product of the subregions' kept labels within `budget`: while it is
/// larger, drop the kept label whose in-context fit is worst relative to its
/// cell's best (the least plausible alternative of all cells; a cell keeps at
/// least its best label, and its best [`TRIM_PROTECTED`] while any cell has
/// more; null stays where it is allowed). A full 3 x 2 x 2
/// box of genus-0 cells keeps 3^12 = 531,441 products otherwise, which refused
/// every part of seven or more cells.
pub(super) fn trim_to_budget(options: &mut [Vec<Primitive>], locals: &mut [LocalResult], budget: usize) {
    loop {
        let product: f64 = options.iter().map(|o| o.len().max(1) as f64).product();
        if product <= budget as f64 {
            break;
        }
        // (cell, fit of its worst kept label over its best); the labels ranked
        // below TRIM_PROTECTED go first, from every cell, before any cell loses
        // one of its best TRIM_PROTECTED
        let candidates = |floor: usize| {
            (0..options.len())
                .filter_map(|i| {
                    let k = options[i].iter().filter(|p| **p != Primitive::Null).count();
                    let fits = &locals[i].fits;
                    (k > floor && fits.len() >= k).then(|| (i, fits[k - 1].1 / fits[0].1.max(1e-12)))
                })
                .max_by(|a, b| a.1.total_cmp(&b.1))
        };
        let pick = candidates(TRIM_PROTECTED).or_else(|| candidates(1));
        let Some((i, _)) = pick else { break };
        // a cell's kept labels are its best-ranked ones, in the order of its fits,
        // so the worst kept label is the last non-null one
        let Some(drop) = options[i].iter().rev().find(|p| **p != Primitive::Null).copied() else { break };
        options[i].retain(|p| *p != drop);
        locals[i].kept.retain(|n| n != drop.name());
    }
}

/// The products of the kept labels (`options[i]` for the cell `cells[i]`, every
/// other cell null) that are valid assemblies of genus `input_genus`; more than
/// [`MAX_COMBINATIONS`] products refuse the box.
fn assemblies(cells: &[usize], options: &[Vec<Primitive>], input_genus: i64) -> std::result::Result<Vec<(Context, f64)>, String> {
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
            return Err(format!("{} label combinations; use --ratios with fewer cells", combos.len()));
        }
    }
    let mut cands: Vec<(Context, f64)> = Vec::new();
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
    Ok(cands)
}
