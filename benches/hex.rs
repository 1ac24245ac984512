//! Hex-mesh benchmark over the real test meshes (BENCHMARKS.md "Hex mesh").
//!
//! cargo bench --bench hex -- [FILTER...] [--level N] [--levels 1-4] [--out DIR] [--info] [--surface-map charts|best]
//!
//! For every model whose name contains one of the filters (all when none): load,
//! PCA-align, map onto the hand-chosen context, build the hex mesh and print one
//! line of statistics (and a JSON line with the full report).

use sddpm::context::Context;
use sddpm::hex::{build_hex_mesh, HexInput, HexOptions};
use sddpm::mesh::{LoadOptions, TriMesh};
use std::path::PathBuf;
use std::time::Instant;

/// (file, context labels, why this context)
const MODELS: &[(&str, &str, &str)] = &[
    ("cgal_hole.off", "THC+Z,0,0,0,0,0,0,0,0,0,0,0", "cube with a square through-hole"),
    ("cinolib_torus.obj", "THC+Z,0,0,0,0,0,0,0,0,0,0,0", "torus, hole along the smallest axis"),
    ("trimesh_round.stl", "THC+X,THC+X,THC+X,0,0,0,0,0,0,0,0,0", "thin tube, bore along the long axis"),
    ("cgal_dragknob.off", "BHC+Z,0,0,0,0,0,0,0,0,0,0,0", "knob with a blind recess"),
    ("cgal_dragknob.off", "cube,0,0,0,0,0,0,0,0,0,0,0", "knob, recess left to the surface map"),
    ("cgal_spool.off", "BHC+Z,0,0,0,0,0,0,0,0,0,0,0", "spool with a blind recess"),
    ("cinolib_cube_minus_sphere.obj", "cube,0,0,0,0,0,0,0,0,0,0,0", "cube with a spherical bite (axes kept)"),
    ("mambo_B0.obj", "cube,cube,0,0,0,0,0,0,0,0,0,0", "block with a channel"),
    ("hexgen_bust.obj", "cube,cube,0,0,0,0,0,0,0,0,0,0", "bust"),
    ("hexgen_hepta.obj", "cube,0,0,0,0,0,0,0,0,0,0,0", "hepta"),
    ("hexgen_rod.obj", "THC+Z,cube,THC+Y,0,0,0,0,0,0,0,0,0", "rod: eye (Z) and tab hole (Y)"),
    ("hexgen_joint.obj", "THC+X,THC+X,0,0,0,0,0,0,0,0,0,0", "turned joint with an axial bore"),
    ("hexgen_rockerarm.obj", "cube,THC+Z,cube,0,0,0,0,0,0,0,0,0", "rocker arm, one hole"),
    ("cgal_pinion.off", "THC+Z,0,0,0,0,0,0,0,0,0,0,0", "pinion, axial bore"),
    ("cgal_eight.off", "THC+Z,THC+Z,0,0,0,0,0,0,0,0,0,0", "double torus"),
    ("cinolib_3holes.obj", "THC+Z,THC+Z,THC+Z,0,0,0,0,0,0,0,0,0", "three holes"),
];

/// Models whose PCA frame is not the polycube's: their own axes are kept (centred, scaled).
const KEEP_AXES: &[&str] = &["cinolib_cube_minus_sphere.obj"];

fn main() {
    run();
}

