//! Cases run in child processes (`worker.rs`): the test binary re-invokes itself
//! (`worker_entry_point`) with the cases to run in its environment, under a virtual-memory
//! ceiling (`ulimit -v`), with one Rayon thread, and runs them in-process one after another.
//! The parent reads each case's record from the worker's stdout. A case that has used the time
//! limit in CPU seconds (or ten times it in wall time) without an answer is a hang: the worker is
//! killed. A worker whose output ends in mid-case aborted: its signal or exit code and what it
//! said on stderr since the case began (e.g. "memory allocation of N bytes failed" and the
//! workspace frames of the backtrace) are recorded. Either way a new worker carries on with the
//! next case, so an abort or hang costs one process start and the cases in between run at
//! in-process speed.

use crate::stages::{self, Class, Outcome};
use crate::worker::{Work, cpu_seconds};
use std::io::{BufRead, BufReader, Read};
use std::process::{Child, Command, Stdio};
use std::sync::{Arc, Mutex, mpsc};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// Limits on one case.
#[derive(Debug, Clone, Copy)]
pub struct Limits {
    /// Time for one case before it counts as a hang.
    pub timeout: Duration,
    /// Virtual-memory ceiling of a worker process, MiB.
    pub memory_mb: u64,
}

/// One case's record, as the parent collects it.
#[derive(Debug, Clone)]
pub struct Record {
    /// The case index (or the file's index in a file list).
    pub index: u64,
    /// The corpus input (path relative to the package) or file.
    pub input: String,
    /// The mutations applied.
    pub notes: Vec<String>,
    /// The outcome.
    pub outcome: Outcome,
    /// Wall time, ms.
    pub ms: f64,
    /// CPU time of the worker over the case (all threads), ms.
    pub cpu_ms: f64,
    /// Peak of live heap bytes during the case above what was live before it, MiB.
    pub peak_mb: f64,
}

enum Line {
    Start(u64, String, Vec<String>),
    Stage(String),
    Done(u64, serde_json::Value),
    Harness(u64, String),
    End,
}

fn parse_line(l: &str) -> Option<Line> {
    let rest = l.strip_prefix("@@fuzz ")?;
    let mut parts = rest.splitn(3, ' ');
    let (kind, k, json) = (parts.next()?, parts.next()?, parts.next()?);
    let k: u64 = k.parse().ok()?;
    let v: serde_json::Value = serde_json::from_str(json).ok()?;
    let s = |v: &serde_json::Value| v.as_str().unwrap_or("").to_string();
    Some(match kind {
        "start" => Line::Start(
            k,
            s(&v["input"]),
            v["notes"]
                .as_array()
                .map(|a| a.iter().map(s).collect())
                .unwrap_or_default(),
        ),
        "done" => Line::Done(k, v),
        "stage" => Line::Stage(s(&v)),
        _ => Line::Harness(k, format!("{} at {}", s(&v["message"]), s(&v["location"]))),
    })
}

fn spawn(work: &Work, from: u64, to: u64, stride: u64, limits: Limits) -> std::io::Result<Child> {
    let exe = std::env::current_exe()?;
    let args = [
        "worker_entry_point",
        "--exact",
        "--nocapture",
        "--test-threads=1",
        "-q",
    ];
    let mut cmd = if cfg!(unix) {
        // The ceiling through the shell's ulimit: no libc binding needed in the test.
        let mut c = Command::new("sh");
        c.arg("-c")
            .arg("ulimit -v \"$NONLIN3D_FUZZ_LIMIT_KB\" 2>/dev/null; exec \"$0\" \"$@\"")
            .arg(exe);
        c
    } else {
        Command::new(exe)
    };
    let work = match work {
        Work::Cases(seed) => format!("cases:{seed}"),
        Work::Probes => "probes:".into(),
        Work::Files(f) => format!(
            "files:{}",
            f.iter()
                .map(|p| p.display().to_string())
                .collect::<Vec<_>>()
                .join("\n")
        ),
    };
    cmd.args(args)
        .env("NONLIN3D_FUZZ_ROLE", "worker")
        .env("NONLIN3D_FUZZ_WORK", work)
        .env("NONLIN3D_FUZZ_FROM", from.to_string())
        .env("NONLIN3D_FUZZ_TO", to.to_string())
        .env("NONLIN3D_FUZZ_STRIDE", stride.to_string())
        .env(
            "NONLIN3D_FUZZ_LIMIT_KB",
            (limits.memory_mb * 1024).to_string(),
        )
        .env("RAYON_NUM_THREADS", "1")
        // Rust prints a backtrace after "memory allocation of N bytes failed" with this set.
        .env("RUST_BACKTRACE", "full")
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
}

