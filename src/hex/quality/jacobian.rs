//! Local max-min optimisation of the Verdict scaled Jacobian (which also
//! untangles: it raises negative terms first), and the optimisation step: the
//! max-min optimisation, its polish, the mean ascent of the interior, and the
//! release of the boundary nodes where the boundary itself is folded.
//!
//! A move is kept only when the smallest scaled Jacobian of the node's elements
//! does not drop, so the optimisation cannot lower the minimum of the mesh.

use super::ascent::mean_ascent;
use super::measure::{element_qualities, scaled_jacobian, summary, QualitySummary, DEGENERATE};
use super::step::{pass_reporter, stage_report};
use super::terms::softmin_gradient;
use super::untangle::{mean_ratio_smooth, mean_ratio_smooth_released};
use crate::error::{check_progress, Error, Progress, Result};
use crate::geometry::vec3::*;
use crate::hex::options::QualityOptions;
use crate::hex::stages::{OptimisationDetails, Stage, StageDetails, StageReport};
use crate::hex::surface::Surface;
use crate::hex::work::{better, local_eval, mean_edge, q, slide, MoveStats, Role, Work};
use std::time::Instant;

/// The optimisation step: the max-min optimisation (`opts.optimise_passes`
/// passes), then (with passes) the mean-ratio energy again never below the
/// minimum reached and half the passes more, the mean ascent of the interior
/// when nothing is inverted, and where elements are still inverted the release
/// of their boundary nodes ([`release_folded`]). `diag_w`: the input's diagonal.
pub fn optimisation(work: &mut Work, sw: &Surface, diag_w: f64, opts: &QualityOptions, progress: &mut dyn Progress) -> Result<StageReport> {
    check_progress(progress, 0.65, "hex: optimisation")?;
    let t0 = Instant::now();
    let before = summary(&work.mesh);
    let passes = opts.optimise_passes;
    let mut cancelled = false;
    let mut st = optimise(work, sw, opts.optimise_target, passes, pass_reporter(progress, 0.65, 0.2, passes, &mut cancelled));
    if cancelled {
        return Err(Error::Cancelled("hex: optimisation".into()));
    }
    // polish: the mean-ratio energy again, now never below the minimum reached
    if passes > 0 {
        check_progress(progress, 0.88, "hex: optimisation")?;
        let floor = summary(&work.mesh).min;
        let p = mean_ratio_smooth(work, sw, opts.smooth_iterations, Some(floor.max(0.0)), |_| true);
        let p2 = optimise(work, sw, opts.optimise_target, passes / 2, |_| false);
        st.passes += p.passes + p2.passes;
        st.moves_tried += p.moves_tried + p2.moves_tried;
        st.moves_accepted += p.moves_accepted + p2.moves_accepted;
    }
    // mean ascent of the interior nodes: raise the mean scaled Jacobian, never below
    // the minimum reached
    let mut ascent = MoveStats::default();
    let q = summary(&work.mesh);
    let mean_before_ascent = q.mean;
    if passes > 0 && q.inverted == 0 {
        check_progress(progress, 0.9, "hex: optimisation")?;
        ascent = mean_ascent(work, passes, q.min, pass_reporter(progress, 0.9, 0.05, passes, &mut cancelled));
        if cancelled {
            return Err(Error::Cancelled("hex: optimisation".into()));
        }
    }
    let released_nodes = if opts.release_distance > 0.0 && q.inverted > 0 { release_folded(work, sw, &q, opts.release_distance * diag_w, opts) } else { 0 };
    let details = OptimisationDetails { moves: st, mean_ascent: ascent, mean_before_ascent, released_boundary_nodes: released_nodes };
    Ok(stage_report(Stage::Optimisation, before, &work.mesh, t0, StageDetails::Optimisation(details)))
}

/// Where elements are still inverted, the boundary itself is folded: the boundary
/// nodes of the bad elements (and their ring) may leave the input by `leave`
/// (the mean ascent runs only without them and cannot invert one: `q`, the
/// quality before it, still counts them). Undone when it leaves the mesh worse
/// than `q`; returns the nodes released (0 when undone).
fn release_folded(work: &mut Work, sw: &Surface, q: &QualitySummary, leave: f64, opts: &QualityOptions) -> usize {
    let passes = opts.optimise_passes;
    let sj = element_qualities(&work.mesh);
    let mut rel = vec![false; work.mesh.nodes.len()];
    for (e, el) in work.mesh.elements.iter().enumerate() {
        if sj[e] <= 0.05 || sj[e] == DEGENERATE {
            for &v in el {
                rel[v as usize] = true;
                for &u in work.nbr.of(v as usize) {
                    rel[u as usize] = true;
                }
            }
        }
    }
    for v in 0..rel.len() {
        rel[v] &= work.role[v].on_boundary();
    }
    let mut released_nodes = rel.iter().filter(|&&b| b).count();
    let keep = (work.mesh.nodes.clone(), work.attach.clone());
    mean_ratio_smooth_released(work, sw, opts.smooth_iterations, None, |_| true, &rel, leave);
    optimise(work, sw, opts.optimise_target, passes / 2, |_| false);
    let q1 = summary(&work.mesh);
    if (q1.inverted, -q1.min) > (q.inverted, -q.min) {
        work.mesh.nodes = keep.0;
        work.attach = keep.1;
        released_nodes = 0;
    }
    released_nodes
}

