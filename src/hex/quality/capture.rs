//! Sharp-edge capture (`QualityOptions::capture_features`): boundary nodes near
//! the input's sharp feature curves go onto them (or, at a staircase step's
//! convex corner, off them onto the majority face), after the smoothing and
//! again ("recapture") after the optimisation; the pulls towards a target that
//! the coverage step shares.

use super::ascent::mean_ascent;
use super::jacobian::optimise;
use super::measure::summary;
use super::smooth::smooth_nodes;
use super::step::{fit_step_kept, guarded_fit_step, pass_reporter};
use super::jacobian::optimise_nodes;
use crate::error::{check_progress, Error, Progress, Result};
use crate::geometry::vec3::*;
use crate::hex::stages::{CaptureDetails, Stage, StageDetails, StageReport};
use crate::hex::surface::Surface;
use crate::hex::work::{local_eval, mean_boundary_edge, Role, Work};
use crate::hex::HexOptions;
use rayon::prelude::*;

/// The capture step (with `QualityOptions::capture_features`), after the smoothing:
/// [`capture_features`] within [`CAPTURE_REACH`] boundary edges, kept by
/// [`fit_step_kept`] (closer, the minimum held).
pub fn capture(work: &mut Work, sw: &Surface, opts: &HexOptions) -> Option<StageReport> {
    if !opts.quality.capture_features {
        return None;
    }
    let reach = CAPTURE_REACH * mean_boundary_edge(work);
    let kept = |b: &_, a: &_, h0, h1| fit_step_kept(b, a, h0, h1, &opts.goals, false);
    guarded_fit_step(work, sw, opts, Stage::Capture, kept, StageDetails::Capture, |w, floor| {
        let st = capture_features(w, sw, reach, opts.surface.relax_iterations, floor);
        (st.candidates > 0, st.snapped + st.lifted > 0, CaptureDetails { capture: st, moves: None, mean_ascent: None })
    })
}

/// The sharp-edge capture again on the optimised mesh, then re-optimised (with
/// `QualityOptions::capture_features`, optimisation passes and no inverted
/// element). The optimisation slides boundary nodes along the surface, off the
/// curves the first capture put them on or nearer to: capture once more, optimise
/// and raise the mean again, keep it all only when the distance falls and the
/// minimum and the mean hold (each at least as before or meeting its goal: the
/// mesh is final now; hexgen_hepta at 36 voxels: 1.67 -> 1.31 %, at 12: 1.77 ->
/// 1.49 % with the coverage step; undone on hexgen_rod at 28 and 36).
pub fn recapture(work: &mut Work, sw: &Surface, opts: &HexOptions, progress: &mut dyn Progress) -> Result<Option<StageReport>> {
    let passes = opts.quality.optimise_passes;
    if !(opts.quality.capture_features && passes > 0 && summary(&work.mesh).inverted == 0) {
        return Ok(None);
    }
    check_progress(progress, 0.95, "hex: recapture")?;
    let reach = CAPTURE_REACH * mean_boundary_edge(work);
    let mut cancelled = false;
    let kept = |b: &_, a: &_, h0, h1| fit_step_kept(b, a, h0, h1, &opts.goals, true);
    let report = guarded_fit_step(work, sw, opts, Stage::Recapture, kept, StageDetails::Capture, |w, floor| {
        let st = capture_features(w, sw, reach, opts.surface.relax_iterations, floor);
        let moved = st.snapped + st.lifted > 0;
        let mut details = CaptureDetails { capture: st, moves: None, mean_ascent: None };
        if moved {
            let o = optimise(w, sw, opts.quality.optimise_target, passes, pass_reporter(progress, 0.95, 0.005, passes, &mut cancelled));
            let m = summary(&w.mesh).min;
            let a = mean_ascent(w, passes, m, pass_reporter(progress, 0.955, 0.005, passes, &mut cancelled));
            details.moves = Some(o);
            details.mean_ascent = Some(a);
        }
        (st.candidates > 0, moved, details)
    });
    if cancelled {
        return Err(Error::Cancelled("hex: recapture".into()));
    }
    Ok(report)
}

/// How near a sharp curve (in mean boundary edge lengths) a boundary node must be
/// for the capture step to move it (0.5 / 0.75 / 1.0 / 1.5 measured on hepta and
/// rod at HexGen-like counts: BENCHMARKS.md "Sharp-edge capture").
pub const CAPTURE_REACH: f64 = 0.75;

