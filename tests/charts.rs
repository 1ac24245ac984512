//! Charts and chart maps: a warped box and a warped through-hole cube segment into
//! the charts of their polycube's faces and map onto them without flips; the
//! polycube path's hex meshes are irregular only along polycube edges.

use sddpm::context::{context_frame, Context};
use sddpm::error::NoProgress;
use sddpm::geometry::vec3::*;
use sddpm::hex::charts::{polycube_faces, segment_and_map, ChartOptions, PolycubeFaces};
use sddpm::hex::grid::lattice_hex;
use sddpm::hex::topology::{boundary_quads, HEX_EDGES};
use sddpm::hex::{build_hex_mesh, Affine, HexInput, HexMesh, HexOptions, MapMethod};
use sddpm::mesh::TriMesh;
use std::collections::HashMap;

#[path = "support/polycube_surface.rs"]
mod support;

/// The polycube's own boundary in the normalised frame, every quad split k x k
/// with alternating diagonals.
fn polycube_surface(ctx: &Context, k: usize) -> TriMesh {
    support::polycube_surface(ctx, k, support::Diagonals::Alternating)
}

/// A smooth warp (bend, anisotropic scale, twist) plus small deterministic noise,
/// then the bounding box mapped back onto the original one (as the hex stage's
/// input is: the input's box scaled onto the occupied cells' box).
fn warped(mut m: TriMesh, noise: f64) -> TriMesh {
    let bb0 = sddpm::geometry::Aabb::of_points(&m.vertices);
    for (i, p) in m.vertices.iter_mut().enumerate() {
        let [x, y, z] = *p;
        let h = ((i as f64 * 12.9898).sin() * 43758.5453).fract();
        let h2 = ((i as f64 * 78.233).sin() * 12345.6789).fract();
        let h3 = ((i as f64 * 3.7).sin() * 9876.54321).fract();
        *p = [1.25 * x + 0.08 * z * y + noise * h, 0.85 * y + 0.06 * x * x + noise * h2, z + 0.18 * x * x - 0.05 * y + noise * h3];
    }
    let bb = sddpm::geometry::Aabb::of_points(&m.vertices);
    let (s0, s) = (bb0.size(), bb.size());
    for p in m.vertices.iter_mut() {
        *p = std::array::from_fn(|a| bb0.min[a] + (p[a] - bb.min[a]) * s0[a] / s[a]);
    }
    m
}

fn input(ctx: &Context, surface: TriMesh) -> HexInput {
    HexInput { surface, context: *ctx, correspondence: vec![], to_user: Affine::similarity(1.0, [0.0; 3]) }
}

#[test]
fn a_warped_box_gives_six_disc_charts_and_eight_corners_mapped_without_flips() {
    let ctx = Context::parse("cube,0,0,0,0,0,0,0,0,0,0,0").unwrap();
    let surface = warped(polycube_surface(&ctx, 4), 0.01);
    let c = segment_and_map(&input(&ctx, surface), &ChartOptions::default()).unwrap();
    let seg = &c.segmentation;
    assert!(seg.is_valid(), "{:?}", seg.check());
    assert_eq!(seg.charts.len(), 6);
    for st in &seg.charts {
        assert_eq!((st.components, st.euler), (1, 1));
    }
    assert_eq!(seg.corners.iter().flatten().count(), 8);
    for (f, m) in c.maps.iter().enumerate() {
        let m = m.as_ref().unwrap_or_else(|e| panic!("face {}: {e}", c.faces.name(f)));
        assert!(m.convex);
        assert_eq!((m.flipped, m.degenerate), (0, 0), "face {}", c.faces.name(f));
    }
}

