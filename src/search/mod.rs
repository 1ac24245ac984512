//! Polycube search: from an input surface to verified candidate polycubes. The
//! input laid out for a candidate context ([`inference`]), the user-guided
//! generation ([`generate`]) and the automated, genus-guided mode ([`auto`]), the
//! hierarchical verification of a diffusion output ([`verify`]), and the held-in
//! synthetic cases ([`synthetic`]) on which the model and the search are measured
//! ([`eval`]).

pub mod auto;
pub mod eval;
pub mod generate;
pub mod inference;
pub mod synthetic;
pub mod verify;
