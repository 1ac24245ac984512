//! `sddpm run` for callers inside a process (the C ABI's sddpm_run, the Python
//! package's `sddpm.run`): the command's own argument parser, checks and files,
//! without printing.

use super::{Cli, Command};
use clap::{CommandFactory, Parser};
use sddpm::error::{Error, Progress};
use sddpm::Result;
use serde_json::{json, Value};
use std::any::TypeId;
use std::path::PathBuf;

/// The main job with the arguments that follow `sddpm run` on the command line
/// (the mesh, `-o DIR` and any option of `sddpm run --help`), parsed as the
/// command parses them: the same checks and the same files in the folder
/// (report.json and report.html included), progress through `progress`, nothing
/// printed (`--quiet` and `--json` change nothing here). Returns report.json's content.
pub fn run_with_args(args: &[String], progress: &mut dyn Progress) -> Result<Value> {
    let a = parse_run_args(args)?;
    let command = std::iter::once("sddpm run".to_string()).chain(args.iter().map(|a| super::common::shell_quote(a))).collect::<Vec<_>>().join(" ");
    Ok(super::run::run_folder(&a, progress, &command)?.report)
}

fn parse_run_args(args: &[String]) -> Result<super::run::RunArgs> {
    let argv = ["sddpm", "run"].into_iter().map(String::from).chain(args.iter().cloned());
    match Cli::try_parse_from(argv) {
        Ok(Cli { command: Command::Run(a) }) => Ok(a),
        Ok(_) => Err(Error::Internal("the arguments of sddpm run parsed as another command".into())),
        Err(e) => Err(Error::InvalidArgument(parse_message(&e))),
    }
}

/// The parser's message on one line: what is wrong and its tip, without the usage.
fn parse_message(e: &clap::Error) -> String {
    use clap::error::ErrorKind;
    if matches!(e.kind(), ErrorKind::DisplayHelp | ErrorKind::DisplayVersion | ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand) {
        return "--help and --version are flags of the command line, not options of the main job".into();
    }
    let text = e.to_string();
    let lines: Vec<&str> = text
        .lines()
        .map(str::trim)
        .take_while(|l| !l.starts_with("Usage:") && !l.starts_with("For more information"))
        .filter(|l| !l.is_empty())
        .collect();
    let joined = lines.join("; ");
    joined.strip_prefix("error: ").unwrap_or(&joined).to_string()
}

/// Every argument of `sddpm run`, as a JSON array of objects: "name" (the argument's
/// long name, or "mesh" for the input), "kind" ("positional", "flag": present or
/// not, "value": one value, "list": repeatable), "type" ("bool", "int", "number",
/// "string", "path"), "required", "default" (null when none) and "help".
pub fn run_arguments() -> Value {
    let cli = Cli::command();
    let Some(run) = cli.find_subcommand("run") else {
        return json!([]);
    };
    let args: Vec<Value> = run
        .get_arguments()
        .filter(|a| !matches!(a.get_id().as_str(), "help" | "version"))
        .map(|a| {
            let kind = if a.is_positional() {
                "positional"
            } else if !a.get_action().takes_values() {
                "flag"
            } else if matches!(a.get_action(), clap::ArgAction::Append) {
                "list"
            } else {
                "value"
            };
            let defaults: Vec<String> = a.get_default_values().iter().map(|v| v.to_string_lossy().into_owned()).collect();
            json!({
                "name": a.get_long().map(str::to_string).unwrap_or_else(|| a.get_id().to_string()),
                "kind": kind,
                "type": value_type(a),
                "required": a.is_required_set(),
                "default": defaults.first(),
                "help": a.get_help().map(|h| h.to_string()).unwrap_or_default(),
            })
        })
        .collect();
    Value::Array(args)
}

fn value_type(a: &clap::Arg) -> &'static str {
    if !a.get_action().takes_values() {
        return "bool";
    }
    let t = a.get_value_parser().type_id();
    if t == TypeId::of::<PathBuf>() {
        "path"
    } else if t == TypeId::of::<f64>() || t == TypeId::of::<f32>() {
        "number"
    } else if [TypeId::of::<u32>(), TypeId::of::<u64>(), TypeId::of::<usize>(), TypeId::of::<i64>(), TypeId::of::<i32>()].iter().any(|x| t == *x) {
        "int"
    } else {
        "string"
    }
}
