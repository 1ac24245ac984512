//! The named options: every scalar option of [`RunOptions`] by its dotted path in
//! the option structs ("hex.quality.pillow", "polycube.verify.tau_cd",
//! "hex_candidates"), with its type, default and one line of documentation
//! ([`OPTIONS`]). A value is set by serialising the options to JSON, replacing the
//! named value, deserialising them back and checking them all
//! ([`RunOptions::validate`]), so an unknown name, a value of the wrong type and a
//! value out of its range are errors naming the option, and the options stay valid.
//! The C API's options handle (sddpm_options_*) and the Python package's keyword
//! arguments use these names: a new option needs no new C declaration.
//!
//! Not named (no scalar value): `spline.sharp_edges` (a list of edges) and
//! `spline.refine` (automatic refinement's settings, off by default).

use super::RunOptions;
use crate::error::{Error, Result};
use serde_json::Value;

/// The type of a named option's value.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum OptionKind {
    /// A finite floating-point number.
    Number,
    /// A whole number >= 0 (set through a number that must be integral).
    Integer,
    Bool,
    /// One of the names the documentation lists.
    String,
}

impl OptionKind {
    pub fn name(self) -> &'static str {
        match self {
            OptionKind::Number => "number",
            OptionKind::Integer => "integer",
            OptionKind::Bool => "bool",
            OptionKind::String => "string",
        }
    }
}

/// One named option.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct OptionInfo {
    /// The dotted path in [`RunOptions`].
    pub name: &'static str,
    pub kind: OptionKind,
    /// The option may be unset (none): an automatic choice or a step turned off,
    /// as the documentation says.
    pub nullable: bool,
    pub doc: &'static str,
}

/// A value to set or a value read.
#[derive(Debug, Clone, PartialEq)]
pub enum OptionValue {
    /// A number (an integer option takes an integral one).
    Number(f64),
    Bool(bool),
    String(String),
    /// Unset (only for a nullable option).
    None,
}

const fn opt(name: &'static str, kind: OptionKind, nullable: bool, doc: &'static str) -> OptionInfo {
    OptionInfo { name, kind, nullable, doc }
}

use OptionKind::{Bool, Integer, Number, String as Str};

