//! Reading real files: every mesh in tests/data/meshes loads, passes the
//! checks and has the catalogue's counts and genus; every file in bad/ is
//! refused for the catalogued reason (or repaired by a documented default).
//! Also the file formats' corner cases, written on the fly.

use sddpm::mesh::{IssueKind, LoadOptions, Severity, TriMesh};
use sddpm::Status;
use std::path::PathBuf;

fn data(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/meshes").join(name)
}

/// (file, vertices, triangles, genus) from tests/data/meshes/CATALOG.md.
const GOOD: &[(&str, usize, usize, i64)] = &[
    ("cgal_dragknob.off", 161, 318, 0),
    ("cgal_eight.off", 315, 634, 2),
    ("cgal_hole.off", 20, 40, 1),
    ("cgal_joint.off", 221, 446, 2),
    ("cgal_pinion.off", 650, 1300, 1),
    ("cgal_spool.off", 649, 1294, 0),
    ("cinolib_3holes.obj", 1987, 3982, 3),
    ("cinolib_cube_minus_sphere.obj", 2066, 4128, 0),
    ("cinolib_torus.obj", 768, 1536, 1),
    ("hexgen_bust.obj", 12596, 25188, 0),
    ("hexgen_hepta.obj", 509, 1014, 0),
    ("hexgen_joint.obj", 3806, 7612, 1),
    ("hexgen_rockerarm.obj", 11656, 23312, 1),
    ("hexgen_rod.obj", 2238, 4480, 2),
    ("mambo_B0.obj", 9984, 19964, 0),
    ("trimesh_round.stl", 560, 1120, 1),
];

#[test]
fn catalogue_lists_every_good_mesh() {
    let mut files: Vec<String> = std::fs::read_dir(data(""))
        .unwrap()
        .filter_map(|e| e.ok())
        .filter(|e| e.path().is_file())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| !n.ends_with(".md"))
        .collect();
    files.sort();
    let mut known: Vec<String> = GOOD.iter().map(|g| g.0.to_string()).collect();
    known.sort();
    assert_eq!(files, known);
}

#[test]
fn good_meshes_load_and_pass() {
    for &(name, nv, nt, genus) in GOOD {
        let m = TriMesh::load(data(name), &LoadOptions::default()).unwrap_or_else(|e| panic!("{name}: {e}"));
        let r = m.validate().unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!((r.vertices, r.triangles), (nv, nt), "{name}");
        assert_eq!(r.genus, Some(genus), "{name}");
        assert_eq!(r.components, 1, "{name}");
        assert!(r.closed && r.manifold && r.oriented_outward, "{name}");
        assert!(r.volume > 0.0 && r.area > 0.0, "{name}");
        // only the rockerarm crosses itself (5 pairs, as tetgen -d finds)
        let expect_si = if name == "hexgen_rockerarm.obj" { 5 } else { 0 };
        assert_eq!(r.self_intersecting_pairs, expect_si, "{name}");
    }
}

fn refused(name: &str) -> (sddpm::Error, sddpm::mesh::MeshReport) {
    let m = TriMesh::load(data(name), &LoadOptions::default()).unwrap_or_else(|e| panic!("{name}: {e}"));
    let r = m.check();
    (m.validate().expect_err(name), r)
}

fn error_kinds(r: &sddpm::mesh::MeshReport) -> Vec<IssueKind> {
    r.issues.iter().filter(|i| i.severity == Severity::Error).map(|i| i.kind).collect()
}

#[test]
fn bad_bones_has_26_components() {
    let (e, r) = refused("bad/cgal_bones.off");
    assert_eq!(e.status(), Status::InvalidMesh);
    assert_eq!(r.components, 26);
    assert_eq!(error_kinds(&r), vec![IssueKind::MultipleComponents]);
    assert!(e.to_string().contains("26 connected components"), "{e}");
}

