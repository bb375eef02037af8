//! The `cachert` command: parses flags, runs the library, prints the result. Every failure prints
//! `error: file:line:col: …` (with the offending line and a caret when there is one) and exits with status 2;
//! a check that ran and found failures (`golden check`) exits with status 1.

use std::io::Write;
use std::process::ExitCode;

use clap::Parser;

fn main() -> ExitCode {
    let cli = cachert::cli::Cli::parse();
    match cachert::cli::run(&cli) {
        Ok(done) => {
            let out = done.text;
            if !out.is_empty() {
                // A closed pipe (`cachert compare … | head -1`) is not an error of ours.
                let mut stdout = std::io::stdout().lock();
                if let Err(e) = writeln!(stdout, "{}", out.trim_end())
                    && e.kind() != std::io::ErrorKind::BrokenPipe
                {
                    eprintln!("error: cannot write to standard output: {e}");
                    return ExitCode::from(2);
                }
            }
            if done.passed { ExitCode::SUCCESS } else { ExitCode::from(1) }
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
