//! `dmpctl`: parses flags and calls the library. Exit codes: 0 success, 3 a run that completed with problems
//! (collision, stall, missed goal, non-finite values, late setpoints), 2 bad input (the message names the field), 1
//! any other failure.

use std::process::ExitCode;

use clap::Parser;
use dmp_client::without_source_paths;
use dmpctl::cli::{Cli, run};

/// The load generator decodes a hundred thousand segments a second (a few vectors each): mimalloc makes that
/// allocation cheaper than the system allocator, and leaves more of a shared machine to the server under test.
#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

fn main() -> ExitCode {
    let cli = Cli::parse();
    match run(cli) {
        Ok(out) => {
            println!("{out}");
            ExitCode::SUCCESS
        }
        Err(dmpctl::DmpctlError::Problems { summary, problems }) => {
            println!("{summary}");
            let problems = without_source_paths(&problems.join("; "));
            eprintln!("dmpctl: the run completed with problems: {problems}");
            ExitCode::from(3)
        }
        Err(e) => {
            // No source location of a library reaches the user.
            eprintln!("dmpctl: {}", without_source_paths(&e.to_string()));
            ExitCode::from(e.exit_code())
        }
    }
}
