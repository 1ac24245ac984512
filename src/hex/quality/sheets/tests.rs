use super::insert::insert_sheet;
use super::patches::{merge_narrow_patches, triangle_patches};
use super::*;
use crate::geometry::vec3::*;
use crate::hex::topology::hex_volume;
use crate::hex::Stage;
use crate::hex::{build_voxel_hex_mesh, Affine, HexOptions};
use crate::mesh::TriMesh;

/// A 6 x 4 x 3 box of unit voxels' faces, turned so that none of its edges
/// runs along a lattice axis.
fn turned_box() -> TriMesh {
    let m = crate::geometry::trimesh::tests::voxels([6, 4, 3], |_, _, _| true);
    let (a, b) = (25f64.to_radians(), 15f64.to_radians());
    let v = m
        .vertices
        .iter()
        .map(|p| {
            // about z by a, then about x by b
            let q = [p[0] * a.cos() - p[1] * a.sin(), p[0] * a.sin() + p[1] * a.cos(), p[2]];
            [q[0], q[1] * b.cos() - q[2] * b.sin(), q[1] * b.sin() + q[2] * b.cos()]
        })
        .collect();
    TriMesh { vertices: v, triangles: m.triangles }
}

/// A unit cube whose edge along x at y = z = 1 is cut by a 45-degree chamfer
/// `c` deep on both faces (`c` * sqrt 2 wide).
fn chamfered_cube(c: f64) -> TriMesh {
    let vertices = vec![
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0, 1.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, 0.0, 1.0],
        [1.0, 0.0, 1.0],
        [0.0, 1.0 - c, 1.0],
        [1.0, 1.0 - c, 1.0],
        [0.0, 1.0, 1.0 - c],
        [1.0, 1.0, 1.0 - c],
    ];
    let faces: [&[u32]; 7] = [&[0, 3, 8, 6, 4], &[1, 5, 7, 9, 2], &[0, 4, 5, 1], &[0, 1, 2, 3], &[3, 2, 9, 8], &[4, 6, 7, 5], &[8, 9, 7, 6]];
    let mut triangles = Vec::new();
    for f in faces {
        for k in 1..f.len() - 1 {
            let t = [f[0], f[k], f[k + 1]];
            let p = t.map(|i| vertices[i as usize]);
            let n = cross(sub(p[1], p[0]), sub(p[2], p[0]));
            let out = sub(scale(add(add(p[0], p[1]), p[2]), 1.0 / 3.0), [0.5; 3]);
            triangles.push(if dot(n, out) > 0.0 { t } else { [t[0], t[2], t[1]] });
        }
    }
    TriMesh { vertices, triangles }
}

#[test]
fn a_chamfer_narrower_than_the_limit_joins_a_neighbouring_face() {
    let mesh = chamfered_cube(0.05);
    let sw = Surface::new(mesh.clone(), crate::hex::surface::detect_features(&mesh, 40.0, 45.0));
    let (tp, np) = triangle_patches(&sw);
    assert_eq!(np, 7);
    // the chamfer: 0.0707 wide, twice its area over its perimeter 0.066
    let chamfer = tp[tp.len() - 1];
    let et = crate::hex::surface::edge_triangles(&mesh);
    let (merged, n, k) = merge_narrow_patches(&sw, &et, &tp, np, 0.1);
    assert_eq!((n, k), (6, 1));
    // into the y = 1 face (triangles 10, 11) or the z = 1 face (12, 13), which
    // share as much of its boundary and are as steep to it
    let c = merged[merged.len() - 1];
    assert!(c == merged[10] || c == merged[12], "{merged:?}");
    assert_ne!(merged[10], merged[12]);
    // the six faces of the cube keep a patch each
    let mut faces = merged[..14].to_vec();
    faces.sort_unstable();
    faces.dedup();
    assert_eq!(faces.len(), 6);
    // a limit under its width: nothing merged
    let (same, n, k) = merge_narrow_patches(&sw, &et, &tp, np, 0.05);
    assert_eq!((n, k), (7, 0));
    assert_eq!(same.iter().filter(|&&p| p == same[same.len() - 1]).count(), tp.iter().filter(|&&p| p == chamfer).count());
}

