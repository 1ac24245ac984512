//! Spline-stage measurements for BENCHMARKS.md ("Spline" section).
//!
//! cargo bench --bench spline -- [reference|sharp|fit|properties|poisson|all]
//!
//! reference   construction / extraction time, Gauss-point Jacobians on HexGen's meshes
//! fit         boundary distance to the input surface: before fit, after fit, after local refinement
//! sharp       sharp-feature angle vs. folded elements and repairs
//! properties  partition of unity, linear reproduction, continuity jumps on built-in meshes
//! poisson     L2 convergence of the IGA Poisson solver (block and rod)

use sddpm::error::NoProgress;
use sddpm::export::vtk::read_vtk_legacy;
use sddpm::hex::HexMesh;
use sddpm::mesh::TriMesh;
use sddpm::spline::iga::{solve_poisson, PoissonOptions};
use sddpm::spline::{build_spline, check, FitOptions, RefineOptions, Spline, SplineOptions};

use std::path::Path;
use std::time::Instant;

#[path = "../tests/support/meshes.rs"]
mod meshes;

const MODELS: [&str; 4] = ["hepta", "joint", "rockerarm", "rod"];

fn load(name: &str) -> (HexMesh, TriMesh) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/meshes");
    let hex = read_vtk_legacy(&root.join(format!("reference_hex/hexgen_{name}_hex.vtk"))).expect("hex");
    let surf = TriMesh::load(root.join(format!("hexgen_{name}.obj")), &Default::default()).expect("surface");
    (hex, surf)
}

fn reference() {
    println!("## reference meshes: construction, extraction, Gauss-point Jacobians (no fit)");
    println!("| mesh | hex elements | vertices | extraordinary edges | sharp edges | basis | construct+extract s | min det J | min scaled J | mean elem. min scaled J | repaired elements | elements det<=0 | BEXT MB (dense) | BEXT s |");
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|");
    for name in MODELS {
        let (hex, _) = load(name);
        let opts = SplineOptions::default();
        let t = Instant::now();
        let sp = Spline::construct(&hex, &opts).unwrap();
        let tc = t.elapsed().as_secs_f64();
        let r = sp.report();
        let t = Instant::now();
        let txt = sddpm::export::bext::to_bext_string(&sp, false);
        let tb = t.elapsed().as_secs_f64();
        println!(
            "| {name} | {} | {} | {} | {} | {} | {:.3} | {:.4e} | {:.4} | {:.4} | {} | {} | {:.1} | {:.2} |",
            hex.elements.len(),
            hex.nodes.len(),
            r.extraordinary_edges,
            r.sharp_edges,
            r.basis_functions,
            tc,
            r.min_jacobian,
            r.min_scaled_jacobian,
            r.mean_scaled_jacobian,
            r.repaired_elements,
            r.negative_jacobian_elements,
            txt.len() as f64 / 1e6,
            tb
        );
    }
}

fn fit() {
    println!("## boundary distance to the input surface (relative to the bbox diagonal)");
    println!("| mesh | control net (hex boundary) Hausdorff | spline before fit: max / Hausdorff | after fit: max / Hausdorff | after auto refinement: max / Hausdorff | refined elements | basis after | repaired elements | min scaled J after | fit s | refine s |");
    println!("|---|---|---|---|---|---|---|---|---|---|---|");
    for name in MODELS {
        let (hex, surf) = load(name);
        let loc = sddpm::geometry::SurfaceLocator::new(&surf);
        let diag = sddpm::geometry::Aabb::of_points(&surf.vertices).diagonal();
        let bnd: Vec<[f64; 3]> = hex.nodes.clone();
        let _ = bnd;
        // control net: boundary vertices of the hex mesh to the surface
        let sp0 = Spline::construct(&hex, &SplineOptions::default()).unwrap();
        let topo = sp0.topology();
        let bverts: Vec<[f64; 3]> = (0..topo.nv)
            .filter(|&v| !topo.vertex_bquads[v].is_empty())
            .map(|v| hex.nodes[v])
            .collect();
        let net = loc.max_distance(&bverts) / diag;
        let opts = SplineOptions { refine: Some(RefineOptions::default()), ..Default::default() };
        let sp = build_spline(&hex, Some(&surf), &opts, &mut NoProgress).unwrap();
        let r = sp.report();
        let b = r.fitting_before.clone().unwrap();
        // after fit only: rebuild without refinement
        let sp_fit = build_spline(&hex, Some(&surf), &SplineOptions::default(), &mut NoProgress).unwrap();
        let f = sp_fit.report().fitting_after.clone().unwrap();
        let a = r.fitting_after.clone().unwrap();
        println!(
            "| {name} | {:.3}% (vertices) | {:.3}% / {:.3}% | {:.3}% / {:.3}% | {:.3}% / {:.3}% | {} | {} | {} | {:.4} | {:.2} | {:.2} |",
            100.0 * net,
            100.0 * b.max_relative,
            100.0 * b.hausdorff_relative,
            100.0 * f.max_relative,
            100.0 * f.hausdorff_relative,
            100.0 * a.max_relative,
            100.0 * a.hausdorff_relative,
            r.refined_elements,
            r.basis_functions,
            r.repaired_elements,
            r.min_scaled_jacobian,
            sp_fit.report().seconds.fitting,
            r.seconds.refinement
        );
    }
}

