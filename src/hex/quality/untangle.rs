//! Untangling and smoothing by the target mean-ratio energy of the element
//! corners (Escobar et al. 2003's modified determinant, so that inverted corners
//! have a finite, smooth energy): the smoothing step, the finer levels' interior,
//! the polish after the optimisation and the release of folded boundary nodes.

use super::measure::{summary, CORNERS};
use super::step::stage_report;
use crate::geometry::vec3::*;
use crate::hex::stages::{Stage, StageDetails, StageReport};
use crate::hex::surface::Surface;
use crate::hex::work::{local_eval, mark_with_neighbours, mean_edge, slide, MoveStats, Role, Work};
use std::time::Instant;

/// The smoothing step: `iterations` passes of [`untangle`] over every node.
pub fn smoothing(work: &mut Work, sw: &Surface, iterations: usize) -> StageReport {
    let t0 = Instant::now();
    let before = summary(&work.mesh);
    let st: MoveStats = untangle(work, sw, iterations, |_| true);
    stage_report(Stage::Smoothing, before, &work.mesh, t0, StageDetails::Smoothing(st))
}

/// Untangling and smoothing by the target mean-ratio energy of the corners:
/// [`mean_ratio_smooth`] without a quality floor.
pub fn untangle(w: &mut Work, sw: &Surface, passes: usize, nodes_filter: impl Fn(usize) -> bool) -> MoveStats {
    mean_ratio_smooth(w, sw, passes, None, nodes_filter)
}

/// Gauss-Seidel passes over the movable nodes minimising the target mean-ratio energy
/// of their corners (boundary nodes tangentially, then back onto the surface / curve),
/// steepest descent with backtracking. A move is kept when the node's energy decreases,
/// its valid elements stay valid, and with `floor = Some(f)` when the smallest scaled
/// Jacobian of its elements stays at least min(before, f). The first pass visits every
/// node, later passes only the neighbourhood of nodes that moved.
pub fn mean_ratio_smooth(
    w: &mut Work,
    sw: &Surface,
    passes: usize,
    floor: Option<f64>,
    nodes_filter: impl Fn(usize) -> bool,
) -> MoveStats {
    mean_ratio_smooth_released(w, sw, passes, floor, nodes_filter, &[], 0.0)
}

/// [`mean_ratio_smooth`] where the surface / curve nodes flagged in `released` may
/// leave the input by at most `leave` (they move freely, then are pulled back to
/// within `leave` of their closest surface point): the trade of a little surface fit
/// for validity where the boundary itself is folded.
pub fn mean_ratio_smooth_released(
    w: &mut Work,
    sw: &Surface,
    passes: usize,
    floor: Option<f64>,
    nodes_filter: impl Fn(usize) -> bool,
    released: &[bool],
    leave: f64,
) -> MoveStats {
    let mut st = MoveStats::default();
    let n = w.mesh.nodes.len();
    let mut active: Vec<bool> = (0..n).map(|v| !matches!(w.role[v], Role::Corner(_)) && nodes_filter(v)).collect();
    for _ in 0..passes {
        st.passes += 1;
        let mut next = vec![false; n];
        let mut moved = 0usize;
        for v in 0..n {
            if !active[v] {
                continue;
            }
            let role = w.role[v];
            let l = mean_edge(w, v);
            if !(l > 0.0) {
                continue;
            }
            let (smin, smean) = rel_dets(w, v as u32);
            let delta = if smin < 1e-3 * smean { 0.05 * smean } else { 1e-4 * smean };
            let x = w.mesh.nodes[v];
            let q_before = local_eval(w, v as u32, x);
            let valid_before = q_before.1 == 0;
            let (e0, mut g) = node_energy(w, v as u32, x, delta);
            if !e0.is_finite() {
                continue;
            }
            let free3d = released.get(v).copied().unwrap_or(false) && matches!(role, Role::Free | Role::Curve(_));
            if let (Role::Free, false) = (role, free3d) {
                let t = w.attach[v];
                let nrm = if t != u32::MAX { sw.normal(t) } else { sw.normal(sw.closest(x).1) };
                g = sub(g, scale(nrm, dot(g, nrm)));
            }
            let gl = norm(g);
            if !(gl > 0.0) {
                continue;
            }
            let mut step = 0.2 * l / gl;
            for _ in 0..10 {
                st.moves_tried += 1;
                let (y, t) = if free3d {
                    let y = add(x, scale(g, -step));
                    let (q, t, d) = sw.closest(y);
                    (if d > leave { add(q, scale(sub(y, q), leave / d)) } else { y }, t)
                } else {
                    slide(sw, role, x, w.attach[v], scale(g, -step))
                };
                let (e1, _) = node_energy(w, v as u32, y, delta);
                let ok = e1 < e0 - 1e-12 * e0 && {
                    let q = local_eval(w, v as u32, y);
                    (!valid_before || q.1 == 0) && floor.is_none_or(|f| q.0 >= q_before.0.min(f))
                };
                if ok {
                    w.mesh.nodes[v] = y;
                    w.attach[v] = t;
                    st.moves_accepted += 1;
                    if norm(sub(y, x)) > 1e-3 * l {
                        moved += 1;
                        mark_with_neighbours(w, v, &mut next);
                    }
                    break;
                }
                step *= 0.5;
            }
        }
        for v in 0..n {
            active[v] = next[v] && !matches!(w.role[v], Role::Corner(_)) && nodes_filter(v);
        }
        if moved == 0 {
            break;
        }
    }
    st
}

