//! Unit tests on meshes built in code.

use super::*;
use crate::error::Status;
use crate::geometry::trimesh::tests::voxels;

pub(crate) fn tetrahedron() -> TriMesh {
    TriMesh {
        vertices: vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
        triangles: vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
    }
}

pub(crate) fn cube() -> TriMesh {
    voxels([1, 1, 1], |_, _, _| true)
}

/// Picture frame: 3 x 3 outer, 1 x 1 hole, height 1.
pub(crate) fn square_torus() -> TriMesh {
    voxels([3, 3, 1], |x, y, _| !(x == 1 && y == 1))
}

fn translated(m: &TriMesh, d: [f64; 3]) -> TriMesh {
    TriMesh { vertices: m.vertices.iter().map(|p| [p[0] + d[0], p[1] + d[1], p[2] + d[2]]).collect(), triangles: m.triangles.clone() }
}

fn union(a: &TriMesh, b: &TriMesh) -> TriMesh {
    let off = a.vertices.len() as u32;
    let mut m = a.clone();
    m.vertices.extend_from_slice(&b.vertices);
    m.triangles.extend(b.triangles.iter().map(|t| t.map(|v| v + off)));
    m
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-12 * (1.0 + b.abs())
}

fn kinds(r: &MeshReport) -> Vec<IssueKind> {
    r.issues.iter().filter(|i| i.severity == Severity::Error).map(|i| i.kind).collect()
}

#[test]
fn tetrahedron_measures() {
    let r = tetrahedron().validate().expect("valid");
    assert_eq!((r.vertices, r.triangles, r.edges), (4, 4, 6));
    assert_eq!(r.euler_characteristic, 2);
    assert_eq!(r.genus, Some(0));
    assert!(close(r.volume, 1.0 / 6.0));
    assert!(close(r.area, 1.5 + 3f64.sqrt() / 2.0));
    assert!(r.closed && r.manifold && r.orientation_consistent && r.oriented_outward);
    assert_eq!(r.bbox_min, [0.0; 3]);
    assert_eq!(r.bbox_max, [1.0; 3]);
}

#[test]
fn cube_measures() {
    let r = cube().validate().expect("valid");
    assert_eq!((r.vertices, r.triangles, r.edges, r.components), (8, 12, 18, 1));
    assert_eq!(r.genus, Some(0));
    assert!(close(r.volume, 1.0));
    assert!(close(r.area, 6.0));
    assert_eq!(r.self_intersecting_pairs, 0);
    assert_eq!(r.degenerate_triangles, 0);
}

#[test]
fn square_torus_measures() {
    let m = square_torus();
    let r = m.validate().expect("valid");
    assert_eq!((r.vertices, r.triangles), (32, 64));
    assert_eq!(r.euler_characteristic, 0);
    assert_eq!(r.genus, Some(1));
    assert!(close(r.volume, 8.0));
    assert!(close(r.area, 32.0));
    assert_eq!(r.self_intersecting_pairs, 0);
}

#[test]
fn two_disjoint_cubes_are_refused() {
    let m = union(&cube(), &translated(&cube(), [3.0, 0.0, 0.0]));
    let r = m.check();
    assert_eq!(r.components, 2);
    assert_eq!(r.genus, Some(0)); // total genus of two spheres
    assert!(close(r.volume, 2.0));
    assert_eq!(kinds(&r), vec![IssueKind::MultipleComponents]);
    let e = m.validate().unwrap_err();
    assert_eq!(e.status(), Status::InvalidMesh);
    assert!(e.to_string().contains("2 connected components"), "{e}");
}

#[test]
fn cube_with_a_flipped_face_is_refused_and_repairable() {
    let mut m = cube();
    m.triangles[5].swap(0, 1);
    let r = m.check();
    assert!(!r.orientation_consistent);
    assert_eq!(r.inconsistent_edges, 3);
    assert_eq!(kinds(&r), vec![IssueKind::InconsistentOrientation]);
    let msg = m.validate().unwrap_err().to_string();
    assert!(msg.contains("3 edges") && msg.contains("repair_orientation"), "{msg}");
    let flipped = m.repair_orientation();
    assert_eq!(flipped, 1);
    let r = m.validate().expect("repaired");
    assert!(close(r.volume, 1.0));
}

#[test]
fn inside_out_cube_is_refused_and_repairable() {
    let mut m = cube();
    for t in &mut m.triangles {
        t.swap(1, 2);
    }
    let r = m.check();
    assert!(r.orientation_consistent && !r.oriented_outward);
    assert!(close(r.volume, -1.0));
    assert_eq!(kinds(&r), vec![IssueKind::InwardOrientation]);
    assert_eq!(m.repair_orientation(), 12);
    assert!(m.validate().is_ok());
}

