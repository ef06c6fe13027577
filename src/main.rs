//! The `nonlin3d` command-line program.
//!
//! - `nonlin3d` or `nonlin3d run [SCENE.toml] [--out DIR]`: runs a scene (docs/SCENES.md); with
//!   none, the thesis's reference case (30 mm circle, ε = −0.001 … −0.005). Prints a table,
//!   writes `DIR/results.json`, `front_K.csv`, `model.pvd` + `model_K.vtu`, SVG plots.
//! - `nonlin3d export SCENE.toml --inp FILE`: the scene as a CalculiX deck.
//! - `run`, `export` and `solve` take `--max-memory SIZE` (2GiB, 500MB): the run stays below
//!   it and below the machine's and the process's own limits, or stops with the estimate.
//! - `nonlin3d eigen-check`: the element eigen-check of thesis §2.5.
//! - `nonlin3d study SCENE.toml --knobs KNOBS.toml --out DIR`: speed against error over the
//!   knobs file's cases (`DIR/study.json`, `study.csv`, `study.svg`, a table).
//! - `nonlin3d sweep plan|run|status|merge`: a parametric study from a scene's `[sweep]`
//!   ([`nonlin3d::sweep`]); `run` on such a scene plans, runs and merges it into `--out`.
//! - `nonlin3d solve DECK.inp --out DIR`: solves an Abaqus/CalculiX deck (the subset in
//!   docs/DECKS.md; linear or NLGEOM static steps) and writes `DIR/displacements.csv`,
//!   `DIR/step-K/displacements.csv`, the output requests per increment
//!   (`DIR/step-K/node-print-SET.csv`, …) and `DIR/summary.json`; DIR defaults to
//!   `nonlin3d-solve-out` (run's to `nonlin3d-out`).
//! - Both write `status.sta` (a line per attempt) and `convergence.cvg` (a line per Newton
//!   iteration) as they go, `manifest.json` (the files they wrote, removed by the next run into
//!   the folder), and a `provenance` block in results.json / summary.json.
//! - `-v`: one line per Newton iteration on stderr; `-q`: nothing but errors. The progress bar
//!   is drawn on stderr only when it is a terminal.
//!
//! Exit status: 0 complete; 1 the analysis (or writing its results) failed; 2 bad input (scene,
//! deck, arguments, an output folder that cannot be written); 130 interrupted by SIGINT, 143 by
//! SIGTERM. `run` writes each level and `solve` each increment as it converges, so a failed or
//! interrupted run leaves everything converged so far, with `"complete": false` in results.json
//! (summary.json for `solve`).

mod progress;
mod signals;
mod solve_command;
mod study_command;

use clap::{Parser, Subcommand};
use progress::{Monitor, Shared, Verbosity};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

#[derive(Parser)]
#[command(
    name = "nonlin3d",
    version,
    about = "Geometrically nonlinear 3-D FE analysis of delaminated composite laminates",
    after_help = "Exit status: 0 complete; 1 analysis failed (converged levels kept, results.json \
                  \"complete\": false); 2 bad input; 130 interrupted (SIGINT), 143 (SIGTERM)."
)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
    /// One line per Newton iteration on stderr: increment, attempt, iteration, ‖r‖, ‖Δu‖,
    /// negative pivots, time.
    #[arg(short, long, global = true, conflicts_with = "quiet")]
    verbose: bool,
    /// Nothing but errors.
    #[arg(short, long, global = true)]
    quiet: bool,
    /// Threads for assembly and the factorisation (default: all cores); the results are
    /// bitwise identical for any count. Overrides a scene's `threads`.
    #[arg(long, global = true,
          value_parser = clap::builder::RangedU64ValueParser::<usize>::new().range(0..=1024))]
    threads: Option<usize>,
}

impl Cli {
    fn verbosity(&self) -> Verbosity {
        match (self.quiet, self.verbose) {
            (true, _) => Verbosity::Quiet,
            (_, true) => Verbosity::Verbose,
            _ => Verbosity::Normal,
        }
    }
}

