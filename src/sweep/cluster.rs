//! `nonlin3d sweep submit` and the scheduler's side of `sweep status`: the job array submitted
//! with `sbatch --parsable`, its job ids recorded in `DIR/slurm/jobs.json` (atomically), and
//! each case's state from its results on disk (which win) and, for the cases not finished on
//! disk, `squeue` (pending, running) and `sacct` where accounting is on (how a task ended).
//! Without either command the states come from the disk alone. `--failed` resubmits an array
//! of exactly the tasks holding failed, killed or missing cases and nothing queued.

use super::plan::Plan;
use super::run::{CaseState, case_state};
use super::slurm::{SCRIPT, Settings, array_option};
use crate::Error;
use crate::output::write_atomic;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::Path;
use std::process::Command;

/// The submitted jobs, in the study folder.
pub const JOBS: &str = "slurm/jobs.json";

/// One `sbatch` of the study.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Job {
    /// Slurm's job id (of the array).
    pub job_id: String,
    /// The array tasks submitted (indices into the script's chunks of cases).
    pub tasks: Vec<usize>,
    /// `--array=…` as given to sbatch.
    pub array: String,
    /// A `submit --failed`.
    pub failed_only: bool,
    /// When, s since 1970.
    pub submitted_unix: u64,
}

/// `DIR/slurm/jobs.json`.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct Jobs {
    /// Every submission, oldest first.
    pub jobs: Vec<Job>,
}

impl Jobs {
    /// Reads `DIR/slurm/jobs.json` (none yet: empty).
    pub fn read(dir: &Path) -> Result<Self, Error> {
        let path = dir.join(JOBS);
        match std::fs::read_to_string(&path) {
            Err(_) => Ok(Self::default()),
            Ok(text) => serde_json::from_str(&text)
                .map_err(|e| Error::Sweep(format!("{}: {e}", path.display()))),
        }
    }

    /// The latest job holding array task `task`.
    fn latest(&self, task: usize) -> Option<&Job> {
        self.jobs.iter().rev().find(|j| j.tasks.contains(&task))
    }
}

/// An array task as the scheduler reports it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum TaskState {
    /// Waiting (squeue PENDING, CONFIGURING, REQUEUED, SUSPENDED…).
    Pending,
    /// RUNNING or COMPLETING.
    Running,
    /// Left the queue; sacct's state when accounting is on (`TIMEOUT`, `CANCELLED by 0`…).
    Ended(Option<String>),
}

/// What the scheduler said about the study's jobs.
#[derive(Debug, Clone, Default)]
pub struct Queue {
    /// squeue answered (the tasks not listed have left the queue).
    pub squeue: bool,
    /// sacct answered (accounting on).
    pub sacct: bool,
    /// (job id, task) → state.
    pub tasks: BTreeMap<(String, usize), TaskState>,
}

impl Queue {
    /// squeue and sacct asked about `jobs`; what does not answer is left out.
    pub fn query(jobs: &Jobs) -> Self {
        let mut q = Self::default();
        if jobs.jobs.is_empty() {
            return q;
        }
        let ids: Vec<&str> = jobs.jobs.iter().map(|j| j.job_id.as_str()).collect();
        // The user's own jobs, one line per array task (`-r`): array job id, index, state.
        if let Some(text) = output("squeue", &["-h", "-r", "--me", "-o", "%F|%K|%T"]) {
            q.squeue = true;
            for line in text.lines() {
                let f: Vec<&str> = line.trim().split('|').collect();
                if let [job, task, state] = f[..]
                    && ids.contains(&job)
                    && let Ok(task) = task.parse::<usize>()
                {
                    let s = match state {
                        "RUNNING" | "COMPLETING" => TaskState::Running,
                        _ => TaskState::Pending,
                    };
                    q.tasks.insert((job.to_string(), task), s);
                }
            }
        }
        let list = ids.join(",");
        if let Some(text) = output(
            "sacct",
            &["-n", "-P", "-X", "-j", &list, "-o", "JobID,State"],
        ) {
            q.sacct = true;
            for line in text.lines() {
                if let Some((id, state)) = line.trim().split_once('|')
                    && let Some((job, task)) = id.split_once('_')
                    && let Ok(task) = task.parse::<usize>()
                {
                    let key = (job.to_string(), task);
                    let ended = !matches!(state, "PENDING" | "RUNNING" | "COMPLETING");
                    if ended || !q.squeue {
                        q.tasks.entry(key).or_insert(if ended {
                            TaskState::Ended(Some(state.to_string()))
                        } else if state == "RUNNING" {
                            TaskState::Running
                        } else {
                            TaskState::Pending
                        });
                    }
                }
            }
        }
        q
    }

