//! The C ABI (include/sddpm.h is generated from this module by cbindgen).
//!
//! Rules (DESIGN.md "C ABI"): names `sddpm_<object>_<verb>`; opaque handles
//! with `_new`/`_free` pairs (free of NULL is a no-op); every fallible call
//! returns an `sddpm_status`; the message of the last error is kept per thread
//! and copied into a caller's buffer; out-parameters come last and are written
//! only on success; NULL pointers, wrong lengths and NaN coordinates are
//! errors; no panic crosses the boundary: every export runs inside
//! [`ffi_boundary!`], which turns a panic into `SDDPM_STATUS_INTERNAL`.

use crate::error::{Error, Progress, Result, Status};
use std::cell::RefCell;
use std::ffi::{c_char, c_int, c_void, CStr, CString};
use std::sync::OnceLock;

mod context;
mod hex;
mod mesh;
mod model;
mod options;
mod run;
mod spline;
pub use context::*;
pub use hex::*;
pub use mesh::*;
pub use model::*;
pub use options::*;
pub use run::*;
pub use spline::*;

/// Version of the C ABI: bumped whenever a declaration in include/sddpm.h changes incompatibly.
pub const ABI_VERSION: u32 = 5;

/// The panic boundary around every export: runs the body (a closure body whose
/// value implements [`FfiReturn`]), records errors and panics as the thread's
/// last error and returns the C value.
#[macro_export]
#[doc(hidden)]
macro_rules! ffi_boundary {
    ($($body:tt)*) => {
        $crate::ffi::guard(move || { $($body)* })
    };
}
pub use ffi_boundary;

/// What an export's body may produce and how it becomes a C value.
pub trait FfiReturn {
    type C;
    /// The C value for a normal return (errors are recorded as the last error here).
    fn into_c(self) -> Self::C;
    /// The C value when the body panicked.
    fn on_panic() -> Self::C;
}

impl FfiReturn for Result<()> {
    type C = Status;
    fn into_c(self) -> Status {
        match self {
            Ok(()) => Status::Ok,
            Err(e) => {
                let s = e.status();
                set_last_error(s, &e.to_string());
                s
            }
        }
    }
    fn on_panic() -> Status {
        Status::Internal
    }
}

impl FfiReturn for () {
    type C = ();
    fn into_c(self) {}
    fn on_panic() {}
}

impl FfiReturn for u32 {
    type C = u32;
    fn into_c(self) -> u32 {
        self
    }
    fn on_panic() -> u32 {
        0
    }
}

impl FfiReturn for Status {
    type C = Status;
    fn into_c(self) -> Status {
        self
    }
    fn on_panic() -> Status {
        Status::Internal
    }
}

impl FfiReturn for *const c_char {
    type C = *const c_char;
    fn into_c(self) -> *const c_char {
        self
    }
    fn on_panic() -> *const c_char {
        std::ptr::null()
    }
}

#[doc(hidden)]
pub fn guard<R: FfiReturn>(f: impl FnOnce() -> R) -> R::C {
    match std::panic::catch_unwind(std::panic::AssertUnwindSafe(f)) {
        Ok(r) => r.into_c(),
        Err(payload) => {
            let what = payload
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| payload.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "unknown panic payload".to_string());
            set_last_error(Status::Internal, &format!("internal error (a bug in libsddpm, please report it): panic: {what}"));
            R::on_panic()
        }
    }
}

thread_local! {
    static LAST_ERROR: RefCell<Option<(Status, CString)>> = const { RefCell::new(None) };
}

fn set_last_error(status: Status, message: &str) {
    let c = CString::new(message.replace('\0', "\\0")).unwrap_or_default();
    LAST_ERROR.with(|e| *e.borrow_mut() = Some((status, c)));
}

/// Turn a NULL pointer argument into an error naming it.
pub(crate) fn non_null<T>(p: *const T, name: &str) -> Result<()> {
    if p.is_null() {
        Err(Error::InvalidArgument(format!("argument `{name}` is NULL")))
    } else {
        Ok(())
    }
}

/// Version of the C ABI this library implements (compare with what your
/// header was written for before calling anything else).
#[no_mangle]
pub extern "C" fn sddpm_abi_version() -> u32 {
    ffi_boundary! { ABI_VERSION }
}

/// The library version, e.g. "0.1.0" (static storage, never free it).
#[no_mangle]
pub extern "C" fn sddpm_version_string() -> *const c_char {
    ffi_boundary! {
        static V: &str = concat!(env!("CARGO_PKG_VERSION"), "\0");
        V.as_ptr() as *const c_char
    }
}

/// The name of a status number, e.g. "INVALID_MESH" (static storage);
/// "UNKNOWN" for numbers that are not a status.
#[no_mangle]
pub extern "C" fn sddpm_status_name(status: i32) -> *const c_char {
    ffi_boundary! {
        static NAMES: OnceLock<Vec<CString>> = OnceLock::new();
        static UNKNOWN: &CStr = c"UNKNOWN";
        let names = NAMES.get_or_init(|| ALL_STATUS.iter().map(|s| CString::new(s.name()).unwrap_or_default()).collect());
        match status_from_i32(status) {
            Some(s) => names[ALL_STATUS.iter().position(|x| *x == s).unwrap_or(0)].as_ptr(),
            None => UNKNOWN.as_ptr(),
        }
    }
}

const ALL_STATUS: [Status; 15] = Status::ALL;

