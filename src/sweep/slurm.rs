//! `nonlin3d sweep plan --slurm`: the study's job-array script, `DIR/slurm/sweep.sbatch`, and
//! its settings, `DIR/slurm/slurm.json`. Of T = ⌈cases / N⌉ tasks (`N` = `--per-task`), task `i`
//! runs cases `i, i + T, i + 2T, …` in one process, `nonlin3d sweep run DIR --cases
//! i-LAST/T --jobs 1` (for N = 1 case `i` alone), by the absolute paths of the program and of DIR, so the
//! script runs from any folder of a shared file system; a case complete already is skipped by
//! `sweep run` itself. Memory and time are asked for from the
//! model size ([`crate::budget::estimate_scene`]) of the largest case, with margins
//! ([`MEMORY_MARGIN`], [`TIME_MARGIN`]); `--time` replaces the time estimate.

use super::plan::{Plan, Resolved};
use crate::Error;
use crate::output::write_atomic;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// The job-array script, in the study folder.
pub const SCRIPT: &str = "slurm/sweep.sbatch";
/// The script's settings (what `sweep submit` reads back).
pub const SETTINGS: &str = "slurm/slurm.json";
/// The tasks' output and error files, `%A_%a.out` / `.err` (job id, array index).
pub const LOGS: &str = "slurm/logs";

/// Memory asked for: the budget's estimate of the largest case's peak, times this. The
/// estimate's factor is 0.75–1.13 times faer's count above 2 M entries and the rest of the
/// peak is counted at 56 B per tangent nonzero against 45–57 measured (src/budget.rs); the
/// peak resident size of `nonlin3d run` measured 1.22 and 1.28 times the estimate on coarse
/// through-width scenes of 131 and 278 MiB estimated (this machine, 2026-11-24), so 1.5 leaves
/// a sixth or more to spare.
pub const MEMORY_MARGIN: f64 = 1.5;
/// Least memory asked for, MiB (the process, its libraries and the case's output files).
pub const MEMORY_FLOOR_MIB: u64 = 256;
/// Time asked for: the largest case's estimate ([`case_seconds`]) times this, times the cases
/// per task.
pub const TIME_MARGIN: f64 = 3.0;
/// Least time asked for per task, s (start-up and a loaded node).
pub const TIME_FLOOR_S: u64 = 300;
/// Estimated work per array task when `--per-task` is not given, s: Slurm costs about 0.5 s of
/// a CPU slot per task (scheduling, slurmstepd, a process start: docs/CLUSTER.md), so a task of
/// a minute's estimated work loses under 1 % to it. Measured on the 200-case study of
/// docs/CLUSTER.md (0.03–0.1 s a case on an idle node): one case per task took 3× the local
/// wall, 10 per task 1.85×, 100 per task (as many tasks as slots) 1.02–1.05×.
pub const TASK_SECONDS: f64 = 60.0;

/// The `--slurm` options of `sweep plan`.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct SlurmOptions {
    /// Cases per array task (1 or more); `None`: [`default_per_task`].
    pub per_task: Option<usize>,
    /// `--partition`, passed through.
    pub partition: Option<String>,
    /// `--account`, passed through.
    pub account: Option<String>,
    /// `--time` (`[D-]HH:MM:SS`), instead of the estimate.
    pub time: Option<String>,
    /// Tasks running at once (`%K`; 0: as many as Slurm gives).
    pub max_parallel: usize,
}

impl SlurmOptions {
    /// Checks the options before anything is planned.
    pub fn check(&self) -> Result<(), Error> {
        let bad = |m: String| Err(Error::Sweep(m));
        if self.per_task == Some(0) {
            return bad("--per-task 0: one case per task or more".into());
        }
        for (flag, v) in [
            ("--partition", &self.partition),
            ("--account", &self.account),
        ] {
            if let Some(v) = v
                && (v.is_empty()
                    || v.contains(|c: char| c.is_whitespace() || c == '\'' || c == '"'))
            {
                return bad(format!(
                    "{flag} '{v}': a Slurm name, without spaces or quotes"
                ));
            }
        }
        if let Some(t) = &self.time {
            parse_time(t)?;
        }
        Ok(())
    }
}

/// `DIR/slurm/slurm.json`: how the script was made.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Settings {
    /// The program the tasks run (absolute).
    pub program: String,
    /// The study folder (absolute).
    pub dir: String,
    /// Cases in the plan.
    pub cases: usize,
    /// Cases per task.
    pub per_task: usize,
    /// Array tasks: ⌈cases / per_task⌉.
    pub tasks: usize,
    /// Tasks at once (0: no limit).
    pub max_parallel: usize,
    /// `--mem` of each task, MiB.
    pub mem_mib: u64,
    /// `--time` of each task.
    pub time: String,
    /// The largest case's estimated peak memory, bytes.
    pub case_bytes: u64,
    /// The largest case's estimated wall time, s.
    pub case_seconds: f64,
    /// `--partition`.
    pub partition: Option<String>,
    /// `--account`.
    pub account: Option<String>,
}