    /// Whether the scheduler was reached at all.
    pub fn answered(&self) -> bool {
        self.squeue || self.sacct
    }

    /// Task `task` of `job`: listed, or ended when the scheduler answered without listing it.
    fn task(&self, job: &Job, task: usize) -> Option<TaskState> {
        match self.tasks.get(&(job.job_id.clone(), task)) {
            Some(s) => Some(s.clone()),
            None if self.answered() => Some(TaskState::Ended(None)),
            None => None,
        }
    }

    /// Which commands answered, in words.
    pub fn source(&self) -> &'static str {
        match (self.squeue, self.sacct) {
            (true, true) => "the results on disk, squeue and sacct",
            (true, false) => "the results on disk and squeue (sacct: no accounting)",
            (false, true) => "the results on disk and sacct (no squeue)",
            (false, false) => "the results on disk (no squeue or sacct answered)",
        }
    }
}

/// `program` to run with no signal blocked in the child. The `nonlin3d` program blocks SIGINT
/// and SIGTERM in all its threads (its src/signals.rs), and a child inherits the mask (std
/// does not reset it): `squeue` or `sbatch` would otherwise ignore Ctrl-C and SIGTERM.
fn command(program: &str) -> Command {
    #[allow(unused_mut)]
    let mut c = Command::new(program);
    #[cfg(unix)]
    {
        use std::os::unix::process::CommandExt;
        // SAFETY: the closure runs in the child between fork and exec, and calls only
        // sigemptyset and pthread_sigmask (async-signal-safe) on a set on its stack.
        unsafe {
            c.pre_exec(|| {
                let mut none: libc::sigset_t = std::mem::zeroed();
                libc::sigemptyset(&mut none);
                libc::pthread_sigmask(libc::SIG_SETMASK, &none, std::ptr::null_mut());
                Ok(())
            });
        }
    }
    c
}

/// Stdout of `program args` when it runs and succeeds.
fn output(program: &str, args: &[&str]) -> Option<String> {
    let o = command(program).args(args).output().ok()?;
    o.status
        .success()
        .then(|| String::from_utf8_lossy(&o.stdout).into_owned())
}

/// A case's state on a cluster: what its folder says, unless the scheduler knows better.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Seen {
    /// What results.json says (complete, failed, incomplete with no scheduler to say whether
    /// it still runs, missing and not queued).
    Disk(CaseState),
    /// Started, not finished, and its task has left the queue (cancelled, out of time, node
    /// failure): failed, with why.
    Killed(String),
    /// Its task runs it now.
    Running,
    /// Its task waits in the queue (or runs an earlier case of its chunk).
    Pending,
}

impl Seen {
    /// `complete`, `failed`, `running`, `pending`, `incomplete`, `missing`.
    pub fn name(&self) -> &'static str {
        match self {
            Self::Disk(d) => d.name(),
            Self::Killed(_) => "failed",
            Self::Running => "running",
            Self::Pending => "pending",
        }
    }

    /// Why a failed case failed.
    pub fn error(&self) -> Option<&str> {
        match self {
            Self::Disk(d) => d.error(),
            Self::Killed(e) => Some(e),
            _ => None,
        }
    }

    /// A case `submit --failed` runs again.
    pub fn to_resubmit(&self) -> bool {
        matches!(
            self,
            Self::Disk(CaseState::Failed(_) | CaseState::Incomplete | CaseState::Missing)
                | Self::Killed(_)
        )
    }

    /// results.json says complete.
    pub fn is_complete(&self) -> bool {
        *self == Self::Disk(CaseState::Complete)
    }
}