fn status_from_i32(n: i32) -> Option<Status> {
    ALL_STATUS.into_iter().find(|s| *s as i32 == n)
}

/// The status of the last failed call on this thread (SDDPM_STATUS_OK if none
/// failed since the thread started or since sddpm_last_error_clear).
#[no_mangle]
pub extern "C" fn sddpm_last_error_status() -> Status {
    ffi_boundary! { LAST_ERROR.with(|e| e.borrow().as_ref().map(|x| x.0).unwrap_or(Status::Ok)) }
}

/// Copy the message of the last failed call on this thread, NUL-terminated,
/// into `buf` (capacity `len` bytes). `needed` (may be NULL) receives the size
/// the message needs including its NUL, whether or not it fits. Returns
/// SDDPM_STATUS_BUFFER_TOO_SMALL (buf untouched) when `len` is too small or
/// `buf` is NULL. Successful calls do not clear the message, and this call
/// never replaces it. With no error recorded the message is "".
///
/// # Safety
/// `buf` must be NULL or point to `len` writable bytes; `needed` NULL or valid.
#[no_mangle]
pub unsafe extern "C" fn sddpm_last_error_message(buf: *mut c_char, len: usize, needed: *mut usize) -> Status {
    ffi_boundary! {
        LAST_ERROR.with(|e| {
            let e = e.borrow();
            let msg: &[u8] = e.as_ref().map(|x| x.1.as_bytes_with_nul()).unwrap_or(b"\0");
            if !needed.is_null() {
                *needed = msg.len();
            }
            if buf.is_null() || len < msg.len() {
                return Status::BufferTooSmall;
            }
            std::ptr::copy_nonoverlapping(msg.as_ptr() as *const c_char, buf, msg.len());
            Status::Ok
        })
    }
}

/// Forget the last error of this thread.
#[no_mangle]
pub extern "C" fn sddpm_last_error_clear() {
    ffi_boundary! { LAST_ERROR.with(|e| *e.borrow_mut() = None) }
}

/// Test-only export (left out of the header; built only with the cargo feature
/// `test-hooks`, which the C++ contract tests' CMake build enables): panics inside
/// the boundary so that contract tests can check a panic becomes
/// SDDPM_STATUS_INTERNAL.
#[cfg(feature = "test-hooks")]
#[doc(hidden)]
#[no_mangle]
pub extern "C" fn sddpm_test_force_panic() -> Status {
    ffi_boundary! {
        if std::hint::black_box(true) {
            panic!("forced by sddpm_test_force_panic");
        }
        Ok::<(), Error>(())
    }
}

/// Progress callback for long calls: `fraction` in [0, 1], `stage` a short
/// NUL-terminated name valid during the call, `user_data` as given by the
/// caller. Return nonzero to cancel (the call then returns SDDPM_STATUS_CANCELLED).
pub type SddpmProgressCb = Option<unsafe extern "C" fn(fraction: f64, stage: *const c_char, user_data: *mut c_void) -> c_int>;

/// Adapter from a C progress callback to the library's [`Progress`] trait.
pub struct CProgress {
    pub callback: SddpmProgressCb,
    pub user_data: *mut c_void,
}

impl Progress for CProgress {
    fn report(&mut self, fraction: f64, stage: &str) -> bool {
        match self.callback {
            None => true,
            Some(cb) => {
                let stage = CString::new(stage.replace('\0', " ")).unwrap_or_default();
                // SAFETY: the caller promised a valid callback and user data.
                unsafe { cb(fraction, stage.as_ptr(), self.user_data) == 0 }
            }
        }
    }
}

/// A NUL-terminated UTF-8 path argument.
pub(crate) unsafe fn c_path(p: *const c_char, name: &str) -> Result<std::path::PathBuf> {
    non_null(p, name)?;
    let s = CStr::from_ptr(p).to_str().map_err(|_| Error::InvalidArgument(format!("{name} is not UTF-8")))?;
    if s.is_empty() {
        return Err(Error::InvalidArgument(format!("{name} is empty")));
    }
    Ok(std::path::PathBuf::from(s))
}

/// Copy `s` NUL-terminated into (`buf`, `len`); `needed` (may be NULL) receives its size
/// with the NUL. BUFFER_TOO_SMALL (buffer untouched) when it does not fit or `buf` is NULL.
pub(crate) unsafe fn copy_string(s: &str, buf: *mut c_char, len: usize, needed: *mut usize, what: &str) -> Result<()> {
    if !needed.is_null() {
        *needed = s.len() + 1;
    }
    if buf.is_null() || len < s.len() + 1 {
        return Err(Error::BufferTooSmall(format!("{what} needs {} bytes, the buffer holds {len}", s.len() + 1)));
    }
    std::ptr::copy_nonoverlapping(s.as_ptr() as *const c_char, buf, s.len());
    *buf.add(s.len()) = 0;
    Ok(())
}

/// Copy `src` into the caller's buffer of `capacity` elements; BUFFER_TOO_SMALL (buffer
/// untouched) when it is shorter than `src`.
pub(crate) unsafe fn copy_slice<T: Copy>(src: &[T], dst: *mut T, capacity: usize, what: &str) -> Result<()> {
    non_null(dst, what)?;
    if capacity < src.len() {
        return Err(Error::BufferTooSmall(format!("{what}: {} values needed, the buffer holds {capacity}", src.len())));
    }
    std::ptr::copy_nonoverlapping(src.as_ptr(), dst, src.len());
    Ok(())
}