impl Settings {
    /// Reads `DIR/slurm/slurm.json`.
    pub fn read(dir: &Path) -> Result<Self, Error> {
        let path = dir.join(SETTINGS);
        let text = std::fs::read_to_string(&path).map_err(|_| {
            Error::Sweep(format!(
                "{}: no Slurm script in this study: plan it with `nonlin3d sweep plan SCENE --out \
                 {} --slurm`",
                path.display(),
                dir.display()
            ))
        })?;
        serde_json::from_str(&text)
            .map_err(|e| Error::Sweep(format!("{}: {e}: plan again with --slurm", path.display())))
    }

    /// The cases of array task `task`.
    /// Strided, `task`, `task + T`, `task + 2T`, … (T tasks), so that every task holds a
    /// mix of the study (cases along the last field grow or shrink together): contiguous
    /// chunks of the 200-case study ended with one task running its largest cases alone.
    pub fn cases_of(&self, task: usize) -> impl Iterator<Item = usize> + use<> {
        (task..self.cases).step_by(self.tasks.max(1))
    }

    /// The array task that runs case `case`.
    pub fn task_of(&self, case: usize) -> usize {
        case % self.tasks.max(1)
    }
}

/// Reads a Slurm time `[D-]HH:MM:SS` (or `MM:SS`, or minutes) into seconds.
pub fn parse_time(text: &str) -> Result<u64, Error> {
    let bad = || {
        Error::Sweep(format!(
            "--time '{text}': a wall time as Slurm writes it, [D-]HH:MM:SS (e.g. 00:30:00 or \
             1-12:00:00)"
        ))
    };
    let (days, rest) = match text.split_once('-') {
        Some((d, r)) => (d.parse::<u64>().map_err(|_| bad())?, r),
        None => (0, text),
    };
    let parts: Vec<u64> = rest
        .split(':')
        .map(|p| p.parse::<u64>().map_err(|_| bad()))
        .collect::<Result<_, _>>()?;
    let s = match parts[..] {
        [h, m, s] if m < 60 && s < 60 => h * 3600 + m * 60 + s,
        [m, s] if days == 0 && s < 60 => m * 60 + s,
        [m] if days == 0 => m * 60,
        _ => return Err(bad()),
    };
    let s = days * 86_400 + s;
    if s == 0 {
        return Err(bad());
    }
    Ok(s)
}

/// Seconds as a Slurm time: `HH:MM:SS`, or `D-HH:MM:SS` from a day on.
pub fn format_time(seconds: u64) -> String {
    let (d, r) = (seconds / 86_400, seconds % 86_400);
    let hms = format!("{:02}:{:02}:{:02}", r / 3600, r % 3600 / 60, r % 60);
    if d > 0 { format!("{d}-{hms}") } else { hms }
}

/// Sustained LDLᵀ rate assumed for the time estimate, flop/s: a fifth of faer's measured 53
/// GFLOP/s on one core (docs/PERFORMANCE.md), since the study's models are small.
const FACTOR_RATE: f64 = 10e9;
/// Newton iterations assumed per level (a level converges in 3–6; cut-backs and the stability
/// check's factorisations counted in).
const ITERATIONS_PER_LEVEL: f64 = 10.0;
/// Element work per iteration and cell, s (9 µs per Hex20 kernel, measured, with assembly and
/// the residual: 30 µs).
const SECONDS_PER_CELL: f64 = 30e-6;

/// A case's wall time, estimated from its model size (one solver thread): levels × iterations
/// × (factorisation F²/n flops at `FACTOR_RATE` + element work), plus a second of start-up.
/// F²/n is the least Σ c_k² of n columns holding F entries (flops of an LDLᵀ, within 2×).
pub fn case_seconds(resolved: &Resolved) -> f64 {
    let e = crate::budget::estimate_scene(&resolved.scene);
    let levels = resolved
        .scene
        .loads
        .strains
        .len()
        .max(resolved.scene.loads.transverse_n.len())
        .max(1) as f64;
    let f = e.factor_entries as f64;
    let flops = f * f / (e.dofs.max(1) as f64);
    let per_iteration = flops / FACTOR_RATE + e.cells as f64 * SECONDS_PER_CELL;
    1.0 + levels * ITERATIONS_PER_LEVEL * per_iteration
}