/// Every named option. A unit test checks that this list and the scalar values of
/// the serialised [`RunOptions`] are the same names of the same types.
pub static OPTIONS: &[OptionInfo] = &[
    // polycube generation: the reverse process
    opt("polycube.sampler.steps", Integer, false, "Network evaluations of the reverse process: 0 or >= T runs the full T-step ancestral sampler, 1..T the strided deterministic sampler with that many steps"),
    opt("polycube.sampler.seed", Integer, false, "Seed of the sampler noise"),
    opt("polycube.sampler.keep_every", Integer, false, "Keep the state every this many steps for visualisation (0: none)"),
    opt("polycube.sampler.max_batch", Integer, false, "Candidates per network call"),
    opt("polycube.sampler.start_step", Integer, false, "The step the reverse process starts from, the input forward-noised to it (0 = T); overridden by start_noise"),
    opt("polycube.sampler.start_noise", Number, true, "Start each candidate at the first step whose noise, in its cells' units, reaches this value (none: start_step)"),
    opt("polycube.sampler.raw_start", Bool, false, "Start from the raw input geometry without forward noising"),
    opt("polycube.sampler.refine_passes", Integer, false, "Denoising passes after the last step"),
    opt("polycube.sampler.refine_t", Integer, false, "Timestep of the refinement passes"),
    opt("polycube.sampler.clip_margin", Number, false, "Strided sampler: clip each predicted x_0 point to its cell's box grown by this margin (cell units; negative: no clipping)"),
    opt("polycube.sampler.eps_scale", Number, false, "Factor applied to every predicted noise (1: off)"),
    opt("polycube.sampler.guidance", Number, false, "Classifier-free guidance weight (0: off)"),
    opt("polycube.sampler.kernel_gate", Number, true, "Gate of the template attention: 1 its Bayes estimate alone, 0 the U-Net alone (none: the gate the weights learned)"),
    opt("polycube.sampler.visible_prior", Bool, false, "The template attention attends to each cell's primitive without the faces shared with an occupied neighbour"),
    opt("polycube.sampler.use_rank", Bool, false, "The point denoiser sees each slot's rank"),
    // polycube generation: verification
    opt("polycube.verify.zero_norm", Number, false, "Points of norm <= this are placeholders (null cells hold the origin)"),
    opt("polycube.verify.min_points", Integer, false, "Points a cell needs to count as active (GOCC)"),
    opt("polycube.verify.tau_active", Number, false, "Minimum largest bounding-box span of an active cell, cell units (GOCC)"),
    opt("polycube.verify.cell_tolerance", Number, false, "Tolerance around a cell for the spatial check, cell units (GOCC)"),
    opt("polycube.verify.min_inside_fraction", Number, false, "Fraction of an occupied block's points that must lie in its cell (GOCC)"),
    opt("polycube.verify.max_null_region_fraction", Number, false, "Largest fraction of the active points allowed in null cells (GOCC)"),
    opt("polycube.verify.tau_cd", Number, false, "TCV threshold on the penalty Chamfer distance, squared cell units"),
    opt("polycube.verify.penalty_p", Number, false, "Exponent p of the Chamfer distance's penalty"),
    opt("polycube.verify.template_points", Integer, false, "Points sampled on each template"),
    opt("polycube.verify.visible_coverage", Bool, false, "Leave the template faces shared with an occupied neighbour out of TCV's coverage half"),
    opt("polycube.verify.same_genus_rivals", Bool, false, "In a cell whose input shows the label's hole, TCV compares the label only with the labels that keep the context's genus (off: with all ten everywhere)"),
    // polycube generation: pre-checks and search
    opt("polycube.orientations", Str, false, "Grid rotations of the aligned input tried: \"Identity\" (as aligned), \"SignFlips\" (and its sign flips) or \"All\" (all 24)"),
    opt("polycube.max_in_empty_fraction", Number, false, "Pre-check: largest fraction of the input's surface allowed in cells the context leaves empty"),
    opt("polycube.min_occupied_fraction", Number, false, "Pre-check: an occupied cell must receive at least this fraction of its fair share of the surface"),
    opt("polycube.orientations_per_context", Integer, false, "Orientations kept per context after the pre-check"),
    opt("polycube.max_fit", Number, false, "Pre-check: largest geometric fit score (squared cell units) a candidate may have to be diffused"),
    opt("polycube.relative_fit", Number, false, "Pre-check: candidates within this factor of the input's best fit are diffused even above max_fit (0: off)"),
    opt("polycube.relative_fit_cap", Number, false, "The relative fit rule admits no fit above this"),
    opt("polycube.warp_fit", Bool, false, "Pre-check: also fit each candidate after a quadratic registration of the input onto its polycube, and lay the input out after it when it fits better"),
    opt("polycube.neighbour_fit_ratio", Number, false, "Pre-check of a caller's context: refused when relabelling one cell fits the input this many times better (0: off)"),
    opt("polycube.visible_retry", Bool, false, "A candidate that fails verification is diffused again with the visible prior and verified with the visible coverage"),
    opt("polycube.oversampling", Integer, false, "Surface samples drawn from the input, shared by every candidate"),
    opt("polycube.seed", Integer, false, "Seed of the input's surface sampling and of the candidates' layout (the sampler has its own, polycube.sampler.seed)"),
    // the automated mode
    opt("auto.resolution", Integer, false, "Automated mode: voxels along the longest edge of the temporary volume"),
    opt("auto.min_fill", Number, false, "Automated mode: a subregion filled less than this is empty"),
    opt("auto.null_fill", Number, false, "Automated mode: a subregion filled less than this may also be empty (both are tried)"),
    opt("auto.local_keep", Integer, false, "Automated mode: labels kept per subregion after the local fit"),
    opt("auto.local_diffusion", Bool, false, "Automated mode: run the local single-cell diffusion and verification"),
    opt("auto.max_global", Integer, false, "Automated mode: global candidates diffused at most, best fit first"),
    opt("auto.finer_box_factor", Number, false, "Automated mode: a finer box is preferred only when its fit beats the coarsest acceptable box's by this factor"),
    opt("auto.max_boxes", Integer, false, "Automated mode: boxes tried, best first, before giving up"),
    opt("auto.local_steps", Integer, false, "Automated mode: sampler steps of the local single-cell diffusion"),
    opt("auto.joint_labels", Bool, false, "Automated mode: also choose the subregions' labels jointly on the global fit"),
    opt("auto.register_cells", Bool, false, "Automated mode: rank a subregion's labels after a local affine registration of its cell"),
    opt("auto.opening_labels", Bool, false, "Automated mode: rank first the labels whose hole the subregion's voxels show"),
    opt("auto.axis_frames", Bool, false, "Automated mode: also try the boxes with three cells along X with the grid's X along the input's Y and Z"),
    opt("auto.fitted_splits", Bool, false, "Automated mode: also try each box with its cell boundaries where the part's cross-section changes (the input warped onto the equal grid)"),
    // the hex stage (docs/hex.md)
    opt("hex.map.level", Integer, true, "Fixed octree subdivision level, 0 to 6 (none: chosen by the stopping rule)"),
    opt("hex.map.min_level", Integer, false, "Smallest level the stopping rule may choose (at most hex.map.max_level)"),
    opt("hex.map.max_level", Integer, false, "Largest level the stopping rule may choose, at most 6"),
    opt("hex.map.threshold", Number, false, "Stopping rule: largest distance between a mapped midpoint and its linear interpolation, fraction of the bounding-box diagonal"),
    opt("hex.map.stall_ratio", Number, false, "Stopping rule: also stop when a level's measure is above this fraction of the previous level's"),
    opt("hex.map.use_correspondence", Bool, false, "Seed the surface map with the diffusion correspondence (never for an unverified candidate)"),
    opt("hex.map.fit_planes", Bool, false, "Without a correspondence, fit the polycube's sub-voxel planes to the input before mapping"),
    opt("hex.map.surface_map", Str, false, "How the polycube's boundary goes onto the input: \"Projection\" (closest facing point and relaxation), \"Charts\" (inverse chart maps; the projection where a chart does not map) or \"Best\" (the charts, and the projection too when their mesh misses a goal; the better kept)"),
    opt("hex.map.local_refinement", Integer, false, "Rounds of local refinement of the chosen level where its mesh is farthest from the input, when it misses the distance goal alone (0: none)"),
    opt("hex.surface.feature_angle", Number, false, "Dihedral angle (degrees) above which an input edge is a sharp feature"),
    opt("hex.surface.min_feature_length", Number, false, "Feature curves shorter than this fraction of the bounding-box diagonal are ignored"),
    opt("hex.surface.feature_median_angle", Number, false, "Feature curves whose median dihedral angle (degrees, 0 to 180) is below this are ignored"),
    opt("hex.surface.corner_angle", Number, false, "Turning angle (degrees) that makes a feature-curve vertex a corner"),
    opt("hex.surface.relax_iterations", Integer, false, "Rounds of the boundary fit and relaxation of the surface map on level 0"),
    opt("hex.quality.pillow", Bool, false, "One pillow layer under the boundary"),
    opt("hex.quality.feature_sheets", Bool, false, "Feature sheets on the fallback's lattice meshes: a sheet of elements under each surface patch, the nodes between patches on the sharp curves"),
    opt("hex.quality.narrow_corner_faces", Number, false, "Feature sheets: a face whose angle at a held corner is below this many degrees keeps the lattice's quads there (0: off)"),
    opt("hex.quality.narrow_patch_width", Number, false, "Feature sheets: a patch narrower than this fraction of the lattice's boundary edge is merged into its neighbour (0: off)"),
    opt("hex.quality.smooth_iterations", Integer, false, "Passes of mean-ratio smoothing (untangling)"),
    opt("hex.quality.capture_features", Bool, false, "Sharp-edge capture: boundary nodes near the input's sharp edges go onto them"),
    opt("hex.quality.pin_uncovered", Number, false, "Coverage step: input vertices farther than this fraction of the Hausdorff goal from the boundary get a node pinned to them (0: off)"),
    opt("hex.quality.optimise_target", Number, false, "The optimisation works on elements below this scaled Jacobian"),
    opt("hex.quality.optimise_passes", Integer, false, "Passes of the scaled-Jacobian optimisation (0: none)"),
    opt("hex.quality.release_distance", Number, false, "Where elements stay inverted, the surface nodes around them may leave the input by this fraction of the bounding-box diagonal"),
    opt("hex.quality.boundary_ascent", Bool, false, "Boundary mean ascent: the last quality step, boundary nodes sliding on the input"),
    opt("hex.quality.keep_better_mapped", Bool, false, "Return the mapped mesh when the quality steps end below its minimum scaled Jacobian"),
    opt("hex.fallback.enabled", Bool, false, "Grid-based fallback: when no polycube mesh meets the goals, also mesh the input on a voxel lattice and keep that mesh when it ranks better"),
    opt("hex.fallback.resolution", Integer, false, "Fallback: voxels along the longest bounding-box edge of the first lattice (2 to 192)"),
    opt("hex.fallback.refinements", Integer, false, "Fallback: finer lattices tried after the first while the mesh misses the goals"),
    opt("hex.fallback.lattice_planes", Number, false, "Fallback: lattice planes moved onto the input's axis-parallel faces of at least this share of its area, in [0, 1) (0: off)"),
    opt("hex.fallback.local_refinement", Integer, false, "Fallback: local refinement rounds around the points farthest from the mesh (0: off)"),
    opt("hex.goals.min_scaled_jacobian", Number, false, "Quality goal: smallest acceptable minimum scaled Jacobian"),
    opt("hex.goals.mean_scaled_jacobian", Number, false, "Quality goal: smallest acceptable mean scaled Jacobian"),
    opt("hex.goals.hausdorff", Number, false, "Quality goal: largest acceptable two-sided Hausdorff distance to the input, fraction of the bounding-box diagonal"),
    opt("hex.max_elements", Integer, false, "Most elements before pillowing: caps the automatic level and the fallback's lattices"),
    opt("hex.target_size", Number, true, "Target element size in model units: fixes the polycube level and the fallback's lattice (none: the stopping rule and hex.fallback.resolution)"),
    opt("hex.hausdorff_samples", Integer, false, "Extra random surface samples for the Hausdorff distance"),
    // the spline stage (docs/spline.md)
    opt("spline.sharp_angle_deg", Number, true, "Boundary edges whose quads' normals differ by more than this angle (degrees, 0 to 180) are sharp (none: no automatic sharp edges)"),
    opt("spline.boundary_enrichment", Bool, false, "C0 Bernstein functions on the two Bézier layers next to the boundary"),
    opt("spline.interpolate_vertices", Bool, false, "Control points chosen so that the spline passes through every control-mesh vertex"),
    opt("spline.repair_jacobian", Bool, false, "Elements with a non-positive Jacobian get the control-mesh element's trilinear map"),
    opt("spline.fit.enabled", Bool, false, "Fit the spline boundary to the surface"),
    opt("spline.fit.iterations", Integer, false, "Fit: closest-point / least-squares rounds"),
    opt("spline.fit.samples", Integer, false, "Fit: samples per direction on each boundary face of each element (at least 1)"),
    opt("spline.fit.regularization", Number, false, "Fit: Tikhonov weight towards the current control points, relative to the normal matrix's mean diagonal"),
    opt("spline.fit.max_backtracks", Integer, false, "Fit: halvings of a step that would create a non-positive Jacobian"),
    opt("spline.fit.two_sided", Bool, false, "Fit: also pull the boundary towards every surface vertex"),
    opt("spline.fit.max_reverse_points", Integer, false, "Fit: most surface vertices the two-sided term uses"),
    opt("spline.sparse_bext", Bool, false, "Write sparse BEXT operator rows (default; false: dense rows of 64 entries, as Hex2Spline)"),
    opt("spline.bext_tolerance", Number, false, "Absolute tolerance of the BEXT operator entries: the fewest decimals that read back within it (0: exact)"),
    // the main job
    opt("accept_unverified", Bool, false, "When no candidate passes verification, mesh unverified candidates (by fit) instead of failing with VERIFICATION_FAILED"),
    opt("require_valid_hex", Bool, false, "Refuse (MESHING_FAILED) a hex mesh that keeps inverted elements"),
    opt("hex_candidates", Integer, false, "Candidates meshed at most (verified ones by score, then unverified ones by fit); the best mesh is kept"),
];

