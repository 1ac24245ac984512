//! Hex mesh handle: built from a polycube handle (or from the caller's arrays), its
//! counts, nodes, elements, quality, export to every format, free.

use super::model::SddpmPolycube;
use super::{c_path, copy_slice, copy_string, ffi_boundary, non_null, CProgress, SddpmProgressCb};
use crate::error::{Error, Result, Status};
use crate::hex::quality::{element_qualities, summarize};
use crate::hex::{HexMesh, HexOption, HexOptions, HexResult};
use crate::mesh::TriMesh;
use crate::pipeline::{build_hex_for_polycube, fallback_order, ranked_verified, RunOptions};
use std::ffi::{c_char, c_void};

/// An opaque all-hex mesh with its quality; not thread-safe to free while in use,
/// read-only calls may be made from several threads.
pub struct SddpmHexMesh {
    pub(crate) mesh: HexMesh,
    pub(crate) scaled_jacobian: Vec<f64>,
    /// The full result when built by the pipeline (None for a mesh from arrays).
    pub(crate) result: Option<HexResult>,
    /// The surface the mesh was built for (the spline's default fitting target).
    pub(crate) surface: Option<TriMesh>,
    pub(crate) verified: bool,
}

/// Options of the hex stage; fill with sddpm_hex_options_default, then change fields.
#[repr(C)]
#[derive(Debug, Clone, Copy)]
pub struct SddpmHexOptions {
    /// Fixed octree level, or -1 to choose it by the stopping rule (default -1).
    pub level: i32,
    /// Smallest and largest level the stopping rule may choose (defaults 2 and 4).
    pub min_level: u32,
    pub max_level: u32,
    /// Stopping-rule threshold, fraction of the bounding-box diagonal (default 0.005).
    pub threshold: f64,
    /// Most elements before pillowing (default 200000): caps the automatic level (not
    /// below min_level) and the fallback's lattices.
    pub max_elements: usize,
    /// Dihedral angle in degrees above which an input edge is a feature (default 40).
    pub feature_angle: f64,
    /// One pillow layer (default true).
    pub pillow: bool,
    /// Smoothing passes (default 20) and Jacobian-optimisation passes (default 30).
    pub smooth_iterations: u32,
    pub optimise_passes: u32,
    /// Optimisation works on elements below this scaled Jacobian (default 0.8).
    pub optimise_target: f64,
    /// Candidates meshed (verified ones, else diffused ones by fit); the best mesh is kept (default 4).
    pub hex_candidates: u32,
    /// Mesh the best-fitting diffused candidate when none passed verification (default true).
    pub accept_unverified: bool,
    /// When no candidate's mesh meets the goals below (with a fixed level: when every
    /// one keeps inverted elements), also mesh the input on a voxel lattice and keep
    /// that mesh when it ranks better (default true; the quality then reports
    /// `verified_polycube` false).
    pub voxel_fallback: bool,
    /// Voxels along the longest bounding-box edge of the fallback's first lattice
    /// (default 24; doubled while its topology is wrong, refined while it misses the goals).
    pub voxel_resolution: u32,
    /// Quality goals: minimum and mean scaled Jacobian (defaults 0.3 and 0.85) and the
    /// two-sided Hausdorff distance to the input over the bounding-box diagonal
    /// (default 0.01). Meshes are ranked by inverted elements, then goals missed, then
    /// how far they miss them (sum of the relative misses), then minimum scaled Jacobian.
    pub goal_min_scaled_jacobian: f64,
    pub goal_mean_scaled_jacobian: f64,
    pub goal_hausdorff: f64,
    /// How many finer lattices the fallback may try after its first (default 2; 0:
    /// the first lattice only).
    pub voxel_refinements: u32,
    /// Coverage step: input vertices farther than this fraction of the Hausdorff goal
    /// from the boundary get a boundary node pinned to them (default 0: off; 0.6 was
    /// measured).
    pub pin_uncovered: f64,
    /// Sharp-edge capture steps (after smoothing and after the optimisation):
    /// boundary nodes near the input's sharp edges go onto them (default true).
    pub capture_features: bool,
    /// Local refinement rounds of the fallback: the voxels around the points
    /// farthest from its mesh split 3 x 3 x 3 with conforming transition elements
    /// (default 0: off). ABI 3.
    pub local_refinement: u32,
    /// Feature sheets on the fallback's lattice meshes: a sheet of elements under
    /// each surface patch, the nodes between patches onto the input's sharp curves
    /// (default true; docs/hex.md "Feature sheets"). ABI 4.
    pub feature_sheets: bool,
}

