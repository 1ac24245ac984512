//! The options handle: every option of the pipeline by name
//! ("hex.quality.pillow"), set and read with typed calls, listed with its type,
//! default and documentation by sddpm_options_describe_json. A new option of the
//! library needs no new declaration here (docs/design.md "C ABI").

use super::{copy_string, ffi_boundary, non_null};
use crate::error::{Error, Result, Status};
use crate::pipeline::options::OptionValue;
use crate::pipeline::RunOptions;
use std::ffi::{c_char, CStr};

/// An opaque set of options (create with sddpm_options_new, release with
/// sddpm_options_free), given to sddpm_generate_polycube, sddpm_hex_mesh_build and
/// sddpm_spline_build (NULL there: the defaults). Each call reads the options it
/// needs when it is made. Setters are not thread-safe on one handle; reads (the
/// getters, describe, the build calls) may come from several threads at once.
pub struct SddpmOptions {
    pub(crate) run: RunOptions,
}

/// The options of a handle (the defaults for NULL).
pub(crate) unsafe fn run_options(o: *const SddpmOptions) -> RunOptions {
    o.as_ref().map(|o| o.run.clone()).unwrap_or_default()
}

unsafe fn name_arg<'a>(name: *const c_char) -> Result<&'a str> {
    non_null(name, "name")?;
    CStr::from_ptr(name).to_str().map_err(|_| Error::InvalidArgument("the option name is not UTF-8".into()))
}

unsafe fn opts_mut<'a>(o: *mut SddpmOptions) -> Result<&'a mut SddpmOptions> {
    non_null(o, "options")?;
    Ok(&mut *o)
}

unsafe fn opts_ref<'a>(o: *const SddpmOptions) -> Result<&'a SddpmOptions> {
    non_null(o, "options")?;
    Ok(&*o)
}

/// New options holding every default.
///
/// # Safety
/// `out` a writable handle pointer.
#[no_mangle]
pub unsafe extern "C" fn sddpm_options_new(out: *mut *mut SddpmOptions) -> Status {
    ffi_boundary! {
        non_null(out, "out")?;
        *out = Box::into_raw(Box::new(SddpmOptions { run: RunOptions::default() }));
        Ok(())
    }
}

/// Release options (NULL is a no-op).
///
/// # Safety
/// `o` NULL or a handle from sddpm_options_new, not used afterwards.
#[no_mangle]
pub unsafe extern "C" fn sddpm_options_free(o: *mut SddpmOptions) {
    ffi_boundary! {
        if !o.is_null() {
            drop(Box::from_raw(o));
        }
    }
}

/// Set a number or integer option, e.g. "hex.map.level" or "hex.goals.hausdorff"
/// (an integer option takes a whole number >= 0). INVALID_ARGUMENT, naming the
/// option, for an unknown name, an option of another type or a value out of its
/// range; the options are then unchanged.
///
/// # Safety
/// `o` a valid handle; `name` NUL-terminated.
#[no_mangle]
pub unsafe extern "C" fn sddpm_options_set_number(o: *mut SddpmOptions, name: *const c_char, value: f64) -> Status {
    ffi_boundary! {
        let o = opts_mut(o)?;
        o.run.set_option(name_arg(name)?, OptionValue::Number(value))
    }
}

/// Set a bool option, e.g. "hex.quality.pillow"; errors as sddpm_options_set_number.
///
/// # Safety
/// `o` a valid handle; `name` NUL-terminated.
#[no_mangle]
pub unsafe extern "C" fn sddpm_options_set_bool(o: *mut SddpmOptions, name: *const c_char, value: bool) -> Status {
    ffi_boundary! {
        let o = opts_mut(o)?;
        o.run.set_option(name_arg(name)?, OptionValue::Bool(value))
    }
}

