//! Command-line definitions. Each command lives in its own file and returns
//! an exit code: 0 on success, 2 on bad input (with `error: <what>` on stderr).
//! The `sddpm` binary calls [`run`]; [`run_with_args`] runs `sddpm run` inside a
//! process with the same parser (the C ABI's sddpm_run).

use clap::{Parser, Subcommand};

mod batch;
mod common;
mod context;
mod dataset;
mod evalmodel;
mod info;
mod library;
mod plotloss;
mod polycube;
mod run;
mod train;
mod weights;

pub use library::{run_arguments, run_with_args};

/// Exit code for bad input (DESIGN.md).
pub const EXIT_BAD_INPUT: i32 = 2;

#[derive(Parser, Debug)]
#[command(name = "sddpm", version, about = "Scalable DDPM-Polycube: CAD surface to polycube, all-hex mesh and volumetric spline")]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Subcommand, Debug)]
pub enum Command {
    /// Read a mesh, print what was measured, exit 2 if it cannot go on to meshing.
    Info(info::InfoArgs),
    /// Encode a context: one-hot vector, assembled genus, validity and the reason.
    Context(context::ContextArgs),
    /// Write the training set (tensors, contexts, a few assemblies as OBJ).
    Dataset(dataset::DatasetArgs),
    /// Generate and verify a polycube for a mesh (user-guided or automated).
    Polycube(polycube::PolycubeCommandArgs),
    /// The main job: polycube, hex mesh, spline, exports and report.html.
    Run(run::RunArgs),
    /// The main job on every mesh of a folder, files in parallel, with a summary table.
    Batch(batch::BatchArgs),
    /// Measure a model on held-in synthetic inputs (developer command).
    #[command(name = "eval-model")]
    EvalModel(evalmodel::EvalArgs),
    /// Plot a training loss log (loss.csv) as PNGs: whole run, last part, gradient.
    #[command(name = "plot-loss")]
    PlotLoss(plotloss::PlotLossArgs),
    /// Rewrite a weights file (--half: half precision, the embedded format).
    Weights(weights::WeightsArgs),
    /// Train the diffusion model (checkpoints every epoch; --resume continues).
    Train(train::TrainArgs),
}

pub fn run() -> i32 {
    let cli = match Cli::try_parse() {
        Ok(c) => c,
        Err(e) => {
            let code = if e.use_stderr() { EXIT_BAD_INPUT } else { 0 };
            let _ = e.print();
            return code;
        }
    };
    match cli.command {
        Command::Info(args) => info::run(&args),
        Command::Context(args) => context::run(&args).unwrap_or_else(fail),
        Command::Dataset(args) => dataset::run(&args).unwrap_or_else(fail),
        Command::Polycube(args) => polycube::run(&args).unwrap_or_else(fail),
        Command::Run(args) => run::run(&args).unwrap_or_else(fail),
        Command::Batch(args) => batch::run(&args).unwrap_or_else(fail),
        Command::EvalModel(args) => evalmodel::run(&args).unwrap_or_else(fail),
        Command::Train(args) => train::run(&args).unwrap_or_else(fail),
        Command::PlotLoss(args) => plotloss::run(&args).unwrap_or_else(fail),
        Command::Weights(args) => weights::run(&args).unwrap_or_else(fail),
    }
}

/// Print `error: <what>` on stderr and return the bad-input exit code.
pub fn fail(what: impl std::fmt::Display) -> i32 {
    eprintln!("error: {what}");
    EXIT_BAD_INPUT
}