#[test]
fn a_turned_box_keeps_its_edges_and_corners_with_the_sheets() {
    let mesh = turned_box();
    let one = |sheets: bool| { let mut o = HexOptions::default(); o.fallback.resolution = 12; o.fallback.refinements = 0; o.quality.feature_sheets = sheets; o };
    let id = Affine::similarity(1.0, [0.0; 3]);
    let plain = build_voxel_hex_mesh(&mesh, &id, 0, &one(false), &mut crate::error::NoProgress).unwrap();
    let r = build_voxel_hex_mesh(&mesh, &id, 0, &one(true), &mut crate::error::NoProgress).unwrap();
    let st = r.stages.iter().find(|s| s.stage == Stage::FeatureSheets).expect("a feature-sheets stage");
    let d = &st.details_json();
    assert_eq!(d["patches"], 6, "{d}");
    assert_eq!(d["sheets"], 6, "{d}");
    assert_eq!(d["kept"], true, "{d}");
    assert_eq!(d["corner_nodes"], 8, "{d}");
    assert!(d["curve_nodes"].as_u64().unwrap() > 12, "{d}");
    assert_eq!(r.quality.inverted, 0, "{:?}", r.quality);
    assert!(r.quality.min > 0.2, "{:?}", r.quality);
    // the box's corners are nodes of the result
    let corners = [[0.0, 0.0, 0.0], [6.0, 0.0, 0.0], [0.0, 4.0, 0.0], [6.0, 4.0, 3.0]];
    let turned = turned_box();
    for c in corners {
        let k = crate::geometry::trimesh::tests::voxels([6, 4, 3], |_, _, _| true).vertices.iter().position(|p| *p == c).unwrap();
        let x = turned.vertices[k];
        let near = r.mesh.nodes.iter().map(|p| norm(sub(*p, x))).fold(f64::INFINITY, f64::min);
        assert!(near < 1e-9, "corner {c:?}: nearest node {near}");
    }
    // closer to the input than without the sheets, by more than a third
    assert!(r.hausdorff_relative < 0.67 * plain.hausdorff_relative, "{} vs {}", r.hausdorff_relative, plain.hausdorff_relative);
    let v = mesh.signed_volume();
    assert!((r.volume - v).abs() < 0.01 * v, "{} vs {v}", r.volume);
}

/// The voxel fallback's mesh of hexgen_rod with these options.
fn rod_lattice(opts: &HexOptions) -> crate::hex::HexResult {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/meshes/hexgen_rod.obj");
    let mesh = TriMesh::load(&path, &crate::mesh::LoadOptions::default()).unwrap();
    let genus = mesh.validate().unwrap().genus.unwrap();
    build_voxel_hex_mesh(&mesh, &Affine::similarity(1.0, [0.0; 3]), genus, opts, &mut crate::error::NoProgress).unwrap()
}

#[test]
fn the_rod_meets_every_goal_at_36_voxels_with_every_corner_held() {
    // hexgen_rod at 36 voxels with the coverage step: plain 1.10 % away; with
    // the sheets, its four concave corners (where the small end's step meets
    // the shoulder) have a face of 52-60 degrees, which the sheets split into
    // two quads: elements at 0.24, and the corners had to be released (0.485 %).
    // With those faces' lattice quads kept out of their sheets every corner is
    // held within the minimum goal, and the first mesh meets every goal
    // (0.47 %; HexGen's rod: 0.48 % at 1,280 elements; BENCHMARKS.md "One quad
    // for a narrow face at a corner"), where the fallback without the sheets
    // needed 48 voxels (5,723 elements)
    let opts = { let mut o = HexOptions::default(); o.fallback.resolution = 36; o.fallback.refinements = 0; o.quality.pin_uncovered = 0.6; o };
    let r = rod_lattice(&opts);
    let note = &r.stages[0].details_json()["feature_sheets"];
    assert_eq!((&note["compared"], &note["kept"]), (&serde_json::json!(false), &serde_json::json!(true)), "{note}");
    assert_eq!(opts.goals.missed(&r), 0, "{:?} {}", r.quality, r.hausdorff_relative);
    // within a tenth of HexGen's 0.48 % (one lattice's trajectory carries
    // about a tenth of noise, "Lattice placement at HexGen's counts")
    assert!(r.hausdorff_relative < 0.0053, "{}", r.hausdorff_relative);
    assert!(r.quality.elements < 5_723, "{}", r.quality.elements);
    let st = r.stages.iter().find(|s| s.stage == Stage::FeatureSheets).unwrap();
    let d = &st.details_json();
    // the rod has 8 feature corners, all held; 4 with a narrow face
    assert_eq!((d["kept"].as_bool(), d["corner_nodes"].as_u64(), d["narrow_corners"].as_u64()), (Some(true), Some(8), Some(4)), "{d}");
    let held: Vec<[u32; 2]> = serde_json::from_value(d["corners_held"].clone()).unwrap();
    for [v, _] in held {
        let worst = r.mesh.elements.iter().zip(&r.scaled_jacobian).filter(|(el, _)| el.contains(&v)).map(|(_, &q)| q).fold(f64::INFINITY, f64::min);
        assert!(worst >= opts.goals.min_scaled_jacobian, "corner node {v} at {:?}: an element at {worst}", r.mesh.nodes[v as usize]);
    }
}

