//! What the hex stage hands to `sddpm run`: the names of its files in the output
//! folder (written by `export::hexfmt::write_hex_files`) and the "hex" object of
//! report.json (DESIGN.md "Command line").

use super::pipeline::HexResult;

/// File names of the hex stage inside the output folder.
pub const HEX_VTU: &str = "hex.vtu";
pub const HEX_VTK: &str = "hex.vtk";
pub const HEX_MESH: &str = "hex.mesh";
pub const HEX_K: &str = "hex.k";

/// The "hex" object of report.json: the keys DESIGN.md fixes (vertices, elements,
/// min_scaled_jacobian, mean_scaled_jacobian, inverted, hausdorff_relative, file)
/// and more: level, histogram, volumes, per-level and per-stage reports.
pub fn report_json(r: &HexResult) -> serde_json::Value {
    serde_json::json!({
        "vertices": r.mesh.nodes.len(),
        "elements": r.mesh.elements.len(),
        "min_scaled_jacobian": r.quality.min,
        "mean_scaled_jacobian": r.quality.mean,
        "inverted": r.quality.inverted,
        "hausdorff_relative": r.hausdorff_relative,
        "file": HEX_VTU,
        "files": [HEX_VTU, HEX_VTK, HEX_MESH, HEX_K],
        "level": r.level,
        "scaled_jacobian_measure": "Verdict hex scaled Jacobian (8 corners + centre principal axes, VTK node order)",
        "histogram": { "bins": r.histogram.len(), "range": [-1.0, 1.0], "counts": r.histogram },
        "hausdorff": r.hausdorff,
        "volume": r.volume,
        "input_volume": r.input_volume,
        "returned": r.returned,
        "domain": r.domain,
        "levels": r.levels,
        "surface_map": r.surface_map,
        "stages": r.stages,
        "seconds": r.seconds_total,
    })
}

/// Seconds per hex stage, for report.json's "seconds" object ("hex_mapping", ...).
pub fn stage_seconds(r: &HexResult) -> Vec<(String, f64)> {
    r.stages.iter().map(|s| (format!("hex_{}", s.stage), s.seconds)).collect()
}
