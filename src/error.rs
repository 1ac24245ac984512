//! Typed errors shared by every stage, and the fixed status numbers of the C ABI.
//!
//! The core returns `Result<T, Error>`; only `ffi` turns an `Error` into a
//! `Status` number plus a per-thread message. The numbers are part of the ABI
//! and never change meaning (new ones are appended).

use std::fmt;

/// Fixed status numbers (mirrored by `sddpm_status` in include/sddpm.h).
#[repr(i32)]
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Status {
    Ok = 0,
    /// A NULL pointer, a wrong length, an out-of-range option, a NaN where a number is needed.
    InvalidArgument = 1,
    /// A file could not be opened, read or written.
    Io = 2,
    /// A file was read but its content is not a valid OBJ / STL / OFF / BEXT / weights file.
    Parse = 3,
    /// The mesh cannot go on to meshing: empty, open, non-manifold, several components,
    /// inconsistent orientation, non-finite coordinates, degenerate, self-intersecting.
    InvalidMesh = 4,
    /// A context (132-vector or labels) is malformed or its assembly is not a valid solid.
    InvalidContext = 5,
    /// The genus of a context's assembly differs from the input's.
    GenusMismatch = 6,
    /// No candidate polycube passed verification.
    VerificationFailed = 7,
    /// The model weights could not be loaded or do not describe a compatible model.
    Model = 8,
    /// The hex-meshing stage could not produce a valid mesh.
    MeshingFailed = 9,
    /// The spline stage failed.
    SplineFailed = 10,
    /// The caller cancelled through the progress callback.
    Cancelled = 11,
    /// A caller's buffer is too small; the message says how large it must be.
    BufferTooSmall = 12,
    /// The input exceeds a documented limit (size, memory budget).
    LimitExceeded = 13,
    /// A bug inside the library (caught panic). The process survives.
    Internal = 14,
}

impl Status {
    /// Every status, in number order.
    pub const ALL: [Status; 15] = [
        Status::Ok,
        Status::InvalidArgument,
        Status::Io,
        Status::Parse,
        Status::InvalidMesh,
        Status::InvalidContext,
        Status::GenusMismatch,
        Status::VerificationFailed,
        Status::Model,
        Status::MeshingFailed,
        Status::SplineFailed,
        Status::Cancelled,
        Status::BufferTooSmall,
        Status::LimitExceeded,
        Status::Internal,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Status::Ok => "OK",
            Status::InvalidArgument => "INVALID_ARGUMENT",
            Status::Io => "IO",
            Status::Parse => "PARSE",
            Status::InvalidMesh => "INVALID_MESH",
            Status::InvalidContext => "INVALID_CONTEXT",
            Status::GenusMismatch => "GENUS_MISMATCH",
            Status::VerificationFailed => "VERIFICATION_FAILED",
            Status::Model => "MODEL",
            Status::MeshingFailed => "MESHING_FAILED",
            Status::SplineFailed => "SPLINE_FAILED",
            Status::Cancelled => "CANCELLED",
            Status::BufferTooSmall => "BUFFER_TOO_SMALL",
            Status::LimitExceeded => "LIMIT_EXCEEDED",
            Status::Internal => "INTERNAL",
        }
    }
}

/// Every error the library reports. The message names what is wrong and where.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum Error {
    #[error("invalid argument: {0}")]
    InvalidArgument(String),
    #[error("{path}: {message}")]
    Io { path: String, message: String },
    #[error("{path}: {message}")]
    Parse { path: String, message: String },
    #[error("invalid mesh: {0}")]
    InvalidMesh(String),
    #[error("invalid context: {0}")]
    InvalidContext(String),
    #[error("genus mismatch: the input surface has genus {input} but the context's assembly has genus {context}{detail}")]
    GenusMismatch { input: i64, context: i64, detail: String },
    #[error("verification failed: {0}")]
    VerificationFailed(String),
    #[error("model: {0}")]
    Model(String),
    #[error("hex meshing failed: {0}")]
    MeshingFailed(String),
    #[error("spline construction failed: {0}")]
    SplineFailed(String),
    #[error("cancelled by the caller during {0}")]
    Cancelled(String),
    #[error("buffer too small: {0}")]
    BufferTooSmall(String),
    #[error("limit exceeded: {0}")]
    LimitExceeded(String),
    #[error("internal error: {0}")]
    Internal(String),
}