fn sharp() {
    println!("## sharp-feature angle vs. folds (strict check: 3x3x3 Gauss points + 5x5x5 lattice)");
    println!("| mesh | sharp angle | sharp edges | elements folded before repair | repaired elements | basis after repair | min scaled J (Gauss) |");
    println!("|---|---|---|---|---|---|---|");
    for name in MODELS {
        let (hex, _) = load(name);
        for ang in [None, Some(35.0), Some(60.0), Some(80.0)] {
            let o = SplineOptions { sharp_angle_deg: ang, repair_jacobian: false, ..Default::default() };
            let sp = Spline::construct(&hex, &o).unwrap();
            let all: Vec<usize> = (0..sp.num_elements()).collect();
            let folded = all.iter().filter(|&&e| check::element_strict(&sp, e) <= 0.0).count();
            let sp2 = Spline::construct(&hex, &SplineOptions { sharp_angle_deg: ang, ..Default::default() }).unwrap();
            let r = sp2.report();
            println!(
                "| {name} | {} | {} | {folded} | {} | {} | {:.4} |",
                ang.map(|a| format!("{a}°")).unwrap_or("off".into()),
                r.sharp_edges,
                r.repaired_elements,
                r.basis_functions,
                r.min_scaled_jacobian
            );
        }
    }
}

fn properties() {
    println!("## basis properties on built-in meshes (20 random points per element)");
    println!("| mesh | elements | basis | max abs(sum N - 1) | min N | linear field error | rank / basis | regular faces: max jump d0 d1 d2 | other faces: max jump d0 d1 d2 (C1-broken faces) |");
    println!("|---|---|---|---|---|---|---|---|---|");
    let cases: Vec<(&str, HexMesh, bool)> = vec![
        ("cube", meshes::block([1, 1, 1], [1.0, 1.0, 1.0]), true),
        ("block 3x3x3", meshes::block([3, 3, 3], [1.0, 1.0, 1.0]), true),
        ("valence 3 edge", meshes::extraordinary_edge(3, 2, 3), false),
        ("valence 5 edge", meshes::extraordinary_edge(5, 2, 3), false),
        ("valence 4 disk", meshes::extraordinary_edge(4, 3, 5), false),
    ];
    for (name, hex, all_regular) in cases {
        for refined in [false, true] {
            let mut sp = Spline::construct(&hex, &SplineOptions::default()).unwrap();
            if refined {
                let n = sp.num_elements();
                sp.refine(&[0, n / 2, n - 1]).unwrap();
            }
            let pu = check::partition_of_unity(&sp, 20, 1);
            let lin = check::linear_reproduction(&sp, 20, 2);
            let (rank, n) = check::independence_rank(&sp);
            let all = |_: u32, _: u32| true;
            let c = if all_regular { check::continuity(&sp, 3, Some(&all)) } else { check::continuity(&sp, 3, None) };
            println!(
                "| {name}{} | {} | {} | {:.1e} | {:.1e} | {:.1e} | {rank} / {n} | {} faces: {:.1e} {:.1e} {:.1e} | {} faces: {:.1e} {:.1e} {:.1e} ({}) |",
                if refined { " + 3 refined" } else { "" },
                sp.num_elements(),
                sp.num_basis(),
                pu.max_sum_error,
                pu.min_value,
                lin,
                c.regular.faces,
                c.regular.max_jump[0],
                c.regular.max_jump[1],
                c.regular.max_jump[2],
                c.other.faces,
                c.other.max_jump[0],
                c.other.max_jump[1],
                c.other.max_jump[2],
                c.other.faces_c1_broken
            );
        }
    }
}

