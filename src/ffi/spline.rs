//! Spline handle: TH-spline3D built from a hex mesh handle, its Bézier extraction,
//! evaluation of the map and its Jacobian, export (BEXT, LS-DYNA deck, VTK), free.

use super::hex::SddpmHexMesh;
use super::mesh::SddpmMesh;
use super::{c_path, copy_string, ffi_boundary, non_null, CProgress, SddpmOptions, SddpmProgressCb};
use crate::error::{Error, Result, Status};
use crate::export::spline_files::OutputOptions;
use crate::spline::{build_spline, Spline};
use std::ffi::{c_char, c_void};

/// An opaque volumetric spline (read-only calls may come from several threads).
pub struct SddpmSpline {
    pub(crate) spline: Spline,
}

unsafe fn sp_ref<'a>(s: *const SddpmSpline) -> Result<&'a SddpmSpline> {
    non_null(s, "spline")?;
    Ok(&*s)
}

/// Build the spline of a hex mesh. The boundary is fitted to `surface` when given,
/// else to the surface the hex mesh was built for (none for a mesh from arrays).
/// `options` (NULL: the defaults) gives the "spline.*" options.
///
/// # Safety
/// `hex` a valid handle; `surface`, `options` NULL or valid; `progress` NULL or a valid
/// callback; `out` writable.
#[no_mangle]
pub unsafe extern "C" fn sddpm_spline_build(
    hex: *const SddpmHexMesh,
    surface: *const SddpmMesh,
    options: *const SddpmOptions,
    progress: SddpmProgressCb,
    user_data: *mut c_void,
    out: *mut *mut SddpmSpline,
) -> Status {
    ffi_boundary! {
        non_null(hex, "hex mesh")?;
        non_null(out, "out")?;
        let h = &*hex;
        let opts = super::options::run_options(options).spline.unwrap_or_default();
        let surf = if surface.is_null() { h.surface.as_ref() } else { Some((*surface).mesh()) };
        let mut p = CProgress { callback: progress, user_data };
        let spline = build_spline(&h.mesh, surf, &opts, &mut p)?;
        *out = Box::into_raw(Box::new(SddpmSpline { spline }));
        Ok(())
    }
}

/// Release a spline (NULL is a no-op).
///
/// # Safety
/// `s` NULL or a handle from sddpm_spline_build, not used afterwards.
#[no_mangle]
pub unsafe extern "C" fn sddpm_spline_free(s: *mut SddpmSpline) {
    ffi_boundary! {
        if !s.is_null() {
            drop(Box::from_raw(s));
        }
    }
}

/// Element (Bézier cell) and basis-function counts.
///
/// # Safety
/// `s` a valid handle; `elements`, `basis_functions` writable.
#[no_mangle]
pub unsafe extern "C" fn sddpm_spline_counts(s: *const SddpmSpline, elements: *mut usize, basis_functions: *mut usize) -> Status {
    ffi_boundary! {
        let s = sp_ref(s)?;
        non_null(elements, "elements")?;
        non_null(basis_functions, "basis_functions")?;
        *elements = s.spline.num_elements();
        *basis_functions = s.spline.num_basis();
        Ok(())
    }
}

/// Bézier extraction of `element`: `n_basis` receives how many global basis functions
/// are non-zero on it; `basis_ids` (capacity >= n_basis) their ids and `operator`
/// (capacity >= 64 * n_basis doubles) the dense extraction rows, row r holding the
/// coefficients of basis_ids[r] on the 64 Bernstein polynomials (index i + 4j + 16k,
/// u fastest). Call with NULL buffers and capacity 0 to ask for `n_basis` only
/// (returns BUFFER_TOO_SMALL then, with `n_basis` written).
///
/// # Safety
/// `s` a valid handle; `basis_ids` NULL or `capacity` writable ints; `operator` NULL or
/// 64 * `capacity` writable doubles; `n_basis` writable.
#[no_mangle]
pub unsafe extern "C" fn sddpm_spline_element_extraction(
    s: *const SddpmSpline,
    element: usize,
    basis_ids: *mut u32,
    operator: *mut f64,
    capacity: usize,
    n_basis: *mut usize,
) -> Status {
    ffi_boundary! {
        let s = sp_ref(s)?;
        non_null(n_basis, "n_basis")?;
        let ne = s.spline.num_elements();
        if element >= ne {
            return Err(Error::InvalidArgument(format!("element {element} does not exist (the spline has {ne})")));
        }
        let ids = s.spline.element_basis(element)?;
        *n_basis = ids.len();
        if basis_ids.is_null() || operator.is_null() || capacity < ids.len() {
            return Err(Error::BufferTooSmall(format!("element {element} has {} basis functions, the buffers hold {capacity}", ids.len())));
        }
        let op = s.spline.extraction_operator(element)?;
        std::ptr::copy_nonoverlapping(ids.as_ptr(), basis_ids, ids.len());
        std::ptr::copy_nonoverlapping(op.as_ptr(), operator, op.len());
        Ok(())
    }
}

/// The spline map at parameters (u, v, w) in [0, 1]^3 of `element`: `xyz` (3 doubles)
/// and, if `jacobian` is not NULL, its Jacobian (9 doubles, row-major d x_i / d u_j).
///
/// # Safety
/// `s` a valid handle; `xyz` 3 writable doubles; `jacobian` NULL or 9 writable doubles.
#[no_mangle]
pub unsafe extern "C" fn sddpm_spline_evaluate(s: *const SddpmSpline, element: usize, u: f64, v: f64, w: f64, xyz: *mut f64, jacobian: *mut f64) -> Status {
    ffi_boundary! {
        let s = sp_ref(s)?;
        non_null(xyz, "xyz")?;
        let (x, j) = s.spline.evaluate(element, u, v, w)?;
        std::ptr::copy_nonoverlapping(x.as_ptr(), xyz, 3);
        if !jacobian.is_null() {
            for r in 0..3 {
                for c in 0..3 {
                    *jacobian.add(3 * r + c) = j[r][c];
                }
            }
        }
        Ok(())
    }
}

/// Write spline.bext, model.k (the LS-DYNA deck including it), spline.vtu and
/// spline_control.vtk into the folder `dir` (created if missing).
///
/// # Safety
/// `s` a valid handle; `dir` NUL-terminated.
#[no_mangle]
pub unsafe extern "C" fn sddpm_spline_write(s: *const SddpmSpline, dir: *const c_char) -> Status {
    ffi_boundary! {
        let s = sp_ref(s)?;
        let d = c_path(dir, "dir")?;
        crate::export::spline_files::write_outputs(&d, &s.spline, &OutputOptions::default()).map(|_| ())
    }
}

/// The spline's report (report.json's "spline" object without file names) as JSON;
/// buffer convention of sddpm_polycube_report_json.
///
/// # Safety
/// `s` a valid handle; `buf` NULL or `len` writable bytes; `needed` NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn sddpm_spline_report_json(s: *const SddpmSpline, buf: *mut c_char, len: usize, needed: *mut usize) -> Status {
    ffi_boundary! {
        let s = sp_ref(s)?;
        let v = serde_json::to_string(s.spline.report()).map_err(|e| Error::Internal(e.to_string()))?;
        copy_string(&v, buf, len, needed, "the report")
    }
}
