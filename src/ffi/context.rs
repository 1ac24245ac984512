//! Context handle: a stack of one or more 12-cell contexts, made from labels,
//! one-hot vectors or partial constraints.

use super::{ffi_boundary, non_null};
use crate::context::{Constraints, Context};
use crate::error::{Error, Result, Status};
use crate::polycube::{Primitive, CONTEXT_DIM, NUM_CELLS, NUM_LABELS};
use std::ffi::{c_char, CStr};

/// An opaque stack of contexts (release with sddpm_context_free). Immutable once
/// created: calls that take it may come from several threads at once; freeing it
/// while another thread uses it is not allowed.
pub struct SddpmContext {
    pub(crate) contexts: Vec<Context>,
}

/// Partial constraints: counts per family (-1 = free), optional exact counts per
/// label (index = label 0..10, -1 = free; entry 0 is ignored), the cells that may be
/// occupied and those that must be (bit n = cell n), and a genus filter (-1 = none).
#[repr(C)]
#[derive(Debug, Clone, Copy)]
pub struct SddpmConstraints {
    pub cube: i32,
    pub thc: i32,
    pub bhc: i32,
    pub per_label: [i32; 11],
    pub allowed_mask: u16,
    pub required_mask: u16,
    pub genus: i64,
}

unsafe fn ctx_ref<'a>(c: *const SddpmContext) -> Result<&'a SddpmContext> {
    non_null(c, "context")?;
    Ok(&*c)
}

fn pick(c: &SddpmContext, index: usize) -> Result<&Context> {
    c.contexts.get(index).ok_or_else(|| Error::InvalidArgument(format!("context index {index} is out of range (the stack holds {})", c.contexts.len())))
}

fn handle(contexts: Vec<Context>) -> *mut SddpmContext {
    Box::into_raw(Box::new(SddpmContext { contexts }))
}

/// Fill `out` with unconstrained constraints (all counts free, every cell allowed).
///
/// # Safety
/// `out` must point to one writable struct.
#[no_mangle]
pub unsafe extern "C" fn sddpm_constraints_default(out: *mut SddpmConstraints) -> Status {
    ffi_boundary! {
        non_null(out, "out")?;
        *out = SddpmConstraints { cube: -1, thc: -1, bhc: -1, per_label: [-1; 11], allowed_mask: 0x0fff, required_mask: 0, genus: -1 };
        Ok(())
    }
}

/// Contexts from `count` integer labels (a multiple of 12, cell-index order; each 0..10).
///
/// # Safety
/// `labels` points to `count` values; `out` to a writable handle pointer.
#[no_mangle]
pub unsafe extern "C" fn sddpm_context_new_from_labels(labels: *const i32, count: usize, out: *mut *mut SddpmContext) -> Status {
    ffi_boundary! {
        non_null(labels, "labels")?;
        non_null(out, "out")?;
        if count == 0 || count % NUM_CELLS != 0 {
            return Err(Error::InvalidContext(format!("labels come 12 per context; got {count}")));
        }
        let v = std::slice::from_raw_parts(labels, count);
        let mut cs = Vec::with_capacity(count / NUM_CELLS);
        for (i, chunk) in v.chunks(NUM_CELLS).enumerate() {
            let l: Vec<i64> = chunk.iter().map(|&x| x as i64).collect();
            cs.push(Context::from_labels(&l).map_err(|e| match e {
                Error::InvalidContext(m) => Error::InvalidContext(format!("context {i}: {m}")),
                o => o,
            })?);
        }
        *out = handle(cs);
        Ok(())
    }
}

/// Contexts from a comma-separated label string ("cube,THC+Z,0,..."), several separated by ';'.
///
/// # Safety
/// `text` a NUL-terminated string; `out` a writable handle pointer.
#[no_mangle]
pub unsafe extern "C" fn sddpm_context_new_from_string(text: *const c_char, out: *mut *mut SddpmContext) -> Status {
    ffi_boundary! {
        non_null(text, "text")?;
        non_null(out, "out")?;
        let s = CStr::from_ptr(text).to_str().map_err(|_| Error::InvalidArgument("text is not UTF-8".into()))?;
        let cs: Vec<Context> = s.split(';').filter(|p| !p.trim().is_empty()).map(Context::parse).collect::<Result<_>>()?;
        if cs.is_empty() {
            return Err(Error::InvalidContext("no context in the text".into()));
        }
        *out = handle(cs);
        Ok(())
    }
}

