//! The main job keeps the polycube's mesh on real parts the grid can hold:
//! mambo_B0, a block with a round channel across its top, which the grid-based
//! fallback meshed before the automated mode found its arch of five cells, and
//! cinolib_cube_minus_sphere, a cube with a spherical bite at one corner, whose
//! seven cubes meet the goals through the chart maps (the projection alone folds
//! the bite's rim).

use std::process::Command;

/// `sddpm run MESH --no-spline` in a temporary folder; its report.json.
fn main_job(name: &str) -> serde_json::Value {
    let mesh = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/meshes").join(name);
    let dir = tempfile::tempdir().expect("temp dir");
    let out = dir.path().join("out");
    let args = ["run", mesh.to_str().unwrap(), "-o", out.to_str().unwrap(), "--no-spline", "--quiet"];
    let o = Command::new(env!("CARGO_BIN_EXE_sddpm")).args(args).output().expect("run sddpm");
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(0), "{stderr}");
    serde_json::from_str(&std::fs::read_to_string(out.join("report.json")).expect("report.json")).expect("json")
}

/// The kept mesh comes from the verified polycube and meets every goal, with
/// fewer irregular edges than `max_share` of the element count.
fn assert_polycube_mesh(report: &serde_json::Value, max_share: f64) {
    let path = &report["mesh_path"];
    assert_eq!(path["from"], "polycube", "{path}");
    assert_eq!(path["verified"], true, "{path}");
    let hex = &report["hex"];
    assert_eq!(hex["domain"], "polycube", "{hex}");
    for g in hex["goals"].as_array().expect("goals") {
        assert_eq!(g["met"], true, "{g}");
    }
    let elements = hex["elements"].as_u64().unwrap() as f64;
    let irregular = hex["irregular_edges"].as_u64().unwrap() as f64;
    assert!(irregular / elements < max_share, "{irregular} irregular edges for {elements} elements");
}

#[test]
fn a_block_with_a_channel_is_meshed_from_its_verified_polycube_and_meets_the_goals() {
    let report = main_job("mambo_B0.obj");
    assert_eq!(report["polycube"]["names"], "cube,cube,cube,cube,null,cube,null,null,null,null,null,null", "{}", report["polycube"]);
    // far fewer irregular edges than the fallback's lattice has (4,256 elements
    // with 448 there), all on the boundary, along the polycube's edges
    assert_polycube_mesh(&report, 0.06);
    assert_eq!(report["hex"]["irregular_edges_interior"], 0, "{}", report["hex"]);
}

#[test]
fn a_cube_with_a_spherical_bite_is_meshed_from_its_seven_cubes_through_the_chart_maps() {
    let report = main_job("cinolib_cube_minus_sphere.obj");
    let names = report["polycube"]["names"].as_str().unwrap();
    assert_eq!(names.split(',').filter(|l| *l == "cube").count(), 7, "{names}");
    assert_eq!(names.split(',').filter(|l| *l != "cube" && *l != "null").count(), 0, "{names}");
    // the fallback's lattice: 17,354 elements with 3,474 irregular edges (this
    // polycube mesh: 15,552 with 374)
    assert_polycube_mesh(&report, 0.05);
    assert_eq!(report["hex"]["surface_map"]["method"], "charts", "{}", report["hex"]["surface_map"]);
}