/// Quality summary of a hex mesh.
#[repr(C)]
#[derive(Debug, Clone, Copy, Default)]
pub struct SddpmHexQuality {
    pub elements: usize,
    pub nodes: usize,
    /// Verdict hex scaled Jacobian: minimum, mean, maximum over the elements.
    pub min_scaled_jacobian: f64,
    pub mean_scaled_jacobian: f64,
    pub max_scaled_jacobian: f64,
    /// Elements with scaled Jacobian <= 0.
    pub inverted: usize,
    /// Two-sided Hausdorff distance to the input / bounding-box diagonal (NaN for a mesh from arrays).
    pub hausdorff_relative: f64,
    /// Octree level (-1 for a mesh from arrays).
    pub level: i32,
    /// Volume of the hex mesh and of the input surface (NaN when unknown).
    pub volume: f64,
    pub input_volume: f64,
    /// False when the polycube it was built from did not pass verification.
    pub verified_polycube: bool,
}

/// File formats of sddpm_hex_mesh_write.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SddpmHexFormat {
    /// VTK XML unstructured grid (.vtu) with the cell data "scaled_jacobian".
    Vtu = 0,
    /// Legacy VTK (.vtk), same content.
    VtkLegacy = 1,
    /// Medit (.mesh).
    Medit = 2,
    /// LS-DYNA keyword (*NODE, *ELEMENT_SOLID).
    Lsdyna = 3,
}

unsafe fn hex_ref<'a>(h: *const SddpmHexMesh) -> Result<&'a SddpmHexMesh> {
    non_null(h, "hex mesh")?;
    Ok(&*h)
}

/// Fill `out` with the default hex options.
///
/// # Safety
/// `out` writable.
#[no_mangle]
pub unsafe extern "C" fn sddpm_hex_options_default(out: *mut SddpmHexOptions) -> Status {
    ffi_boundary! {
        non_null(out, "out")?;
        let h = HexOptions::default();
        let r = RunOptions::default();
        *out = SddpmHexOptions {
            level: -1,
            min_level: h.map.min_level,
            max_level: h.map.max_level,
            threshold: h.map.threshold,
            max_elements: h.max_elements,
            feature_angle: h.surface.feature_angle,
            pillow: h.quality.pillow,
            smooth_iterations: h.quality.smooth_iterations as u32,
            optimise_passes: h.quality.optimise_passes as u32,
            optimise_target: h.quality.optimise_target,
            hex_candidates: r.hex_candidates as u32,
            accept_unverified: r.accept_unverified,
            voxel_fallback: h.fallback.enabled,
            voxel_resolution: h.fallback.resolution as u32,
            goal_min_scaled_jacobian: h.goals.min_scaled_jacobian,
            goal_mean_scaled_jacobian: h.goals.mean_scaled_jacobian,
            goal_hausdorff: h.goals.hausdorff,
            voxel_refinements: h.fallback.refinements as u32,
            pin_uncovered: h.quality.pin_uncovered,
            capture_features: h.quality.capture_features,
            local_refinement: h.fallback.local_refinement as u32,
            feature_sheets: h.quality.feature_sheets,
        };
        Ok(())
    }
}

