//! Frame selection for polycube fitting. PCA axes are right for elongated smooth
//! shapes, but the principal axes of an L-shaped or stepped part are tilted against
//! its faces. A polycube's faces are axis-aligned, so for CAD-like parts the frame
//! is instead the rotation that best aligns the area-weighted face normals with the
//! coordinate axes: it maximises the quartic alignment
//!
//! E(R) = sum_t A_t sum_a (R n_t)_a^4 / sum_t A_t,
//!
//! which is 1 when every normal is axis-aligned and 3/5 for an isotropic normal
//! distribution (a sphere). When the best E reaches `MIN_ALIGNMENT_STRENGTH` that
//! frame is used, otherwise the PCA frame. Either way the axes are then ordered by
//! bounding-box extent (longest -> X, as the 3x2x2 grid is), signs follow the third
//! moment of area (as in [`super::align`]), and the surface is centred and
//! normalised (longest edge 2).

use super::vec3::*;
use super::{principal_axes, third_moment, Aabb, Alignment, Transform, SKEW_TIE};
use crate::error::{Error, Result};
use super::TriMesh;
use serde::Serialize;

/// Alignment strength above which the normal-aligned frame replaces PCA.
pub const MIN_ALIGNMENT_STRENGTH: f64 = 0.75;

/// Which frame was chosen and why.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct FrameChoice {
    /// "normals" (quartic normal alignment) or "pca".
    pub method: &'static str,
    /// E of the best normal-aligned frame (0.6 sphere .. 1 box).
    pub strength: f64,
}

fn rot_axis(k: usize, t: f64) -> [[f64; 3]; 3] {
    let (c, s) = (t.cos(), t.sin());
    let mut m = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    let (i, j) = ((k + 1) % 3, (k + 2) % 3);
    m[i][i] = c;
    m[i][j] = -s;
    m[j][i] = s;
    m[j][j] = c;
    m
}

fn matmul(a: [[f64; 3]; 3], b: [[f64; 3]; 3]) -> [[f64; 3]; 3] {
    std::array::from_fn(|i| std::array::from_fn(|j| (0..3).map(|k| a[i][k] * b[k][j]).sum()))
}

fn energy(rows: &[[f64; 3]; 3], normals: &[([f64; 3], f64)]) -> f64 {
    let mut e = 0.0;
    let mut w = 0.0;
    for (n, a) in normals {
        let m: f64 = rows.iter().map(|r| dot(*r, *n).powi(4)).sum();
        e += a * m;
        w += a;
    }
    e / w.max(1e-300)
}

/// Local maximisation of E by pattern search over small rotations.
fn refine(mut rows: [[f64; 3]; 3], normals: &[([f64; 3], f64)]) -> ([[f64; 3]; 3], f64) {
    let mut best = energy(&rows, normals);
    let mut step = 0.2;
    while step > 1e-6 {
        let mut improved = false;
        for k in 0..3 {
            for sgn in [1.0, -1.0] {
                let cand = matmul(rows, rot_axis(k, sgn * step));
                let e = energy(&cand, normals);
                if e > best + 1e-14 {
                    best = e;
                    rows = cand;
                    improved = true;
                }
            }
        }
        if !improved {
            step *= 0.5;
        }
    }
    (rows, best)
}