#[test]
fn a_warped_through_hole_cube_gives_the_charts_of_its_polycube() {
    let ctx = Context::parse("THC+Z,0,0,0,0,0,0,0,0,0,0,0").unwrap();
    let surface = warped(polycube_surface(&ctx, 3), 0.005);
    let c = segment_and_map(&input(&ctx, surface), &ChartOptions::default()).unwrap();
    let seg = &c.segmentation;
    assert_eq!(seg.charts.len(), c.faces.faces.len());
    assert_eq!(seg.charts.len(), 10);
    assert!(seg.is_valid(), "{:?}", seg.check());
    for st in &seg.charts {
        assert_eq!(st.components, 1);
        assert_eq!(st.euler, st.expected_euler);
    }
    assert_eq!(seg.corners.iter().flatten().count(), 16);
    // the 8 discs and the 2 annuli (cut into four quadrilaterals) map without a flip
    let mut annuli = 0;
    for (f, m) in c.maps.iter().enumerate() {
        let m = m.as_ref().unwrap_or_else(|e| panic!("face {}: {e}", c.faces.name(f)));
        assert_eq!((m.flipped, m.degenerate), (0, 0), "face {}", c.faces.name(f));
        annuli += usize::from(c.faces.faces[f].loops.len() == 2);
    }
    assert_eq!(annuli, 2);
}

#[test]
fn the_segmentation_reports_what_does_not_match() {
    // a box surface with the context of a through-hole cube: the hole walls get no chart
    let cube = Context::parse("cube,0,0,0,0,0,0,0,0,0,0,0").unwrap();
    let thc = Context::parse("THC+Z,0,0,0,0,0,0,0,0,0,0,0").unwrap();
    let c = segment_and_map(&input(&thc, polycube_surface(&cube, 3)), &ChartOptions::default()).unwrap();
    assert!(!c.segmentation.is_valid());
    let msg = c.segmentation.check().unwrap_err().to_string();
    assert!(msg.contains("has no chart"), "{msg}");
    // bad input: typed errors, no panic
    let mut bad = polycube_surface(&cube, 1);
    bad.triangles[0][0] = 1_000_000;
    assert!(segment_and_map(&input(&cube, bad), &ChartOptions::default()).is_err());
    let mut nan = polycube_surface(&cube, 1);
    nan.vertices[0][1] = f64::NAN;
    assert!(segment_and_map(&input(&cube, nan), &ChartOptions::default()).is_err());
    assert!(segment_and_map(&input(&Context::default(), polycube_surface(&cube, 1)), &ChartOptions::default()).is_err());
    let mut o = ChartOptions::default();
    o.sharp_angle = 0.0;
    assert!(segment_and_map(&input(&cube, polycube_surface(&cube, 1)), &o).is_err());
}

/// Irregular edges of a hex mesh: interior edges with other than 4 elements,
/// boundary edges with other than 2.
fn irregular_edges(m: &HexMesh) -> Vec<[u32; 2]> {
    let key = |a: u32, b: u32| if a < b { [a, b] } else { [b, a] };
    let mut valence: HashMap<[u32; 2], u32> = HashMap::new();
    for el in &m.elements {
        for e in HEX_EDGES {
            *valence.entry(key(el[e[0]], el[e[1]])).or_insert(0) += 1;
        }
    }
    let mut on_boundary = std::collections::HashSet::new();
    for q in boundary_quads(m).unwrap() {
        for i in 0..4 {
            on_boundary.insert(key(q.nodes[i], q.nodes[(i + 1) % 4]));
        }
    }
    valence.into_iter().filter(|(e, v)| if on_boundary.contains(e) { *v != 2 } else { *v != 4 }).map(|(e, _)| e).collect()
}

