//! The output folder of a run, written as the run goes: each level's files as soon as it
//! converges, `results.json` rewritten after every level with `"complete": false`, and only the
//! last write after a whole run with `"complete": true`. Every file is written under a
//! temporary name and renamed into place, so a reader (or a run killed at any instant) never
//! sees half a file, and a `results.json` that says complete is complete (docs/RELIABILITY.md).
//!
//! A failed level, or a SIGINT/SIGTERM ([`RunOutput::interrupt_handle`]), leaves every level
//! converged so far with `"complete": false` and `"stopped"` saying why.
//!
//! `manifest.json` lists every file the run wrote there ([`Manifest`]); the next run into the
//! same folder removes those files first, and nothing else (a folder without a manifest, from
//! an earlier version, is cleaned by our file names). `status.sta` and `convergence.cvg`
//! ([`crate::log`]) grow a line per attempt and per Newton iteration as the run goes.

use crate::Error;
pub use crate::atomic::{atomically, write_atomic};
use crate::fields::{write_level_vtu, write_pvds};
use crate::log::{CONVERGENCE_FILE, STATUS_FILE, StatusFiles};
use crate::model::Model;
use crate::results::{LevelResult, ModelSummary, Provenance, Results, Timings};
use std::collections::BTreeMap;
use std::path::{Component, Path, PathBuf};
use std::sync::{Arc, Condvar, Mutex};
use std::time::SystemTime;
use std::time::{Duration, Instant};

fn io(path: &Path) -> impl FnOnce(std::io::Error) -> Error + '_ {
    move |source| Error::Io {
        path: path.to_path_buf(),
        source,
    }
}

/// Files a run writes (and removes from a previous run in the same folder, so no stale
/// `front_7.csv` outlives a rerun with fewer levels).
fn ours(name: &str) -> bool {
    let numbered = |prefix: &str, ext: &str| {
        name.strip_prefix(prefix)
            .and_then(|r| r.strip_suffix(ext))
            .is_some_and(|k| !k.is_empty() && k.bytes().all(|b| b.is_ascii_digit()))
    };
    matches!(
        name,
        "results.json"
            | "levels.csv"
            | "model.pvd"
            | "front.pvd"
            | "g_i.svg"
            | "g_ii.svg"
            | "g_t.svg"
            | "deflection.svg"
            | "overview.svg"
            | "failure_index.svg"
    ) || numbered("front_", ".csv")
        || numbered("model_", ".vtu")
        || numbered("front_", ".vtu")
        || (name.starts_with('.') && name.ends_with(".partial"))
        || name == STATUS_FILE
        || name == CONVERGENCE_FILE
}

/// A run's files by path relative to its folder (for the [`Manifest`]).
fn ours_relative(path: &Path) -> bool {
    let mut parts = path.components();
    matches!((parts.next(), parts.next()), (Some(Component::Normal(n)), None)
        if ours(&n.to_string_lossy()))
}

/// The name of the manifest in an output folder.
pub const MANIFEST: &str = "manifest.json";

/// The files this program wrote in an output folder, listed in `manifest.json` (paths relative
/// to the folder, one level of subfolders at most) and rewritten after every write.
#[derive(Debug, Clone)]
pub struct Manifest {
    dir: PathBuf,
    ours: fn(&Path) -> bool,
    /// The files left in the folder after the cleaning, with their modification times: the
    /// user's, unless this run rewrites them.
    before: BTreeMap<PathBuf, Option<SystemTime>>,
}

/// The modification time of `path`, if it can be read.
fn modified(path: &Path) -> Option<SystemTime> {
    std::fs::metadata(path).and_then(|m| m.modified()).ok()
}

/// Files in `dir` and in its immediate subfolders, relative to `dir`.
fn files_below(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let Ok(entries) = std::fs::read_dir(dir) else {
        return out;
    };
    for e in entries.flatten() {
        let Ok(kind) = e.file_type() else { continue };
        let name = PathBuf::from(e.file_name());
        if kind.is_file() {
            out.push(name);
        } else if kind.is_dir() {
            for inner in std::fs::read_dir(e.path()).into_iter().flatten().flatten() {
                if inner.file_type().is_ok_and(|t| t.is_file()) {
                    out.push(name.join(inner.file_name()));
                }
            }
        }
    }
    out.sort();
    out
}