/// Contexts from `len` floats: n stacked 132-vectors (12 cells x 11 states, one-hot
/// per cell). A non-one-hot cell is refused with a message naming it.
///
/// # Safety
/// `v` points to `len` floats; `out` a writable handle pointer.
#[no_mangle]
pub unsafe extern "C" fn sddpm_context_new_from_one_hot(v: *const f32, len: usize, out: *mut *mut SddpmContext) -> Status {
    ffi_boundary! {
        non_null(v, "v")?;
        non_null(out, "out")?;
        let cs = Context::batch_from_one_hot(std::slice::from_raw_parts(v, len))?;
        *out = handle(cs);
        Ok(())
    }
}

/// Every valid context satisfying the constraints (sorted, deduplicated).
/// INVALID_CONTEXT when none does.
///
/// # Safety
/// `c` points to one struct; `out` a writable handle pointer.
#[no_mangle]
pub unsafe extern "C" fn sddpm_context_new_from_constraints(c: *const SddpmConstraints, out: *mut *mut SddpmContext) -> Status {
    ffi_boundary! {
        non_null(c, "constraints")?;
        non_null(out, "out")?;
        let cs = constraints_from_c(&*c)?.enumerate()?;
        if cs.is_empty() {
            return Err(Error::InvalidContext("no valid context satisfies the constraints".into()));
        }
        *out = handle(cs);
        Ok(())
    }
}

/// The library's constraints from the C struct.
pub(crate) fn constraints_from_c(c: &SddpmConstraints) -> Result<Constraints> {
        let free = |x: i32| -> Result<Option<usize>> {
            if x < -1 { Err(Error::InvalidArgument(format!("count {x} is negative (use -1 for free)"))) } else { Ok((x >= 0).then_some(x as usize)) }
        };
        let mut labels = std::collections::BTreeMap::new();
        for l in 1..NUM_LABELS {
            if let Some(n) = free(c.per_label[l])? {
                labels.insert(Primitive::ALL[l].name().to_string(), n);
            }
        }
        let cells = |m: u16| (0..NUM_CELLS).filter(|&n| m >> n & 1 == 1).collect::<Vec<_>>();
        if c.allowed_mask >> NUM_CELLS != 0 || c.required_mask >> NUM_CELLS != 0 {
            return Err(Error::InvalidArgument("cell masks use bits 0..11 only".into()));
        }
        Ok(Constraints {
            cube: free(c.cube)?,
            thc: free(c.thc)?,
            bhc: free(c.bhc)?,
            labels,
            allowed: Some(cells(c.allowed_mask)),
            required: cells(c.required_mask),
            genus: (c.genus >= 0).then_some(c.genus),
        })
}

/// Release a context handle (NULL is a no-op).
///
/// # Safety
/// `c` NULL or a handle from a sddpm_context_new_* call, not used afterwards.
#[no_mangle]
pub unsafe extern "C" fn sddpm_context_free(c: *mut SddpmContext) {
    ffi_boundary! {
        if !c.is_null() {
            drop(Box::from_raw(c));
        }
    }
}

/// Number of contexts in the stack.
///
/// # Safety
/// `c` a valid handle; `out` writable.
#[no_mangle]
pub unsafe extern "C" fn sddpm_context_count(c: *const SddpmContext, out: *mut usize) -> Status {
    ffi_boundary! {
        let c = ctx_ref(c)?;
        non_null(out, "out")?;
        *out = c.contexts.len();
        Ok(())
    }
}

