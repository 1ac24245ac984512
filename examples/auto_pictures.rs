//! The paper's automated-mode figure for one mesh: the automated mode (default
//! options, embedded model), then three pictures of what it did and a table of
//! the chosen box's subregions.
//!
//! `cargo run --release --example auto_pictures -- MESH OUT_PREFIX`
//!
//! writes OUT_PREFIX_subregions.png (the input in the aligned frame, each
//! triangle coloured by the subregion of the chosen box its centroid lies in),
//! OUT_PREFIX_context.png (the chosen context's exact assembly, each cell in the
//! same colour as its subregion) and OUT_PREFIX_diffused.png (the chosen
//! candidate's reverse-diffusion output, the verified point set, coloured by
//! cell, seen from above the grid's Z axis), and prints one markdown row per subregion: cell, fill, genus, the
//! feasible labels with their in-context fits, the labels kept and the labels
//! that passed local verification.
use sddpm::search::auto::AutoOptions;
use sddpm::search::generate::PolycubeOptions;
use sddpm::diffusion::Model;
use sddpm::error::NoProgress;
use sddpm::export::render::{render_png, Camera, Layer};
use sddpm::pipeline::{generate_polycube, ContextRequest};
use sddpm::polycube::{Primitive, NUM_CELLS};

const PALETTE: [[u8; 3]; NUM_CELLS] = [
    [40, 90, 170],
    [200, 90, 40],
    [50, 150, 70],
    [160, 60, 150],
    [200, 170, 40],
    [60, 170, 180],
    [120, 80, 40],
    [230, 120, 160],
    [100, 100, 100],
    [150, 200, 60],
    [90, 60, 200],
    [220, 60, 60],
];

fn main() -> sddpm::Result<()> {
    let a: Vec<String> = std::env::args().collect();
    let (Some(path), Some(prefix)) = (a.get(1), a.get(2)) else {
        eprintln!("usage: auto_pictures MESH OUT_PREFIX");
        std::process::exit(2);
    };
    let mesh = sddpm::mesh::TriMesh::load(path, &sddpm::mesh::LoadOptions::default())?;
    let genus = mesh.validate()?.genus.expect("a validated surface has a genus");
    let model = Model::default_model()?;
    let t = std::time::Instant::now();
    let (pr, auto, err) = generate_polycube(&model, &mesh, genus, &ContextRequest::Auto, &PolycubeOptions::default(), &AutoOptions::default(), &mut NoProgress)?;
    let secs = t.elapsed().as_secs_f64();
    if let Some(e) = err {
        println!("automated mode: {e}");
    }
    let auto = auto.expect("the automated mode reports its boxes");
    let chosen = pr.chosen.map(|i| &pr.candidates[i]);
    println!(
        "{path}: genus {genus}, {} candidates, {} verified, chosen {:?} ({:.1} s); temporary volume {} tets, {:.4} vs surface {:.4}",
        pr.candidates.len(),
        pr.verified().count(),
        chosen.map(|c| format!("{} under {}", c.context.names(), c.rotation)),
        secs,
        auto.volume_tetrahedra,
        auto.volume,
        auto.surface_volume
    );
    let Some(bx) = auto.chosen() else {
        println!("no box chosen");
        return Ok(());
    };
    // the box's subregions lie in its frame: the aligned mesh's points are turned into it
    let frame = sddpm::search::auto::frames::FRAMES.iter().copied().find(|r| r.name() == bx.frame).unwrap_or(sddpm::polycube::orientation::AxisRotation::IDENTITY);
    println!("\nchosen box {}, {} genus-consistent global candidates, best fit {:?}\n", bx.name(), bx.candidates, bx.best_fit);
    println!("| cell | colour | fill | genus | feasible labels (in-context fit) | kept | passed local verification |");
    println!("|---:|---|---:|---:|---|---|---|");
    for l in &bx.locals {
        let s = &l.subregion;
        let c = PALETTE[s.cell];
        println!(
            "| {} | #{:02x}{:02x}{:02x} | {:.2} | {} | {} | {} | {} |",
            s.cell,
            c[0],
            c[1],
            c[2],
            s.fill,
            s.genus,
            l.fits.iter().map(|(n, f)| format!("{n} {f:.3}")).collect::<Vec<_>>().join(", "),
            l.kept.join(", "),
            if l.verified.is_empty() { "—".to_string() } else { l.verified.join(", ") }
        );
    }

    // 1. the input, coloured by subregion (aligned frame, where the boxes live)
    let m = &pr.alignment.mesh;
    let mut by_cell: Vec<Vec<[u32; 3]>> = vec![Vec::new(); NUM_CELLS + 1];
    for t in &m.triangles {
        let c = frame.apply(std::array::from_fn(|d| (0..3).map(|k| m.vertices[t[k] as usize][d]).sum::<f64>() / 3.0));
        let cell = bx.locals.iter().map(|l| &l.subregion).find(|s| (0..3).all(|d| c[d] >= s.lo[d] - 1e-9 && c[d] <= s.hi[d] + 1e-9)).map_or(NUM_CELLS, |s| s.cell);
        by_cell[cell].push(*t);
    }
    let layers: Vec<Layer> = by_cell
        .iter()
        .enumerate()
        .filter(|(_, t)| !t.is_empty())
        .map(|(c, t)| Layer::Surface { vertices: &m.vertices, triangles: t, edges: &[], colour: if c < NUM_CELLS { PALETTE[c] } else { [200, 200, 200] } })
        .collect();
    render_png(std::path::Path::new(&format!("{prefix}_subregions.png")), &layers, 640, 480, Camera::default())?;

    let Some(c) = chosen else {
        println!("nothing verified: no context or diffused pictures");
        return Ok(());
    };
    // 2. the chosen context's exact assembly, one colour per cell
    let mut parts = Vec::new();
    for n in 0..NUM_CELLS {
        if c.context.labels[n] == Primitive::Null {
            continue;
        }
        let mut only = [Primitive::Null; NUM_CELLS];
        only[n] = c.context.labels[n];
        let cell_mesh = sddpm::polycube::boundary(&sddpm::context::Context::new(only).assemble()).to_trimesh();
        parts.push((n, cell_mesh));
    }
    let layers: Vec<Layer> = parts.iter().map(|(n, cm)| Layer::Surface { vertices: &cm.vertices, triangles: &cm.triangles, edges: &[], colour: PALETTE[*n] }).collect();
    render_png(std::path::Path::new(&format!("{prefix}_context.png")), &layers, 640, 480, Camera::default())?;

    // 3. the reverse-diffusion output of the chosen candidate, coloured by cell
    let out = c.output.as_ref().expect("a verified candidate keeps its output");
    let mut pts = Vec::new();
    let mut cols = Vec::new();
    for n in 0..NUM_CELLS {
        if c.context.labels[n] == Primitive::Null {
            continue;
        }
        let p = sddpm::search::verify::active_points(out, n, 1e-4);
        cols.extend(std::iter::repeat(PALETTE[n]).take(p.len()));
        pts.extend(p);
    }
    let layers = [Layer::Points { points: &pts, colours: &cols, radius_px: 1.6 }];
    // from above the through holes of the grid's Z axis show as gaps in the cloud
    render_png(std::path::Path::new(&format!("{prefix}_diffused.png")), &layers, 640, 480, Camera { azimuth: -90.0, elevation: 89.0 })?;
    println!("\nwrote {prefix}_subregions.png, {prefix}_context.png, {prefix}_diffused.png");
    Ok(())
}