/// How a child ended, in words.
fn exit_words(status: std::process::ExitStatus) -> String {
    #[cfg(unix)]
    {
        use std::os::unix::process::ExitStatusExt;
        if let Some(sig) = status.signal() {
            let name = match sig {
                4 => "SIGILL",
                6 => "SIGABRT",
                7 => "SIGBUS",
                8 => "SIGFPE",
                9 => "SIGKILL",
                11 => "SIGSEGV",
                _ => "signal",
            };
            return format!("killed by signal {sig} ({name})");
        }
    }
    match status.code() {
        Some(c) => format!("exit code {c}"),
        None => "ended without a code".into(),
    }
}

/// What a dying process said: the lines of its stderr that are not a backtrace's (frames
/// are numbered, their places start with "at") nor libtest's.
fn last_words(stderr: &str) -> String {
    let said: Vec<&str> = stderr
        .lines()
        .map(str::trim)
        .filter(|l| {
            !l.is_empty()
                && !l.starts_with("at ")
                && !l.starts_with("stack backtrace")
                && !l.starts_with("note: ")
                && l.split(':')
                    .next()
                    .is_none_or(|n| n.parse::<usize>().is_err())
                && !l.starts_with("running ")
                && !l.starts_with("test ")
                && !l.starts_with("@@fuzz")
        })
        .collect();
    said[said.len().saturating_sub(3)..].join(" / ")
}

fn failure(
    index: u64,
    input: &str,
    notes: &[String],
    class: Class,
    stage: &str,
    message: String,
) -> Record {
    Record {
        index,
        input: input.to_string(),
        notes: notes.to_vec(),
        outcome: Outcome {
            class,
            stage: stage.to_string(),
            message,
            location: String::new(),
            frames: Vec::new(),
            dofs: 0,
            solved: false,
        },
        ms: 0.0,
        cpu_ms: 0.0,
        peak_mb: 0.0,
    }
}

fn record_of(k: u64, input: &str, notes: &[String], v: &serde_json::Value) -> Record {
    let s = |key: &str| v[key].as_str().unwrap_or("").to_string();
    Record {
        index: k,
        input: input.to_string(),
        notes: notes.to_vec(),
        outcome: Outcome {
            class: Class::from_name(&s("class")).unwrap_or(Class::Panic),
            stage: s("stage"),
            message: s("message"),
            location: s("location"),
            frames: v["frames"]
                .as_array()
                .map(|a| {
                    a.iter()
                        .filter_map(|f| f.as_str().map(str::to_string))
                        .collect()
                })
                .unwrap_or_default(),
            dofs: v["dofs"].as_u64().unwrap_or(0) as usize,
            solved: v["solved"].as_bool().unwrap_or(false),
        },
        ms: v["ms"].as_f64().unwrap_or(0.0),
        cpu_ms: v["cpu_ms"].as_f64().unwrap_or(0.0),
        peak_mb: v["peak_mb"].as_f64().unwrap_or(0.0),
    }
}

/// Runs items `from..to` of `work` on `jobs` workers (worker j takes from + j, from + j + jobs,
/// …); returns the records sorted by index, and harness errors (bugs of this test, not of the
/// program). `progress` is called after each record.
pub fn run(
    work: &Work,
    from: u64,
    to: u64,
    jobs: u64,
    limits: Limits,
    progress: &(dyn Fn(&Record) + Sync),
) -> (Vec<Record>, Vec<String>) {
    let jobs = jobs.max(1);
    let all = Mutex::new((Vec::new(), Vec::new()));
    std::thread::scope(|scope| {
        for j in 0..jobs {
            let all = &all;
            scope.spawn(move || {
                let (records, errors) = lane(work, from + j, to, jobs, limits, progress);
                if let Ok(mut a) = all.lock() {
                    a.0.extend(records);
                    a.1.extend(errors);
                }
            });
        }
    });
    let (mut records, errors) = all.into_inner().unwrap_or_default();
    records.sort_by_key(|r: &Record| r.index);
    (records, errors)
}

/// The worker's protocol lines, read on a thread ([`Line::End`] when its stdout closes).
fn lines_of(child: &mut Child) -> mpsc::Receiver<Line> {
    let (tx, rx) = mpsc::channel();
    if let Some(out) = child.stdout.take() {
        std::thread::spawn(move || {
            for l in BufReader::new(out).lines().map_while(Result::ok) {
                if let Some(line) = parse_line(&l) {
                    let _ = tx.send(line);
                }
            }
            let _ = tx.send(Line::End);
        });
    }
    rx
}

