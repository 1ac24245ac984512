//! Smart Laplacian smoothing: every movable node towards the average of its
//! neighbours when that keeps its elements' smallest scaled Jacobian; the fit
//! and the pulls of the capture and coverage steps even out the interior with it.

use crate::hex::surface::Surface;
use crate::hex::work::{local_eval, slide, MoveStats, Role, Work};
use crate::geometry::vec3::*;

/// Smart Laplacian smoothing: every movable node goes towards the average of its
/// neighbours (surface / curve neighbours for boundary nodes) when that keeps the
/// smallest scaled Jacobian of its elements at or above min(before, floor);
/// with `interior_only`, the interior nodes only.
pub fn smooth_nodes(w: &mut Work, sw: &Surface, iterations: usize, floor: f64, interior_only: bool) -> MoveStats {
    let mut st = MoveStats::default();
    let n = w.mesh.nodes.len();
    for _ in 0..iterations {
        st.passes += 1;
        let mut moved = 0usize;
        for v in 0..n {
            let role = w.role[v];
            if interior_only && role != Role::Interior {
                continue;
            }
            let nb: &[u32] = match role {
                Role::Corner(_) => continue,
                Role::Interior => w.nbr.of(v),
                Role::Free => w.bgraph.of(v),
                Role::Curve(_) => &w.curve_nb[v],
            };
            if nb.is_empty() {
                continue;
            }
            let x = w.mesh.nodes[v];
            let avg = scale(nb.iter().fold([0.0; 3], |a, &u| add(a, w.mesh.nodes[u as usize])), 1.0 / nb.len() as f64);
            let d = sub(avg, x);
            if norm(d) < 1e-12 * (1.0 + norm(x)) {
                continue;
            }
            let before = local_eval(w, v as u32, x);
            let (y, t) = slide(sw, role, x, w.attach[v], d);
            st.moves_tried += 1;
            let after = local_eval(w, v as u32, y);
            if after.0 >= before.0.min(floor) && after.1 <= before.1 {
                w.mesh.nodes[v] = y;
                w.attach[v] = t;
                st.moves_accepted += 1;
                moved += 1;
            }
        }
        if moved == 0 {
            break;
        }
    }
    st
}
