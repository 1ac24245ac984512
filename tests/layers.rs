//! The stages of the library stack one way. Lowest first:
//!
//! error < geometry < mesh < polycube < context < diffusion < search < hex < spline
//! < export < pipeline < cli < ffi
//!
//! A file's stage is the first path component under src/ (the file stem for a file
//! directly in src/); lib.rs and main.rs, which only declare the stages, are exempt.
//! A stage may use itself, `error` and the stages below it, nothing else: every
//! `crate::<stage>` path in code (`use crate::x::...`, the members of
//! `use crate::{a, b}` groups, `crate::x::y` inline, `$crate::x` in macros) must name
//! such a stage, and no `super::super::...` path may climb out of its stage folder.
//! Comments and string literals are not code. There is no exception list: a
//! reference that breaks the order is fixed by moving code, not by listing it here.

use std::path::{Path, PathBuf};

/// The stages, lowest first; stages in one entry share a rank.
const ORDER: &[&[&str]] = &[
    &["error"],
    &["geometry"],
    &["mesh"],
    &["polycube"],
    &["context"],
    &["diffusion"],
    &["search"],
    &["hex"],
    &["spline"],
    &["export"],
    &["pipeline"],
    // the C ABI's sddpm_run runs `sddpm run` with the command line's own parser
    &["cli"],
    &["ffi"],
];

/// Usable by every stage.
const BASE: &str = "error";

/// Files that only declare the stages.
const ROOTS: &[&str] = &["lib.rs", "main.rs"];

fn rank(stage: &str) -> Option<usize> {
    ORDER.iter().position(|r| r.contains(&stage))
}

/// What a file refers to.
#[derive(Debug, PartialEq)]
enum Ref {
    /// `crate::<stage>` on a line (1-based).
    Stage { line: usize, target: String },
    /// A `super::` chain of `hops` that leaves the stage folder, on a line.
    Escape { line: usize, hops: usize },
}

/// The text with comments and string and character literals blanked out (newlines
/// kept, so that line numbers stay right).
fn code_only(src: &str) -> Vec<char> {
    let c: Vec<char> = src.chars().collect();
    let mut out = c.clone();
    let blank = |out: &mut Vec<char>, from: usize, to: usize| {
        for ch in out.iter_mut().take(to.min(c.len())).skip(from) {
            if *ch != '\n' {
                *ch = ' ';
            }
        }
    };
    let ident = |ch: char| ch.is_alphanumeric() || ch == '_';
    let mut i = 0;
    while i < c.len() {
        let next = c.get(i + 1).copied();
        if c[i] == '/' && next == Some('/') {
            let end = (i..c.len()).find(|&k| c[k] == '\n').unwrap_or(c.len());
            blank(&mut out, i, end);
            i = end;
        } else if c[i] == '/' && next == Some('*') {
            let (mut k, mut depth) = (i + 2, 1);
            while k < c.len() && depth > 0 {
                if c[k] == '/' && c.get(k + 1) == Some(&'*') {
                    depth += 1;
                    k += 2;
                } else if c[k] == '*' && c.get(k + 1) == Some(&'/') {
                    depth -= 1;
                    k += 2;
                } else {
                    k += 1;
                }
            }
            blank(&mut out, i, k);
            i = k;
        } else if c[i] == '"' {
            let mut k = i + 1;
            while k < c.len() && c[k] != '"' {
                k += if c[k] == '\\' { 2 } else { 1 };
            }
            blank(&mut out, i, k + 1);
            i = k + 1;
        } else if c[i] == 'r' && (i == 0 || !ident(c[i - 1]) || (c[i - 1] == 'b' && (i < 2 || !ident(c[i - 2])))) && matches!(next, Some('"') | Some('#')) {
            // raw string r"..." / r#"..."# (also br"...")
            let hashes = (i + 1..c.len()).take_while(|&k| c[k] == '#').count();
            if c.get(i + 1 + hashes) != Some(&'"') {
                i += 1;
                continue;
            }
            let mut k = i + 2 + hashes;
            while k < c.len() && !(c[k] == '"' && (1..=hashes).all(|h| c.get(k + h) == Some(&'#'))) {
                k += 1;
            }
            blank(&mut out, i, k + 1 + hashes);
            i = k + 1 + hashes;
        } else if c[i] == '\'' {
            if next == Some('\\') {
                let end = (i + 3..c.len()).find(|&k| c[k] == '\'').unwrap_or(c.len());
                blank(&mut out, i, end + 1);
                i = end + 1;
            } else if c.get(i + 2) == Some(&'\'') {
                blank(&mut out, i, i + 3);
                i += 3;
            } else {
                i += 1; // a lifetime or a label
            }
        } else {
            i += 1;
        }
    }
    out
}

