//! All-hex control mesh: parametric mapping of the polycube, octree subdivision,
//! pillowing, smoothing and Jacobian optimisation (issue 6). docs/hex.md describes
//! the method, the frames and every default.

pub mod distance;
pub mod frame;
pub mod grid;
pub mod lattice;
pub mod map;
pub mod optimize;
pub mod pillow;
pub mod pipeline;
pub mod quality;
pub mod refine;
pub mod report;
pub mod sheets;
pub mod surface;
pub mod topology;
pub mod voxel;

pub use frame::Affine;
pub use pipeline::{build_hex_mesh, HexInput, HexOptions, HexResult, QualityGoals, LevelReport, StageReport, SurfaceMapReport};
pub use report::report_json;
pub use voxel::build_voxel_hex_mesh;

use serde::{Deserialize, Serialize};

/// An unstructured all-hex mesh. Elements use VTK_HEXAHEDRON node order
/// (bottom face 0-3 counter-clockwise seen from above, top face 4-7 above them).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct HexMesh {
    pub nodes: Vec<[f64; 3]>,
    pub elements: Vec<[u32; 8]>,
}

impl HexMesh {
    /// The unit cube [0, 1]^3 as one element (a fixture for tests and examples).
    pub fn unit_cube() -> HexMesh {
        let nodes = (0..8).map(|i: usize| [((i + 1) / 2 % 2) as f64, (i / 2 % 2) as f64, (i / 4) as f64]).collect();
        HexMesh { nodes, elements: vec![[0, 1, 2, 3, 4, 5, 6, 7]] }
    }

    pub fn element_corners(&self, e: usize) -> [[f64; 3]; 8] {
        self.elements[e].map(|i| self.nodes[i as usize])
    }
}
