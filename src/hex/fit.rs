//! The boundary fit shared by the polycube map and the grid-based fallback: the
//! boundary nodes of a valid lattice mesh pulled onto the input surface in
//! validity-preserving steps, the tangential relaxation that spreads them on it,
//! and the discrete harmonic interior.

use super::quality::smooth::smooth_nodes;
use super::quality::jacobian::optimise_nodes;
use super::quality::summary;
use super::surface::Surface;
use super::topology::Csr;
use super::work::{local_eval, quad_normals, slide, Attach, Role, Work};
use crate::geometry::vec3::*;
use rayon::prelude::*;

/// Smallest cosine between the mesh boundary normal and the normal of the triangle a
/// boundary node is pulled to.
pub const FIT_FACING: f64 = 0.3;

/// What fitting did.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize)]
pub struct FitStats {
    pub rounds: usize,
    /// Boundary moves kept / tried.
    pub pulls_accepted: usize,
    pub pulls_tried: usize,
    /// Largest distance of a boundary node from its target before the final snap (relative to the surface diagonal).
    pub residual_before_snap: f64,
}

/// Where a boundary node at `x` (mesh normal `normal`) belongs on the surface, and
/// the surface triangle it then lies on (u32::MAX for a corner or a curve): its
/// corner, the closest point of its curve, or the closest point among triangles
/// facing like the mesh there. None for an interior node.
fn boundary_target(sw: &Surface, role: Role, x: [f64; 3], normal: [f64; 3]) -> Option<([f64; 3], u32)> {
    match role {
        Role::Corner(c) => Some((sw.mesh.vertices[c as usize], u32::MAX)),
        Role::Curve(c) => Some((sw.closest_on_curve(c as usize, x).point, u32::MAX)),
        Role::Free => {
            let (q, t, _) = sw.closest_facing(x, normal, FIT_FACING);
            Some((q, t))
        }
        Role::Interior => None,
    }
}

/// Pull the boundary of a valid mesh onto the surface in small steps that keep it valid.
///
/// Each round moves every boundary node part of the way to its target (the closest
/// surface point among triangles facing like the mesh boundary there, its curve, its
/// corner) plus a tangential Laplacian step that keeps the boundary nodes spread; a
/// move is kept only when the node's elements keep a scaled Jacobian of at least
/// min(before, floor) (halving the step twice before giving up). After the boundary,
/// the interior is smoothed and optimised. The last round snaps every boundary node
/// onto its target whatever that does to quality (the later stages repair).
pub fn fit_to_surface(w: &mut Work, sw: &Surface, bquads: &[[u32; 4]], rounds: usize, floor: f64) -> FitStats {
    let n = w.mesh.nodes.len();
    let bnodes: Vec<usize> = (0..n).filter(|&v| w.role[v].on_boundary()).collect();
    let mut st = FitStats::default();
    let diag = sw.bbox.diagonal();
    for r in 0..rounds {
        st.rounds += 1;
        let alpha = (0.2 + 0.8 * (r + 1) as f64 / rounds as f64).min(1.0);
        let nrm = quad_normals(n, bquads, &w.mesh.nodes);
        let mut maxres: f64 = 0.0;
        for &v in &bnodes {
            let role = w.role[v];
            let x = w.mesh.nodes[v];
            let Some((target, tri)) = boundary_target(sw, role, x, nrm[v]) else { continue };
            maxres = maxres.max(norm(sub(target, x)));
            // tangential spreading (Free and Curve nodes)
            let nb: &[u32] = match role {
                Role::Curve(_) => &w.curve_nb[v],
                Role::Free => w.bgraph.of(v),
                _ => &[],
            };
            let mut d = scale(sub(target, x), alpha);
            if !nb.is_empty() {
                let avg = scale(nb.iter().fold([0.0; 3], |a, &u| add(a, w.mesh.nodes[u as usize])), 1.0 / nb.len() as f64);
                let mut lap = sub(avg, x);
                let nn = if tri != u32::MAX { sw.normal(tri) } else { nrm[v] };
                lap = sub(lap, scale(nn, dot(lap, nn)));
                d = add(d, scale(lap, 0.3));
            }
            let before = local_eval(w, v as u32, x);
            for k in 0..3 {
                st.pulls_tried += 1;
                let y = add(x, scale(d, 0.5f64.powi(k)));
                let after = local_eval(w, v as u32, y);
                if after.0 >= before.0.min(floor) && after.1 <= before.1 {
                    w.mesh.nodes[v] = y;
                    w.attach[v] = tri;
                    st.pulls_accepted += 1;
                    break;
                }
            }
        }
        st.residual_before_snap = maxres / diag;
        smooth_nodes(w, sw, 2, floor, true);
        optimise_nodes(w, sw, 0.3, 2, true, |_| false);
    }
    // final snap
    let nrm = quad_normals(n, bquads, &w.mesh.nodes);
    let mut maxres: f64 = 0.0;
    for &v in &bnodes {
        let x = w.mesh.nodes[v];
        let Some((target, tri)) = boundary_target(sw, w.role[v], x, nrm[v]) else { continue };
        maxres = maxres.max(norm(sub(target, x)));
        w.mesh.nodes[v] = target;
        w.attach[v] = tri;
    }
    st.residual_before_snap = maxres / diag;
    st
}

