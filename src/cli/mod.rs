//! The `sddpm` command line (DESIGN.md, "Command line").

pub mod train;

use clap::{Parser, Subcommand};

#[derive(Parser, Debug)]
#[command(name = "sddpm", version, about = "CAD surface to polycube, all-hex mesh and volumetric spline (SDDPM)")]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Subcommand, Debug)]
pub enum Command {
    /// Train the diffusion model.
    Train(train::TrainArgs),
}

/// Run a parsed command line; returns the process exit code.
pub fn run(cli: Cli) -> i32 {
    let r = match &cli.command {
        Command::Train(a) => train::run(a),
    };
    match r {
        Ok(code) => code,
        Err(e) => {
            eprintln!("error: {e}");
            2
        }
    }
}