/// Cases per task when `--per-task` is not given: enough for [`TASK_SECONDS`] of estimated
/// work, ⌈TASK_SECONDS / case_seconds⌉, but no fewer tasks than `max_parallel` slots (0: no
/// limit given) so that none idles, and at least one case.
pub fn default_per_task(cases: usize, case_seconds: f64, max_parallel: usize) -> usize {
    let cases = cases.max(1);
    let for_time = if case_seconds > 0.0 {
        (TASK_SECONDS / case_seconds).ceil() as usize
    } else {
        cases
    };
    let for_slots = if max_parallel > 0 {
        cases.div_ceil(max_parallel)
    } else {
        cases
    };
    for_time.min(for_slots).clamp(1, cases)
}

/// The settings of a study's script: the largest case's memory and time, with margins.
pub fn settings(
    dir: &Path,
    program: &Path,
    cases: &[Resolved],
    o: &SlurmOptions,
) -> Result<Settings, Error> {
    let case_bytes = cases
        .iter()
        .map(|r| crate::budget::estimate_scene(&r.scene).bytes)
        .max()
        .unwrap_or(0);
    let case_seconds = cases.iter().map(case_seconds).fold(0.0, f64::max);
    let mib = (case_bytes as f64 * MEMORY_MARGIN / (1 << 20) as f64).ceil() as u64;
    let mem_mib = mib.max(MEMORY_FLOOR_MIB).div_ceil(64) * 64;
    let per_task = o
        .per_task
        .unwrap_or_else(|| default_per_task(cases.len(), case_seconds, o.max_parallel))
        .max(1);
    let time = match &o.time {
        Some(t) => format_time(parse_time(t)?),
        None => {
            let s = (case_seconds * TIME_MARGIN * per_task as f64).ceil() as u64;
            format_time(s.max(TIME_FLOOR_S).div_ceil(60) * 60)
        }
    };
    Ok(Settings {
        program: program.display().to_string(),
        dir: dir.display().to_string(),
        cases: cases.len(),
        per_task,
        tasks: cases.len().div_ceil(per_task),
        max_parallel: o.max_parallel,
        mem_mib,
        time,
        case_bytes,
        case_seconds,
        partition: o.partition.clone(),
        account: o.account.clone(),
    })
}

/// `text` quoted for the shell: in single quotes, a single quote written `'\''`.
pub fn shell_quote(text: &str) -> String {
    format!("'{}'", text.replace('\'', r"'\''"))
}

/// Array indices as Slurm reads them: runs as ranges (`0-3,5,7-9`).
pub fn array_list(indices: &[usize]) -> String {
    let mut out: Vec<String> = Vec::new();
    let mut i = 0;
    while i < indices.len() {
        let mut j = i;
        while j + 1 < indices.len() && indices[j + 1] == indices[j] + 1 {
            j += 1;
        }
        out.push(if j > i {
            format!("{}-{}", indices[i], indices[j])
        } else {
            indices[i].to_string()
        });
        i = j + 1;
    }
    out.join(",")
}

/// `--array=LIST[%K]`.
pub fn array_option(indices: &[usize], max_parallel: usize) -> String {
    let throttle = if max_parallel > 0 {
        format!("%{max_parallel}")
    } else {
        String::new()
    };
    format!("--array={}{throttle}", array_list(indices))
}

/// The job-array script.
pub fn script(plan: &Plan, s: &Settings) -> String {
    let name: String = plan
        .title
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '-' })
        .take(40)
        .collect();
    let name = name.trim_matches('-');
    let logs = Path::new(&s.dir).join(LOGS);
    let all: Vec<usize> = (0..s.tasks).collect();
    let mut o = String::from("#!/bin/bash\n");
    o += &format!(
        "# {} cases of '{}' ({}), {} per task, written by `nonlin3d sweep plan --slurm`.\n\
         # Submit with `nonlin3d sweep submit {}` (or sbatch this file; `--array` on sbatch's \
         command line replaces the one below).\n\
         # Memory: the largest case's estimated peak {:.0} MiB x {MEMORY_MARGIN}; time: its \
         estimated {:.1} s x {TIME_MARGIN} x {} cases per task, at least {} s.\n",
        s.cases,
        plan.title,
        plan.scene,
        s.per_task,
        s.dir,
        s.case_bytes as f64 / (1 << 20) as f64,
        s.case_seconds,
        s.per_task,
        TIME_FLOOR_S
    );
    let mut directive = |line: String| o += &format!("#SBATCH {line}\n");
    directive(format!(
        "--job-name=nonlin3d-{}",
        if name.is_empty() { "study" } else { name }
    ));
    directive(array_option(&all, s.max_parallel));
    directive("--ntasks=1".into());
    directive("--cpus-per-task=1".into());
    directive(format!("--mem={}M", s.mem_mib));
    directive(format!("--time={}", s.time));
    directive(format!("--output={}", logs.join("%A_%a.out").display()));
    directive(format!("--error={}", logs.join("%A_%a.err").display()));
    if let Some(p) = &s.partition {
        directive(format!("--partition={p}"));
    }
    if let Some(a) = &s.account {
        directive(format!("--account={a}"));
    }
    o += &format!(
        "set -u\n\
         program={}\n\
         dir={}\n\
         # per_task={} of cases={}: task i runs cases i, i + tasks, i + 2 tasks, … in one\n\
         # process (a process per case costs its start and cold caches).\n\
         tasks={}\n\
         last={}\n\
         exec \"$program\" sweep run \"$dir\" --cases \"$SLURM_ARRAY_TASK_ID-$last/$tasks\" --jobs 1\n",
        shell_quote(&s.program),
        shell_quote(&s.dir),
        s.per_task,
        s.cases,
        s.tasks,
        s.cases.saturating_sub(1)
    );
    o
}

