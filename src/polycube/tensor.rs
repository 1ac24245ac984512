//! The 64 x 96 x 3 point tensor (channels first in code: [3, 64, 96]).
//!
//! 512 points per cell; cell n = 6k + 3j + i sits in block row r = 2k + j and
//! block column i; each block is 16 x 32, filled row-major with the cell's points
//! sorted lexicographically by (x, y, z). Null cells hold 512 copies of (0, 0, 0).

use super::primitive::{cell_coords, NUM_CELLS};

pub const POINTS_PER_CELL: usize = 512;
pub const NUM_POINTS: usize = POINTS_PER_CELL * NUM_CELLS;
pub const TENSOR_H: usize = 64;
pub const TENSOR_W: usize = 96;
pub const BLOCK_H: usize = 16;
pub const BLOCK_W: usize = 32;
/// Number of f32 values in one tensor (3 x 64 x 96).
pub const TENSOR_LEN: usize = 3 * TENSOR_H * TENSOR_W;

/// (row, column) in the 64 x 96 image of point `p` (0..512) of cell `n`.
#[inline]
pub fn slot(n: usize, p: usize) -> (usize, usize) {
    let [i, j, k] = cell_coords(n);
    let r = 2 * k + j;
    (BLOCK_H * r + p / BLOCK_W, BLOCK_W * i + p % BLOCK_W)
}

/// Flat index of channel `c` at (row, col) in a [3, 64, 96] tensor.
#[inline]
pub fn flat(c: usize, row: usize, col: usize) -> usize {
    c * TENSOR_H * TENSOR_W + row * TENSOR_W + col
}

/// Lexicographic (x, y, z) order; returns the permutation that sorts `pts`.
pub fn sort_order(pts: &[[f32; 3]]) -> Vec<usize> {
    let mut idx: Vec<usize> = (0..pts.len()).collect();
    idx.sort_by(|&a, &b| {
        let (p, q) = (pts[a], pts[b]);
        p[0].total_cmp(&q[0]).then(p[1].total_cmp(&q[1])).then(p[2].total_cmp(&q[2])).then(a.cmp(&b))
    });
    idx
}

/// Write per-cell point sets (each exactly 512 points, or empty for a null cell)
/// into a [3, 64, 96] tensor. The points are written in the order given: sort them
/// first with [`sort_order`] (the order is what the correspondence refers to).
pub fn layout(cells: &[Vec<[f32; 3]>]) -> Vec<f32> {
    assert_eq!(cells.len(), NUM_CELLS);
    let mut t = vec![0f32; TENSOR_LEN];
    for (n, pts) in cells.iter().enumerate() {
        if pts.is_empty() {
            continue;
        }
        assert_eq!(pts.len(), POINTS_PER_CELL, "cell {n} must hold {POINTS_PER_CELL} points");
        for (p, x) in pts.iter().enumerate() {
            let (r, c) = slot(n, p);
            for ch in 0..3 {
                t[flat(ch, r, c)] = x[ch];
            }
        }
    }
    t
}

/// Read a [3, 64, 96] tensor back into 12 blocks of 512 points (slot order).
pub fn unlayout(t: &[f32]) -> Vec<Vec<[f32; 3]>> {
    assert_eq!(t.len(), TENSOR_LEN);
    (0..NUM_CELLS)
        .map(|n| {
            (0..POINTS_PER_CELL)
                .map(|p| {
                    let (r, c) = slot(n, p);
                    [t[flat(0, r, c)], t[flat(1, r, c)], t[flat(2, r, c)]]
                })
                .collect()
        })
        .collect()
}

/// Uniform scale + translation between grid units and the model's normalised frame:
/// normalised = (grid - centre) * scale.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct BoxFrame {
    pub centre: [f64; 3],
    pub scale: f64,
}

impl BoxFrame {
    /// The frame that centres the box [lo, hi] (grid units) at the origin with its longest edge 2.
    pub fn for_box(lo: [f64; 3], hi: [f64; 3]) -> Self {
        let ext = [hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]];
        let longest = ext[0].max(ext[1]).max(ext[2]);
        BoxFrame {
            centre: [(lo[0] + hi[0]) / 2.0, (lo[1] + hi[1]) / 2.0, (lo[2] + hi[2]) / 2.0],
            scale: 2.0 / longest,
        }
    }

    pub fn to_normalised(&self, p: [f64; 3]) -> [f64; 3] {
        [
            (p[0] - self.centre[0]) * self.scale,
            (p[1] - self.centre[1]) * self.scale,
            (p[2] - self.centre[2]) * self.scale,
        ]
    }

    pub fn to_grid(&self, q: [f64; 3]) -> [f64; 3] {
        [
            q[0] / self.scale + self.centre[0],
            q[1] / self.scale + self.centre[1],
            q[2] / self.scale + self.centre[2],
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slots_cover_the_image_once() {
        let mut seen = vec![false; TENSOR_H * TENSOR_W];
        for n in 0..NUM_CELLS {
            for p in 0..POINTS_PER_CELL {
                let (r, c) = slot(n, p);
                assert!(!seen[r * TENSOR_W + c]);
                seen[r * TENSOR_W + c] = true;
            }
        }
        assert!(seen.iter().all(|&b| b));
        // Cell 0 top-left, cell 2 top-right block, cell 3 second block row, cell 6 third.
        assert_eq!(slot(0, 0), (0, 0));
        assert_eq!(slot(2, 0), (0, 64));
        assert_eq!(slot(3, 0), (16, 0));
        assert_eq!(slot(6, 33), (33, 1));
        assert_eq!(slot(11, 511), (63, 95));
    }

    #[test]
    fn layout_round_trip() {
        let mut cells: Vec<Vec<[f32; 3]>> = vec![Vec::new(); NUM_CELLS];
        cells[5] = (0..POINTS_PER_CELL).map(|i| [i as f32, 1.0, -(i as f32)]).collect();
        let t = layout(&cells);
        let back = unlayout(&t);
        assert_eq!(back[5], cells[5]);
        assert!(back[0].iter().all(|p| *p == [0.0, 0.0, 0.0]));
        let pts = vec![[1.0, 0.0, 0.0], [0.0, 2.0, 0.0], [0.0, 1.0, 5.0], [0.0, 1.0, 4.0]];
        assert_eq!(sort_order(&pts), vec![3, 2, 1, 0]);
    }
}
