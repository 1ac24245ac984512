//! File formats of the hex and spline stages (VTK, VTU, Medit, LS-DYNA, BEXT), the
//! stages' files of a run folder, PNG plots and the software renderer.

pub mod obj;
pub mod vtk;
pub mod bext;
pub mod hexfmt;
pub mod lsdyna;
pub mod spline_vtk;
pub mod spline_vtu;
pub mod spline_files;
pub mod plot;
pub mod render;
