//! Contexts: the 12-cell labelling of the G(3x2x2) grid, its 132-d one-hot encoding,
//! the expansion of partial constraints (counts + spatial arrangement) into every
//! valid context that satisfies them, and a context's normalised frame
//! ([`context_frame`]).

use crate::error::{Error, Result};
use crate::geometry::VoxelGrid;
use crate::polycube::assembly::{assemble, check, occupied_cell_box, Validity};
use crate::polycube::primitive::{cell_coords, Family, Primitive, CONTEXT_DIM, NUM_CELLS, NUM_LABELS};
use crate::polycube::tensor::BoxFrame;
use rayon::prelude::*;
use std::sync::atomic::{AtomicUsize, Ordering};
use serde::{Deserialize, Serialize};

/// A labelling of the 12 cells (cell index order n = 6k + 3j + i).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Default)]
pub struct Context {
    pub labels: [Primitive; NUM_CELLS],
}

impl Context {
    pub fn new(labels: [Primitive; NUM_CELLS]) -> Self {
        Context { labels }
    }

    /// From 12 integer labels; a wrong length or an out-of-range label names the cell.
    pub fn from_labels(labels: &[i64]) -> Result<Self> {
        if labels.len() != NUM_CELLS {
            return Err(Error::InvalidContext(format!(
                "a context has {NUM_CELLS} labels (one per cell), got {}",
                labels.len()
            )));
        }
        let mut out = [Primitive::Null; NUM_CELLS];
        for (n, &l) in labels.iter().enumerate() {
            out[n] = u8::try_from(l).ok().and_then(Primitive::from_label).ok_or_else(|| {
                Error::InvalidContext(format!("cell {n} {:?}: label {l} is out of range 0..10", cell_coords(n)))
            })?;
        }
        Ok(Context { labels: out })
    }

    /// Parse "1,0,THC+Z,..." (12 comma-separated integers or names).
    pub fn parse(s: &str) -> Result<Self> {
        let parts: Vec<&str> = s.split(',').collect();
        if parts.len() != NUM_CELLS {
            return Err(Error::InvalidContext(format!(
                "expected {NUM_CELLS} comma-separated labels (one per cell, in cell-index order), got {}",
                parts.len()
            )));
        }
        let mut out = [Primitive::Null; NUM_CELLS];
        for (n, p) in parts.iter().enumerate() {
            out[n] = Primitive::parse(p).map_err(|e| match e {
                Error::InvalidContext(m) => Error::InvalidContext(format!("cell {n} {:?}: {m}", cell_coords(n))),
                other => other,
            })?;
        }
        Ok(Context { labels: out })
    }

    /// Decode one 132-vector. Every cell block must be exactly one-hot (entries 0 or 1
    /// within 1e-6, exactly one 1).
    pub fn from_one_hot(v: &[f32]) -> Result<Self> {
        if v.len() != CONTEXT_DIM {
            return Err(Error::InvalidContext(format!(
                "a one-hot context has {CONTEXT_DIM} entries (12 cells x 11 states), got {}",
                v.len()
            )));
        }
        let mut out = [Primitive::Null; NUM_CELLS];
        for n in 0..NUM_CELLS {
            let block = &v[n * NUM_LABELS..(n + 1) * NUM_LABELS];
            let mut hot = None;
            for (s, &x) in block.iter().enumerate() {
                if !x.is_finite() {
                    return Err(Error::InvalidContext(format!(
                        "cell {n} {:?}: entry {s} is not a finite number",
                        cell_coords(n)
                    )));
                }
                if (x - 1.0).abs() <= 1e-6 {
                    if hot.is_some() {
                        return Err(Error::InvalidContext(format!(
                            "cell {n} {:?}: more than one state is set (entries {} and {s})",
                            cell_coords(n),
                            hot.unwrap()
                        )));
                    }
                    hot = Some(s);
                } else if x.abs() > 1e-6 {
                    return Err(Error::InvalidContext(format!(
                        "cell {n} {:?}: entry {s} is {x}, not 0 or 1 (the vector is not one-hot)",
                        cell_coords(n)
                    )));
                }
            }
            let s = hot.ok_or_else(|| {
                Error::InvalidContext(format!("cell {n} {:?}: no state is set (all 11 entries are 0)", cell_coords(n)))
            })?;
            out[n] = Primitive::ALL[s];
        }
        Ok(Context { labels: out })
    }

