//! The `cachert` command: parses flags, runs the library, prints the result. Every failure prints
//! `error: file:line:col: …` (with the offending line and a caret when there is one) and exits with status 2.

use std::process::ExitCode;

use clap::Parser;

fn main() -> ExitCode {
    let cli = cachert::cli::Cli::parse();
    match cachert::cli::run(&cli) {
        Ok(out) => {
            if !out.is_empty() {
                println!("{}", out.trim_end());
            }
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("error: {e}");
            if let Some(x) = e.excerpt() {
                eprintln!("{x}");
            }
            ExitCode::from(2)
        }
    }
}