/// The named option `name`, or an error naming it (with the options of the same
/// last component, when there are some).
pub fn option_info(name: &str) -> Result<&'static OptionInfo> {
    if let Some(o) = OPTIONS.iter().find(|o| o.name == name) {
        return Ok(o);
    }
    let last = name.rsplit('.').next().unwrap_or(name);
    let near: Vec<&str> = OPTIONS.iter().filter(|o| o.name.rsplit('.').next() == Some(last)).map(|o| o.name).collect();
    let hint = if near.is_empty() { String::new() } else { format!(" (did you mean {}?)", near.join(" or ")) };
    Err(Error::InvalidArgument(format!("unknown option \"{name}\"{hint}; sddpm_options_describe_json lists every option")))
}

/// The options as JSON, the spline's always present (its defaults when off).
fn to_json(o: &RunOptions) -> Result<Value> {
    let mut v = serde_json::to_value(o).map_err(|e| Error::Internal(format!("the options do not serialise: {e}")))?;
    if v["spline"].is_null() {
        v["spline"] = serde_json::to_value(crate::spline::SplineOptions::default()).map_err(|e| Error::Internal(e.to_string()))?;
    }
    Ok(v)
}

fn slot<'a>(v: &'a mut Value, name: &str) -> Option<&'a mut Value> {
    name.split('.').try_fold(v, |v, k| v.get_mut(k))
}

