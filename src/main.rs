//! The `cstep` command: evaluate, benchmark, and (with the node) serve C-STEP.

mod cli;

use std::process::ExitCode;

use clap::Parser;

fn main() -> ExitCode {
    let command = cli::Cli::parse();
    match cli::run(command) {
        Ok(()) => ExitCode::SUCCESS,
        Err(error) => {
            eprintln!("cstep: error: {error}");
            ExitCode::FAILURE
        }
    }
}