/// The worker's stderr, kept (its last 128–256 KiB) by a thread that ends with the worker.
fn stderr_of(child: &mut Child) -> (Arc<Mutex<String>>, Option<JoinHandle<()>>) {
    let stderr = Arc::new(Mutex::new(String::new()));
    let mut reader = None;
    if let Some(mut err) = child.stderr.take() {
        let keep = Arc::clone(&stderr);
        reader = Some(std::thread::spawn(move || {
            let mut buf = [0u8; 4096];
            while let Ok(n) = err.read(&mut buf) {
                if n == 0 {
                    break;
                }
                if let Ok(mut s) = keep.lock() {
                    s.push_str(&String::from_utf8_lossy(&buf[..n]));
                    if s.len() > 1 << 18 {
                        let cut = s.len() - (1 << 17);
                        let cut = (cut..s.len()).find(|&i| s.is_char_boundary(i)).unwrap_or(0);
                        s.drain(..cut);
                    }
                }
            }
        }));
    }
    (stderr, reader)
}

/// How often a lane looks at a silent worker's CPU time.
const POLL: Duration = Duration::from_secs(5);

/// One worker lane: children started one after another until every item is answered.
fn lane(
    work: &Work,
    first: u64,
    to: u64,
    stride: u64,
    limits: Limits,
    progress: &(dyn Fn(&Record) + Sync),
) -> (Vec<Record>, Vec<String>) {
    let mut records = Vec::new();
    let mut errors = Vec::new();
    let mut next = first;
    while next < to {
        let mut child = match spawn(work, next, to, stride, limits) {
            Ok(c) => c,
            Err(e) => {
                errors.push(format!("cannot start a worker: {e}"));
                return (records, errors);
            }
        };
        let rx = lines_of(&mut child);
        let (stderr, mut stderr_reader) = stderr_of(&mut child);
        let pid = child.id().to_string();
        let spawned = Instant::now();
        // (case, CPU seconds of the worker at its start, wall clock at its start)
        let mut clock: Option<(f64, Instant)> = None;
        let mut current: Option<(u64, String, Vec<String>)> = None;
        let mut stage = String::new();
        loop {
            match rx.recv_timeout(POLL.min(limits.timeout)) {
                Ok(Line::Start(k, input, notes)) => {
                    current = Some((k, input, notes));
                    clock = Some((cpu_seconds(&pid).unwrap_or(0.0), Instant::now()));
                }
                Ok(Line::Stage(s)) => stage = s,
                Ok(Line::Done(k, v)) => {
                    clock = None;
                    let (input, notes) = match current.take() {
                        Some((_, i, n)) => (i, n),
                        None => (String::new(), Vec::new()),
                    };
                    let r = record_of(k, &input, &notes, &v);
                    progress(&r);
                    records.push(r);
                    next = k + stride;
                }
                Ok(Line::Harness(k, m)) => {
                    errors.push(format!("case {k}: building the input panicked: {m}"));
                    next = k + stride;
                }
                Ok(Line::End) => {
                    let status = child.wait();
                    // The child's last words: its stderr read to the end.
                    if let Some(h) = stderr_reader.take() {
                        let _ = h.join();
                    }
                    if let Some((k, input, notes)) = current.take() {
                        let how = status.map_or_else(|e| e.to_string(), exit_words);
                        // What the worker said on stderr since it started this case.
                        let said = stderr.lock().map(|s| s.clone()).unwrap_or_default();
                        let marker = format!("@@fuzz start {k}\n");
                        let said = said.rsplit_once(&marker).map_or(said.as_str(), |p| p.1);
                        let message = format!("{how}: {}", last_words(said));
                        let mut r = failure(k, &input, &notes, Class::Abort, &stage, message);
                        r.outcome.frames = stages::nonlin3d_frames(said);
                        progress(&r);
                        records.push(r);
                        next = k + stride;
                    } else if next < to {
                        let said = stderr.lock().map(|s| last_words(&s)).unwrap_or_default();
                        errors.push(format!("a worker stopped before item {next}: {said}"));
                        return (records, errors);
                    }
                    break;
                }
                Err(_) => {
                    // A hang is a case that has used the limit in CPU time (a loaded machine
                    // only slows it down), or ten times the limit in wall time.
                    let limit = limits.timeout.as_secs_f64();
                    let (cpu, wall) = match clock {
                        Some((cpu0, t0)) => {
                            let wall = t0.elapsed().as_secs_f64();
                            (cpu_seconds(&pid).map_or(wall, |c| c - cpu0), wall)
                        }
                        None => {
                            let wall = spawned.elapsed().as_secs_f64();
                            (wall, wall)
                        }
                    };
                    if cpu < limit && wall < 10.0 * limit {
                        continue;
                    }
                    let _ = child.kill();
                    let _ = child.wait();
                    match current.take() {
                        Some((k, input, notes)) => {
                            let message = format!(
                                "no answer after {cpu:.0} s of CPU time ({wall:.0} s wall; the \
                                 worker was killed)"
                            );
                            let r = failure(k, &input, &notes, Class::Hang, &stage, message);
                            progress(&r);
                            records.push(r);
                            next = k + stride;
                        }
                        None => {
                            errors.push(format!("a worker did not start item {next} in time"));
                            return (records, errors);
                        }
                    }
                    break;
                }
            }
        }
    }
    (records, errors)
}
