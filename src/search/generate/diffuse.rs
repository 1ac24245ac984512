//! Diffusion and verification of the candidates that passed the pre-check, and the
//! ranked result.

use super::*;

/// Diffuse and verify the candidates that passed the pre-check (batched).
pub fn diffuse_and_verify(
    model: &Model,
    cands: &mut [Candidate],
    opts: &PolycubeOptions,
    progress: &mut dyn Progress,
    timings: &mut PolycubeTimings,
) -> Result<()> {
    let idx: Vec<usize> = (0..cands.len()).filter(|&i| cands[i].stage == Stage::Pending && cands[i].input.is_some()).collect();
    if idx.is_empty() {
        return Ok(());
    }
    let inputs: Vec<Vec<f32>> = idx.iter().map(|&i| cands[i].input.as_ref().unwrap().tensor.clone()).collect();
    let ctxs: Vec<Context> = idx.iter().map(|&i| cands[i].context).collect();
    let t0 = Instant::now();
    let out = reverse_diffusion(model, &inputs, &ctxs, &opts.sampler, progress)?;
    timings.diffusion += t0.elapsed().as_secs_f64();
    let t0 = Instant::now();
    for (k, &i) in idx.iter().enumerate() {
        let c = &mut cands[i];
        let inp = c.input.as_ref().unwrap();
        let rep = verify_cells(&out.tensors[k], &c.context, &inp.frame, &opts.verify, c.holes_shown);
        c.stage = if !rep.gocc_pass {
            Stage::Gocc
        } else if !rep.tcv_pass {
            Stage::Tcv
        } else {
            Stage::Verified
        };
        c.score = Some(c.fit_mean);
        c.set_output(out.tensors[k].clone(), rep);
    }
    timings.verification += t0.elapsed().as_secs_f64();
    if opts.visible_retry && !opts.sampler.visible_prior {
        visible_retry(model, cands, &idx, opts, progress, timings)?;
    }
    Ok(())
}

/// The second opinion of [`PolycubeOptions::visible_retry`]: the candidates of `idx`
/// that failed verification are diffused again with the visible prior (start step
/// [`VISIBLE_RETRY_START_STEP`]) and verified with visible coverage; one that passes
/// is verified, with that output and report (its score, the mean cell fit, does not
/// depend on the output).
fn visible_retry(model: &Model, cands: &mut [Candidate], idx: &[usize], opts: &PolycubeOptions, progress: &mut dyn Progress, timings: &mut PolycubeTimings) -> Result<()> {
    let again: Vec<usize> = idx.iter().copied().filter(|&i| cands[i].stage != Stage::Verified).collect();
    if again.is_empty() {
        return Ok(());
    }
    let inputs: Vec<Vec<f32>> = again.iter().map(|&i| cands[i].input.as_ref().unwrap().tensor.clone()).collect();
    let ctxs: Vec<Context> = again.iter().map(|&i| cands[i].context).collect();
    let sampler = SamplerOptions { visible_prior: true, start_step: VISIBLE_RETRY_START_STEP, ..opts.sampler.clone() };
    let verify_opts = VerifyOptions { visible_coverage: true, ..opts.verify.clone() };
    let t0 = Instant::now();
    let out = reverse_diffusion(model, &inputs, &ctxs, &sampler, progress)?;
    timings.diffusion += t0.elapsed().as_secs_f64();
    let t0 = Instant::now();
    for (k, &i) in again.iter().enumerate() {
        let c = &mut cands[i];
        let rep = verify_cells(&out.tensors[k], &c.context, &c.input.as_ref().unwrap().frame, &verify_opts, c.holes_shown);
        if rep.passed {
            c.stage = Stage::Verified;
            c.set_output(out.tensors[k].clone(), rep);
            c.visible_retry = true;
        }
    }
    timings.verification += t0.elapsed().as_secs_f64();
    Ok(())
}

/// User-guided mode with complete contexts (one or a stack). `input_genus` is the
/// genus the mesh check measured. A context of another genus is refused before any
/// diffusion.
pub fn generate_from_contexts(
    model: &Model,
    mesh: &TriMesh,
    input_genus: i64,
    contexts: &[Context],
    opts: &PolycubeOptions,
    progress: &mut dyn Progress,
) -> Result<PolycubeResult> {
    let t_all = Instant::now();
    check_contexts(contexts, input_genus)?;
    let mut timings = PolycubeTimings::default();
    let t0 = Instant::now();
    let input = prepare_input(mesh, opts)?;
    timings.align = t0.elapsed().as_secs_f64();
    check_progress(progress, 0.0, "occupancy pre-check")?;
    let t0 = Instant::now();
    let mut cands = Vec::new();
    for c in contexts {
        cands.extend(precheck(&input, c, &without_fit_limit(opts))?);
    }
    limit_fit(&mut cands, opts, f64::INFINITY);
    refuse_worse_than_neighbours(&input, &mut cands, opts.neighbour_fit_ratio);
    lay_out(&input, &mut cands, opts)?;
    timings.precheck = t0.elapsed().as_secs_f64();
    diffuse_and_verify(model, &mut cands, opts, progress, &mut timings)?;
    timings.total = t_all.elapsed().as_secs_f64();
    Ok(finish(input, input_genus, "user", cands, timings, model.generator_name(opts.sampler.kernel_gate)))
}

/// Rank the verified candidates (fewest cells whose label the input's openings
/// do not carry, then the lowest score) and build the result.
pub fn finish(input: PreparedInput, input_genus: i64, source: &'static str, cands: Vec<Candidate>, timings: PolycubeTimings, generator: String) -> PolycubeResult {
    let key = |c: &Candidate| (c.openings_missed, c.score.unwrap_or(f64::INFINITY));
    let chosen = cands
        .iter()
        .enumerate()
        .filter(|(_, c)| c.stage == Stage::Verified && c.output.is_some())
        .min_by(|a, b| {
            let (ka, kb) = (key(a.1), key(b.1));
            ka.0.cmp(&kb.0).then(ka.1.total_cmp(&kb.1))
        })
        .map(|(i, _)| i);
    PolycubeResult { input_genus, source, alignment: input.alignment, frame: input.frame, candidates: cands, chosen, timings, generator, samples: std::sync::Arc::new(input.samples) }
}