#[derive(Subcommand)]
enum Command {
    /// Run a scene (default: the thesis's 30 mm circular delamination on the default mesh).
    Run {
        /// The scene (TOML); omitted: the built-in reference scene.
        scene: Option<PathBuf>,
        /// Output directory.
        #[arg(long, default_value = "nonlin3d-out")]
        out: PathBuf,
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
    /// A parametric study from a scene's [sweep]: plan, run (all cases or one), status, merge.
    #[command(subcommand)]
    Sweep(nonlin3d::sweep::cli::SweepCommand),
    /// Zero-energy modes of distorted Hex20/Hex8 elements under each rule (thesis §2.5).
    EigenCheck,
    /// Speed against error: the scene over the knobs file's cases (docs/ACCURACY.md §4).
    Study {
        /// The scene (TOML).
        scene: PathBuf,
        /// The cases: `[common]` and `[[case]]` tables of scene knobs.
        #[arg(long)]
        knobs: PathBuf,
        /// Output directory (study.json, study.csv, study.svg).
        #[arg(long, default_value = "nonlin3d-study")]
        out: PathBuf,
        /// Cases run side by side, each on one thread (default: --threads or all cores).
        #[arg(long)]
        jobs: Option<usize>,
    },
    /// Solve an Abaqus/CalculiX .inp deck (static steps, NLGEOM or linear).
    Solve(solve_command::SolveArgs),
}

/// The monitor of a command, fed with Newton's events through `tracing` and writing them to
/// `files`.
fn watch(verbosity: Verbosity, unit: &'static str, files: nonlin3d::log::StatusFiles) -> Shared {
    use tracing_subscriber::layer::SubscriberExt;
    let mut monitor = Monitor::new(verbosity, unit);
    monitor.write_to(files);
    let monitor = monitor.shared();
    let subscriber = tracing_subscriber::registry().with(progress::layer(&monitor));
    // Only fails if one is set already (a command runs once per process).
    let _ = tracing::subscriber::set_global_default(subscriber);
    monitor
}

/// The monitor, locked (a panic elsewhere while it was held leaves it usable).
fn lock(monitor: &Shared) -> std::sync::MutexGuard<'_, Monitor> {
    monitor
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner)
}

fn read_scene(path: Option<&Path>) -> Result<nonlin3d::Scene, nonlin3d::Error> {
    match path {
        None => nonlin3d::Scene::reference(),
        Some(p) => {
            let text = std::fs::read_to_string(p).map_err(|source| nonlin3d::Error::Io {
                path: p.to_path_buf(),
                source,
            })?;
            // A study is not one scene: say what to do instead of toml's "unknown field".
            if nonlin3d::sweep::has_sweep(&text) {
                return Err(nonlin3d::Error::Scene(format!(
                    "{}: this scene has a [sweep] table, so it is a study, not one scene: \
                     `nonlin3d run` runs it, `nonlin3d sweep plan` writes one scene per case \
                     (cases/NNNN/scene.toml), which this command takes",
                    p.display()
                )));
            }
            // "scene: FILE: what", not "scene: FILE: scene: what".
            nonlin3d::Scene::from_toml(&text).map_err(|e| {
                let what = match e {
                    nonlin3d::Error::Scene(m) => m,
                    other => other.to_string(),
                };
                nonlin3d::Error::Scene(format!("{}: {what}", p.display()))
            })
        }
    }
}

/// How a command failed, for the exit status (README, `--help`): bad input exits 2, a failure
/// of the analysis or of writing its results 1.
enum Failure {
    /// The scene, deck or arguments are wrong: nothing was computed.
    Input(nonlin3d::Error),
    /// The analysis or the writing of its results failed.
    Run(nonlin3d::Error),
}

impl Failure {
    fn code(&self) -> u8 {
        match self {
            Self::Input(_) => 2,
            Self::Run(_) => 1,
        }
    }

    fn error(&self) -> &nonlin3d::Error {
        match self {
            Self::Input(e) | Self::Run(e) => e,
        }
    }
}

fn run(
    path: Option<&Path>,
    out: &Path,
    verbosity: Verbosity,
    max_memory: Option<u64>,
    threads: Option<usize>,
) -> Result<(), Failure> {
    use nonlin3d::analysis::Progress;
    let t0 = Instant::now();
    // A scene with [sweep] is a study: planned, run and merged into `out`.
    if let Some(p) =
        path.filter(|p| std::fs::read_to_string(p).is_ok_and(|t| nonlin3d::sweep::has_sweep(&t)))
    {
        let quiet = verbosity == Verbosity::Quiet;
        return nonlin3d::sweep::cli::study(p, out, quiet, threads, max_memory)
            .map_err(sweep_failure);
    }
    nonlin3d::budget::install(max_memory);
    let mut scene = read_scene(path).map_err(Failure::Input)?;
    let input = path
        .map(nonlin3d::provenance::input_file)
        .transpose()
        .map_err(Failure::Input)?;
    if let Some(n) = threads {
        scene.analysis.threads = n;
    }
    let quantity = if matches!(scene.geometry, nonlin3d::scene::Geometry::Plate { .. }) {
        "load_n"
    } else {
        "strain"
    };
    // The folder is made and tested before anything is computed; each level lands there as
    // it converges.
    let mut output =
        nonlin3d::output::RunOutput::create(out, &scene.title, quantity).map_err(Failure::Input)?;
    let mut provenance = nonlin3d::provenance::Provenance::new(
        input,
        serde_json::to_value(&scene).ok(),
        nonlin3d::analysis::settings(&scene).0.solver,
    );
    provenance.stage("read", t0.elapsed().as_secs_f64());
    output.set_provenance(provenance).map_err(Failure::Run)?;
    signals::stop_on(output.interrupt_handle());
    let monitor = watch(verbosity, "level", output.status_files());
    lock(&monitor).say(&scene.title);
    for w in scene.warnings() {
        lock(&monitor).warn(&w);
    }
    lock(&monitor).message("building the model".into());
    let outcome = nonlin3d::analysis::run(&scene, &mut |p| match p {
        Progress::Built {
            model,
            dofs,
            levels,
        } => {
            let mut m = lock(&monitor);
            m.units(levels);
            m.begin(1, 0.0);
            m.message(format!("{} nodes, {dofs} DOFs", model.mesh.nodes.len()));
            drop(m);
            output.built(model, dofs)
        }
        Progress::Level {
            index,
            value,
            result,
        } => {
            let mut m = lock(&monitor);
            m.begin(index + 2, 0.0);
            m.message(format!("level {} at {value} converged", index + 1));
            drop(m);
            output.level(result)
        }
    });
    let status_error = lock(&monitor).finish();
    let mut results = match outcome {
        Ok(r) => r,
        Err(e) => {
            // Keep what converged, say why it stopped; the write error (if any) is secondary.
            let _ = output.failed(&e);
            let input = matches!(e, nonlin3d::Error::Scene(_) | nonlin3d::Error::Laminate(_));
            return Err(if input {
                Failure::Input(e)
            } else {
                Failure::Run(nonlin3d::Error::Partial {
                    source: Box::new(e),
                    folder: out.to_path_buf(),
                    kept: "levels",
                    summary: "results.json",
                })
            });
        }
    };
    output.finish(&mut results).map_err(Failure::Run)?;
    if let Some(e) = status_error {
        return Err(Failure::Run(e));
    }
    let m = lock(&monitor);
    m.say(nonlin3d::report::table(&results).trim_end());
    m.say(&format!("results in {}", out.display()));
    Ok(())
}