/// Spread the boundary nodes on the surface (plain tangential Laplacian), take the
/// harmonic interior when it is better than the current one, and fit again
/// (`iterations`: the surface relaxation iterations, `SurfaceOptions::relax_iterations`).
pub fn relax_and_refit(work: &mut Work, sw: &Surface, bquads: &[[u32; 4]], iterations: usize, fit_stats: &mut Vec<FitStats>) {
    let before = work.mesh.nodes.clone();
    let before_attach = work.attach.clone();
    let q0 = summary(&work.mesh);
    relax_boundary(sw, &work.role, &work.curve_nb, &work.bgraph, &mut work.mesh.nodes, &mut work.attach, iterations * 2, 0.5);
    let mut harm = work.mesh.nodes.clone();
    harmonic_interior(&work.nbr, &work.role, &mut harm, 1e-9, 5000);
    let q_keep = summary(&work.mesh);
    let keep = std::mem::replace(&mut work.mesh.nodes, harm);
    let q_harm = summary(&work.mesh);
    if (q_keep.inverted, -q_keep.min) < (q_harm.inverted, -q_harm.min) {
        work.mesh.nodes = keep;
    }
    let f = fit_to_surface(work, sw, bquads, iterations, 0.2);
    fit_stats.push(f);
    let q1 = summary(&work.mesh);
    if (q1.inverted, -q1.min) > (q0.inverted, -q0.min) {
        work.mesh.nodes = before;
        work.attach = before_attach;
    }
}

/// Tangential Laplacian relaxation of the boundary nodes on the surface (Jacobi
/// iterations with damping `lambda`).
pub fn relax_boundary(
    sw: &Surface,
    role: &[Role],
    curve_nb: &[Vec<u32>],
    bgraph: &Csr,
    pos: &mut [[f64; 3]],
    attach: &mut [Attach],
    iterations: usize,
    lambda: f64,
) {
    let nodes: Vec<usize> = (0..pos.len()).filter(|&v| matches!(role[v], Role::Free | Role::Curve(_))).collect();
    for _ in 0..iterations {
        let upd: Vec<([f64; 3], Attach)> = nodes
            .par_iter()
            .map(|&v| {
                let nb: &[u32] = match role[v] {
                    Role::Curve(_) => &curve_nb[v],
                    _ => bgraph.of(v),
                };
                if nb.is_empty() {
                    return (pos[v], attach[v]);
                }
                let avg = scale(nb.iter().fold([0.0; 3], |a, &w| add(a, pos[w as usize])), 1.0 / nb.len() as f64);
                slide(sw, role[v], pos[v], attach[v], scale(sub(avg, pos[v]), lambda))
            })
            .collect();
        for (k, &v) in nodes.iter().enumerate() {
            pos[v] = upd[k].0;
            attach[v] = upd[k].1;
        }
    }
}

