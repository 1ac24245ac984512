//! Hex mesh handle: built from a polycube handle (or from the caller's arrays), its
//! counts, nodes, elements, quality, export to every format, free.

use super::model::SddpmPolycube;
use super::options::run_options;
use super::{c_path, copy_slice, copy_string, ffi_boundary, non_null, CProgress, SddpmOptions, SddpmProgressCb};
use crate::error::{Error, Result, Status};
use crate::hex::quality::{element_qualities, summarize};
use crate::hex::{HexMesh, HexResult};
use crate::mesh::TriMesh;
use crate::pipeline::mesh_polycube;
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

/// Build the all-hex mesh of a polycube result, in the input's coordinates, as the
/// main job does (one rule for the command line, this call and the Python
/// package): up to "hex_candidates" candidates are meshed, the verified ones best
/// score first, then (with "accept_unverified") unverified ones by geometric fit;
/// the best mesh is kept (fewest inverted elements, then fewest quality goals
/// missed, then highest minimum scaled Jacobian), and when none meets the goals
/// the grid-based fallback ("hex.fallback.enabled") is meshed too and kept when it
/// ranks better (the quality then reports `verified_polycube` false). Without a
/// verified candidate and with "accept_unverified" false: the polycube's
/// VERIFICATION_FAILED; with "require_valid_hex": MESHING_FAILED for a mesh that
/// keeps inverted elements. `options` (NULL: the defaults) gives the "hex.*" options
/// and those three; the polycube's own options are the ones it was generated with.
/// Progress over 0-1.
///
/// # Safety
/// `polycube` a valid handle; `options` NULL (defaults) or valid; `progress` NULL or a
/// valid callback; `out` writable.
#[no_mangle]
pub unsafe extern "C" fn sddpm_hex_mesh_build(
    polycube: *const SddpmPolycube,
    options: *const SddpmOptions,
    progress: SddpmProgressCb,
    user_data: *mut c_void,
    out: *mut *mut SddpmHexMesh,
) -> Status {
    ffi_boundary! {
        non_null(polycube, "polycube")?;
        non_null(out, "out")?;
        let pc = &*polycube;
        let mut opts = run_options(options);
        opts.polycube = pc.options.clone();
        // the handle is shared: the candidates the order lays out go into a copy
        let mut result = pc.result.clone();
        let mut p = CProgress { callback: progress, user_data };
        let stage = mesh_polycube(&mut result, pc.error.clone(), &pc.mesh, &opts, &mut p)?;
        let r = stage.hex;
        *out = Box::into_raw(Box::new(SddpmHexMesh {
            mesh: r.mesh.clone(),
            scaled_jacobian: r.scaled_jacobian.clone(),
            result: Some(r),
            surface: Some(pc.mesh.clone()),
            verified: stage.verified,
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
                let irregular = crate::hex::topology::irregular_edges(&h.mesh);
                serde_json::json!({ "vertices": h.mesh.nodes.len(), "elements": h.mesh.elements.len(),
                    "min_scaled_jacobian": q.min, "mean_scaled_jacobian": q.mean, "inverted": q.inverted,
                    "irregular_edges": irregular.total(), "irregular_edges_interior": irregular.interior,
                    "irregular_edges_boundary": irregular.boundary })
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
