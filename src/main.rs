//! The `nonlin3d` command-line program.
//!
//! - `nonlin3d` or `nonlin3d run [SCENE.toml] [--out DIR]`: runs a scene (docs/SCENES.md); with
//!   none, the thesis's reference case (30 mm circle, ε = −0.001 … −0.005). Prints a table,
//!   writes `DIR/results.json`, `front_K.csv`, `model.pvd` + `model_K.vtu`, SVG plots.
//! - `nonlin3d export SCENE.toml --inp FILE`: the scene as a CalculiX deck.
//! - `run` and `export` take `--max-memory SIZE` (2GiB, 500MB): the run stays below it and
//!   below the machine's and the process's own limits, or stops with the estimate.
//! - `nonlin3d eigen-check`: the element eigen-check of thesis §2.5.
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
    /// Run a scene (default: the thesis's 30 mm circular delamination, Fig. 5.1.3).
    Run {
        /// The scene (TOML); omitted: the built-in reference scene.
        scene: Option<PathBuf>,
        /// Output directory.
        #[arg(long, default_value = "nonlin3d-out")]
        out: PathBuf,
        /// No progress bar.
        #[arg(long)]
        quiet: bool,
        /// Memory the run may use (2GiB, 500MB, 1.5G); the machine's and the process's own
        /// limits apply as well.
        #[arg(long, value_parser = nonlin3d::budget::parse_size)]
        max_memory: Option<u64>,
    },
    /// Write a scene as an Abaqus/CalculiX deck.
    Export {
        /// The scene (TOML).
        scene: PathBuf,
        /// The deck to write.
        #[arg(long)]
        inp: PathBuf,
        /// Memory the export may use (2GiB, 500MB, 1.5G).
        #[arg(long, value_parser = nonlin3d::budget::parse_size)]
        max_memory: Option<u64>,
    },
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

fn read_scene(path: Option<&Path>) -> Result<nonlin3d::Scene, nonlin3d::Error> {
    match path {
        None => nonlin3d::Scene::thesis_reference(),
        Some(p) => {
            let text = std::fs::read_to_string(p).map_err(|source| nonlin3d::Error::Io {
                path: p.to_path_buf(),
                source,
            })?;
            nonlin3d::Scene::from_toml(&text)
                .map_err(|e| nonlin3d::Error::Scene(format!("{}: {e}", p.display())))
        }
    }
}

fn run(
    scene: Option<&Path>,
    out: &Path,
    quiet: bool,
    max_memory: Option<u64>,
) -> Result<(), nonlin3d::Error> {
    use indicatif::{ProgressBar, ProgressStyle};
    use nonlin3d::analysis::Progress;
    nonlin3d::budget::install(max_memory);
    let scene = read_scene(scene)?;
    println!("{}", scene.title);
    let bar = if quiet {
        ProgressBar::hidden()
    } else {
        ProgressBar::new(0)
    };
    bar.set_style(
        ProgressStyle::with_template(
            "{spinner} [{elapsed_precise}] {bar:30} {pos}/{len} levels {msg}",
        )
        .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    bar.set_message("building the model");
    let mut results = nonlin3d::analysis::run(&scene, &mut |p| match p {
        Progress::Built {
            nodes,
            dofs,
            levels,
        } => {
            bar.set_length(levels as u64);
            bar.set_message(format!("{nodes} nodes, {dofs} DOFs"));
        }
        Progress::Level { index, value } => {
            bar.set_position(index as u64 + 1);
            bar.set_message(format!("level {value} converged"));
        }
    })?;
    bar.finish_and_clear();
    nonlin3d::report::write_all(&mut results, out)?;
    print!("{}", nonlin3d::report::table(&results));
    println!("results in {}", out.display());
    Ok(())
}

fn export(scene: &Path, inp: &Path, max_memory: Option<u64>) -> Result<(), nonlin3d::Error> {
    nonlin3d::budget::install(max_memory);
    let scene = read_scene(Some(scene))?;
    let text = nonlin3d::export::deck(&scene)?;
    std::fs::write(inp, text).map_err(|source| nonlin3d::Error::Io {
        path: inp.to_path_buf(),
        source,
    })?;
    println!("wrote {}", inp.display());
    Ok(())
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        None => run(None, Path::new("nonlin3d-out"), false, None),
        Some(Command::Run {
            scene,
            out,
            quiet,
            max_memory,
        }) => run(scene.as_deref(), &out, quiet, max_memory),
        Some(Command::Export {
            scene,
            inp,
            max_memory,
        }) => export(&scene, &inp, max_memory),
        Some(Command::EigenCheck) => nonlin3d::eigen_check::run()
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