    /// Decode an n x 132 stack.
    pub fn batch_from_one_hot(v: &[f32]) -> Result<Vec<Self>> {
        if v.is_empty() || v.len() % CONTEXT_DIM != 0 {
            return Err(Error::InvalidContext(format!(
                "a stack of contexts has a multiple of {CONTEXT_DIM} entries, got {}",
                v.len()
            )));
        }
        v.chunks(CONTEXT_DIM)
            .enumerate()
            .map(|(i, c)| {
                Context::from_one_hot(c).map_err(|e| match e {
                    Error::InvalidContext(m) => Error::InvalidContext(format!("context {i}: {m}")),
                    o => o,
                })
            })
            .collect()
    }

    pub fn one_hot(&self) -> [f32; CONTEXT_DIM] {
        let mut v = [0f32; CONTEXT_DIM];
        for (n, p) in self.labels.iter().enumerate() {
            v[n * NUM_LABELS + p.label() as usize] = 1.0;
        }
        v
    }

    /// The 132-vector with the labels withheld: null cells keep their null entry,
    /// every occupied cell's row is all zeros ("occupied, label unknown"). The
    /// unconditional input of classifier-free guidance (label dropout in training,
    /// `SamplerOptions::guidance` in sampling).
    pub fn one_hot_unlabelled(&self) -> [f32; CONTEXT_DIM] {
        let mut v = self.one_hot();
        for n in self.occupied() {
            v[n * NUM_LABELS..(n + 1) * NUM_LABELS].iter_mut().for_each(|x| *x = 0.0);
        }
        v
    }

    pub fn label_values(&self) -> [u8; NUM_CELLS] {
        self.labels.map(|p| p.label())
    }

    /// Names, comma-separated (the command-line form).
    pub fn names(&self) -> String {
        self.labels.iter().map(|p| p.name()).collect::<Vec<_>>().join(",")
    }

    /// The occupied cells for a reader: each label with its cell's grid position
    /// (x, y, z), e.g. "THC+Z at (0,0,0)" or "cube at (0,0,0), BHC+Z at (1,0,0)";
    /// "empty" for no occupied cell.
    pub fn describe(&self) -> String {
        let v: Vec<String> = self
            .occupied()
            .map(|n| {
                let c = cell_coords(n);
                format!("{} at ({},{},{})", self.labels[n].name(), c[0], c[1], c[2])
            })
            .collect();
        if v.is_empty() {
            "empty".into()
        } else {
            v.join(", ")
        }
    }

    pub fn occupied(&self) -> impl Iterator<Item = usize> + '_ {
        (0..NUM_CELLS).filter(move |&n| self.labels[n] != Primitive::Null)
    }

    pub fn occupancy_mask(&self) -> u16 {
        self.occupied().fold(0u16, |m, n| m | (1 << n))
    }

    pub fn assemble(&self) -> VoxelGrid {
        assemble(&self.labels)
    }

    /// Validity and genus of the assembled solid.
    pub fn validity(&self) -> Validity {
        check(&self.assemble())
    }

    /// The same assembly turned by `r` (new axis `a` = sign * old axis `perm[a]`)
    /// and moved to the grid's first cell: cells move with the rotation and each
    /// label's hole axis and opening side turn with it. `None` when the rotated
    /// occupied box does not fit the 3 x 2 x 2 grid, or nothing is occupied.
    pub fn rotated(&self, r: crate::polycube::orientation::AxisRotation) -> Option<Context> {
        let (lo, hi) = crate::polycube::assembly::occupied_cell_box(&self.labels)?;
        let d: [usize; 3] = std::array::from_fn(|a| hi[a] - lo[a]);
        let grid = [3usize, 2, 2];
        if (0..3).any(|k| d[r.perm[k]] > grid[k]) {
            return None;
        }
        let mut out = [Primitive::Null; NUM_CELLS];
        for n in self.occupied() {
            let c = cell_coords(n);
            let old: [usize; 3] = std::array::from_fn(|a| c[a] - lo[a]);
            let new: [usize; 3] = std::array::from_fn(|k| if r.sign[k] > 0 { old[r.perm[k]] } else { d[r.perm[k]] - 1 - old[r.perm[k]] });
            let p = self.labels[n];
            let label = match p.hole() {
                None => p,
                Some((axis, side)) => {
                    let k = (0..3).find(|&k| r.perm[k] == axis).expect("a permutation");
                    Primitive::from_hole(p.family(), k, side * r.sign[k] as i32)
                }
            };
            out[crate::polycube::primitive::cell_index(new[0], new[1], new[2])] = label;
        }
        Some(Context::new(out))
    }

    /// Every distinct placement of this assembly at the grid's first cell under the
    /// 24 proper rotations that fits the grid (each congruent to `self`).
    pub fn rotations(&self) -> Vec<(crate::polycube::orientation::AxisRotation, Context)> {
        let mut v: Vec<(crate::polycube::orientation::AxisRotation, Context)> = Vec::new();
        for r in crate::polycube::orientation::rotations() {
            if let Some(c) = self.rotated(*r) {
                if !v.iter().any(|(_, x)| *x == c) {
                    v.push((*r, c));
                }
            }
        }
        v
    }
}

