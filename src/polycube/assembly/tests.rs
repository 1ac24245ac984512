use super::*;
use Primitive::*;

#[test]
fn betti_of_primitives_and_of_the_voxelised_torus() {
    use crate::geometry::voxel::{betti, voxelize};
    for p in Primitive::solids() {
        let (b0, b2, b1) = betti(&single(p));
        assert_eq!((b0, b2, b1), (1, 0, p.standalone_genus()), "{p}");
    }
    // The voxelised picture-frame torus (THC+Z alone): genus 1, volume close to the surface's.
    let mut labels = [Null; NUM_CELLS];
    labels[0] = ThcZ;
    let m = boundary(&assemble(&labels)).to_trimesh();
    let vol = voxelize(&m, 30).unwrap();
    assert!((vol.volume() - 24.0 / 27.0).abs() < 1e-9, "{}", vol.volume());
    let (b0, b2, b1) = betti(&vol.grid);
    assert_eq!((b0, b2, b1), (1, 0, 1));
}

#[test]
fn the_tables_agree_with_the_direct_counts_on_random_assemblies() {
    // Euler characteristic from the lattice-point table against V - E + F - C
    // counted directly, and 1 - chi against the genus of every valid assembly
    use rand::{RngExt, SeedableRng};
    let mut rng = rand::rngs::StdRng::seed_from_u64(7);
    let all: Vec<Primitive> = (0..11u8).filter_map(Primitive::from_label).filter(|p| *p != Null).collect();
    let (mut valid, mut genera) = (0, std::collections::BTreeSet::new());
    for _ in 0..3000 {
        let mut l = [Null; NUM_CELLS];
        for c in l.iter_mut() {
            if rng.random::<f64>() < 0.6 {
                *c = all[rng.random_range(0..all.len())];
            }
        }
        let g = assemble(&l);
        let chi = euler_solid(&g);
        // direct count: solid cells of each dimension in the closed union
        let at = |x: i64, y: i64, z: i64| g.at(x, y, z);
        let [nx, ny, nz] = g.dims.map(|d| d as i64);
        let (mut cv, mut ce, mut cf, mut cc) = (0i64, 0i64, 0i64, 0i64);
        for z in 0..=nz {
            for y in 0..=ny {
                for x in 0..=nx {
                    // voxels touching vertex, edges along a, faces normal to a, voxel
                    let near = |dx: &[i64], dy: &[i64], dz: &[i64]| dx.iter().any(|&i| dy.iter().any(|&j| dz.iter().any(|&k| at(x + i, y + j, z + k))));
                    cv += near(&[-1, 0], &[-1, 0], &[-1, 0]) as i64;
                    ce += near(&[0], &[-1, 0], &[-1, 0]) as i64 + near(&[-1, 0], &[0], &[-1, 0]) as i64 + near(&[-1, 0], &[-1, 0], &[0]) as i64;
                    cf += near(&[-1, 0], &[0], &[0]) as i64 + near(&[0], &[-1, 0], &[0]) as i64 + near(&[0], &[0], &[-1, 0]) as i64;
                    cc += at(x, y, z) as i64;
                }
            }
        }
        assert_eq!(chi, cv - ce + cf - cc, "{l:?}");
        let v = check(&g);
        if v.valid {
            valid += 1;
            genera.insert(v.genus.unwrap());
            assert_eq!(v.genus, Some(1 - chi), "{l:?}");
        }
    }
    assert!(valid > 100 && genera.len() >= 3, "{valid} valid, genera {genera:?}");
}

fn labels(pairs: &[(usize, Primitive)]) -> [Primitive; NUM_CELLS] {
    let mut l = [Null; NUM_CELLS];
    for &(n, p) in pairs {
        l[n] = p;
    }
    l
}

#[test]
fn single_primitives() {
    for p in Primitive::solids() {
        let v = check(&single(p));
        assert!(v.valid, "{p}: {:?}", v.reason);
        assert_eq!(v.genus, Some(p.standalone_genus()), "{p}");
        let v2 = check(&assemble(&labels(&[(4, p)])));
        assert_eq!(v2.genus, Some(p.standalone_genus()));
    }
}

