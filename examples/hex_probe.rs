//! Mesh one input with a fixed context under hex-option variants and print the
//! quality of each (issue 6 experiments):
//! `cargo run --release --example hex_probe -- MESH LABELS [release_distance ...]`
//! or `-- MESH voxelN [refinements]` for the voxel lattice mesh alone
//! (the mesh goes to /tmp/voxel_probe.vtk; `HEX_NO_VOXEL=1` meshes the
//! context without the grid-based fallback; `HEX_PIN=F` turns the coverage step on at F times the Hausdorff goal,
//! `HEX_HAUSDORFF=G` sets that goal, 0.01 by default; `HEX_CAPTURE=0` turns the sharp-edge capture steps off, on by default as in the library; `HEX_SHEETS=0` turns the feature sheets off, on by default as in the library; `HEX_MIN` / `HEX_MEAN` set the scaled-Jacobian goals; `HEX_NARROW=DEG` the narrow corner faces' angle, 0 off; `HEX_NARROW_PATCH=F` the narrow patches' width, 0 off; `HEX_MEDIAN=DEG` the feature curves' median angle).
use sddpm::context::Context;
use sddpm::diffusion::Model;
use sddpm::mesh::{LoadOptions, TriMesh};
use sddpm::pipeline::{run, ContextRequest, RunOptions};

