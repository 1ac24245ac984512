//! BEXT (Bézier extraction) text, version 1, as Hex2Spline writes it:
//!
//! ```text
//! B E X T
//! type hex
//! nodeN <control points>
//! elemN <elements>
//! gnode x y z w           (nodeN lines)
//! belem n 3 3 3           (per element)
//! <n global basis ids, 0-based>
//! d c0 ... c63            (n dense rows) or
//! s nnz k0 v0 k1 v1 ...   (n sparse rows: Bernstein index, value)
//! ```
//! Bernstein index i + 4j + 16k (u fastest). The element's Bézier points are
//! Pb[k] = sum_r C[r][k] P[ids[r]]. Control points are written in the shortest
//! form that reads back to the same f64. Operator entries too by default
//! ([`bext_text`]); [`bext_text_within`] writes each with the fewest decimals that
//! read back within an absolute tolerance (the run folder's spline.bext: within
//! [`RUN_FOLDER_TOLERANCE`] by default), and a sparse row then leaves out the
//! entries that round to zero.

use crate::error::{Error, Result};
use crate::spline::Spline;
use std::fmt::Write as _;
use std::path::Path;

/// One element of a BEXT file.
#[derive(Debug, Clone, PartialEq)]
pub struct BextElement {
    pub degree: [u32; 3],
    /// Global basis ids (0-based).
    pub ids: Vec<u32>,
    /// Row-major `ids.len() x 64` extraction operator.
    pub operator: Vec<f64>,
}

/// The content of a BEXT file.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Bext {
    /// Control points x, y, z and weight.
    pub nodes: Vec<[f64; 4]>,
    pub elements: Vec<BextElement>,
}

impl Bext {
    /// Bézier control points of element e (polynomial: weights ignored when all 1;
    /// rational weights are applied as projective coordinates).
    pub fn bezier_points(&self, e: usize) -> Vec<[f64; 3]> {
        let el = &self.elements[e];
        let mut out = vec![[0.0; 4]; 64];
        for (r, &id) in el.ids.iter().enumerate() {
            let p = self.nodes[id as usize];
            for k in 0..64 {
                let c = el.operator[r * 64 + k];
                if c != 0.0 {
                    for i in 0..3 {
                        out[k][i] += c * p[i] * p[3];
                    }
                    out[k][3] += c * p[3];
                }
            }
        }
        out.iter().map(|q| [q[0] / q[3], q[1] / q[3], q[2] / q[3]]).collect()
    }

    /// The BEXT content of a spline.
    pub fn from_spline(sp: &Spline) -> Bext {
        let nodes = sp.control_points().iter().map(|p| [p[0], p[1], p[2], 1.0]).collect();
        let elements = (0..sp.num_elements())
            .map(|e| BextElement {
                degree: [3, 3, 3],
                ids: sp.element_basis(e).expect("element").to_vec(),
                operator: sp.extraction_operator(e).expect("element"),
            })
            .collect();
        Bext { nodes, elements }
    }
}

/// Shortest text that parses back to the same f64.
pub fn fmt_f64(v: f64) -> String {
    if v == 0.0 {
        return "0".into();
    }
    let a = v.abs();
    if (1e-4..1e15).contains(&a) {
        format!("{v}")
    } else {
        format!("{v:e}")
    }
}

/// The default absolute tolerance of the operator entries in the run folder's
/// spline.bext ([`crate::spline::DEFAULT_BEXT_TOLERANCE`], 1e-8; why that value:
/// there).
pub const RUN_FOLDER_TOLERANCE: f64 = crate::spline::DEFAULT_BEXT_TOLERANCE;

/// Decimals that round any value to within `tol` (half a unit in the last place).
fn decimals_for(tol: f64) -> usize {
    // 10^-d / 2 <= tol, with a margin of a few ulps for the decimal-to-binary read
    ((0.5 / tol).log10() * (1.0 + 1e-12)).ceil().clamp(0.0, 17.0) as usize
}

/// `v` with the fewest decimals (at most `d`) that reads back within half a unit
/// of the d-th decimal: rounded to d decimals, trailing zeros dropped ("0.5",
/// "0.166666666667", "1"); "0" for a value that rounds to zero. Values of 1e6 or
/// more are written exactly ([`fmt_f64`]).
fn fmt_decimals(v: f64, d: usize) -> String {
    if !v.is_finite() || v.abs() >= 1e6 {
        return fmt_f64(v);
    }
    let mut s = format!("{v:.d$}");
    if s.contains('.') {
        while s.ends_with('0') {
            s.pop();
        }
        if s.ends_with('.') {
            s.pop();
        }
    }
    if s == "-0" {
        s = "0".into();
    }
    s
}

/// BEXT text of a spline (dense or sparse operator rows), every number exact.
pub fn to_bext_string(sp: &Spline, sparse: bool) -> String {
    bext_text(&Bext::from_spline(sp), sparse)
}