/// The references of a file whose module sits `depth` levels below its stage's
/// root module (src/x/mod.rs: 0, src/x/a.rs: 1, src/x/a/b.rs: 2; src/x.rs: 0).
fn references(src: &str, depth: usize) -> Vec<Ref> {
    let c = code_only(src);
    let ident = |ch: char| ch.is_alphanumeric() || ch == '_';
    let line_of = |i: usize| 1 + c[..i].iter().filter(|&&ch| ch == '\n').count();
    let skip_ws = |mut k: usize| {
        while k < c.len() && c[k].is_whitespace() {
            k += 1;
        }
        k
    };
    let word_at = |k: usize| -> (String, usize) {
        let end = (k..c.len()).find(|&e| !ident(c[e])).unwrap_or(c.len());
        (c[k..end].iter().collect(), end)
    };
    let path_sep = |k: usize| -> Option<usize> {
        let k = skip_ws(k);
        (c.get(k) == Some(&':') && c.get(k + 1) == Some(&':')).then(|| skip_ws(k + 2))
    };
    let mut refs = Vec::new();
    let (mut braces, mut mods, mut pending_mod) = (0usize, Vec::<usize>::new(), false);
    let mut i = 0;
    while i < c.len() {
        let ch = c[i];
        if ch == '{' {
            braces += 1;
            if pending_mod {
                mods.push(braces);
                pending_mod = false;
            }
            i += 1;
            continue;
        }
        if ch == '}' {
            if mods.last() == Some(&braces) {
                mods.pop();
            }
            braces = braces.saturating_sub(1);
            i += 1;
            continue;
        }
        if !ident(ch) || (i > 0 && ident(c[i - 1])) {
            i += 1;
            continue;
        }
        let (word, end) = word_at(i);
        match word.as_str() {
            "mod" => {
                // an inline module `mod name {` adds a level for `super`
                let k = skip_ws(end);
                let (name, after) = word_at(k);
                pending_mod = !name.is_empty() && c.get(skip_ws(after)) == Some(&'{');
            }
            "crate" => {
                if let Some(k) = path_sep(end) {
                    if c.get(k) == Some(&'{') {
                        // a group: the first name of every member at the top level
                        let (mut k, mut level, mut start) = (k + 1, 1, true);
                        while k < c.len() && level > 0 {
                            match c[k] {
                                '{' => level += 1,
                                '}' => level -= 1,
                                ',' if level == 1 => start = true,
                                x if start && ident(x) => {
                                    let (name, e) = word_at(k);
                                    if name != "self" {
                                        refs.push(Ref::Stage { line: line_of(k), target: name });
                                    }
                                    start = false;
                                    k = e;
                                    continue;
                                }
                                x if !x.is_whitespace() => start = false,
                                _ => {}
                            }
                            k += 1;
                        }
                    } else {
                        let (name, _) = word_at(k);
                        if !name.is_empty() {
                            refs.push(Ref::Stage { line: line_of(i), target: name });
                        }
                    }
                }
            }
            "super" => {
                // `super::super::...` (a bare `pub(super)` is a visibility, not a path)
                let (mut hops, mut k) = (0, i);
                loop {
                    let (w, e) = word_at(k);
                    if w != "super" {
                        break;
                    }
                    match path_sep(e) {
                        Some(n) => {
                            hops += 1;
                            k = n;
                        }
                        None => break,
                    }
                }
                if hops > depth + mods.len() {
                    refs.push(Ref::Escape { line: line_of(i), hops });
                }
                i = k.max(end);
                continue;
            }
            _ => {}
        }
        i = end;
    }
    refs
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let mut entries: Vec<PathBuf> = std::fs::read_dir(dir).expect("src/ is readable").map(|e| e.unwrap().path()).collect();
    entries.sort();
    for p in entries {
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|e| e == "rs") {
            out.push(p);
        }
    }
}

