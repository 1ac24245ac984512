//! The hierarchical verification funnel of the paper on a four-cell genus-3 case:
//! the exact assembly of CONTEXT (default THC+Y,THC+Y,cube,THC+Y in a 2 x 1 x 2
//! box), smoothly warped, through the automated mode with the box's splitting
//! ratios; prints how many candidates survive each stage (occupancy / genus,
//! local verification, pre-check, global GOCC, global TCV).
//!
//! `cargo run --release --example funnel -- [CONTEXT] [RATIOS] [WARP]`
use sddpm::search::auto::{AutoOptions, SplitRatios};
use sddpm::search::generate::{PolycubeOptions, Stage};
use sddpm::context::Context;
use sddpm::diffusion::Model;
use sddpm::error::NoProgress;
use sddpm::pipeline::{generate_polycube, ContextRequest};

fn main() -> sddpm::Result<()> {
    let a: Vec<String> = std::env::args().collect();
    let ctx = Context::parse(a.get(1).map(String::as_str).unwrap_or("THC+Y,THC+Y,null,null,null,null,cube,THC+Y,null,null,null,null"))?;
    let ratios = SplitRatios::parse(a.get(2).map(String::as_str).unwrap_or("1,1:1:1,1"))?;
    let warp: f64 = a.get(3).map(|s| s.parse().unwrap()).unwrap_or(0.04);
    let v = ctx.validity();
    let genus = v.genus.expect("a valid context");
    let mut mesh = sddpm::polycube::boundary(&ctx.assemble()).to_trimesh();
    // a smooth warp of amplitude `warp` x the part's size, so that the input is not the template
    let bb = sddpm::geometry::Aabb::of_points(&mesh.vertices);
    let size = bb.size().iter().copied().fold(0.0, f64::max);
    for p in mesh.vertices.iter_mut() {
        let q = *p;
        p[0] += warp * size * (1.3 * q[1] / size + 0.7 * q[2] / size).sin();
        p[1] += warp * size * (0.9 * q[2] / size + 1.1 * q[0] / size).sin();
        p[2] += warp * size * (1.7 * q[0] / size).sin();
    }
    let report = mesh.validate()?;
    println!("input: {ctx} (genus {genus}), {} triangles, measured genus {:?}", mesh.triangles.len(), report.genus);
    let model = Model::default_model()?;
    let t = std::time::Instant::now();
    let (pr, auto, err) = generate_polycube(&model, &mesh, genus, &ContextRequest::Ratios(ratios), &PolycubeOptions::default(), &AutoOptions::default(), &mut NoProgress)?;
    let secs = t.elapsed().as_secs_f64();
    if let Some(a) = &auto {
        for b in &a.boxes {
            println!("box {:?}: {} genus-consistent global candidates; refused: {:?}", b.dims, b.candidates, b.refused);
            let mut products = 1usize;
            for l in &b.locals {
                products *= l.fits.len().max(1);
                println!(
                    "  subregion cell {}: genus {}, fill {:.2}, feasible {} ({}), locally verified {:?}, kept {:?}",
                    l.subregion.cell,
                    l.subregion.genus,
                    l.subregion.fill,
                    l.fits.len(),
                    l.fits.iter().map(|(n, f)| format!("{n} {f:.3}")).collect::<Vec<_>>().join(", "),
                    l.verified,
                    l.kept
                );
            }
            println!("  label products of the feasible labels: {products}");
        }
    }
    let n = pr.candidates.len();
    let count = |s: &[Stage]| pr.candidates.iter().filter(|c| s.contains(&c.stage)).count();
    let diffused = count(&[Stage::Gocc, Stage::Tcv, Stage::Verified]);
    let gocc = count(&[Stage::Tcv, Stage::Verified]);
    let tcv = count(&[Stage::Verified]);
    println!("| stage | candidates | pass rate |");
    println!("|---|---:|---:|");
    println!("| global candidates (valid assembly, input's genus, kept labels) | {n} | |");
    println!("| pre-check (occupancy + fit limit) | {diffused} | {:.0} % |", 100.0 * diffused as f64 / n.max(1) as f64);
    println!("| global GOCC | {gocc} | {:.0} % |", 100.0 * gocc as f64 / diffused.max(1) as f64);
    println!("| global TCV | {tcv} | {:.0} % |", 100.0 * tcv as f64 / gocc.max(1) as f64);
    for c in &pr.candidates {
        println!("  {} {} fit {:.4} stage {:?}{}", c.context, c.rotation, c.fit, c.stage, if pr.chosen.is_some_and(|i| std::ptr::eq(&pr.candidates[i], c)) { " (chosen)" } else { "" });
    }
    println!("{:.1} s; {}", secs, err.map(|e| e.to_string()).unwrap_or_else(|| "verified".into()));
    Ok(())
}
