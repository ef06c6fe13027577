//! `nonlin3d solve DECK.inp`: the deck read and checked, solved increment by increment with
//! the status lines and files written as it goes, and `summary.json` at the end
//! ([`nonlin3d::deck`] does the work).

use crate::progress::Verbosity;
use crate::{Failure, lock, signals, watch};
use nonlin3d::newton::NewtonSettings;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// The arguments of `nonlin3d solve`.
#[derive(clap::Args)]
pub(crate) struct SolveArgs {
    /// The deck.
    pub(crate) deck: PathBuf,
    /// Output directory.
    #[arg(long, default_value = "nonlin3d-solve-out")]
    pub(crate) out: PathBuf,
    /// Absolute residual tolerance in N instead of the default relative criterion
    /// (‖r‖∞ ≤ 1e-8 of the largest external or reaction force; docs/THEORY.md).
    #[arg(long)]
    pub(crate) tolerance: Option<f64>,
    /// First increment of every NLGEOM step as a fraction of its period, every increment
    /// with DIRECT (default: the deck's *STATIC initial increment).
    #[arg(long)]
    pub(crate) increment: Option<f64>,
    /// Linear solver: auto (faer-mixed from 4 000 DOF in NLGEOM steps that keep a
    /// factorisation over many iterations — BFGS, modified Newton — with each direction solved
    /// to 1 % of the residual; faer elsewhere), faer (LDLᵀ, f64), faer-mixed (f32 factor refined in f64 to the
    /// same residual; falls back to f64 where f32 is not enough) or profile (the thesis's
    /// skyline).
    #[arg(long, default_value = "auto", value_parser = ["auto", "faer", "faer-mixed", "profile"])]
    pub(crate) solver: String,
    /// Factorisations in a static step: auto (bfgs in *STATIC, DIRECT steps, full where
    /// the increment size follows the iteration count), bfgs (the kept tangent updated by BFGS pairs,
    /// factorised anew when an iteration more than doubles ‖r‖, and at each converged increment
    /// for its negative pivots), modified (the kept tangent without BFGS pairs, factorised anew
    /// when ‖r‖ falls by less than half) or full (a factorisation every iteration, as
    /// CalculiX). An increment bfgs or modified cannot converge is redone by full Newton.
    #[arg(long, default_value = "auto", value_parser = ["auto", "bfgs", "modified", "full"])]
    pub(crate) newton: String,
    /// Start of an increment without prescribed-value changes: the step's last converged
    /// states extrapolated in step time (quadratic through three, linear through two) or
    /// the last state (none).
    #[arg(long, default_value = "quadratic", value_parser = ["quadratic", "linear", "none"])]
    pub(crate) extrapolation: String,
    /// Keep an extrapolated start only if its ‖r‖∞ is no larger than the last state's.
    #[arg(long)]
    pub(crate) guard: bool,
    /// Backtracking line search on ‖r‖∞ in every iteration (off, as CalculiX iterates).
    #[arg(long)]
    pub(crate) line_search: bool,

    /// Memory the solve may use (2GiB, 500MB, 1.5G); the machine's available memory and the
    /// process's own limits apply as well. A deck whose factor does not fit is refused after
    /// the symbolic analysis, with the estimate and the limit.
    #[arg(long, value_parser = nonlin3d::budget::parse_size)]
    pub(crate) max_memory: Option<u64>,
}

/// `nonlin3d solve`: the arguments read into [`SolveFlags`], the deck solved.
pub(crate) fn run(args: &SolveArgs, verbosity: Verbosity) -> Result<(), Failure> {
    let flags = SolveFlags {
        tolerance: args.tolerance,
        increment: args.increment,
        solver: &args.solver,
        // clap admits only these three names.
        newton: args.newton.parse().unwrap_or_default(),
        start: nonlin3d::deck::IncrementStart {
            extrapolation: match args.extrapolation.as_str() {
                "none" => 0,
                "linear" => 1,
                _ => 2,
            },
            guarded: args.guard,
            line_search: args.line_search,
        },
        max_memory: args.max_memory,
    };
    solve(&args.deck, &args.out, &flags, verbosity)
}

/// What `solve` takes beyond the deck and the output folder.
pub(crate) struct SolveFlags<'a> {
    tolerance: Option<f64>,
    increment: Option<f64>,
    solver: &'a str,
    newton: nonlin3d::deck::Strategy,
    start: nonlin3d::deck::IncrementStart,
    max_memory: Option<u64>,
}

