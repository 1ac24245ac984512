//! The spline on HexGen's published all-hex meshes (tests/data/meshes/reference_hex):
//! positive Jacobian at every 3x3x3 Gauss point, boundary fitting to the input
//! surface, local refinement that reduces the boundary distance.

use sddpm::error::NoProgress;
use sddpm::export::vtk::read_vtk_legacy;
use sddpm::hex::HexMesh;
use sddpm::mesh::TriMesh;
use sddpm::spline::{build_spline, check, FitOptions, RefineOptions, SplineOptions};
use std::path::Path;

fn load(name: &str) -> (HexMesh, TriMesh) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/meshes");
    let hex = read_vtk_legacy(&root.join(format!("reference_hex/hexgen_{name}_hex.vtk"))).unwrap();
    let surf = TriMesh::load(root.join(format!("hexgen_{name}.obj")), &Default::default()).unwrap();
    (hex, surf)
}

#[test]
fn spline_reference_meshes_have_positive_jacobian() {
    for name in ["hepta", "joint", "rockerarm", "rod"] {
        let (hex, surf) = load(name);
        let sp = build_spline(&hex, Some(&surf), &SplineOptions::default(), &mut NoProgress).unwrap();
        let r = sp.report();
        assert!(r.min_jacobian > 0.0 && r.min_scaled_jacobian > 0.0, "{name}: {r:?}");
        assert_eq!(r.negative_jacobian_elements, 0, "{name}");
        let b = r.fitting_before.as_ref().unwrap();
        let a = r.fitting_after.as_ref().unwrap();
        assert!(a.rms < b.rms, "{name}: fit did not reduce the RMS distance ({} -> {})", b.rms, a.rms);
        assert!(a.max <= b.max * 1.05, "{name}: fit increased the max distance ({} -> {})", b.max, a.max);
        let pu = check::partition_of_unity(&sp, 2, 3);
        assert!(pu.max_sum_error < 1e-11 && pu.min_value > -1e-13, "{name}: {pu:?}");
        // report.json keys the CLI relies on
        let j = serde_json::to_value(r).unwrap();
        for k in ["elements", "basis_functions", "min_jacobian", "min_scaled_jacobian", "fitting_before", "fitting_after"] {
            assert!(j.get(k).is_some(), "{k}");
        }
    }
}

#[test]
fn spline_rod_local_refinement_reduces_boundary_distance() {
    let (hex, surf) = load("rod");
    let fo = FitOptions::default();
    let opts = SplineOptions::default();
    let mut sp = build_spline(&hex, Some(&surf), &opts, &mut NoProgress).unwrap();
    let before = sp.report().fitting_after.clone().unwrap();
    let n0 = sp.num_elements();
    let rep = sp.refine_auto(&surf, &RefineOptions { tolerance: 0.0005, ..Default::default() }, &fo).unwrap();
    assert!(rep.refined > 0 && sp.num_elements() == n0 + 7 * rep.refined);
    let after = rep.distance_after.unwrap();
    assert!(after.max < before.max, "max distance {} -> {}", before.max, after.max);
    assert!(after.rms < before.rms, "rms distance {} -> {}", before.rms, after.rms);
    assert!(sp.report().min_jacobian > 0.0);
    let pu = check::partition_of_unity(&sp, 3, 5);
    assert!(pu.max_sum_error < 1e-11 && pu.min_value > -1e-13, "{pu:?}");
}
