//! Tests of the hex stage: perfect grid from a unit box, never worse than the
//! mapped mesh, THC and BHC inputs with the right volume, orientation, exports.

use sddpm::context::Context;
use sddpm::error::NoProgress;
use sddpm::geometry::vec3::*;
use sddpm::hex::quality::{element_qualities, summarize};
use sddpm::hex::topology::{hex_volume, mesh_volume};
use sddpm::hex::{build_hex_mesh, Affine, Domain, HexInput, HexOptions, HexResult, Stage};
use sddpm::mesh::{LoadOptions, TriMesh};


#[path = "support/polycube_surface.rs"]
mod support;

/// The polycube's own boundary in the normalised frame, every quad split k x k, then
/// moved by `deform`.
fn polycube_surface(ctx: &Context, k: usize, deform: impl Fn([f64; 3]) -> [f64; 3]) -> TriMesh {
    let mut m = support::polycube_surface(ctx, k, support::Diagonals::Fixed);
    m.vertices = m.vertices.into_iter().map(deform).collect();
    m
}

/// The default options with the subdivision level fixed.
fn at_level(level: u32) -> HexOptions {
    let mut o = HexOptions::default();
    o.map.level = Some(level);
    o
}

fn run(input: &HexInput, opts: &HexOptions) -> HexResult {
    build_hex_mesh(input, opts, &mut NoProgress).expect("hex mesh")
}

fn assert_never_worse(r: &HexResult) {
    let mapped = r.stages[0].after.min;
    assert!(r.quality.min >= mapped - 1e-12, "returned min {} below mapped {}", r.quality.min, mapped);
    // what is returned is what is reported
    let q = summarize(&element_qualities(&r.mesh));
    assert_eq!(q.elements, r.mesh.elements.len());
    assert!((q.min - r.quality.min).abs() < 1e-12);
}

#[test]
fn unit_box_gives_a_perfect_grid() {
    let ctx = Context::parse("cube,0,0,0,0,0,0,0,0,0,0,0").unwrap();
    let surface = polycube_surface(&ctx, 1, |p| p);
    // user frame: the unit box [0,1]^3
    let input = HexInput { surface, context: ctx, correspondence: vec![], to_user: Affine::similarity(0.5, [0.5; 3]) };
    for level in 0..=2 {
        let r = run(&input, &at_level(level));
        let n = 3usize << level;
        assert_eq!(r.mapped.elements.len(), n * n * n);
        let q = summarize(&element_qualities(&r.mapped));
        assert!((q.min - 1.0).abs() < 1e-12, "level {level}: mapped min {}", q.min);
        assert_eq!(r.stages[0].stage, Stage::Mapping);
        assert!((r.stages[0].after.min - 1.0).abs() < 1e-12);
        // the mapped grid is the regular grid of the unit box
        for p in &r.mapped.nodes {
            for c in p {
                let t = c * n as f64;
                assert!((t - t.round()).abs() < 1e-9 && (-1e-12..=1.0 + 1e-12).contains(c), "{p:?}");
            }
        }
        assert_never_worse(&r);
        assert!(r.quality.min > 0.999);
        assert!((mesh_volume(&r.mesh) - 1.0).abs() < 1e-9);
        assert!(r.hausdorff_relative < 1e-9);
    }
}

fn thc_context() -> Context {
    Context::parse("THC+Z,0,0,0,0,0,0,0,0,0,0,0").unwrap()
}

