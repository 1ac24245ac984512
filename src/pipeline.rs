//! The whole job, stage by stage, as one library call each: polycube generation from
//! a request (complete contexts, partial constraints, splitting ratios or the
//! automated search), then (in later stages) the hex mesh and the spline.

use crate::context::auto::{auto_failure, generate_auto, AutoOptions, AutoReport, SplitRatios};
use crate::context::generate::{generate_from_contexts, PolycubeOptions, PolycubeResult};
use crate::context::{Constraints, Context};
use crate::diffusion::Model;
use crate::error::{Error, Progress, Result};
use crate::mesh::TriMesh;
use serde::{Deserialize, Serialize};

/// How the caller asks for a polycube.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum ContextRequest {
    /// Complete contexts (one or a stack).
    Contexts(Vec<Context>),
    /// Partial constraints, expanded to every valid context of the input's genus.
    Constraints(Constraints),
    /// The automated search over the full grid split by these ratios.
    Ratios(SplitRatios),
    /// The automated search over every occupied box.
    Auto,
}

/// Most contexts a constraint set may expand to before diffusion (after the genus filter).
pub const MAX_CONSTRAINT_CONTEXTS: usize = 4096;

/// Generate and verify polycubes for `mesh` (whose genus the mesh check measured).
/// On success the result has a chosen candidate; when nothing passes, the error is
/// `VerificationFailed` naming what failed (the result is returned alongside so that a
/// caller can still report every candidate).
pub fn generate_polycube(
    model: &Model,
    mesh: &TriMesh,
    genus: i64,
    request: &ContextRequest,
    opts: &PolycubeOptions,
    aopts: &AutoOptions,
    progress: &mut dyn Progress,
) -> Result<(PolycubeResult, Option<AutoReport>, Option<Error>)> {
    match request {
        ContextRequest::Contexts(cs) => {
            let r = generate_from_contexts(model, mesh, genus, cs, opts, progress)?;
            let e = r.accepted().err();
            Ok((r, None, e))
        }
        ContextRequest::Constraints(c) => {
            let mut c = c.clone();
            if let Some(g) = c.genus {
                if g != genus {
                    return Err(Error::GenusMismatch { input: genus, context: g, detail: " (the constraints ask for that genus); no diffusion was run".into() });
                }
            }
            c.genus = Some(genus);
            let all = c.enumerate()?;
            if all.is_empty() {
                return Err(Error::InvalidContext(format!(
                    "no valid context satisfies the constraints with the input's genus {genus}; relax the counts or the allowed cells"
                )));
            }
            if all.len() > MAX_CONSTRAINT_CONTEXTS {
                return Err(Error::LimitExceeded(format!(
                    "the constraints expand to {} contexts (limit {MAX_CONSTRAINT_CONTEXTS}); fix more counts or cells",
                    all.len()
                )));
            }
            let r = generate_from_contexts(model, mesh, genus, &all, opts, progress)?;
            let e = r.accepted().err();
            Ok((r, None, e))
        }
        ContextRequest::Ratios(ratios) => {
            let (r, rep) = generate_auto(model, mesh, genus, Some(ratios), opts, aopts, progress)?;
            let e = auto_failure(&r, &rep);
            Ok((r, Some(rep), e))
        }
        ContextRequest::Auto => {
            let (r, rep) = generate_auto(model, mesh, genus, None, opts, aopts, progress)?;
            let e = auto_failure(&r, &rep);
            Ok((r, Some(rep), e))
        }
    }
}
