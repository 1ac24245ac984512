//! Scaled-Jacobian distributions of several hex meshes in one plot (the paper's
//! histograms, ours next to HexGen's): the fraction of elements per bin of width
//! 0.05 over [-1, 1] (Verdict's hex scaled Jacobian, the minimum over the eight
//! corners), one line per mesh, and one markdown row per mesh.
//!
//! `cargo run --release --example sj_histograms -- OUT.png TITLE NAME=MESH.vtk [NAME=MESH.vtk ...]`
use sddpm::export::plot::{line_png, Series};
use sddpm::hex::quality::scaled_jacobian;

const BINS: usize = 40;

fn main() -> sddpm::Result<()> {
    let a: Vec<String> = std::env::args().collect();
    if a.len() < 4 {
        eprintln!("usage: sj_histograms OUT.png TITLE NAME=MESH.vtk [NAME=MESH.vtk ...]");
        std::process::exit(2);
    }
    let mut names = Vec::new();
    let mut curves = Vec::new();
    println!("| mesh | elements | min SJ | mean SJ | elements < 0.3 | elements >= 0.9 |");
    println!("|---|---:|---:|---:|---:|---:|");
    for spec in &a[3..] {
        let (name, path) = spec.split_once('=').unwrap_or((spec.as_str(), spec.as_str()));
        let m = sddpm::export::vtk::read_vtk_legacy(std::path::Path::new(path))?;
        let q: Vec<f64> = m.elements.iter().map(|e| scaled_jacobian(&e.map(|v| m.nodes[v as usize]))).collect();
        let n = q.len().max(1) as f64;
        let mut counts = [0usize; BINS];
        for &v in &q {
            let b = (((v + 1.0) / 2.0 * BINS as f64) as usize).min(BINS - 1);
            counts[b] += 1;
        }
        let min = q.iter().copied().fold(f64::INFINITY, f64::min);
        let mean = q.iter().sum::<f64>() / n;
        let low = q.iter().filter(|&&v| v < 0.3).count();
        let high = q.iter().filter(|&&v| v >= 0.9).count();
        println!("| {name} | {} | {min:.3} | {mean:.3} | {:.1} % | {:.1} % |", q.len(), 100.0 * low as f64 / n, 100.0 * high as f64 / n);
        names.push(name.to_string());
        // only the bins from the first non-empty one: most meshes have nothing below 0
        curves.push(counts.iter().enumerate().map(|(b, &c)| (-1.0 + (b as f64 + 0.5) * 2.0 / BINS as f64, c as f64 / n)).collect::<Vec<_>>());
    }
    let first = curves.iter().filter_map(|c| c.iter().position(|p| p.1 > 0.0)).min().unwrap_or(0).saturating_sub(1);
    let series: Vec<Series> = names.iter().zip(&curves).map(|(nm, c)| Series { name: nm, points: c[first..].to_vec() }).collect();
    line_png(std::path::Path::new(&a[1]), &series, &a[2], "scaled Jacobian (bin centre, width 0.05)", "fraction of elements", false)?;
    println!("wrote {}", a[1]);
    Ok(())
}