/// Set a string option, e.g. "polycube.orientations" to "SignFlips"; errors as
/// sddpm_options_set_number.
///
/// # Safety
/// `o` a valid handle; `name`, `value` NUL-terminated.
#[no_mangle]
pub unsafe extern "C" fn sddpm_options_set_string(o: *mut SddpmOptions, name: *const c_char, value: *const c_char) -> Status {
    ffi_boundary! {
        let o = opts_mut(o)?;
        let name = name_arg(name)?;
        non_null(value, "value")?;
        let v = CStr::from_ptr(value).to_str().map_err(|_| Error::InvalidArgument(format!("the value of option {name} is not UTF-8")))?;
        o.run.set_option(name, OptionValue::String(v.to_string()))
    }
}

/// Unset an option that may be unset ("nullable" in sddpm_options_describe_json),
/// e.g. "hex.map.level" (the level chosen by the stopping rule again) or
/// "spline.sharp_angle_deg" (no automatic sharp edges); INVALID_ARGUMENT for any
/// other option.
///
/// # Safety
/// `o` a valid handle; `name` NUL-terminated.
#[no_mangle]
pub unsafe extern "C" fn sddpm_options_unset(o: *mut SddpmOptions, name: *const c_char) -> Status {
    ffi_boundary! {
        let o = opts_mut(o)?;
        o.run.set_option(name_arg(name)?, OptionValue::None)
    }
}

/// The value of a number or integer option. INVALID_ARGUMENT for an unknown name,
/// an option of another type, or an option that is unset; `out` is then untouched.
///
/// # Safety
/// `o` a valid handle; `name` NUL-terminated; `out` writable.
#[no_mangle]
pub unsafe extern "C" fn sddpm_options_get_number(o: *const SddpmOptions, name: *const c_char, out: *mut f64) -> Status {
    ffi_boundary! {
        let o = opts_ref(o)?;
        let name = name_arg(name)?;
        non_null(out, "out")?;
        match o.run.option(name)? {
            OptionValue::Number(x) => {
                *out = x;
                Ok(())
            }
            other => Err(wrong_type(name, "number", &other)),
        }
    }
}

/// The value of a bool option; errors as sddpm_options_get_number.
///
/// # Safety
/// `o` a valid handle; `name` NUL-terminated; `out` writable.
#[no_mangle]
pub unsafe extern "C" fn sddpm_options_get_bool(o: *const SddpmOptions, name: *const c_char, out: *mut bool) -> Status {
    ffi_boundary! {
        let o = opts_ref(o)?;
        let name = name_arg(name)?;
        non_null(out, "out")?;
        match o.run.option(name)? {
            OptionValue::Bool(b) => {
                *out = b;
                Ok(())
            }
            other => Err(wrong_type(name, "bool", &other)),
        }
    }
}

/// The value of a string option, NUL-terminated, into `buf` (capacity `len`);
/// `needed` (may be NULL) receives its size with the NUL. BUFFER_TOO_SMALL when it
/// does not fit; other errors as sddpm_options_get_number.
///
/// # Safety
/// `o` a valid handle; `name` NUL-terminated; `buf` NULL or `len` writable bytes;
/// `needed` NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn sddpm_options_get_string(o: *const SddpmOptions, name: *const c_char, buf: *mut c_char, len: usize, needed: *mut usize) -> Status {
    ffi_boundary! {
        let o = opts_ref(o)?;
        let name = name_arg(name)?;
        match o.run.option(name)? {
            OptionValue::String(s) => copy_string(&s, buf, len, needed, &format!("option {name}")),
            other => Err(wrong_type(name, "string", &other)),
        }
    }
}

fn wrong_type(name: &str, asked: &str, v: &OptionValue) -> Error {
    match v {
        OptionValue::None => Error::InvalidArgument(format!("option {name} is unset")),
        OptionValue::Number(_) => Error::InvalidArgument(format!("option {name} is a number, not a {asked}: read it with sddpm_options_get_number")),
        OptionValue::Bool(_) => Error::InvalidArgument(format!("option {name} is a bool, not a {asked}: read it with sddpm_options_get_bool")),
        OptionValue::String(_) => Error::InvalidArgument(format!("option {name} is a string, not a {asked}: read it with sddpm_options_get_string")),
    }
}