/// Mesh `ctx` through the polycube path at level 1 and check that every irregular
/// edge of the mapped mesh (and of the returned mesh without pillowing) lies on a
/// polycube edge, mapped back through the lattice (node i of the mapped mesh is
/// lattice node i). Returns the irregular counts (mapped, returned with pillowing).
fn irregular_on_polycube_edges(ctx: &Context, surface: TriMesh) -> (usize, usize) {
    let pf: PolycubeFaces = polycube_faces(ctx).unwrap();
    let frame = context_frame(ctx).unwrap();
    let inp = input(ctx, surface);
    let mut opts = HexOptions::default();
    opts.map.level = Some(1);
    opts.quality.pillow = false;
    let r = build_hex_mesh(&inp, &opts, &mut NoProgress).unwrap();
    let lat = lattice_hex(&ctx.assemble(), r.level);
    assert_eq!(r.mapped.elements, lat.mesh.elements, "the mapped mesh is the lattice mesh");
    assert_eq!(r.mesh.elements, lat.mesh.elements, "without pillowing the returned mesh keeps the lattice topology");
    let on_edge = |e: &[u32; 2]| {
        let mid = scale(add(lat.mesh.nodes[e[0] as usize], lat.mesh.nodes[e[1] as usize]), 0.5);
        pf.on_edge(frame.to_normalised(mid), 1e-9)
    };
    let irr = irregular_edges(&r.mapped);
    let off: Vec<&[u32; 2]> = irr.iter().filter(|e| !on_edge(e)).collect();
    assert!(off.is_empty(), "{} of {} irregular edges off the polycube edges", off.len(), irr.len());
    let off_final = irregular_edges(&r.mesh).iter().filter(|e| !on_edge(e)).count();
    assert_eq!(off_final, 0);
    // with the default pillowing: counted, for the report
    opts.quality.pillow = true;
    let rp = build_hex_mesh(&inp, &opts, &mut NoProgress).unwrap();
    (irr.len(), irregular_edges(&rp.mesh).len())
}

#[test]
fn polycube_meshes_are_irregular_only_along_polycube_edges() {
    let cube = Context::parse("cube,0,0,0,0,0,0,0,0,0,0,0").unwrap();
    let (m, p) = irregular_on_polycube_edges(&cube, warped(polycube_surface(&cube, 2), 0.0));
    // a cube's boundary edges along its 12 edges (6 lattice edges each at level 1)
    assert_eq!(m, 72);
    eprintln!("cube: {m} irregular edges mapped, {p} after pillowing");
    let thc = Context::parse("THC+Z,0,0,0,0,0,0,0,0,0,0,0").unwrap();
    let (m, p) = irregular_on_polycube_edges(&thc, warped(polycube_surface(&thc, 2), 0.0));
    eprintln!("THC: {m} irregular edges mapped, {p} after pillowing");
    assert!(m > 72);
}

#[test]
fn a_warped_l_shape_gives_eight_charts_and_maps_its_l_shaped_faces() {
    let ctx = Context::parse("cube,cube,0,cube,0,0,0,0,0,0,0,0").unwrap();
    let surface = warped(polycube_surface(&ctx, 3), 0.005);
    let c = segment_and_map(&input(&ctx, surface), &ChartOptions::default()).unwrap();
    assert!(c.segmentation.is_valid(), "{:?}", c.segmentation.check());
    assert_eq!(c.segmentation.charts.len(), 8);
    let mut non_convex = 0;
    for (f, m) in c.maps.iter().enumerate() {
        let m = m.as_ref().unwrap_or_else(|e| panic!("face {}: {e}", c.faces.name(f)));
        // Tutte is only guaranteed on the convex faces; the L-shaped ones are counted
        eprintln!("face {}: convex {}, {} flipped, {} without area", c.faces.name(f), m.convex, m.flipped, m.degenerate);
        if m.convex {
            assert_eq!((m.flipped, m.degenerate), (0, 0), "face {}", c.faces.name(f));
        } else {
            non_convex += 1;
        }
    }
    assert_eq!(non_convex, 2);
}