#[test]
fn bad_cow_has_a_pinched_vertex_after_welding() {
    let (e, r) = refused("bad/cgal_cow.off");
    assert_eq!(r.vertices, 2903);
    assert_eq!(r.non_manifold_vertices, 1);
    assert_eq!(r.euler_characteristic, 1);
    assert_eq!(error_kinds(&r), vec![IssueKind::NonManifoldVertices]);
    assert!(e.to_string().contains("non-manifold vertices: 1 vertices") && e.to_string().contains("first vertex"), "{e}");
    // without welding it is a closed genus-0 manifold
    let raw = TriMesh::load(data("bad/cgal_cow.off"), &LoadOptions { weld_tolerance: -1.0, ..Default::default() }).unwrap();
    let r = raw.check();
    assert!(r.closed && r.manifold);
    assert_eq!(r.genus, Some(0));
}

#[test]
fn bad_shark_is_open_with_4_holes() {
    let (e, r) = refused("bad/cgal_mech-holes-shark.off");
    assert_eq!((r.boundary_edges, r.boundary_loops), (304, 4));
    assert!(error_kinds(&r).contains(&IssueKind::BoundaryEdges));
    assert!(e.to_string().contains("304 boundary edges in 4 loops") && e.to_string().contains("first boundary edge ("), "{e}");
}

#[test]
fn bad_oblong_is_inconsistently_oriented_and_repairable() {
    let (e, r) = refused("bad/cgal_oblong-shuffled.off");
    assert!(r.closed);
    assert_eq!(r.inconsistent_edges, 625);
    assert_eq!(error_kinds(&r), vec![IssueKind::InconsistentOrientation]);
    assert!(e.to_string().contains("625 edges"), "{e}");
    // the explicit repair makes it a valid outward genus-0 solid
    let opts = LoadOptions { repair_orientation: true, ..Default::default() };
    let (m, stats) = TriMesh::load_with_stats(data("bad/cgal_oblong-shuffled.off"), &opts).unwrap();
    assert!(stats.triangles_flipped > 0);
    let r = m.validate().expect("repaired");
    assert_eq!(r.genus, Some(0));
    assert!(r.volume > 0.0);
}

#[test]
fn featuretype_raw_is_closed_by_default_welding() {
    let (m, stats) = TriMesh::load_with_stats(data("bad/trimesh_featuretype_raw.stl"), &LoadOptions::default()).unwrap();
    assert_eq!(stats.format, Some("stl"));
    let r = m.validate().expect("welding closes it");
    assert_eq!(r.genus, Some(9));
    // exact welding leaves the 576 boundary edges the catalogue lists
    let exact = TriMesh::load(data("bad/trimesh_featuretype_raw.stl"), &LoadOptions { weld_tolerance: 0.0, ..Default::default() }).unwrap();
    assert_eq!(exact.check().boundary_edges, 576);
}

// ---------------------------------------------------------------- formats

/// A file written in a directory of its own, removed with it when dropped.
struct TmpFile {
    path: PathBuf,
    _dir: tempfile::TempDir,
}

impl std::ops::Deref for TmpFile {
    type Target = PathBuf;
    fn deref(&self) -> &PathBuf {
        &self.path
    }
}

impl AsRef<std::path::Path> for TmpFile {
    fn as_ref(&self) -> &std::path::Path {
        &self.path
    }
}

fn tmp(name: &str, bytes: &[u8]) -> TmpFile {
    let dir = tempfile::Builder::new().prefix("sddpm_mesh_files_").tempdir().unwrap();
    let path = dir.path().join(name);
    std::fs::write(&path, bytes).unwrap();
    TmpFile { path, _dir: dir }
}

const TET: [[f64; 3]; 4] = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
const TET_TRI: [[usize; 3]; 4] = [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]];

fn tet_binary_stl(header: &[u8]) -> Vec<u8> {
    let mut b = vec![b' '; 80];
    b[..header.len()].copy_from_slice(header);
    b.extend_from_slice(&4u32.to_le_bytes());
    for t in TET_TRI {
        b.extend_from_slice(&[0u8; 12]);
        for v in t {
            for c in TET[v] {
                b.extend_from_slice(&(c as f32).to_le_bytes());
            }
        }
        b.extend_from_slice(&[0u8; 2]);
    }
    b
}