/// Local max-min optimisation of the scaled Jacobian. Visits, worst first, the nodes of
/// elements whose scaled Jacobian is below `target`; each visit takes a few steps along
/// the gradient of a soft minimum of the node's terms (projected on the surface / curve
/// for boundary nodes) and keeps a step only when the true minimum over the node's
/// elements increases. Stops after `max_passes` or when a pass changes nothing.
pub fn optimise(w: &mut Work, sw: &Surface, target: f64, max_passes: usize, cancel: impl FnMut(usize) -> bool) -> MoveStats {
    optimise_nodes(w, sw, target, max_passes, false, cancel)
}

/// [`optimise`], optionally on interior nodes only.
pub fn optimise_nodes(
    w: &mut Work,
    sw: &Surface,
    target: f64,
    max_passes: usize,
    interior_only: bool,
    mut cancel: impl FnMut(usize) -> bool,
) -> MoveStats {
    let mut st = MoveStats::default();
    let n = w.mesh.nodes.len();
    let mut buf = Vec::with_capacity(128);
    let mut quality: Vec<f64> =
        (0..w.mesh.elements.len()).map(|e| q(scaled_jacobian(&w.mesh.element_corners(e)))).collect();
    for pass in 0..max_passes {
        if cancel(pass) {
            break;
        }
        st.passes += 1;
        // active nodes, worst first: the elements in the tail above the current minimum
        let gmin = quality.iter().copied().fold(f64::INFINITY, f64::min);
        let threshold = target.min(gmin.max(-1.0) + 0.15);
        let mut node_q = vec![f64::INFINITY; n];
        for (e, el) in w.mesh.elements.iter().enumerate() {
            if quality[e] < threshold {
                for &v in el {
                    node_q[v as usize] = node_q[v as usize].min(quality[e]);
                }
            }
        }
        let mut active: Vec<usize> =
            (0..n)
                .filter(|&v| node_q[v].is_finite() && !matches!(w.role[v], Role::Corner(_)))
                .filter(|&v| !interior_only || w.role[v] == Role::Interior)
                .collect();
        if active.is_empty() {
            break;
        }
        active.sort_by(|&a, &b| node_q[a].total_cmp(&node_q[b]).then(a.cmp(&b)));
        let mut improved = 0usize;
        for &v in &active {
            let role = w.role[v];
            let h = mean_edge(w, v);
            if !(h > 0.0) {
                continue;
            }
            let mut cur = local_eval(w, v as u32, w.mesh.nodes[v]);
            let mut beta = 40.0;
            for _step in 0..4 {
                let mut g = softmin_gradient(w, v as u32, beta, &mut buf);
                if role.on_boundary() {
                    // tangential part only (the slide projects back anyway)
                    let t = w.attach[v];
                    if let Role::Free = role {
                        let nrm = if t != u32::MAX { sw.normal(t) } else { sw.normal(sw.closest(w.mesh.nodes[v]).1) };
                        g = sub(g, scale(nrm, dot(g, nrm)));
                    }
                }
                let gl = norm(g);
                if !(gl > 1e-14) {
                    break;
                }
                let dir = scale(g, 1.0 / gl);
                let mut s = 0.25 * h;
                let mut accepted = false;
                for _ls in 0..7 {
                    st.moves_tried += 1;
                    let x = w.mesh.nodes[v];
                    let (y, t) = slide(sw, role, x, w.attach[v], scale(dir, s));
                    let val = local_eval(w, v as u32, y);
                    if better(val, cur) {
                        w.mesh.nodes[v] = y;
                        w.attach[v] = t;
                        cur = val;
                        accepted = true;
                        st.moves_accepted += 1;
                        break;
                    }
                    s *= 0.5;
                }
                if !accepted {
                    if beta < 400.0 {
                        beta *= 4.0;
                        continue;
                    }
                    break;
                }
                improved += 1;
            }
            for &e in w.n2e.of(v) {
                quality[e as usize] = q(scaled_jacobian(&w.mesh.element_corners(e as usize)));
            }
        }
        if improved == 0 {
            break;
        }
    }
    st
}
