//! The voxel fallback's lattice planes: uniform (`resolution` voxels of one size
//! along the longest bounding-box edge, centred on the box), or with planes moved
//! onto the input's large axis-parallel planar faces (a rectilinear lattice:
//! between two such faces the spacing is their distance over the nearest whole
//! number of voxels, beyond the outermost ones the uniform size). A face on a
//! lattice plane is met by the voxels' faces themselves instead of by a staircase
//! the fit has to pull half a voxel onto it; the scaled Jacobian of a box does not
//! depend on its aspect, so the unequal spacings cost no quality by themselves.
//!
//! The lattice is voxelised through the warp that takes each axis's planes to
//! equally spaced ones (piecewise linear per axis, so a point is inside the
//! surface exactly when its image is inside the image of the surface): the
//! uniform voxeliser runs unchanged on the warped surface.

use crate::error::Result;
use crate::geometry::Aabb;
use crate::mesh::TriMesh;
use std::borrow::Cow;

/// The planes of a rectilinear lattice, per axis in increasing order (the voxel
/// `i` along axis `a` lies between `planes[a][i]` and `planes[a][i + 1]`), and the
/// uniform lattice `lo + i * h` they are warped to for voxelising.
#[derive(Clone, Debug, PartialEq)]
pub struct LatticePlanes {
    pub planes: [Vec<f64>; 3],
    /// The nominal voxel size (the uniform lattice's).
    pub h: f64,
    /// The uniform lattice's first plane per axis (= `planes[a][0]`).
    pub lo: [f64; 3],
    /// The planes moved onto faces, per axis (empty when uniform).
    pub aligned: [Vec<f64>; 3],
}

/// A planar face group of the input: the axis it is normal to, where it lies and
/// its area.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AxisPlane {
    pub axis: usize,
    pub at: f64,
    pub area: f64,
}

/// Triangles whose normal is within this of an axis count as normal to it
/// (cos 0.5 degrees: CAD planes are exact, faceted curved faces are not).
const AXIS_NORMAL_COS: f64 = 0.999_96;

/// The input's axis-parallel planes: triangles normal to an axis grouped by their
/// position along it (within 1e-4 of the longest bounding-box edge), each with its
/// area, largest first; and the surface's whole area.
pub fn axis_planes(mesh: &TriMesh) -> (Vec<AxisPlane>, f64) {
    let bb = Aabb::of_points(&mesh.vertices);
    let tol = 1e-4 * bb.size().iter().copied().fold(0.0, f64::max);
    let mut out = Vec::new();
    let mut total = 0.0;
    for axis in 0..3 {
        let mut tris: Vec<(f64, f64)> = Vec::new();
        for t in &mesh.triangles {
            let [a, b, c] = t.map(|i| mesh.vertices[i as usize]);
            let u = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
            let v = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
            let n = [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]];
            let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
            if axis == 0 {
                total += len / 2.0;
            }
            if len > 0.0 && (n[axis] / len).abs() >= AXIS_NORMAL_COS {
                tris.push(((a[axis] + b[axis] + c[axis]) / 3.0, len / 2.0));
            }
        }
        tris.sort_by(|x, y| x.0.total_cmp(&y.0));
        let mut i = 0;
        while i < tris.len() {
            let mut j = i;
            let (mut area, mut moment) = (0.0, 0.0);
            while j < tris.len() && tris[j].0 - tris[i].0 <= tol {
                area += tris[j].1;
                moment += tris[j].0 * tris[j].1;
                j += 1;
            }
            out.push(AxisPlane { axis, at: moment / area, area });
            i = j;
        }
    }
    out.sort_by(|x, y| y.area.total_cmp(&x.area));
    (out, total)
}

impl LatticePlanes {
    /// The uniform lattice of `crate::geometry::voxel::voxelize`: `resolution`
    /// voxels along the longest edge, centred on the bounding box.
    pub fn uniform(mesh: &TriMesh, resolution: usize) -> Result<LatticePlanes> {
        let (lo, h, dims) = crate::geometry::voxel::uniform_lattice(mesh, resolution)?;
        let planes: [Vec<f64>; 3] = std::array::from_fn(|a| (0..=dims[a]).map(|i| lo[a] + i as f64 * h).collect());
        Ok(LatticePlanes { lo, planes, h, aligned: Default::default() })
    }

    /// The lattice of the same voxel size with planes on the input's axis-parallel
    /// planar faces of at least `min_share` of its area (largest first; one closer
    /// than half a voxel to a plane already taken is skipped). Uniform when there
    /// is none.
    pub fn aligned(mesh: &TriMesh, resolution: usize, min_share: f64) -> Result<LatticePlanes> {
        let uniform = Self::uniform(mesh, resolution)?;
        if !(min_share > 0.0) {
            return Ok(uniform);
        }
        let bb = Aabb::of_points(&mesh.vertices);
        let h = uniform.h;
        let (found, total) = axis_planes(mesh);
        let mut anchors: [Vec<f64>; 3] = Default::default();
        for p in found {
            if p.area < min_share * total {
                break;
            }
            let taken = &mut anchors[p.axis];
            if taken.iter().all(|&q| (q - p.at).abs() >= 0.5 * h) {
                taken.push(p.at);
            }
        }
        let planes: [Vec<f64>; 3] = std::array::from_fn(|a| {
            let mut an = anchors[a].clone();
            if an.is_empty() {
                return uniform.planes[a].clone();
            }
            an.sort_by(f64::total_cmp);
            let (lo, hi) = (bb.min[a], bb.max[a]);
            let mut v = vec![an[0]];
            for w in an.windows(2) {
                let k = ((w[1] - w[0]) / h).round().max(1.0) as usize;
                v.extend((1..=k).map(|i| w[0] + (w[1] - w[0]) * i as f64 / k as f64));
            }
            // beyond the outermost faces: the uniform size until the box is covered
            let slack = 1e-9 * h;
            while *v.last().unwrap() < hi - slack {
                let x = *v.last().unwrap() + h;
                v.push(x);
            }
            let mut below = Vec::new();
            let mut x = v[0];
            while x > lo + slack {
                x -= h;
                below.push(x);
            }
            below.reverse();
            below.extend(v);
            below
        });
        Ok(LatticePlanes { lo: std::array::from_fn(|a| planes[a][0]), planes, h, aligned: anchors.map(|mut v| {
            v.sort_by(f64::total_cmp);
            v
        }) })
    }

