//! `sddpm info MESH [--json]`: read, weld, check and measure a mesh.

use super::fail;
use clap::Args;
use sddpm::mesh::{LoadOptions, LoadStats, MeshReport, Severity, TriMesh, DEFAULT_WELD_TOLERANCE};
use serde_json::{json, Value};
use std::path::PathBuf;

#[derive(Args, Debug)]
pub struct InfoArgs {
    /// Mesh file (.obj, .stl, .off).
    pub mesh: PathBuf,
    /// Print one JSON object on stdout instead of text.
    #[arg(long)]
    pub json: bool,
    /// Weld tolerance relative to the bounding-box diagonal (negative: no welding).
    #[arg(long, default_value_t = DEFAULT_WELD_TOLERANCE, allow_negative_numbers = true)]
    pub weld_tolerance: f64,
    /// Explicit repair: re-orient a closed manifold consistently outward.
    #[arg(long)]
    pub repair_orientation: bool,
}

pub fn run(args: &InfoArgs) -> i32 {
    let opts = LoadOptions {
        weld_tolerance: args.weld_tolerance,
        repair_orientation: args.repair_orientation,
        ..LoadOptions::default()
    };
    let path = args.mesh.display().to_string();
    let (mesh, stats) = match TriMesh::load_with_stats(&args.mesh, &opts) {
        Ok(x) => x,
        Err(e) => {
            if args.json {
                println!("{}", json!({ "path": path, "ok": false, "status": e.status().name(), "error": e.to_string() }));
            }
            return fail(e);
        }
    };
    let report = mesh.check();
    let error = report.to_error();
    if args.json {
        println!("{}", to_json(&path, &stats, &report, error.as_ref().map(|e| e.to_string())));
    } else {
        print_text(&path, &stats, &report);
    }
    match error {
        Some(e) => fail(format!("{path}: {e}")),
        None => 0,
    }
}

fn to_json(path: &str, stats: &LoadStats, report: &MeshReport, error: Option<String>) -> Value {
    let mut v = serde_json::to_value(report).expect("report serialises");
    let obj = v.as_object_mut().expect("report is an object");
    obj.insert("path".into(), json!(path));
    obj.insert("oriented".into(), json!(report.oriented_outward));
    obj.insert("bbox".into(), json!({ "min": report.bbox_min, "max": report.bbox_max }));
    obj.insert("load".into(), serde_json::to_value(stats).expect("stats serialise"));
    obj.insert("ok".into(), json!(error.is_none()));
    obj.insert("error".into(), json!(error));
    v
}

fn yes(b: bool) -> &'static str {
    if b {
        "yes"
    } else {
        "no"
    }
}

fn print_text(path: &str, s: &LoadStats, r: &MeshReport) {
    println!("mesh:                 {path}");
    println!(
        "read:                 {} ({} vertices, {} triangles{}); welded {} vertices within {:.3e}; removed {} unused{}",
        s.format.unwrap_or("?"),
        s.vertices_read,
        s.triangles_read,
        if s.polygons_split > 0 { format!(", {} polygons split", s.polygons_split) } else { String::new() },
        s.vertices_merged,
        s.weld_distance,
        s.unreferenced_removed,
        if s.triangles_flipped > 0 { format!("; re-oriented {} triangles", s.triangles_flipped) } else { String::new() }
    );
    println!("vertices:             {}", r.vertices);
    println!("triangles:            {}", r.triangles);
    println!("edges:                {}", r.edges);
    println!("components:           {}", r.components);
    println!("closed:               {} ({} boundary edges in {} loops)", yes(r.closed), r.boundary_edges, r.boundary_loops);
    println!(
        "manifold:             {} ({} non-manifold edges, {} non-manifold vertices)",
        yes(r.manifold),
        r.non_manifold_edges,
        r.non_manifold_vertices
    );
    println!(
        "oriented:             {} (consistent: {}, {} inconsistent edges, outward: {})",
        yes(r.oriented_outward),
        yes(r.orientation_consistent),
        r.inconsistent_edges,
        yes(r.oriented_outward)
    );
    println!("euler characteristic: {}", r.euler_characteristic);
    match r.genus {
        Some(g) => println!("genus:                {g}"),
        None => println!("genus:                undefined (not a closed manifold)"),
    }
    println!("volume:               {}", r.volume);
    println!("area:                 {}", r.area);
    println!(
        "bbox:                 [{}, {}, {}] .. [{}, {}, {}] (diagonal {})",
        r.bbox_min[0], r.bbox_min[1], r.bbox_min[2], r.bbox_max[0], r.bbox_max[1], r.bbox_max[2], r.bbox_diagonal
    );
    println!("degenerate triangles: {} (+ {} collapsed)", r.degenerate_triangles, r.collapsed_triangles);
    println!("self-intersections:   {} pairs", r.self_intersecting_pairs);
    for i in &r.issues {
        let tag = match i.severity {
            Severity::Error => "problem",
            Severity::Warning => "warning",
        };
        println!("{tag}: {}", i.message);
    }
    println!("can go on:            {}", yes(r.can_proceed));
}