fn assert_tet(p: &PathBuf) {
    let m = TriMesh::load(p, &LoadOptions::default()).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
    let r = m.validate().unwrap();
    assert_eq!((r.vertices, r.triangles, r.genus), (4, 4, Some(0)));
    assert!((r.volume - 1.0 / 6.0).abs() < 1e-9);
}

#[test]
fn binary_stl_whose_header_starts_with_solid() {
    assert_tet(&tmp("solid_header.stl", &tet_binary_stl(b"solid this is binary")));
    assert_tet(&tmp("plain_header.stl", &tet_binary_stl(b"binary")));
}

#[test]
fn ascii_stl_in_double_precision() {
    let mut s = String::from("solid tet\n");
    for t in TET_TRI {
        s += "  facet normal 0 0 0\n    outer loop\n";
        for v in t {
            let p = TET[v];
            // a coordinate f32 cannot hold: 1 + 1e-10
            let x = if p[0] == 1.0 { "1.0000000001".to_string() } else { p[0].to_string() };
            s += &format!("      vertex {x} {} {}\n", p[1], p[2]);
        }
        s += "    endloop\n  endfacet\n";
    }
    s += "endsolid tet\n";
    let p = tmp("ascii.stl", s.as_bytes());
    let m = TriMesh::load(&p, &LoadOptions { weld_tolerance: 0.0, ..Default::default() }).unwrap();
    assert!(m.vertices.iter().any(|v| v[0] == 1.0000000001));
    assert_tet(&p);
}

#[test]
fn off_with_comments_counts_on_header_line_and_quads() {
    let off = "OFF 8 6 0 # a cube\n# comment line\n\
        0 0 0\n1 0 0\n0 1 0\n1 1 0\n0 0 1\n1 0 1\n0 1 1\n1 1 1\n\
        4 0 2 3 1\n4 4 5 7 6\n4 0 1 5 4\n4 2 6 7 3\n4 0 4 6 2\n4 1 3 7 5 255 0 0\n";
    let (m, stats) = TriMesh::load_with_stats(tmp("cube.off", off.as_bytes()), &LoadOptions::default()).unwrap();
    assert_eq!(stats.polygons_split, 6);
    let r = m.validate().unwrap();
    assert_eq!((r.vertices, r.triangles), (8, 12));
    assert!((r.volume - 1.0).abs() < 1e-12);
}

#[test]
fn obj_with_quads_and_content_sniffing() {
    let obj = "# cube\no cube\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nv 0 0 1\nv 1 0 1\nv 0 1 1\nv 1 1 1\n\
        vt 0 0\nf 1/1 3/1 4/1 2/1\nf 5 6 8 7\nf 1 2 6 5\nf 3 7 8 4\nf 1 5 7 3\nf 2 4 8 6\n";
    let r = TriMesh::load(tmp("cube.obj", obj.as_bytes()), &LoadOptions::default()).unwrap().validate().unwrap();
    assert!((r.volume - 1.0).abs() < 1e-12);
    // unknown extension: the content decides
    let r = TriMesh::load(tmp("cube.mesh_without_ext", obj.as_bytes()), &LoadOptions::default()).unwrap().validate().unwrap();
    assert_eq!(r.triangles, 12);
    let off = std::fs::read(data("cgal_hole.off")).unwrap();
    assert_eq!(TriMesh::load(tmp("hole.data", &off), &LoadOptions::default()).unwrap().triangles.len(), 40);
    let stl = tet_binary_stl(b"solid x");
    assert_tet(&tmp("tet.bin", &stl));
}

