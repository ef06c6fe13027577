//! The `nonlin3d` command-line program.
//!
//! - `nonlin3d` or `nonlin3d eigen-check`: the element eigen-check of thesis §2.5.
//! - `nonlin3d solve DECK.inp --out DIR`: solves an Abaqus/CalculiX deck (the subset
//!   documented in `nonlin3d_mesh::read_inp`; linear or NLGEOM static steps) and writes
//!   `DIR/displacements.csv`, `DIR/step-K/displacements.csv` and `DIR/summary.json`.

use clap::{Parser, Subcommand};
use nonlin3d::newton::{NewtonSettings, Stepping};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

#[derive(Parser)]
#[command(
    name = "nonlin3d",
    version,
    about = "Geometrically nonlinear 3-D FE analysis of delaminated composite laminates"
)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
}

#[derive(Subcommand)]
enum Command {
    /// Zero-energy modes of distorted Hex20/Hex8 elements under each rule (thesis §2.5).
    EigenCheck,
    /// Solve an Abaqus/CalculiX .inp deck (static steps, NLGEOM or linear).
    Solve {
        /// The deck.
        deck: PathBuf,
        /// Output directory.
        #[arg(long, default_value = "nonlin3d-out")]
        out: PathBuf,
        /// Residual tolerance in N (the thesis used 1e-4 N, §4.4).
        #[arg(long, default_value_t = 1e-4)]
        tolerance: f64,
        /// First load-factor increment of each step.
        #[arg(long, default_value_t = 0.25)]
        increment: f64,
    },
}

fn solve(deck: &Path, out: &Path, tolerance: f64, increment: f64) -> Result<(), nonlin3d::Error> {
    let text = std::fs::read_to_string(deck)
        .map_err(|e| nonlin3d::Error::Numerical(format!("reading {}: {e}", deck.display())))?;
    let model = nonlin3d::mesh::read_inp(&text)?;
    let settings = NewtonSettings {
        force_tolerance: tolerance,
        ..NewtonSettings::default()
    };
    let stepping = Stepping {
        initial: increment,
        ..Stepping::default()
    };
    let results = nonlin3d::deck::solve_deck(&model, &settings, &stepping)?;
    nonlin3d::deck::write_results(out, &model, &results)?;
    for r in &results {
        let iterations: usize = r.increments.iter().map(|i| i.iterations).sum();
        println!(
            "step {}: {} increments, {iterations} iterations{}",
            r.step,
            r.increments.len(),
            if r.nlgeom { " (NLGEOM)" } else { "" }
        );
    }
    println!("results in {}", out.display());
    Ok(())
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        None | Some(Command::EigenCheck) => nonlin3d::eigen_check::run()
            .map(|rows| print!("{}", nonlin3d::eigen_check::report(&rows))),
        Some(Command::Solve {
            deck,
            out,
            tolerance,
            increment,
        }) => solve(&deck, &out, tolerance, increment),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("nonlin3d: {e}");
            ExitCode::FAILURE
        }
    }
}