/// BEXT text of parsed / assembled content, every number exact.
pub fn bext_text(b: &Bext, sparse: bool) -> String {
    bext_text_within(b, sparse, 0.0)
}

/// BEXT text whose operator entries read back within `tolerance` (absolute; 0 or
/// less: exact) with the fewest decimals that guarantee it; control points exact.
/// A sparse row lists only the entries whose written value is not zero.
pub fn bext_text_within(b: &Bext, sparse: bool, tolerance: f64) -> String {
    let d = (tolerance > 0.0).then(|| decimals_for(tolerance));
    let entry = |v: f64| match d {
        Some(d) => fmt_decimals(v, d),
        None => fmt_f64(v),
    };
    let mut s = String::with_capacity(64 * b.nodes.len() + 2048 * b.elements.len());
    s.push_str("B E X T\ntype hex\n");
    let _ = writeln!(s, "nodeN {}", b.nodes.len());
    let _ = writeln!(s, "elemN {}", b.elements.len());
    for p in &b.nodes {
        let _ = writeln!(s, "gnode {} {} {} {}", fmt_f64(p[0]), fmt_f64(p[1]), fmt_f64(p[2]), fmt_f64(p[3]));
    }
    for el in &b.elements {
        let n = el.ids.len();
        let _ = writeln!(s, "belem {} {} {} {}", n, el.degree[0], el.degree[1], el.degree[2]);
        let ids: Vec<String> = el.ids.iter().map(|i| i.to_string()).collect();
        s.push_str(&ids.join(" "));
        s.push('\n');
        for r in 0..n {
            let row = &el.operator[r * 64..(r + 1) * 64];
            if sparse {
                let nz: Vec<(usize, String)> = row.iter().enumerate().filter(|(_, &v)| v != 0.0).map(|(k, &v)| (k, entry(v))).filter(|(_, t)| t != "0").collect();
                let _ = write!(s, "s {}", nz.len());
                for (k, t) in nz {
                    let _ = write!(s, " {k} {t}");
                }
            } else {
                s.push('d');
                for &v in row {
                    s.push(' ');
                    s.push_str(&entry(v));
                }
            }
            s.push('\n');
        }
    }
    s
}

/// Write the spline's Bézier extraction as BEXT v1, every number exact.
pub fn write_bext(path: &Path, sp: &Spline, sparse: bool) -> Result<()> {
    write_bext_within(path, sp, sparse, 0.0)
}

/// Write the spline's Bézier extraction as BEXT v1 with operator entries within
/// `tolerance` ([`bext_text_within`]).
pub fn write_bext_within(path: &Path, sp: &Spline, sparse: bool, tolerance: f64) -> Result<()> {
    std::fs::write(path, bext_text_within(&Bext::from_spline(sp), sparse, tolerance)).map_err(|e| Error::io(path.display(), e))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each entry reads back within the tolerance, with no more decimals than
    /// needed; zero stays "0".
    #[test]
    fn entries_within_a_tolerance() {
        assert_eq!(decimals_for(1e-12), 12);
        assert_eq!(decimals_for(5e-13), 13);
        assert_eq!(decimals_for(1e-3), 3);
        let d = decimals_for(1e-12);
        assert_eq!(fmt_decimals(0.5, d), "0.5");
        assert_eq!(fmt_decimals(1.0, d), "1");
        assert_eq!(fmt_decimals(1.0 / 6.0, d), "0.166666666667");
        assert_eq!(fmt_decimals(0.19999999999999998, d), "0.2");
        assert_eq!(fmt_decimals(-1e-14, d), "0");
        assert_eq!(fmt_decimals(3e-13, d), "0");
        let mut x = 0.123456789;
        for _ in 0..10_000 {
            x = (x * 9301.0 + 0.49297) % 1.0;
            let v = x * x * x;
            let back: f64 = fmt_decimals(v, d).parse().unwrap();
            assert!((back - v).abs() <= 1e-12, "{v}: {back}");
        }
    }
}

/// Read a BEXT v1 file (hexahedral elements, dense or sparse rows).
pub fn read_bext(path: &Path) -> Result<Bext> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path.display(), e))?;
    parse_bext(&text).map_err(|m| Error::parse(path.display(), m))
}

struct Lines<'a> {
    it: std::iter::Enumerate<std::str::Lines<'a>>,
    line: usize,
}

impl<'a> Lines<'a> {
    fn next(&mut self) -> std::result::Result<&'a str, String> {
        for (i, l) in self.it.by_ref() {
            let t = l.trim();
            if !t.is_empty() && !t.starts_with('#') {
                self.line = i + 1;
                return Ok(t);
            }
        }
        Err("unexpected end of file".into())
    }
}

