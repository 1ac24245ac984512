//! Parts the 3x2x2 grid cannot hold still get a mesh: a closed genus-9 part (a plate
//! with a 3 x 3 array of through holes; twelve cells hold at most a few holes in the
//! arrangements the automated mode forms) is meshed by `sddpm run` with the
//! grid-based fallback, and report.json says why the polycube was not used.

use std::collections::{BTreeSet, HashMap};
use std::path::Path;
use std::process::Command;

/// The boundary of a union of unit voxels as an OBJ surface (two outward
/// triangles per exposed voxel face, vertices shared by integer position).
fn voxel_surface_obj(voxels: &BTreeSet<[i32; 3]>) -> String {
    let mut ids: HashMap<[i32; 3], usize> = HashMap::new();
    let mut verts: Vec<[i32; 3]> = Vec::new();
    let mut tris: Vec<[usize; 3]> = Vec::new();
    let mut id = |p: [i32; 3], verts: &mut Vec<[i32; 3]>| {
        *ids.entry(p).or_insert_with(|| {
            verts.push(p);
            verts.len()
        })
    };
    for v in voxels {
        for axis in 0..3 {
            for side in [-1i32, 1] {
                let mut n = *v;
                n[axis] += side;
                if voxels.contains(&n) {
                    continue;
                }
                let (b, c) = ((axis + 1) % 3, (axis + 2) % 3);
                let corner = |u: i32, w: i32| {
                    let mut p = *v;
                    if side > 0 {
                        p[axis] += 1;
                    }
                    p[b] += u;
                    p[c] += w;
                    p
                };
                // e_b x e_c = e_axis: counter-clockwise in (b, c) faces +axis
                let mut q = [corner(0, 0), corner(1, 0), corner(1, 1), corner(0, 1)];
                if side < 0 {
                    q.reverse();
                }
                let q = q.map(|p| id(p, &mut verts));
                tris.push([q[0], q[1], q[2]]);
                tris.push([q[0], q[2], q[3]]);
            }
        }
    }
    let mut s = String::new();
    for p in &verts {
        s += &format!("v {} {} {}\n", p[0], p[1], p[2]);
    }
    for t in &tris {
        s += &format!("f {} {} {}\n", t[0], t[1], t[2]);
    }
    s
}

#[test]
fn a_genus_9_part_gets_a_fallback_mesh_with_the_reason() {
    let dir = tempfile::tempdir().expect("temp dir");
    // a 7 x 7 x 1 plate with a hole in every odd (x, y) voxel: 9 through holes
    let plate: BTreeSet<[i32; 3]> = (0..7).flat_map(|x| (0..7).map(move |y| [x, y, 0])).filter(|v| v[0] % 2 == 0 || v[1] % 2 == 0).collect();
    let mesh = dir.path().join("plate9.obj");
    std::fs::write(&mesh, voxel_surface_obj(&plate)).expect("write mesh");
    let out = dir.path().join("out");
    // the first lattice only and no spline: the test is about the path, not the cost
    let args = ["run", mesh.to_str().unwrap(), "-o", out.to_str().unwrap(), "--no-spline", "--voxel-refinements", "0", "--quiet"];
    let o = Command::new(env!("CARGO_BIN_EXE_sddpm")).args(args).output().expect("run sddpm");
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(0), "{stderr}");
    let report: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(out.join("report.json")).expect("report.json")).expect("json");
    assert_eq!(report["input"]["genus"], 9);
    let path = &report["mesh_path"];
    assert_eq!(path["from"], "grid-based fallback", "{path}");
    assert!(path["polycube"].is_null(), "{path}");
    let why = path["why"].as_str().expect("why");
    assert!(why.contains("no polycube was meshed") && why.contains("genus 9") && why.contains("grid-based fallback"), "{why}");
    // a valid mesh that meets every quality goal
    let hex = &report["hex"];
    assert_eq!(hex["inverted"], 0, "{hex}");
    for g in hex["goals"].as_array().expect("goals") {
        assert_eq!(g["met"], true, "{g}");
    }
    assert!(hex["elements"].as_u64().unwrap() > 0);
    // no polycube file: none was formed; the manifest lists what is there
    assert!(!Path::new(&out.join("polycube.obj")).exists());
    assert_eq!(report["polycube"]["candidates"], 0);
    assert!(report["polycube"]["labels"].is_null());
    for f in report["files"].as_array().expect("files") {
        assert!(out.join(f["name"].as_str().unwrap()).exists(), "{f}");
    }
    assert!(out.join("hex.vtu").exists() && out.join("report.html").exists());
}