fn run() {
    let args: Vec<String> = std::env::args().skip(1).filter(|a| a != "--bench").collect();
    let mut filters = Vec::new();
    let mut opts = HexOptions::default();
    let mut info = false;
    let mut reference = false;
    let mut levels: Option<String> = None;
    let mut table: Vec<String> = Vec::new();
    let mut out: Option<PathBuf> = None;
    let mut i = 0;
    while i < args.len() {
        match args[i].as_str() {
            "--level" => {
                opts.map.level = Some(args[i + 1].parse().unwrap());
                i += 1;
            }
            "--out" => {
                out = Some(PathBuf::from(&args[i + 1]));
                i += 1;
            }
            "--info" => info = true,
            "--reference" => reference = true,
            "--levels" => {
                levels = Some(args[i + 1].clone());
                i += 1;
            }
            "--surface-map" => {
                opts.map.surface_map = match args[i + 1].as_str() {
                    "charts" => sddpm::hex::SurfaceMap::Charts,
                    "best" => sddpm::hex::SurfaceMap::Best,
                    _ => sddpm::hex::SurfaceMap::Projection,
                };
                i += 1;
            }
            "--raw" => opts.quality.keep_better_mapped = false,
            "--no-pillow" => opts.quality.pillow = false,
            "--fit-rounds" => {
                opts.surface.relax_iterations = args[i + 1].parse().unwrap();
                i += 1;
            }
            "--no-quality" => {
                opts.quality.smooth_iterations = 0;
                opts.quality.optimise_passes = 0;
            }
            a => filters.push(a.to_string()),
        }
        i += 1;
    }
    if let Ok(a) = std::env::var("HEX_FEATURE_ANGLE") {
        opts.surface.feature_angle = a.parse().unwrap();
    }
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/meshes");
    for (file, labels, _why) in MODELS {
        let mut labels_override: Option<String> = None;
        if !filters.is_empty() && !filters.iter().any(|f| file.contains(f.as_str())) {
            continue;
        }
        let mesh = TriMesh::load(dir.join(file), &LoadOptions::default()).expect("load");
        let mut al = sddpm::geometry::align(&mesh).expect("align");
        if KEEP_AXES.contains(file) {
            let bb = sddpm::geometry::Aabb::of_points(&mesh.vertices);
            let s = 2.0 / bb.size().iter().copied().fold(0.0, f64::max);
            let c = bb.centre();
            al.transform = sddpm::geometry::Transform { rotation: sddpm::geometry::Transform::IDENTITY.rotation, translation: [-s * c[0], -s * c[1], -s * c[2]], scale: s };
            al.mesh = al.transform.apply_mesh(&mesh);
        }
        if let Ok(l) = std::env::var("HEX_LABELS") {
            labels_override = Some(l);
        }
        if info {
            let bb = sddpm::geometry::Aabb::of_points(&al.mesh.vertices);
            println!("{file}: {} v {} t aligned size {:?}", mesh.vertices.len(), mesh.triangles.len(), bb.size());
            if let Some(o) = &out {
                std::fs::create_dir_all(o).unwrap();
                let stem = file.split('.').next().unwrap();
                for (k, v) in [[0.0, 0.0, 1.0], [0.0, -1.0, 0.0], [1.0, -0.6, 0.8]].iter().enumerate() {
                    let up = if k == 0 { [0.0, 1.0, 0.0] } else { [0.0, 0.0, 1.0] };
                    render_tri(&al.mesh, *v, up, &o.join(format!("{stem}_input{k}.png")));
                }
            }
            continue;
        }
        if reference {
            let stem = file.split('.').next().unwrap();
            let p = dir.join("reference_hex").join(format!("{stem}_hex.vtk"));
            if let Ok(h) = sddpm::export::vtk::read_vtk_legacy(&p) {
                let q = sddpm::hex::quality::summarize(&sddpm::hex::quality::element_qualities(&h));
                let hd = sddpm::hex::distance::hausdorff(&h, &mesh, 20_000);
                table.push(format!(
                    "| {stem} (HexGen) | {} | {} | {:.3} | {:.3} | {} | {:.2} % |",
                    h.nodes.len(),
                    h.elements.len(),
                    q.min,
                    q.mean,
                    q.inverted,
                    100.0 * hd.relative
                ));
            }
            continue;
        }
        let ctx = Context::parse(labels_override.as_deref().unwrap_or(labels)).expect("context");
        if let Some(spec) = &levels {
            let (a, b) = spec.split_once('-').map(|(a, b)| (a.parse::<u32>().unwrap(), b.parse::<u32>().unwrap())).unwrap_or((1, 4));
            for l in a..=b {
                let (input, _) = HexInput::from_alignment(&al, ctx).expect("input");
                let mut o = opts.clone();
                o.map.level = Some(l);
                let t0 = Instant::now();
                let r = build_hex_mesh(&input, &o, &mut sddpm::error::NoProgress).expect("hex");
                let total = t0.elapsed().as_secs_f64();
                let st = |name: &str| r.stages.iter().find(|s| s.stage.name() == name).map(|s| s.seconds).unwrap_or(0.0);
                // capture = the sharp-edge capture, coverage and recapture steps
                table.push(format!(
                    "| {} | {} | {} | {} | {:.2} | {:.2} | {:.2} | {:.2} | {:.2} | {:.2} | {:.1} | {:.3} | {:.3} | {} | {:.2} % |",
                    file.split('.').next().unwrap(),
                    l,
                    r.mesh.nodes.len(),
                    r.mesh.elements.len(),
                    st("mapping"),
                    st("pillowing"),
                    st("smoothing"),
                    st("optimisation"),
                    st("capture") + st("coverage") + st("recapture"),
                    total - r.stages.iter().map(|s| s.seconds).sum::<f64>(),
                    total,
                    r.quality.min,
                    r.quality.mean,
                    r.quality.inverted,
                    100.0 * r.hausdorff_relative
                ));
                println!("{}", table.last().unwrap());
            }
            continue;
        }
        let (input, _) = HexInput::from_alignment(&al, ctx).expect("input");
        let t0 = Instant::now();
        let r = match build_hex_mesh(&input, &opts, &mut sddpm::error::NoProgress) {
            Ok(r) => r,
            Err(e) => {
                println!("{file}: FAILED {e}");
                continue;
            }
        };
        let secs = t0.elapsed().as_secs_f64();
        let st = |name: &str| r.stages.iter().find(|s| s.stage.name() == name).map(|s| s.seconds).unwrap_or(0.0);
        table.push(format!(
            "| {} | {} | {} / {} | {} | {} / {} | {:.3} | {:.3} | {} | {:.2} % | {:.2} % | {:.2} / {:.2} / {:.2} / {:.2} | {:.1} |",
            file.split('.').next().unwrap(),
            labels_override.as_deref().unwrap_or(labels),
            mesh.vertices.len(),
            mesh.triangles.len(),
            r.level,
            r.mesh.nodes.len(),
            r.mesh.elements.len(),
            r.quality.min,
            r.quality.mean,
            r.quality.inverted,
            100.0 * r.hausdorff_relative,
            100.0 * (r.volume - r.input_volume) / r.input_volume,
            st("mapping"),
            st("pillowing"),
            st("smoothing"),
            st("optimisation"),
            secs
        ));
        println!(
            "{file}: level {} nodes {} elements {} minSJ {:.3} meanSJ {:.3} inverted {} hausdorff {:.4} vol {:.4} ({:.4}) returned {} {:.1}s",
            r.level,
            r.mesh.nodes.len(),
            r.mesh.elements.len(),
            r.quality.min,
            r.quality.mean,
            r.quality.inverted,
            r.hausdorff_relative,
            r.volume,
            r.input_volume,
            r.returned,
            secs
        );
        // one comparison row: surface map, elements, inverted, min / mean scaled
        // Jacobian, Hausdorff, irregular edges, seconds
        println!(
            "ROW | {} | {} | {} | {} | {} | {:.3} | {:.3} | {:.2} % | {} | {:.1} |",
            file.split('.').next().unwrap(),
            labels_override.as_deref().unwrap_or(labels),
            r.surface_map.method,
            r.mesh.elements.len(),
            r.quality.inverted,
            r.quality.min,
            r.quality.mean,
            100.0 * r.hausdorff_relative,
            sddpm::hex::topology::irregular_edges(&r.mesh).total(),
            secs
        );
        if let Some(w) = &r.surface_map.why {
            println!("    surface map: projection because {w}");
        }
        for s in &r.stages {
            println!(
                "    {:<13} min {:.3} -> {:.3}  mean {:.3} -> {:.3}  inv {} -> {}  {:.2}s",
                s.stage, s.before.min, s.after.min, s.before.mean, s.after.mean, s.before.inverted, s.after.inverted, s.seconds
            );
            if std::env::var("HEX_DETAILS").is_ok() {
                println!("        {}", s.details_json());
            }
        }
        for l in &r.levels {
            println!("    level {} elements {} dev {:?} flipped {} inverted {} {:.2}s", l.level, l.elements, l.deviation, l.flipped_quads, l.inverted, l.seconds);
        }
        println!("    map {:?}", r.surface_map);
        if let Ok(v) = std::env::var("HEX_NODE") {
            let v: u32 = v.parse().unwrap();
            let m = &r.mapped;
            println!("    node {v} at {:?}", m.nodes[v as usize]);
            for (e, el) in m.elements.iter().enumerate() {
                if el.contains(&v) {
                    let c = m.element_corners(e);
                    let cen = c.iter().fold([0.0; 3], |a, p| [a[0] + p[0] / 8.0, a[1] + p[1] / 8.0, a[2] + p[2] / 8.0]);
                    println!("      element {e} sj {:.3} centroid {:?}", sddpm::hex::quality::scaled_jacobian(&c), cen);
                }
            }
            for q in sddpm::hex::topology::boundary_quads(m).unwrap() {
                if q.nodes.contains(&v) {
                    let p = q.nodes.map(|i| m.nodes[i as usize]);
                    println!("      quad {:?} {:?}", q.nodes, p);
                }
            }
        }
        if std::env::var("HEX_MAPPED_BAD").is_ok() {
            let q = sddpm::hex::quality::element_qualities(&r.mapped);
            let bq = sddpm::hex::topology::boundary_quads(&r.mapped).unwrap();
            let mut nb = vec![0; r.mapped.elements.len()];
            for b in &bq {
                nb[b.element as usize] += 1;
            }
            for (e, &v) in q.iter().enumerate() {
                if v <= 0.1 {
                    let c = r.mapped.element_corners(e);
                    let cen = c.iter().fold([0.0; 3], |a, p| [a[0] + p[0] / 8.0, a[1] + p[1] / 8.0, a[2] + p[2] / 8.0]);
                    println!("      mapped element {e} sj {v:.3} boundary faces {} centroid {:.3?}", nb[e], cen);
                }
            }
        }
        if std::env::var("HEX_WORST").is_ok() {
            let mut idx: Vec<usize> = (0..r.scaled_jacobian.len()).collect();
            idx.sort_by(|&a, &b| r.scaled_jacobian[a].total_cmp(&r.scaled_jacobian[b]));
            for &e in idx.iter().take(3) {
                println!("    worst element {e} sj {:.3} nodes {:?}", r.scaled_jacobian[e], r.mesh.elements[e]);
                for p in r.mesh.element_corners(e) {
                    println!("        {:.4} {:.4} {:.4}", p[0], p[1], p[2]);
                }
            }
        }
        {
            let loc = sddpm::geometry::SurfaceLocator::new(&mesh);
            let bq = sddpm::hex::topology::boundary_quads(&r.mapped).unwrap();
            let mut d: Vec<f64> = bq.iter().flat_map(|q| q.nodes).map(|v| loc.closest(r.mapped.nodes[v as usize]).2).collect();
            d.sort_by(|a, b| a.total_cmp(b));
            let diag = sddpm::geometry::Aabb::of_points(&mesh.vertices).diagonal();
            println!("    mapped boundary node distance to input / diag: median {:.2e} max {:.2e}", d[d.len() / 2] / diag, d[d.len() - 1] / diag);
        }
        if let Some(o) = &out {
            std::fs::create_dir_all(o).unwrap();
            let stem = file.split('.').next().unwrap();
            let sj = r.scaled_jacobian.clone();
            sddpm::export::vtk::write_vtk_legacy(&o.join(format!("{stem}.vtk")), &r.mesh, stem, &[("scaled_jacobian", &sj)]).unwrap();
            for (k, (v, u)) in [([1.0, 0.3, 0.5], [0.0, 0.0, 1.0]), ([0.2, 0.3, 1.0], [0.0, 1.0, 0.0])].iter().enumerate() {
                render(&r.mapped, *v, *u, &o.join(format!("{stem}_mapped{k}.png")));
                render(&r.mesh, *v, *u, &o.join(format!("{stem}_final{k}.png")));
            }
        }
    }
    println!();
    for l in &table {
        println!("{l}");
    }
}