/// Choose the frame (see the module docs) and align, centre and normalise.
pub fn align_axes(mesh: &TriMesh) -> Result<(Alignment, FrameChoice)> {
    let (pca, lambda, mom) = principal_axes(mesh)?;
    let normals: Vec<([f64; 3], f64)> = mesh
        .triangles
        .iter()
        .filter_map(|t| {
            let [a, b, c] = t.map(|i| mesh.vertices[i as usize]);
            let n = tri_normal(a, b, c);
            let l = norm(n);
            (l > 0.0 && l.is_finite()).then(|| (scale(n, 1.0 / l), 0.5 * l))
        })
        .collect();
    let identity = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    let mut starts = vec![pca, identity];
    for k in 0..3 {
        starts.push(matmul(pca, rot_axis(k, std::f64::consts::FRAC_PI_4)));
    }
    let mut best: Option<([[f64; 3]; 3], f64)> = None;
    for s in starts {
        let (r, e) = refine(s, &normals);
        if best.is_none_or(|b| e > b.1 + 1e-12) {
            best = Some((r, e));
        }
    }
    let (nrows, strength) = best.unwrap();
    let (mut axes, method) = if strength >= MIN_ALIGNMENT_STRENGTH { (nrows, "normals") } else { (pca, "pca") };
    // Order by bounding-box extent, longest first (stable on ties).
    let extent = |e: [f64; 3]| {
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for &p in &mesh.vertices {
            let v = dot(e, p);
            lo = lo.min(v);
            hi = hi.max(v);
        }
        hi - lo
    };
    let ext = axes.map(extent);
    let mut idx = [0usize, 1, 2];
    idx.sort_by(|&a, &b| {
        let tie = (ext[a] - ext[b]).abs() <= 1e-6 * ext[a].max(ext[b]);
        if tie {
            a.cmp(&b)
        } else {
            ext[b].total_cmp(&ext[a])
        }
    });
    axes = idx.map(|i| axes[i]);
    for k in 0..2 {
        let m = third_moment(mesh, mom.centroid, axes[k]);
        let sigma = lambda[0].sqrt().max(1e-300);
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
    let rotated: Vec<[f64; 3]> = mesh.vertices.iter().map(|&p| [dot(axes[0], p), dot(axes[1], p), dot(axes[2], p)]).collect();
    let bb = Aabb::of_points(&rotated);
    let size = bb.size();
    let longest = size[0].max(size[1]).max(size[2]);
    if !(longest > 0.0) || !longest.is_finite() {
        return Err(Error::InvalidMesh(format!("cannot normalise a surface whose bounding box has longest edge {longest}")));
    }
    let s = 2.0 / longest;
    let transform = Transform { rotation: axes, translation: scale(bb.centre(), -s), scale: s };
    let aligned = TriMesh { vertices: rotated.iter().map(|&r| sub(scale(r, s), scale(bb.centre(), s))).collect(), triangles: mesh.triangles.clone() };
    let c = transform.apply(mom.centroid);
    let third_moments = std::array::from_fn(|k| {
        let e: [f64; 3] = std::array::from_fn(|i| if i == k { 1.0 } else { 0.0 });
        third_moment(&aligned, c, e)
    });
    let variances = std::array::from_fn(|k| {
        let e = axes[k];
        (0..3).map(|i| (0..3).map(|j| e[i] * mom.covariance[i][j] * e[j]).sum::<f64>()).sum::<f64>() * s * s
    });
    Ok((Alignment { mesh: aligned, transform, variances, third_moments }, FrameChoice { method, strength }))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::trimesh::tests::voxels;

    #[test]
    fn tilted_l_shape_gets_its_faces_back_on_the_axes() {
        // An L of four cubes (three along X, one more along Y): its principal axes
        // are tilted, its faces are not.
        let m = voxels([3, 2, 1], |x, y, _| y == 0 || x == 0);
        let r = matmul(matmul(rot_axis(0, 0.4), rot_axis(1, -0.7)), rot_axis(2, 1.1));
        let tilted = TriMesh { vertices: m.vertices.iter().map(|&p| [dot(r[0], p), dot(r[1], p), dot(r[2], p)]).collect(), triangles: m.triangles.clone() };
        let (al, choice) = align_axes(&tilted).unwrap();
        assert_eq!(choice.method, "normals");
        assert!(choice.strength > 0.999999, "{}", choice.strength);
        // Every face normal of the aligned mesh is along an axis.
        for t in &al.mesh.triangles {
            let [a, b, c] = t.map(|i| al.mesh.vertices[i as usize]);
            let n = tri_normal(a, b, c);
            let l = norm(n);
            let big = n.iter().map(|v| v.abs() / l).fold(0.0, f64::max);
            assert!(big > 1.0 - 1e-6, "{n:?}");
        }
        // Extents: X longest.
        let bb = Aabb::of_points(&al.mesh.vertices).size();
        assert!((bb[0] - 2.0).abs() < 1e-9 && bb[0] >= bb[1] && bb[1] >= bb[2]);
    }
}