/// The stage of a file and the depth of its module below the stage's root module.
fn stage_of(rel: &Path) -> (String, usize) {
    let parts: Vec<String> = rel.iter().map(|p| p.to_string_lossy().into_owned()).collect();
    let stem = |s: &str| s.trim_end_matches(".rs").to_string();
    if parts.len() == 1 {
        return (stem(&parts[0]), 0);
    }
    let depth = if parts.last().map(String::as_str) == Some("mod.rs") { parts.len() - 2 } else { parts.len() - 1 };
    (parts[0].clone(), depth)
}

/// Every break of the order in the files under `src`, as messages.
fn violations(src: &Path) -> Vec<String> {
    let mut files = Vec::new();
    rust_files(src, &mut files);
    assert!(!files.is_empty(), "no .rs files under {}", src.display());
    let mut bad = Vec::new();
    for f in &files {
        let rel = f.strip_prefix(src).unwrap();
        if rel.components().count() == 1 && ROOTS.iter().any(|r| rel == Path::new(r)) {
            continue;
        }
        let shown = Path::new("src").join(rel).display().to_string();
        let (stage, depth) = stage_of(rel);
        let Some(own) = rank(&stage) else {
            bad.push(format!("{shown}: stage '{stage}' is not in the order of tests/layers.rs"));
            continue;
        };
        let text = std::fs::read_to_string(f).unwrap();
        for r in references(&text, depth) {
            match r {
                Ref::Stage { line, target } => {
                    if target == stage || target == BASE {
                        continue;
                    }
                    match rank(&target) {
                        Some(t) if t < own => {}
                        Some(_) => bad.push(format!("{shown}:{line}: stage '{stage}' uses stage '{target}', which is not below it")),
                        None => bad.push(format!("{shown}:{line}: stage '{stage}' uses crate::{target}, which is not a stage of the order")),
                    }
                }
                Ref::Escape { line, hops } => {
                    bad.push(format!("{shown}:{line}: stage '{stage}' climbs out of its folder with {hops} x super::"))
                }
            }
        }
    }
    bad
}

#[test]
fn every_stage_uses_only_the_stages_below_it() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let bad = violations(&src);
    assert!(bad.is_empty(), "{} references break the order of the stages (lowest first: {}):\n{}", bad.len(), ORDER.iter().map(|r| r.join(" / ")).collect::<Vec<_>>().join(" < "), bad.join("\n"));
}

#[test]
fn the_scanner_finds_paths_groups_and_escapes_and_skips_comments_and_strings() {
    let text = r##"
use crate::geometry::TriMesh;
use crate::{mesh::{self, TriMesh as T}, polycube,
    hex::HexMesh};
// crate::spline in a comment
/* crate::export in a block /* nested crate::export */ comment */
const S: &str = "crate::pipeline in a string";
const R: &str = r#"crate::pipeline in a raw "string""#;
const C: char = '"';
fn f<'a>(x: &'a str) -> usize { crate::search::auto::run(x) }
macro_rules! m { () => { $crate::ffi::guard() } }
pub(super) fn g() {}
mod tests {
    use super::super::X;
    mod inner {
        use super::super::super::Y;
    }
}
use super::super::Z;
"##;
    let refs = references(text, 1);
    let stages: Vec<(usize, &str)> = refs
        .iter()
        .filter_map(|r| match r {
            Ref::Stage { line, target } => Some((*line, target.as_str())),
            _ => None,
        })
        .collect();
    assert_eq!(stages, vec![(2, "geometry"), (3, "mesh"), (3, "polycube"), (4, "hex"), (10, "search"), (11, "ffi")]);
    let escapes: Vec<&Ref> = refs.iter().filter(|r| matches!(r, Ref::Escape { .. })).collect();
    assert_eq!(escapes, vec![&Ref::Escape { line: 19, hops: 2 }]);
    // a file at the root of its stage (src/x/mod.rs or src/x.rs) may not climb at all
    assert_eq!(references("use super::y;", 0), vec![Ref::Escape { line: 1, hops: 1 }]);
    assert_eq!(stage_of(Path::new("hex/voxel.rs")), ("hex".to_string(), 1));
    assert_eq!(stage_of(Path::new("hex/mod.rs")), ("hex".to_string(), 0));
    assert_eq!(stage_of(Path::new("error.rs")), ("error".to_string(), 0));
    assert_eq!(stage_of(Path::new("a/b/mod.rs")), ("a".to_string(), 1));
}