/// Every case of the study in `dir` with its state, from the disk and the scheduler.
pub fn status(dir: &Path) -> Result<(Plan, Vec<Seen>, Queue), Error> {
    let plan = Plan::read(dir)?;
    let jobs = Jobs::read(dir)?;
    let settings = Settings::read(dir).ok();
    let queue = Queue::query(&jobs);
    let disk: Vec<CaseState> = plan
        .cases
        .iter()
        .map(|c| case_state(&plan.case_dir(dir, c)))
        .collect();
    let seen = (0..disk.len())
        .map(|k| {
            let task = settings.as_ref().map(|s| s.task_of(k));
            let job = task.and_then(|t| jobs.latest(t));
            let queued = match (job, task) {
                (Some(j), Some(t)) => queue.task(j, t).map(|s| (j, t, s)),
                _ => None,
            };
            match (&disk[k], queued) {
                (d @ (CaseState::Complete | CaseState::Failed(_)), _) => Seen::Disk(d.clone()),
                (_, Some((_, _, TaskState::Pending))) => Seen::Pending,
                (d, Some((_, t, TaskState::Running))) => {
                    // A task runs its chunk in order: the first unfinished case is the one running.
                    let first = settings.as_ref().and_then(|s| {
                        s.cases_of(t).find(|&i| {
                            !matches!(disk[i], CaseState::Complete | CaseState::Failed(_))
                        })
                    });
                    if *d == CaseState::Incomplete || first == Some(k) {
                        Seen::Running
                    } else {
                        Seen::Pending
                    }
                }
                (CaseState::Incomplete, Some((j, t, TaskState::Ended(how)))) => {
                    Seen::Killed(format!(
                        "stopped before it finished: task {}_{t} {} (cancelled, out of time or its \
                         node failed); `nonlin3d sweep submit --failed` runs it again",
                        j.job_id,
                        how.map_or("left the queue".into(), |h| format!("ended {h}"))
                    ))
                }
                (d, _) => Seen::Disk(d.clone()),
            }
        })
        .collect();
    Ok((plan, seen, queue))
}

/// What [`submit`] did.
#[derive(Debug, Clone, PartialEq)]
pub enum Submitted {
    /// A job: its record.
    Job(Job),
    /// Nothing to run: every case complete, or queued already.
    Nothing(String),
}

/// Submits the study in `dir` (every task holding a case not complete), or with `failed` only
/// the tasks holding failed, killed or missing cases that are not queued. Refuses a plain
/// submit while a job of the study is queued, and a case folder it cannot write to.
pub fn submit(dir: &Path, failed: bool) -> Result<Submitted, Error> {
    let settings = Settings::read(dir)?;
    let script = dir.join(SCRIPT);
    if !script.is_file() {
        return Err(Error::Sweep(format!(
            "{}: missing: plan again with --slurm",
            script.display()
        )));
    }
    let (plan, seen, _queue) = status(dir)?;
    if plan.cases.len() != settings.cases {
        return Err(Error::Sweep(format!(
            "{}: written for {} cases, the plan has {}: plan again with --slurm",
            dir.join(super::slurm::SETTINGS).display(),
            settings.cases,
            plan.cases.len()
        )));
    }
    let busy = |t: usize| {
        settings
            .cases_of(t)
            .any(|k| matches!(seen[k], Seen::Running | Seen::Pending))
    };
    if !failed
        && let Some(k) = seen
            .iter()
            .position(|s| matches!(s, Seen::Running | Seen::Pending))
    {
        return Err(Error::Sweep(format!(
            "case {k} is {} in a job submitted before: wait for it, or `scancel` it, or \
             `nonlin3d sweep submit --failed {}` for the cases not queued",
            seen[k].name(),
            dir.display()
        )));
    }
    let tasks: Vec<usize> = (0..settings.tasks)
        .filter(|&t| !busy(t))
        .filter(|&t| {
            settings.cases_of(t).any(|k| {
                if failed {
                    seen[k].to_resubmit()
                } else {
                    !seen[k].is_complete()
                }
            })
        })
        .collect();
    if tasks.is_empty() {
        let counts = counts(seen.iter().map(Seen::name));
        return Ok(Submitted::Nothing(format!("nothing to submit ({counts})")));
    }
    // Every case a task will write must take a file: refused here, not in the queue.
    for &t in &tasks {
        for k in settings.cases_of(t) {
            writable(&plan.case_dir(dir, &plan.cases[k]))?;
        }
    }
    let array = array_option(&tasks, settings.max_parallel);
    let job_id = sbatch(dir, &array)?;
    let job = Job {
        job_id,
        tasks,
        array,
        failed_only: failed,
        submitted_unix: std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(0, |d| d.as_secs()),
    };
    let mut jobs = Jobs::read(dir)?;
    jobs.jobs.push(job.clone());
    write_atomic(
        &dir.join(JOBS),
        serde_json::to_string_pretty(&jobs)?.as_bytes(),
    )?;
    Ok(Submitted::Job(job))
}