#[test]
fn synthetic_thc_and_bhc_are_valid_with_the_input_volume() {
    // smooth bends of the primitives' own shapes, mapped to a user frame with a
    // rotation and a non-uniform scale
    let bend = |p: [f64; 3]| [p[0] + 0.12 * (1.3 * p[1]).sin(), p[1] + 0.08 * (p[0] * p[2]), p[2] * (1.0 + 0.1 * p[0])];
    let (c, s) = (0.6f64.cos(), 0.6f64.sin());
    let to_user = Affine { m: [[3.0 * c, -3.0 * s, 0.0], [2.0 * s, 2.0 * c, 0.0], [0.0, 0.0, 1.5]], t: [10.0, -4.0, 2.0] };
    for labels in ["THC+Z,0,0,0,0,0,0,0,0,0,0,0", "BHC+Z,0,0,0,0,0,0,0,0,0,0,0", "THC+X,cube,BHC-Y,0,0,0,0,0,0,0,0,0"] {
        let ctx = Context::parse(labels).unwrap();
        let surface = polycube_surface(&ctx, 6, bend);
        let user = TriMesh { vertices: surface.vertices.iter().map(|&p| to_user.apply(p)).collect(), triangles: surface.triangles.clone() };
        let vol = user.signed_volume();
        let input = HexInput { surface, context: ctx, correspondence: vec![], to_user };
        let r = run(&input, &at_level(2));
        assert_eq!(r.quality.inverted, 0, "{labels}");
        assert!(r.quality.min > 0.3, "{labels}: min {}", r.quality.min);
        assert!(((r.volume - vol) / vol).abs() < 0.01, "{labels}: volume {} vs {}", r.volume, vol);
        assert!(r.hausdorff_relative < 0.01, "{labels}: hausdorff {}", r.hausdorff_relative);
        assert_never_worse(&r);
        for e in 0..r.mesh.elements.len() {
            assert!(hex_volume(&r.mesh.element_corners(e)) > 0.0);
        }
    }
}

fn real(file: &str, labels: &str) -> (HexInput, f64) {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/meshes");
    let mesh = TriMesh::load(dir.join(file), &LoadOptions::default()).unwrap();
    let vol = mesh.signed_volume();
    (HexInput::from_user_mesh(&mesh, Context::parse(labels).unwrap()).unwrap(), vol)
}

#[test]
fn real_thc_input_is_valid_with_the_input_volume() {
    let (input, vol) = real("cgal_hole.off", "THC+Z,0,0,0,0,0,0,0,0,0,0,0");
    let r = run(&input, &at_level(2));
    assert_eq!(r.quality.inverted, 0);
    assert!(r.quality.min >= 0.3, "min {}", r.quality.min);
    assert!(((r.volume - vol) / vol).abs() < 0.01, "volume {} vs {}", r.volume, vol);
    assert!(r.hausdorff_relative < 0.01);
    assert_never_worse(&r);
    let (input, vol) = real("cinolib_torus.obj", "THC+Z,0,0,0,0,0,0,0,0,0,0,0");
    let r = run(&input, &at_level(2));
    assert_eq!(r.quality.inverted, 0);
    assert!(((r.volume - vol) / vol).abs() < 0.015, "volume {} vs {}", r.volume, vol);
    assert_never_worse(&r);
}

#[test]
fn stopping_rule_picks_a_level_within_the_range() {
    let ctx = thc_context();
    let surface = polycube_surface(&ctx, 4, |p| [p[0], p[1], p[2] + 0.1 * (p[0] * 2.0).sin()]);
    let input = HexInput { surface, context: ctx, correspondence: vec![], to_user: Affine::IDENTITY };
    let mut opts = HexOptions::default();
    (opts.map.min_level, opts.map.max_level, opts.map.threshold) = (1, 3, 0.004);
    let r = run(&input, &opts);
    assert!((1..=3).contains(&r.level));
    let chosen = r.levels.iter().find(|l| l.level == r.level).unwrap();
    if r.level < 3 {
        // below the threshold, or stalled against the level before
        let d = chosen.deviation.unwrap();
        let before = r.levels.iter().find(|l| l.level + 1 == r.level).and_then(|l| l.deviation);
        assert!(d <= 0.004 || before.is_some_and(|b| d > opts.map.stall_ratio * b), "{d}");
    }
    for l in r.levels.iter().filter(|l| l.level >= 1 && l.level < r.level) {
        assert!(l.deviation.unwrap() > 0.004, "level {} passed the rule but a finer one was chosen", l.level);
    }
}

