//! LS-DYNA keyword decks for the spline: a ready-to-run deck that includes the
//! BEXT file as isogeometric solid elements, plus a small fixed-format parser
//! used by the tests (and by anyone checking a deck).
//!
//! Card layout (LS-DYNA keyword manual; 10-character fields unless noted):
//! * `*IGA_INCLUDE_BEZIER`: FILENAME (A256) / FILETYPE (1 = ASCII), PID, DIM (3 = volume)
//! * `*PART`: HEADING (A70) / PID, SECID, MID, EOSID, HGID, GRAV, ADPOPT, TMID
//! * `*SECTION_SOLID`: SECID, ELFORM (201 = isogeometric solid), AET
//! * `*MAT_ELASTIC`: MID, RO, E, PR, DA, DB
//! * `*CONTROL_IMPLICIT_GENERAL`: IMFLAG, DT0
//! * `*CONTROL_IMPLICIT_EIGENVALUE`: NEIG, CENTER
//! * `*CONTROL_TERMINATION`: ENDTIM
//!
//! The alternative `IncludeStyle::IncludeTransform` reproduces the deck
//! Hex2Spline ships with its BEXT output (`*INCLUDE_TRANSFORM` of the BEXT file
//! with the card `1,0,1,0,0`).

use crate::error::{Error, Result};
use serde::Serialize;
use std::path::Path;

/// How the deck brings in the Bézier extraction.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum IncludeStyle {
    /// `*IGA_INCLUDE_BEZIER` (current LS-DYNA keyword).
    IgaIncludeBezier,
    /// `*INCLUDE_TRANSFORM`, as in Hex2Spline's example deck.
    IncludeTransform,
}

/// Analysis the deck runs.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub enum Analysis {
    /// Implicit eigenvalue analysis of the first `modes` modes (free-free).
    Eigenvalue { modes: u32 },
}

/// Settings of the keyword deck. Defaults: part/section/material 1, steel in
/// mm-tonne-s units (RO 7.85e-9, E 210000, PR 0.3), 10 eigenmodes,
/// `*IGA_INCLUDE_BEZIER`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct DeckOptions {
    pub title: String,
    pub part_id: u32,
    pub section_id: u32,
    pub material_id: u32,
    pub density: f64,
    pub youngs_modulus: f64,
    pub poisson_ratio: f64,
    pub include: IncludeStyle,
    pub analysis: Analysis,
}

impl Default for DeckOptions {
    fn default() -> Self {
        DeckOptions {
            title: "sddpm TH-spline3D volume".into(),
            part_id: 1,
            section_id: 1,
            material_id: 1,
            density: 7.85e-9,
            youngs_modulus: 210000.0,
            poisson_ratio: 0.3,
            include: IncludeStyle::IgaIncludeBezier,
            analysis: Analysis::Eigenvalue { modes: 10 },
        }
    }
}

/// An integer right-aligned in a 10-character field.
pub fn i10(v: i64) -> Result<String> {
    let s = v.to_string();
    if s.len() > 10 {
        return Err(Error::InvalidArgument(format!("{v} does not fit a 10-character field")));
    }
    Ok(format!("{s:>10}"))
}

/// A real right-aligned in a 10-character field, with as many digits as fit in
/// 9 characters (one blank always separates it from the previous field).
pub fn f10(v: f64) -> Result<String> {
    if !v.is_finite() {
        return Err(Error::InvalidArgument(format!("{v} is not a finite number")));
    }
    let plain = format!("{v}");
    let s = if plain.len() <= 8 && (v == 0.0 || v.abs() >= 1e-3) {
        if plain.contains('.') || plain.contains('e') {
            plain
        } else {
            format!("{plain}.")
        }
    } else if (1e-3..1e8).contains(&v.abs()) {
        // fixed point with as many decimals as fit in 9 characters
        let mut out = format!("{v:.0}.");
        for prec in (1..=8).rev() {
            let t = format!("{:.*}", prec, v);
            if t.len() <= 9 {
                out = t.trim_end_matches('0').to_string();
                break;
            }
        }
        out
    } else {
        // scientific with the most mantissa digits that fit
        let mut out = None;
        for prec in (0..=6).rev() {
            let t = format!("{:.*E}", prec, v);
            if t.len() <= 9 {
                out = Some(t);
                break;
            }
        }
        out.ok_or_else(|| Error::InvalidArgument(format!("{v} does not fit a 10-character field")))?
    };
    Ok(format!("{s:>10}"))
}

