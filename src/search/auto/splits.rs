//! Splits fitted to the part: boxes whose cell boundaries sit where the part's
//! cross-section's outline changes, instead of at equal fractions of its bounding box.
//!
//! A real part's features rarely fall on thirds or halves of its bounding box: a
//! block with a channel across its top has the channel's sides at a quarter and
//! three quarters of its length and its floor at half its height; a rod's eyes end
//! where its shaft begins. Equal cells cut such features in two, and no label of
//! the cells that hold half a feature fits (BENCHMARKS.md "Boxes compared in
//! one length, splits fitted to the part").
//!
//! Along each axis the outline of the temporary volume's section (the bounding
//! rectangle of its majority-filtered voxels) is compared layer by layer
//! ([`section_changes`]). The part's steps,
//! shoulders and floors are where that share peaks. A box with `n` cells along an
//! axis puts its `n - 1` boundaries at the strongest peaks, each cell at least
//! [`MIN_CELL`] of the box long ([`fitted_points`]). The input is then warped,
//! piecewise linearly along each axis, so that those boundaries fall on the equal
//! grid ([`AxisWarp`], [`warp_input`]): every later step (subregions, label
//! ranking, diffusion, verification) sees a part whose features lie on the cell
//! boundaries, on the grid the model was trained on. The hex stage maps the
//! polycube onto the unwarped input and finds the boundaries itself (its plane fit,
//! docs/hex.md).

use super::super::generate::PreparedInput;
use crate::geometry::{Aabb, Alignment, SurfaceSample, TriMesh, VoxelGrid};

/// A layer boundary is a candidate split where the outline changes at least this
/// much across it ([`section_changes`]).
pub const MIN_CHANGE: f64 = 0.1;
/// No fitted cell is shorter than this share of the box along its axis.
pub const MIN_CELL: f64 = 0.15;
/// A fitted box is analysed only when one of its boundaries is at least this
/// share of the box away from the equal split's (nearer, it is the equal box).
pub const MIN_SHIFT: f64 = 0.06;

/// How much the outline of the section changes across each boundary between
/// voxel layers along `axis` of `g`: `(k, change)` for the boundary between layers
/// `k - 1` and `k` (1 <= k < dims), change = 1 - the intersection over the union of
/// the two sections' bounding rectangles. The rectangles, not the sections: a hole
/// or a pocket inside a cell changes the section but not its outline (the walls of
/// a block's three holes are no cell boundaries), a step, a shoulder or a channel
/// across the part changes both.
pub fn section_changes(g: &VoxelGrid, axis: usize) -> Vec<(usize, f64)> {
    let d = g.dims;
    let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
    // per layer: the bounding rectangle [u0, u1) x [v0, v1) of its voxels
    let rect = |a: usize| -> Option<[usize; 4]> {
        let mut r: Option<[usize; 4]> = None;
        for j in 0..d[v] {
            for i in 0..d[u] {
                let mut p = [0usize; 3];
                p[axis] = a;
                p[u] = i;
                p[v] = j;
                if g.occ[g.idx(p[0], p[1], p[2])] {
                    r = Some(match r {
                        None => [i, i + 1, j, j + 1],
                        Some(q) => [q[0].min(i), q[1].max(i + 1), q[2].min(j), q[3].max(j + 1)],
                    });
                }
            }
        }
        r
    };
    let rects: Vec<Option<[usize; 4]>> = (0..d[axis]).map(rect).collect();
    let area = |r: [usize; 4]| ((r[1] - r[0]) * (r[3] - r[2])) as f64;
    (1..d[axis])
        .map(|k| {
            let c = match (rects[k - 1], rects[k]) {
                (None, None) => 0.0,
                (Some(a), Some(b)) => {
                    let w = a[1].min(b[1]).saturating_sub(a[0].max(b[0]));
                    let h = a[3].min(b[3]).saturating_sub(a[2].max(b[2]));
                    let inter = (w * h) as f64;
                    1.0 - inter / (area(a) + area(b) - inter)
                }
                _ => 1.0,
            };
            (k, c)
        })
        .collect()
}

