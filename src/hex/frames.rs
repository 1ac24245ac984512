//! The working frame W of the hex stage, shared by the polycube map and the
//! grid-based fallback: the input surface in the user frame, centred, scaled to a
//! longest bounding-box edge of 2 and mirrored when the map to the user frame
//! reverses orientation, with its sharp features.

use super::frame::Affine;
use super::surface::{detect_features, prune_features, Surface};
use super::HexOptions;
use crate::error::{Error, Result};
use crate::geometry::Aabb;
use crate::mesh::TriMesh;

/// The input surface in the working frame W (the user frame centred, scaled to a
/// longest bounding-box edge of 2, mirrored when the map to the user frame reverses
/// orientation), with its sharp features.
pub struct Frames {
    /// The surface in W, with features.
    pub sw: Surface,
    pub to_w: Affine,
    pub w_to_u: Affine,
    pub mirror: bool,
    pub sw_scale: f64,
    pub diag_w: f64,
}

/// Also returns the surface in the caller's frame, outward oriented.
pub fn working_frames(surface: &TriMesh, to_user: &Affine, opts: &HexOptions) -> Result<(Frames, TriMesh)> {
    let mut mesh_n = surface.clone();
    if mesh_n.signed_volume() < 0.0 {
        for t in mesh_n.triangles.iter_mut() {
            t.swap(1, 2);
        }
    }
    let user_pts: Vec<[f64; 3]> = mesh_n.vertices.iter().map(|&p| to_user.apply(p)).collect();
    let ubox = Aabb::of_points(&user_pts);
    let longest = ubox.size().iter().copied().fold(0.0, f64::max);
    if !(longest > 0.0) {
        return Err(Error::InvalidArgument("the input surface has no extent".into()));
    }
    let sw_scale = 2.0 / longest;
    // W is U centred and scaled, and mirrored in x when the map to U reverses
    // orientation, so that the lattice's positive elements stay positive in W.
    let mirror = to_user.det() < 0.0;
    let sx = if mirror { -sw_scale } else { sw_scale };
    let c = ubox.centre();
    let u_to_w = Affine::diagonal([sx, sw_scale, sw_scale], [-sx * c[0], -sw_scale * c[1], -sw_scale * c[2]]);
    let to_w = u_to_w.after(to_user);
    let w_to_u = u_to_w.inverse().expect("similarity");
    let mesh_w = TriMesh { vertices: mesh_n.vertices.iter().map(|&p| to_w.apply(p)).collect(), triangles: mesh_n.triangles.clone() };
    let features = detect_features(&mesh_w, opts.surface.feature_angle, opts.surface.corner_angle);
    let diag0 = Aabb::of_points(&mesh_w.vertices).diagonal();
    let features = prune_features(&mesh_w, features, opts.surface.min_feature_length * diag0, opts.surface.feature_median_angle);
    let sw = Surface::new(mesh_w, features);
    let diag_w = sw.bbox.diagonal();
    Ok((Frames { sw, to_w, w_to_u, mirror, sw_scale, diag_w }, mesh_n))
}