impl RunOptions {
    /// Set the option `name` ([`OPTIONS`]). The options are left unchanged when the
    /// name is unknown, the value of another type (an integer option takes an
    /// integral number >= 0) or out of its range ([`RunOptions::validate`]); the
    /// error (INVALID_ARGUMENT) names the option.
    pub fn set_option(&mut self, name: &str, value: OptionValue) -> Result<()> {
        let info = option_info(name)?;
        let bad = |what: String| Error::InvalidArgument(format!("option {name} {what}"));
        let new = match (&value, info.kind) {
            (OptionValue::None, _) if info.nullable => Value::Null,
            (OptionValue::None, _) => return Err(bad(format!("cannot be unset (it is a {} option)", info.kind.name()))),
            (OptionValue::Number(x), OptionKind::Number) => {
                serde_json::Number::from_f64(*x).map(Value::Number).ok_or_else(|| bad(format!("must be a finite number, got {x}")))?
            }
            (OptionValue::Number(x), OptionKind::Integer) => {
                if !(x.is_finite() && x.fract() == 0.0 && *x >= 0.0 && *x <= 9_007_199_254_740_992.0) {
                    return Err(bad(format!("must be a whole number >= 0, got {x}")));
                }
                Value::from(*x as u64)
            }
            (OptionValue::Bool(b), OptionKind::Bool) => Value::Bool(*b),
            (OptionValue::String(s), OptionKind::String) => Value::String(s.clone()),
            (v, k) => {
                let given = match v {
                    OptionValue::Number(_) => "a number",
                    OptionValue::Bool(_) => "a bool",
                    OptionValue::String(_) => "a string",
                    OptionValue::None => "none",
                };
                return Err(bad(format!("is a {} option, got {given}", k.name())));
            }
        };
        let was_off = self.spline.is_none();
        let mut v = to_json(self)?;
        *slot(&mut v, name).ok_or_else(|| Error::Internal(format!("option {name} is not in the options' JSON")))? = new;
        let mut o: RunOptions = serde_json::from_value(v).map_err(|e| bad(format!("does not take that value: {e}")))?;
        if was_off && !name.starts_with("spline.") {
            o.spline = None;
        }
        o.validate()?;
        *self = o;
        Ok(())
    }

