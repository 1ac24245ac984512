//! The main job keeps the polycube's mesh on a real part the grid can hold:
//! mambo_B0, a block with a round channel across its top, which the grid-based
//! fallback meshed before the automated mode found its arch of five cells.

use std::process::Command;

#[test]
fn a_block_with_a_channel_is_meshed_from_its_verified_polycube_and_meets_the_goals() {
    let mesh = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/meshes/mambo_B0.obj");
    let dir = tempfile::tempdir().expect("temp dir");
    let out = dir.path().join("out");
    let args = ["run", mesh.to_str().unwrap(), "-o", out.to_str().unwrap(), "--no-spline", "--quiet"];
    let o = Command::new(env!("CARGO_BIN_EXE_sddpm")).args(args).output().expect("run sddpm");
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(0), "{stderr}");
    let report: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(out.join("report.json")).expect("report.json")).expect("json");
    let path = &report["mesh_path"];
    assert_eq!(path["from"], "polycube", "{path}");
    assert_eq!(path["verified"], true, "{path}");
    assert_eq!(report["polycube"]["names"], "cube,cube,cube,cube,null,cube,null,null,null,null,null,null", "{}", report["polycube"]);
    let hex = &report["hex"];
    assert_eq!(hex["domain"], "polycube", "{hex}");
    for g in hex["goals"].as_array().expect("goals") {
        assert_eq!(g["met"], true, "{g}");
    }
    // a polycube mesh: irregular edges only where the polycube has edges, far
    // fewer than the fallback's lattice has (4,256 elements with 448 there)
    let elements = hex["elements"].as_u64().unwrap() as f64;
    let irregular = hex["irregular_edges"].as_u64().unwrap() as f64;
    assert_eq!(hex["irregular_edges_interior"], 0, "{hex}");
    assert!(irregular / elements < 0.06, "{irregular} irregular edges for {elements} elements");
}