#[test]
fn bad_inputs_are_refused() {
    let ctx = thc_context();
    let surface = polycube_surface(&ctx, 1, |p| p);
    let mut input = HexInput { surface, context: ctx, correspondence: vec![], to_user: Affine::IDENTITY };
    input.to_user.m[2] = [0.0; 3];
    assert!(build_hex_mesh(&input, &HexOptions::default(), &mut NoProgress).is_err());
    input.to_user = Affine::IDENTITY;
    input.surface.vertices[0][0] = f64::NAN;
    assert!(build_hex_mesh(&input, &HexOptions::default(), &mut NoProgress).is_err());
    let bad_ctx = Context::parse("cube,0,0,0,cube,0,0,0,0,0,0,0").unwrap(); // cells meet along an edge
    let input = HexInput { surface: polycube_surface(&thc_context(), 1, |p| p), context: bad_ctx, correspondence: vec![], to_user: Affine::IDENTITY };
    assert!(build_hex_mesh(&input, &HexOptions::default(), &mut NoProgress).is_err());
    // cancel through the progress callback
    let input = HexInput { surface: polycube_surface(&thc_context(), 1, |p| p), context: thc_context(), correspondence: vec![], to_user: Affine::IDENTITY };
    let mut cancel = |_f: f64, stage: &str| !stage.contains("pillow");
    let e = build_hex_mesh(&input, &at_level(1), &mut cancel).unwrap_err();
    assert_eq!(e.status(), sddpm::Status::Cancelled);
}

#[test]
fn correspondence_seed_is_used_and_harmless() {
    // a correspondence that is the identity plus noise: the result stays valid
    let ctx = thc_context();
    let surface = polycube_surface(&ctx, 4, |p| scale(p, 1.0 + 0.05 * p[2]));
    let mut corr = Vec::new();
    for (i, p) in surface.vertices.iter().enumerate() {
        let noise = 0.01 * ((i as f64 * 12.9898).sin());
        corr.push((*p, [p[0] + noise, p[1] - noise, p[2]]));
    }
    let input = HexInput { surface, context: ctx, correspondence: corr, to_user: Affine::IDENTITY };
    let r = run(&input, &HexOptions { map: sddpm::hex::MapOptions { level: Some(2), use_correspondence: true, ..Default::default() }, ..Default::default() });
    assert!(r.surface_map.correspondence_pairs > 0);
    assert_eq!(r.quality.inverted, 0);
    assert_never_worse(&r);
}

/// The main job on a genus-0 input whose only candidate is a blind hole (user-guided,
/// unverified): the fallback also meshes the same cells as plain cubes, and keeps the
/// valid mesh. (A box input: the blind hole has nothing to map to and folds or fits
/// worse; the cube block maps to it exactly.)
#[test]
fn an_unverified_genus_0_job_also_tries_plain_cubes() {
    use sddpm::pipeline::{run, ContextRequest, RunOptions};
    let ctx = Context::parse("cube,0,0,0,0,0,0,0,0,0,0,0").unwrap();
    // a 2 x 1 x 1 box, its faces split so the input has interior vertices
    let mesh = polycube_surface(&ctx, 4, |p| [2.0 * p[0], p[1], p[2]]);
    let model = sddpm::diffusion::Model::default_model().unwrap();
    let req = ContextRequest::Contexts(vec![Context::parse("BHC+Z,0,0,0,0,0,0,0,0,0,0,0").unwrap()]);
    let mut o = RunOptions { spline: None, ..Default::default() };
    o.polycube.sampler.steps = 5;
    o.hex.map.level = Some(1);
    let r = run(&model, &mesh, 0, &req, &o, &mut NoProgress).unwrap();
    assert!(!r.verified);
    let names: Vec<String> = r.polycube.candidates.iter().map(|c| c.context.names()).collect();
    assert!(names.iter().any(|n| n.starts_with("cube,")), "no plain-cube candidate among {names:?}");
    assert_eq!(r.hex.quality.inverted, 0, "attempts: {:?}", r.hex_attempts);
    // the kept mesh is the best of the attempts: fewest inverted, then highest minimum
    let best = r.hex_attempts.iter().map(|a| (a.inverted, -a.min_scaled_jacobian)).min_by(|a, b| a.partial_cmp(b).unwrap()).unwrap();
    assert_eq!((r.hex.quality.inverted, -r.hex.quality.min), best);
}

