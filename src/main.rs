//! The `asi-lift` command: its arguments and subcommands are in the library (src/lib.rs).

use clap::Parser;
use std::process::ExitCode;

fn main() -> ExitCode {
    match asi_lift::run(asi_lift::Cli::parse()) {
        Ok(code) => ExitCode::from(code),
        Err(msg) => {
            eprintln!("asi-lift: {msg}");
            ExitCode::FAILURE
        }
    }
}
