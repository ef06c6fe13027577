//! Cases run in child processes: the test binary re-invokes itself (`worker_entry_point`) with
//! the cases to run in its environment, under a virtual-memory ceiling (`ulimit -v`), with one
//! Rayon thread. The child runs its cases in-process one after another under `catch_unwind`
//! and reports each on stdout (`@@fuzz start K …`, `@@fuzz done K …`). The parent waits for
//! each answer at most the per-case time limit: silence is a hang (the child is killed), an end
//! of output in mid-case is an abort (signal, exit code and the last lines of stderr recorded);
//! either way a new child carries on with the next case. Aborts and hangs so cost one process
//! start each, and the cases in between run at in-process speed.

use crate::mutate::{Format, mutate};
use crate::rng::Rng;
use crate::stages::{self, Class, Outcome};
use std::alloc::{GlobalAlloc, Layout, System};
use std::io::{BufRead, BufReader, Read, Write};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex, mpsc};
use std::time::{Duration, Instant};

/// The system allocator, counting live bytes and their peak (reported per case).
pub struct Counting;

static LIVE: AtomicUsize = AtomicUsize::new(0);
static PEAK: AtomicUsize = AtomicUsize::new(0);

fn grew(by: usize) {
    let now = LIVE.fetch_add(by, Ordering::Relaxed) + by;
    PEAK.fetch_max(now, Ordering::Relaxed);
}

// SAFETY: every call is forwarded to `System` unchanged; the counters only observe sizes.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        // SAFETY: the caller's contract is `System.alloc`'s.
        let p = unsafe { System.alloc(layout) };
        if !p.is_null() {
            grew(layout.size());
        }
        p
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        // SAFETY: as for `alloc`.
        let p = unsafe { System.alloc_zeroed(layout) };
        if !p.is_null() {
            grew(layout.size());
        }
        p
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: `ptr` came from this allocator with `layout`.
        unsafe { System.dealloc(ptr, layout) };
        LIVE.fetch_sub(layout.size(), Ordering::Relaxed);
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        // SAFETY: as for `dealloc`, with `new_size` checked by the caller.
        let q = unsafe { System.realloc(ptr, layout, new_size) };
        if !q.is_null() {
            if new_size >= layout.size() {
                grew(new_size - layout.size());
            } else {
                LIVE.fetch_sub(layout.size() - new_size, Ordering::Relaxed);
            }
        }
        q
    }
}

/// Limits on one case.
#[derive(Debug, Clone, Copy)]
pub struct Limits {
    /// Time for one case before it counts as a hang.
    pub timeout: Duration,
    /// Virtual-memory ceiling of a worker process, MiB.
    pub memory_mb: u64,
}

/// What the workers run: mutated corpus cases of a seed, or files as they are.
#[derive(Debug, Clone)]
pub enum Work {
    /// Case k is the k-th mutation of a corpus input under this seed.
    Cases(u64),
    /// Item k is this file, unmutated.
    Files(Vec<PathBuf>),
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
    /// Peak of live heap bytes during the case above what was live before it, MiB.
    pub peak_mb: f64,
}

/// The package root.
pub fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// The corpus: committed scenes and decks and the fuzz seeds, sorted by path (the case →
/// input map depends on this order, so adding a file changes which input a case index mutates).
pub fn corpus() -> Vec<(String, String)> {
    let mut paths = Vec::new();
    for dir in ["examples/scenes", "tests/decks", "tests/fuzz/seeds"] {
        let Ok(entries) = std::fs::read_dir(root().join(dir)) else {
            continue;
        };
        for e in entries.flatten() {
            let p = e.path();
            if Format::of(&p).is_some() {
                paths.push(format!("{dir}/{}", e.file_name().to_string_lossy()));
            }
        }
    }
    paths.sort();
    paths
        .into_iter()
        .filter_map(|p| Some((p.clone(), std::fs::read_to_string(root().join(&p)).ok()?)))
        .collect()
}

/// Input `k` of `work`: name, format, bytes, the unmutated text, the mutations.
pub struct Input {
    /// Corpus path or file.
    pub name: String,
    /// Scene or deck.
    pub format: Format,
    /// What is fed to the pipeline.
    pub bytes: Vec<u8>,
    /// The unmutated text (cases only).
    pub original: Option<String>,
    /// Mutations applied.
    pub notes: Vec<String>,
}

/// Case `k` of `work`.
pub fn input(work: &Work, corpus: &[(String, String)], k: u64) -> Input {
    match work {
        Work::Cases(seed) => {
            let mut rng = Rng::for_case(*seed, k);
            let (name, text) = rng.pick(corpus);
            let format = Format::of(Path::new(name)).unwrap_or(Format::Scene);
            let m = mutate(&mut rng, text, format);
            Input {
                name: name.clone(),
                format,
                bytes: m.bytes,
                original: Some(text.clone()),
                notes: m.notes,
            }
        }
        Work::Files(files) => {
            let path = &files[k as usize];
            Input {
                name: path
                    .strip_prefix(root())
                    .unwrap_or(path)
                    .display()
                    .to_string(),
                format: Format::of(path).unwrap_or(Format::Scene),
                bytes: std::fs::read(path).unwrap_or_default(),
                original: None,
                notes: Vec::new(),
            }
        }
    }
}

