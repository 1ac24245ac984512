use sddpm::search::generate::{prepare_input, PolycubeOptions};
use sddpm::search::synthetic::{cases, SyntheticOptions};
use sddpm::search::inference::occupancy_only;
use sddpm::polycube::orientation::rotations;
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let idx: usize = args[1].parse().unwrap();
    let cs = cases(1000, idx + 1, 1, 6, &SyntheticOptions::default());
    let (ctx, mesh) = &cs[idx];
    println!("{ctx}");
    let inp = prepare_input(mesh, &PolycubeOptions::default()).unwrap();
    println!("frame {:?}", inp.frame);
    let bb = sddpm::geometry::Aabb::of_points(&inp.alignment.mesh.vertices);
    println!("bbox {:?}", bb.size());
    for (k, r) in rotations().iter().enumerate() {
        let o = occupancy_only(&inp.samples[..8192], ctx, *r, 0.2).unwrap();
        println!("{k} {} empty {:.3} starved {:?}", r.name(), o.in_empty_cells, o.starved_cells);
    }
}