/// Mesh `ctx` through the polycube path at level 1 with the chart surface map and
/// check the mapped mesh: no inverted element, every boundary node on the input
/// (within 1e-9 of the diagonal), and every node on one polycube face at the inverse
/// map of its polycube point, in a triangle of that face's chart.
fn chart_surface_map_is_on_the_input_and_in_the_right_chart(ctx: &Context, surface: TriMesh, corners: usize, chains: usize) {
    use sddpm::hex::charts::ChartInverse;
    let frame = context_frame(ctx).unwrap();
    let inp = input(ctx, surface.clone());
    let mut opts = HexOptions::default();
    opts.map.level = Some(1);
    opts.map.surface_map = sddpm::hex::SurfaceMap::Charts;
    let r = build_hex_mesh(&inp, &opts, &mut NoProgress).unwrap();
    assert_eq!(r.surface_map.method, MapMethod::Charts, "{:?}", r.surface_map.why);
    assert_eq!(r.surface_map.why, None);
    // the polycube's corners and edges land on the input's feature corners and
    // sharp curves, which the quality steps then keep them on
    let sm = &r.surface_map;
    assert_eq!((sm.matched_corners, sm.matched_chains), (corners, chains), "{sm:?}");
    let q = sddpm::hex::quality::summary(&r.mapped);
    assert_eq!(q.inverted, 0, "inverted elements after mapping (min SJ {:.3})", q.min);
    let diag = sddpm::geometry::Aabb::of_points(&surface.vertices).diagonal();
    let loc = sddpm::geometry::SurfaceLocator::new(&surface);
    let c = segment_and_map(&inp, &ChartOptions::default()).unwrap();
    let ci = ChartInverse::new(&surface, &c).unwrap();
    let lat = lattice_hex(&ctx.assemble(), r.level);
    assert_eq!(r.mapped.elements, lat.mesh.elements, "the mapped mesh is the lattice mesh");
    let mut on_boundary = std::collections::HashSet::new();
    for bq in boundary_quads(&r.mapped).unwrap() {
        on_boundary.extend(bq.nodes);
    }
    let mut single = 0;
    for &v in &on_boundary {
        let p = r.mapped.nodes[v as usize];
        let d = loc.closest(p).2;
        assert!(d < 1e-9 * diag, "boundary node {v} is {d:e} off the input");
        let u = frame.to_normalised(lat.mesh.nodes[v as usize]);
        let faces = ci.faces_at(u);
        assert!(!faces.is_empty(), "boundary node {v} is on no polycube face");
        let l = ci.locate(u).unwrap();
        assert!(norm(sub(l.point, p)) < 1e-9 * diag, "node {v} is not at its chart image");
        if faces.len() == 1 {
            single += 1;
            assert_eq!(c.segmentation.face_of[l.triangle as usize] as usize, faces[0], "node {v} is outside its face's chart");
        }
    }
    assert!(single > 0);
}

#[test]
fn the_chart_surface_map_meshes_a_warped_box_and_a_warped_torus() {
    let cube = Context::parse("cube,0,0,0,0,0,0,0,0,0,0,0").unwrap();
    chart_surface_map_is_on_the_input_and_in_the_right_chart(&cube, warped(polycube_surface(&cube, 4), 0.01), 8, 12);
    let thc = Context::parse("THC+Z,0,0,0,0,0,0,0,0,0,0,0").unwrap();
    chart_surface_map_is_on_the_input_and_in_the_right_chart(&thc, warped(polycube_surface(&thc, 3), 0.005), 16, 24);
}

#[test]
fn the_chart_surface_map_falls_back_to_the_projection_with_the_reason() {
    // a box surface with the context of a through-hole cube: the hole walls get no chart
    let cube = Context::parse("cube,0,0,0,0,0,0,0,0,0,0,0").unwrap();
    let thc = Context::parse("THC+Z,0,0,0,0,0,0,0,0,0,0,0").unwrap();
    let mut opts = HexOptions::default();
    opts.map.level = Some(1);
    opts.map.surface_map = sddpm::hex::SurfaceMap::Charts;
    let r = build_hex_mesh(&input(&thc, polycube_surface(&cube, 3)), &opts, &mut NoProgress).unwrap();
    assert_eq!(r.surface_map.method, MapMethod::Projection);
    let why = r.surface_map.why.clone().expect("the reason is recorded");
    assert!(why.contains("has no chart"), "{why}");
    let js = sddpm::hex::report_json(&r);
    assert_eq!(js["surface_map"]["method"], "projection", "{js}");
}

