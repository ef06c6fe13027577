//! The `nonlin3d sweep` subcommands (plan, run, status, merge) and `nonlin3d run` on a scene
//! with `[sweep]` (all three in one), with a progress bar over the cases on a terminal; `sweep
//! submit` and the `--slurm` options of `sweep plan` for a Slurm cluster.

use super::cluster::Submitted;
use super::plan::{Case, Resolved, plan, plan_with};
use super::run::{Outcome, RunOptions, run};
use super::slurm::SlurmOptions;
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
        /// Also write DIR/slurm/sweep.sbatch, a Slurm job array over the cases
        /// (docs/CLUSTER.md).
        #[arg(long)]
        slurm: bool,
        /// Cases per array task (with --slurm; default: a minute of estimated work a task,
        /// and no fewer tasks than --max-parallel).
        #[arg(long, requires = "slurm")]
        per_task: Option<usize>,
        /// Slurm partition (with --slurm).
        #[arg(long, requires = "slurm")]
        partition: Option<String>,
        /// Slurm account (with --slurm).
        #[arg(long, requires = "slurm")]
        account: Option<String>,
        /// Wall time of each task, [D-]HH:MM:SS (with --slurm; default: estimated from the
        /// model size).
        #[arg(long, requires = "slurm")]
        time: Option<String>,
        /// Array tasks running at once (`--array=0-M%K`; with --slurm; 0: no limit).
        #[arg(long, default_value_t = 0, requires = "slurm")]
        max_parallel: usize,
    },
    /// Submit the study's Slurm job array (planned with --slurm) with sbatch; job ids in
    /// DIR/slurm/jobs.json.
    Submit {
        /// The study folder.
        dir: PathBuf,
        /// Only the failed, killed or missing cases that are not queued.
        #[arg(long)]
        failed: bool,
    },
    /// Run the cases that are not complete: all of them in parallel, or one (`--case K`, what a
    /// job-array task calls).
    Run {
        /// The study folder.
        dir: PathBuf,
        /// Only this case (0-based id).
        #[arg(long, conflicts_with = "cases")]
        case: Option<usize>,
        /// Only the cases FIRST-LAST (0-based ids, both included), or every STEP-th of them
        /// with FIRST-LAST/STEP, in one process: a job-array task's share.
        #[arg(long, value_name = "FIRST-LAST[/STEP]")]
        cases: Option<String>,
        /// Cases at once (default: one per core). Each case's solver runs on one thread unless
        /// `--threads` says otherwise.
        #[arg(long, default_value_t = 0)]
        jobs: usize,
    },
    /// Complete, failed, running, pending, incomplete or missing, per case (from the results
    /// on disk, and squeue/sacct for a submitted study).
    Status {
        /// The study folder.
        dir: PathBuf,
    },
    /// Write DIR/study.csv, study.json, study.svg and study-wall.csv from the cases on disk.
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
        SweepCommand::Plan {
            scene,
            out,
            slurm,
            per_task,
            partition,
            account,
            time,
            max_parallel,
        } => {
            let options = slurm.then_some(SlurmOptions {
                per_task,
                partition,
                account,
                time,
                max_parallel,
            });
            plan_command(&scene, &out, options.as_ref(), quiet)
        }
        SweepCommand::Submit { dir, failed } => {
            match super::cluster::submit(&dir, failed).map_err(input)? {
                Submitted::Job(j) => println!(
                    "submitted job {} ({}, {} tasks); `nonlin3d sweep status {}` follows it",
                    j.job_id,
                    j.array,
                    j.tasks.len(),
                    dir.display()
                ),
                Submitted::Nothing(why) => println!("{}: {why}", dir.display()),
            }
            Ok(())
        }
        SweepCommand::Run {
            dir,
            case,
            cases,
            jobs,
        } => {
            let (case, last, step) = match cases {
                None => (case, None, 1),
                Some(text) => {
                    let (range, step) = text.split_once('/').unwrap_or((&text, "1"));
                    let read = || {
                        let (a, b) = range.split_once('-')?;
                        let step: usize = step.trim().parse().ok().filter(|&s| s > 0)?;
                        Some((a.trim().parse().ok()?, b.trim().parse().ok()?, step))
                    };
                    match read() {
                        Some((a, b, step)) => (Some(a), Some(b), step),
                        None => {
                            return Err(input(Error::Sweep(format!(
                                "--cases '{text}': FIRST-LAST or FIRST-LAST/STEP, case ids and a \
                                 step of 1 or more, e.g. --cases 10-19 or --cases 3-199/20"
                            ))));
                        }
                    }
                }
            };
            let options = RunOptions {
                jobs,
                threads,
                case,
                last,
                step,
            };
            run_cases(&dir, options, quiet)
        }
        SweepCommand::Status { dir } => {
            let (plan, states, queue) = super::cluster::status(&dir).map_err(input)?;
            for (c, s) in plan.cases.iter().zip(&states) {
                let error = s.error().map(|e| format!(": {e}")).unwrap_or_default();
                println!("{:>5}  {:<10}  {}{error}", c.id, s.name(), c.label());
            }
            if dir.join(super::cluster::JOBS).is_file() {
                println!("(from {})", queue.source());
            }
            println!(
                "{}",
                super::cluster::counts(states.iter().map(|s| s.name()))
            );
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

/// `sweep plan`, with the Slurm script when `slurm` is given.
fn plan_command(
    scene: &Path,
    out: &Path,
    slurm: Option<&SlurmOptions>,
    quiet: bool,
) -> Result<(), Failure> {
    if let Some(o) = slurm {
        o.check().map_err(input)?;
    }
    let written = std::cell::RefCell::new(None);
    let extra = |folder: &Path, abs: &Path, p: &super::Plan, cases: &[Resolved]| {
        if let Some(o) = slurm {
            *written.borrow_mut() = Some(super::slurm::write(folder, abs, p, cases, o)?);
        }
        Ok(())
    };
    let p = plan_with(scene, out, Some(&extra)).map_err(input)?;
    if !quiet {
        println!(
            "{} cases of {} in {} (fields: {})",
            p.cases.len(),
            scene.display(),
            out.display(),
            p.fields.join(", ")
        );
        if let Some(s) = written.into_inner() {
            println!(
                "{}: {} array tasks of {} case(s), --mem={}M --time={} each (largest case: \
                 about {:.0} MiB, {:.1} s); `nonlin3d sweep submit {}` submits it",
                out.join(super::slurm::SCRIPT).display(),
                s.tasks,
                s.per_task,
                s.mem_mib,
                s.time,
                s.case_bytes as f64 / (1 << 20) as f64,
                s.case_seconds,
                out.display()
            );
        }
    }
    Ok(())
}

fn merge(dir: &Path, quiet: bool) -> Result<(), Failure> {
    let merged = super::merge(dir).map_err(|e| match e {
        Error::Sweep(_) | Error::Io { .. } => input(e),
        other => failed(other),
    })?;
    if !quiet {
        println!(
            "{}: study.csv, study.json, study.svg, study-wall.csv ({})",
            dir.display(),
            super::cluster::summary(&merged.counts)
        );
    }
    Ok(())
}

/// Runs the cases with a bar over them (on a terminal) and a line per case.
fn run_cases(dir: &Path, options: RunOptions, quiet: bool) -> Result<(), Failure> {
    let total = match options.case {
        Some(k) => options
            .last
            .map_or(1, |l| l.saturating_sub(k) / options.step.max(1) + 1),
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
