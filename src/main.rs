use clap::Parser;

fn main() {
    let cli = sddpm::cli::Cli::parse();
    std::process::exit(sddpm::cli::run(cli));
}