#[test]
fn open_cube_names_its_boundary() {
    let mut m = cube();
    m.triangles.remove(0);
    let r = m.check();
    assert!(!r.closed);
    assert_eq!((r.boundary_edges, r.boundary_loops), (3, 1));
    assert_eq!(r.genus, None);
    let msg = m.validate().unwrap_err().to_string();
    assert!(msg.contains("3 boundary edges in 1 loops") && msg.contains("first boundary edge ("), "{msg}");
}

#[test]
fn non_manifold_edge_and_vertex() {
    // two cubes sharing one edge: the edge has 4 triangles
    let a = voxels([2, 2, 1], |x, y, _| x == y);
    let r = a.check();
    assert_eq!(r.non_manifold_edges, 1);
    assert!(!r.manifold);
    assert!(kinds(&r).contains(&IssueKind::NonManifoldEdges));
    // two cubes sharing one corner: a pinched vertex
    let b = voxels([2, 2, 2], |x, y, z| (x, y, z) == (0, 0, 0) || (x, y, z) == (1, 1, 1));
    let r = b.check();
    assert_eq!(r.non_manifold_vertices, 1);
    assert_eq!(r.non_manifold_edges, 0);
    assert_eq!(kinds(&r), vec![IssueKind::NonManifoldVertices]);
    let msg = b.validate().unwrap_err().to_string();
    assert!(msg.contains("first vertex") && msg.contains("(1, 1, 1)"), "{msg}");
}

#[test]
fn self_intersection_of_overlapping_cubes() {
    let m = union(&cube(), &translated(&cube(), [0.5, 0.3, 0.2]));
    let r = m.check();
    assert!(r.self_intersecting_pairs > 0);
    assert!(r.issues.iter().any(|i| i.kind == IssueKind::SelfIntersections && i.severity == Severity::Warning));
    let disjoint = union(&cube(), &translated(&cube(), [1.5, 0.0, 0.0]));
    assert_eq!(disjoint.check().self_intersecting_pairs, 0);
    // touching along an edge or at a corner is contact, not crossing
    for d in [[1.0, 1.0, 0.0], [1.0, 1.0, 1.0]] {
        let touching = union(&cube(), &translated(&cube(), d));
        assert_eq!(touching.check().self_intersecting_pairs, 0, "{d:?}");
    }
    // coplanar faces that overlap (one face lying on another) are counted
    let stacked = union(&cube(), &translated(&cube(), [1.0, 0.25, 0.0]));
    assert!(stacked.check().self_intersecting_pairs > 0);
}

#[test]
fn from_arrays_refuses_bad_input() {
    let c = cube();
    let xyz: Vec<f64> = c.vertices.iter().flatten().copied().collect();
    let tri: Vec<u32> = c.triangles.iter().flatten().copied().collect();
    let ok = TriMesh::from_arrays(&xyz, &tri, &LoadOptions::default()).unwrap();
    assert_eq!(ok, c);
    let tri64: Vec<i64> = tri.iter().map(|&i| i as i64).collect();
    assert_eq!(TriMesh::from_arrays(&xyz, &tri64, &LoadOptions::default()).unwrap(), c);

    let mut nan = xyz.clone();
    nan[7] = f64::NAN;
    let e = TriMesh::from_arrays(&nan, &tri, &LoadOptions::default()).unwrap_err();
    assert_eq!(e.status(), Status::InvalidMesh);
    assert!(e.to_string().contains("non-finite") && e.to_string().contains("vertex 2"), "{e}");
    let mut inf = xyz.clone();
    inf[0] = f64::INFINITY;
    assert_eq!(TriMesh::from_arrays(&inf, &tri, &LoadOptions::default()).unwrap_err().status(), Status::InvalidMesh);

    let e = TriMesh::from_arrays::<u32>(&xyz, &[], &LoadOptions::default()).unwrap_err();
    assert_eq!(e.status(), Status::InvalidMesh);
    assert!(e.to_string().contains("empty"), "{e}");

    let e = TriMesh::from_arrays(&xyz, &[0u32, 1, 8], &LoadOptions::default()).unwrap_err();
    assert_eq!(e.status(), Status::InvalidArgument);
    let e = TriMesh::from_arrays(&xyz, &[0i64, 1, -1], &LoadOptions::default()).unwrap_err();
    assert_eq!(e.status(), Status::InvalidArgument);
    let e = TriMesh::from_arrays(&xyz[..5], &tri, &LoadOptions::default()).unwrap_err();
    assert_eq!(e.status(), Status::InvalidArgument);
}

/// The cube as a triangle soup (3 vertices per triangle), as STL stores it.
fn soup(m: &TriMesh) -> (Vec<f64>, Vec<u32>) {
    let xyz: Vec<f64> = m.triangles.iter().flat_map(|t| t.iter().flat_map(|&v| m.vertices[v as usize])).collect();
    let tri: Vec<u32> = (0..3 * m.triangles.len() as u32).collect();
    (xyz, tri)
}