#[test]
fn the_best_surface_map_keeps_the_charts_mesh_that_meets_the_goals_and_ranks_both_when_it_does_not() {
    let cube = Context::parse("cube,0,0,0,0,0,0,0,0,0,0,0").unwrap();
    let inp = input(&cube, warped(polycube_surface(&cube, 4), 0.01));
    let mut opts = HexOptions::default();
    assert_eq!(opts.map.surface_map, sddpm::hex::SurfaceMap::Best, "the default");
    opts.map.level = Some(1);
    // the charts' mesh meets the goals: it is kept and the projection is not built
    let r = build_hex_mesh(&inp, &opts, &mut NoProgress).unwrap();
    assert_eq!(opts.goals.missed(&r), 0);
    assert_eq!(r.surface_map.method, MapMethod::Charts);
    let tried = &r.surface_map.tried;
    assert_eq!(tried.len(), 1, "{tried:?}");
    assert!(tried[0].kept && tried[0].method == MapMethod::Charts && tried[0].goals_missed == 0, "{tried:?}");
    // a goal neither meets: both maps are meshed, the better by the goals kept
    opts.goals.hausdorff = 1e-12;
    let r = build_hex_mesh(&inp, &opts, &mut NoProgress).unwrap();
    let tried = &r.surface_map.tried;
    assert_eq!(tried.iter().map(|t| t.method.name()).collect::<Vec<_>>(), ["charts", "projection"], "{tried:?}");
    assert_eq!(tried.iter().filter(|t| t.kept).count(), 1, "{tried:?}");
    let kept = tried.iter().find(|t| t.kept).unwrap();
    assert_eq!(kept.method, r.surface_map.method);
    assert_eq!((kept.elements, kept.inverted), (r.quality.elements, r.quality.inverted));
    assert_eq!(kept.hausdorff_relative, r.hausdorff_relative);
    let other = tried.iter().find(|t| !t.kept).unwrap();
    let key = |t: &sddpm::hex::report::SurfaceMapTry| (t.inverted, t.goals_missed);
    assert!(key(kept) <= key(other), "{tried:?}");
    let js = sddpm::hex::report_json(&r);
    assert_eq!(js["surface_map"]["tried"].as_array().map(Vec::len), Some(2), "{js}");
    // charts that cannot be built: the projection's mesh alone, the reason recorded
    let thc = Context::parse("THC+Z,0,0,0,0,0,0,0,0,0,0,0").unwrap();
    let r = build_hex_mesh(&input(&thc, polycube_surface(&cube, 3)), &opts, &mut NoProgress).unwrap();
    assert_eq!(r.surface_map.method, MapMethod::Projection);
    assert!(r.surface_map.why.is_some());
    assert_eq!(r.surface_map.tried.len(), 1);
}

#[test]
fn a_mesh_that_misses_the_distance_goal_alone_is_also_meshed_one_level_finer() {
    let cube = Context::parse("cube,0,0,0,0,0,0,0,0,0,0,0").unwrap();
    let inp = input(&cube, warped(polycube_surface(&cube, 4), 0.01));
    let mut opts = HexOptions::default();
    opts.map.max_level = 3;
    // only the distance goal can be missed
    opts.goals.min_scaled_jacobian = -0.99;
    opts.goals.mean_scaled_jacobian = -0.99;
    opts.goals.hausdorff = 1e-12;
    // the finer level alone (local refinement: the next test)
    opts.map.local_refinement = 0;
    let r = build_hex_mesh(&inp, &opts, &mut NoProgress).unwrap();
    let tried = &r.surface_map.tried;
    let methods: Vec<&str> = tried.iter().map(|t| t.method.name()).collect();
    assert_eq!(methods.len(), 3, "{tried:?}");
    assert_eq!(&methods[..2], ["charts", "projection"], "{tried:?}");
    let finer = &tried[2];
    assert_eq!(finer.level, tried[0].level.max(tried[1].level) + 1, "{tried:?}");
    assert!(finer.elements > tried[0].elements.max(tried[1].elements), "{tried:?}");
    assert_eq!(tried.iter().filter(|t| t.kept).count(), 1, "{tried:?}");
    let kept = tried.iter().find(|t| t.kept).unwrap();
    assert_eq!((kept.level, kept.elements), (r.level, r.quality.elements), "{tried:?}");
    // a level the caller fixed is kept as it is
    opts.map.level = Some(1);
    let r = build_hex_mesh(&inp, &opts, &mut NoProgress).unwrap();
    assert_eq!(r.level, 1);
    assert!(r.surface_map.tried.iter().all(|t| t.level == 1), "{:?}", r.surface_map.tried);
}