/// What [`capture_features`] did.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize)]
pub struct CaptureStats {
    /// Boundary nodes within reach of a sharp curve whose quads lie on both sides.
    pub candidates: usize,
    /// Nodes to go onto the curve / off it onto one face; how many got there.
    pub snap: usize,
    pub snapped: usize,
    pub lift: usize,
    pub lifted: usize,
    pub rounds: usize,
}

/// Sharp-edge capture on a lattice boundary (`QualityOptions::capture_features`): a boundary node
/// within `reach` of a sharp feature curve whose boundary quads face both faces of
/// the curve (by their normals) goes onto the curve when at least two quads face
/// each side, and otherwise (one quad on the minority side: the convex corner of a
/// staircase step) off the curve by half `reach` onto its majority face, so that
/// no quad gets three nodes on a straight curve. The nodes are pulled in steps that
/// keep every element above min(before, `floor`); snapped nodes then slide on the
/// curve, nodes not reached go back.
pub fn capture_features(w: &mut Work, sw: &Surface, reach: f64, rounds: usize, floor: f64) -> CaptureStats {
    let mut st = CaptureStats::default();
    if sw.features.curves.is_empty() {
        return st;
    }
    let bq: Vec<[u32; 4]> = crate::hex::topology::boundary_quads(&w.mesh).unwrap_or_default().into_iter().map(|q| q.nodes).collect();
    let n = w.mesh.nodes.len();
    let mut node_quads: Vec<Vec<u32>> = vec![Vec::new(); n];
    for (k, q) in bq.iter().enumerate() {
        for &v in q {
            node_quads[v as usize].push(k as u32);
        }
    }
    let qn: Vec<[f64; 3]> = bq
        .iter()
        .map(|q| {
            let p = q.map(|i| w.mesh.nodes[i as usize]);
            let c = cross(sub(p[2], p[0]), sub(p[3], p[1]));
            let l = norm(c);
            if l > 0.0 {
                scale(c, 1.0 / l)
            } else {
                c
            }
        })
        .collect();
    // the two faces along each input edge
    let edge_tris = crate::hex::surface::edge_triangles(&sw.mesh);
    // the curves' segments in runs of CAPTURE_CHUNK with their boxes: a node looks
    // only at the runs whose box is within reach (the nearest curve within reach is
    // among them)
    const CAPTURE_CHUNK: usize = 16;
    let chunks: Vec<(usize, std::ops::Range<usize>, crate::geometry::bvh::Aabb)> = (0..sw.features.curves.len())
        .flat_map(|c| {
            let ns = sw.curve_segments(c);
            (0..ns).step_by(CAPTURE_CHUNK).map(move |s0| (c, s0..(s0 + CAPTURE_CHUNK).min(ns)))
        })
        .map(|(c, r)| {
            let b = r.clone().fold(crate::geometry::bvh::Aabb::EMPTY, |b, s| {
                let (p, q) = sw.curve_segment(c, s);
                b.grow(p).grow(q)
            });
            (c, r, b)
        })
        .collect();
    // (node, target, curve to slide on once there)
    let plan: Vec<(usize, [f64; 3], Option<u32>)> = (0..n)
        .into_par_iter()
        .filter_map(|v| {
            if w.role[v] != Role::Free || node_quads[v].len() < 2 {
                return None;
            }
            let x = w.mesh.nodes[v];
            let (c, cp) = chunks
                .iter()
                .filter(|ch| ch.2.dist2(x) <= reach * reach)
                .map(|ch| (ch.0, sw.closest_on_curve_segments(ch.0, ch.1.clone(), x)))
                .min_by(|a, b| a.1.distance.total_cmp(&b.1.distance))?;
            if cp.distance > reach {
                return None;
            }
            let cv = &sw.features.curves[c];
            let (a, b) = (cv.vertices[cp.segment as usize], cv.vertices[(cp.segment as usize + 1) % cv.vertices.len()]);
            let tris = edge_tris.get(&(a.min(b), a.max(b)))?;
            if tris.len() != 2 {
                return None;
            }
            let (n1, n2) = (sw.normal(tris[0]), sw.normal(tris[1]));
            let (mut k1, mut k2) = (0usize, 0usize);
            for &q in &node_quads[v] {
                if dot(qn[q as usize], n1) >= dot(qn[q as usize], n2) {
                    k1 += 1;
                } else {
                    k2 += 1;
                }
            }
            if k1 == 0 || k2 == 0 {
                return None;
            }
            if k1 >= 2 && k2 >= 2 {
                return Some((v, cp.point, Some(c as u32)));
            }
            // off the curve onto the majority face: away from the other face's plane
            let (maj, other) = if k1 > k2 { (n1, n2) } else { (n2, n1) };
            let y = sub(cp.point, scale(other, 0.5 * reach));
            let (q, _, _) = sw.closest_facing(y, maj, 0.9);
            Some((v, q, None))
        })
        .collect();
    st.candidates = plan.len();
    st.snap = plan.iter().filter(|p| p.2.is_some()).count();
    st.lift = plan.len() - st.snap;
    if plan.is_empty() {
        return st;
    }
    let saved_role: Vec<Role> = plan.iter().map(|p| w.role[p.0]).collect();
    for p in &plan {
        // held while pulled: no projection (only interior nodes are smoothed
        // meanwhile, so the vertex index is never used)
        w.role[p.0] = Role::Corner(0);
    }
    let start: Vec<([f64; 3], u32)> = plan.iter().map(|p| (w.mesh.nodes[p.0], w.attach[p.0])).collect();
    let tol = 1e-3 * reach;
    let moves: Vec<(usize, [f64; 3])> = plan.iter().map(|&(v, t, _)| (v, t)).collect();
    st.rounds = pull_nodes(w, sw, &moves, rounds, floor, tol).0;
    for (k, &(v, target, curve)) in plan.iter().enumerate() {
        let x = w.mesh.nodes[v];
        if norm(sub(target, x)) <= tol {
            w.mesh.nodes[v] = target;
            match curve {
                Some(c) => {
                    w.role[v] = Role::Curve(c);
                    w.attach[v] = u32::MAX;
                    st.snapped += 1;
                }
                None => {
                    w.role[v] = saved_role[k];
                    w.attach[v] = sw.closest(target).1;
                    st.lifted += 1;
                }
            }
            continue;
        }
        w.role[v] = saved_role[k];
        put_back(w, sw, v, start[k], floor);
    }
    st
}