#[test]
fn unreadable_files_are_io_or_parse_errors() {
    let e = TriMesh::load("/nonexistent/dir/x.obj", &LoadOptions::default()).unwrap_err();
    assert_eq!(e.status(), Status::Io);
    assert!(e.to_string().contains("/nonexistent/dir/x.obj"), "{e}");
    for (name, content) in [
        ("garbage.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n"),
        ("badindex.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n"),
        ("header.off", "NOT AN OFF\n"),
        ("garbage.stl", "solid x\nfacet normal 0 0 0\nouter loop\nvertex 0 0\n"),
        ("short.stl", "abc"),
        ("garbage.obj", "v 0 0 zero\nf 1 2 3\n"),
        ("unknown.xyz", "\u{1}\u{2}\u{3}"),
    ] {
        let e = TriMesh::load(tmp(name, content.as_bytes()), &LoadOptions::default()).unwrap_err();
        assert_eq!(e.status(), Status::Parse, "{name}: {e}");
    }
    // a truncated binary STL (count says 4, holds 3)
    let stl = tet_binary_stl(b"binary");
    let e = TriMesh::load(tmp("trunc.stl", &stl[..stl.len() - 50]), &LoadOptions::default()).unwrap_err();
    assert_eq!(e.status(), Status::Parse, "{e}");
    // readable but empty / non-finite: the mesh cannot go on
    let e = TriMesh::load(tmp("empty.off", b"OFF\n0 0 0\n"), &LoadOptions::default()).unwrap_err();
    assert_eq!(e.status(), Status::InvalidMesh);
    let e = TriMesh::load(tmp("nan.off", b"OFF\n3 1 0\n0 0 0\n1 nan 0\n0 1 0\n3 0 1 2\n"), &LoadOptions::default()).unwrap_err();
    assert_eq!(e.status(), Status::InvalidMesh);
    assert!(e.to_string().contains("non-finite") && e.to_string().contains("vertex 1"), "{e}");
}

/// A binary STL announcing 10^7 triangles (a sparse file of the size the count
/// implies, 500 MB that take no disk) is refused with LIMIT_EXCEEDED from its
/// 84-byte header, before the rest of the file is read; an OFF file whose header
/// announces more faces than the limit, and that is large enough to hold them, is
/// refused before its faces are parsed.
#[test]
fn oversized_inputs_are_refused_from_their_headers() {
    let n: u64 = 10_000_000;
    let p = tmp("ten_million.stl", &[]);
    {
        use std::io::Write;
        let mut f = std::fs::File::create(&p).unwrap();
        let mut head = vec![b' '; 80];
        head.extend_from_slice(&(n as u32).to_le_bytes());
        f.write_all(&head).unwrap();
        f.set_len(84 + 50 * n).unwrap();
    }
    let e = TriMesh::load(&p, &LoadOptions::default()).unwrap_err();
    assert_eq!(e.status(), sddpm::Status::LimitExceeded, "{e}");
    assert!(e.to_string().contains("10000000 triangles"), "{e}");
    std::fs::remove_file(&p).unwrap();

    // the same header from bytes held in memory (the C ABI's and the fuzzers' path)
    let mut bytes = vec![b' '; 80];
    bytes.extend_from_slice(&(sddpm::mesh::MAX_TRIANGLES as u32 + 1).to_le_bytes());
    bytes.resize(84 + 50 * (sddpm::mesh::MAX_TRIANGLES + 1), 0);
    let e = TriMesh::from_bytes(&bytes, None, "big.stl", &LoadOptions::default()).unwrap_err();
    assert_eq!(e.status(), sddpm::Status::LimitExceeded, "{e}");

    let faces = sddpm::mesh::MAX_TRIANGLES + 1;
    let mut off = format!("OFF\n3 {faces} 0\n0 0 0\n1 0 0\n0 1 0\n");
    off.push_str(&" ".repeat(2 * faces));
    let e = TriMesh::from_bytes(off.as_bytes(), None, "big.off", &LoadOptions::default()).unwrap_err();
    assert_eq!(e.status(), sddpm::Status::LimitExceeded, "{e}");
}