impl Error {
    pub fn status(&self) -> Status {
        match self {
            Error::InvalidArgument(_) => Status::InvalidArgument,
            Error::Io { .. } => Status::Io,
            Error::Parse { .. } => Status::Parse,
            Error::InvalidMesh(_) => Status::InvalidMesh,
            Error::InvalidContext(_) => Status::InvalidContext,
            Error::GenusMismatch { .. } => Status::GenusMismatch,
            Error::VerificationFailed(_) => Status::VerificationFailed,
            Error::Model(_) => Status::Model,
            Error::MeshingFailed(_) => Status::MeshingFailed,
            Error::SplineFailed(_) => Status::SplineFailed,
            Error::Cancelled(_) => Status::Cancelled,
            Error::BufferTooSmall(_) => Status::BufferTooSmall,
            Error::LimitExceeded(_) => Status::LimitExceeded,
            Error::Internal(_) => Status::Internal,
        }
    }

    pub fn io(path: impl fmt::Display, e: impl fmt::Display) -> Self {
        Error::Io { path: path.to_string(), message: e.to_string() }
    }

    pub fn parse(path: impl fmt::Display, message: impl Into<String>) -> Self {
        Error::Parse { path: path.to_string(), message: message.into() }
    }
}

pub type Result<T> = std::result::Result<T, Error>;

/// Progress reporting shared by long stages: `report(fraction, stage)` returns
/// `false` when the caller wants to cancel.
pub trait Progress {
    fn report(&mut self, fraction: f64, stage: &str) -> bool;
}

/// A progress sink that never cancels and reports nothing.
pub struct NoProgress;

impl Progress for NoProgress {
    fn report(&mut self, _fraction: f64, _stage: &str) -> bool {
        true
    }
}

impl<F: FnMut(f64, &str) -> bool> Progress for F {
    fn report(&mut self, fraction: f64, stage: &str) -> bool {
        self(fraction, stage)
    }
}

/// Report progress and turn a cancel request into `Error::Cancelled`.
pub fn check_progress(p: &mut dyn Progress, fraction: f64, stage: &str) -> Result<()> {
    if p.report(fraction.clamp(0.0, 1.0), stage) {
        Ok(())
    } else {
        Err(Error::Cancelled(stage.to_string()))
    }
}

/// Progress of a sub-stage mapped onto [lo, hi] of the caller's range; cancel requests
/// pass through.
pub struct SubProgress<'a> {
    pub inner: &'a mut dyn Progress,
    pub lo: f64,
    pub hi: f64,
}

impl Progress for SubProgress<'_> {
    fn report(&mut self, fraction: f64, stage: &str) -> bool {
        let f = self.lo + (self.hi - self.lo) * fraction.clamp(0.0, 1.0);
        self.inner.report(f, stage)
    }
}

/// A progress sink that never goes backwards: each fraction passed on is the
/// largest reported so far. Stages estimate their share ahead of time (the number
/// of candidates to diffuse, of lattices to try) and a later estimate can fall
/// below an earlier one; the caller sees the bar hold instead of going back.
/// Cancel requests pass through. The main job ([`crate::pipeline::run`]) and the
/// command line's progress bar report through one.
pub struct MonotoneProgress<'a> {
    inner: &'a mut dyn Progress,
    best: f64,
}

impl<'a> MonotoneProgress<'a> {
    pub fn new(inner: &'a mut dyn Progress) -> Self {
        MonotoneProgress { inner, best: 0.0 }
    }
}

impl Progress for MonotoneProgress<'_> {
    fn report(&mut self, fraction: f64, stage: &str) -> bool {
        // NaN is ignored (the last fraction is repeated)
        if fraction > self.best {
            self.best = fraction.min(1.0);
        }
        self.inner.report(self.best, stage)
    }
}

#[cfg(test)]
mod progress_tests {
    use super::*;

    /// Fractions that go back (a sub-stage re-estimating its share) reach the
    /// caller as the largest so far, through nested sub-ranges too; cancel passes.
    #[test]
    fn monotone_progress_never_goes_backwards() {
        let mut seen: Vec<f64> = Vec::new();
        let mut sink = |f: f64, _: &str| {
            seen.push(f);
            true
        };
        {
            let mut m = MonotoneProgress::new(&mut sink);
            let mut sub = SubProgress { inner: &mut m, lo: 0.0, hi: 0.5 };
            for f in [0.1, 0.76, 0.66, 0.8, f64::NAN, 0.2, 1.0] {
                assert!(sub.report(f, "reverse diffusion"));
            }
            let mut sub2 = SubProgress { inner: &mut m, lo: 0.3, hi: 1.0 };
            for f in [0.0, 0.5, 0.4, 2.0] {
                assert!(sub2.report(f, "hex"));
            }
        }
        assert!(seen.windows(2).all(|w| w[1] >= w[0]), "{seen:?}");
        assert_eq!(seen[..3], [0.05, 0.38, 0.38]);
        assert_eq!(*seen.last().unwrap(), 1.0);
        let mut cancel = |_: f64, _: &str| false;
        let mut m = MonotoneProgress::new(&mut cancel);
        assert!(!m.report(0.5, "x"));
    }
}
