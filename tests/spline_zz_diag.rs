use sddpm::export::vtk::read_vtk_legacy;
use sddpm::mesh::TriMesh;
use sddpm::spline::{Spline, SplineOptions, FitOptions, RefineOptions};
use std::path::Path;
#[test]
#[ignore]
fn diag() {
    for name in ["hepta", "rod"] {
        let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/meshes");
        let hex = read_vtk_legacy(&root.join(format!("reference_hex/hexgen_{name}_hex.vtk"))).unwrap();
        let surf = TriMesh::load(root.join(format!("hexgen_{name}.obj")), &Default::default()).unwrap();
        let mut sp = Spline::construct(&hex, &SplineOptions::default()).unwrap();
        let fo = FitOptions::default();
        let d = sp.fit_boundary(&surf, &fo).unwrap();
        println!("{name} fit: max {:.3}% haus {:.3}% minsj {:.4} basis {}", 100.0*d.max_relative, 100.0*d.hausdorff_relative, sp.report().min_scaled_jacobian, sp.num_basis());
        for frac in [0.05, 0.1, 0.25] {
            let mut s2 = sp.clone();
            let ro = RefineOptions { fraction: frac, passes: 1, ..Default::default() };
            let r = s2.refine_auto(&surf, &ro, &fo).unwrap();
            let d = r.distance_after.unwrap();
            println!("  frac {frac}: refined {} max {:.3}% haus {:.3}% minsj {:.4} basis {}", r.refined, 100.0*d.max_relative, 100.0*d.hausdorff_relative, s2.report().min_scaled_jacobian, s2.num_basis());
        }
    }
}