impl std::fmt::Display for Context {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.names())
    }
}

/// Partial constraints (the paper's "high-level" user input): counts per category
/// and a spatial arrangement. Unset counts are free.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Constraints {
    /// Number-Cube.
    pub cube: Option<usize>,
    /// Number-THC (any orientation).
    pub thc: Option<usize>,
    /// Number-BHC (any orientation).
    pub bhc: Option<usize>,
    /// Optional exact counts per primitive name (e.g. {"THC+Z": 1}); they refine the family counts.
    pub labels: std::collections::BTreeMap<String, usize>,
    /// Cells that may be occupied (cell indices); default: all.
    pub allowed: Option<Vec<usize>>,
    /// Cells that must be occupied; `allowed == required` is an exact occupancy mask.
    pub required: Vec<usize>,
    /// Keep only contexts whose assembly has this genus.
    pub genus: Option<i64>,
}

impl Default for Constraints {
    fn default() -> Self {
        Constraints { cube: None, thc: None, bhc: None, labels: Default::default(), allowed: None, required: vec![], genus: None }
    }
}

impl Constraints {
    /// An exact occupancy mask given as 12 characters '0'/'1' in cell-index order.
    pub fn with_mask(mut self, mask: &str) -> Result<Self> {
        let cells: Vec<usize> = mask
            .chars()
            .enumerate()
            .filter_map(|(i, c)| (c == '1').then_some(i))
            .collect();
        if mask.len() != NUM_CELLS || mask.chars().any(|c| c != '0' && c != '1') {
            return Err(Error::InvalidArgument(format!(
                "an occupancy mask is 12 characters 0/1 in cell-index order, got '{mask}'"
            )));
        }
        self.allowed = Some(cells.clone());
        self.required = cells;
        Ok(self)
    }

    fn per_label(&self) -> Result<[Option<usize>; NUM_LABELS]> {
        let mut out = [None; NUM_LABELS];
        for (name, &c) in &self.labels {
            let p = Primitive::parse(name).map_err(|e| Error::InvalidArgument(format!("constraints: {e}")))?;
            if p == Primitive::Null {
                return Err(Error::InvalidArgument("constraints: counts of 'null' are not allowed; use allowed/required cells".into()));
            }
            out[p.label() as usize] = Some(c);
        }
        Ok(out)
    }

    fn masks(&self) -> Result<(u16, u16)> {
        let mut allowed = 0u16;
        match &self.allowed {
            None => allowed = 0x0fff,
            Some(v) => {
                for &n in v {
                    if n >= NUM_CELLS {
                        return Err(Error::InvalidArgument(format!("constraints: allowed cell {n} is out of range 0..11")));
                    }
                    allowed |= 1 << n;
                }
            }
        }
        let mut required = 0u16;
        for &n in &self.required {
            if n >= NUM_CELLS {
                return Err(Error::InvalidArgument(format!("constraints: required cell {n} is out of range 0..11")));
            }
            required |= 1 << n;
        }
        if required & !allowed != 0 {
            return Err(Error::InvalidArgument("constraints: a required cell is not among the allowed cells".into()));
        }
        Ok((allowed, required))
    }

