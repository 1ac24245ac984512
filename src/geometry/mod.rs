//! Geometry shared by every stage, the lowest one after `error`: the triangle mesh
//! type ([`TriMesh`]), voxel sets and the voxeliser ([`voxel`]), the seeded random
//! streams ([`rng`]), PCA alignment with centring and normalisation (and the
//! transform back to user coordinates), area-uniform surface sampling, a triangle
//! BVH and closest-point queries.
//!
//! Alignment (docs/mesh-checks.md has the same in prose):
//! 1. Surface moments are area-weighted integrals over the triangles (exact for
//!    piecewise-linear surfaces), not vertex averages, so the result does not
//!    depend on how densely a region is triangulated.
//! 2. The principal axes of the surface covariance, sorted by variance:
//!    largest -> X, then Y, then Z. Eigenvalues within 1e-6 (relative to the
//!    largest) of each other are a tie: the tied axes are replaced by the input's
//!    own coordinate axes (x, then y, then z) projected into the tied subspace and
//!    orthonormalised, so axis-aligned symmetric parts keep their orientation.
//! 3. Signs: X and Y point where the third moment of area (skewness) along them
//!    is positive; when that moment is below 1e-6 A sigma^3 the sign puts the
//!    axis's largest-magnitude component (first one on ties) positive.
//!    Z = X x Y (right-handed, a proper rotation).
//! 4. The rotated surface is centred (bounding-box centre at the origin) and
//!    scaled so that the longest bounding-box edge is 2.

pub mod bvh;
pub mod orient;
pub mod rng;
pub mod trimesh;
pub(crate) mod union_find;
pub mod vec3;
pub mod voxel;

pub use bvh::{closest_point_on_triangle, Aabb, Bvh, ClosestPoint, SurfaceLocator};
pub use trimesh::TriMesh;
pub use voxel::VoxelGrid;

/// Hasher state with fixed keys: hash maps and sets built with it iterate in an
/// order that depends only on what was inserted (std's default state draws
/// random keys per process), so code whose result follows an iteration order
/// gives the same mesh for the same input on every run.
pub type StableState = std::hash::BuildHasherDefault<std::collections::hash_map::DefaultHasher>;
/// A hash map with [`StableState`].
pub type StableHashMap<K, V> = std::collections::HashMap<K, V, StableState>;
/// A hash set with [`StableState`].
pub type StableHashSet<K> = std::collections::HashSet<K, StableState>;
pub(crate) use union_find::UnionFind;

use crate::error::{Error, Result};
use nalgebra::{Matrix3, SymmetricEigen};
use vec3::*;

/// Relative tolerance for equal eigenvalues.
pub const EIGEN_TIE: f64 = 1e-6;
/// Relative tolerance (of A sigma^3) below which a third moment counts as zero.
pub const SKEW_TIE: f64 = 1e-6;

/// A similarity transform `p -> scale * rotation * p + translation`
/// (rotation rows are the new X, Y, Z axes in user coordinates).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Transform {
    pub rotation: [[f64; 3]; 3],
    pub translation: [f64; 3],
    pub scale: f64,
}

impl Transform {
    pub const IDENTITY: Transform =
        Transform { rotation: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]], translation: [0.0; 3], scale: 1.0 };

    /// Map a point of user coordinates into the aligned frame.
    pub fn apply(&self, p: [f64; 3]) -> [f64; 3] {
        let r = self.rotation;
        add(scale([dot(r[0], p), dot(r[1], p), dot(r[2], p)], self.scale), self.translation)
    }

    /// Map a point of the aligned frame back to user coordinates.
    pub fn apply_inverse(&self, q: [f64; 3]) -> [f64; 3] {
        let d = scale(sub(q, self.translation), 1.0 / self.scale);
        let r = self.rotation;
        std::array::from_fn(|k| r[0][k] * d[0] + r[1][k] * d[1] + r[2][k] * d[2])
    }

    /// Rotate a direction (no translation, no scale).
    pub fn apply_direction(&self, v: [f64; 3]) -> [f64; 3] {
        let r = self.rotation;
        [dot(r[0], v), dot(r[1], v), dot(r[2], v)]
    }

    /// The inverse transform, of the same form.
    pub fn inverse(&self) -> Transform {
        let r = self.rotation;
        let rt: [[f64; 3]; 3] = std::array::from_fn(|i| std::array::from_fn(|j| r[j][i]));
        let s = 1.0 / self.scale;
        let t = self.translation;
        let rtt: [f64; 3] = std::array::from_fn(|i| dot(rt[i], t));
        Transform { rotation: rt, translation: scale(rtt, -s), scale: s }
    }

    /// Apply to every vertex of a mesh (triangles unchanged: a proper rotation keeps orientation).
    pub fn apply_mesh(&self, mesh: &TriMesh) -> TriMesh {
        TriMesh { vertices: mesh.vertices.iter().map(|&p| self.apply(p)).collect(), triangles: mesh.triangles.clone() }
    }
}