fn say(line: &str) {
    let mut out = std::io::stdout().lock();
    let _ = writeln!(out, "{line}");
    let _ = out.flush();
}

/// The child's side: runs the items `FROM, FROM + STRIDE, … < TO` of the work in its
/// environment (nothing when not started as a worker).
pub fn worker_main() {
    let var = |k: &str| std::env::var(format!("NONLIN3D_FUZZ_{k}")).ok();
    if var("ROLE").as_deref() != Some("worker") {
        return;
    }
    let num = |k: &str| var(k).and_then(|v| v.parse::<u64>().ok()).unwrap_or(0);
    let (from, to, stride) = (num("FROM"), num("TO"), num("STRIDE").max(1));
    let work = match var("WORK").unwrap_or_default().split_once(':') {
        Some(("cases", seed)) => Work::Cases(seed.parse().unwrap_or(0)),
        Some(("files", list)) => Work::Files(list.split('\n').map(PathBuf::from).collect()),
        _ => return,
    };
    stages::record_panics();
    stages::ANNOUNCE.store(true, Ordering::Relaxed);
    // The program's main thread has 8 MiB of stack; libtest's threads 2 MiB.
    let runner = std::thread::Builder::new()
        .stack_size(8 << 20)
        .spawn(move || {
            let corpus = corpus();
            let mut k = from;
            while k < to {
                run_item(&work, &corpus, k);
                k += stride;
            }
        });
    if let Ok(handle) = runner {
        let _ = handle.join();
    }
}

fn run_item(work: &Work, corpus: &[(String, String)], k: u64) {
    let made = std::panic::catch_unwind(|| input(work, corpus, k));
    let Ok(inp) = made else {
        let p = stages::take_panic().unwrap_or_default();
        say(&format!(
            "@@fuzz harness {k} {}",
            serde_json::json!({ "message": p.message, "location": p.location })
        ));
        return;
    };
    say(&format!(
        "@@fuzz start {k} {}",
        serde_json::json!({ "input": inp.name, "notes": inp.notes })
    ));
    stages::take_panic();
    let base = LIVE.load(Ordering::Relaxed);
    PEAK.store(base, Ordering::Relaxed);
    let t = Instant::now();
    let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        stages::run_input(inp.format, &inp.bytes, inp.original.as_deref())
    }));
    let ms = t.elapsed().as_secs_f64() * 1e3;
    let peak_mb = PEAK.load(Ordering::Relaxed).saturating_sub(base) as f64 / (1 << 20) as f64;
    let o = result.unwrap_or_else(|_| {
        let p = stages::take_panic().unwrap_or_default();
        Outcome {
            class: Class::Panic,
            stage: stages::current_stage().into(),
            message: p.message,
            location: p.location,
            frames: p.frames,
            dofs: 0,
            solved: false,
        }
    });
    say(&format!(
        "@@fuzz done {k} {}",
        serde_json::json!({
            "class": o.class.name(), "stage": o.stage, "message": o.message,
            "location": o.location, "frames": o.frames, "dofs": o.dofs, "solved": o.solved,
            "ms": ms, "peak_mb": peak_mb,
        })
    ));
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
        let (tx, rx) = mpsc::channel();
        if let Some(out) = child.stdout.take() {
            let tx = tx.clone();
            std::thread::spawn(move || {
                for l in BufReader::new(out).lines().map_while(Result::ok) {
                    if let Some(line) = parse_line(&l) {
                        let _ = tx.send(line);
                    }
                }
                let _ = tx.send(Line::End);
            });
        }
        let stderr = Arc::new(Mutex::new(String::new()));
        if let Some(mut err) = child.stderr.take() {
            let keep = Arc::clone(&stderr);
            std::thread::spawn(move || {
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
            });
        }
        let mut current: Option<(u64, String, Vec<String>)> = None;
        let mut stage = String::new();
        loop {
            match rx.recv_timeout(limits.timeout) {
                Ok(Line::Start(k, input, notes)) => {
                    current = Some((k, input, notes));
                    if let Ok(mut s) = stderr.lock() {
                        s.clear();
                    }
                }
                Ok(Line::Stage(s)) => stage = s,
                Ok(Line::Done(k, v)) => {
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
                    // Give the stderr reader a moment to drain the child's last words.
                    std::thread::sleep(Duration::from_millis(50));
                    if let Some((k, input, notes)) = current.take() {
                        let how = status.map_or_else(|e| e.to_string(), exit_words);
                        let said = stderr.lock().map(|s| s.clone()).unwrap_or_default();
                        let message = format!("{how}: {}", last_words(&said));
                        let mut r = failure(k, &input, &notes, Class::Abort, &stage, message);
                        r.outcome.frames = stages::nonlin3d_frames(&said);
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
                    let _ = child.kill();
                    let _ = child.wait();
                    match current.take() {
                        Some((k, input, notes)) => {
                            let message = format!(
                                "no answer within {} s (the worker was killed)",
                                limits.timeout.as_secs()
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