fn main() -> sddpm::Result<()> {
    let a: Vec<String> = std::env::args().collect();
    let mesh = TriMesh::load(std::path::Path::new(&a[1]), &LoadOptions::default())?;
    let genus = mesh.validate()?.genus.unwrap();
    if a[2].starts_with("voxel") {
        let mut opts = sddpm::hex::HexOptions::default();
        if let Ok(n) = a[2]["voxel".len()..].parse() {
            opts.fallback.resolution = n; // e.g. voxel48
        }
        if let Some(r) = a.get(3).and_then(|s| s.parse().ok()) {
            opts.fallback.refinements = r; // e.g. voxel48 0: that lattice only
        }
        // HEX_PIN=F: the coverage step at F times the Hausdorff goal (QualityOptions::pin_uncovered)
        opts.quality.pin_uncovered = std::env::var("HEX_PIN").ok().and_then(|s| s.parse().ok()).unwrap_or(0.0);
        // HEX_CAPTURE=0: without the sharp-edge capture steps (QualityOptions::capture_features, on by default)
        if let Ok(v) = std::env::var("HEX_CAPTURE") {
            opts.quality.capture_features = v != "0";
        }
        // HEX_SHEETS=0: without the feature sheets (QualityOptions::feature_sheets, on by default)
        if let Ok(v) = std::env::var("HEX_SHEETS") {
            opts.quality.feature_sheets = v != "0";
        }
        // HEX_NARROW=DEG: narrow corner faces below DEG degrees (QualityOptions::narrow_corner_faces, 70 by default; 0 off)
        if let Some(d) = std::env::var("HEX_NARROW").ok().and_then(|s| s.parse().ok()) {
            opts.quality.narrow_corner_faces = d;
        }
        // HEX_MEDIAN=DEG: the feature curves' median dihedral angle (SurfaceOptions::feature_median_angle, 60 by default)
        if let Some(d) = std::env::var("HEX_MEDIAN").ok().and_then(|s| s.parse().ok()) {
            opts.surface.feature_median_angle = d;
        }
        // HEX_NARROW_PATCH=F: patches narrower than F lattice spacings merged (QualityOptions::narrow_patch_width, 0.75 by default; 0 off)
        if let Some(d) = std::env::var("HEX_NARROW_PATCH").ok().and_then(|s| s.parse().ok()) {
            opts.quality.narrow_patch_width = d;
        }
        // HEX_ALIGN=F: lattice planes on the axis-parallel faces of at least F of the area (FallbackOptions::lattice_planes)
        if let Some(d) = std::env::var("HEX_ALIGN").ok().and_then(|s| s.parse().ok()) {
            opts.fallback.lattice_planes = d;
        }
        // HEX_REFINE=N: N local refinement rounds (FallbackOptions::local_refinement)
        opts.fallback.local_refinement = std::env::var("HEX_REFINE").ok().and_then(|s| s.parse().ok()).unwrap_or(0);
        // HEX_HAUSDORFF=G: the surface-fit goal the lattice loop aims at (QualityGoals::hausdorff)
        if let Some(g) = std::env::var("HEX_HAUSDORFF").ok().and_then(|s| s.parse().ok()) {
            opts.goals.hausdorff = g;
        }
        // HEX_MIN=M / HEX_MEAN=M: the scaled-Jacobian goals (QualityGoals), 0.3 / 0.85 by default
        if let Some(g) = std::env::var("HEX_MIN").ok().and_then(|s| s.parse().ok()) {
            opts.goals.min_scaled_jacobian = g;
        }
        if let Some(g) = std::env::var("HEX_MEAN").ok().and_then(|s| s.parse().ok()) {
            opts.goals.mean_scaled_jacobian = g;
        }
        let t = std::time::Instant::now();
        let r = sddpm::hex::build_voxel_hex_mesh(&mesh, &sddpm::hex::Affine::similarity(1.0, [0.0; 3]), genus, &opts, &mut sddpm::error::NoProgress)?;
        let q = &r.quality;
        println!(
            "{}: elements {} inverted {} min {:.3} mean {:.3} hausdorff {:.4} volume {:.4} vs {:.4} ({:.1} s)",
            r.domain, q.elements, q.inverted, q.min, q.mean, r.hausdorff_relative, r.volume, r.input_volume, t.elapsed().as_secs_f64()
        );
        let hd = &r.hausdorff;
        let diag = hd.distance / hd.relative.max(1e-300);
        println!("   hausdorff: hex->surface {:.4} surface->hex {:.4} mean {:.5} (relative)", hd.hex_to_surface / diag, hd.surface_to_hex / diag, hd.mean_relative);
        if let Some(l) = r.lattice() {
            println!("   lattices meshed: {}", serde_json::json!(l.lattices_meshed));
            if let Some(f) = &l.feature_sheets {
                println!("   feature sheets: {}", serde_json::json!(f));
            }
            for line in l.resolutions_tried.iter().flatten() {
                println!("   tried {line}");
            }
        }
        for s in &r.stages {
            println!("   {} {} -> {} inverted, min {:.3} -> {:.3} {:.1} s {}", s.stage, s.before.inverted, s.after.inverted, s.before.min, s.after.min, s.seconds, s.details_json().to_string().chars().take(300).collect::<String>());
        }
        sddpm::export::vtk::write_vtk_legacy(std::path::Path::new("/tmp/voxel_probe.vtk"), &r.mesh, "voxel", &[("scaled_jacobian", &r.scaled_jacobian)]).ok();
        return Ok(());
    }
    let ctx = Context::parse(&a[2])?;
    let model = Model::default_model()?;
    let variants: Vec<f64> = a[3..].iter().map(|s| s.parse().unwrap()).collect();
    for rd in if variants.is_empty() { vec![0.002] } else { variants } {
        let mut o = RunOptions { spline: None, hex_candidates: 1, ..Default::default() };
        o.hex.quality.release_distance = rd;
        // HEX_NO_VOXEL=1: the polycube mesh alone, without the grid-based fallback
        o.hex.fallback.enabled = std::env::var("HEX_NO_VOXEL").map_or(true, |v| v != "1");
        let t = std::time::Instant::now();
        let r = run(&model, &mesh, genus, &ContextRequest::Contexts(vec![ctx]), &o, &mut sddpm::error::NoProgress)?;
        let q = &r.hex.quality;
        println!(
            "release {rd}: level {} elements {} inverted {} min {:.3} mean {:.3} hausdorff {:.4} ({:.1} s)",
            r.hex.level, q.elements, q.inverted, q.min, q.mean, r.hex.hausdorff_relative, t.elapsed().as_secs_f64()
        );
        println!("   surface map: {:?}", r.hex.surface_map);
        for s in &r.hex.stages {
            println!("   {} {} -> {} inverted, min {:.3} -> {:.3} {}", s.stage, s.before.inverted, s.after.inverted, s.before.min, s.after.min, s.details_json());
        }
        sddpm::export::vtk::write_vtk_legacy(std::path::Path::new("/tmp/voxel_probe.vtk"), &r.hex.mesh, "hex", &[("scaled_jacobian", &r.hex.scaled_jacobian)]).ok();
    }
    Ok(())
}
