//! Model handle (default embedded weights, from a file, from bytes) and polycube
//! generation (user-guided or automated) with its result handle.

use super::context::SddpmContext;
use super::{ffi_boundary, non_null, CProgress, SddpmConstraints, SddpmMesh, SddpmOptions, SddpmProgressCb};
use crate::search::auto::{AutoReport, SplitRatios};
use crate::search::generate::{PolycubeOptions, PolycubeResult, Stage};
use crate::diffusion::{Backend, Model};
use crate::error::{Error, Result, Status};
use crate::pipeline::{generate_polycube, ContextRequest};
use crate::polycube::tensor::NUM_POINTS;
use crate::polycube::NUM_CELLS;
use std::ffi::{c_char, c_void, CStr};

/// An opaque diffusion model (immutable once loaded: one handle may be used by
/// several threads at once).
pub struct SddpmModel {
    pub(crate) model: Model,
}

/// What a model is.
#[repr(C)]
#[derive(Debug, Clone, Copy, Default)]
pub struct SddpmModelInfo {
    pub parameters: usize,
    pub base_width: usize,
    pub diffusion_steps: usize,
    pub trained_epochs: usize,
    pub training_seed: u64,
    pub final_loss: f64,
}

unsafe fn model_ref<'a>(m: *const SddpmModel) -> Result<&'a SddpmModel> {
    non_null(m, "model")?;
    Ok(&*m)
}

/// The model embedded in the library (trained by `sddpm train`, seed 42).
///
/// # Safety
/// `out` a writable handle pointer.
#[no_mangle]
pub unsafe extern "C" fn sddpm_model_new_default(out: *mut *mut SddpmModel) -> Status {
    ffi_boundary! {
        non_null(out, "out")?;
        let model = Model::default_model()?;
        *out = Box::into_raw(Box::new(SddpmModel { model }));
        Ok(())
    }
}

/// A model from a weights file written by `sddpm train`.
///
/// # Safety
/// `path` NUL-terminated; `out` a writable handle pointer.
#[no_mangle]
pub unsafe extern "C" fn sddpm_model_new_from_file(path: *const c_char, out: *mut *mut SddpmModel) -> Status {
    ffi_boundary! {
        non_null(path, "path")?;
        non_null(out, "out")?;
        let p = CStr::from_ptr(path).to_str().map_err(|_| Error::InvalidArgument("path is not UTF-8".into()))?;
        let model = Model::from_file(std::path::Path::new(p), Backend::default())?;
        *out = Box::into_raw(Box::new(SddpmModel { model }));
        Ok(())
    }
}

/// A model from the bytes of a weights file (copied; the caller keeps its buffer).
///
/// # Safety
/// `bytes` points to `len` readable bytes; `out` a writable handle pointer.
#[no_mangle]
pub unsafe extern "C" fn sddpm_model_new_from_bytes(bytes: *const u8, len: usize, out: *mut *mut SddpmModel) -> Status {
    ffi_boundary! {
        non_null(bytes, "bytes")?;
        non_null(out, "out")?;
        let model = Model::from_bytes(std::slice::from_raw_parts(bytes, len), Backend::default())?;
        *out = Box::into_raw(Box::new(SddpmModel { model }));
        Ok(())
    }
}

/// Release a model (NULL is a no-op).
///
/// # Safety
/// `m` NULL or a model handle not used afterwards.
#[no_mangle]
pub unsafe extern "C" fn sddpm_model_free(m: *mut SddpmModel) {
    ffi_boundary! {
        if !m.is_null() {
            drop(Box::from_raw(m));
        }
    }
}

/// Describe a model.
///
/// # Safety
/// `m` a valid handle; `out` writable.
#[no_mangle]
pub unsafe extern "C" fn sddpm_model_get_info(m: *const SddpmModel, out: *mut SddpmModelInfo) -> Status {
    ffi_boundary! {
        let m = model_ref(m)?;
        non_null(out, "out")?;
        let meta = &m.model.meta;
        *out = SddpmModelInfo {
            parameters: m.model.parameter_count(),
            base_width: meta.model.field.as_ref().map_or(meta.model.base_width, |f| f.width),
            diffusion_steps: meta.schedule.steps,
            trained_epochs: meta.training.epochs,
            training_seed: meta.training.seed,
            final_loss: meta.training.final_loss,
        };
        Ok(())
    }
}

/// The result of polycube generation (release with sddpm_polycube_free). Immutable
/// once created: read calls and sddpm_hex_mesh_build may come from several threads
/// at once; freeing it while another thread uses it is not allowed.
pub struct SddpmPolycube {
    pub(crate) result: PolycubeResult,
    pub(crate) auto: Option<AutoReport>,
    pub(crate) error: Option<Error>,
    /// The input surface (what the hex stage maps and the spline fits).
    pub(crate) mesh: crate::mesh::TriMesh,
    /// The options it was generated with (the hex stage lays out the candidates it
    /// adds with their seed).
    pub(crate) options: PolycubeOptions,
}