#[test]
fn welding_is_relative_and_explicit() {
    let (mut xyz, tri) = soup(&cube());
    let r = TriMesh::from_arrays(&xyz, &tri, &LoadOptions::default()).unwrap().validate().unwrap();
    assert_eq!(r.vertices, 8);
    // exact-only welding also closes an exact soup; -0.0 equals +0.0
    for c in xyz.iter_mut() {
        if *c == 0.0 {
            *c = -0.0;
        }
    }
    xyz[0] = 0.0;
    let exact = LoadOptions { weld_tolerance: 0.0, ..Default::default() };
    assert_eq!(TriMesh::from_arrays(&xyz, &tri, &exact).unwrap().vertices.len(), 8);
    // a perturbation of 1e-12 of the diagonal: merged by default, not by exact welding
    xyz[3] += 1e-12;
    assert_eq!(TriMesh::from_arrays(&xyz, &tri, &LoadOptions::default()).unwrap().vertices.len(), 8);
    let m = TriMesh::from_arrays(&xyz, &tri, &exact).unwrap();
    assert_eq!(m.vertices.len(), 9);
    assert!(!m.check().closed);
    // negative tolerance: no welding at all
    let none = LoadOptions { weld_tolerance: -1.0, ..Default::default() };
    assert_eq!(TriMesh::from_arrays(&xyz, &tri, &none).unwrap().vertices.len(), 36);
    // NaN tolerance is an argument error
    let nan = LoadOptions { weld_tolerance: f64::NAN, ..Default::default() };
    assert_eq!(TriMesh::from_arrays(&xyz, &tri, &nan).unwrap_err().status(), Status::InvalidArgument);
}

#[test]
fn welding_to_a_point_collapses_triangles() {
    let mut m = tetrahedron();
    m.vertices[3] = [1e-13, 0.0, 0.0];
    let (xyz, tri) = (m.vertices.iter().flatten().copied().collect::<Vec<_>>(), m.triangles.iter().flatten().copied().collect::<Vec<_>>());
    let w = TriMesh::from_arrays(&xyz, &tri, &LoadOptions::default()).unwrap();
    let r = w.check();
    assert_eq!(r.collapsed_triangles, 2);
    assert!(kinds(&r).contains(&IssueKind::CollapsedTriangles));
}

#[test]
fn degenerate_triangle_is_a_warning() {
    // a cube whose top face is split with a zero-area sliver: insert a vertex on an edge
    let mut m = tetrahedron();
    m.vertices.push([0.5, 0.5, 0.0]); // on edge 1-2
    // replace the base (0,2,1) by (0,2,4),(0,4,1) and face (1,2,3) by (1,4,3),(4,2,3)
    m.triangles = vec![[0, 2, 4], [0, 4, 1], [0, 1, 3], [0, 3, 2], [1, 4, 3], [4, 2, 3]];
    let r = m.validate().expect("valid");
    assert_eq!(r.degenerate_triangles, 0);
    m.triangles.push([1, 4, 2]); // zero area, makes edges non-manifold too
    let r = m.check();
    assert_eq!(r.degenerate_triangles, 1);
}

#[test]
fn check_survives_garbage_in_public_fields() {
    let mut m = cube();
    m.triangles.push([0, 1, 99]);
    m.vertices[3] = [f64::NAN, 0.0, 0.0];
    let r = m.check();
    assert!(!r.can_proceed);
    let k = kinds(&r);
    assert!(k.contains(&IssueKind::IndexOutOfRange) && k.contains(&IssueKind::NonFinite), "{k:?}");
    let empty = TriMesh::default().check();
    assert_eq!(kinds(&empty), vec![IssueKind::Empty]);
}

#[test]
fn report_serialises_to_json() {
    let v = serde_json::to_value(square_torus().check()).unwrap();
    assert_eq!(v["genus"], 1);
    assert_eq!(v["closed"], true);
    assert!(v["issues"].as_array().unwrap().is_empty());
}

#[test]
fn message_coordinates_are_short() {
    assert_eq!(check::fmt_p([0.5, -1.0, 0.0]), "(0.5, -1, 0)");
    assert_eq!(check::fmt_p([2.2779507836064226e-41, 1e307, -1.55991e-8]), "(2.2779507836064226e-41, 1e307, -1.55991e-8)");
}

#[test]
fn solid_fractions_of_a_curved_part_add_up_to_its_volume() {
    // any closed part: the fractions add up to its volume (cgal_spool, whose lip
    // and recess cut voxels at every angle; 4 x 4 rays a column sample it to 0.5 %)
    use crate::geometry::voxel::{solid_fractions, voxelize};
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/meshes/cgal_spool.off");
    let spool = TriMesh::load(&path, &LoadOptions::default()).unwrap();
    let vol = voxelize(&spool, 24).unwrap();
    let f = solid_fractions(&spool, &vol, 4);
    let sum: f64 = f.iter().map(|&x| x as f64).sum::<f64>() * vol.h.powi(3);
    let v = spool.signed_volume();
    assert!((sum - v).abs() < 0.005 * v, "{sum} vs {v}");
    assert!(f.iter().all(|&x| (0.0..=1.0 + 1e-6).contains(&x)));
}