/// Refuses a case folder that cannot take a new file (a task writes its results there).
fn writable(folder: &Path) -> Result<(), Error> {
    let probe = folder.join(format!(".nonlin3d-submit-{}", std::process::id()));
    match std::fs::write(&probe, b"") {
        Ok(()) => {
            let _ = std::fs::remove_file(&probe);
            Ok(())
        }
        Err(e) => Err(Error::Sweep(format!(
            "{}: not writable ({e}): its task could not write its results there; nothing \
             submitted",
            folder.display()
        ))),
    }
}

/// `sbatch --parsable ARRAY slurm/sweep.sbatch` in `dir`: the job id.
fn sbatch(dir: &Path, array: &str) -> Result<String, Error> {
    let o = command("sbatch")
        .args(["--parsable", array, SCRIPT])
        .current_dir(dir)
        .output()
        .map_err(|e| {
            Error::Sweep(format!(
                "sbatch could not be run ({e}): submit from a machine with Slurm's commands \
                 on PATH, or run the study here with `nonlin3d sweep run {}`",
                dir.display()
            ))
        })?;
    let out = String::from_utf8_lossy(&o.stdout);
    let err = String::from_utf8_lossy(&o.stderr);
    let id = out.trim().split(';').next().unwrap_or_default().to_string();
    if !o.status.success() || id.is_empty() || !id.bytes().all(|b| b.is_ascii_digit()) {
        return Err(Error::Sweep(format!(
            "sbatch {array} {SCRIPT} failed ({}): {}; nothing submitted",
            o.status,
            [err.trim(), out.trim()]
                .iter()
                .filter(|s| !s.is_empty())
                .copied()
                .collect::<Vec<_>>()
                .join(" / ")
        )));
    }
    Ok(id)
}

/// `3 complete, 1 failed`: how many of each name.
pub(crate) fn counts<'a>(names: impl Iterator<Item = &'a str>) -> String {
    let mut counts = std::collections::BTreeMap::new();
    for n in names {
        *counts.entry(n).or_insert(0) += 1;
    }
    summary(&counts)
}

pub(crate) fn summary(counts: &std::collections::BTreeMap<&str, usize>) -> String {
    counts
        .iter()
        .map(|(k, n)| format!("{n} {k}"))
        .collect::<Vec<_>>()
        .join(", ")
}

#[cfg(all(test, target_os = "linux"))]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    /// Whether `sig` is in the `SigBlk:` mask of a /proc status text.
    fn blocks(status: &str, sig: i32) -> bool {
        status
            .lines()
            .find_map(|l| l.strip_prefix("SigBlk:"))
            .and_then(|m| u64::from_str_radix(m.trim(), 16).ok())
            .is_some_and(|m| m >> (sig - 1) & 1 == 1)
    }

    /// A child started while this thread blocks SIGTERM (as every thread of the program does)
    /// blocks nothing; started by `Command` alone, it blocks SIGTERM too (std keeps the mask).
    #[test]
    fn children_start_with_no_signal_blocked() {
        // SAFETY: this test thread's own mask, put back at the end.
        let previous = unsafe {
            let mut set: libc::sigset_t = std::mem::zeroed();
            libc::sigemptyset(&mut set);
            libc::sigaddset(&mut set, libc::SIGTERM);
            let mut previous: libc::sigset_t = std::mem::zeroed();
            libc::pthread_sigmask(libc::SIG_BLOCK, &set, &mut previous);
            previous
        };
        let child = |mut c: Command| {
            let o = c.args(["SigBlk", "/proc/self/status"]).output();
            o.map(|o| String::from_utf8_lossy(&o.stdout).into_owned())
        };
        let ours = child(command("grep"));
        let plain = child(Command::new("grep"));
        // SAFETY: restoring the mask pthread_sigmask gave back above.
        unsafe { libc::pthread_sigmask(libc::SIG_SETMASK, &previous, std::ptr::null_mut()) };
        let (ours, plain) = (ours.unwrap(), plain.unwrap());
        assert!(!blocks(&ours, libc::SIGTERM), "{ours}");
        assert!(blocks(&plain, libc::SIGTERM), "{plain}");
    }
}