/// A path the manifest may name: relative, at most two plain components.
fn inside(path: &Path) -> bool {
    let parts: Vec<Component> = path.components().collect();
    !parts.is_empty() && parts.len() <= 2 && parts.iter().all(|c| matches!(c, Component::Normal(_)))
}

impl Manifest {
    /// Makes `dir` (and parents), checks that a file can be written there (before anything is
    /// computed: an unwritable folder fails now, naming it), and removes the files an earlier
    /// run listed in its manifest — or, with no manifest, the files whose names `ours` claims
    /// (relative paths) — with the subfolders that leaves empty. A user's file (not listed) is
    /// never touched when there is a manifest.
    pub fn prepare(dir: &Path, ours: fn(&Path) -> bool) -> Result<Self, Error> {
        std::fs::create_dir_all(dir).map_err(io(dir))?;
        let probe = dir.join(".nonlin3d-write-test.partial");
        std::fs::write(&probe, b"").map_err(io(&probe))?;
        std::fs::remove_file(&probe).map_err(io(&probe))?;
        let listed = dir.join(MANIFEST);
        let stale: Vec<PathBuf> = match std::fs::read_to_string(&listed) {
            Ok(text) => {
                let v: serde_json::Value = serde_json::from_str(&text).unwrap_or_default();
                v["files"]
                    .as_array()
                    .into_iter()
                    .flatten()
                    .filter_map(|f| f.as_str().map(PathBuf::from))
                    .chain(std::iter::once(PathBuf::from(MANIFEST)))
                    .collect()
            }
            Err(_) => files_below(dir).into_iter().filter(|p| ours(p)).collect(),
        };
        // Temporaries of a run killed mid-write are ours in any case.
        let partial = files_below(dir).into_iter().filter(|p| {
            p.file_name()
                .is_some_and(|n| n.to_string_lossy().ends_with(".partial"))
                && ours(p)
        });
        for rel in stale.into_iter().chain(partial).filter(|p| inside(p)) {
            let path = dir.join(&rel);
            if path.is_file() {
                std::fs::remove_file(&path).map_err(io(&path))?;
            }
            if rel.components().count() == 2 {
                // Kept if anything else is left in it.
                let _ = std::fs::remove_dir(path.parent().unwrap_or(dir));
            }
        }
        let before = files_below(dir)
            .into_iter()
            .map(|p| {
                let t = modified(&dir.join(&p));
                (p, t)
            })
            .collect();
        Ok(Self {
            dir: dir.to_path_buf(),
            ours,
            before,
        })
    }

    /// Rewrites `manifest.json` with every file in the folder that is ours: named as ours and
    /// not a file that was there before this run and is unchanged (a user's).
    pub fn write(&self) -> Result<(), Error> {
        let files: Vec<String> = files_below(&self.dir)
            .into_iter()
            .filter(|p| {
                (self.ours)(p)
                    && p != Path::new(MANIFEST)
                    && !p.to_string_lossy().ends_with(".partial")
                    && self
                        .before
                        .get(p)
                        .is_none_or(|&t| t != modified(&self.dir.join(p)))
            })
            .map(|p| p.to_string_lossy().into_owned())
            .collect();
        let text = serde_json::to_string_pretty(&serde_json::json!({
            "program": format!("nonlin3d {}", env!("CARGO_PKG_VERSION")),
            "note": "files this program wrote here; the next run into this folder removes them",
            "files": files,
        }))?;
        write_atomic(&self.dir.join(MANIFEST), text.as_bytes())
    }
}

/// What the signal handler needs: the folder and the text of `results.json` as it would read
/// if the run stopped now. The lock is held while `results.json` is written.
#[derive(Debug, Default)]
struct Pending {
    path: PathBuf,
    stopped_json: Option<String>,
}

/// A run's output folder, written level by level.
#[derive(Debug)]
pub struct RunOutput {
    dir: PathBuf,
    snapshot: Results,
    model: Option<Model>,
    pending: Arc<Mutex<Pending>>,
    manifest: Manifest,
    status: StatusFiles,
    started: Instant,
}