/// Genus of the boundary surface of a hex mesh (its quads split into triangles).
fn boundary_genus(m: &sddpm::hex::HexMesh) -> i64 {
    let quads = sddpm::hex::topology::boundary_quads(m).unwrap();
    let mut id = vec![u32::MAX; m.nodes.len()];
    let mut t = TriMesh::default();
    for q in &quads {
        let v = q.nodes.map(|n| {
            if id[n as usize] == u32::MAX {
                id[n as usize] = t.vertices.len() as u32;
                t.vertices.push(m.nodes[n as usize]);
            }
            id[n as usize]
        });
        t.triangles.push([v[0], v[1], v[2]]);
        t.triangles.push([v[0], v[2], v[3]]);
    }
    t.validate().unwrap().genus.unwrap()
}

/// The grid-based fallback on two parts whose polycube meshes fold (BENCHMARKS.md
/// "Main job"): a valid mesh of the input's genus, first lattice only. Tolerances:
/// the voxel size is 1/24 of the longest edge, and the boundary faces are chords of
/// the surface, so the volume is within 5 % and the Hausdorff distance within 3 % of
/// the diagonal (measured: rod 3.1 % / 1.9 %, three-hole block 1.7 % / 0.9 %).
#[test]
fn voxel_fallback_gives_a_valid_mesh_of_the_inputs_genus() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/meshes");
    for (file, genus) in [("hexgen_rod.obj", 2), ("cinolib_3holes.obj", 3)] {
        let mesh = TriMesh::load(dir.join(file), &LoadOptions::default()).unwrap();
        assert_eq!(mesh.validate().unwrap().genus, Some(genus));
        let mut opts = HexOptions::default();
        opts.fallback.refinements = 0;
        let r = sddpm::hex::build_voxel_hex_mesh(&mesh, &Affine::similarity(1.0, [0.0; 3]), genus, &opts, &mut NoProgress).unwrap();
        assert_eq!(r.domain, Domain::Voxel { resolution: 24 });
        assert_eq!(r.domain.to_string(), "voxel 24");
        assert_eq!(r.quality.inverted, 0, "{file}: {:?}", r.quality);
        assert!(r.quality.min > 0.3, "{file}: {:?}", r.quality);
        let vol = mesh.signed_volume().abs();
        assert!(((r.volume - vol) / vol).abs() < 0.05, "{file}: volume {} vs {vol}", r.volume);
        assert!(r.hausdorff_relative < 0.03, "{file}: Hausdorff {}", r.hausdorff_relative);
        assert_eq!(boundary_genus(&r.mesh), genus, "{file}");
        // every element positively oriented in the user's frame
        assert!(r.mesh.elements.iter().all(|e| hex_volume(&e.map(|i| r.mesh.nodes[i as usize])) > 0.0));
    }
}