#[test]
fn the_rod_at_33_voxels_releases_every_corner_when_the_concave_ones_leave_it_short() {
    // hexgen_rod at 33 voxels, default options (a lattice the main job used
    // to choose): the sheets' mesh misses the minimum at the
    // 4 concave corners; with those released it is valid but 1.06 % away;
    // with all 8 released 0.93 %, every goal met (BENCHMARKS.md "Releasing
    // every corner when the corners at fault are not enough")
    // (the narrow corner faces off: with them the concave corners are held
    // within the minimum goal and nothing is released, "One quad for a narrow
    // face at a corner")
    let opts = { let mut o = HexOptions::default(); o.fallback.resolution = 33; o.fallback.refinements = 0; o.quality.narrow_corner_faces = 0.0; o };
    let r = rod_lattice(&opts);
    let note = &r.stages[0].details_json()["feature_sheets"];
    assert_eq!((note["corners_released"].as_u64(), note["corners_released_all"].as_u64()), (Some(4), Some(8)), "{note}");
    // the targeted release missed a goal (that is why every corner was tried)
    let rel = &note["released"];
    let missed = rel["inverted"].as_u64() != Some(0)
        || rel["min_scaled_jacobian"].as_f64().unwrap() < opts.goals.min_scaled_jacobian
        || rel["mean_scaled_jacobian"].as_f64().unwrap() < opts.goals.mean_scaled_jacobian
        || rel["hausdorff_relative"].as_f64().unwrap() > opts.goals.hausdorff;
    assert!(missed, "{note}");
    assert_eq!(note["chosen"], "released_all", "{note}");
    assert_eq!(opts.goals.missed(&r), 0, "{:?} {}", r.quality, r.hausdorff_relative);
    let st = r.stages.iter().find(|s| s.stage == Stage::FeatureSheets).unwrap();
    assert_eq!((st.details_json()["kept"].as_bool(), st.details_json()["corner_nodes"].as_u64()), (Some(true), Some(0)), "{}", st.details_json());
}

#[test]
fn the_sheets_of_hepta_are_kept_through_the_inversions_at_20_voxels() {
    // hexgen_hepta's 45-degree chamfers are narrower than a voxel at 20: the
    // two sheets of a chamfer meet and the smoothing leaves 13 elements
    // inverted (the sheets used to be undone there); the steps after it untangle them, and with the corners whose
    // elements stay below the minimum goal released every goal but the
    // distance is met, much closer than without the sheets (1.07 % against
    // 1.71 %, BENCHMARKS.md "Feature sheets through the inversions")
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/meshes/hexgen_hepta.obj");
    let mesh = TriMesh::load(&path, &crate::mesh::LoadOptions::default()).unwrap();
    // (the uniform lattice only, on which these figures were measured)
    let one = |sheets: bool| { let mut o = HexOptions::default(); o.fallback.resolution = 20; o.fallback.refinements = 0; o.quality.feature_sheets = sheets; o.fallback.lattice_planes = 0.0; o };
    let id = Affine::similarity(1.0, [0.0; 3]);
    let plain = build_voxel_hex_mesh(&mesh, &id, 0, &one(false), &mut crate::error::NoProgress).unwrap();
    let r = build_voxel_hex_mesh(&mesh, &id, 0, &one(true), &mut crate::error::NoProgress).unwrap();
    let st = r.stages.iter().find(|s| s.stage == Stage::FeatureSheets).expect("a feature-sheets stage");
    assert_eq!(st.details_json()["kept"], true, "{}", st.details_json());
    let note = &r.stages[0].details_json()["feature_sheets"];
    assert_eq!((&note["compared"], &note["chosen"]), (&serde_json::json!(true), &serde_json::json!("released")), "{note}");
    assert_eq!(r.quality.inverted, 0, "{:?}", r.quality);
    assert!(r.quality.min >= one(true).goals.min_scaled_jacobian && r.quality.mean >= one(true).goals.mean_scaled_jacobian, "{:?}", r.quality);
    assert!(r.hausdorff_relative < 0.8 * plain.hausdorff_relative, "{} vs {}", r.hausdorff_relative, plain.hausdorff_relative);
}