/// The core options of the C options (None: the defaults), checked by
/// [`HexOptions::validate`] with the bad option named by its C field; with the
/// run's `hex_candidates` and `accept_unverified`.
fn hex_options(o: Option<&SddpmHexOptions>) -> Result<(HexOptions, usize, bool)> {
    let mut h = HexOptions::default();
    let r = RunOptions::default();
    let Some(o) = o else { return Ok((h, r.hex_candidates, r.accept_unverified)) };
    if o.level < -1 {
        return Err(Error::InvalidArgument(format!("hex options: level must be -1 (automatic) or a subdivision level in 0..=6, got {}", o.level)));
    }
    h.map.level = (o.level >= 0).then_some(o.level as u32);
    h.map.min_level = o.min_level;
    h.map.max_level = o.max_level;
    h.map.threshold = o.threshold;
    h.max_elements = o.max_elements;
    h.surface.feature_angle = o.feature_angle;
    h.quality.pillow = o.pillow;
    h.quality.smooth_iterations = o.smooth_iterations as usize;
    h.quality.optimise_passes = o.optimise_passes as usize;
    h.quality.optimise_target = o.optimise_target;
    h.quality.pin_uncovered = o.pin_uncovered;
    h.quality.capture_features = o.capture_features;
    h.quality.feature_sheets = o.feature_sheets;
    h.fallback.enabled = o.voxel_fallback;
    h.fallback.resolution = o.voxel_resolution as usize;
    h.fallback.refinements = o.voxel_refinements as usize;
    h.fallback.local_refinement = o.local_refinement as usize;
    h.goals = crate::hex::QualityGoals {
        min_scaled_jacobian: o.goal_min_scaled_jacobian,
        mean_scaled_jacobian: o.goal_mean_scaled_jacobian,
        hausdorff: o.goal_hausdorff,
    };
    h.validate().map_err(|e| Error::InvalidArgument(format!("hex options: {} must be {}, got {}", c_field(e.option), e.expected, e.value)))?;
    Ok((h, (o.hex_candidates as usize).max(1), o.accept_unverified))
}

/// The field of sddpm_hex_options that sets a hex option (the core's path for
/// the options the C struct leaves at their defaults).
fn c_field(o: HexOption) -> &'static str {
    match o {
        HexOption::Level => "level",
        HexOption::MinLevel => "min_level",
        HexOption::MaxLevel => "max_level",
        HexOption::Threshold => "threshold",
        HexOption::FeatureAngle => "feature_angle",
        HexOption::OptimiseTarget => "optimise_target",
        HexOption::PinUncovered => "pin_uncovered",
        HexOption::VoxelResolution => "voxel_resolution",
        HexOption::GoalMinScaledJacobian => "goal_min_scaled_jacobian",
        HexOption::GoalMeanScaledJacobian => "goal_mean_scaled_jacobian",
        HexOption::GoalHausdorff => "goal_hausdorff",
        HexOption::MaxElements => "max_elements",
        other => other.path(),
    }
}

/// Build the all-hex mesh of a polycube result: the best of its verified candidates
/// (up to `hex_candidates`, best score first; fewest inverted elements, then highest
/// minimum scaled Jacobian), in the input's coordinates. Without a verified candidate:
/// the best of up to `hex_candidates` diffused ones, best geometric fit first, when
/// `accept_unverified` (the quality reports `verified_polycube` false), else the
/// polycube's VERIFICATION_FAILED.
///
/// # Safety
/// `polycube` a valid handle; `options` NULL (defaults) or valid; `progress` NULL or a
/// valid callback; `out` writable.
#[no_mangle]
pub unsafe extern "C" fn sddpm_hex_mesh_build(
    polycube: *const SddpmPolycube,
    options: *const SddpmHexOptions,
    progress: SddpmProgressCb,
    user_data: *mut c_void,
    out: *mut *mut SddpmHexMesh,
) -> Status {
    ffi_boundary! {
        non_null(polycube, "polycube")?;
        non_null(out, "out")?;
        let pc = &*polycube;
        let (mut hopts, n, accept) = hex_options(options.as_ref())?;
        let mut result = std::borrow::Cow::Borrowed(&pc.result);
        let (order, verified) = if pc.result.chosen.is_some() {
            let mut o = ranked_verified(&pc.result);
            o.truncate(n);
            (o, true)
        } else {
            let refusal = || pc.result.accepted().err().unwrap_or_else(|| Error::VerificationFailed("no candidate".into()));
            if !accept {
                return Err(refusal());
            }
            hopts.map.use_correspondence = false;
            let r = result.to_mut();
            let genus = r.input_genus;
            let o = fallback_order(r, &pc.mesh, &pc.options, genus, n);
            if o.is_empty() {
                return Err(refusal());
            }
            (o, false)
        };
        let mut p = CProgress { callback: progress, user_data };
        let (_, _, r) = build_hex_for_polycube(&result, &order, &pc.mesh, &hopts, &mut p)?;
        let verified = verified && r.from_polycube();
        *out = Box::into_raw(Box::new(SddpmHexMesh {
            mesh: r.mesh.clone(),
            scaled_jacobian: r.scaled_jacobian.clone(),
            result: Some(r),
            surface: Some(pc.mesh.clone()),
            verified,
        }));
        Ok(())
    }
}