impl RunOutput {
    /// Creates `dir` (and parents), checks that it can be written before any analysis runs,
    /// removes the files of an earlier run there ([`Manifest::prepare`]) and starts
    /// `status.sta` and `convergence.cvg`.
    pub fn create(dir: &Path, title: &str, quantity: &str) -> Result<Self, Error> {
        let manifest = Manifest::prepare(dir, ours_relative)?;
        let status = StatusFiles::create(dir, "level")?;
        let snapshot = Results {
            title: title.into(),
            quantity: quantity.into(),
            complete: false,
            stopped: None,
            model: ModelSummary {
                nodes: 0,
                cells: 0,
                dofs: 0,
                front_points: 0,
                perturbation_n: None,
                perturbed_at: None,
                substructure: None,
            },
            levels: Vec::new(),
            accuracy: None,
            critical: None,
            timings: Timings {
                mesh_s: 0.0,
                setup_s: 0.0,
                solve_s: 0.0,
                vcct_s: 0.0,
                output_s: 0.0,
                threads: rayon::current_num_threads(),
                mixed_precision: None,
                factor: Vec::new(),
            },
            model_data: None,
            coarser: None,
            warnings: Vec::new(),
            provenance: None,
        };
        let mut out = Self {
            dir: dir.to_path_buf(),
            snapshot,
            model: None,
            pending: Arc::new(Mutex::new(Pending {
                path: dir.join("results.json"),
                stopped_json: None,
            })),
            manifest,
            status,
            started: Instant::now(),
        };
        out.write_json()?;
        Ok(out)
    }

    /// The folder.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// The folder's `status.sta` and `convergence.cvg`, for the caller to append Newton's
    /// records to as they come ([`crate::log`]).
    pub fn status_files(&self) -> StatusFiles {
        self.status.clone()
    }

    /// Records where the run came from: written into every `results.json` from now on, its
    /// total time and peak memory brought up to date at each write.
    pub fn set_provenance(&mut self, provenance: Provenance) -> Result<(), Error> {
        self.snapshot.provenance = Some(provenance);
        self.write_json()
    }

    /// The model is built: its size goes into the snapshot and its mesh is kept for the VTU
    /// files of the levels.
    pub fn built(&mut self, model: &Model, dofs: usize) -> Result<(), Error> {
        self.snapshot.model.nodes = model.mesh.nodes.len();
        self.snapshot.model.cells = model.mesh.cells.len();
        self.snapshot.model.dofs = dofs;
        self.model = Some(model.clone());
        self.write_json()
    }

    /// A level converged: writes its front CSV and VTU, the PVD and `levels.csv` so far, and
    /// `results.json` with every level so far and `"complete": false`.
    pub fn level(&mut self, level: &LevelResult) -> Result<(), Error> {
        // Every file under the lock the signal handler takes (its exit cannot cut one short).
        let lock = self.pending.clone();
        let mut pending = lock.lock().map_err(|_| Error::OutputLock)?;
        let k = self.snapshot.levels.len();
        self.snapshot.model.front_points = level.front.len();
        self.snapshot.levels.push(level.clone());
        let p = self.dir.join(format!("front_{k}.csv"));
        write_atomic(&p, crate::report::front_csv(&self.snapshot, k).as_bytes())?;
        if let Some(model) = &self.model {
            write_level_vtu(&self.dir, model, level, k)?;
            write_pvds(&self.dir, &self.snapshot.levels)?;
        }
        let p = self.dir.join("levels.csv");
        write_atomic(&p, crate::report::levels_csv(&self.snapshot).as_bytes())?;
        self.snapshot.warnings = self.snapshot.stability_warnings();
        self.write_json_locked(&mut pending)
    }

    /// The run failed: `results.json` keeps every converged level, `"complete": false` and the
    /// error in `"stopped"`.
    pub fn failed(&mut self, error: &Error) -> Result<(), Error> {
        self.snapshot.stopped = Some(format!("error: {error}"));
        self.write_json()
    }

    /// The run is complete: every output rewritten from the final results (criterion, critical
    /// strain, plots, timings), `"complete": true` last.
    pub fn finish(&mut self, results: &mut Results) -> Result<(), Error> {
        results.complete = true;
        results.stopped = None;
        results.provenance = self.snapshot.provenance.take().map(|mut p| {
            p.finish(self.started.elapsed().as_secs_f64());
            p
        });
        // Under the lock the signal handler takes, so that its exit cannot cut a file short; a
        // signal meanwhile waits, then finds the run finished and writes nothing.
        let mut pending = self.pending.lock().map_err(|_| Error::OutputLock)?;
        // A level's model VTU, written when it converged, is current if the final results
        // hold the same state on the same model (they do, unless the caller changed them).
        let same_model = match (&self.model, &results.model_data) {
            (Some(a), Some(b)) => {
                a.mesh == b.mesh && a.materials == b.materials && a.rule == b.rule
            }
            _ => false,
        };
        let current: Vec<bool> = (results.levels.iter().enumerate())
            .map(|(k, l)| {
                same_model
                    && self.snapshot.levels.get(k).is_some_and(|w| {
                        w.displacements.len() == l.displacements.len()
                            && (w.displacements.iter().zip(&l.displacements))
                                .all(|(a, b)| a.to_bits() == b.to_bits())
                    })
            })
            .collect();
        crate::report::write_all_but(results, &self.dir, |k| current[k])?;
        pending.stopped_json = None;
        self.manifest.write()
    }

