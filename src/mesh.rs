//! Triangle meshes: reading (OBJ, STL, OFF, arrays), welding, checks and measures.
//! (Being written: see issue 2.)

/// An indexed triangle mesh in f64. Triangles are counter-clockwise seen from outside
/// once the mesh has passed the checks.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct TriMesh {
    pub vertices: Vec<[f64; 3]>,
    pub triangles: Vec<[u32; 3]>,
}