/// When the first lattice misses the quality goals, the fallback refines it: on the
/// rod the 24-voxel mesh is 1.9 % of the diagonal from the surface (BENCHMARKS.md
/// "Main job"), the refined one must meet all three default goals (no inverted
/// element, minimum scaled Jacobian >= 0.3, mean >= 0.85, Hausdorff <= 1 %), be
/// closer to the surface than the first, and keep the input's genus; the report
/// lists every lattice meshed, the first one first.
#[test]
fn voxel_fallback_refines_its_lattice_until_the_goals_are_met() {
    // hexgen_rod, default options: 24 voxels miss the distance goal (1.88 %), 48
    // meet every goal with room (0.66 %), the lattice predicted from the two (38
    // voxels, 0.57 %) has room again, the next one predicted from 24 and 38 (32
    // voxels) misses the goal (1.13 %) and the one between (34, 0.53 %) is kept:
    // 2,935 elements where the first prediction alone kept 3,752, and 2,692 on
    // its lattice with the planes on the rod's faces (BENCHMARKS.md "Coarser
    // lattices while the kept one has room", "Boundary mean ascent", "Lattice
    // planes on the faces")
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/meshes");
    let mesh = TriMesh::load(dir.join("hexgen_rod.obj"), &LoadOptions::default()).unwrap();
    let frame = Affine::similarity(1.0, [0.0; 3]);
    let opts = HexOptions::default();
    let r = sddpm::hex::build_voxel_hex_mesh(&mesh, &frame, 2, &opts, &mut NoProgress).unwrap();
    assert_eq!(opts.goals.missed(&r), 0, "{}: {:?}, Hausdorff {}", r.domain, r.quality, r.hausdorff_relative);
    assert_eq!(boundary_genus(&r.mesh), 2);
    let meshed = r.stages[0].details_json()["lattices_meshed"].as_array().expect("lattices_meshed").clone();
    let res: Vec<u64> = meshed.iter().map(|m| m["resolution"].as_u64().unwrap()).collect();
    let h = |i: usize| meshed[i]["hausdorff_relative"].as_f64().unwrap();
    // the first lattice misses the goal, the finer one meets it with room
    assert_eq!(res[..2], [24, 48], "{meshed:?}");
    assert!(h(0) > opts.goals.hausdorff && h(1) < 0.95 * opts.goals.hausdorff, "{meshed:?}");
    assert!(r.hausdorff_relative < h(0) && r.domain != Domain::Voxel { resolution: 24 }, "{} {meshed:?}", r.domain);
    // two coarser lattices after the finest, each coarser than the last
    assert!(res.len() >= 4 && res[2] < 48 && res[3] < res[2], "{meshed:?}");
    // kept: a lattice coarser than the first prediction, with fewer elements
    let Domain::Voxel { resolution } = r.domain else { panic!("{}", r.domain) };
    let kept = resolution as u64;
    assert!(kept < res[2], "{} {meshed:?}", r.domain);
    assert!(r.quality.elements < meshed[2]["elements"].as_u64().unwrap() as usize, "{} {meshed:?}", r.quality.elements);
}

/// Side by side with HexGen's published mesh of the rod (reference_hex, 1,280
/// elements, its scaled Jacobian measured by the same code: minimum 0.319, mean
/// 0.832, 0.48 % from the input): the fallback's 28-voxel lattice with the coverage
/// step (`sddpm run --voxel-resolution 28 --voxel-refinements 0 --pin-uncovered
/// 0.6`) keeps its planes on the rod's two sides, 1,405 elements (1.10x) with
/// minimum 0.567, mean 0.877 and 0.94 % (BENCHMARKS.md "At HexGen's element
/// counts"): a minimum and a mean at least HexGen's at a comparable count, within
/// the 1 % goal (HexGen's surface fit is closer).
#[test]
fn at_hexgen_s_element_count_the_rod_s_minimum_and_mean_are_at_least_hexgen_s() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/meshes");
    let hexgen = sddpm::export::vtk::read_vtk_legacy(&dir.join("reference_hex/hexgen_rod_hex.vtk")).unwrap();
    let theirs = summarize(&element_qualities(&hexgen));
    assert_eq!(hexgen.elements.len(), 1280);
    assert!((theirs.min - 0.319).abs() < 5e-4 && (theirs.mean - 0.832).abs() < 5e-4, "{theirs:?}");
    let mesh = TriMesh::load(dir.join("hexgen_rod.obj"), &LoadOptions::default()).unwrap();
    let frame = Affine::similarity(1.0, [0.0; 3]);
    let mut opts = HexOptions::default();
    (opts.fallback.resolution, opts.fallback.refinements, opts.quality.pin_uncovered) = (28, 0, 0.6);
    let r = sddpm::hex::build_voxel_hex_mesh(&mesh, &frame, 2, &opts, &mut NoProgress).unwrap();
    let ours = &r.quality;
    assert!(ours.elements as f64 <= 1.5 * hexgen.elements.len() as f64, "{} elements", ours.elements);
    assert_eq!(ours.inverted, 0);
    assert!(ours.min >= theirs.min && ours.mean >= theirs.mean, "ours {ours:?}, HexGen {theirs:?}");
    assert!(r.hausdorff_relative <= opts.goals.hausdorff, "{}", r.hausdorff_relative);
    assert_eq!(boundary_genus(&r.mesh), 2);
}
