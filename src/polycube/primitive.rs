//! The eleven primitive categories (label 0 = null, 1..10 = solids) on the 3x3x3
//! sub-voxel lattice of a cell, and the G(3x2x2) grid they are placed on.

use crate::error::{Error, Result};

/// Cells along X, Y, Z.
pub const GRID: [usize; 3] = [3, 2, 2];
/// Number of cells in the grid.
pub const NUM_CELLS: usize = 12;
/// Number of per-cell states (null + 10 primitives).
pub const NUM_LABELS: usize = 11;
/// Length of the one-hot context vector.
pub const CONTEXT_DIM: usize = NUM_CELLS * NUM_LABELS;
/// Sub-voxels per cell edge.
pub const SUB: usize = 3;
/// The sub-voxel lattice of the whole grid.
pub const LATTICE: [usize; 3] = [GRID[0] * SUB, GRID[1] * SUB, GRID[2] * SUB];

/// Cell index n = 6k + 3j + i (0-based).
#[inline]
pub fn cell_index(i: usize, j: usize, k: usize) -> usize {
    6 * k + 3 * j + i
}

/// Inverse of [`cell_index`].
#[inline]
pub fn cell_coords(n: usize) -> [usize; 3] {
    [n % 3, (n / 3) % 2, n / 6]
}

/// The primitive categories, in the fixed label order of DESIGN.md.
#[repr(u8)]
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Default)]
pub enum Primitive {
    #[default]
    Null = 0,
    Cube = 1,
    ThcZ = 2,
    ThcX = 3,
    ThcY = 4,
    BhcPz = 5,
    BhcMz = 6,
    BhcPx = 7,
    BhcMx = 8,
    BhcPy = 9,
    BhcMy = 10,
}

/// Broad family of a primitive, used by counts constraints and by genus rules.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Family {
    Null,
    Cube,
    Thc,
    Bhc,
}

impl Primitive {
    pub const ALL: [Primitive; NUM_LABELS] = [
        Primitive::Null,
        Primitive::Cube,
        Primitive::ThcZ,
        Primitive::ThcX,
        Primitive::ThcY,
        Primitive::BhcPz,
        Primitive::BhcMz,
        Primitive::BhcPx,
        Primitive::BhcMx,
        Primitive::BhcPy,
        Primitive::BhcMy,
    ];

    /// The ten solid primitives (labels 1..10).
    pub fn solids() -> impl Iterator<Item = Primitive> {
        Self::ALL[1..].iter().copied()
    }

    pub fn label(self) -> u8 {
        self as u8
    }

    pub fn from_label(label: u8) -> Option<Primitive> {
        Self::ALL.get(label as usize).copied()
    }