/// Text of a ready-to-run deck that includes `bext_file_name`.
pub fn iga_deck_string(bext_file_name: &str, o: &DeckOptions) -> Result<String> {
    if bext_file_name.is_empty() || bext_file_name.len() > 256 || bext_file_name.contains(['\n', '\r']) {
        return Err(Error::InvalidArgument("the BEXT file name must have 1..256 characters on one line".into()));
    }
    for (n, v) in [("density", o.density), ("Young's modulus", o.youngs_modulus)] {
        if !(v.is_finite() && v > 0.0) {
            return Err(Error::InvalidArgument(format!("{n} must be positive, got {v}")));
        }
    }
    if !(o.poisson_ratio > -1.0 && o.poisson_ratio < 0.5) {
        return Err(Error::InvalidArgument(format!("Poisson ratio must be in (-1, 0.5), got {}", o.poisson_ratio)));
    }
    let mut s = String::new();
    let title: String = o.title.chars().filter(|c| *c != '\n' && *c != '\r').take(80).collect();
    s.push_str("*KEYWORD\n*TITLE\n");
    s.push_str(&title);
    s.push('\n');
    s.push_str("$ TH-spline3D Bezier extraction written by sddpm; elements are isogeometric solids\n");
    match o.include {
        IncludeStyle::IgaIncludeBezier => {
            s.push_str("*IGA_INCLUDE_BEZIER\n");
            s.push_str("$ FILENAME\n");
            s.push_str(bext_file_name);
            s.push('\n');
            s.push_str("$ FILETYPE       PID       DIM\n");
            s.push_str(&format!("{}{}{}\n", i10(1)?, i10(o.part_id as i64)?, i10(3)?));
        }
        IncludeStyle::IncludeTransform => {
            s.push_str("*INCLUDE_TRANSFORM\n");
            s.push_str(bext_file_name);
            s.push('\n');
            s.push_str("1,0,1,0,0\n");
        }
    }
    s.push_str("*PART\n$ HEADING\n");
    s.push_str("spline volume\n");
    s.push_str("$      PID     SECID       MID     EOSID      HGID      GRAV    ADPOPT      TMID\n");
    s.push_str(&format!(
        "{}{}{}{}{}{}{}{}\n",
        i10(o.part_id as i64)?,
        i10(o.section_id as i64)?,
        i10(o.material_id as i64)?,
        i10(0)?,
        i10(0)?,
        i10(0)?,
        i10(0)?,
        i10(0)?
    ));
    s.push_str("*SECTION_SOLID\n$    SECID    ELFORM       AET\n");
    s.push_str(&format!("{}{}{}\n", i10(o.section_id as i64)?, i10(201)?, i10(0)?));
    s.push_str("*MAT_ELASTIC\n$      MID        RO         E        PR        DA        DB\n");
    s.push_str(&format!(
        "{}{}{}{}{}{}\n",
        i10(o.material_id as i64)?,
        f10(o.density)?,
        f10(o.youngs_modulus)?,
        f10(o.poisson_ratio)?,
        f10(0.0)?,
        f10(0.0)?
    ));
    match o.analysis {
        Analysis::Eigenvalue { modes } => {
            if modes == 0 {
                return Err(Error::InvalidArgument("at least one eigenmode".into()));
            }
            s.push_str("*CONTROL_IMPLICIT_GENERAL\n$   IMFLAG       DT0\n");
            s.push_str(&format!("{}{}\n", i10(1)?, f10(1.0)?));
            s.push_str("*CONTROL_IMPLICIT_EIGENVALUE\n$     NEIG    CENTER\n");
            s.push_str(&format!("{}{}\n", i10(modes as i64)?, f10(0.0)?));
            s.push_str("*CONTROL_TERMINATION\n$   ENDTIM\n");
            s.push_str(&format!("{}\n", f10(1.0)?));
        }
    }
    s.push_str("*END\n");
    Ok(s)
}

/// Write the deck (`model.k`) next to the BEXT file it includes.
pub fn write_iga_deck(path: &Path, bext_file_name: &str, o: &DeckOptions) -> Result<()> {
    let s = iga_deck_string(bext_file_name, o)?;
    std::fs::write(path, s).map_err(|e| Error::io(path.display(), e))
}

/// One keyword of a parsed deck: its name (without `*`) and its data lines
/// (comment lines starting with `$` removed).
#[derive(Debug, Clone, PartialEq)]
pub struct Keyword {
    pub name: String,
    pub cards: Vec<String>,
    /// 1-based line number of the keyword line.
    pub line: usize,
}

/// Split a keyword deck into keywords and cards.
pub fn parse_deck(text: &str) -> Vec<Keyword> {
    let mut out: Vec<Keyword> = Vec::new();
    for (i, l) in text.lines().enumerate() {
        let l = l.trim_end_matches('\r');
        if l.starts_with('$') {
            continue;
        }
        if let Some(k) = l.strip_prefix('*') {
            out.push(Keyword { name: k.trim().to_uppercase(), cards: Vec::new(), line: i + 1 });
        } else if let Some(k) = out.last_mut() {
            k.cards.push(l.to_string());
        }
    }
    out
}

/// The text of a fixed-width field (columns `start..start+width`, trimmed);
/// empty when the line is shorter.
pub fn field(line: &str, start: usize, width: usize) -> &str {
    let b = line.as_bytes();
    if start >= b.len() {
        return "";
    }
    let end = (start + width).min(b.len());
    line.get(start..end).unwrap_or("").trim()
}