/// A hex mesh from the caller's arrays: `xyz` 3 doubles per node (`n_nodes`), `conn`
/// 8 node indices per element (`n_elements`, VTK_HEXAHEDRON order, 0-based). An index
/// out of range or a non-finite coordinate is refused naming the element / node.
///
/// # Safety
/// `xyz` 3 * n_nodes readable doubles; `conn` 8 * n_elements readable ints; `out` writable.
#[no_mangle]
pub unsafe extern "C" fn sddpm_hex_mesh_new_from_arrays(
    xyz: *const f64,
    n_nodes: usize,
    conn: *const u32,
    n_elements: usize,
    out: *mut *mut SddpmHexMesh,
) -> Status {
    ffi_boundary! {
        non_null(xyz, "xyz")?;
        non_null(conn, "conn")?;
        non_null(out, "out")?;
        if n_elements == 0 {
            return Err(Error::InvalidArgument("a hex mesh needs at least one element".into()));
        }
        let x = std::slice::from_raw_parts(xyz, 3 * n_nodes);
        let c = std::slice::from_raw_parts(conn, 8 * n_elements);
        let nodes: Vec<[f64; 3]> = x.chunks_exact(3).map(|p| [p[0], p[1], p[2]]).collect();
        if let Some(i) = nodes.iter().position(|p| p.iter().any(|v| !v.is_finite())) {
            return Err(Error::InvalidArgument(format!("node {i} has a non-finite coordinate")));
        }
        let mut elements = Vec::with_capacity(n_elements);
        for (e, ch) in c.chunks_exact(8).enumerate() {
            let el: [u32; 8] = std::array::from_fn(|k| ch[k]);
            if let Some(&bad) = el.iter().find(|&&v| v as usize >= n_nodes) {
                return Err(Error::InvalidArgument(format!("element {e} refers to node {bad} but there are {n_nodes} nodes")));
            }
            elements.push(el);
        }
        let mesh = HexMesh { nodes, elements };
        let scaled_jacobian = element_qualities(&mesh);
        *out = Box::into_raw(Box::new(SddpmHexMesh { mesh, scaled_jacobian, result: None, surface: None, verified: true }));
        Ok(())
    }
}

/// Release a hex mesh (NULL is a no-op).
///
/// # Safety
/// `h` NULL or a handle from sddpm_hex_mesh_build / _new_from_arrays, not used afterwards.
#[no_mangle]
pub unsafe extern "C" fn sddpm_hex_mesh_free(h: *mut SddpmHexMesh) {
    ffi_boundary! {
        if !h.is_null() {
            drop(Box::from_raw(h));
        }
    }
}

/// Node and element counts.
///
/// # Safety
/// `h` a valid handle; `nodes`, `elements` writable.
#[no_mangle]
pub unsafe extern "C" fn sddpm_hex_mesh_counts(h: *const SddpmHexMesh, nodes: *mut usize, elements: *mut usize) -> Status {
    ffi_boundary! {
        let h = hex_ref(h)?;
        non_null(nodes, "nodes")?;
        non_null(elements, "elements")?;
        *nodes = h.mesh.nodes.len();
        *elements = h.mesh.elements.len();
        Ok(())
    }
}

/// Copy the node coordinates (3 doubles per node, user coordinates); `capacity` in doubles.
///
/// # Safety
/// `h` a valid handle; `xyz` `capacity` writable doubles.
#[no_mangle]
pub unsafe extern "C" fn sddpm_hex_mesh_copy_nodes(h: *const SddpmHexMesh, xyz: *mut f64, capacity: usize) -> Status {
    ffi_boundary! {
        let h = hex_ref(h)?;
        let flat: Vec<f64> = h.mesh.nodes.iter().flatten().copied().collect();
        copy_slice(&flat, xyz, capacity, "xyz")
    }
}

