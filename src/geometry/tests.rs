use super::*;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

fn boxed(size: [f64; 3]) -> TriMesh {
    let mut m = TriMesh {
        vertices: (0..8).map(|i| [(i & 1) as f64 * size[0], ((i >> 1) & 1) as f64 * size[1], ((i >> 2) & 1) as f64 * size[2]]).collect(),
        triangles: vec![
            [0, 2, 3], [0, 3, 1], [4, 5, 7], [4, 7, 6], [0, 1, 5], [0, 5, 4],
            [2, 6, 7], [2, 7, 3], [0, 4, 6], [0, 6, 2], [1, 3, 7], [1, 7, 5],
        ],
    };
    m.vertices.iter_mut().for_each(|p| *p = add(*p, [10.0, -3.0, 7.0]));
    m
}

fn rot(axis: [f64; 3], angle: f64) -> [[f64; 3]; 3] {
    let n = norm(axis);
    let [x, y, z] = scale(axis, 1.0 / n);
    let (s, c) = angle.sin_cos();
    let t = 1.0 - c;
    [
        [t * x * x + c, t * x * y - s * z, t * x * z + s * y],
        [t * x * y + s * z, t * y * y + c, t * y * z - s * x],
        [t * x * z - s * y, t * y * z + s * x, t * z * z + c],
    ]
}

fn rotate(m: &TriMesh, r: [[f64; 3]; 3]) -> TriMesh {
    Transform { rotation: r, translation: [1.0, 2.0, 3.0], scale: 1.0 }.apply_mesh(m)
}

/// An asymmetric solid: a 4 x 2 x 1 box with a small box on one end (an "L").
fn ell() -> TriMesh {
    super::trimesh::tests::voxels([4, 2, 2], |x, y, z| z == 0 || (x == 0 && y == 0))
}

#[test]
fn box_is_aligned_and_normalised() {
    let m = rotate(&boxed([4.0, 2.0, 1.0]), rot([1.0, 2.0, 3.0], 0.7));
    let a = align(&m).unwrap();
    let bb = Aabb::of_points(&a.mesh.vertices);
    for k in 0..3 {
        assert!((bb.size()[k] - [2.0, 1.0, 0.5][k]).abs() < 1e-9, "{:?}", bb.size());
        assert!(bb.centre()[k].abs() < 1e-9);
    }
    // the rotation is proper and the inverse maps back
    let r = a.transform.rotation;
    let det = dot(r[0], cross(r[1], r[2]));
    assert!((det - 1.0).abs() < 1e-12);
    for (p, q) in m.vertices.iter().zip(&a.mesh.vertices) {
        let back = a.transform.apply_inverse(*q);
        assert!(dist2(*p, back).sqrt() < 1e-9);
        let inv = a.transform.inverse();
        assert!(dist2(inv.apply(*q), *p).sqrt() < 1e-9);
        assert!(dist2(a.transform.apply(*p), *q).sqrt() < 1e-12);
    }
    assert!(a.variances[0] > a.variances[1] && a.variances[1] > a.variances[2]);
}

#[test]
fn alignment_is_deterministic_and_sign_fixed() {
    let base = ell();
    let a0 = align(&base).unwrap();
    // positive skewness along X and Y after alignment
    assert!(a0.third_moments[0] > 0.0 && a0.third_moments[1] > 0.0, "{:?}", a0.third_moments);
    // any rigid motion of the input gives the same aligned shape
    for (axis, ang) in [([0.0, 0.0, 1.0], 3.0), ([1.0, -1.0, 0.5], 1.1), ([0.3, 0.2, -1.0], 2.5)] {
        let a = align(&rotate(&base, rot(axis, ang))).unwrap();
        for (p, q) in a0.mesh.vertices.iter().zip(&a.mesh.vertices) {
            assert!(dist2(*p, *q).sqrt() < 1e-9, "{p:?} vs {q:?}");
        }
    }
}