    /// The value of the option `name` ([`OptionValue::None`] when unset).
    pub fn option(&self, name: &str) -> Result<OptionValue> {
        let info = option_info(name)?;
        let mut v = to_json(self)?;
        let x = slot(&mut v, name).ok_or_else(|| Error::Internal(format!("option {name} is not in the options' JSON")))?;
        Ok(match x {
            Value::Null => OptionValue::None,
            Value::Bool(b) => OptionValue::Bool(*b),
            Value::Number(n) => OptionValue::Number(n.as_f64().unwrap_or(f64::NAN)),
            Value::String(s) => OptionValue::String(s.clone()),
            other => return Err(Error::Internal(format!("option {} has the non-scalar value {other}", info.name))),
        })
    }

    /// Every named option as a JSON object: name -> {"default", "doc", "nullable",
    /// "type" ("number", "integer", "bool" or "string"), "value"}.
    pub fn describe_options(&self) -> Result<Value> {
        let d = RunOptions::default();
        let mut out = serde_json::Map::new();
        for o in OPTIONS {
            let js = |x: OptionValue| match x {
                OptionValue::Number(n) if o.kind == OptionKind::Integer => Value::from(n as u64),
                OptionValue::Number(n) => serde_json::Number::from_f64(n).map(Value::Number).unwrap_or(Value::Null),
                OptionValue::Bool(b) => Value::Bool(b),
                OptionValue::String(s) => Value::String(s),
                OptionValue::None => Value::Null,
            };
            out.insert(
                o.name.to_string(),
                // keys in sorted order, whatever serde_json's map keeps
                serde_json::json!({
                    "default": js(d.option(o.name)?),
                    "doc": o.doc,
                    "nullable": o.nullable,
                    "type": o.kind.name(),
                    "value": js(self.option(o.name)?),
                }),
            );
        }
        Ok(Value::Object(out))
    }