/// Axis (0 = u: node 0 -> 1, 1 = v: 0 -> 3, 2 = w: 0 -> 4) of each edge of each Verdict corner.
const CORNER_AXES: [[usize; 3]; 8] = {
    const UNIT: [[i32; 3]; 8] = [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]];
    let mut out = [[0usize; 3]; 8];
    let mut c = 0;
    while c < 8 {
        let mut k = 0;
        while k < 3 {
            let a = UNIT[CORNERS[c][0]];
            let b = UNIT[CORNERS[c][k + 1]];
            let mut ax = 0;
            while ax < 3 {
                if a[ax] != b[ax] {
                    out[c][k] = ax;
                }
                ax += 1;
            }
            k += 1;
        }
        c += 1;
    }
    out
};

/// Mean-ratio energy of one corner with edge vectors a, b, c measured against a target
/// box with edge lengths `d` along the element's axes (`axes` says which axis each edge
/// follows), with the modified determinant h(s) = (s + sqrt(s^2 + 4 delta^2)) / 2 of
/// Escobar et al. (2003) so that inverted corners have a finite, smooth energy:
/// eta = (|a|^2/d_a^2 + |b|^2/d_b^2 + |c|^2/d_c^2) / (3 h(det(a, b, c) / (d0 d1 d2))^(2/3)).
/// eta = 1 exactly for the target box. Returns eta and d eta / d(a, b, c).
#[inline]
fn corner_energy(a: [f64; 3], b: [f64; 3], c: [f64; 3], d: [f64; 3], axes: [usize; 3], delta: f64) -> (f64, [[f64; 3]; 3]) {
    let (wa, wb, wc) = (1.0 / (d[axes[0]] * d[axes[0]]), 1.0 / (d[axes[1]] * d[axes[1]]), 1.0 / (d[axes[2]] * d[axes[2]]));
    let vol = d[0] * d[1] * d[2];
    let f = wa * dot(a, a) + wb * dot(b, b) + wc * dot(c, c);
    let bc = cross(b, c);
    let s = dot(a, bc) / vol;
    let r = (s * s + 4.0 * delta * delta).sqrt();
    let h = 0.5 * (s + r);
    if !(h > 0.0) {
        return (f64::INFINITY, [[0.0; 3]; 3]);
    }
    let h23 = h.powf(2.0 / 3.0);
    let eta = f / (3.0 * h23);
    let dh = if r > 0.0 { 0.5 * (1.0 + s / r) } else { 1.0 };
    let k1 = 2.0 / (3.0 * h23);
    let k2 = (2.0 / 9.0) * f / (h23 * h) * dh / vol;
    let ga = sub(scale(a, k1 * wa), scale(bc, k2));
    let gb = sub(scale(b, k1 * wb), scale(cross(c, a), k2));
    let gc = sub(scale(c, k1 * wc), scale(cross(a, b), k2));
    (eta, [ga, gb, gc])
}

/// Energy of node v at x over the corners of its elements that involve it, and its gradient.
fn node_energy(w: &Work, v: u32, x: [f64; 3], delta: f64) -> (f64, [f64; 3]) {
    let mut e_sum = 0.0;
    let mut g = [0.0; 3];
    for &e in w.n2e.of(v as usize) {
        let el = w.mesh.elements[e as usize];
        let d = w.target.get(e as usize).copied().unwrap_or([1.0; 3]);
        let p: [[f64; 3]; 8] = std::array::from_fn(|k| if el[k] == v { x } else { w.mesh.nodes[el[k] as usize] });
        let m = el.iter().position(|&u| u == v).unwrap();
        for (ci, cn) in CORNERS.iter().enumerate() {
            let Some(role) = cn.iter().position(|&k| k == m) else { continue };
            let o = p[cn[0]];
            let (eta, gr) = corner_energy(sub(p[cn[1]], o), sub(p[cn[2]], o), sub(p[cn[3]], o), d, CORNER_AXES[ci], delta);
            e_sum += eta;
            if !eta.is_finite() {
                continue;
            }
            let dg = match role {
                0 => scale(add(add(gr[0], gr[1]), gr[2]), -1.0),
                k => gr[k - 1],
            };
            g = add(g, dg);
        }
    }
    (e_sum, g)
}

/// Smallest and mean corner determinant (relative to the target boxes) of the elements of v.
fn rel_dets(w: &Work, v: u32) -> (f64, f64) {
    let mut m = f64::INFINITY;
    let mut sum = 0.0;
    let mut n = 0.0;
    for &e in w.n2e.of(v as usize) {
        let p = w.mesh.element_corners(e as usize);
        let d = w.target.get(e as usize).copied().unwrap_or([1.0; 3]);
        let vol = d[0] * d[1] * d[2];
        for cn in CORNERS {
            let o = p[cn[0]];
            let s = dot(sub(p[cn[1]], o), cross(sub(p[cn[2]], o), sub(p[cn[3]], o))) / vol;
            m = m.min(s);
            sum += s.abs();
            n += 1.0;
        }
    }
    (m, if n > 0.0 { sum / n } else { 0.0 })
}