/// The `n - 1` inner boundaries of `n` cells along an axis from `lo` to `hi`
/// fitted to the section changes `changes` (positions in the axis's coordinate):
/// the strongest local peaks of at least [`MIN_CHANGE`], each cell at least
/// [`MIN_CELL`] of the length; None when fewer such peaks exist, or when `n` is 1.
pub fn fitted_points(changes: &[(f64, f64)], lo: f64, hi: f64, n: usize) -> Option<Vec<f64>> {
    if n < 2 {
        return None;
    }
    let len = hi - lo;
    let min = MIN_CELL * len;
    // local peaks: not below either neighbour (a plateau keeps its first layer)
    let mut peaks: Vec<(f64, f64)> = (0..changes.len())
        .filter(|&i| {
            let c = changes[i].1;
            c >= MIN_CHANGE && (i == 0 || changes[i - 1].1 < c) && (i + 1 == changes.len() || changes[i + 1].1 <= c)
        })
        .map(|i| changes[i])
        .filter(|&(x, _)| x - lo >= min && hi - x >= min)
        .collect();
    peaks.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.total_cmp(&b.0)));
    let mut taken: Vec<f64> = Vec::new();
    for (x, _) in peaks {
        if taken.iter().all(|t| (t - x).abs() >= min) {
            taken.push(x);
            if taken.len() == n - 1 {
                break;
            }
        }
    }
    if taken.len() < n - 1 {
        return None;
    }
    taken.sort_by(f64::total_cmp);
    Some(taken)
}

/// The [`section_changes`] of the grid `g` (voxels of edge `h` from `origin`)
/// along each axis, at their positions in the axis's coordinate: measured once
/// and shared by every box.
pub fn outline_changes(g: &VoxelGrid, origin: [f64; 3], h: f64) -> [Vec<(f64, f64)>; 3] {
    std::array::from_fn(|a| section_changes(g, a).into_iter().map(|(k, c)| (origin[a] + k as f64 * h, c)).collect())
}

/// The fitted boundaries of a box with `dims` cells in the bounding box `bb`,
/// from the outline's changes along each axis ([`outline_changes`]), per axis:
/// the fitted inner points where [`fitted_points`] finds them, else the equal
/// ones; None when no axis is fitted at least [`MIN_SHIFT`] away from the equal
/// split.
pub fn fitted_box(changes: &[Vec<(f64, f64)>; 3], bb: &Aabb, dims: [usize; 3]) -> Option<[Vec<f64>; 3]> {
    let mut shifted = false;
    let inner: [Vec<f64>; 3] = std::array::from_fn(|a| {
        let (lo, hi) = (bb.min[a], bb.max[a]);
        let equal: Vec<f64> = (1..dims[a]).map(|k| lo + (hi - lo) * k as f64 / dims[a] as f64).collect();
        match fitted_points(&changes[a], lo, hi, dims[a]) {
            Some(p) => {
                if p.iter().zip(&equal).any(|(x, e)| (x - e).abs() >= MIN_SHIFT * (hi - lo)) {
                    shifted = true;
                }
                p
            }
            None => equal,
        }
    });
    shifted.then_some(inner)
}

/// A piecewise linear map of each axis that takes the fitted boundaries to the
/// equal ones (the bounding box's ends stay).
#[derive(Debug, Clone, PartialEq)]
pub struct AxisWarp {
    /// Per axis, the breakpoints (from, to): the box's ends and its inner boundaries.
    pub knots: [Vec<(f64, f64)>; 3],
}

impl AxisWarp {
    /// The warp of the box `bb` whose inner boundaries `inner` go to equal shares.
    pub fn new(bb: &Aabb, inner: &[Vec<f64>; 3]) -> AxisWarp {
        AxisWarp {
            knots: std::array::from_fn(|a| {
                let (lo, hi) = (bb.min[a], bb.max[a]);
                let n = inner[a].len() + 1;
                let mut k = vec![(lo, lo)];
                k.extend(inner[a].iter().enumerate().map(|(i, &x)| (x, lo + (hi - lo) * (i + 1) as f64 / n as f64)));
                k.push((hi, hi));
                k
            }),
        }
    }

    /// The splitting ratios of the fitted boundaries (cell lengths along each axis).
    pub fn ratios(&self) -> super::SplitRatios {
        let r = |a: usize| -> Vec<f64> { self.knots[a].windows(2).map(|w| w[1].0 - w[0].0).collect() };
        super::SplitRatios { x: r(0), y: r(1), z: r(2) }
    }

    /// The warped point (outside the box, the end pieces extended).
    pub fn apply(&self, p: [f64; 3]) -> [f64; 3] {
        std::array::from_fn(|a| {
            let k = &self.knots[a];
            let i = k.windows(2).position(|w| p[a] <= w[1].0).unwrap_or(k.len() - 2);
            let (x0, y0) = k[i];
            let (x1, y1) = k[i + 1];
            if x1 > x0 {
                y0 + (p[a] - x0) * (y1 - y0) / (x1 - x0)
            } else {
                y0
            }
        })
    }
}