    pub fn dims(&self) -> [usize; 3] {
        std::array::from_fn(|a| self.planes[a].len() - 1)
    }

    /// Whether every axis is uniformly spaced from `lo` by `h` (then the warp is
    /// the identity and is skipped, so the uniform lattice's results are exact).
    pub fn is_uniform(&self) -> bool {
        self.aligned.iter().all(|v| v.is_empty())
    }

    /// Lattice coordinate (voxel index, fractional) -> position.
    pub fn to_world(&self, u: [f64; 3]) -> [f64; 3] {
        std::array::from_fn(|a| {
            let p = &self.planes[a];
            let n = p.len() - 1;
            if self.aligned[a].is_empty() {
                return self.lo[a] + u[a] * self.h;
            }
            let i = (u[a].floor().max(0.0) as usize).min(n - 1);
            p[i] + (u[a] - i as f64) * (p[i + 1] - p[i])
        })
    }

    /// Position -> lattice coordinate (the inverse of [`Self::to_world`]; linear
    /// beyond the outermost planes).
    pub fn to_lattice(&self, x: [f64; 3]) -> [f64; 3] {
        std::array::from_fn(|a| {
            let p = &self.planes[a];
            if self.aligned[a].is_empty() {
                return (x[a] - self.lo[a]) / self.h;
            }
            let n = p.len() - 1;
            let i = p.partition_point(|&q| q <= x[a]).saturating_sub(1).min(n - 1);
            i as f64 + (x[a] - p[i]) / (p[i + 1] - p[i])
        })
    }

    /// The size of voxel `c` along each axis.
    pub fn voxel_size(&self, c: [u32; 3]) -> [f64; 3] {
        std::array::from_fn(|a| if self.aligned[a].is_empty() { self.h } else { self.planes[a][c[a] as usize + 1] - self.planes[a][c[a] as usize] })
    }

    /// The surface as the uniform voxeliser should see it: warped so that the
    /// planes fall on `lo + i * h` (itself when the lattice is uniform).
    pub fn warped<'m>(&self, mesh: &'m TriMesh) -> Cow<'m, TriMesh> {
        if self.is_uniform() {
            return Cow::Borrowed(mesh);
        }
        let vertices = mesh.vertices.iter().map(|&x| {
            let u = self.to_lattice(x);
            std::array::from_fn(|a| self.lo[a] + u[a] * self.h)
        });
        Cow::Owned(TriMesh { vertices: vertices.collect(), triangles: mesh.triangles.clone() })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_uniform_planes_are_the_voxelisers() {
        let b = crate::geometry::trimesh::tests::box_mesh([0.0, 0.0, 0.0], [1.0, 1.0, 0.55]);
        let l = LatticePlanes::uniform(&b, 10).unwrap();
        let v = crate::geometry::voxel::voxelize(&b, 10).unwrap();
        assert_eq!(l.dims(), v.grid.dims);
        assert_eq!(l.lo, v.lo);
        assert_eq!(l.h, v.h);
        assert!(l.is_uniform());
        assert!(matches!(l.warped(&b), Cow::Borrowed(_)));
    }

    #[test]
    fn planes_land_on_the_large_faces_and_the_warp_inverts() {
        // a box of 1 x 1 x 0.55 at 10 voxels: uniform planes at -0.025 + 0.1 i in z
        // miss its top and bottom; aligned, z has 6 voxels of 0.55 / 6 from 0
        let b = crate::geometry::trimesh::tests::box_mesh([0.0, 0.0, 0.0], [1.0, 1.0, 0.55]);
        let l = LatticePlanes::aligned(&b, 10, 0.05).unwrap();
        assert_eq!(l.aligned, [vec![0.0, 1.0], vec![0.0, 1.0], vec![0.0, 0.55]]);
        assert_eq!(l.dims(), [10, 10, 6]);
        assert!((l.planes[2][6] - 0.55).abs() < 1e-15 && l.planes[2][0] == 0.0);
        for x in [[0.0, 0.3, 0.0], [0.37, 0.91, 0.2], [1.0, 1.0, 0.55]] {
            let y = l.to_world(l.to_lattice(x));
            assert!((0..3).all(|a| (x[a] - y[a]).abs() < 1e-14), "{x:?} {y:?}");
        }
        let s = l.voxel_size([0, 0, 4]);
        assert!((s[2] - 0.55 / 6.0).abs() < 1e-12 && (s[0] - 0.1).abs() < 1e-12);
        // the warped surface fills the lattice's voxels exactly
        let w = l.warped(&b);
        let g = crate::geometry::voxel::voxelize_on(&w, l.lo, l.h, l.dims());
        assert_eq!(g.count(), 600);
    }
}
