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
//! The material constants are in the deck's unit system ([`Units`]); named
//! materials ([`Material`]) are given in SI units and scaled into it.
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

/// Analysis the deck runs (`sddpm run --analysis`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub enum Analysis {
    /// No control cards: the model alone (nodes or Bézier include, part, section,
    /// material), to include in the user's own deck.
    None,
    /// Implicit eigenvalue analysis of the first `modes` modes (free-free).
    Eigenvalue { modes: u32 },
    /// One implicit static step (end time 1); the loads and constraints are the
    /// user's to add (a free body has no static solution).
    Static,
}

impl Analysis {
    /// The analysis of a command-line name: "none", "modal" (10 modes) or "static".
    pub fn parse(name: &str) -> Result<Analysis> {
        match name {
            "none" => Ok(Analysis::None),
            "modal" => Ok(Analysis::Eigenvalue { modes: 10 }),
            "static" => Ok(Analysis::Static),
            o => Err(Error::InvalidArgument(format!("--analysis must be none, modal or static, got {o:?}"))),
        }
    }
}

/// A consistent unit system of the deck: the model's length unit is the mesh's
/// coordinates, the material constants are scaled into it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum Units {
    /// mm, tonne, s: stress in MPa, density in t/mm^3 (steel 210000, 7.85e-9).
    MmTonneS,
    /// m, kg, s: SI, stress in Pa, density in kg/m^3 (steel 2.1e11, 7850).
    MKgS,
    /// mm, kg, ms: stress in GPa, density in kg/mm^3 (steel 210, 7.85e-6).
    MmKgMs,
}

impl Units {
    /// The units of a command-line name: "mm-t-s", "m-kg-s" or "mm-kg-ms".
    pub fn parse(name: &str) -> Result<Units> {
        match name {
            "mm-t-s" => Ok(Units::MmTonneS),
            "m-kg-s" => Ok(Units::MKgS),
            "mm-kg-ms" => Ok(Units::MmKgMs),
            o => Err(Error::InvalidArgument(format!("--units must be mm-t-s, m-kg-s or mm-kg-ms, got {o:?}"))),
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Units::MmTonneS => "mm-t-s",
            Units::MKgS => "m-kg-s",
            Units::MmKgMs => "mm-kg-ms",
        }
    }

    /// Factors from SI (Pa, kg/m^3) to these units' stress and density.
    pub fn factors(self) -> (f64, f64) {
        match self {
            Units::MmTonneS => (1e-6, 1e-12),
            Units::MKgS => (1.0, 1.0),
            Units::MmKgMs => (1e-9, 1e-9),
        }
    }
}

/// An isotropic elastic material in SI units.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Material {
    /// Young's modulus, Pa (> 0).
    pub youngs_modulus: f64,
    /// Poisson ratio, in (-1, 0.5).
    pub poisson_ratio: f64,
    /// Density, kg/m^3 (> 0).
    pub density: f64,
}

impl Material {
    /// Structural steel: 210 GPa, 0.3, 7850 kg/m^3.
    pub fn steel() -> Material {
        Material { youngs_modulus: 210e9, poisson_ratio: 0.3, density: 7850.0 }
    }

    /// Aluminium alloy: 70 GPa, 0.33, 2700 kg/m^3.
    pub fn aluminium() -> Material {
        Material { youngs_modulus: 70e9, poisson_ratio: 0.33, density: 2700.0 }
    }

    /// "steel", "aluminium" (or "aluminum"), or "E,nu,rho" in SI units (Pa, -, kg/m^3).
    pub fn parse(text: &str) -> Result<Material> {
        let m = match text {
            "steel" => Material::steel(),
            "aluminium" | "aluminum" => Material::aluminium(),
            t => {
                let bad = || Error::InvalidArgument(format!("--material must be steel, aluminium or E,nu,rho (SI units: Pa, -, kg/m^3), got {t:?}"));
                let v: Vec<f64> = t.split(',').map(|x| x.trim().parse::<f64>()).collect::<std::result::Result<_, _>>().map_err(|_| bad())?;
                if v.len() != 3 {
                    return Err(bad());
                }
                Material { youngs_modulus: v[0], poisson_ratio: v[1], density: v[2] }
            }
        };
        m.check()?;
        Ok(m)
    }