fn sweep_failure(f: nonlin3d::sweep::cli::Failure) -> Failure {
    if f.input {
        Failure::Input(f.error)
    } else {
        Failure::Run(f.error)
    }
}

fn export(
    scene: &Path,
    inp: &Path,
    max_memory: Option<u64>,
    verbosity: Verbosity,
) -> Result<(), Failure> {
    nonlin3d::budget::install(max_memory);
    let scene = read_scene(Some(scene)).map_err(Failure::Input)?;
    let loud = verbosity != Verbosity::Quiet;
    for w in scene.warnings().iter().filter(|_| loud) {
        eprintln!("nonlin3d: warning: {w}");
    }
    let text = nonlin3d::export::deck(&scene).map_err(Failure::Input)?;
    nonlin3d::output::write_atomic(inp, text.as_bytes()).map_err(Failure::Run)?;
    if loud {
        println!("wrote {}", inp.display());
    }
    Ok(())
}

fn main() -> ExitCode {
    // Before any thread exists: SIGINT and SIGTERM go to one thread only (src/signals.rs).
    if let Err(e) = signals::block() {
        eprintln!("nonlin3d: {e}");
        return ExitCode::from(1);
    }
    let cli = Cli::parse();
    // One rayon pool for assembly and the solver; 0 or none: all cores.
    if let Some(n) = cli.threads.filter(|&n| n > 0)
        && let Err(e) = rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build_global()
    {
        eprintln!("nonlin3d: --threads {n}: {e}");
        return ExitCode::from(2);
    }
    let verbosity = cli.verbosity();
    // The command runs on a worker of that pool (rayon::scope from outside the pool runs its
    // body there), so its own joins start on the pool: a join made from a thread outside the
    // pool hands both halves to the workers and waits on a lock for them (about 4 % of a
    // two-thread deck solve at 9 k DOF).
    let result = rayon::scope(move |_| match cli.command {
        None => run(
            None,
            Path::new("nonlin3d-out"),
            verbosity,
            None,
            cli.threads,
        ),
        Some(Command::Run {
            scene,
            out,
            max_memory,
        }) => run(scene.as_deref(), &out, verbosity, max_memory, cli.threads),
        Some(Command::Export {
            scene,
            inp,
            max_memory,
        }) => export(&scene, &inp, max_memory, verbosity),
        Some(Command::Study {
            scene,
            knobs,
            out,
            jobs,
        }) => study_command::study(&scene, &knobs, &out, jobs.unwrap_or(0), verbosity),
        // -q: nothing but errors, as for every command (the table is the report).
        Some(Command::Sweep(command)) => {
            nonlin3d::sweep::cli::main(command, verbosity == Verbosity::Quiet, cli.threads)
                .map_err(sweep_failure)
        }
        Some(Command::EigenCheck) => nonlin3d::eigen_check::run()
            .map(|rows| {
                if !matches!(verbosity, Verbosity::Quiet) {
                    print!("{}", nonlin3d::eigen_check::report(&rows))
                }
            })
            .map_err(Failure::Run),
        Some(Command::Solve(args)) => solve_command::run(&args, verbosity),
    });
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(f) => {
            eprintln!("nonlin3d: {}", f.error());
            ExitCode::from(f.code())
        }
    }
}
