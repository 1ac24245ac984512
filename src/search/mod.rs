//! Polycube search: from an input surface to verified candidate polycubes. The
//! input laid out for a candidate context ([`inference`]), the user-guided
//! generation ([`generate`]) and the automated, genus-guided mode ([`auto`]), the
//! hierarchical verification of a diffusion output ([`verify`]), and the held-in
//! synthetic cases ([`synthetic`]) on which the model and the search are measured
//! ([`eval`]), an evaluation set of deformation families independent of them
//! ([`evalset`]) and where the automated mode lost a part's true polycube
//! ([`funnel`]).

pub mod auto;
pub mod eval;
pub mod evalset;
pub mod funnel;
pub mod generate;
pub mod inference;
pub mod synthetic;
pub mod verify;