    /// A handle for a signal handler: [`InterruptHandle::stop`] writes `results.json` as it
    /// stands with `"stopped": "interrupted …"`.
    pub fn interrupt_handle(&self) -> InterruptHandle {
        InterruptHandle {
            pending: self.pending.clone(),
            backlog: Arc::default(),
        }
    }

    /// Writes the snapshot's `results.json` and prepares its interrupted form.
    fn write_json(&mut self) -> Result<(), Error> {
        let lock = self.pending.clone();
        let mut pending = lock.lock().map_err(|_| Error::OutputLock)?;
        self.write_json_locked(&mut pending)
    }

    /// [`write_json`](Self::write_json) with the signal handler's lock already held.
    fn write_json_locked(&mut self, pending: &mut Pending) -> Result<(), Error> {
        if let Some(p) = &mut self.snapshot.provenance {
            p.finish(self.started.elapsed().as_secs_f64());
        }
        let mut value = serde_json::to_value(&self.snapshot)?;
        let now = serde_json::to_string_pretty(&value)?;
        if self.snapshot.stopped.is_none() {
            value["stopped"] = "interrupted".into();
        }
        let stopped = serde_json::to_string_pretty(&value)?;
        write_atomic(&pending.path, now.as_bytes())?;
        pending.stopped_json = Some(stopped);
        // The manifest under the same lock (a signal's exit must not cut it short).
        self.manifest.write()
    }
}

/// Writes an interrupted run's `results.json` from another thread (a signal handler).
#[derive(Debug, Clone)]
pub struct InterruptHandle {
    pending: Arc<Mutex<Pending>>,
    /// Writes handed to another thread and not yet done, waited for by [`stop`](Self::stop).
    backlog: Arc<Backlog>,
}

/// How long [`InterruptHandle::stop`] waits for a writer thread's backlog (at most two
/// increments' files) before it writes the stopped state as it stands.
const BACKLOG_WAIT: Duration = Duration::from_secs(60);

/// Writes handed to a writer thread and not yet done (`nonlin3d solve` on two or more threads,
/// [`crate::deck::write_in_background`]): [`InterruptHandle::stop`] waits for those handed over
/// before the signal, so that an interrupt keeps every increment that had converged.
#[derive(Debug, Default)]
pub struct Backlog {
    counts: Mutex<BacklogCounts>,
    changed: Condvar,
}

#[derive(Debug, Default)]
struct BacklogCounts {
    sent: u64,
    done: u64,
    /// The writer has ended (no more writes will be done).
    closed: bool,
}

impl Backlog {
    fn update(&self, f: impl FnOnce(&mut BacklogCounts)) {
        let mut c = self.counts.lock().unwrap_or_else(|e| e.into_inner());
        f(&mut c);
        self.changed.notify_all();
    }

    /// One write more handed over.
    pub fn sent(&self) {
        self.update(|c| c.sent += 1);
    }

    /// One write done.
    pub fn done(&self) {
        self.update(|c| c.done += 1);
    }

    /// The writer has ended: nothing more will be done.
    pub fn close(&self) {
        self.update(|c| c.closed = true);
    }

    /// Waits until every write handed over before the call is done or the writer has ended,
    /// for at most `limit`; whether nothing handed over was left undone.
    pub fn wait(&self, limit: Duration) -> bool {
        let c = self.counts.lock().unwrap_or_else(|e| e.into_inner());
        let target = c.sent;
        let (c, _) = self
            .changed
            .wait_timeout_while(c, limit, |c| c.done < target && !c.closed)
            .unwrap_or_else(|e| e.into_inner());
        c.done >= target
    }
}

