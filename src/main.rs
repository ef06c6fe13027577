//! The `nonlin3d` command-line program.
//!
//! Until the delamination analysis pipeline lands, it runs the element eigen-check of thesis
//! §2.5 on distorted elements of every kind and rule and prints the table.

use std::process::ExitCode;

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.iter().any(|a| a == "-h" || a == "--help") {
        println!(
            "nonlin3d {}\n\nUSAGE: nonlin3d\n\nRuns the element eigen-check (thesis §2.5) and prints the zero-energy modes of",
            env!("CARGO_PKG_VERSION")
        );
        println!("distorted Hex20/Hex8 elements under each integration rule.");
        return ExitCode::SUCCESS;
    }
    if let Some(a) = args.first() {
        eprintln!("nonlin3d: unexpected argument '{a}' (try --help)");
        return ExitCode::from(2);
    }
    match nonlin3d::eigen_check::run() {
        Ok(rows) => {
            print!("{}", nonlin3d::eigen_check::report(&rows));
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("nonlin3d: {e}");
            ExitCode::FAILURE
        }
    }
}
