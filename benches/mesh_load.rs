//! Mesh-load benchmark (our side): for each file, the median over repetitions
//! of TriMesh::load (read + weld + drop unused vertices), check() (topology,
//! measures, self-intersection test) and the genus.
//! Usage: cargo bench --bench mesh_load -- REPEATS FILE...   (benches/run_mesh_bench.sh runs both sides)
//! Prints CSV: file,triangles,load_seconds,check_seconds,total_seconds,genus,volume.

use sddpm::mesh::{LoadOptions, TriMesh};
use std::time::Instant;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).filter(|a| !a.starts_with("--")).collect();
    let (reps, files) = match args.split_first() {
        Some((r, f)) if !f.is_empty() => (r.parse::<usize>().unwrap_or(5).max(1), f.to_vec()),
        _ => {
            eprintln!("usage: cargo bench --bench mesh_load -- REPEATS FILE...");
            std::process::exit(2);
        }
    };
    println!("file,triangles,load_seconds,check_seconds,total_seconds,genus,volume");
    for f in &files {
        let (mut load, mut check, mut total) = (Vec::new(), Vec::new(), Vec::new());
        let (mut genus, mut volume, mut triangles) = (None, 0.0, 0);
        for _ in 0..reps {
            let t0 = Instant::now();
            let m = TriMesh::load(f, &LoadOptions::default()).unwrap_or_else(|e| panic!("{f}: {e}"));
            let t1 = Instant::now();
            let r = m.check();
            genus = r.genus;
            triangles = r.triangles;
            volume = r.volume;
            let t2 = Instant::now();
            load.push((t1 - t0).as_secs_f64());
            check.push((t2 - t1).as_secs_f64());
            total.push((t2 - t0).as_secs_f64());
        }
        let name = f.rsplit('/').next().unwrap_or(f);
        let g = genus.map(|g| g.to_string()).unwrap_or_else(|| "-".into());
        println!("{name},{triangles},{:.6},{:.6},{:.6},{g},{volume:.17e}", median(load), median(check), median(total));
    }
}