pub(crate) fn solve(
    deck: &Path,
    out: &Path,
    flags: &SolveFlags<'_>,
    verbosity: Verbosity,
) -> Result<(), Failure> {
    let SolveFlags {
        tolerance,
        increment,
        solver,
        max_memory,
        ..
    } = *flags;
    use nonlin3d::deck::Progress;
    let t0 = Instant::now();
    nonlin3d::budget::install(max_memory);
    let model = nonlin3d::mesh::read_inp_file(deck)
        .map_err(|e| Failure::Input(nonlin3d::Error::from(e)))?;
    let input = nonlin3d::provenance::input_file(deck).map_err(Failure::Input)?;
    let mut newton = match tolerance {
        // An absolute tolerance replaces the relative one, as in a scene's tolerance_n.
        Some(t) => NewtonSettings {
            force_tolerance: t,
            relative_tolerance: 0.0,
            ..NewtonSettings::default()
        },
        None => NewtonSettings::default(),
    };
    use nonlin3d::solver::SolverKind;
    newton.solver = match solver {
        "faer-mixed" => SolverKind::FaerLdltMixed(0),
        "profile" => SolverKind::Profile,
        _ => SolverKind::FaerLdlt,
    };
    let kept_solver = (solver == "auto").then_some(SolverKind::FaerLdltKept(0));
    let options = nonlin3d::deck::StepOptions {
        newton,
        initial_increment: increment,
        start: flags.start,
        strategy: flags.newton,
        kept_solver,
    };
    // Bad input (no step, an inverted element, …) and an output folder that cannot be written
    // are found before anything is solved; each increment lands there as it converges.
    let checked = nonlin3d::deck::check(&model, &options).map_err(Failure::Input)?;
    let mut provenance =
        nonlin3d::provenance::Provenance::new(Some(input), None, options.newton.solver);
    if let Some(kept) = kept_solver {
        let (kept, _) = nonlin3d::provenance::solver_names(kept);
        provenance.solver = format!(
            "{kept}, in steps that keep a factorisation (BFGS, modified Newton); {} in the others",
            provenance.solver
        );
    }
    provenance.stage("read_and_check", t0.elapsed().as_secs_f64());
    let mut output = nonlin3d::deck::DeckOutput::create(out, &model).map_err(Failure::Input)?;
    output.set_provenance(provenance).map_err(Failure::Run)?;
    signals::stop_on(output.interrupt_handle());
    let monitor = watch(verbosity, "step", output.status_files());
    let steps = model.steps.len();
    lock(&monitor).units(steps);
    for n in &model.not_used {
        lock(&monitor).say(&format!("not used: {}, {}: {}", n.at, n.keyword, n.reason));
    }
    // The status lines on this thread as each report comes; the files on a thread of their own
    // when the solve has two or more (`write_in_background`), else here.
    let report = |p: Progress<'_>| {
        let mut m = lock(&monitor);
        match p {
            Progress::Increment(r) => {
                let last = r.increments.iter().rev().find(|i| i.converged);
                let done = last.map_or(0.0, |i| i.step_time / r.period.max(f64::MIN_POSITIVE));
                m.begin(r.step, done);
            }
            Progress::Step(r) => {
                let iterations: usize = r.increments.iter().map(|i| i.iterations).sum();
                let done = r.increments.iter().filter(|i| i.converged).count();
                let contact = r
                    .increments
                    .iter()
                    .rev()
                    .find_map(|i| i.contact.as_ref())
                    .map(|c| {
                        format!(
                            "; contact: {} pairs closed, max force {:.4e}",
                            c.pairs_closed, c.max_force
                        )
                    })
                    .unwrap_or_default();
                m.say(&format!(
                    "step {}: {done} increments ({} attempts), {iterations} iterations{}{contact}",
                    r.step,
                    r.increments.len(),
                    if r.nlgeom { " (NLGEOM)" } else { "" }
                ));
                // A Riks step: the load proportionality factor by increment, as Abaqus's
                // status file lists it.
                for i in r.increments.iter().filter(|i| i.lpf.is_some()) {
                    m.say(&format!(
                        "  increment {:3}: LPF {:+.6e}, arc length {:.4e}, {} iterations",
                        i.increment,
                        i.lpf.unwrap_or_default(),
                        i.arc_length.unwrap_or_default(),
                        i.iterations
                    ));
                }
                // The step's factor: the numbers CalculiX and Abaqus print for a step.
                if let Some(f) = &r.factor {
                    m.say(&format!("  {}", f.line()));
                }
                // `--solver faer-mixed`: whether the f32 factor held, by increment.
                for i in r.increments.iter() {
                    if let Some(mp) = &i.mixed_precision {
                        m.say(&format!("  increment {:3}: {}", i.increment, mp.line()));
                    }
                }
                // The next step's events are numbered within it.
                m.begin(r.step + 1, 0.0);
            }
            Progress::Failed(_) => {}
        }
    };
    let (outcome, written) = if rayon::current_num_threads() >= 2 {
        nonlin3d::deck::write_in_background(&mut output, |write| {
            nonlin3d::deck::solve_checked_with(&model, &options, checked, &mut |p| {
                report(p);
                write(p)
            })
        })
    } else {
        let outcome = nonlin3d::deck::solve_checked_with(&model, &options, checked, &mut |p| {
            report(p);
            output.progress(p)
        });
        (outcome, Ok(()))
    };
    let status_error = lock(&monitor).finish();
    // A write that failed after the last report fails the solve as one before it would.
    let outcome = outcome.and_then(|r| written.map(|()| r));
    let results = match outcome {
        Ok(r) => r,
        Err(e) => {
            // Keep what converged, say why it stopped; the write error (if any) is secondary.
            let _ = output.failed(&e);
            return Err(Failure::Run(nonlin3d::Error::Partial {
                source: Box::new(e),
                folder: out.to_path_buf(),
                kept: "increments",
                summary: "summary.json",
            }));
        }
    };
    output.finish(&results).map_err(Failure::Run)?;
    if let Some(e) = status_error {
        return Err(Failure::Run(e));
    }
    lock(&monitor).say(&format!("results in {}", out.display()));
    Ok(())
}
