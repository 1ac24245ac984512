//! The `sddpm` command line (see DESIGN.md "Command line" and `sddpm --help`).

fn main() {
    std::process::exit(sddpm::cli::run());
}
