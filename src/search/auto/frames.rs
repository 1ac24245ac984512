//! The frames in which the automated mode splits the aligned input into boxes.
//!
//! The alignment orders the input's axes by bounding-box extent (longest along
//! X), and the grid holds three cells along X and two along Y and Z. A part whose
//! three-cell direction is not its longest (a 3 x 2 x 2 assembly scaled 0.7 along
//! its row and 1.4 across it is longer across) has no box of the aligned frame
//! that holds it: every three-cell box cuts its long side into thirds. So the
//! boxes with three cells along X are also analysed with the grid's X along the
//! input's Y and along its Z (the input turned by a cyclic permutation of its
//! axes, [`in_frame`]); their candidates are diffused and verified against the
//! aligned input in that rotation, like any rotated candidate.

use super::super::generate::PreparedInput;
use crate::geometry::{Alignment, SurfaceSample, TriMesh};
use crate::polycube::orientation::AxisRotation;

/// The aligned frame and the two cyclic permutations that put the input's Y,
/// then its Z, along the grid's X (`apply` maps an aligned point into the frame).
pub const FRAMES: [AxisRotation; 3] = [
    AxisRotation::IDENTITY,
    AxisRotation { perm: [1, 2, 0], sign: [1, 1, 1] },
    AxisRotation { perm: [2, 0, 1], sign: [1, 1, 1] },
];

/// The aligned input seen in the frame `r`: its mesh, its samples and its
/// alignment's axes turned by `r` (the transform still maps user coordinates into
/// the turned frame). Areas and the samples' triangles are unchanged.
pub fn in_frame(input: &PreparedInput, r: AxisRotation) -> PreparedInput {
    let a = &input.alignment;
    let t = &a.transform;
    let mut transform = *t;
    transform.rotation = std::array::from_fn(|k| t.rotation[r.perm[k]].map(|x| r.sign[k] as f64 * x));
    transform.translation = r.apply(t.translation);
    let permute = |v: [f64; 3]| -> [f64; 3] { std::array::from_fn(|k| v[r.perm[k]]) };
    let alignment = Alignment {
        mesh: TriMesh { vertices: a.mesh.vertices.iter().map(|p| r.apply(*p)).collect(), triangles: a.mesh.triangles.clone() },
        transform,
        variances: permute(a.variances),
        third_moments: r.apply(a.third_moments),
    };
    let samples = input.samples.iter().map(|s| SurfaceSample { point: r.apply(s.point), ..*s }).collect();
    PreparedInput { alignment, frame: input.frame, samples, area: input.area }
}