#[test]
fn known_cases() {
    // THC+X with a cube on its -X side: the hole is capped -> blind -> genus 0.
    let v = check(&assemble(&labels(&[(1, ThcX), (0, Cube)])));
    assert!(v.valid, "{:?}", v.reason);
    assert_eq!(v.genus, Some(0));
    // THC+X with cubes on both sides: sealed cavity.
    let v = check(&assemble(&labels(&[(1, ThcX), (0, Cube), (2, Cube)])));
    assert!(!v.valid);
    assert_eq!(v.cavities, 1);
    // Two THC+Z stacked along Z: one longer hole, genus 1.
    let v = check(&assemble(&labels(&[(0, ThcZ), (6, ThcZ)])));
    assert_eq!(v.genus, Some(1));
    // Two THC+X in a row: genus 1.
    let v = check(&assemble(&labels(&[(0, ThcX), (1, ThcX), (2, ThcX)])));
    assert_eq!(v.genus, Some(1));
    // Three THC+Z in a row along X: genus 3.
    let v = check(&assemble(&labels(&[(0, ThcZ), (1, ThcZ), (2, ThcZ)])));
    assert_eq!(v.genus, Some(3));
    // BHC+Z under a cube: sealed cavity -> invalid.
    let v = check(&assemble(&labels(&[(0, BhcPz), (6, Cube)])));
    assert!(!v.valid);
    assert!(v.reason.as_ref().unwrap().contains("cavit"), "{:?}", v.reason);
    // BHC-Z under a cube: the opening faces down, fine.
    let v = check(&assemble(&labels(&[(0, BhcMz), (6, Cube)])));
    assert!(v.valid);
    assert_eq!(v.genus, Some(0));
    // BHC+Z under a BHC-Z: joined blind holes make a sealed cavity.
    let v = check(&assemble(&labels(&[(0, BhcPz), (6, BhcMz)])));
    assert!(!v.valid);
    // BHC+Z under a THC+Z: the hole runs on through the upper cell but the BHC's
    // bottom stays closed -> one deeper blind hole, genus 0.
    let v = check(&assemble(&labels(&[(0, BhcPz), (6, ThcZ)])));
    assert!(v.valid);
    assert_eq!(v.genus, Some(0));
    // A THC+Z column (one hole through two cells) beside a THC+X row capped by the
    // column on its -X end (a blind hole): genus 1.
    let v = check(&assemble(&labels(&[(0, ThcZ), (6, ThcZ), (1, ThcX), (2, ThcX)])));
    assert_eq!(v.genus, Some(1 + 0), "{:?}", v.reason);
    // Two cubes touching only along an edge.
    let v = check(&assemble(&labels(&[(0, Cube), (4, Cube)])));
    assert!(!v.valid);
    assert!(v.edge_contacts > 0);
    assert!(v.reason.as_ref().unwrap().contains("cell 0"), "{:?}", v.reason);
    // Two cubes touching at a corner only.
    let v = check(&assemble(&labels(&[(0, Cube), (10, Cube)])));
    assert!(!v.valid);
    assert!(v.vertex_contacts > 0 || v.components == 2);
    // 2x2x2 block minus two diagonally opposite cells: the two empty cells meet at a vertex.
    let mut l = [Null; NUM_CELLS];
    for n in [0, 1, 3, 4, 6, 7, 9, 10] {
        l[n] = Cube;
    }
    l[0] = Null;
    l[10] = Null;
    let v = check(&assemble(&l));
    assert!(!v.valid, "{v:?}");
    assert!(v.vertex_contacts > 0);
}

#[test]
fn cube_occupancy_patterns() {
    let mut valid = 0;
    for mask in 1u32..4096 {
        let mut l = [Null; NUM_CELLS];
        for (n, slot) in l.iter_mut().enumerate() {
            if mask >> n & 1 == 1 {
                *slot = Cube;
            }
        }
        let v = check(&assemble(&l));
        if v.valid {
            valid += 1;
            assert_eq!(v.genus, Some(0), "mask {mask:#x}");
        }
    }
    assert_eq!(valid, 1058);
}

#[test]
fn boundary_mesh_is_closed_and_consistent() {
    let g = assemble(&labels(&[(0, ThcZ), (1, Cube), (6, BhcPx)]));
    let q = boundary(&g);
    let v = check(&g);
    let t = q.to_trimesh();
    // Every directed edge appears once, and its reverse once.
    let mut edges = std::collections::HashMap::new();
    for tri in &t.triangles {
        for e in 0..3 {
            *edges.entry((tri[e], tri[(e + 1) % 3])).or_insert(0) += 1;
        }
    }
    for (&(a, b), &c) in &edges {
        assert_eq!(c, 1);
        assert_eq!(edges.get(&(b, a)), Some(&1));
    }
    let chi = t.vertices.len() as i64 - edges.len() as i64 / 2 + t.triangles.len() as i64;
    assert_eq!(chi, v.euler);
    // Signed volume = voxel count x (1/3)^3.
    let mut vol = 0.0;
    for tri in &t.triangles {
        let [a, b, c] = tri.map(|i| t.vertices[i as usize]);
        vol += (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) + a[2] * (b[0] * c[1] - b[1] * c[0])) / 6.0;
    }
    assert!((vol - g.count() as f64 / 27.0).abs() < 1e-12, "{vol}");
}
