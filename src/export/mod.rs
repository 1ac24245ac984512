//! File formats of the hex and spline stages (VTK, VTU, Medit, LS-DYNA, BEXT).

pub mod obj;
pub mod vtk;
pub mod bext;
pub mod hexfmt;
pub mod lsdyna;
pub mod spline_vtk;
pub mod spline_files;
pub mod plot;
pub mod render;
pub mod report;
