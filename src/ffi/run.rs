//! The main job as the command line runs it: `sddpm run`'s arguments in, its
//! output folder out (one parser and one pipeline for the command, this call and
//! the Python package's `sddpm.run`).

use super::{copy_string, ffi_boundary, non_null, CProgress, SddpmProgressCb};
use crate::error::{Error, Status};
use std::ffi::{c_char, c_void, CStr};

/// Run the main job of `sddpm run` into its output folder. `args`: `n_args`
/// NUL-terminated UTF-8 strings, the arguments that follow `sddpm run` on the
/// command line (the mesh path, `-o DIR` or `--output=DIR`, and any option of
/// `sddpm run --help`; "--" before a mesh path that starts with a dash). They go
/// through the command's own parser and checks, and the folder gets every file
/// the command writes (report.json and report.html included; the report's
/// "command" is `sddpm run` with these arguments). Nothing is printed (`--quiet`
/// and `--json` change nothing here); progress over 0-1 through `progress`.
/// INVALID_ARGUMENT with the parser's message for arguments the command refuses;
/// otherwise the statuses of the stages (IO, INVALID_MESH, GENUS_MISMATCH, ...).
///
/// # Safety
/// `args` NULL (only with `n_args` 0) or `n_args` readable pointers to NUL-terminated
/// strings; `progress` NULL or a valid callback.
#[no_mangle]
pub unsafe extern "C" fn sddpm_run(args: *const *const c_char, n_args: usize, progress: SddpmProgressCb, user_data: *mut c_void) -> Status {
    ffi_boundary! {
        if n_args > 0 {
            non_null(args, "args")?;
        }
        let mut v = Vec::with_capacity(n_args);
        for i in 0..n_args {
            let p = *args.add(i);
            non_null(p, &format!("args[{i}]"))?;
            let s = CStr::from_ptr(p).to_str().map_err(|_| Error::InvalidArgument(format!("args[{i}] is not UTF-8")))?;
            v.push(s.to_string());
        }
        let mut cp = CProgress { callback: progress, user_data };
        crate::cli::run_with_args(&v, &mut cp).map(|_| ())
    }
}

/// Every argument of `sddpm run` as a JSON array, NUL-terminated, copied into `buf`
/// (`len` bytes; `needed`, may be NULL, receives the size with the NUL): objects
/// with "name" (the long name, e.g. "no-spline"; "mesh" for the input), "kind"
/// ("positional", "flag", "value", "list": repeatable), "type" ("bool", "int",
/// "number", "string", "path"), "required", "default" (null when none) and "help".
/// BUFFER_TOO_SMALL (buffer untouched) when it does not fit.
///
/// # Safety
/// `buf` NULL or `len` writable bytes; `needed` NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn sddpm_run_arguments_json(buf: *mut c_char, len: usize, needed: *mut usize) -> Status {
    ffi_boundary! {
        let s = crate::cli::run_arguments().to_string();
        copy_string(&s, buf, len, needed, "the arguments of sddpm run")
    }
}
