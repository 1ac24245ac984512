//! How far a context's geometric fit is from its best one-cell alternative, for the
//! true context and for one wrong genus-consistent context of each held-in
//! synthetic case (the trials of `sddpm eval-model --wrong`), without diffusion:
//! the measurement behind `PolycubeOptions::neighbour_fit_ratio`.
//!
//! `cargo run --release --example neighbour_fit -- [CASES] [SEED] [MIN] [MAX]`
//! prints one line per context: kind, fit, best alternative's fit, their ratio.
//! `cargo run --release --example neighbour_fit -- mesh PATH CONTEXT` does the same
//! for one real mesh and the context the automated mode chose for it.
use sddpm::search::generate::{best_neighbour, limit_fit, precheck, prepare_input, without_fit_limit, PolycubeOptions, PreparedInput, Stage};
use sddpm::context::Context;
use sddpm::search::eval::wrong_context;
use sddpm::search::synthetic::{cases, SyntheticOptions};

fn main() -> sddpm::Result<()> {
    let a: Vec<String> = std::env::args().collect();
    let opts = PolycubeOptions::default();
    println!("kind,case,context,stage,fit,alt_cell,alt_label,alt_fit,ratio");
    if a.get(1).map(String::as_str) == Some("mesh") {
        let mesh = sddpm::mesh::TriMesh::load(&a[2], &Default::default())?;
        let ctx = sddpm::context::Context::parse(&a[3])?;
        let input = prepare_input(&mesh, &opts)?;
        return line(&input, "real", 0, &ctx, &opts);
    }
    let arg = |i: usize, d: u64| a.get(i).map(|s| s.parse().unwrap()).unwrap_or(d);
    let (n, seed, min, max) = (arg(1, 256) as usize, arg(2, 7000), arg(3, 1) as usize, arg(4, 3) as usize);
    for (i, (ctx, mesh)) in cases(seed, n, min, max, &SyntheticOptions::default()).into_iter().enumerate() {
        let input = prepare_input(&mesh, &opts)?;
        let mut todo = vec![("true", ctx)];
        if let Some(w) = wrong_context(&ctx, i as u64) {
            todo.push(("wrong", w));
        }
        for (kind, c) in todo {
            line(&input, kind, i, &c, &opts)?;
        }
    }
    Ok(())
}

fn line(input: &PreparedInput, kind: &str, i: usize, c: &Context, opts: &PolycubeOptions) -> sddpm::Result<()> {
    let mut cands = precheck(input, c, &without_fit_limit(opts))?;
    limit_fit(&mut cands, opts, f64::INFINITY);
    let cand = &cands[0];
    let stage = if cand.stage == Stage::Occupancy { "refused" } else { "pending" };
    match best_neighbour(input, cand) {
        Some((cell, l, f)) => println!("{kind},{i},{},{stage},{:.5},{cell},{},{:.5},{:.3}", c.names().replace(',', " "), cand.fit, l.name(), f, cand.fit / f),
        None => println!("{kind},{i},{},{stage},{:.5},,,,", c.names().replace(',', " "), cand.fit),
    }
    Ok(())
}