/// Copy the connectivity (8 node indices per element, VTK_HEXAHEDRON order, 0-based);
/// `capacity` in indices.
///
/// # Safety
/// `h` a valid handle; `conn` `capacity` writable ints.
#[no_mangle]
pub unsafe extern "C" fn sddpm_hex_mesh_copy_elements(h: *const SddpmHexMesh, conn: *mut u32, capacity: usize) -> Status {
    ffi_boundary! {
        let h = hex_ref(h)?;
        let flat: Vec<u32> = h.mesh.elements.iter().flatten().copied().collect();
        copy_slice(&flat, conn, capacity, "conn")
    }
}

/// The per-element Verdict scaled Jacobian; `capacity` in doubles.
///
/// # Safety
/// `h` a valid handle; `values` `capacity` writable doubles.
#[no_mangle]
pub unsafe extern "C" fn sddpm_hex_mesh_copy_scaled_jacobian(h: *const SddpmHexMesh, values: *mut f64, capacity: usize) -> Status {
    ffi_boundary! {
        let h = hex_ref(h)?;
        copy_slice(&h.scaled_jacobian, values, capacity, "values")
    }
}

/// Histogram of the scaled Jacobian: `bins` equal bins over [-1, 1] into `counts`.
///
/// # Safety
/// `h` a valid handle; `counts` `bins` writable values.
#[no_mangle]
pub unsafe extern "C" fn sddpm_hex_mesh_histogram(h: *const SddpmHexMesh, counts: *mut usize, bins: usize) -> Status {
    ffi_boundary! {
        let h = hex_ref(h)?;
        non_null(counts, "counts")?;
        if bins == 0 || bins > 100_000 {
            return Err(Error::InvalidArgument(format!("bins must be 1..100000, got {bins}")));
        }
        let mut v = vec![0usize; bins];
        for &q in &h.scaled_jacobian {
            let q = if q.is_finite() { q.clamp(-1.0, 1.0) } else { -1.0 };
            let b = (((q + 1.0) / 2.0) * bins as f64).floor() as usize;
            v[b.min(bins - 1)] += 1;
        }
        std::ptr::copy_nonoverlapping(v.as_ptr(), counts, bins);
        Ok(())
    }
}

/// The quality summary.
///
/// # Safety
/// `h` a valid handle; `out` writable.
#[no_mangle]
pub unsafe extern "C" fn sddpm_hex_mesh_quality(h: *const SddpmHexMesh, out: *mut SddpmHexQuality) -> Status {
    ffi_boundary! {
        let h = hex_ref(h)?;
        non_null(out, "out")?;
        let q = summarize(&h.scaled_jacobian);
        let (haus, level, vol, ivol) = match &h.result {
            Some(r) => (r.hausdorff_relative, r.level as i32, r.volume, r.input_volume),
            None => (f64::NAN, -1, crate::hex::topology::mesh_volume(&h.mesh), f64::NAN),
        };
        *out = SddpmHexQuality {
            elements: q.elements,
            nodes: h.mesh.nodes.len(),
            min_scaled_jacobian: q.min,
            mean_scaled_jacobian: q.mean,
            max_scaled_jacobian: q.max,
            inverted: q.inverted,
            hausdorff_relative: haus,
            level,
            volume: vol,
            input_volume: ivol,
            verified_polycube: h.verified,
        };
        Ok(())
    }
}

/// The hex stage's report (report.json's "hex" object) as JSON; buffer convention of
/// sddpm_polycube_report_json.
///
/// # Safety
/// `h` a valid handle; `buf` NULL or `len` writable bytes; `needed` NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn sddpm_hex_mesh_report_json(h: *const SddpmHexMesh, buf: *mut c_char, len: usize, needed: *mut usize) -> Status {
    ffi_boundary! {
        let h = hex_ref(h)?;
        let v = match &h.result {
            Some(r) => crate::hex::report_json(r),
            None => {
                let q = summarize(&h.scaled_jacobian);
                serde_json::json!({ "vertices": h.mesh.nodes.len(), "elements": h.mesh.elements.len(),
                    "min_scaled_jacobian": q.min, "mean_scaled_jacobian": q.mean, "inverted": q.inverted })
            }
        };
        copy_string(&v.to_string(), buf, len, needed, "the report")
    }
}