/// A box whose top face has a round bump off its centre: far from a coarse
/// level's mesh there and nowhere else.
fn bumped_box(k: usize) -> (Context, TriMesh) {
    let cube = Context::parse("cube,0,0,0,0,0,0,0,0,0,0,0").unwrap();
    let mut m = polycube_surface(&cube, k);
    let bb0 = sddpm::geometry::Aabb::of_points(&m.vertices);
    let s = bb0.size();
    let c = [bb0.min[0] + 0.3 * s[0], bb0.min[1] + 0.3 * s[1]];
    let r = 0.2 * s[0];
    for p in m.vertices.iter_mut() {
        let d = ((p[0] - c[0]).powi(2) + (p[1] - c[1]).powi(2)).sqrt();
        if p[2] > bb0.max[2] - 1e-9 && d < r {
            p[2] += 0.08 * s[2] * (1.0 - (d / r).powi(2)).powi(2);
        }
    }
    // the input's box onto the occupied cells' box, as the hex stage's input is
    let bb = sddpm::geometry::Aabb::of_points(&m.vertices);
    let sz = bb.size();
    for p in m.vertices.iter_mut() {
        *p = std::array::from_fn(|a| bb0.min[a] + (p[a] - bb.min[a]) * s[a] / sz[a]);
    }
    (cube, m)
}

#[test]
fn a_mesh_far_from_the_input_in_one_place_is_refined_there_alone() {
    let (cube, surface) = bumped_box(24);
    let inp = input(&cube, surface);
    let mut opts = HexOptions::default();
    opts.map.max_level = 2;
    opts.map.min_level = 2;
    opts.map.surface_map = sddpm::hex::SurfaceMap::Charts;
    // only the distance goal can be missed, and the level's mesh misses it
    opts.goals.min_scaled_jacobian = -0.99;
    opts.goals.mean_scaled_jacobian = -0.99;
    opts.map.local_refinement = 0;
    let plain = build_hex_mesh(&inp, &opts, &mut NoProgress).unwrap();
    assert_eq!(plain.level, 2);
    opts.goals.hausdorff = 0.5 * plain.hausdorff_relative;
    opts.map.local_refinement = 2;
    let r = build_hex_mesh(&inp, &opts, &mut NoProgress).unwrap();
    let tried = &r.surface_map.tried;
    let local: Vec<_> = tried.iter().filter(|t| t.split_elements > 0).collect();
    assert!(!local.is_empty(), "{tried:?}");
    let level_elements = tried[0].elements;
    for t in &local {
        // refined around the bump, not everywhere: a fifth of the level at most
        assert!(t.split_elements * 5 < level_elements, "{tried:?}");
        assert!(t.elements > level_elements && t.inverted == 0, "{tried:?}");
        assert_eq!(t.level, 2, "{tried:?}");
    }
    // the refined mesh is nearer the input than the level's, and it is the one kept
    let best_local = local.iter().map(|t| t.hausdorff_relative).fold(f64::INFINITY, f64::min);
    assert!(best_local < 0.8 * plain.hausdorff_relative, "{} -> {tried:?}", plain.hausdorff_relative);
    assert!(r.hausdorff_relative <= best_local + 1e-12 && r.quality.elements > level_elements, "{tried:?}");
    assert_eq!(r.quality.inverted, 0);
    assert_eq!(tried.iter().filter(|t| t.kept).count(), 1, "{tried:?}");
    // conforming: every boundary quad's edges are shared by exactly two boundary quads
    let q = sddpm::hex::topology::boundary_quads(&r.mesh).unwrap();
    let mut edges: HashMap<(u32, u32), usize> = HashMap::new();
    for b in &q {
        for i in 0..4 {
            let (a, c) = (b.nodes[i], b.nodes[(i + 1) % 4]);
            *edges.entry((a.min(c), a.max(c))).or_default() += 1;
        }
    }
    assert!(edges.values().all(|&n| n == 2), "the refined mesh's boundary is not closed and manifold");
    // a box warped and roughened all over with a distance goal every point
    // misses: the far region is the whole level, whose split would outgrow the
    // level one finer, so no round is meshed
    opts.goals.hausdorff = 1e-12;
    let r = build_hex_mesh(&input(&cube, warped(polycube_surface(&cube, 4), 0.01)), &opts, &mut NoProgress).unwrap();
    assert!(r.surface_map.tried.iter().all(|t| t.split_elements == 0), "{:?}", r.surface_map.tried);
}