/// Generate polycube candidates for `mesh` and verify them. The request is, in
/// order of precedence: `contexts` (complete contexts; a context whose genus differs
/// from the mesh's is refused with GENUS_MISMATCH before any diffusion),
/// `constraints` (expanded to every valid context of the mesh's genus), `ratios`
/// (7 doubles X1,X2,X3,Y1,Y2,Z1,Z2: the automated mode on the full grid with these
/// splitting ratios), or the automated mode over every occupied box when all three
/// are NULL. `options` (NULL: the defaults) gives the "polycube.*" and "auto.*"
/// options. Returns OK whenever the search ran, even when no candidate passed:
/// check sddpm_polycube_status, which returns VERIFICATION_FAILED with the reason.
///
/// # Safety
/// `model`, `mesh` valid handles; `contexts`, `constraints`, `ratios`, `options`
/// NULL or valid; `progress` NULL or a valid callback; `out` writable.
#[no_mangle]
pub unsafe extern "C" fn sddpm_generate_polycube(
    model: *const SddpmModel,
    mesh: *const SddpmMesh,
    contexts: *const SddpmContext,
    constraints: *const SddpmConstraints,
    ratios: *const f64,
    options: *const SddpmOptions,
    progress: SddpmProgressCb,
    user_data: *mut c_void,
    out: *mut *mut SddpmPolycube,
) -> Status {
    ffi_boundary! {
        let m = model_ref(model)?;
        non_null(mesh, "mesh")?;
        non_null(out, "out")?;
        let mesh = (*mesh).mesh();
        let report = mesh.validate()?;
        let genus = report.genus.ok_or_else(|| Error::InvalidMesh("the genus of the mesh is undefined".into()))?;
        let run = super::options::run_options(options);
        let (popts, aopts) = (run.polycube, run.auto);
        let request = if !contexts.is_null() {
            ContextRequest::Contexts((*contexts).contexts.clone())
        } else if !constraints.is_null() {
            ContextRequest::Constraints(super::context::constraints_from_c(&*constraints)?)
        } else if !ratios.is_null() {
            let r = std::slice::from_raw_parts(ratios, 7);
            ContextRequest::Ratios(SplitRatios::parse(&format!("{},{},{}:{},{}:{},{}", r[0], r[1], r[2], r[3], r[4], r[5], r[6]))?)
        } else {
            ContextRequest::Auto
        };
        let mut p = CProgress { callback: progress, user_data };
        let (result, auto, error) = generate_polycube(&m.model, mesh, genus, &request, &popts, &aopts, &mut p)?;
        *out = Box::into_raw(Box::new(SddpmPolycube { result, auto, error, mesh: mesh.clone(), options: popts }));
        Ok(())
    }
}

unsafe fn pc_ref<'a>(p: *const SddpmPolycube) -> Result<&'a SddpmPolycube> {
    non_null(p, "polycube")?;
    Ok(&*p)
}

/// Release a polycube result (NULL is a no-op).
///
/// # Safety
/// `p` NULL or a handle from sddpm_generate_polycube, not used afterwards.
#[no_mangle]
pub unsafe extern "C" fn sddpm_polycube_free(p: *mut SddpmPolycube) {
    ffi_boundary! {
        if !p.is_null() {
            drop(Box::from_raw(p));
        }
    }
}

/// OK when a candidate was accepted; VERIFICATION_FAILED (message: which
/// candidates failed where, and what to try) otherwise.
///
/// # Safety
/// `p` a valid handle.
#[no_mangle]
pub unsafe extern "C" fn sddpm_polycube_status(p: *const SddpmPolycube) -> Status {
    ffi_boundary! {
        let p = pc_ref(p)?;
        match &p.error {
            Some(e) => Err(e.clone()),
            None => Ok(()),
        }
    }
}

/// The accepted polycube's 12 labels (capacity >= 12).
///
/// # Safety
/// `p` a valid handle; `labels` points to `capacity` writable ints.
#[no_mangle]
pub unsafe extern "C" fn sddpm_polycube_labels(p: *const SddpmPolycube, labels: *mut i32, capacity: usize) -> Status {
    ffi_boundary! {
        let p = pc_ref(p)?;
        non_null(labels, "labels")?;
        let c = p.result.accepted()?;
        if capacity < NUM_CELLS {
            return Err(Error::BufferTooSmall(format!("labels buffer holds {capacity} values but 12 are needed")));
        }
        for n in 0..NUM_CELLS {
            *labels.add(n) = c.labels[n] as i32;
        }
        Ok(())
    }
}

/// What the verification measured for one candidate.
#[repr(C)]
#[derive(Debug, Clone, Copy, Default)]
pub struct SddpmCandidateReport {
    pub labels: [i32; 12],
    /// 0 pending, 1 refused by the occupancy / fit pre-check, 2 failed GOCC, 3 failed TCV, 4 verified.
    pub stage: i32,
    /// Surface fraction in cells the context leaves empty.
    pub in_empty_fraction: f64,
    /// Geometric fit to the exact polycube (squared cell units).
    pub fit: f64,
    /// Mean PCD to the target templates over active cells (NaN if not diffused).
    pub mean_target_pcd: f64,
    /// Ranking score, lower is better (NaN if not diffused).
    pub score: f64,
    pub chosen: bool,
}

