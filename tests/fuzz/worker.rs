//! The worker side of the fuzz harness: a child process (the test binary re-invoked as
//! `worker_entry_point`) that builds its cases from the environment and runs them in-process
//! one after another under `catch_unwind`, announcing each on stdout (`@@fuzz start K …`,
//! `@@fuzz stage …`, `@@fuzz done K …`) for the parent (`supervise.rs`). Also the counting
//! allocator that measures each case's heap peak.

use crate::mutate::{Format, mutate};
use crate::rng::Rng;
use crate::stages::{self, Class, Outcome};
use std::alloc::{GlobalAlloc, Layout, System};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

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

/// What the workers run: mutated corpus cases of a seed, or files as they are.
#[derive(Debug, Clone)]
pub enum Work {
    /// Case k is the k-th mutation of a corpus input under this seed.
    Cases(u64),
    /// Item k is this file, unmutated.
    Files(Vec<PathBuf>),
    /// Item k misbehaves as [`PROBES`]\[k\] says: the harness's self-test.
    Probes,
}

/// What the self-test items do: panic, abort, allocate past the ceiling, spin.
pub const PROBES: [&str; 4] = ["panic", "abort", "memory", "spin"];

/// The self-test item `kind`.
fn probe(kind: &str) -> Outcome {
    match kind {
        "panic" => panic!("probe: a panic"),
        "abort" => std::process::abort(),
        "memory" => {
            let v = vec![1u8; 3 << 30];
            std::hint::black_box(&v);
        }
        _ => loop {
            std::hint::black_box(0u64);
        },
    }
    Outcome {
        class: Class::Ok,
        stage: String::new(),
        message: String::new(),
        location: String::new(),
        frames: Vec::new(),
        dofs: 0,
        solved: false,
    }
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
    // Self-contained inputs only: a deck that includes another (read from text, *INCLUDE is
    // refused by design) or a mesh-only fragment meant to be included (no *STEP) cannot be
    // solved on its own.
    let whole = |text: &str| {
        let upper = text.to_ascii_uppercase();
        !upper.contains("*INCLUDE") && (upper.contains("*STEP") || !upper.contains("*NODE"))
    };
    paths
        .into_iter()
        .filter_map(|p| Some((p.clone(), std::fs::read_to_string(root().join(&p)).ok()?)))
        .filter(|(_, text)| whole(text))
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
        Work::Probes => Input {
            name: format!("probe:{}", PROBES[k as usize % PROBES.len()]),
            format: Format::Scene,
            bytes: Vec::new(),
            original: None,
            notes: Vec::new(),
        },
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

/// A protocol line to the parent; a worker whose parent is gone (broken pipe) stops.
pub fn say(line: &str) {
    let mut out = std::io::stdout().lock();
    if writeln!(out, "{line}").and_then(|_| out.flush()).is_err() {
        std::process::exit(0);
    }
}

/// CPU seconds (user + system, all threads) a process has used, from `/proc/PID/stat` (Linux;
/// clock ticks of 1/100 s); `None` elsewhere.
pub fn cpu_seconds(pid: &str) -> Option<f64> {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).ok()?;
    // Fields after the command name (which may hold spaces) start with the state, field 3;
    // utime and stime are fields 14 and 15.
    let rest = &stat[stat.rfind(')')? + 1..];
    let f: Vec<&str> = rest.split_whitespace().collect();
    let ticks: f64 = f.get(11)?.parse::<f64>().ok()? + f.get(12)?.parse::<f64>().ok()?;
    Some(ticks / 100.0)
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
        Some(("probes", _)) => Work::Probes,
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
    // The same mark on stderr: what follows it there belongs to this case.
    eprintln!("@@fuzz start {k}");
    stages::take_panic();
    let base = LIVE.load(Ordering::Relaxed);
    PEAK.store(base, Ordering::Relaxed);
    let t = Instant::now();
    let cpu0 = cpu_seconds("self");
    let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| match work {
        Work::Probes => probe(inp.name.trim_start_matches("probe:")),
        _ => stages::run_input(inp.format, &inp.bytes, inp.original.as_deref()),
    }));
    let ms = t.elapsed().as_secs_f64() * 1e3;
    let cpu_ms = cpu_seconds("self")
        .zip(cpu0)
        .map_or(ms, |(b, a)| (b - a) * 1e3);
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
            "ms": ms, "cpu_ms": cpu_ms, "peak_mb": peak_mb,
        })
    ));
}
