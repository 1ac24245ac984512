//! `sddpm plot-loss CSV -o DIR`: the training loss curve, its last part and its
//! gradient as PNG plots (`sddpm train` also draws them at every checkpoint).

use sddpm::export::plot::plot_loss;
use sddpm::Result;
use std::path::PathBuf;

#[derive(clap::Args, Debug)]
pub struct PlotLossArgs {
    /// loss.csv of a checkpoint folder (e.g. models/default.sddpmw.ckpt/loss.csv).
    pub csv: PathBuf,
    /// Output folder.
    #[arg(short = 'o', long = "output")]
    pub output: PathBuf,
    /// Moving-average window, in log entries.
    #[arg(long, default_value_t = 20)]
    pub window: usize,
}

pub fn run(a: &PlotLossArgs) -> Result<i32> {
    for f in plot_loss(&a.csv, &a.output, a.window)? {
        println!("{}", a.output.join(f).display());
    }
    Ok(0)
}