/// Writes `slurm/sweep.sbatch` (executable), `slurm/slurm.json` and `slurm/logs/` into
/// `folder` (the plan being written), for the study whose absolute folder is `dir`.
pub fn write(
    folder: &Path,
    dir: &Path,
    plan: &Plan,
    cases: &[Resolved],
    o: &SlurmOptions,
) -> Result<Settings, Error> {
    let program = std::env::current_exe().map_err(|source| Error::Io {
        path: "the nonlin3d program".into(),
        source,
    })?;
    let s = settings(dir, &program, cases, o)?;
    let logs = folder.join(LOGS);
    std::fs::create_dir_all(&logs).map_err(|source| Error::Io {
        path: logs.clone(),
        source,
    })?;
    let path = folder.join(SCRIPT);
    write_atomic(&path, script(plan, &s).as_bytes())?;
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        let _ = std::fs::set_permissions(&path, std::fs::Permissions::from_mode(0o755));
    }
    write_atomic(
        &folder.join(SETTINGS),
        serde_json::to_string_pretty(&s)?.as_bytes(),
    )?;
    Ok(s)
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    #[test]
    fn times_read_and_print_as_slurm_does() {
        assert_eq!(parse_time("00:30:00").unwrap(), 1800);
        assert_eq!(parse_time("1-02:00:05").unwrap(), 93_605);
        assert_eq!(parse_time("90").unwrap(), 5400);
        for bad in ["", "1:61:00", "ab", "0", "1-2"] {
            assert!(parse_time(bad).is_err(), "{bad}");
        }
        assert_eq!(format_time(93_605), "1-02:00:05");
        assert_eq!(format_time(300), "00:05:00");
    }

    #[test]
    fn arrays_list_runs_as_ranges() {
        assert_eq!(array_list(&[0, 1, 2, 3, 5, 7, 8, 9]), "0-3,5,7-9");
        assert_eq!(array_option(&[4], 2), "--array=4%2");
        assert_eq!(array_option(&[0, 1], 0), "--array=0-1");
    }

    #[test]
    fn tasks_cover_the_cases_in_chunks() {
        let s = Settings {
            program: String::new(),
            dir: String::new(),
            cases: 7,
            per_task: 3,
            tasks: 3,
            max_parallel: 0,
            mem_mib: 256,
            time: String::new(),
            case_bytes: 0,
            case_seconds: 0.0,
            partition: None,
            account: None,
        };
        let of = |t| s.cases_of(t).collect::<Vec<_>>();
        assert_eq!(of(0), [0, 3, 6]);
        assert_eq!(of(1), [1, 4]);
        assert_eq!(s.task_of(5), 2);
        assert_eq!(shell_quote("a'b c"), r"'a'\''b c'");
    }

    #[test]
    fn tasks_default_to_a_minute_of_work_and_fill_the_slots() {
        // 200 cases of 1.2 s: 50 a task by time; 2 slots would take 100 each, so 50.
        assert_eq!(default_per_task(200, 1.2, 2), 50);
        // 200 cases of 0.5 s: 120 by time, but 2 slots want 2 tasks of 100.
        assert_eq!(default_per_task(200, 0.5, 2), 100);
        // Cases of ten minutes: one a task.
        assert_eq!(default_per_task(200, 600.0, 0), 1);
        // No estimate: everything in one task (no slot limit given) or one per slot.
        assert_eq!(default_per_task(8, 0.0, 0), 8);
        assert_eq!(default_per_task(8, 0.0, 3), 3);
    }
}
