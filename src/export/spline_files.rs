//! The spline stage's files of a run folder: the BEXT file, the LS-DYNA deck that
//! includes it, the spline sampled per element (VTU) and the control mesh ([`write_outputs`]), with the `spline`
//! object of report.json.

use super::lsdyna::DeckOptions;
use super::{bext, lsdyna, spline_vtk, spline_vtu};
use crate::error::{Error, Result};
use crate::spline::Spline;
use serde::Serialize;

/// File names and settings of `write_outputs`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct OutputOptions {
    /// BEXT file (default "spline.bext").
    pub bext: String,
    /// LS-DYNA deck including it (default "model.k").
    pub lsdyna: String,
    /// The spline sampled per element as binary VTU ([`spline_vtu`]; default
    /// Some("spline.vtu"); None skips it).
    pub vtu: Option<String>,
    /// The same samples as binary legacy VTK (default None: the VTU holds the same
    /// grid and data; legacy readers only).
    pub vtk: Option<String>,
    /// Control mesh (default Some("spline_control.vtk")).
    pub control_vtk: Option<String>,
    /// Sub-cells along each element edge in the sampled files (default
    /// [`DEFAULT_SAMPLES`], 2: 27 points and 8 cells per element, enough to show each
    /// element's curvature; 1 to [`MAX_SAMPLES`]), lowered (to 1 at least) so that
    /// the file has at most `vtk_max_cells` cells.
    pub vtk_samples: usize,
    /// Cap on the sampled files' cells (default 500,000, about 23 MB of VTU: 4
    /// samples on the 144,000 elements of a voxel-68 cgal_joint would be 9.2 M cells).
    pub vtk_max_cells: usize,
    /// Sparse BEXT rows (default: `SplineOptions::sparse_bext` of the spline).
    pub sparse_bext: Option<bool>,
    /// Absolute tolerance of the BEXT operator entries: each is written with the
    /// fewest decimals that read back within it (default:
    /// `SplineOptions::bext_tolerance` of the spline; 0: every entry exact).
    pub bext_tolerance: Option<f64>,
    pub deck: DeckOptions,
}

impl Default for OutputOptions {
    fn default() -> Self {
        OutputOptions {
            bext: "spline.bext".into(),
            lsdyna: "model.k".into(),
            vtu: Some("spline.vtu".into()),
            vtk: None,
            control_vtk: Some("spline_control.vtk".into()),
            vtk_samples: DEFAULT_SAMPLES,
            vtk_max_cells: 500_000,
            sparse_bext: None,
            bext_tolerance: None,
            deck: Default::default(),
        }
    }
}

/// Default [`OutputOptions::vtk_samples`] (`sddpm run --spline-sample`).
pub const DEFAULT_SAMPLES: usize = 2;
/// Largest [`OutputOptions::vtk_samples`]: 512 cells per element.
pub const MAX_SAMPLES: usize = 8;

/// Samples per direction and element of the sampled files: `o.vtk_samples`, fewer
/// when `elements` x samples^3 would pass `o.vtk_max_cells`, and at least 1.
fn vtk_samples(o: &OutputOptions, elements: usize) -> usize {
    let mut n = o.vtk_samples.max(1);
    while n > 1 && elements.saturating_mul(n * n * n) > o.vtk_max_cells {
        n -= 1;
    }
    n
}

/// Write the spline's files into `dir` (BEXT, the LS-DYNA deck that includes it,
/// the sampled spline, the control mesh) and return the `spline` object of report.json: the keys
/// DESIGN.md fixes ("elements", "basis_functions", "bext", "lsdyna") plus the
/// whole `SplineReport` and the names of the VTK files.
pub fn write_outputs(dir: &std::path::Path, sp: &Spline, o: &OutputOptions) -> Result<serde_json::Value> {
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir.display(), e))?;
    let sparse = o.sparse_bext.unwrap_or(sp.options().sparse_bext);
    let tolerance = o.bext_tolerance.unwrap_or(sp.options().bext_tolerance);
    bext::write_bext_within(&dir.join(&o.bext), sp, sparse, tolerance)?;
    lsdyna::write_iga_deck(&dir.join(&o.lsdyna), &o.bext, &o.deck)?;
    if !(1..=MAX_SAMPLES).contains(&o.vtk_samples) {
        return Err(Error::InvalidArgument(format!("samples per element edge must be 1..={MAX_SAMPLES}, got {}", o.vtk_samples)));
    }
    let n = vtk_samples(o, sp.num_elements());
    if let Some(v) = &o.vtu {
        spline_vtu::write_spline_vtu(&dir.join(v), sp, n)?;
    }
    if let Some(v) = &o.vtk {
        spline_vtk::write_spline_vtk_binary(&dir.join(v), sp, n)?;
    }
    if let Some(v) = &o.control_vtk {
        spline_vtk::write_control_mesh_vtk(&dir.join(v), sp)?;
    }
    let mut j = serde_json::to_value(sp.report()).map_err(|e| Error::Internal(e.to_string()))?;
    if let Some(m) = j.as_object_mut() {
        m.insert("bext".into(), o.bext.clone().into());
        m.insert("lsdyna".into(), o.lsdyna.clone().into());
        m.insert("vtu".into(), o.vtu.clone().into());
        m.insert("vtk".into(), o.vtk.clone().into());
        let sampled = o.vtu.is_some() || o.vtk.is_some();
        m.insert("sample_cells_per_edge".into(), if sampled { n.into() } else { serde_json::Value::Null });
        m.insert("control_vtk".into(), o.control_vtk.clone().into());
        m.insert("bext_sparse".into(), sparse.into());
        m.insert("bext_tolerance".into(), tolerance.into());
    }
    Ok(j)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// With 4 samples the VTK keeps them on the main job's level-2 meshes (2,592
    /// elements: 165,888 cells) and drops to 1 on a 144,000-element one.
    #[test]
    fn sampled_vtk_stays_under_its_cell_cap() {
        assert_eq!(vtk_samples(&OutputOptions::default(), 2_592), 2);
        let o = OutputOptions { vtk_samples: 4, ..OutputOptions::default() };
        assert_eq!(vtk_samples(&o, 2_592), 4);
        assert_eq!(vtk_samples(&o, 25_469), 2);
        assert_eq!(vtk_samples(&o, 143_996), 1);
        assert_eq!(vtk_samples(&o, 10_000_000), 1);
        assert_eq!(vtk_samples(&OutputOptions { vtk_samples: 1, ..o.clone() }, 1), 1);
        for e in [1, 100, 7_813, 7_814, 62_500, 62_501] {
            let n = vtk_samples(&o, e);
            assert!(n == 1 || e * n * n * n <= o.vtk_max_cells, "{e}: {n}");
            assert!(n == 4 || e * (n + 1).pow(3) > o.vtk_max_cells, "{e}: {n} could be larger");
        }
    }
}
