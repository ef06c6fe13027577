//! The output folder of a run, written as the run goes: each level's files as soon as it
//! converges, `results.json` rewritten after every level with `"complete": false`, and only the
//! last write after a whole run with `"complete": true`. Every file is written under a
//! temporary name and renamed into place, so a reader (or a run killed at any instant) never
//! sees half a file, and a `results.json` that says complete is complete (docs/RELIABILITY.md).
//!
//! A failed level, or a SIGINT/SIGTERM ([`RunOutput::interrupt_handle`]), leaves every level
//! converged so far with `"complete": false` and `"stopped"` saying why.

use crate::Error;
pub use crate::atomic::{atomically, write_atomic};
use crate::fields::{write_level_vtu, write_pvds};
use crate::model::Model;
use crate::results::{LevelResult, ModelSummary, Results, Timings};
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

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
    ) || numbered("front_", ".csv")
        || numbered("model_", ".vtu")
        || numbered("front_", ".vtu")
        || (name.starts_with('.') && name.ends_with(".partial"))
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
}

impl RunOutput {
    /// Creates `dir` (and parents), checks that it can be written before any analysis runs, and
    /// removes the files of an earlier run there (only the names this program writes).
    pub fn create(dir: &Path, title: &str, quantity: &str) -> Result<Self, Error> {
        std::fs::create_dir_all(dir).map_err(io(dir))?;
        let probe = dir.join(".nonlin3d-write-test.partial");
        std::fs::write(&probe, b"").map_err(io(&probe))?;
        std::fs::remove_file(&probe).map_err(io(&probe))?;
        for entry in std::fs::read_dir(dir).map_err(io(dir))?.flatten() {
            if entry.file_type().is_ok_and(|t| t.is_file())
                && ours(&entry.file_name().to_string_lossy())
            {
                std::fs::remove_file(entry.path()).map_err(io(&entry.path()))?;
            }
        }
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
            critical: None,
            timings: Timings {
                mesh_s: 0.0,
                setup_s: 0.0,
                solve_s: 0.0,
                vcct_s: 0.0,
                output_s: 0.0,
                threads: rayon::current_num_threads(),
            },
            model_data: None,
            warnings: Vec::new(),
        };
        let out = Self {
            dir: dir.to_path_buf(),
            snapshot,
            model: None,
            pending: Arc::new(Mutex::new(Pending {
                path: dir.join("results.json"),
                stopped_json: None,
            })),
        };
        out.write_json()?;
        Ok(out)
    }

    /// The folder.
    pub fn dir(&self) -> &Path {
        &self.dir
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
        self.write_json()
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
        crate::report::write_all(results, &self.dir)?;
        if let Ok(mut p) = self.pending.lock() {
            p.stopped_json = None;
        }
        Ok(())
    }

    /// A handle for a signal handler: [`InterruptHandle::stop`] writes `results.json` as it
    /// stands with `"stopped": "interrupted …"`.
    pub fn interrupt_handle(&self) -> InterruptHandle {
        InterruptHandle {
            pending: self.pending.clone(),
        }
    }

    /// Writes the snapshot's `results.json` and prepares its interrupted form.
    fn write_json(&self) -> Result<(), Error> {
        let mut value = serde_json::to_value(&self.snapshot)?;
        let now = serde_json::to_string_pretty(&value)?;
        if self.snapshot.stopped.is_none() {
            value["stopped"] = "interrupted".into();
        }
        let stopped = serde_json::to_string_pretty(&value)?;
        let mut pending = self.pending.lock().map_err(|_| Error::OutputLock)?;
        write_atomic(&pending.path, now.as_bytes())?;
        pending.stopped_json = Some(stopped);
        Ok(())
    }
}

/// Writes an interrupted run's `results.json` from another thread (a signal handler).
#[derive(Debug, Clone)]
pub struct InterruptHandle {
    pending: Arc<Mutex<Pending>>,
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
        }
    }

    /// Under the lock [`stop`](Self::stop) takes: runs `write` (the state's other files),
    /// writes `now` to the status file, and keeps `stopped` for `stop` (the status with
    /// `"stopped": "interrupted"`; None once the run is finished).
    pub fn publish(
        &self,
        write: impl FnOnce() -> Result<(), Error>,
        now: &str,
        stopped: Option<String>,
    ) -> Result<(), Error> {
        let mut pending = self.pending.lock().map_err(|_| Error::OutputLock)?;
        write()?;
        write_atomic(&pending.path, now.as_bytes())?;
        pending.stopped_json = stopped;
        Ok(())
    }

    /// Waits for any `results.json` write in progress, then writes the run's state with
    /// `"stopped": "interrupted by SIGNAL"` (nothing after a finished run) and keeps the lock,
    /// so that the run writes nothing more: call it only to exit. Returns whether a file was
    /// written.
    pub fn stop(&self, signal: &str) -> bool {
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
