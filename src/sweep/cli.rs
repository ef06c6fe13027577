//! The `nonlin3d sweep` subcommands (plan, run, status, merge) and `nonlin3d run` on a scene
//! with `[sweep]` (all three in one), with a progress bar over the cases on a terminal.

use super::plan::{Case, plan};
use super::run::{Outcome, RunOptions, run, status};
use crate::Error;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::io::IsTerminal;
use std::path::{Path, PathBuf};

/// `nonlin3d sweep …`.
#[derive(Debug, Clone, clap::Subcommand)]
pub enum SweepCommand {
    /// Expand a scene's `[sweep]` into DIR/cases/NNNN/scene.toml and DIR/plan.json.
    Plan {
        /// The scene (TOML) with a `[sweep]` table.
        scene: PathBuf,
        /// The study folder (new, or empty, or holding this same plan).
        #[arg(long)]
        out: PathBuf,
    },
    /// Run the cases that are not complete: all of them in parallel, or one (`--case K`, what a
    /// job-array task calls).
    Run {
        /// The study folder.
        dir: PathBuf,
        /// Only this case (0-based id).
        #[arg(long)]
        case: Option<usize>,
        /// Cases at once (default: one per core). Each case's solver runs on one thread unless
        /// `--threads` says otherwise.
        #[arg(long, default_value_t = 0)]
        jobs: usize,
    },
    /// Complete, failed, incomplete (running or killed) or missing, per case.
    Status {
        /// The study folder.
        dir: PathBuf,
    },
    /// Write DIR/study.csv, study.json and study.svg from the cases that are complete.
    Merge {
        /// The study folder.
        dir: PathBuf,
    },
}

/// How a sweep command failed: bad input (exit 2) or cases that did not complete (exit 1).
#[derive(Debug)]
pub struct Failure {
    /// The scene, plan or arguments are wrong.
    pub input: bool,
    /// What went wrong.
    pub error: Error,
}

fn input(error: Error) -> Failure {
    Failure { input: true, error }
}

fn failed(error: Error) -> Failure {
    Failure {
        input: false,
        error,
    }
}

/// Runs a `nonlin3d sweep` subcommand; `threads` is the global `--threads`.
pub fn main(command: SweepCommand, quiet: bool, threads: Option<usize>) -> Result<(), Failure> {
    crate::budget::install(None);
    match command {
        SweepCommand::Plan { scene, out } => {
            let p = plan(&scene, &out).map_err(input)?;
            if !quiet {
                println!(
                    "{} cases of {} in {} (fields: {})",
                    p.cases.len(),
                    scene.display(),
                    out.display(),
                    p.fields.join(", ")
                );
            }
            Ok(())
        }
        SweepCommand::Run { dir, case, jobs } => {
            let options = RunOptions {
                jobs,
                threads,
                case,
            };
            run_cases(&dir, options, quiet)
        }
        SweepCommand::Status { dir } => {
            let (plan, states) = status(&dir).map_err(input)?;
            let mut counts = std::collections::BTreeMap::new();
            for (c, s) in plan.cases.iter().zip(&states) {
                *counts.entry(s.name()).or_insert(0) += 1;
                let error = s.error().map(|e| format!(": {e}")).unwrap_or_default();
                println!("{:>5}  {:<10}  {}{error}", c.id, s.name(), c.label());
            }
            println!("{}", summary(&counts));
            Ok(())
        }
        SweepCommand::Merge { dir } => merge(&dir, quiet),
    }
}

/// `nonlin3d run SCENE --out DIR` on a scene with `[sweep]`: plan into DIR (kept if it holds
/// this plan already, so a second run resumes), run the cases, merge. `max_memory` bounds
/// each case (`--max-memory`), not the cases running together.
pub fn study(
    scene: &Path,
    out: &Path,
    quiet: bool,
    threads: Option<usize>,
    max_memory: Option<u64>,
) -> Result<(), Failure> {
    crate::budget::install(max_memory);
    let p = plan(scene, out).map_err(input)?;
    if !quiet {
        println!(
            "{} has a [sweep]: {} cases planned in {} (nonlin3d sweep plan/run/merge)",
            scene.display(),
            p.cases.len(),
            out.display()
        );
    }
    let ran = run_cases(
        out,
        RunOptions {
            threads,
            ..RunOptions::default()
        },
        quiet,
    );
    merge(out, quiet)?;
    ran
}

fn summary(counts: &std::collections::BTreeMap<&str, usize>) -> String {
    counts
        .iter()
        .map(|(k, n)| format!("{n} {k}"))
        .collect::<Vec<_>>()
        .join(", ")
}

fn merge(dir: &Path, quiet: bool) -> Result<(), Failure> {
    let merged = super::merge(dir).map_err(|e| match e {
        Error::Sweep(_) | Error::Io { .. } => input(e),
        other => failed(other),
    })?;
    if !quiet {
        println!(
            "{}: study.csv, study.json, study.svg ({})",
            dir.display(),
            summary(&merged.counts)
        );
    }
    Ok(())
}

/// Runs the cases with a bar over them (on a terminal) and a line per case.
fn run_cases(dir: &Path, options: RunOptions, quiet: bool) -> Result<(), Failure> {
    let total = match options.case {
        Some(_) => 1,
        None => super::Plan::read(dir).map_err(input)?.cases.len(),
    };
    let bar = if quiet || !std::io::stderr().is_terminal() {
        ProgressBar::hidden()
    } else {
        ProgressBar::with_draw_target(Some(total as u64), ProgressDrawTarget::stderr())
    };
    bar.set_style(
        ProgressStyle::with_template("{elapsed_precise} {bar:24} {pos}/{len} cases {wide_msg}")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let say = |line: String| {
        if quiet {
            return;
        }
        if bar.is_hidden() {
            eprintln!("{line}");
        } else {
            bar.println(line);
        }
    };
    let done = |case: &Case, o: &Outcome| {
        bar.inc(1);
        let what = if o.skipped {
            "complete already".to_string()
        } else {
            match o.state.error() {
                Some(e) => format!("failed in {:.1} s: {e}", o.seconds),
                None => format!("{} in {:.1} s", o.state.name(), o.seconds),
            }
        };
        say(format!("case {} ({}): {what}", case.id, case.label()));
    };
    let outcomes = run(dir, options, &done).map_err(input)?;
    bar.finish_and_clear();
    let bad: Vec<&Outcome> = outcomes
        .iter()
        .filter(|o| o.state.error().is_some())
        .collect();
    match bad.first() {
        None => Ok(()),
        Some(first) => Err(failed(Error::Sweep(format!(
            "{} of {} cases failed (the first, case {}: {}); `nonlin3d sweep status {}` \
             lists them",
            bad.len(),
            outcomes.len(),
            first.id,
            first.state.error().unwrap_or_default(),
            dir.display()
        )))),
    }
}
