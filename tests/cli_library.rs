//! `sddpm run` inside a process (sddpm::cli::run_with_args, under the C ABI's
//! sddpm_run): its argument list and the parser's refusals. The runs themselves
//! are tested from Python (bindings/python/tests/test_run.py) against the command.

use sddpm::cli::{run_arguments, run_with_args};
use sddpm::error::{Error, NoProgress};
use serde_json::Value;

fn args(a: &[&str]) -> Vec<String> {
    a.iter().map(|s| s.to_string()).collect()
}

#[test]
fn run_arguments_name_every_option_of_the_command() {
    let v = run_arguments();
    let find = |n: &str| v.as_array().unwrap().iter().find(|a| a["name"] == n).cloned().unwrap_or(Value::Null);
    assert_eq!(find("mesh")["kind"], "positional");
    assert_eq!(find("mesh")["type"], "path");
    assert_eq!(find("output")["required"], true);
    assert_eq!(find("level")["type"], "int");
    assert_eq!(find("level")["kind"], "value");
    assert_eq!(find("weld-tolerance")["type"], "number");
    assert_eq!(find("constraints")["type"], "path");
    assert_eq!(find("no-spline")["kind"], "flag");
    assert_eq!(find("labels")["kind"], "list");
    assert_eq!(find("generator")["default"], "learned");
    assert!(find("level")["help"].as_str().unwrap().contains("octree"));
    assert!(v.as_array().unwrap().iter().all(|a| a["name"] != "help" && a["name"] != "version"));
}

#[test]
fn parse_errors_are_one_line_without_usage() {
    let dir = tempfile::tempdir().unwrap();
    let out = format!("--output={}", dir.path().join("out").display());
    let mesh = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/meshes/cgal_hole.off");
    for (bad, what) in [("--levl=2", "--levl"), ("--level=x", "--level"), ("--help", "--help")] {
        let e = run_with_args(&args(&[&out, bad, mesh]), &mut NoProgress).unwrap_err();
        let m = e.to_string();
        assert!(matches!(e, Error::InvalidArgument(_)), "{m}");
        assert!(m.contains(what) && !m.contains("Usage") && !m.contains('\n'), "{m}");
    }
    let e = run_with_args(&args(&[mesh]), &mut NoProgress).unwrap_err();
    assert!(e.to_string().contains("--output"), "{e}");
    // a value the command refuses after parsing, before the folder is made
    let e = run_with_args(&args(&[&out, "--goal-hausdorff=-1", mesh]), &mut NoProgress).unwrap_err();
    assert!(e.to_string().contains("--goal-hausdorff"), "{e}");
    assert!(!dir.path().join("out").exists());
}