    fn check(&self) -> Result<()> {
        for (n, v) in [("Young's modulus", self.youngs_modulus), ("density", self.density)] {
            if !(v.is_finite() && v > 0.0) {
                return Err(Error::InvalidArgument(format!("{n} must be a finite number > 0, got {v}")));
            }
        }
        if !(self.poisson_ratio > -1.0 && self.poisson_ratio < 0.5) {
            return Err(Error::InvalidArgument(format!("Poisson ratio must be in (-1, 0.5), got {}", self.poisson_ratio)));
        }
        Ok(())
    }
}

/// Settings of the keyword decks (model.k and hex.k). Defaults: part/section/material
/// 1, steel in mm-tonne-s units (RO 7.85e-9, E 210000, PR 0.3), 10 eigenmodes,
/// `*IGA_INCLUDE_BEZIER`. `density`, `youngs_modulus` and `poisson_ratio` are in
/// the deck's units ([`DeckOptions::with_material`] scales SI values into them).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct DeckOptions {
    pub title: String,
    pub part_id: u32,
    pub section_id: u32,
    pub material_id: u32,
    pub density: f64,
    pub youngs_modulus: f64,
    pub poisson_ratio: f64,
    /// The unit system the constants are in (a comment in the deck; default mm-t-s).
    pub units: Units,
    pub include: IncludeStyle,
    pub analysis: Analysis,
}

impl DeckOptions {
    /// `self` with `m` (SI) in `units`.
    pub fn with_material(mut self, m: Material, units: Units) -> Result<DeckOptions> {
        m.check()?;
        let (stress, density) = units.factors();
        self.youngs_modulus = m.youngs_modulus * stress;
        self.density = m.density * density;
        self.poisson_ratio = m.poisson_ratio;
        self.units = units;
        Ok(self)
    }
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
            units: Units::MmTonneS,
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
    s.push_str(&model_cards(o, 201, "spline volume")?);
    s.push_str("*END\n");
    Ok(s)
}

/// The cards after the mesh: *PART (`heading`), *SECTION_SOLID with element
/// formulation `elform` (201: isogeometric solid; 2: fully integrated
/// selectively reduced hexahedron), *MAT_ELASTIC and the analysis's control cards,
/// with a comment naming the units.
pub fn model_cards(o: &DeckOptions, elform: i64, heading: &str) -> Result<String> {
    Material { youngs_modulus: o.youngs_modulus, poisson_ratio: o.poisson_ratio, density: o.density }.check()?;
    let mut s = String::new();
    s.push_str("*PART\n$ HEADING\n");
    s.push_str(heading);
    s.push('\n');
    s.push_str("$      PID     SECID       MID     EOSID      HGID      GRAV    ADPOPT      TMID\n");
    let ids = [o.part_id as i64, o.section_id as i64, o.material_id as i64, 0, 0, 0, 0, 0];
    s.push_str(&ids.iter().map(|&v| i10(v)).collect::<Result<String>>()?);
    s.push('\n');
    s.push_str("*SECTION_SOLID\n$    SECID    ELFORM       AET\n");
    s.push_str(&format!("{}{}{}\n", i10(o.section_id as i64)?, i10(elform)?, i10(0)?));
    s.push_str(&format!("$ units {}: RO density, E Young's modulus, PR Poisson ratio\n", o.units.name()));
    s.push_str("*MAT_ELASTIC\n$      MID        RO         E        PR        DA        DB\n");
    s.push_str(&format!("{}{}{}{}{}{}\n", i10(o.material_id as i64)?, f10(o.density)?, f10(o.youngs_modulus)?, f10(o.poisson_ratio)?, f10(0.0)?, f10(0.0)?));
    s.push_str(&analysis_cards(o.analysis)?);
    Ok(s)
}

/// The control cards of an analysis.
fn analysis_cards(a: Analysis) -> Result<String> {
    let mut s = String::new();
    match a {
        Analysis::None => {}
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
        Analysis::Static => {
            s.push_str("$ implicit static step: add the loads and constraints\n");
            s.push_str("*CONTROL_IMPLICIT_GENERAL\n$   IMFLAG       DT0\n");
            s.push_str(&format!("{}{}\n", i10(1)?, f10(1.0)?));
            s.push_str("*CONTROL_TERMINATION\n$   ENDTIM\n");
            s.push_str(&format!("{}\n", f10(1.0)?));
        }
    }
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