#[test]
fn symmetric_axis_aligned_shapes_keep_their_axes() {
    // a cube: all variances tie, all third moments vanish -> identity rotation
    let a = align(&boxed([1.0, 1.0, 1.0])).unwrap();
    assert_eq!(a.transform.rotation, Transform::IDENTITY.rotation);
    // a square rod along z: x and y tie
    let a = align(&boxed([1.0, 1.0, 3.0])).unwrap();
    let r = a.transform.rotation;
    assert!(dist2(r[0], [0.0, 0.0, 1.0]) < 1e-18, "{r:?}");
    assert!(dist2(r[1], [1.0, 0.0, 0.0]) < 1e-18, "{r:?}");
    assert!(dist2(r[2], [0.0, 1.0, 0.0]) < 1e-18, "{r:?}");
}

#[test]
fn moments_are_area_weighted() {
    // refining one face must not move the centroid
    let mut m = boxed([1.0, 1.0, 1.0]);
    let c0 = surface_moments(&m).centroid;
    // split triangle 0 into 3 around its centroid
    let [a, b, c] = m.triangles[0];
    let p = scale(add(add(m.vertices[a as usize], m.vertices[b as usize]), m.vertices[c as usize]), 1.0 / 3.0);
    m.vertices.push(p);
    let n = m.vertices.len() as u32 - 1;
    m.triangles[0] = [a, b, n];
    m.triangles.push([b, c, n]);
    m.triangles.push([c, a, n]);
    let c1 = surface_moments(&m).centroid;
    assert!(dist2(c0, c1).sqrt() < 1e-12);
    assert!(dist2(c0, [10.5, -2.5, 7.5]).sqrt() < 1e-12);
}

#[test]
fn sampling_is_seeded_uniform_and_on_the_surface() {
    let m = boxed([2.0, 1.0, 1.0]);
    let s1 = sample_surface(&m, 60_000, &mut ChaCha8Rng::seed_from_u64(42));
    let s2 = sample_surface(&m, 60_000, &mut ChaCha8Rng::seed_from_u64(42));
    assert_eq!(s1, s2);
    let loc = SurfaceLocator::new(&m);
    // area of the 2 x 1 faces is 2 of total 10 each (4 faces), of the 1 x 1 faces 1 of 10
    let mut per_tri = vec![0usize; m.triangles.len()];
    for s in &s1 {
        per_tri[s.triangle as usize] += 1;
        assert!((s.bary.iter().sum::<f64>() - 1.0).abs() < 1e-12);
        assert!(s.bary.iter().all(|&b| b >= 0.0));
        assert!(loc.closest(s.point).2 < 1e-12);
    }
    for (t, &n) in per_tri.iter().enumerate() {
        let [a, b, c] = m.triangles[t].map(|v| m.vertices[v as usize]);
        let expect = 0.5 * norm(tri_normal(a, b, c)) / 10.0 * 60_000.0;
        assert!((n as f64 - expect).abs() < 5.0 * expect.sqrt(), "triangle {t}: {n} vs {expect}");
    }
}

#[test]
fn locator_matches_brute_force() {
    let m = ell();
    let loc = SurfaceLocator::new(&m);
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    use rand::RngExt;
    for _ in 0..500 {
        let p = [rng.random_range(-2.0..6.0), rng.random_range(-2.0..4.0), rng.random_range(-2.0..4.0)];
        let (q, t, d) = loc.closest(p);
        let brute = m
            .triangles
            .iter()
            .map(|tr| {
                let [a, b, c] = tr.map(|v| m.vertices[v as usize]);
                dist2(p, closest_point_on_triangle(p, a, b, c).0).sqrt()
            })
            .fold(f64::INFINITY, f64::min);
        assert!((d - brute).abs() < 1e-12, "{d} vs {brute}");
        assert!((dist2(p, q).sqrt() - d).abs() < 1e-12);
        assert!((t as usize) < m.triangles.len());
    }
    assert_eq!(loc.closest([0.5, 0.5, -1.0]).2, 1.0);
}
