//! The polycube's start embedding: its sub-voxel planes, uniform or fitted to the
//! input (`MapOptions::fit_planes`).

use crate::hex::grid::{boundary_faces_lattice, LatticeHex};
use crate::hex::surface::Surface;
use crate::geometry::vec3::*;

/// A per-axis piecewise-linear map from grid units to the normalised frame through the
/// sub-voxel planes (grid coordinate k / 3): the polycube's start embedding. The
/// uniform warp is the context frame itself; [`fit_warp`] moves the inner planes
/// towards the input so that, e.g., a through-hole of the polycube starts where the
/// input's hole is.
#[derive(Debug, Clone, PartialEq)]
pub struct Warp {
    /// planes[a][k]: normalised coordinate of grid coordinate k / 3 along axis a.
    pub planes: [Vec<f64>; 3],
}

impl Warp {
    pub fn uniform(frame: &crate::polycube::tensor::BoxFrame) -> Warp {
        let lat = crate::polycube::primitive::LATTICE;
        Warp {
            planes: std::array::from_fn(|a| {
                (0..=lat[a]).map(|k| (k as f64 / 3.0 - frame.centre[a]) * frame.scale).collect()
            }),
        }
    }

    /// Grid units -> normalised frame.
    pub fn apply(&self, g: [f64; 3]) -> [f64; 3] {
        std::array::from_fn(|a| {
            let p = &self.planes[a];
            let s = g[a] * 3.0;
            let k = (s.floor().max(0.0) as usize).min(p.len() - 2);
            let f = s - k as f64;
            p[k] + f * (p[k + 1] - p[k])
        })
    }

    /// Normalised extent along each axis of the element at lattice cell `c` of a
    /// lattice with `subdiv` elements per sub-voxel.
    pub fn element_extent(&self, c: [u32; 3], subdiv: usize) -> [f64; 3] {
        std::array::from_fn(|a| {
            let k = (c[a] as usize / subdiv).min(self.planes[a].len() - 2);
            (self.planes[a][k + 1] - self.planes[a][k]) / subdiv as f64
        })
    }
}

/// What [`fit_warp`] measured per axis: the planes moved and by how much at most
/// (normalised units).
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize)]
pub struct WarpReport {
    pub planes_fitted: usize,
    pub max_shift: f64,
}

/// Fit the inner sub-voxel planes of the occupied box to the input: for every level-0
/// boundary quad lying on a plane, the line through its centre along the plane's
/// normal meets the input surface; the nearest crossing whose triangle faces the same
/// way gives that quad's wish, the plane moves to the median wish. Planes without
/// boundary quads are interpolated; the box planes stay; the order is kept with a gap
/// of at least a quarter of the uniform spacing.
pub fn fit_warp(h0: &LatticeHex, frame: &crate::polycube::tensor::BoxFrame, box_cells: ([usize; 3], [usize; 3]), sn: &Surface) -> (Warp, WarpReport) {
    let uni = Warp::uniform(frame);
    let mut wishes: [Vec<Vec<f64>>; 3] = std::array::from_fn(|a| vec![Vec::new(); uni.planes[a].len()]);
    for (q, dir) in boundary_faces_lattice(h0) {
        let axis = (dir / 2) as usize;
        let sign = if dir % 2 == 0 { 1.0 } else { -1.0 };
        let k = h0.node_lattice[q[0] as usize][axis] as usize;
        let c = scale(q.iter().fold([0.0; 3], |acc, &v| add(acc, uni.apply(h0.mesh.nodes[v as usize]))), 0.25);
        let hits = sn.axis_line_hits(c, axis, 4.0);
        let best = hits
            .into_iter()
            .filter(|(_, t)| sn.normal(*t)[axis] * sign > 0.3)
            .min_by(|a, b| a.0.abs().total_cmp(&b.0.abs()));
        if let Some((t, _)) = best {
            wishes[axis][k].push(c[axis] + t);
        }
    }
    let mut rep = WarpReport::default();
    let mut planes = uni.planes.clone();
    for a in 0..3 {
        let (k_lo, k_hi) = (3 * box_cells.0[a], 3 * box_cells.1[a]);
        let def = &uni.planes[a];
        let mut fixed = vec![false; def.len()];
        fixed[k_lo] = true;
        fixed[k_hi] = true;
        for k in k_lo + 1..k_hi {
            let w = &mut wishes[a][k];
            if w.is_empty() {
                continue;
            }
            w.sort_by(|x, y| x.total_cmp(y));
            planes[a][k] = w[w.len() / 2];
            fixed[k] = true;
            rep.planes_fitted += 1;
        }
        // interpolate the free planes between fixed ones
        let mut k = k_lo;
        while k < k_hi {
            let mut k1 = k + 1;
            while !fixed[k1] {
                k1 += 1;
            }
            for j in k + 1..k1 {
                let f = (def[j] - def[k]) / (def[k1] - def[k]);
                planes[a][j] = planes[a][k] + f * (planes[a][k1] - planes[a][k]);
            }
            k = k1;
        }
        // keep the order with a minimum gap
        let gap = 0.25 * (def[1] - def[0]);
        for k in k_lo + 1..k_hi {
            planes[a][k] = planes[a][k].max(planes[a][k - 1] + gap);
        }
        for k in (k_lo + 1..k_hi).rev() {
            planes[a][k] = planes[a][k].min(planes[a][k + 1] - gap);
        }
        for k in k_lo..=k_hi {
            rep.max_shift = rep.max_shift.max((planes[a][k] - def[k]).abs());
        }
    }
    (Warp { planes }, rep)
}