/// Every option as one JSON object, NUL-terminated, into `buf` (capacity `len`):
/// name -> {"value", "default", "type" ("number", "integer", "bool" or "string"),
/// "nullable" (may be unset with sddpm_options_unset), "doc"}; a value that is
/// unset is null. `needed` (may be NULL) receives the size with the NUL;
/// BUFFER_TOO_SMALL when it does not fit. `o` NULL describes the defaults.
///
/// # Safety
/// `o` NULL or a valid handle; `buf` NULL or `len` writable bytes; `needed` NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn sddpm_options_describe_json(o: *const SddpmOptions, buf: *mut c_char, len: usize, needed: *mut usize) -> Status {
    ffi_boundary! {
        let v = run_options(o).describe_options()?;
        copy_string(&v.to_string(), buf, len, needed, "the options' description")
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::ffi::CString;
    use std::ptr::{null, null_mut};

    fn c(s: &str) -> CString {
        CString::new(s).unwrap()
    }

    #[test]
    fn the_handle_sets_reads_and_refuses_by_name() {
        unsafe {
            let mut o = null_mut();
            assert_eq!(sddpm_options_new(&mut o), Status::Ok);
            assert_eq!(sddpm_options_set_number(o, c("hex.map.level").as_ptr(), 2.0), Status::Ok);
            let mut x = 0.0;
            assert_eq!(sddpm_options_get_number(o, c("hex.map.level").as_ptr(), &mut x), Status::Ok);
            assert_eq!(x, 2.0);
            assert_eq!(sddpm_options_unset(o, c("hex.map.level").as_ptr()), Status::Ok);
            assert_eq!(sddpm_options_get_number(o, c("hex.map.level").as_ptr(), &mut x), Status::InvalidArgument);
            assert_eq!(sddpm_options_set_bool(o, c("hex.quality.pillow").as_ptr(), false), Status::Ok);
            let mut b = true;
            assert_eq!(sddpm_options_get_bool(o, c("hex.quality.pillow").as_ptr(), &mut b), Status::Ok);
            assert!(!b);
            assert_eq!(sddpm_options_set_string(o, c("polycube.orientations").as_ptr(), c("Identity").as_ptr()), Status::Ok);
            let mut need = 0;
            assert_eq!(sddpm_options_get_string(o, c("polycube.orientations").as_ptr(), null_mut(), 0, &mut need), Status::BufferTooSmall);
            assert_eq!(need, 9);
            assert_eq!(sddpm_options_set_number(o, c("hex.quality.pilow").as_ptr(), 1.0), Status::InvalidArgument);
            assert_eq!(sddpm_options_set_number(o, null(), 1.0), Status::InvalidArgument);
            assert_eq!(sddpm_options_set_number(null_mut(), c("hex.map.level").as_ptr(), 1.0), Status::InvalidArgument);
            assert_eq!(sddpm_options_describe_json(null(), null_mut(), 0, &mut need), Status::BufferTooSmall);
            // the handle's own description is longer than the defaults' ("false" for
            // "true", "Identity" for "All"): its size is asked of the handle
            assert_eq!(sddpm_options_describe_json(o, null_mut(), 0, &mut need), Status::BufferTooSmall);
            let mut buf = vec![0 as c_char; need];
            assert_eq!(sddpm_options_describe_json(o, buf.as_mut_ptr(), need, null_mut()), Status::Ok);
            let j: serde_json::Value = serde_json::from_str(CStr::from_ptr(buf.as_ptr()).to_str().unwrap()).unwrap();
            assert_eq!(j["hex.quality.pillow"]["value"], serde_json::Value::Bool(false));
            sddpm_options_free(o);
            sddpm_options_free(null_mut());
        }
    }
}
