//! Wavefront OBJ output of triangle meshes and assembled polycube surfaces.

use crate::context::Context;
use crate::error::{Error, Result};
use crate::mesh::TriMesh;
use std::fmt::Write as _;
use std::path::Path;

/// OBJ text of a triangle mesh (1-based indices).
pub fn to_obj(m: &TriMesh, comment: &str) -> String {
    let mut s = String::new();
    for line in comment.lines() {
        let _ = writeln!(s, "# {line}");
    }
    for v in &m.vertices {
        let _ = writeln!(s, "v {} {} {}", v[0], v[1], v[2]);
    }
    for t in &m.triangles {
        let _ = writeln!(s, "f {} {} {}", t[0] + 1, t[1] + 1, t[2] + 1);
    }
    s
}

pub fn write_obj(path: &Path, m: &TriMesh, comment: &str) -> Result<()> {
    std::fs::write(path, to_obj(m, comment)).map_err(|e| Error::io(path.display(), e))
}

/// The boundary of a context's assembly in grid units (one cell = 1) as OBJ, quads
/// split into triangles; refuses an invalid assembly.
pub fn write_polycube_obj(path: &Path, ctx: &Context) -> Result<()> {
    let v = ctx.validity();
    let q = crate::polycube::boundary(&ctx.assemble());
    let comment = format!(
        "libsddpm polycube {}\nvalid: {}  genus: {}  sub-voxels: {}",
        ctx.names(),
        v.valid,
        v.genus.map(|g| g.to_string()).unwrap_or("-".into()),
        v.voxels
    );
    write_obj(path, &q.to_trimesh(), &comment)
}