/// Number of candidates.
///
/// # Safety
/// `p` a valid handle; `out` writable.
#[no_mangle]
pub unsafe extern "C" fn sddpm_polycube_candidate_count(p: *const SddpmPolycube, out: *mut usize) -> Status {
    ffi_boundary! {
        let p = pc_ref(p)?;
        non_null(out, "out")?;
        *out = p.result.candidates.len();
        Ok(())
    }
}

/// The report of candidate `index`.
///
/// # Safety
/// `p` a valid handle; `out` writable.
#[no_mangle]
pub unsafe extern "C" fn sddpm_polycube_candidate(p: *const SddpmPolycube, index: usize, out: *mut SddpmCandidateReport) -> Status {
    ffi_boundary! {
        let p = pc_ref(p)?;
        non_null(out, "out")?;
        let c = p.result.candidates.get(index).ok_or_else(|| Error::InvalidArgument(format!("candidate {index} is out of range ({} candidates)", p.result.candidates.len())))?;
        let mut r = SddpmCandidateReport {
            stage: match c.stage { Stage::Pending => 0, Stage::Occupancy => 1, Stage::Gocc => 2, Stage::Tcv => 3, Stage::Verified => 4 },
            in_empty_fraction: c.occupancy.in_empty_cells,
            fit: c.fit,
            mean_target_pcd: c.report.as_ref().map(|r| r.mean_target_pcd).unwrap_or(f64::NAN),
            score: c.score.unwrap_or(f64::NAN),
            chosen: p.result.chosen == Some(index),
            ..Default::default()
        };
        for n in 0..NUM_CELLS {
            r.labels[n] = c.labels[n] as i32;
        }
        *out = r;
        Ok(())
    }
}

/// The full report (every candidate with its per-cell verification, the automated
/// mode's subregions, timings) as JSON, NUL-terminated, into `buf`; `needed` (may be
/// NULL) receives the size including the NUL. BUFFER_TOO_SMALL when it does not fit.
///
/// # Safety
/// `p` a valid handle; `buf` NULL or `len` writable bytes; `needed` NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn sddpm_polycube_report_json(p: *const SddpmPolycube, buf: *mut c_char, len: usize, needed: *mut usize) -> Status {
    ffi_boundary! {
        let p = pc_ref(p)?;
        let v = serde_json::json!({ "result": p.result, "auto": p.auto, "error": p.error.as_ref().map(|e| e.to_string()) });
        let s = serde_json::to_string(&v).map_err(|e| Error::Internal(e.to_string()))?;
        if !needed.is_null() {
            *needed = s.len() + 1;
        }
        if buf.is_null() || len < s.len() + 1 {
            return Err(Error::BufferTooSmall(format!("the report needs {} bytes, the buffer holds {len}", s.len() + 1)));
        }
        std::ptr::copy_nonoverlapping(s.as_ptr() as *const c_char, buf, s.len());
        *buf.add(s.len()) = 0;
        Ok(())
    }
}

/// The accepted candidate's diffusion output and its correspondence, in the user's
/// coordinates: `points` receives 6144 x 3 doubles (the output point of each tensor
/// slot, cell by cell, 512 per cell; null cells hold the images of (0,0,0)) and
/// `inputs` (may be NULL) the input surface point each slot started from (NaN for
/// null cells). Capacities in doubles; BUFFER_TOO_SMALL below 18432.
///
/// # Safety
/// `p` a valid handle; `points` `capacity` writable doubles; `inputs` NULL or the same.
#[no_mangle]
pub unsafe extern "C" fn sddpm_polycube_copy_points(p: *const SddpmPolycube, points: *mut f64, inputs: *mut f64, capacity: usize) -> Status {
    ffi_boundary! {
        let p = pc_ref(p)?;
        non_null(points, "points")?;
        let c = p.result.accepted()?;
        if capacity < 3 * NUM_POINTS {
            return Err(Error::BufferTooSmall(format!("point buffers hold {capacity} values but {} are needed", 3 * NUM_POINTS)));
        }
        let (Some(inp), Some(out)) = (&c.input, &c.output) else { return Err(Error::Internal("accepted candidate without output".into())) };
        let blocks = crate::polycube::tensor::unlayout(out);
        let t = &p.result.alignment.transform;
        for n in 0..NUM_CELLS {
            for k in 0..crate::polycube::tensor::POINTS_PER_CELL {
                let slot = n * crate::polycube::tensor::POINTS_PER_CELL + k;
                let q = blocks[n][k].map(|v| v as f64);
                let u = t.apply_inverse(inp.map.inverse(q));
                for a in 0..3 {
                    *points.add(3 * slot + a) = u[a];
                }
                if !inputs.is_null() {
                    let s = inp.slots[slot].map(|s| t.apply_inverse(s.point)).unwrap_or([f64::NAN; 3]);
                    for a in 0..3 {
                        *inputs.add(3 * slot + a) = s[a];
                    }
                }
            }
        }
        Ok(())
    }
}
