//! Segmentation into charts and chart maps on real test meshes with the contexts
//! that verify (docs/hex.md "Charts and chart maps"): per mesh the number of charts
//! and faces, the charts that are not connected or not of their face's topology,
//! the corners found, and per face whether its chart map exists and how many
//! triangles it flips.
//!
//!   cargo run --release --example charts                     # cgal_eight, cgal_hole, cinolib_torus
//!   cargo run --release --example charts -- MESH LABELS      # one mesh, one context

use sddpm::context::Context;
use sddpm::hex::charts::{segment_and_map, ChartOptions};
use sddpm::hex::HexInput;
use sddpm::mesh::{LoadOptions, TriMesh};
use std::path::PathBuf;
use std::time::Instant;

const MODELS: &[(&str, &str)] = &[
    ("cgal_eight.off", "THC+Z,THC+Z,0,0,0,0,0,0,0,0,0,0"),
    ("cgal_hole.off", "THC+Z,0,0,0,0,0,0,0,0,0,0,0"),
    ("cinolib_torus.obj", "THC+Z,0,0,0,0,0,0,0,0,0,0,0"),
];

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/meshes");
    let runs: Vec<(PathBuf, String)> = if args.len() >= 2 {
        vec![(PathBuf::from(&args[0]), args[1].clone())]
    } else {
        MODELS.iter().map(|(f, l)| (dir.join(f), l.to_string())).collect()
    };
    for (path, labels) in runs {
        let mesh = TriMesh::load(&path, &LoadOptions::default()).expect("load");
        let ctx = Context::parse(&labels).expect("context");
        let input = HexInput::from_user_mesh(&mesh, ctx).expect("input");
        let t0 = Instant::now();
        let c = segment_and_map(&input, &ChartOptions::default()).expect("charts");
        let secs = t0.elapsed().as_secs_f64();
        let seg = &c.segmentation;
        let name = path.file_name().unwrap().to_string_lossy();
        let not_connected = seg.charts.iter().filter(|s| s.components > 1).count();
        let wrong_euler = seg.charts.iter().filter(|s| s.triangles > 0 && s.euler != s.expected_euler).count();
        let empty = seg.charts.iter().filter(|s| s.triangles == 0).count();
        println!(
            "{name} ({labels}): {} triangles, {} faces, {} charts non-empty, {empty} empty, {not_connected} not connected, \
             {wrong_euler} not of the face's topology, corners {}/{}, islands moved {}, ears moved {}, sweeps {}, {secs:.2} s",
            input.surface.triangles.len(),
            c.faces.faces.len(),
            seg.charts.len() - empty,
            seg.corners.iter().flatten().count(),
            seg.corners.len(),
            seg.islands_moved,
            seg.ears_moved,
            seg.sweeps,
        );
        let maps: Vec<_> = c.maps.iter().flatten().collect();
        println!(
            "  chart maps: {} of {}, {} flipped and {} without area in all, {} of them with a flip",
            maps.len(),
            c.maps.len(),
            maps.iter().map(|m| m.flipped).sum::<usize>(),
            maps.iter().map(|m| m.degenerate).sum::<usize>(),
            maps.iter().filter(|m| m.flipped > 0).count()
        );
        for d in &seg.diagnostics {
            println!("  diagnostic: {d}");
        }
        for (f, m) in c.maps.iter().enumerate() {
            match m {
                Ok(m) => println!("  map {}: {} triangles, {} flipped, {} without area", c.faces.name(f), m.triangles.len(), m.flipped, m.degenerate),
                Err(e) => println!("  map {}: none: {e}", c.faces.name(f)),
            }
        }
    }
}