    /// Check every option against its range; the first one out of it is the error
    /// (INVALID_ARGUMENT), which names it by its name in [`OPTIONS`]. The hex options
    /// are checked by [`crate::hex::HexOptions::validate`].
    pub fn validate(&self) -> Result<()> {
        self.hex
            .validate()
            .map_err(|e| Error::InvalidArgument(format!("option hex.{} must be {}, got {}", e.option.path(), e.expected, e.value)))?;
        let p = &self.polycube;
        let s = &p.sampler;
        let v = &p.verify;
        let a = &self.auto;
        let fraction = "a fraction in [0, 1]";
        let positive = "a finite number > 0";
        let non_negative = "a finite number >= 0";
        let finite = "a finite number";
        let checks: [(&str, f64, bool, &str); 27] = [
            ("polycube.sampler.start_noise", s.start_noise.unwrap_or(1.0), s.start_noise.is_none_or(|x| x.is_finite() && x > 0.0), positive),
            ("polycube.sampler.clip_margin", s.clip_margin, s.clip_margin.is_finite(), finite),
            ("polycube.sampler.eps_scale", s.eps_scale, s.eps_scale.is_finite() && s.eps_scale > 0.0, positive),
            ("polycube.sampler.guidance", s.guidance, s.guidance.is_finite() && s.guidance >= 0.0, non_negative),
            ("polycube.sampler.kernel_gate", s.kernel_gate.unwrap_or(0.0), s.kernel_gate.is_none_or(|g| g.is_finite()), finite),
            ("polycube.verify.zero_norm", v.zero_norm, v.zero_norm.is_finite() && v.zero_norm >= 0.0, non_negative),
            ("polycube.verify.tau_active", v.tau_active, v.tau_active.is_finite() && v.tau_active >= 0.0, non_negative),
            ("polycube.verify.cell_tolerance", v.cell_tolerance, v.cell_tolerance.is_finite() && v.cell_tolerance >= 0.0, non_negative),
            ("polycube.verify.min_inside_fraction", v.min_inside_fraction, (0.0..=1.0).contains(&v.min_inside_fraction), fraction),
            ("polycube.verify.max_null_region_fraction", v.max_null_region_fraction, (0.0..=1.0).contains(&v.max_null_region_fraction), fraction),
            ("polycube.verify.tau_cd", v.tau_cd, v.tau_cd.is_finite() && v.tau_cd > 0.0, positive),
            ("polycube.verify.penalty_p", v.penalty_p, v.penalty_p.is_finite() && v.penalty_p > 0.0, positive),
            ("polycube.verify.template_points", v.template_points as f64, v.template_points > 0, "at least 1"),
            ("polycube.max_in_empty_fraction", p.max_in_empty_fraction, (0.0..=1.0).contains(&p.max_in_empty_fraction), fraction),
            ("polycube.min_occupied_fraction", p.min_occupied_fraction, (0.0..=1.0).contains(&p.min_occupied_fraction), fraction),
            ("polycube.max_fit", p.max_fit, p.max_fit > 0.0, "a number > 0"),
            ("polycube.relative_fit", p.relative_fit, p.relative_fit.is_finite() && p.relative_fit >= 0.0, non_negative),
            ("polycube.relative_fit_cap", p.relative_fit_cap, p.relative_fit_cap >= 0.0, "a number >= 0"),
            ("polycube.neighbour_fit_ratio", p.neighbour_fit_ratio, p.neighbour_fit_ratio.is_finite() && p.neighbour_fit_ratio >= 0.0, non_negative),
            ("auto.resolution", a.resolution as f64, (8..=256).contains(&a.resolution), "between 8 and 256"),
            ("auto.min_fill", a.min_fill, (0.0..=1.0).contains(&a.min_fill), fraction),
            ("auto.null_fill", a.null_fill, (0.0..=1.0).contains(&a.null_fill), fraction),
            ("auto.finer_box_factor", a.finer_box_factor, a.finer_box_factor.is_finite() && a.finer_box_factor > 0.0, positive),
            ("spline.sharp_angle_deg", self.spline_sharp_angle(), (0.0..=180.0).contains(&self.spline_sharp_angle()), "an angle in degrees in [0, 180] (or none)"),
            ("spline.fit.regularization", self.spline.as_ref().map_or(0.0, |s| s.fit.regularization), self.spline.as_ref().is_none_or(|s| s.fit.regularization.is_finite() && s.fit.regularization >= 0.0), non_negative),
            ("spline.fit.samples", self.spline.as_ref().map_or(1.0, |s| s.fit.samples as f64), self.spline.as_ref().is_none_or(|s| s.fit.samples > 0), "at least 1"),
            ("spline.bext_tolerance", self.spline.as_ref().map_or(0.0, |s| s.bext_tolerance), self.spline.as_ref().is_none_or(|s| s.bext_tolerance.is_finite() && s.bext_tolerance >= 0.0), non_negative),
        ];
        if let Some((name, value, _, expected)) = checks.iter().find(|c| !c.2) {
            return Err(Error::InvalidArgument(format!("option {name} must be {expected}, got {value}")));
        }
        if self.hex_candidates == 0 {
            return Err(Error::InvalidArgument("option hex_candidates must be at least 1, got 0".into()));
        }
        Ok(())
    }