fn poisson() {
    println!("## Poisson -Δu = f, u = g on the boundary; L2 error under refinement");
    let k = [1.1, 0.7, 0.9];
    let exact = move |x: [f64; 3]| (k[0] * x[0]).sin() * (k[1] * x[1] + 0.3).cos() * (k[2] * x[2]).exp();
    let grad = move |x: [f64; 3]| {
        let (a, b, c) = ((k[0] * x[0]).sin(), (k[1] * x[1] + 0.3).cos(), (k[2] * x[2]).exp());
        [k[0] * (k[0] * x[0]).cos() * b * c, -k[1] * a * (k[1] * x[1] + 0.3).sin() * c, k[2] * a * b * c]
    };
    let src = move |x: [f64; 3]| (k[0] * k[0] + k[1] * k[1] - k[2] * k[2]) * exact(x);
    let po = PoissonOptions::default();
    println!("### unit cube, control mesh n^3 (uniform subdivision), u = sin(1.1x) cos(0.7y+0.3) exp(0.9z)");
    println!("| boundary | n | basis | L2 error | rate | H1 error | rate | solve s |");
    println!("|---|---|---|---|---|---|---|---|");
    for enrich in [false, true] {
        let mut prev: Option<(f64, f64)> = None;
        for n in [3usize, 6, 12, 24] {
            if enrich && n == 24 {
                continue;
            }
            let hex = meshes::block([n, n, n], [1.0, 1.0, 1.0]);
            let opts = SplineOptions { boundary_enrichment: enrich, ..Default::default() };
            let sp = Spline::construct(&hex, &opts).unwrap();
            let sol = solve_poisson(&sp, src, exact, &po).unwrap();
            let e = sol.errors(&sp, exact, grad, &po).unwrap();
            let (r2, r1) = match prev {
                Some((a, b)) => (format!("{:.2}", (a / e.l2).log2()), format!("{:.2}", (b / e.h1_semi).log2())),
                None => ("-".into(), "-".into()),
            };
            println!(
                "| {} | {n} | {} | {:.3e} | {r2} | {:.3e} | {r1} | {:.2} |",
                if enrich { "enriched" } else { "natural" },
                sp.num_basis(),
                e.l2,
                e.h1_semi,
                sol.seconds
            );
            prev = Some((e.l2, e.h1_semi));
        }
    }
    println!("### unit cube, THB refinement of every element (C0 level-1 space), natural boundary");
    for n in [3usize, 6] {
        let hex = meshes::block([n, n, n], [1.0, 1.0, 1.0]);
        let mut sp = Spline::construct(&hex, &SplineOptions::default()).unwrap();
        let e0 = solve_poisson(&sp, src, exact, &po).unwrap().errors(&sp, exact, grad, &po).unwrap();
        let all: Vec<usize> = (0..sp.num_elements()).collect();
        sp.refine(&all).unwrap();
        let sol = solve_poisson(&sp, src, exact, &po).unwrap();
        let e1 = sol.errors(&sp, exact, grad, &po).unwrap();
        println!(
            "n = {n}: L2 {:.3e} -> {:.3e} (basis {} -> {}, {} solver)",
            e0.l2,
            e1.l2,
            (n + 1).pow(3),
            sp.num_basis(),
            sol.solver
        );
    }
    println!("### HexGen rod (model units, scaled solution), control mesh subdivided uniformly");
    let (hex, _) = load("rod");
    let bb = sddpm::geometry::Aabb::of_points(&hex.nodes);
    let s = 3.0 / bb.diagonal();
    let c = bb.centre();
    let ex2 = move |x: [f64; 3]| exact([(x[0] - c[0]) * s, (x[1] - c[1]) * s, (x[2] - c[2]) * s]);
    let gr2 = move |x: [f64; 3]| grad([(x[0] - c[0]) * s, (x[1] - c[1]) * s, (x[2] - c[2]) * s]).map(|g| g * s);
    let sr2 = move |x: [f64; 3]| src([(x[0] - c[0]) * s, (x[1] - c[1]) * s, (x[2] - c[2]) * s]) * s * s;
    println!("| level | hex elements | basis | L2 error | relative L2 | H1 error | min scaled J | solver | solve s |");
    println!("|---|---|---|---|---|---|---|---|---|");
    let mut h = hex.clone();
    for level in 0..2 {
        let sp = Spline::construct(&h, &SplineOptions::default()).unwrap();
        let sol = solve_poisson(&sp, sr2, ex2, &po).unwrap();
        let e = sol.errors(&sp, ex2, gr2, &po).unwrap();
        println!(
            "| {level} | {} | {} | {:.3e} | {:.3e} | {:.3e} | {:.4} | {} | {:.2} |",
            h.elements.len(),
            sp.num_basis(),
            e.l2,
            e.l2_relative,
            e.h1_semi,
            sp.report().min_scaled_jacobian,
            sol.solver,
            sol.seconds
        );
        h = meshes::subdivide(&h);
    }
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).filter(|a| !a.starts_with("--")).collect();
    let what = args.first().map(|s| s.as_str()).unwrap_or("all");
    let t = Instant::now();
    if what == "reference" || what == "all" {
        reference();
    }
    if what == "sharp" || what == "all" {
        sharp();
    }
    if what == "properties" || what == "all" {
        properties();
    }
    if what == "fit" || what == "all" {
        fit();
    }
    if what == "poisson" || what == "all" {
        poisson();
    }
    let _ = FitOptions::default();
    eprintln!("total {:.1} s", t.elapsed().as_secs_f64());
}