    /// Canonical name as used on the command line and in reports.
    pub fn name(self) -> &'static str {
        match self {
            Primitive::Null => "null",
            Primitive::Cube => "cube",
            Primitive::ThcZ => "THC+Z",
            Primitive::ThcX => "THC+X",
            Primitive::ThcY => "THC+Y",
            Primitive::BhcPz => "BHC+Z",
            Primitive::BhcMz => "BHC-Z",
            Primitive::BhcPx => "BHC+X",
            Primitive::BhcMx => "BHC-X",
            Primitive::BhcPy => "BHC+Y",
            Primitive::BhcMy => "BHC-Y",
        }
    }

    /// Parse a name (case-insensitive, `THC+Z`, `thcz`, `bhc-x` ...) or an integer label.
    pub fn parse(s: &str) -> Result<Primitive> {
        let t = s.trim();
        if let Ok(v) = t.parse::<i64>() {
            return u8::try_from(v).ok().and_then(Primitive::from_label).ok_or_else(|| {
                Error::InvalidContext(format!("label {v} is out of range 0..10"))
            });
        }
        let norm: String = t.to_ascii_lowercase().chars().filter(|c| !c.is_whitespace() && *c != '_').collect();
        let p = match norm.as_str() {
            "null" | "empty" | "none" => Primitive::Null,
            "cube" => Primitive::Cube,
            "thc+z" | "thcz" => Primitive::ThcZ,
            "thc+x" | "thcx" => Primitive::ThcX,
            "thc+y" | "thcy" => Primitive::ThcY,
            "bhc+z" | "bhcpz" => Primitive::BhcPz,
            "bhc-z" | "bhcmz" => Primitive::BhcMz,
            "bhc+x" | "bhcpx" => Primitive::BhcPx,
            "bhc-x" | "bhcmx" => Primitive::BhcMx,
            "bhc+y" | "bhcpy" => Primitive::BhcPy,
            "bhc-y" | "bhcmy" => Primitive::BhcMy,
            _ => {
                return Err(Error::InvalidContext(format!(
                    "unknown primitive name '{t}' (expected 0..10 or one of null, cube, THC+Z, THC+X, THC+Y, BHC+Z, BHC-Z, BHC+X, BHC-X, BHC+Y, BHC-Y)"
                )))
            }
        };
        Ok(p)
    }

    pub fn family(self) -> Family {
        match self {
            Primitive::Null => Family::Null,
            Primitive::Cube => Family::Cube,
            Primitive::ThcZ | Primitive::ThcX | Primitive::ThcY => Family::Thc,
            _ => Family::Bhc,
        }
    }

    /// Sub-voxels (a, b, c) removed from the 3x3x3 lattice of the cell.
    pub fn removed(self) -> &'static [[usize; 3]] {
        match self {
            Primitive::Null => &[],
            Primitive::Cube => &[],
            Primitive::ThcZ => &[[1, 1, 0], [1, 1, 1], [1, 1, 2]],
            Primitive::ThcX => &[[0, 1, 1], [1, 1, 1], [2, 1, 1]],
            Primitive::ThcY => &[[1, 0, 1], [1, 1, 1], [1, 2, 1]],
            Primitive::BhcPz => &[[1, 1, 1], [1, 1, 2]],
            Primitive::BhcMz => &[[1, 1, 0], [1, 1, 1]],
            Primitive::BhcPx => &[[1, 1, 1], [2, 1, 1]],
            Primitive::BhcMx => &[[0, 1, 1], [1, 1, 1]],
            Primitive::BhcPy => &[[1, 1, 1], [1, 2, 1]],
            Primitive::BhcMy => &[[1, 0, 1], [1, 1, 1]],
        }
    }

    /// Occupancy of the 27 sub-voxels, index a + 3b + 9c.
    pub fn subvoxels(self) -> [bool; 27] {
        let mut occ = [self != Primitive::Null; 27];
        for r in self.removed() {
            occ[r[0] + 3 * r[1] + 9 * r[2]] = false;
        }
        occ
    }

    /// Genus of the standalone primitive (0 for cube and BHC, 1 for THC).
    pub fn standalone_genus(self) -> i64 {
        if self.family() == Family::Thc {
            1
        } else {
            0
        }
    }

    /// The hole axis (0 = X, 1 = Y, 2 = Z) and, for a BHC, the side of its opening (+1 / -1).
    pub fn hole(self) -> Option<(usize, i32)> {
        match self {
            Primitive::ThcX => Some((0, 0)),
            Primitive::ThcY => Some((1, 0)),
            Primitive::ThcZ => Some((2, 0)),
            Primitive::BhcPx => Some((0, 1)),
            Primitive::BhcMx => Some((0, -1)),
            Primitive::BhcPy => Some((1, 1)),
            Primitive::BhcMy => Some((1, -1)),
            Primitive::BhcPz => Some((2, 1)),
            Primitive::BhcMz => Some((2, -1)),
            _ => None,
        }
    }

    /// Build a primitive from family, hole axis and opening side (inverse of `hole`).
    pub fn from_hole(family: Family, axis: usize, side: i32) -> Primitive {
        match (family, axis, side) {
            (Family::Null, _, _) => Primitive::Null,
            (Family::Cube, _, _) => Primitive::Cube,
            (Family::Thc, 0, _) => Primitive::ThcX,
            (Family::Thc, 1, _) => Primitive::ThcY,
            (Family::Thc, _, _) => Primitive::ThcZ,
            (Family::Bhc, 0, s) if s > 0 => Primitive::BhcPx,
            (Family::Bhc, 0, _) => Primitive::BhcMx,
            (Family::Bhc, 1, s) if s > 0 => Primitive::BhcPy,
            (Family::Bhc, 1, _) => Primitive::BhcMy,
            (Family::Bhc, _, s) if s > 0 => Primitive::BhcPz,
            (Family::Bhc, _, _) => Primitive::BhcMz,
        }
    }
}

impl std::fmt::Display for Primitive {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn labels_names_round_trip() {
        for p in Primitive::ALL {
            assert_eq!(Primitive::from_label(p.label()), Some(p));
            assert_eq!(Primitive::parse(p.name()).unwrap(), p);
            assert_eq!(Primitive::parse(&p.label().to_string()).unwrap(), p);
            if let Some((axis, side)) = p.hole() {
                assert_eq!(Primitive::from_hole(p.family(), axis, side), p);
            }
        }
        assert!(Primitive::parse("11").is_err());
        assert!(Primitive::parse("-1").is_err());
        assert!(Primitive::parse("sphere").is_err());
    }

    #[test]
    fn cell_order() {
        for n in 0..NUM_CELLS {
            let [i, j, k] = cell_coords(n);
            assert_eq!(cell_index(i, j, k), n);
        }
        assert_eq!(cell_index(2, 1, 1), 11);
        assert_eq!(cell_coords(4), [1, 1, 0]);
    }

    #[test]
    fn subvoxel_counts() {
        assert_eq!(Primitive::Cube.subvoxels().iter().filter(|&&b| b).count(), 27);
        assert_eq!(Primitive::ThcZ.subvoxels().iter().filter(|&&b| b).count(), 24);
        assert_eq!(Primitive::BhcMy.subvoxels().iter().filter(|&&b| b).count(), 25);
        assert_eq!(Primitive::Null.subvoxels().iter().filter(|&&b| b).count(), 0);
    }
}
