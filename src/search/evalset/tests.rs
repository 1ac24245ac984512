use super::*;
use std::collections::HashSet;

/// Contexts of genus 0, 1 and 2 of different sizes.
fn contexts() -> Vec<Context> {
    [
        "cube,null,null,null,null,null,null,null,null,null,null,null",
        "THC+Z,cube,BHC+X,null,null,null,null,null,null,null,null,null",
        "THC+Y,THC+Y,null,null,null,null,cube,THC+Y,null,null,null,null",
        "cube,THC+Z,cube,BHC+Y,cube,THC+X,cube,cube,BHC+Z,cube,cube,cube",
    ]
    .iter()
    .map(|s| Context::parse(s).unwrap())
    .inspect(|c| assert!(c.validity().valid, "{c}"))
    .collect()
}

#[test]
fn every_family_gives_a_closed_manifold_mesh_of_the_contexts_genus() {
    for ctx in contexts() {
        let g = ctx.validity().genus.unwrap();
        for (k, fam) in Deformation::ALL.into_iter().enumerate() {
            let c = EvalCase::of_context(100 + k as u64, "test", &ctx, fam).unwrap_or_else(|e| panic!("{fam} on {ctx}: {e}"));
            let r = c.mesh.check();
            assert!(r.closed && r.manifold && r.components == 1 && r.self_intersecting_pairs == 0, "{fam} on {ctx}: {r:?}");
            assert_eq!(r.genus, Some(g), "{fam} on {ctx}");
            assert_eq!(c.genus, g);
            assert!(c.params.get("qw").is_some() && c.params.get("scale").is_some(), "{fam}: the rigid motion is recorded");
        }
    }
}

#[test]
fn a_case_is_the_same_for_its_seed_and_differs_for_another() {
    for fam in Deformation::ALL {
        let a = EvalCase::generate(910010007, COMPLEXITY_GROUPS[1], fam).unwrap();
        let b = EvalCase::generate(910010007, COMPLEXITY_GROUPS[1], fam).unwrap();
        assert_eq!(a.mesh, b.mesh, "{fam}");
        assert_eq!(a.params, b.params, "{fam}");
        assert_eq!(a.context, b.context);
        let c = EvalCase::generate(910010008, COMPLEXITY_GROUPS[1], fam).unwrap();
        assert_ne!(a.mesh, c.mesh, "{fam}");
        assert!((4..=6).contains(&a.cells), "{}", a.cells);
    }
}

#[test]
fn the_families_change_what_they_say() {
    let ctx = contexts()[2];
    let exact = boundary(&ctx.assemble()).to_trimesh();
    let area = |m: &TriMesh| m.check().area;
    let vol = |m: &TriMesh| m.check().volume;
    // principal variances of the surface (rotation invariant)
    let var = |m: &TriMesh| crate::geometry::principal_axes(m).unwrap().1;
    for fam in Deformation::ALL {
        let c = EvalCase::of_context(5, "test", &ctx, fam).unwrap();
        let s = c.params.get("scale").unwrap();
        // undo the uniform scale: area ~ s^2, volume ~ s^3, variances ~ s^2
        let (ra, rv) = (area(&c.mesh) / (s * s * area(&exact)), vol(&c.mesh) / (s * s * s * vol(&exact)));
        let (v0, v1) = (var(&exact), var(&c.mesh));
        let dv = (0..3).map(|k| (v1[k] / (s * s * v0[k]) - 1.0).abs()).fold(0.0, f64::max);
        match fam {
            // rigid: the same surface
            Deformation::Rotation | Deformation::Remesh => {
                assert!((ra - 1.0).abs() < 1e-9 && (rv - 1.0).abs() < 1e-9 && dv < 1e-6, "{fam}: area {ra} volume {rv} variances {dv}");
            }
            // bending and twisting keep the volume nearly, and change the shape
            Deformation::Bend | Deformation::Twist => assert!((rv - 1.0).abs() < 0.05 && dv > 1e-3, "{fam}: area {ra} volume {rv} variances {dv}"),
            _ => assert!((ra - 1.0).abs() > 1e-4 || dv > 1e-3, "{fam}: area {ra} volume {rv} variances {dv}"),
        }
    }
    // the remeshed surface's triangles are not the exact boundary's regular ones
    let c = EvalCase::of_context(5, "test", &ctx, Deformation::Remesh).unwrap();
    assert!(c.mesh.triangles.len() > exact.triangles.len());
    let areas: HashSet<u64> = c
        .mesh
        .triangles
        .iter()
        .map(|t| {
            let [a, b, cc] = t.map(|i| c.mesh.vertices[i as usize]);
            (crate::geometry::vec3::norm(crate::geometry::vec3::tri_normal(a, b, cc)) * 1e6).round() as u64
        })
        .collect();
    assert!(areas.len() > 20, "{} distinct triangle areas", areas.len());
}

#[test]
fn families_parse_by_name_letter_and_set() {
    assert_eq!(Deformation::parse("c").unwrap(), Deformation::Taper);
    assert_eq!(Deformation::parse("rounding").unwrap(), Deformation::Rounding);
    assert_eq!(Deformation::parse_list("reported").unwrap(), REPORTED_FAMILIES.to_vec());
    assert_eq!(Deformation::parse_list("a,aniso,f").unwrap(), TUNING_FAMILIES.to_vec());
    assert!(Deformation::parse("warp").is_err());
    // the split covers every family once
    for d in Deformation::ALL {
        assert!(TUNING_FAMILIES.contains(&d) ^ REPORTED_FAMILIES.contains(&d), "{d}");
    }
}

#[test]
fn a_set_spreads_the_families_and_records_each_seed() {
    let fams = [Deformation::Twist, Deformation::Remesh];
    let set = eval_set(3, 3, &["simple"], &fams).unwrap();
    assert_eq!(set.iter().map(|c| c.family).collect::<Vec<_>>(), vec![Deformation::Twist, Deformation::Remesh, Deformation::Twist]);
    for (k, c) in set.iter().enumerate() {
        assert_eq!(c.seed, case_seed(3, 0, k));
        assert!((1..=3).contains(&c.cells));
        let again = EvalCase::generate(c.seed, COMPLEXITY_GROUPS[0], c.family).unwrap();
        assert_eq!(again.mesh, c.mesh);
    }
}
