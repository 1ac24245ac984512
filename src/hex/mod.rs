//! All-hex control mesh: parametric mapping of the polycube, octree subdivision,
//! pillowing, smoothing and Jacobian optimisation. docs/hex.md describes
//! the method, the frames and every default.
//!
//! By concern:
//! - [`options`]: the options, nested by concern, and their one check;
//! - [`map`]: the polycube map, the method of this library ([`build_hex_mesh`]);
//! - [`voxel`]: the grid-based fallback ([`build_voxel_hex_mesh`]);
//! - [`quality`]: the quality measure and the quality steps after either, one per file;
//! - [`goals`], [`report`], [`stages`]: the quality goals and the ranking of
//!   meshes, the typed result and its report.json object, the steps' reports;
//! - the shared pieces: the working frame ([`frames`]), the node state and the
//!   node-local measures ([`work`]), the boundary fit ([`fit`]), the lattice
//!   meshes ([`grid`], [`lattice`], [`refine`]), the input surface with its sharp
//!   features ([`surface`]), mesh topology ([`topology`]), the Hausdorff distance
//!   ([`distance`]) and affine frames ([`frame`]).

pub mod distance;
pub(crate) mod fit;
pub mod frame;
pub(crate) mod frames;
pub mod goals;
pub mod grid;
pub mod lattice;
mod map;
pub mod options;
pub mod quality;
pub mod refine;
pub mod report;
pub mod stages;
pub mod surface;
pub mod topology;
pub mod voxel;
pub(crate) mod work;

pub use fit::FitStats;
pub use frame::Affine;
pub use goals::QualityGoals;
pub use map::{build_hex_mesh, charts, HexInput};
pub use options::{FallbackOptions, HexOption, HexOptions, InvalidHexOption, MapOptions, QualityOptions, SurfaceMap, SurfaceOptions};
pub use report::{report_json, Domain, HexResult, LevelReport, MapMethod, Returned, SurfaceMapReport};
pub use stages::{Stage, StageDetails, StageReport};
pub use voxel::build_voxel_hex_mesh;
pub use work::MoveStats;

use serde::{Deserialize, Serialize};

/// An unstructured all-hex mesh. Elements use VTK_HEXAHEDRON node order
/// (bottom face 0-3 counter-clockwise seen from above, top face 4-7 above them).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct HexMesh {
    pub nodes: Vec<[f64; 3]>,
    pub elements: Vec<[u32; 8]>,
}

impl HexMesh {
    /// The unit cube [0, 1]^3 as one element (a fixture of the unit tests).
    #[cfg(test)]
    pub(crate) fn unit_cube() -> HexMesh {
        let nodes = (0..8).map(|i: usize| [((i + 1) / 2 % 2) as f64, (i / 2 % 2) as f64, (i / 4) as f64]).collect();
        HexMesh { nodes, elements: vec![[0, 1, 2, 3, 4, 5, 6, 7]] }
    }

    pub fn element_corners(&self, e: usize) -> [[f64; 3]; 8] {
        self.elements[e].map(|i| self.nodes[i as usize])
    }
}