/// The prepared input warped by `w`: its mesh and its samples (each sample at the
/// warped point; a sample's triangle and barycentric coordinates still name where
/// on the input it was drawn). The alignment's transform is kept: it maps user
/// coordinates into the unwarped aligned frame, which is the frame the result's
/// polycube is placed in. The area is the warped mesh's.
pub fn warp_input(input: &PreparedInput, w: &AxisWarp) -> PreparedInput {
    let a = &input.alignment;
    let mesh = TriMesh { vertices: a.mesh.vertices.iter().map(|p| w.apply(*p)).collect(), triangles: a.mesh.triangles.clone() };
    let area = crate::geometry::surface_moments(&mesh).area;
    let samples = input.samples.iter().map(|s| SurfaceSample { point: w.apply(s.point), ..*s }).collect();
    let alignment = Alignment { mesh, transform: a.transform, variances: a.variances, third_moments: a.third_moments };
    PreparedInput { alignment, frame: input.frame, samples, area }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A block with a channel across its top: `nx` x 4 x `nz` voxels, empty
    /// where x is in [x0, x1) and z >= zc.
    fn channel_block(nx: usize, nz: usize, x0: usize, x1: usize, zc: usize) -> VoxelGrid {
        let mut g = VoxelGrid::empty([nx, 4, nz]);
        for z in 0..nz {
            for y in 0..4 {
                for x in 0..nx {
                    let i = g.idx(x, y, z);
                    g.occ[i] = !((x0..x1).contains(&x) && z >= zc);
                }
            }
        }
        g
    }

    #[test]
    fn a_channel_s_sides_and_floor_are_the_fitted_boundaries() {
        // 40 voxels long, the channel from 10 to 30 (a quarter and three quarters),
        // its floor at half of 20 voxels' height
        let g = channel_block(40, 20, 10, 30, 10);
        let bb = Aabb { min: [0.0; 3], max: [40.0, 4.0, 20.0] };
        let inner = fitted_box(&outline_changes(&g, [0.0; 3], 1.0), &bb, [3, 1, 2]).expect("fitted");
        assert_eq!(inner[0], vec![10.0, 30.0]);
        assert!(inner[1].is_empty());
        assert_eq!(inner[2], vec![10.0]);
        let w = AxisWarp::new(&bb, &inner);
        let r = w.ratios();
        assert_eq!(r.x, vec![10.0, 20.0, 10.0]);
        // the channel's sides go to the thirds, its floor stays at the half
        let p = w.apply([10.0, 2.0, 10.0]);
        assert!((p[0] - 40.0 / 3.0).abs() < 1e-12 && (p[1] - 2.0).abs() < 1e-12 && (p[2] - 10.0).abs() < 1e-12);
        assert!((w.apply([30.0, 0.0, 0.0])[0] - 80.0 / 3.0).abs() < 1e-12);
        assert_eq!(w.apply([40.0, 4.0, 20.0]), [40.0, 4.0, 20.0]);
    }

    #[test]
    fn a_box_whose_features_lie_on_the_equal_split_is_not_fitted() {
        // an L whose step is at the half: the equal box already has it
        let g = channel_block(40, 20, 20, 40, 10);
        let bb = Aabb { min: [0.0; 3], max: [40.0, 4.0, 20.0] };
        assert!(fitted_box(&outline_changes(&g, [0.0; 3], 1.0), &bb, [2, 1, 2]).is_none());
        // a uniform block has no peak at all
        let full = channel_block(40, 20, 0, 0, 0);
        assert!(fitted_box(&outline_changes(&full, [0.0; 3], 1.0), &bb, [3, 1, 2]).is_none());
    }

    #[test]
    fn the_walls_of_holes_inside_the_cells_are_no_boundaries() {
        // a bar 42 x 4 x 10 voxels with three square holes along Y, off the thirds
        let mut g = VoxelGrid::empty([42, 4, 10]);
        for z in 0..10 {
            for y in 0..4 {
                for x in 0..42 {
                    let hole = [(3, 9), (18, 24), (33, 39)].iter().any(|&(a, b)| (a..b).contains(&x)) && (3..7).contains(&z);
                    let i = g.idx(x, y, z);
                    g.occ[i] = !hole;
                }
            }
        }
        let bb = Aabb { min: [0.0; 3], max: [42.0, 4.0, 10.0] };
        assert!(section_changes(&g, 0).iter().all(|&(_, c)| c == 0.0));
        assert!(fitted_box(&outline_changes(&g, [0.0; 3], 1.0), &bb, [3, 1, 1]).is_none());
    }

    #[test]
    fn fitted_cells_are_never_shorter_than_the_minimum() {
        // a step one voxel from the end is no boundary
        let g = channel_block(40, 20, 1, 40, 10);
        let bb = Aabb { min: [0.0; 3], max: [40.0, 4.0, 20.0] };
        let ch: Vec<(f64, f64)> = section_changes(&g, 0).into_iter().map(|(k, c)| (k as f64, c)).collect();
        assert_eq!(fitted_points(&ch, 0.0, 40.0, 2), None);
        assert!(fitted_box(&outline_changes(&g, [0.0; 3], 1.0), &bb, [2, 1, 1]).is_none());
    }
}