fn num<T: std::str::FromStr>(tok: Option<&str>, what: &str, line: usize) -> std::result::Result<T, String> {
    let t = tok.ok_or_else(|| format!("line {line}: missing {what}"))?;
    t.parse::<T>().map_err(|_| format!("line {line}: {what} '{t}' is not a valid number"))
}

/// Parse BEXT v1 text.
pub fn parse_bext(text: &str) -> std::result::Result<Bext, String> {
    let mut ls = Lines { it: text.lines().enumerate(), line: 0 };
    let head = ls.next()?;
    if head.split_whitespace().collect::<String>() != "BEXT" {
        return Err(format!("line {}: expected 'B E X T', found '{head}'", ls.line));
    }
    let mut node_n: Option<usize> = None;
    let mut elem_n: Option<usize> = None;
    let mut first = ls.next()?;
    loop {
        let mut t = first.split_whitespace();
        match t.next() {
            Some("type") => {
                let ty = t.next().unwrap_or("");
                if ty != "hex" {
                    return Err(format!("line {}: only 'type hex' is supported, found '{ty}'", ls.line));
                }
            }
            Some("nodeN") => node_n = Some(num(t.next(), "nodeN", ls.line)?),
            Some("elemN") => elem_n = Some(num(t.next(), "elemN", ls.line)?),
            _ => break,
        }
        first = ls.next()?;
    }
    let node_n = node_n.ok_or("missing nodeN")?;
    let elem_n = elem_n.ok_or("missing elemN")?;
    if node_n > 100_000_000 || elem_n > 100_000_000 {
        return Err("nodeN or elemN is implausibly large".into());
    }
    let mut b = Bext { nodes: Vec::with_capacity(node_n), elements: Vec::with_capacity(elem_n) };
    let mut line = first;
    for i in 0..node_n {
        if i > 0 {
            line = ls.next()?;
        }
        let mut t = line.split_whitespace();
        if t.next() != Some("gnode") {
            return Err(format!("line {}: expected gnode {} of {node_n}", ls.line, i + 1));
        }
        let mut p = [0.0f64; 4];
        for (c, slot) in p.iter_mut().enumerate() {
            *slot = num(t.next(), ["x", "y", "z", "w"][c], ls.line)?;
            if !slot.is_finite() {
                return Err(format!("line {}: non-finite coordinate", ls.line));
            }
        }
        b.nodes.push(p);
    }
    for e in 0..elem_n {
        let l = ls.next()?;
        let mut t = l.split_whitespace();
        if t.next() != Some("belem") {
            return Err(format!("line {}: expected belem of element {e}", ls.line));
        }
        let n: usize = num(t.next(), "number of basis functions", ls.line)?;
        if n == 0 || n > 100_000 {
            return Err(format!("line {}: element {e} has {n} basis functions", ls.line));
        }
        let degree = [0, 1, 2].map(|_| num::<u32>(t.next(), "degree", ls.line));
        let degree = [degree[0].clone()?, degree[1].clone()?, degree[2].clone()?];
        if degree != [3, 3, 3] {
            return Err(format!("line {}: only degree 3 3 3 is supported, found {degree:?}", ls.line));
        }
        let idl = ls.next()?;
        let ids: Vec<u32> = idl
            .split_whitespace()
            .map(|x| x.parse::<u32>().map_err(|_| format!("line {}: bad basis id '{x}'", ls.line)))
            .collect::<std::result::Result<_, _>>()?;
        if ids.len() != n {
            return Err(format!("line {}: element {e} lists {} ids, expected {n}", ls.line, ids.len()));
        }
        if let Some(&bad) = ids.iter().find(|&&i| i as usize >= node_n) {
            return Err(format!("line {}: basis id {bad} >= nodeN {node_n}", ls.line));
        }
        let mut op = vec![0.0; n * 64];
        for r in 0..n {
            let rl = ls.next()?;
            let mut t = rl.split_whitespace();
            match t.next() {
                Some("d") => {
                    for k in 0..64 {
                        op[r * 64 + k] = num(t.next(), "operator entry", ls.line)?;
                    }
                }
                Some("s") => {
                    let nnz: usize = num(t.next(), "nnz", ls.line)?;
                    if nnz > 64 {
                        return Err(format!("line {}: nnz {nnz} > 64", ls.line));
                    }
                    for _ in 0..nnz {
                        let k: usize = num(t.next(), "Bernstein index", ls.line)?;
                        if k >= 64 {
                            return Err(format!("line {}: Bernstein index {k} >= 64", ls.line));
                        }
                        op[r * 64 + k] = num(t.next(), "operator entry", ls.line)?;
                    }
                }
                other => {
                    return Err(format!("line {}: expected a 'd' or 's' operator row, found {other:?}", ls.line));
                }
            }
            if t.next().is_some() {
                return Err(format!("line {}: extra values after the operator row", ls.line));
            }
        }
        b.elements.push(BextElement { degree: [3, 3, 3], ids, operator: op });
    }
    Ok(b)
}
