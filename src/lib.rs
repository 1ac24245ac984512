//! libsddpm: Scalable DDPM-Polycube. A closed triangle surface in; a polycube,
//! an all-hex control mesh and a TH-spline3D volumetric spline with its Bézier
//! extraction out. See docs/ and ../shared/DESIGN.md for the conventions.

pub mod context;
pub mod diffusion;
pub mod error;
pub mod ffi;
pub mod geometry;
pub mod mesh;
pub mod pipeline;
pub mod polycube;
pub mod verify;

pub use error::{Error, Result, Status};
pub mod export;
pub mod hex;
