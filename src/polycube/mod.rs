//! What a polycube is in this library: primitives on the G(3x2x2) grid, their
//! assembly on the 9x6x6 sub-voxel lattice, and the point tensors of the model.

pub mod assembly;
pub mod orientation;
pub mod primitive;
pub mod tensor;

pub use assembly::{assemble, boundary, check, QuadMesh, Validity};
pub use primitive::{cell_coords, cell_index, Family, Primitive, CONTEXT_DIM, GRID, LATTICE, NUM_CELLS, NUM_LABELS};
