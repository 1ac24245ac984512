//! The paper's IGA temperature analysis, on the spline volume: steady heat
//! conduction with uniform internal heat generation, -k ΔT = q in the volume, the
//! surface held at T = 0 (a cooled part). Solved with the project's IGA solver on
//! the TH-spline3D of a hex mesh, then rendered: the spline sampled at 7 x 7 x 7
//! points per element, the half of the part nearer the camera cut away so the hot
//! core shows, points coloured by T (blue = 0, red = max) with a colour bar.
//!
//! `cargo run --release --example iga_temperature -- MESH.vtk|.vtu|.mesh|.k OUT.png`
//! (q / k = 1 / L^2 with L the bounding-box diagonal, so T is dimensionless.)
use sddpm::error::NoProgress;
use sddpm::export::render::{render, Camera, Layer};
use sddpm::spline::iga::{solve_poisson, PoissonOptions};
use sddpm::spline::{build_spline, SplineOptions};
use std::path::Path;

fn colour(s: f64) -> [u8; 3] {
    // blue -> cyan -> green -> yellow -> red
    let stops = [[49.0, 54.0, 149.0], [69.0, 117.0, 180.0], [116.0, 173.0, 209.0], [171.0, 217.0, 233.0], [254.0, 224.0, 144.0], [253.0, 174.0, 97.0], [244.0, 109.0, 67.0], [215.0, 48.0, 39.0], [165.0, 0.0, 38.0]];
    let x = s.clamp(0.0, 1.0) * (stops.len() - 1) as f64;
    let i = (x.floor() as usize).min(stops.len() - 2);
    let f = x - i as f64;
    let c: Vec<u8> = (0..3).map(|k| (stops[i][k] * (1.0 - f) + stops[i + 1][k] * f).round() as u8).collect();
    [c[0], c[1], c[2]]
}

fn main() -> sddpm::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    if args.len() < 3 {
        eprintln!("usage: iga_temperature MESH OUT.png");
        std::process::exit(2);
    }
    let path = Path::new(&args[1]);
    let hex = match path.extension().and_then(|e| e.to_str()) {
        Some("vtu") => sddpm::export::hexfmt::read_vtu(path)?.0,
        Some("mesh") => sddpm::export::hexfmt::read_medit(path)?,
        Some("k") => sddpm::export::hexfmt::read_lsdyna(path)?,
        _ => sddpm::export::vtk::read_vtk_legacy(path)?,
    };
    let t0 = std::time::Instant::now();
    let sp = build_spline(&hex, None, &SplineOptions::default(), &mut NoProgress)?;
    let t_spline = t0.elapsed().as_secs_f64();
    let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    for p in &hex.nodes {
        for a in 0..3 {
            lo[a] = lo[a].min(p[a]);
            hi[a] = hi[a].max(p[a]);
        }
    }
    let diag2: f64 = (0..3).map(|a| (hi[a] - lo[a]).powi(2)).sum();
    let q = 1.0 / diag2;
    let sol = solve_poisson(&sp, |_| q, |_| 0.0, &PoissonOptions::default())?;
    // sample every element
    let g: Vec<f64> = (0..7).map(|i| (i as f64 + 0.5) / 7.0).collect();
    let mut pts = Vec::new();
    let mut vals = Vec::new();
    for e in 0..sp.num_elements() {
        for &w in &g {
            for &v in &g {
                for &u in &g {
                    pts.push(sp.evaluate(e, u, v, w)?.0);
                    vals.push(sol.value(&sp, e, u, v, w)?);
                }
            }
        }
    }
    let tmax = vals.iter().cloned().fold(0.0f64, f64::max);
    let tmin = vals.iter().cloned().fold(f64::INFINITY, f64::min);
    // cut away the half nearer the camera: keep points behind the plane through the
    // centre whose normal is the direction towards the viewer
    let cam = Camera::default();
    let (az, el) = (cam.azimuth.to_radians(), cam.elevation.to_radians());
    let towards = [el.cos() * az.cos(), el.cos() * az.sin(), el.sin()];
    let c = [(lo[0] + hi[0]) / 2.0, (lo[1] + hi[1]) / 2.0, (lo[2] + hi[2]) / 2.0];
    let keep: Vec<usize> = (0..pts.len()).filter(|&i| (0..3).map(|a| (pts[i][a] - c[a]) * towards[a]).sum::<f64>() <= 0.0).collect();
    let kp: Vec<[f64; 3]> = keep.iter().map(|&i| pts[i]).collect();
    let kc: Vec<[u8; 3]> = keep.iter().map(|&i| colour(vals[i] / tmax.max(1e-300))).collect();
    let (w, h) = (900usize, 760usize);
    let mut canvas = render(&[Layer::Points { points: &kp, colours: &kc, radius_px: 2.6 }], w, h, cam)?;
    // colour bar on the right edge, T = 0 at the bottom, max at the top
    for y in 60..h - 60 {
        let s = 1.0 - (y - 60) as f64 / (h - 121) as f64;
        for x in w - 40..w - 20 {
            canvas.rgb[y * w + x] = colour(s);
        }
    }
    canvas.save_png(Path::new(&args[2]))?;
    println!(
        "{}: {} elements, {} basis functions ({} on the boundary), spline {:.2} s, solve {:.2} s ({}, {} iterations), T in [{:.3e}, {:.4e}] (q/k = 1/L^2, L = {:.4})",
        path.file_name().unwrap().to_string_lossy(),
        sp.num_elements(),
        sol.dofs,
        sol.boundary_dofs,
        t_spline,
        sol.seconds,
        sol.solver,
        sol.iterations,
        tmin,
        tmax,
        diag2.sqrt()
    );
    Ok(())
}