/// Area-weighted surface moments.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct SurfaceMoments {
    pub area: f64,
    /// Area centroid.
    pub centroid: [f64; 3],
    /// Covariance of the uniform distribution on the surface.
    pub covariance: [[f64; 3]; 3],
}

/// Exact area moments of a triangle surface (degenerate triangles add nothing).
pub fn surface_moments(mesh: &TriMesh) -> SurfaceMoments {
    // shift to the bounding-box centre for accuracy
    let o = Aabb::of_points(&mesh.vertices).centre();
    let mut area = 0.0;
    let mut s1 = [0.0; 3];
    let mut s2 = [[0.0; 3]; 3];
    for t in &mesh.triangles {
        let v = t.map(|i| sub(mesh.vertices[i as usize], o));
        let a = 0.5 * norm(tri_normal(v[0], v[1], v[2]));
        let s = add(add(v[0], v[1]), v[2]);
        area += a;
        for i in 0..3 {
            s1[i] += a * s[i] / 3.0;
            for j in 0..3 {
                s2[i][j] += a / 12.0 * (v[0][i] * v[0][j] + v[1][i] * v[1][j] + v[2][i] * v[2][j] + s[i] * s[j]);
            }
        }
    }
    let m = scale(s1, 1.0 / area);
    let cov = std::array::from_fn(|i| std::array::from_fn(|j| s2[i][j] / area - m[i] * m[j]));
    SurfaceMoments { area, centroid: add(m, o), covariance: cov }
}

/// Third moment of area along unit direction e about point c: integral of ((x - c) . e)^3 dA.
pub fn third_moment(mesh: &TriMesh, c: [f64; 3], e: [f64; 3]) -> f64 {
    let mut m3 = 0.0;
    for t in &mesh.triangles {
        let v = t.map(|i| mesh.vertices[i as usize]);
        let a = 0.5 * norm(tri_normal(v[0], v[1], v[2]));
        let [f1, f2, f3] = v.map(|p| dot(sub(p, c), e));
        // integral over a triangle of a linear function cubed = A/10 * h3(f1, f2, f3)
        let h3 = f1 * f1 * f1 + f2 * f2 * f2 + f3 * f3 * f3
            + f1 * f1 * (f2 + f3)
            + f2 * f2 * (f1 + f3)
            + f3 * f3 * (f1 + f2)
            + f1 * f2 * f3;
        m3 += a / 10.0 * h3;
    }
    m3
}

/// The aligned, centred and normalised mesh with the transform that made it.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Alignment {
    #[serde(skip)]
    pub mesh: TriMesh,
    /// User coordinates -> aligned frame; `transform.inverse()` maps results back.
    pub transform: Transform,
    /// Surface variances along the new X, Y, Z (descending).
    pub variances: [f64; 3],
    /// Third moments of area along the new X, Y, Z (Z's sign follows from X x Y).
    pub third_moments: [f64; 3],
}