impl InterruptHandle {
    /// A handle for another writer than [`RunOutput`] (the deck solver's, whose status file
    /// `path` is summary.json), with nothing to write until [`publish`](Self::publish).
    pub fn new(path: &Path) -> Self {
        Self {
            pending: Arc::new(Mutex::new(Pending {
                path: path.to_path_buf(),
                stopped_json: None,
            })),
            backlog: Arc::default(),
        }
    }

    /// The backlog [`stop`](Self::stop) waits for: a writer thread counts its writes in it.
    pub fn backlog(&self) -> Arc<Backlog> {
        self.backlog.clone()
    }

    /// Under the lock [`stop`](Self::stop) takes: runs `write` (the state's other files),
    /// writes `now` to the status file, keeps `stopped` for `stop` (the status with
    /// `"stopped": "interrupted"`; None once the run is finished), then runs `after` (the
    /// manifest, which lists the status file). Everything under the lock, so a signal's exit
    /// never cuts a write short (a `.NAME.partial` left behind).
    pub fn publish(
        &self,
        write: impl FnOnce() -> Result<(), Error>,
        now: &str,
        stopped: Option<String>,
        after: impl FnOnce() -> Result<(), Error>,
    ) -> Result<(), Error> {
        let mut pending = self.pending.lock().map_err(|_| Error::OutputLock)?;
        write()?;
        write_atomic(&pending.path, now.as_bytes())?;
        pending.stopped_json = stopped;
        after()
    }

    /// Waits for a writer thread's backlog ([`Backlog`], at most a minute) and any
    /// `results.json` write in progress, then writes the run's state with
    /// `"stopped": "interrupted by SIGNAL"` (nothing after a finished run) and keeps the lock,
    /// so that the run writes nothing more: call it only to exit. Returns whether a file was
    /// written.
    pub fn stop(&self, signal: &str) -> bool {
        // The increments converged before the signal, still in a writer thread's queue, are
        // written first ([`Backlog`]); the solve goes on meanwhile, and what it publishes by
        // then is in the stopped state too.
        self.backlog.wait(BACKLOG_WAIT);
        let Ok(pending) = self.pending.lock() else {
            return false;
        };
        let Some(text) = &pending.stopped_json else {
            return false;
        };
        let text = text.replacen(
            "\"stopped\": \"interrupted\"",
            &format!("\"stopped\": \"interrupted by {signal}\""),
            1,
        );
        let written = write_atomic(&pending.path, text.as_bytes()).is_ok();
        // The lock stays held (the caller exits next): no write of the run that was waiting
        // for it can replace the stopped state.
        std::mem::forget(pending);
        written
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    /// [`Backlog::wait`] returns once every write handed over before it is done, at once when
    /// the writer has ended, and false after its limit with a write still undone.
    #[test]
    fn a_stop_waits_for_the_writes_handed_over_before_it() {
        let backlog = Arc::new(Backlog::default());
        backlog.sent();
        backlog.sent();
        let writer = backlog.clone();
        let t = std::thread::spawn(move || {
            for _ in 0..2 {
                std::thread::sleep(Duration::from_millis(20));
                writer.done();
            }
        });
        assert!(backlog.wait(Duration::from_secs(60)));
        assert_eq!(backlog.counts.lock().unwrap().done, 2);
        t.join().unwrap();
        backlog.sent();
        assert!(!backlog.wait(Duration::from_millis(1)));
        backlog.close();
        assert!(!backlog.wait(Duration::from_secs(60)));
    }

    #[test]
    fn only_our_file_names_are_cleaned() {
        for n in [
            "results.json",
            "front_0.csv",
            "front_12.csv",
            "model_3.vtu",
            "front_3.vtu",
            "front.pvd",
            ".x.partial",
        ] {
            assert!(ours(n), "{n}");
        }
        for n in [
            "front_.csv",
            "front_a.csv",
            "notes.txt",
            "model_3.vtu.bak",
            "my.json",
        ] {
            assert!(!ours(n), "{n}");
        }
    }

    #[test]
    fn an_atomic_write_leaves_no_partial_file() {
        let dir = std::env::temp_dir().join(format!("nonlin3d-atomic-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("a.json");
        write_atomic(&p, b"{}").unwrap();
        write_atomic(&p, b"{\"x\": 1}").unwrap();
        assert_eq!(std::fs::read_to_string(&p).unwrap(), "{\"x\": 1}");
        let names: Vec<String> = std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        assert_eq!(names, ["a.json"]);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