    /// Every valid context satisfying the constraints, sorted and deduplicated.
    pub fn enumerate(&self) -> Result<Vec<Context>> {
        let (allowed, required) = self.masks()?;
        let per_label = self.per_label()?;
        let fam_count = [None, self.cube, self.thc, self.bhc];
        // Label-level counts must be consistent with family totals.
        for (fi, fam) in [Family::Cube, Family::Thc, Family::Bhc].iter().enumerate() {
            let fixed: usize = Primitive::solids().filter(|p| p.family() == *fam).filter_map(|p| per_label[p.label() as usize]).sum();
            if let Some(total) = fam_count[fi + 1] {
                if fixed > total {
                    return Err(Error::InvalidArgument(format!(
                        "constraints: the per-orientation counts of {:?} add up to {fixed}, more than its total {total}",
                        fam
                    )));
                }
            }
        }
        let total = match (self.cube, self.thc, self.bhc) {
            (Some(a), Some(b), Some(c)) => Some(a + b + c),
            _ => None,
        };
        let valid_occ = valid_cube_occupancies();
        let masks: Vec<u16> = (1u16..4096)
            .filter(|&m| m & !allowed == 0 && m & required == required)
            .filter(|&m| total.is_none_or(|t| m.count_ones() as usize == t))
            .filter(|&m| valid_occ[m as usize])
            .collect();
        let genus = self.genus;
        let budget = Budget { checked: AtomicUsize::new(0), limit: MAX_ASSIGNMENTS };
        let mut out: Vec<Context> = masks
            .par_iter()
            .flat_map_iter(|&mask| {
                let cells: Vec<usize> = (0..NUM_CELLS).filter(|&n| mask >> n & 1 == 1).collect();
                let mut found = Vec::new();
                let mut labels = [Primitive::Null; NUM_CELLS];
                let mut fam_used = [0usize; 4];
                let mut lab_used = [0usize; NUM_LABELS];
                let limits = Limits { fam_count: &fam_count, per_label: &per_label, genus, budget: &budget };
                assign(&cells, 0, &mut labels, &mut fam_used, &mut lab_used, &limits, &mut found);
                found
            })
            .collect();
        let checked = budget.checked.load(Ordering::Relaxed);
        if checked > budget.limit {
            let free = masks.iter().map(|m| m.count_ones()).max().unwrap_or(0);
            return Err(Error::InvalidArgument(format!(
                "constraints: more than {} label assignments to check (up to {free} occupied cells with free labels); \
                 fix the counts per category or per label, the allowed cells or the genus to narrow the search",
                budget.limit
            )));
        }
        out.sort();
        out.dedup();
        Ok(out)
    }
}

/// Most complete label assignments [`Constraints::enumerate`] checks before it refuses
/// the constraints as too loose (each check assembles the solid and computes its
/// genus: the refusal of the loosest constraints took 17.8 s on the development
/// machine with a training job on the other core). Without the bound, free counts
/// over many cells ask for up to 10^12 assignments and the call would never return.
pub const MAX_ASSIGNMENTS: usize = 100_000;

struct Budget {
    checked: AtomicUsize,
    limit: usize,
}

struct Limits<'a> {
    fam_count: &'a [Option<usize>; 4],
    per_label: &'a [Option<usize>; NUM_LABELS],
    genus: Option<i64>,
    budget: &'a Budget,
}

fn assign(
    cells: &[usize],
    pos: usize,
    labels: &mut [Primitive; NUM_CELLS],
    fam_used: &mut [usize; 4],
    lab_used: &mut [usize; NUM_LABELS],
    lim: &Limits,
    out: &mut Vec<Context>,
) {
    let (fam_count, per_label, genus) = (lim.fam_count, lim.per_label, lim.genus);
    if lim.budget.checked.load(Ordering::Relaxed) > lim.budget.limit {
        return;
    }
    let remaining = cells.len() - pos;
    // Prune: family counts still reachable?
    let mut need = 0;
    for f in 1..4 {
        if let Some(c) = fam_count[f] {
            if fam_used[f] > c {
                return;
            }
            need += c - fam_used[f];
        }
    }
    for l in 1..NUM_LABELS {
        if let Some(c) = per_label[l] {
            if lab_used[l] > c {
                return;
            }
        }
    }
    if need > remaining {
        return;
    }
    if pos == cells.len() {
        for f in 1..4 {
            if fam_count[f].is_some_and(|c| fam_used[f] != c) {
                return;
            }
        }
        for l in 1..NUM_LABELS {
            if per_label[l].is_some_and(|c| lab_used[l] != c) {
                return;
            }
        }
        if lim.budget.checked.fetch_add(1, Ordering::Relaxed) >= lim.budget.limit {
            lim.budget.checked.store(lim.budget.limit + 1, Ordering::Relaxed);
            return;
        }
        let ctx = Context { labels: *labels };
        let v = ctx.validity();
        if v.valid && genus.is_none_or(|g| v.genus == Some(g)) {
            out.push(ctx);
        }
        return;
    }
    let n = cells[pos];
    for p in Primitive::solids() {
        let f = match p.family() {
            Family::Cube => 1,
            Family::Thc => 2,
            Family::Bhc => 3,
            Family::Null => 0,
        };
        labels[n] = p;
        fam_used[f] += 1;
        lab_used[p.label() as usize] += 1;
        assign(cells, pos + 1, labels, fam_used, lab_used, lim, out);
        fam_used[f] -= 1;
        lab_used[p.label() as usize] -= 1;
    }
    labels[n] = Primitive::Null;
}