/// Orthographic render of the boundary quads of a hex mesh (painter's algorithm),
/// inverted elements' faces in red, faces seen from behind in blue.
#[allow(dead_code)]
pub fn render(m: &sddpm::hex::HexMesh, view: [f64; 3], up: [f64; 3], path: &std::path::Path) {
    let quads = sddpm::hex::topology::boundary_quads(m).unwrap();
    let q = sddpm::hex::quality::element_qualities(m);
    let polys: Vec<(Vec<[f64; 3]>, bool)> =
        quads.iter().map(|bq| (bq.nodes.iter().map(|&i| m.nodes[i as usize]).collect(), q[bq.element as usize] <= 0.0)).collect();
    render_polys(&polys, view, up, path);
}

/// Render a triangle surface the same way.
#[allow(dead_code)]
pub fn render_tri(t: &TriMesh, view: [f64; 3], up: [f64; 3], path: &std::path::Path) {
    let polys: Vec<(Vec<[f64; 3]>, bool)> = t.triangles.iter().map(|tr| (tr.iter().map(|&i| t.vertices[i as usize]).collect(), false)).collect();
    render_polys(&polys, view, up, path);
}

fn render_polys(polys: &[(Vec<[f64; 3]>, bool)], view: [f64; 3], up: [f64; 3], path: &std::path::Path) {
    use plotters::prelude::*;
    use sddpm::geometry::vec3::*;
    let vz = scale(view, 1.0 / norm(view));
    let vx0 = cross(up, vz);
    let vx = scale(vx0, 1.0 / norm(vx0));
    let vy = cross(vz, vx);
    let all: Vec<[f64; 3]> = polys.iter().flat_map(|p| p.0.iter().copied()).collect();
    let bb = sddpm::geometry::Aabb::of_points(&all);
    let c = bb.centre();
    let r = bb.diagonal() / 2.0;
    let (w, h) = (900i32, 900i32);
    let proj = |p: [f64; 3]| {
        let d = sub(p, c);
        ((w as f64 / 2.0 + dot(d, vx) / r * 430.0) as i32, (h as f64 / 2.0 - dot(d, vy) / r * 430.0) as i32, dot(d, vz))
    };
    let mut items: Vec<(f64, Vec<(i32, i32)>, RGBColor)> = Vec::new();
    for (p, bad) in polys {
        let n = cross(sub(p[1], p[0]), sub(p[p.len() - 1], p[0]));
        let facing = dot(n, vz);
        let pts: Vec<(i32, i32)> = p.iter().map(|&x| (proj(x).0, proj(x).1)).collect();
        let depth = p.iter().map(|&x| proj(x).2).sum::<f64>() / p.len() as f64;
        let shade = (60.0 + 180.0 * (facing / norm(n).max(1e-300)).abs()) as u8;
        let col = if *bad { RGBColor(230, 30, 30) } else if facing < 0.0 { RGBColor(40, 40, 120) } else { RGBColor(shade, shade, shade) };
        items.push((depth, pts, col));
    }
    items.sort_by(|a, b| a.0.total_cmp(&b.0));
    let root = BitMapBackend::new(path, (w as u32, h as u32)).into_drawing_area();
    root.fill(&WHITE).unwrap();
    let edges = polys.len() < 60_000;
    for (_, pts, col) in items.iter() {
        root.draw(&Polygon::new(pts.clone(), col.filled())).unwrap();
        if edges {
            let mut closed = pts.clone();
            closed.push(pts[0]);
            root.draw(&PathElement::new(closed, BLACK.stroke_width(1))).unwrap();
        }
    }
    root.present().unwrap();
}