/// Copy the 12 labels of context `index` into `labels` (capacity >= 12).
///
/// # Safety
/// `c` a valid handle; `labels` points to `capacity` writable ints.
#[no_mangle]
pub unsafe extern "C" fn sddpm_context_get_labels(c: *const SddpmContext, index: usize, labels: *mut i32, capacity: usize) -> Status {
    ffi_boundary! {
        let c = ctx_ref(c)?;
        non_null(labels, "labels")?;
        let x = pick(c, index)?;
        if capacity < NUM_CELLS {
            return Err(Error::BufferTooSmall(format!("labels buffer holds {capacity} values but 12 are needed")));
        }
        for (n, p) in x.labels.iter().enumerate() {
            *labels.add(n) = p.label() as i32;
        }
        Ok(())
    }
}

/// Copy the 132-d one-hot vector of context `index` into `v` (capacity >= 132).
///
/// # Safety
/// `c` a valid handle; `v` points to `capacity` writable floats.
#[no_mangle]
pub unsafe extern "C" fn sddpm_context_get_one_hot(c: *const SddpmContext, index: usize, v: *mut f32, capacity: usize) -> Status {
    ffi_boundary! {
        let c = ctx_ref(c)?;
        non_null(v, "v")?;
        let x = pick(c, index)?;
        if capacity < CONTEXT_DIM {
            return Err(Error::BufferTooSmall(format!("one-hot buffer holds {capacity} values but 132 are needed")));
        }
        std::ptr::copy_nonoverlapping(x.one_hot().as_ptr(), v, CONTEXT_DIM);
        Ok(())
    }
}

/// Genus of the assembled solid of context `index`; INVALID_CONTEXT (with the
/// reason as the message) when the assembly is not a valid solid.
///
/// # Safety
/// `c` a valid handle; `genus` writable.
#[no_mangle]
pub unsafe extern "C" fn sddpm_context_genus(c: *const SddpmContext, index: usize, genus: *mut i64) -> Status {
    ffi_boundary! {
        let c = ctx_ref(c)?;
        non_null(genus, "genus")?;
        let v = pick(c, index)?.validity();
        match v.genus {
            Some(g) if v.valid => { *genus = g; Ok(()) }
            _ => Err(Error::InvalidContext(format!("context {index}: {}", v.reason.unwrap_or_default()))),
        }
    }
}

/// Validity of context `index`: `valid` receives whether the assembly is one
/// face-connected manifold solid without sealed cavity; when it is not, the
/// reason is copied (NUL-terminated, truncated to fit) into `reason` if not NULL.
///
/// # Safety
/// `c` a valid handle; `valid` writable; `reason` NULL or `reason_len` writable bytes.
#[no_mangle]
pub unsafe extern "C" fn sddpm_context_validity(c: *const SddpmContext, index: usize, reason: *mut c_char, reason_len: usize, valid: *mut bool) -> Status {
    ffi_boundary! {
        let c = ctx_ref(c)?;
        non_null(valid, "valid")?;
        let v = pick(c, index)?.validity();
        if !reason.is_null() && reason_len > 0 {
            let r = v.reason.clone().unwrap_or_default();
            let b = r.as_bytes();
            let n = b.len().min(reason_len - 1);
            std::ptr::copy_nonoverlapping(b.as_ptr() as *const c_char, reason, n);
            *reason.add(n) = 0;
        }
        *valid = v.valid;
        Ok(())
    }
}

/// Write the assembled surface of context `index` (grid units, one cell = 1) as OBJ.
///
/// # Safety
/// `c` a valid handle; `path` a NUL-terminated path.
#[no_mangle]
pub unsafe extern "C" fn sddpm_context_write_obj(c: *const SddpmContext, index: usize, path: *const c_char) -> Status {
    ffi_boundary! {
        let c = ctx_ref(c)?;
        non_null(path, "path")?;
        let p = CStr::from_ptr(path).to_str().map_err(|_| Error::InvalidArgument("path is not UTF-8".into()))?;
        crate::export::obj::write_polycube_obj(std::path::Path::new(p), pick(c, index)?)
    }
}