/// Pull held nodes towards their targets over `rounds` rounds (a growing share of
/// the way each round, halved up to three times until the node's elements stay
/// above min(before, `floor`) with no more inverted), smoothing the interior
/// between rounds; a node within `reach` of its target is not moved again.
/// Returns the rounds run and the moves accepted.
pub fn pull_nodes(w: &mut Work, sw: &Surface, moves: &[(usize, [f64; 3])], rounds: usize, floor: f64, reach: f64) -> (usize, usize) {
    let (mut ran, mut accepted) = (0, 0);
    for r in 0..rounds {
        ran += 1;
        let alpha = ((r + 1) as f64 / rounds as f64).min(1.0);
        let mut moving = false;
        for &(v, target) in moves {
            let x = w.mesh.nodes[v];
            let d = sub(target, x);
            if norm(d) <= reach {
                continue;
            }
            moving = true;
            let before = local_eval(w, v as u32, x);
            for k in 0..4 {
                let y = add(x, scale(d, alpha * 0.5f64.powi(k)));
                let after = local_eval(w, v as u32, y);
                if after.0 >= before.0.min(floor) && after.1 <= before.1 {
                    w.mesh.nodes[v] = y;
                    accepted += 1;
                    break;
                }
            }
        }
        if !moving {
            break;
        }
        smooth_nodes(w, sw, 2, floor, true);
        optimise_nodes(w, sw, 0.3, 2, true, |_| false);
    }
    (ran, accepted)
}

/// A pulled node that did not arrive: back to where it started (`start`, with its
/// triangle) when that keeps its elements valid and above min(now, `floor`), else
/// onto the surface where it stands, else where it is.
pub fn put_back(w: &mut Work, sw: &Surface, v: usize, start: ([f64; 3], u32), floor: f64) {
    let x = w.mesh.nodes[v];
    let before = local_eval(w, v as u32, x);
    let (q, t, _) = sw.closest(x);
    for (y, a) in [start, (q, t)] {
        let after = local_eval(w, v as u32, y);
        if after.1 <= before.1 && after.0 >= before.0.min(floor) {
            w.mesh.nodes[v] = y;
            w.attach[v] = a;
            break;
        }
    }
}