/// Discrete harmonic interior (uniform edge weights) with the boundary nodes fixed:
/// preconditioned conjugate gradients from the current positions. Returns the
/// iteration count.
pub fn harmonic_interior(nbr: &Csr, role: &[Role], pos: &mut [[f64; 3]], tol: f64, max_iter: usize) -> usize {
    let n = pos.len();
    let inner: Vec<usize> = (0..n).filter(|&v| role[v] == Role::Interior).collect();
    if inner.is_empty() {
        return 0;
    }
    let mut slot = vec![u32::MAX; n];
    for (k, &v) in inner.iter().enumerate() {
        slot[v] = k as u32;
    }
    let m = inner.len();
    let deg: Vec<f64> = inner.iter().map(|&v| nbr.of(v).len() as f64).collect();
    // rhs = sum of boundary neighbours
    let mut iters = 0;
    for axis in 0..3 {
        let b: Vec<f64> = inner
            .par_iter()
            .map(|&v| nbr.of(v).iter().filter(|&&w| slot[w as usize] == u32::MAX).map(|&w| pos[w as usize][axis]).sum())
            .collect();
        let apply = |x: &[f64], y: &mut [f64]| {
            y.par_iter_mut().enumerate().for_each(|(k, yk)| {
                let v = inner[k];
                let mut s = deg[k] * x[k];
                for &w in nbr.of(v) {
                    let j = slot[w as usize];
                    if j != u32::MAX {
                        s -= x[j as usize];
                    }
                }
                *yk = s;
            });
        };
        let mut x: Vec<f64> = inner.iter().map(|&v| pos[v][axis]).collect();
        let mut r = vec![0.0; m];
        apply(&x, &mut r);
        for k in 0..m {
            r[k] = b[k] - r[k];
        }
        let bnorm = b.iter().map(|v| v * v).sum::<f64>().sqrt().max(1e-300);
        let mut z: Vec<f64> = (0..m).map(|k| r[k] / deg[k]).collect();
        let mut p = z.clone();
        let mut rz: f64 = r.iter().zip(&z).map(|(a, b)| a * b).sum();
        let mut ap = vec![0.0; m];
        let mut it = 0;
        while it < max_iter {
            let rn = r.iter().map(|v| v * v).sum::<f64>().sqrt();
            if rn <= tol * bnorm {
                break;
            }
            apply(&p, &mut ap);
            let pap: f64 = p.iter().zip(&ap).map(|(a, b)| a * b).sum();
            if !(pap > 0.0) {
                break;
            }
            let alpha = rz / pap;
            for k in 0..m {
                x[k] += alpha * p[k];
                r[k] -= alpha * ap[k];
            }
            for k in 0..m {
                z[k] = r[k] / deg[k];
            }
            let rz2: f64 = r.iter().zip(&z).map(|(a, b)| a * b).sum();
            let beta = rz2 / rz;
            rz = rz2;
            for k in 0..m {
                p[k] = z[k] + beta * p[k];
            }
            it += 1;
        }
        iters = iters.max(it);
        for (k, &v) in inner.iter().enumerate() {
            pos[v][axis] = x[k];
        }
    }
    iters
}

/// Boundary quads whose normal opposes the normal of the input at their centre.
pub fn flipped_quads(sw: &Surface, pos: &[[f64; 3]], quads: &[[u32; 4]]) -> usize {
    quads
        .par_iter()
        .filter(|q| {
            let p = q.map(|i| pos[i as usize]);
            let nq = cross(sub(p[2], p[0]), sub(p[3], p[1]));
            let c = scale(p.iter().fold([0.0; 3], |a, x| add(a, *x)), 0.25);
            let (_, t, _) = sw.closest(c);
            dot(nq, sw.normal(t)) < 0.0
        })
        .count()
}
