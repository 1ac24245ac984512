//! libsddpm: Scalable DDPM-Polycube. A closed triangle surface in; a polycube,
//! an all-hex control mesh and a TH-spline3D volumetric spline with its Bézier
//! extraction out. See docs/ and ../shared/DESIGN.md for the conventions.
//!
//! The modules are stages that stack one way, lowest first: error, geometry, mesh,
//! polycube, context, diffusion, search, hex, spline, export, pipeline, and on top
//! the command line and the C ABI (ffi). A stage uses only the stages below it
//! (tests/layers.rs checks every `crate::` path).

pub mod context;
pub mod diffusion;
pub mod error;
pub mod ffi;
pub mod geometry;
pub mod mesh;
pub mod pipeline;
pub mod polycube;
pub mod search;

pub use error::{Error, Result, Status};
pub mod export;
pub mod hex;
pub mod spline;