/// Principal axes (rows: X, Y, Z) with the deterministic order and signs described in the module docs.
pub fn principal_axes(mesh: &TriMesh) -> Result<([[f64; 3]; 3], [f64; 3], SurfaceMoments)> {
    let mom = surface_moments(mesh);
    if !mom.area.is_finite() || mom.area <= 0.0 {
        return Err(Error::InvalidMesh(format!("cannot align a surface of area {}", mom.area)));
    }
    let c = mom.covariance;
    let eig = SymmetricEigen::new(Matrix3::from_fn(|i, j| c[i][j]));
    let mut idx = [0usize, 1, 2];
    idx.sort_by(|&a, &b| eig.eigenvalues[b].total_cmp(&eig.eigenvalues[a]).then(a.cmp(&b)));
    let lambda: [f64; 3] = idx.map(|i| eig.eigenvalues[i].max(0.0));
    let mut axes: [[f64; 3]; 3] = idx.map(|i| {
        let v = eig.eigenvectors.column(i);
        [v[0], v[1], v[2]]
    });
    // groups of tied eigenvalues
    let tol = EIGEN_TIE * lambda[0];
    let mut g = 0;
    while g < 3 {
        let mut h = g + 1;
        while h < 3 && lambda[h - 1] - lambda[h] <= tol {
            h += 1;
        }
        if h - g > 1 {
            let basis: Vec<[f64; 3]> = axes[g..h].to_vec();
            let mut chosen: Vec<[f64; 3]> = Vec::new();
            for k in 0..3 {
                if chosen.len() == h - g {
                    break;
                }
                let e: [f64; 3] = std::array::from_fn(|i| if i == k { 1.0 } else { 0.0 });
                let mut p = basis.iter().fold([0.0; 3], |acc, u| add(acc, scale(*u, dot(*u, e))));
                for q in &chosen {
                    p = sub(p, scale(*q, dot(*q, p)));
                }
                let n = norm(p);
                if n > 0.1 {
                    chosen.push(scale(p, 1.0 / n));
                }
            }
            // (three coordinate axes always span the subspace, so `chosen` is full)
            axes[g..h].copy_from_slice(&chosen[..h - g]);
        }
        g = h;
    }
    for k in 0..2 {
        let m = third_moment(mesh, mom.centroid, axes[k]);
        let sigma = lambda[k].sqrt();
        let flip = if m.abs() > SKEW_TIE * mom.area * sigma.powi(3) {
            m < 0.0
        } else {
            let a = axes[k];
            let big = (0..3).fold(0, |b, i| if a[i].abs() > a[b].abs() + 1e-12 { i } else { b });
            a[big] < 0.0
        };
        if flip {
            axes[k] = scale(axes[k], -1.0);
        }
    }
    axes[2] = cross(axes[0], axes[1]);
    let n2 = norm(axes[2]);
    axes[2] = scale(axes[2], 1.0 / n2);
    Ok((axes, lambda, mom))
}

/// PCA-align, centre (bounding-box centre at the origin) and normalise
/// (longest bounding-box edge = 2). Refuses a surface without area.
pub fn align(mesh: &TriMesh) -> Result<Alignment> {
    let (axes, lambda, mom) = principal_axes(mesh)?;
    let rotated: Vec<[f64; 3]> = mesh.vertices.iter().map(|&p| [dot(axes[0], p), dot(axes[1], p), dot(axes[2], p)]).collect();
    let bb = Aabb::of_points(&rotated);
    let size = bb.size();
    let longest = size[0].max(size[1]).max(size[2]);
    if !longest.is_finite() || longest <= 0.0 {
        return Err(Error::InvalidMesh(format!("cannot normalise a surface whose bounding box has longest edge {longest}")));
    }
    let s = 2.0 / longest;
    let transform = Transform { rotation: axes, translation: scale(bb.centre(), -s), scale: s };
    let aligned = TriMesh {
        vertices: rotated.iter().map(|&r| sub(scale(r, s), scale(bb.centre(), s))).collect(),
        triangles: mesh.triangles.clone(),
    };
    let c = transform.apply(mom.centroid);
    let third_moments = std::array::from_fn(|k| {
        let e: [f64; 3] = std::array::from_fn(|i| if i == k { 1.0 } else { 0.0 });
        third_moment(&aligned, c, e)
    });
    Ok(Alignment { mesh: aligned, transform, variances: lambda.map(|l| l * s * s), third_moments })
}

/// A point drawn on the surface.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct SurfaceSample {
    pub point: [f64; 3],
    pub triangle: u32,
    /// Barycentric coordinates in the triangle (sum to 1).
    pub bary: [f64; 3],
}

/// `n` points uniformly distributed by area over the surface, reproducible for a
/// given rng state: a triangle by binary search in the cumulative areas, then
/// (1 - sqrt(r1), sqrt(r1)(1 - r2), sqrt(r1) r2). Empty when the surface has no area.
pub fn sample_surface<R: rand::Rng + ?Sized>(mesh: &TriMesh, n: usize, rng: &mut R) -> Vec<SurfaceSample> {
    use rand::RngExt;
    let mut cum = Vec::with_capacity(mesh.triangles.len());
    let mut total = 0.0;
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|i| mesh.vertices[i as usize]);
        total += 0.5 * norm(tri_normal(a, b, c));
        cum.push(total);
    }
    if !total.is_finite() || total <= 0.0 {
        return Vec::new();
    }
    (0..n)
        .map(|_| {
            let u = rng.random::<f64>() * total;
            let t = cum.partition_point(|&c| c <= u).min(cum.len() - 1);
            let (r1, r2) = (rng.random::<f64>(), rng.random::<f64>());
            let s = r1.sqrt();
            let bary = [1.0 - s, s * (1.0 - r2), s * r2];
            let [a, b, c] = mesh.triangles[t].map(|i| mesh.vertices[i as usize]);
            let point = add(add(scale(a, bary[0]), scale(b, bary[1])), scale(c, bary[2]));
            SurfaceSample { point, triangle: t as u32, bary }
        })
        .collect()
}

#[cfg(test)]
mod tests;
