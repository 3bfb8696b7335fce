//! The `illum` command line: parses the arguments and calls the library's [`illum::cli`], where
//! each command lives in its own module.

use clap::Parser;

#[derive(Parser)]
#[command(
    name = "illum",
    version,
    about = "Physically based rendering on Vulkan"
)]
struct Cli {
    #[command(subcommand)]
    command: illum::cli::Command,
}

fn main() {
    std::process::exit(illum::cli::run(Cli::parse().command));
}