/// Write the mesh (user coordinates) to `path` in `format` (an SddpmHexFormat value).
///
/// # Safety
/// `h` a valid handle; `path` NUL-terminated.
#[no_mangle]
pub unsafe extern "C" fn sddpm_hex_mesh_write(h: *const SddpmHexMesh, path: *const c_char, format: i32) -> Status {
    ffi_boundary! {
        let h = hex_ref(h)?;
        let p = c_path(path, "path")?;
        let sj: &[f64] = &h.scaled_jacobian;
        match format {
            f if f == SddpmHexFormat::Vtu as i32 => crate::export::hexfmt::write_vtu(&p, &h.mesh, &[("scaled_jacobian", sj)]),
            f if f == SddpmHexFormat::VtkLegacy as i32 => crate::export::vtk::write_vtk_legacy(&p, &h.mesh, "sddpm hex mesh", &[("scaled_jacobian", sj)]),
            f if f == SddpmHexFormat::Medit as i32 => crate::export::hexfmt::write_medit(&p, &h.mesh),
            f if f == SddpmHexFormat::Lsdyna as i32 => crate::export::hexfmt::write_lsdyna(&p, &h.mesh, "sddpm hex mesh"),
            f => Err(Error::InvalidArgument(format!("format {f} is not an sddpm_hex_format (0 VTU, 1 legacy VTK, 2 Medit, 3 LS-DYNA)"))),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The C defaults are the core's, and goals that cannot be compared are refused
    /// with the values named.
    #[test]
    fn hex_options_round_trip_and_bad_goals() {
        let mut o = std::mem::MaybeUninit::<SddpmHexOptions>::uninit();
        assert_eq!(unsafe { sddpm_hex_options_default(o.as_mut_ptr()) }, Status::Ok);
        let o = unsafe { o.assume_init() };
        let (h, _, _) = hex_options(Some(&o)).unwrap();
        assert_eq!(h.goals, crate::hex::QualityGoals::default());
        assert_eq!(h, HexOptions::default());
        for (bad, field) in [
            (SddpmHexOptions { goal_hausdorff: f64::NAN, ..o }, "goal_hausdorff"),
            (SddpmHexOptions { goal_hausdorff: -0.01, ..o }, "goal_hausdorff"),
            (SddpmHexOptions { goal_mean_scaled_jacobian: f64::INFINITY, ..o }, "goal_mean_scaled_jacobian"),
            (SddpmHexOptions { max_elements: 0, ..o }, "max_elements"),
            (SddpmHexOptions { min_level: 5, ..o }, "min_level"),
            (SddpmHexOptions { level: -2, ..o }, "level"),
        ] {
            let e = hex_options(Some(&bad)).unwrap_err().to_string();
            assert!(e.contains(&format!("hex options: {field} must be")), "{e}");
        }
        let e = hex_options(Some(&SddpmHexOptions { voxel_resolution: 1, ..o })).unwrap_err().to_string();
        assert!(e.contains("voxel_resolution must be between 2 and 192, got 1"), "{e}");
        let (h, _, _) = hex_options(Some(&SddpmHexOptions { voxel_refinements: 0, pin_uncovered: 0.6, capture_features: false, local_refinement: 3, feature_sheets: false, ..o })).unwrap();
        assert_eq!((h.fallback.refinements, h.quality.pin_uncovered, h.quality.capture_features, h.fallback.local_refinement, h.quality.feature_sheets), (0, 0.6, false, 3, false));
        assert_eq!((o.local_refinement, o.feature_sheets), (0, true));
        assert_eq!((o.voxel_refinements as usize, o.pin_uncovered, o.capture_features), (HexOptions::default().fallback.refinements, 0.0, true));
        for bad in [f64::NAN, -0.1, f64::INFINITY] {
            let e = hex_options(Some(&SddpmHexOptions { pin_uncovered: bad, ..o })).unwrap_err().to_string();
            assert!(e.contains("pin_uncovered"), "{e}");
        }
    }
}
