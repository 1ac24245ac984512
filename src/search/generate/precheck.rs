//! The occupancy pre-check and the geometric fit limit, before any diffusion.

use super::*;

/// Samples used by the cheap pre-check (a prefix of the shared samples).
pub const PRECHECK_SAMPLES: usize = 8192;

/// The occupancy pre-check of one context over the orientation search: the best
/// orientations (lowest surface fraction in empty cells, then fewest starved cells)
/// become candidates; only those that pass get their full inference tensor.
pub fn precheck(input: &PreparedInput, ctx: &Context, opts: &PolycubeOptions) -> Result<Vec<Candidate>> {
    let rots: Vec<AxisRotation> = match opts.orientations {
        OrientationSearch::Identity => vec![rotations()[0]],
        OrientationSearch::SignFlips => rotations()[..4].to_vec(),
        OrientationSearch::All => rotations().to_vec(),
    };
    precheck_in(input, ctx, &rots, opts)
}

/// [`precheck`] over the rotations `rots` of the context against the aligned
/// input (`opts.orientations` is not read): the automated mode's boxes found
/// with the grid's X along another axis of the input check their candidates in
/// that one rotation.
pub fn precheck_in(input: &PreparedInput, ctx: &Context, rots: &[AxisRotation], opts: &PolycubeOptions) -> Result<Vec<Candidate>> {
    let sub = &input.samples[..input.samples.len().min(PRECHECK_SAMPLES)];
    let mut scored: Vec<(usize, Occupancy)> = rots
        .iter()
        .enumerate()
        .filter_map(|(k, r)| occupancy_only(sub, ctx, *r, opts.min_occupied_fraction).map(|o| (k, o)))
        .collect();
    if scored.is_empty() {
        return Err(Error::InvalidContext(format!("{ctx}: no occupied cell")));
    }
    scored.sort_by(|a, b| {
        a.1.starved_cells.len().min(1).cmp(&b.1.starved_cells.len().min(1))
            .then(a.1.in_empty_cells.total_cmp(&b.1.in_empty_cells))
            .then(a.1.starved_cells.len().cmp(&b.1.starved_cells.len()))
            .then(a.0.cmp(&b.0))
    });
    let passes = |o: &Occupancy| o.in_empty_cells <= opts.max_in_empty_fraction && o.starved_cells.is_empty();
    // Among the orientations the occupancy allows, rank by geometric fit.
    let fit_sub = &input.samples[..input.samples.len().min(FIT_SAMPLES)];
    let target = polycube_samples(ctx, FIT_SAMPLES);
    let fit = |r: AxisRotation| super::warp::candidate_fit(fit_sub, ctx, r, &target, opts.warp_fit);
    // (rotation index, occupancy, (worst, mean) fit, registration)
    type Ranked = (usize, Occupancy, (f64, f64), Option<super::warp::Warp>);
    let mut ranked: Vec<Ranked> = scored
        .into_iter()
        .map(|(k, o)| {
            let (f, w) = if passes(&o) { fit(rots[k]) } else { ((f64::INFINITY, f64::INFINITY), None) };
            (k, o, f, w)
        })
        .collect();
    ranked.sort_by(|a, b| (!passes(&a.1)).cmp(&!passes(&b.1)).then(a.2 .0.total_cmp(&b.2 .0)).then(a.0.cmp(&b.0)));
    let n_pass = ranked.iter().filter(|(_, o, f, _)| passes(o) && f.0 <= opts.max_fit).count();
    let keep = if n_pass == 0 { 1 } else { n_pass.min(opts.orientations_per_context.max(1)) };
    let mut out = Vec::with_capacity(keep);
    for (k, occ, (fit, fit_mean), warp) in ranked.into_iter().take(keep) {
        let r = rots[k];
        let ok = passes(&occ) && fit <= opts.max_fit;
        out.push(Candidate {
            context: *ctx,
            labels: ctx.label_values(),
            rotation: r.name(),
            axis_rotation: r,
            occupancy: occ,
            fit,
            fit_mean,
            stage: if ok { Stage::Pending } else { Stage::Occupancy },
            report: None,
            refusal: None,
            visible_retry: false,
            fidelity: None,
            score: None,
            warped: warp.is_some(),
            holes_shown: 0,
            openings_missed: 0,
            warp,
            input: None,
            output: None,
        });
    }
    Ok(out)
}

/// Lay out the inference input (all samples mapped onto the context's box, see
/// [`prepare`]) of every pending candidate that has none yet: called after the fit
/// limit ([`limit_fit`]), so that the candidates it refuses are never laid out.
/// The candidate's occupancy becomes the one measured on all samples.
pub fn lay_out(input: &PreparedInput, cands: &mut [Candidate], opts: &PolycubeOptions) -> Result<()> {
    for c in cands.iter_mut().filter(|c| c.stage == Stage::Pending && c.input.is_none()) {
        let k = rotations().iter().position(|r| *r == c.axis_rotation).unwrap_or(0);
        const LAYOUT_SEED: u64 = 0x9e37;
        let mut rng = seeded_rng(opts.seed ^ LAYOUT_SEED, k as u64);
        let t = prepare(&input.samples, &c.context, c.axis_rotation, c.warp.as_ref(), opts.min_occupied_fraction, &mut rng)?;
        c.occupancy = t.occupancy.clone();
        c.input = Some(t);
    }
    Ok(())
}

/// The options of a pre-check that refuses on occupancy only (the fit limit is
/// applied over all of an input's candidates by [`limit_fit`]).
pub fn without_fit_limit(opts: &PolycubeOptions) -> PolycubeOptions {
    let mut o = opts.clone();
    o.max_fit = f64::INFINITY;
    o
}

/// The pre-check's fit limit over all of an input's candidates: a candidate that
/// passed the occupancy test is diffused when its fit is at most `max_fit` or at
/// most `relative_fit` times the best fit among them (and at most
/// `relative_fit_cap`); the others are refused
/// (stage `Occupancy`, their fit in the report).
/// `best_elsewhere`: the best fit of candidates prechecked apart from these (the
/// automated mode's other occupied boxes), so that a box whose every context fits
/// far worse than another box's best is not diffused on its own terms.
pub fn limit_fit(cands: &mut [Candidate], opts: &PolycubeOptions, best_elsewhere: f64) {
    let best = cands.iter().filter(|c| c.stage == Stage::Pending).map(|c| c.fit).fold(best_elsewhere, f64::min);
    let rel = if opts.relative_fit > 0.0 && best.is_finite() { (opts.relative_fit * best).min(opts.relative_fit_cap) } else { 0.0 };
    let limit = opts.max_fit.max(rel);
    for c in cands.iter_mut().filter(|c| c.stage == Stage::Pending) {
        if !(c.fit <= limit) {
            c.stage = Stage::Occupancy;
            c.input = None;
        }
    }
}