/// For each of the 4096 cell occupancy masks: is the all-cube assembly valid?
/// Every primitive keeps its cell's edges and corners solid, so an occupancy pattern
/// that is invalid with cubes is invalid with any labels.
pub fn valid_cube_occupancies() -> &'static [bool; 4096] {
    static TABLE: std::sync::OnceLock<Box<[bool; 4096]>> = std::sync::OnceLock::new();
    TABLE.get_or_init(|| {
        let mut t = Box::new([false; 4096]);
        for m in 1usize..4096 {
            let mut l = [Primitive::Null; NUM_CELLS];
            for (n, slot) in l.iter_mut().enumerate() {
                if m >> n & 1 == 1 {
                    *slot = Primitive::Cube;
                }
            }
            t[m] = check(&assemble(&l)).valid;
        }
        t
    })
}

/// The normalised frame of a context: its occupied cells' box, longest edge 2, centred.
pub fn context_frame(ctx: &Context) -> Option<BoxFrame> {
    occupied_cell_box(&ctx.labels).map(|(lo, hi)| BoxFrame::for_box(lo.map(|v| v as f64), hi.map(|v| v as f64)))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The readable form names each occupied cell's label and grid position.
    #[test]
    fn describe_names_labels_and_positions() {
        assert_eq!(Context::parse("THC+Z,0,0,0,0,0,0,0,0,0,0,0").unwrap().describe(), "THC+Z at (0,0,0)");
        assert_eq!(Context::parse("cube,BHC+Z,0,0,0,0,0,0,0,0,0,cube").unwrap().describe(), "cube at (0,0,0), BHC+Z at (1,0,0), cube at (2,1,1)");
        assert_eq!(Context::default().describe(), "empty");
    }

    #[test]
    fn congruence_up_to_rotation_and_translation() {
        use crate::polycube::assembly::congruent;
        let a = Context::parse("BHC+X,0,0,0,0,0,0,0,0,0,0,0").unwrap().assemble();
        let b = Context::parse("0,0,0,0,0,0,0,0,0,0,0,BHC-Z").unwrap().assemble();
        assert!(congruent(&a, &b));
        let c = Context::parse("0,0,0,0,0,0,0,0,0,0,0,THC+Z").unwrap().assemble();
        assert!(!congruent(&a, &c));
        let l1 = Context::parse("cube,cube,0,cube,0,0,0,0,0,0,0,0").unwrap().assemble();
        let l2 = Context::parse("0,cube,cube,0,0,cube,0,0,0,0,0,0").unwrap().assemble();
        assert!(congruent(&l1, &l2));
    }

    #[test]
    fn a_rotated_context_assembles_the_same_solid_turned() {
        use crate::polycube::assembly::congruent;
        use crate::polycube::orientation::rotations;
        // an L of three cells with a blind hole, a through hole and a cube
        let c = Context::parse("BHC+X,THC+Z,0,Cube,0,0,0,0,0,0,0,0").unwrap();
        let solid = c.assemble();
        let mut fits = 0;
        for r in rotations() {
            let Some(t) = c.rotated(*r) else { continue };
            fits += 1;
            assert!(congruent(&t.assemble(), &solid), "{} under {}", t, r.name());
            assert_eq!(t.validity().genus, c.validity().genus);
            // the rotated sub-voxels are the original's turned: check one explicit case
            // by the hole axes (a quarter turn about Z maps X to Y)
        }
        assert!(fits >= 4, "{fits}");
        // a quarter turn about Z: new x = -old y, new y = old x
        let quarter = rotations().iter().find(|r| r.perm == [1, 0, 2] && r.sign == [-1, 1, 1]).unwrap();
        let t = c.rotated(*quarter).unwrap();
        // old X-blind hole opening towards +X now opens towards +Y; THC+Z stays
        assert!(t.labels.contains(&Primitive::BhcPy) && t.labels.contains(&Primitive::ThcZ), "{t}");
        // three cells of a 3-long row do not fit 2 cells along Y after a quarter turn
        let row = Context::parse("Cube,Cube,Cube,0,0,0,0,0,0,0,0,0").unwrap();
        assert!(row.rotated(*quarter).is_none());
        assert!(row.rotations().iter().all(|(_, x)| congruent(&x.assemble(), &row.assemble())));
    }

    #[test]
    fn loose_constraints_are_refused_not_enumerated_forever() {
        // every count free on all twelve cells: about 10^12 assignments
        let t = std::time::Instant::now();
        let e = Constraints::default().enumerate().unwrap_err().to_string();
        assert!(e.contains("label assignments") && e.contains("narrow"), "{e}");
        // the refusal is bounded by MAX_ASSIGNMENTS checks, not by the size of the space
        assert!(t.elapsed().as_secs() < 120, "{:?}", t.elapsed());
        // a fixed total keeps the search within the bound
        let k = Constraints { cube: Some(2), thc: Some(0), bhc: Some(0), ..Default::default() };
        assert!(!k.enumerate().unwrap().is_empty());
    }

    #[test]
    fn unlabelled_one_hot_keeps_null_cells_and_withholds_labels() {
        let c = Context::parse("cube,THC+Z,0,0,0,0,BHC-Y,0,0,0,0,0").unwrap();
        let u = c.one_hot_unlabelled();
        for n in 0..NUM_CELLS {
            let row = &u[n * NUM_LABELS..(n + 1) * NUM_LABELS];
            if c.labels[n] == Primitive::Null {
                assert_eq!(row[0], 1.0);
                assert_eq!(row.iter().sum::<f32>(), 1.0);
            } else {
                assert!(row.iter().all(|&v| v == 0.0), "cell {n}");
            }
        }
        // not a valid context (occupied cells have no label), by design
        assert!(Context::from_one_hot(&u).is_err());
    }

    #[test]
    fn one_hot_round_trip_and_errors() {
        let c = Context::parse("cube,THC+Z,0,0,0,0,BHC-Y,0,0,0,0,10").unwrap();
        let v = c.one_hot();
        assert_eq!(Context::from_one_hot(&v).unwrap(), c);
        assert_eq!(v.iter().sum::<f32>(), 12.0);
        let mut bad = v;
        bad[11 + 3] = 1.0; // cell 1 gets a second hot entry
        let e = Context::from_one_hot(&bad).unwrap_err().to_string();
        assert!(e.contains("cell 1"), "{e}");
        let mut bad = v;
        bad[0] = 0.0; // cell 0 empty
        bad[1] = 0.0;
        assert!(Context::from_one_hot(&bad).unwrap_err().to_string().contains("cell 0"));
        let mut bad = v;
        bad[5 * 11] = 0.5;
        assert!(Context::from_one_hot(&bad).unwrap_err().to_string().contains("cell 5"));
        assert!(Context::from_one_hot(&v[..100]).is_err());
        assert!(Context::from_labels(&[0; 11]).is_err());
        let e = Context::from_labels(&[0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 12]).unwrap_err().to_string();
        assert!(e.contains("cell 11"), "{e}");
        let two: Vec<f32> = v.iter().chain(v.iter()).copied().collect();
        assert_eq!(Context::batch_from_one_hot(&two).unwrap().len(), 2);
    }

    #[test]
    fn enumerate_counts() {
        // One THC on the full grid: 12 cells x 3 orientations, all genus 1.
        let c = Constraints { thc: Some(1), cube: Some(0), bhc: Some(0), ..Default::default() };
        let v = c.enumerate().unwrap();
        assert_eq!(v.len(), 36);
        // Two cubes: 2-cell face-adjacent pairs of the 3x2x2 grid = 20.
        let c = Constraints { cube: Some(2), thc: Some(0), bhc: Some(0), ..Default::default() };
        assert_eq!(c.enumerate().unwrap().len(), 20);
        // Exact mask with the genus filter.
        let c = Constraints { thc: Some(3), cube: Some(0), bhc: Some(0), genus: Some(3), ..Default::default() }
            .with_mask("111000000000")
            .unwrap();
        let v = c.enumerate().unwrap();
        assert!(v.iter().any(|x| x.names().starts_with("THC+Z,THC+Z,THC+Z")));
        for x in &v {
            assert_eq!(x.validity().genus, Some(3));
        }
    }
}

impl Serialize for Context {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        s.serialize_str(&self.names())
    }
}

impl<'de> Deserialize<'de> for Context {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        let s = String::deserialize(d)?;
        Context::parse(&s).map_err(serde::de::Error::custom)
    }
}
