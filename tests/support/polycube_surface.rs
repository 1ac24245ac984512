//! A context's polycube boundary as a triangle mesh: the input of the hex-stage
//! and chart tests (`#[path = "support/polycube_surface.rs"] mod polycube_surface;`);
//! not part of the library.
#![allow(dead_code)]

use sddpm::context::{context_frame, Context};
use sddpm::geometry::vec3::*;
use sddpm::mesh::TriMesh;
use std::collections::HashMap;

/// How each sub-square of a polycube quad is split into two triangles.
#[derive(Clone, Copy, PartialEq, Eq)]
pub enum Diagonals {
    /// Always from the square's first corner.
    Fixed,
    /// Alternating like a checkerboard, so that the mesh has no preferred direction.
    Alternating,
}

/// The polycube's own boundary in the normalised frame, every quad split k x k,
/// coincident points welded.
pub fn polycube_surface(ctx: &Context, k: usize, diagonals: Diagonals) -> TriMesh {
    let q = sddpm::polycube::boundary(&ctx.assemble());
    let frame = context_frame(ctx).unwrap();
    let mut verts: Vec<[f64; 3]> = Vec::new();
    let mut index = HashMap::new();
    let mut tris = Vec::new();
    for quad in &q.quads {
        let p = quad.map(|i| q.vertices[i as usize]);
        let at = |u: f64, v: f64| -> [f64; 3] {
            let a = add(scale(p[0], 1.0 - u), scale(p[1], u));
            let b = add(scale(p[3], 1.0 - u), scale(p[2], u));
            add(scale(a, 1.0 - v), scale(b, v))
        };
        let mut id = |g: [f64; 3]| -> u32 {
            let key = g.map(|v| (v * 1e6).round() as i64);
            *index.entry(key).or_insert_with(|| {
                verts.push(frame.to_normalised(g));
                verts.len() as u32 - 1
            })
        };
        for j in 0..k {
            for i in 0..k {
                let s = |i: usize| i as f64 / k as f64;
                let c = [at(s(i), s(j)), at(s(i + 1), s(j)), at(s(i + 1), s(j + 1)), at(s(i), s(j + 1))].map(&mut id);
                if diagonals == Diagonals::Alternating && (i + j) % 2 == 1 {
                    tris.push([c[0], c[1], c[3]]);
                    tris.push([c[1], c[2], c[3]]);
                } else {
                    tris.push([c[0], c[1], c[2]]);
                    tris.push([c[0], c[2], c[3]]);
                }
            }
        }
    }
    TriMesh { vertices: verts, triangles: tris }
}
