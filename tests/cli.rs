//! `sddpm info` as DESIGN.md specifies: exit 0 with measurements, exit 2 with
//! `error: <what>` on stderr for a mesh that cannot go on, one JSON object with --json.

use std::process::Command;

fn sddpm(args: &[&str]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_sddpm"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("run sddpm");
    (out.status.code().unwrap_or(-1), String::from_utf8_lossy(&out.stdout).into_owned(), String::from_utf8_lossy(&out.stderr).into_owned())
}

#[test]
fn info_on_a_good_mesh() {
    let (code, out, err) = sddpm(&["info", "tests/data/meshes/cgal_hole.off"]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("genus:                1"), "{out}");
    assert!(out.contains("closed:               yes"), "{out}");
    let (code, out, _) = sddpm(&["info", "tests/data/meshes/cgal_eight.off", "--json"]);
    assert_eq!(code, 0);
    let v: serde_json::Value = serde_json::from_str(out.trim()).expect("one JSON object");
    for key in ["vertices", "triangles", "components", "closed", "manifold", "oriented", "genus", "volume", "area", "bbox"] {
        assert!(v.get(key).is_some(), "missing {key}");
    }
    assert_eq!(v["genus"], 2);
    assert_eq!(v["ok"], true);
    assert_eq!(out.trim().lines().count(), 1);
}

#[test]
fn info_refuses_with_exit_2() {
    let (code, out, err) = sddpm(&["info", "tests/data/meshes/bad/cgal_mech-holes-shark.off"]);
    assert_eq!(code, 2);
    assert!(out.contains("boundary edges"), "prints what it measured first: {out}");
    assert!(err.starts_with("error: ") && err.contains("304 boundary edges"), "{err}");
    let (code, out, err) = sddpm(&["info", "--json", "tests/data/meshes/bad/cgal_cow.off"]);
    assert_eq!(code, 2);
    let v: serde_json::Value = serde_json::from_str(out.trim()).unwrap();
    assert_eq!(v["ok"], false);
    assert_eq!(v["non_manifold_vertices"], 1);
    assert!(err.starts_with("error: "));
    let (code, out, err) = sddpm(&["info", "--json", "no/such/file.obj"]);
    assert_eq!(code, 2);
    assert!(err.starts_with("error: ") && err.contains("no/such/file.obj"));
    let v: serde_json::Value = serde_json::from_str(out.trim()).unwrap();
    assert_eq!(v["status"], "IO");
    let (code, _, err) = sddpm(&["info"]);
    assert_eq!(code, 2, "{err}");
}

#[test]
fn info_repair_is_explicit() {
    let (code, _, _) = sddpm(&["info", "tests/data/meshes/bad/cgal_oblong-shuffled.off"]);
    assert_eq!(code, 2);
    let (code, out, err) = sddpm(&["info", "--repair-orientation", "tests/data/meshes/bad/cgal_oblong-shuffled.off"]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("re-oriented"), "{out}");
}