    /// The spline's sharp angle for [`RunOptions::validate`] (90 when unset or off).
    fn spline_sharp_angle(&self) -> f64 {
        self.spline.as_ref().and_then(|s| s.sharp_angle_deg).unwrap_or(90.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The scalar leaves of the serialised options with their JSON types.
    fn leaves(v: &Value, prefix: &str, out: &mut Vec<(String, Value)>) {
        match v {
            Value::Object(m) => {
                for (k, x) in m {
                    let p = if prefix.is_empty() { k.clone() } else { format!("{prefix}.{k}") };
                    leaves(x, &p, out);
                }
            }
            other => out.push((prefix.to_string(), other.clone())),
        }
    }

    #[test]
    fn every_scalar_option_is_named_with_its_type() {
        let mut l = Vec::new();
        leaves(&to_json(&RunOptions::default()).unwrap(), "", &mut l);
        let unnamed = ["spline.sharp_edges", "spline.refine"];
        let mut names: Vec<&str> = l.iter().map(|(n, _)| n.as_str()).filter(|n| !unnamed.contains(n)).collect();
        names.sort();
        let mut listed: Vec<&str> = OPTIONS.iter().map(|o| o.name).collect();
        listed.sort();
        assert_eq!(names, listed, "OPTIONS and the option structs differ: name the new option in src/pipeline/options.rs");
        for (n, v) in &l {
            let Ok(o) = option_info(n) else { continue };
            let ok = match (o.kind, v) {
                (_, Value::Null) => o.nullable,
                (OptionKind::Number, Value::Number(_)) => true,
                (OptionKind::Integer, Value::Number(x)) => x.is_u64(),
                (OptionKind::Bool, Value::Bool(_)) => true,
                (OptionKind::String, Value::String(_)) => true,
                _ => false,
            };
            assert!(ok, "{n}: listed as {:?} but its default is {v}", o.kind);
            assert!(!o.doc.is_empty(), "{n} has no documentation");
        }
        RunOptions::default().validate().unwrap();
    }

    #[test]
    fn set_get_and_refusals_name_the_option() {
        let mut o = RunOptions::default();
        o.set_option("hex.quality.pillow", OptionValue::Bool(false)).unwrap();
        assert!(!o.hex.quality.pillow);
        o.set_option("hex.map.level", OptionValue::Number(2.0)).unwrap();
        assert_eq!(o.hex.map.level, Some(2));
        assert_eq!(o.option("hex.map.level").unwrap(), OptionValue::Number(2.0));
        o.set_option("hex.map.level", OptionValue::None).unwrap();
        assert_eq!(o.hex.map.level, None);
        o.set_option("polycube.orientations", OptionValue::String("SignFlips".into())).unwrap();
        assert_eq!(o.option("polycube.orientations").unwrap(), OptionValue::String("SignFlips".into()));
        assert_eq!(o.option("hex.map.surface_map").unwrap(), OptionValue::String("Best".into()));
        o.set_option("hex.map.surface_map", OptionValue::String("Charts".into())).unwrap();
        assert_eq!(o.hex.map.surface_map, crate::hex::SurfaceMap::Charts);
        assert!(o.set_option("hex.map.surface_map", OptionValue::String("Nearest".into())).is_err());
        o.set_option("polycube.verify.tau_cd", OptionValue::Number(0.02)).unwrap();
        assert_eq!(o.polycube.verify.tau_cd, 0.02);
        let before = o.clone();
        for (name, value, needle) in [
            ("hex.quality.pilow", OptionValue::Bool(true), "unknown option \"hex.quality.pilow\""),
            ("pillow", OptionValue::Bool(true), "did you mean hex.quality.pillow?"),
            ("hex.quality.pillow", OptionValue::Number(1.0), "option hex.quality.pillow is a bool option, got a number"),
            ("hex.map.level", OptionValue::Number(1.5), "option hex.map.level must be a whole number >= 0, got 1.5"),
            ("hex.map.level", OptionValue::Number(9.0), "option hex.map.level must be a subdivision level in 0..=6, got 9"),
            ("hex.map.min_level", OptionValue::Number(5.0), "option hex.map.min_level must be at most map.max_level (4), got 5"),
            ("hex.goals.hausdorff", OptionValue::Number(f64::NAN), "option hex.goals.hausdorff must be a finite number, got NaN"),
            ("hex.goals.hausdorff", OptionValue::Number(-0.01), "option hex.goals.hausdorff must be"),
            ("polycube.verify.tau_cd", OptionValue::Number(0.0), "option polycube.verify.tau_cd must be a finite number > 0, got 0"),
            ("polycube.orientations", OptionValue::String("Some".into()), "option polycube.orientations does not take that value: unknown variant `Some`"),
            ("auto.resolution", OptionValue::Number(4.0), "option auto.resolution must be between 8 and 256, got 4"),
            ("hex_candidates", OptionValue::Number(0.0), "option hex_candidates must be at least 1, got 0"),
            ("hex.quality.pillow", OptionValue::None, "option hex.quality.pillow cannot be unset"),
            ("hex.map.min_level", OptionValue::Number(5e9), "option hex.map.min_level does not take that value"),
        ] {
            let e = o.set_option(name, value).unwrap_err();
            assert!(matches!(e, Error::InvalidArgument(_)), "{e}");
            assert!(e.to_string().contains(needle), "{name}: {e}");
            assert_eq!(o, before, "a refused value leaves the options as they were");
        }
        // the spline options of a run without a spline stay off unless one is set
        let mut r = RunOptions { spline: None, ..Default::default() };
        r.set_option("hex.quality.pillow", OptionValue::Bool(false)).unwrap();
        assert!(r.spline.is_none());
        r.set_option("spline.fit.enabled", OptionValue::Bool(false)).unwrap();
        assert!(r.spline.is_some_and(|s| !s.fit.enabled));
    }

    #[test]
    fn describe_lists_every_option() {
        let mut o = RunOptions::default();
        o.set_option("hex.quality.pin_uncovered", OptionValue::Number(0.6)).unwrap();
        let d = o.describe_options().unwrap();
        assert_eq!(d.as_object().unwrap().len(), OPTIONS.len());
        let p = &d["hex.quality.pin_uncovered"];
        assert_eq!((p["value"].as_f64(), p["default"].as_f64(), p["type"].as_str()), (Some(0.6), Some(0.0), Some("number")));
        assert_eq!(d["hex.map.level"]["value"], Value::Null);
        assert_eq!(d["hex.map.level"]["nullable"], Value::Bool(true));
        assert_eq!(d["hex_candidates"]["default"], Value::from(4));
    }
}
