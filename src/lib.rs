//! libsddpm: Scalable DDPM-Polycube. A closed triangle surface in; a polycube,
//! an all-hex control mesh and a TH-spline3D volumetric spline with its Bézier
//! extraction out. See docs/ and ../shared/DESIGN.md for the conventions.
//!
//! The modules are stages that stack one way, lowest first: error, geometry, mesh,
//! polycube, context, diffusion, search, hex, spline, export, pipeline, the command
//! line (cli) and on top the C ABI (ffi), whose sddpm_run runs `sddpm run` with the
//! command line's parser. A stage uses only the stages below it
//! (tests/layers.rs checks every `crate::` path).

// The command line (src/cli) names this crate `sddpm`, as the `sddpm` binary does;
// it is compiled into the library so that the C ABI's sddpm_run parses the same
// arguments as `sddpm run`.
extern crate self as sddpm;

pub mod cli;
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
