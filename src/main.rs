//! The `sddpm` command line (see DESIGN.md "Command line" and `sddpm --help`).

mod cli;

fn main() {
    std::process::exit(cli::run());
}