#[test]
fn hepta_keeps_its_sheets_at_12_voxels_with_its_chamfers_merged() {
    // with the 45- and 51-degree curves followed (feature_median_angle 40),
    // hexgen_hepta at 12 voxels has 21 patches, its chamfers and ledges
    // 0.59-0.70 of the lattice's spacing wide; merged into their neighbours,
    // the sheets hold and the mesh comes within the distance goal (without
    // the merge: min 0.05, 2.92 %, the plain mesh chosen; BENCHMARKS.md
    // "Narrow patches merged")
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/meshes/hexgen_hepta.obj");
    let mesh = TriMesh::load(&path, &crate::mesh::LoadOptions::default()).unwrap();
    let opts = { let mut o = HexOptions::default(); o.fallback.resolution = 12; o.fallback.refinements = 0; o.surface.feature_median_angle = 40.0; o.quality.pin_uncovered = 0.6; o };
    let r = build_voxel_hex_mesh(&mesh, &Affine::similarity(1.0, [0.0; 3]), 0, &opts, &mut crate::error::NoProgress).unwrap();
    let st = r.stages.iter().find(|s| s.stage == Stage::FeatureSheets).expect("a feature-sheets stage");
    assert!(st.details_json()["narrow_patches_merged"].as_u64().unwrap() >= 4, "{}", st.details_json());
    let note = &r.stages[0].details_json()["feature_sheets"];
    assert_eq!(note["chosen"], "with", "{note}");
    assert_eq!(r.quality.inverted, 0, "{:?}", r.quality);
    assert!(r.quality.min >= opts.goals.min_scaled_jacobian, "{:?}", r.quality);
    let without = note["without"]["hausdorff_relative"].as_f64().unwrap();
    assert!(r.hausdorff_relative <= opts.goals.hausdorff && r.hausdorff_relative < 0.5 * without, "{} vs {without}", r.hausdorff_relative);
}

#[test]
fn a_sheet_under_half_a_box_keeps_the_mesh_conforming() {
    // a 2 x 1 x 1 block of unit hexes, the first flagged: one sheet face (the
    // shared face), its four nodes copied; the new element sits between
    let mesh = super::super::HexMesh {
        nodes: (0..12).map(|i| [(i % 3) as f64, ((i / 3) % 2) as f64, (i / 6) as f64]).collect(),
        elements: vec![[0, 1, 4, 3, 6, 7, 10, 9], [1, 2, 5, 4, 7, 8, 11, 10]],
    };
    let mut w = Work {
        mesh: mesh.clone(),
        role: vec![Role::Free; 12],
        attach: vec![u32::MAX; 12],
        curve_nb: vec![Vec::new(); 12],
        bgraph: Default::default(),
        nbr: Default::default(),
        n2e: Default::default(),
        target: vec![[1.0; 3]; 2],
    };
    w.rebuild();
    let (nodes, elements, negative) = insert_sheet(&mut w, &[true, false]);
    assert_eq!((nodes, elements, negative), (4, 1, 0));
    assert_eq!(w.mesh.elements.len(), 3);
    let bq = boundary_quads(&w.mesh).unwrap();
    // 10 boundary faces of the block, plus the new element's 4 sides
    assert_eq!(bq.len(), 14);
    // the flagged element took the copies, the other kept the originals, and
    // every element is positive (the copies moved a quarter of the way into
    // the flagged element)
    assert!(w.mesh.elements[0].iter().filter(|&&v| v >= 12).count() == 4 && w.mesh.elements[1].iter().all(|&v| v < 12));
    assert!((0..3).all(|e| hex_volume(&w.mesh.element_corners(e)) > 0.0));
    assert_eq!(w.role[12..], [Role::Free; 4]);
}
