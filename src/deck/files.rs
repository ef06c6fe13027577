//! The output folder of `nonlin3d solve`, written as the solve goes, with the contract of
//! `nonlin3d run`'s (`crate::output::RunOutput`; docs/RELIABILITY.md, "Decks"):
//!
//! - the folder is made and tested before anything is solved, and the files an earlier solve
//!   listed in its `manifest.json` are removed (`crate::output::Manifest`); `status.sta` and
//!   `convergence.cvg` grow a line per attempt and per Newton iteration;
//! - after every converged increment, the output tables that received rows and `summary.json`
//!   (every step so far, the one in progress with `"complete": false`) are rewritten;
//! - `step-K/displacements.csv` is written only when step K reaches the end of its period, so
//!   one that exists is final; `displacements.csv` (the last step's) only when every step has;
//! - `summary.json` says `"complete": false` until the last write of a whole solve, and
//!   `"stopped"` says why a solve ended early (`"error: …"`, `"interrupted by SIGINT"`).
//!
//! Every file goes through `crate::output::write_atomic` (a temporary name, synced, renamed),
//! under the lock the signal handler takes ([`InterruptHandle::publish`]), so a reader or an
//! interrupted solve never sees half a file. A table is rewritten whole each time it grows:
//! O(its size) per increment, so O(increments² × its rows per increment) over a step. That is
//! nothing for the decks nonlin3d solves today and costly for a large one asking for every
//! stress every increment (docs/RELIABILITY.md gives the numbers).

use super::check::{Prepared, prepare};
use super::{Progress, StepOptions, StepResult};
use crate::Error;
use crate::fields::{Units, state_vtu};
use crate::log::{CONVERGENCE_FILE, STATUS_FILE, StatusFiles};
use crate::output::{InterruptHandle, Manifest, write_atomic};
use crate::results::Provenance;
use nonlin3d_assembly::StressRules;
use nonlin3d_element::{IntegrationRule, Kinematics, Material};
use nonlin3d_laminate::ShearCoupling;
use nonlin3d_mesh::vtu::pvd_string;
use nonlin3d_mesh::{InpModel, Mesh};
use std::path::{Path, PathBuf};

fn io(path: &Path) -> impl FnOnce(std::io::Error) -> Error + '_ {
    move |source| Error::Io {
        path: path.to_path_buf(),
        source,
    }
}

/// Names of the files a solve writes in a `step-K` folder.
fn ours_in_step(name: &str) -> bool {
    name == "displacements.csv"
        || (["node-print", "node-file", "el-print", "el-file"]
            .iter()
            .any(|p| name.starts_with(p))
            && name.ends_with(".csv"))
        || (name.starts_with('.') && name.ends_with(".partial"))
}

/// Names of the files a solve writes in its folder.
fn ours(name: &str) -> bool {
    matches!(
        name,
        "summary.json" | "displacements.csv" | "model.pvd" | STATUS_FILE | CONVERGENCE_FILE
    ) || name
        .strip_prefix("model_")
        .and_then(|r| r.strip_suffix(".vtu"))
        .is_some_and(|k| !k.is_empty() && k.bytes().all(|b| b.is_ascii_digit()))
        || (name.starts_with('.') && name.ends_with(".partial"))
}

/// A `step-K` folder name.
fn step_folder(name: &str) -> bool {
    name.strip_prefix("step-")
        .is_some_and(|k| !k.is_empty() && k.bytes().all(|b| b.is_ascii_digit()))
}

/// A solve's files by path relative to its folder (for the [`Manifest`]).
fn ours_relative(path: &Path) -> bool {
    let parts: Vec<String> = path
        .components()
        .map(|c| c.as_os_str().to_string_lossy().into_owned())
        .collect();
    match parts.as_slice() {
        [name] => ours(name),
        [folder, name] => step_folder(folder) && ours_in_step(name),
        _ => false,
    }
}

/// `node,ux,uy,uz` by deck node id.
fn displacements_csv(model: &InpModel, u: &[[f64; 3]]) -> String {
    let mut t = crate::report::Csv::new(&["node", "ux", "uy", "uz"]);
    for (id, d) in model.node_ids.iter().zip(u) {
        t.row([
            id.to_string(),
            format!("{:e}", d[0]),
            format!("{:e}", d[1]),
            format!("{:e}", d[2]),
        ]);
    }
    t.finish()
}

/// The summary entry of a step: its record, its output files with the increments they hold,
/// and its displacements file once it is complete.
fn step_json(r: &StepResult) -> Result<serde_json::Value, Error> {
    let mut v = serde_json::to_value(r)?;
    v["outputs"] = r
        .outputs
        .iter()
        .map(|t| {
            serde_json::json!({
                "keyword": t.keyword,
                "line": t.line,
                "file": format!("step-{}/{}", r.step, t.file),
                "increments": t.increments,
                "axes": t.axes,
            })
        })
        .collect();
    v["displacements"] = if r.complete {
        format!("step-{}/displacements.csv", r.step).into()
    } else {
        serde_json::Value::Null
    };
    Ok(v)
}

/// The output folder of a deck solve, written increment by increment.
#[derive(Debug)]
pub struct DeckOutput<'a> {
    dir: PathBuf,
    model: &'a InpModel,
    /// summary.json's steps so far; the last may be in progress.
    steps: Vec<serde_json::Value>,
    /// The step whose tables are being written, and how many increments each table held when
    /// it was last written.
    tables_of: usize,
    written: Vec<Option<usize>>,
    complete: bool,
    stopped: Option<String>,
    handle: InterruptHandle,
    /// The oriented mesh, materials and rule of the solve, for the VTU files.
    mesh: Mesh,
    materials: Vec<Material>,
    rule: IntegrationRule,
    /// The PVD's steps so far (total time, file) and the (step, converged increments) of the
    /// last VTU written.
    vtu_steps: Vec<(f64, String)>,
    vtu_last: Option<(usize, usize)>,
    manifest: Manifest,
    status: StatusFiles,
    provenance: Option<Provenance>,
    /// When the folder was made, and the seconds spent writing since.
    started: std::time::Instant,
    output_s: f64,
    /// Written by a thread of its own ([`super::write_in_background`]): the writes overlap
    /// the solve, whose stage time is then the whole wall time.
    background: bool,
}

impl<'a> DeckOutput<'a> {
    /// Creates `dir` (and parents), checks that it can be written before anything is solved,
    /// removes the files of an earlier solve there and writes a `summary.json` with no steps
    /// and `"complete": false`.
    pub fn create(dir: &Path, model: &'a InpModel) -> Result<Self, Error> {
        let manifest = Manifest::prepare(dir, ours_relative)?;
        let status = StatusFiles::create(dir, "step")?;
        let Prepared {
            mesh,
            materials,
            rule,
        } = prepare(model, &StepOptions::default())?;
        let mut out = Self {
            dir: dir.to_path_buf(),
            model,
            steps: Vec::new(),
            tables_of: 0,
            written: Vec::new(),
            complete: false,
            stopped: None,
            handle: InterruptHandle::new(&dir.join("summary.json")),
            mesh,
            materials,
            rule,
            vtu_steps: Vec::new(),
            vtu_last: None,
            manifest,
            status,
            provenance: None,
            started: std::time::Instant::now(),
            output_s: 0.0,
            background: false,
        };
        out.publish(|| Ok(()))?;
        Ok(out)
    }

    /// The folder.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// The folder's `status.sta` and `convergence.cvg` ([`crate::log`]).
    pub fn status_files(&self) -> StatusFiles {
        self.status.clone()
    }

    /// Records where the solve came from: in every `summary.json` from now on, with the
    /// stage times (`solve`, `output`, `total`) and the peak memory brought up to date.
    pub fn set_provenance(&mut self, provenance: Provenance) -> Result<(), Error> {
        self.provenance = Some(provenance);
        self.publish(|| Ok(()))
    }

    /// A handle for a signal handler: `stop` writes `summary.json` as it stands with
    /// `"stopped": "interrupted by …"`.
    pub fn interrupt_handle(&self) -> InterruptHandle {
        self.handle.clone()
    }

    /// Writes what `p` brings: the tables that grew, the step's displacements when it is
    /// complete, and `summary.json`. A signal's stop waits for a write in progress (counted
    /// in the interrupt handle's [`Backlog`](crate::output::Backlog); a writer thread counts
    /// its own), so that the increment being written is kept.
    pub fn progress(&mut self, p: Progress<'_>) -> Result<(), Error> {
        if self.background {
            return self.write_progress(p);
        }
        let backlog = self.handle.backlog();
        backlog.sent();
        let written = self.write_progress(p);
        backlog.done();
        written
    }

    fn write_progress(&mut self, p: Progress<'_>) -> Result<(), Error> {
        let r = match p {
            Progress::Increment(r) | Progress::Step(r) | Progress::Failed(r) => r,
        };
        if self.tables_of != r.step {
            self.tables_of = r.step;
            self.written = vec![None; r.outputs.len()];
        }
        let entry = step_json(r)?;
        match self.steps.get_mut(r.step - 1) {
            Some(s) => *s = entry,
            None => self.steps.push(entry),
        }
        let sub = self.dir.join(format!("step-{}", r.step));
        let grown: Vec<usize> = (0..r.outputs.len())
            .filter(|&i| {
                self.written.get(i).copied().flatten() != Some(r.outputs[i].increments.len())
            })
            .collect();
        let displacements =
            matches!(p, Progress::Step(_)).then(|| displacements_csv(self.model, &r.displacements));
        let vtu = match p {
            Progress::Failed(_) => None,
            _ => self.state_vtu(r)?,
        };
        let pvd = match &vtu {
            Some((name, _)) => {
                let mut steps = self.vtu_steps.clone();
                let time = r
                    .increments
                    .iter()
                    .rev()
                    .find(|i| i.converged)
                    .map_or(r.start_time, |i| i.total_time);
                steps.push((time, name.clone()));
                Some((pvd_string(&steps)?, steps))
            }
            None => None,
        };
        let dir = self.dir.clone();
        self.publish(|| {
            std::fs::create_dir_all(&sub).map_err(io(&sub))?;
            for &i in &grown {
                let t = &r.outputs[i];
                write_atomic(&sub.join(&t.file), t.csv.as_bytes())?;
            }
            if let Some(csv) = &displacements {
                write_atomic(&sub.join("displacements.csv"), csv.as_bytes())?;
            }
            if let (Some((name, text)), Some((pvd, _))) = (&vtu, &pvd) {
                write_atomic(&dir.join(name), text.as_bytes())?;
                write_atomic(&dir.join("model.pvd"), pvd.as_bytes())?;
            }
            Ok(())
        })?;
        if let Some((_, steps)) = pvd {
            self.vtu_steps = steps;
        }
        for i in grown {
            self.written[i] = Some(r.outputs[i].increments.len());
        }
        Ok(())
    }

    /// The VTU of the state `r` holds (its last converged increment), named `model_N.vtu` with
    /// N counting the VTU files of the solve; None when that state was written already.
    fn state_vtu(&mut self, r: &StepResult) -> Result<Option<(String, String)>, Error> {
        let key = (r.step, r.increments.iter().filter(|i| i.converged).count());
        if self.vtu_last == Some(key) || r.displacements.is_empty() {
            return Ok(None);
        }
        let rules = StressRules {
            materials: &self.materials,
            coupling: ShearCoupling::Exact,
            hex20_rule: self.rule,
            hex8_rule: IntegrationRule::Gauss2,
            kinematics: if r.nlgeom {
                Kinematics::Nonlinear
            } else {
                Kinematics::Linear
            },
        };
        let u: Vec<f64> = r.displacements.iter().flatten().copied().collect();
        let text = state_vtu(
            &self.mesh,
            &rules,
            &u,
            Some(&self.model.node_ids),
            Units::DECK,
        )?;
        self.vtu_last = Some(key);
        Ok(Some((format!("model_{}.vtu", self.vtu_steps.len()), text)))
    }

    /// Whether a writer thread of its own writes the files ([`super::write_in_background`]).
    pub(super) fn set_background(&mut self, on: bool) {
        self.background = on;
    }

    /// The solve failed: `summary.json` keeps every step and increment so far, `"complete":
    /// false` and the error in `"stopped"`.
    pub fn failed(&mut self, error: &Error) -> Result<(), Error> {
        self.stopped = Some(format!("error: {error}"));
        self.publish(|| Ok(()))
    }

    /// Every step is complete: `displacements.csv` (the last step's), then `summary.json` with
    /// `"complete": true`, last.
    pub fn finish(&mut self, results: &[StepResult]) -> Result<(), Error> {
        self.complete = true;
        self.stopped = None;
        let last = results
            .last()
            .map(|r| displacements_csv(self.model, &r.displacements));
        let dir = self.dir.clone();
        self.publish(|| match &last {
            Some(csv) => write_atomic(&dir.join("displacements.csv"), csv.as_bytes()),
            None => Ok(()),
        })
    }

    /// Runs `write`, then writes `summary.json` as it stands and prepares its interrupted form
    /// (none once complete), under the signal handler's lock.
    fn publish(&mut self, write: impl FnOnce() -> Result<(), Error>) -> Result<(), Error> {
        let t = std::time::Instant::now();
        if let Some(p) = &mut self.provenance {
            let total = self.started.elapsed().as_secs_f64();
            p.stage("output", self.output_s);
            p.stage(
                "solve",
                if self.background {
                    total
                } else {
                    total - self.output_s
                },
            );
            p.finish(total);
        }
        let not_used: Vec<serde_json::Value> = self
            .model
            .not_used
            .iter()
            .map(|n| serde_json::json!({ "at": n.at, "keyword": n.keyword, "reason": n.reason }))
            .collect();
        let mut value = serde_json::json!({
            "complete": self.complete,
            "stopped": self.stopped,
            "steps": self.steps,
            "not_used": not_used,
            // The factorisation's and assembly's threads (the rayon pool, `--threads N`).
            "threads": rayon::current_num_threads(),
        });
        if let Some(p) = &self.provenance {
            value["provenance"] = serde_json::to_value(p)?;
        }
        let now = serde_json::to_string_pretty(&value)?;
        let stopped = if self.complete {
            None
        } else {
            if self.stopped.is_none() {
                value["stopped"] = "interrupted".into();
            }
            Some(serde_json::to_string_pretty(&value)?)
        };
        let manifest = &self.manifest;
        self.handle
            .publish(write, &now, stopped, || manifest.write())?;
        self.output_s += t.elapsed().as_secs_f64();
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_our_file_names_are_cleaned() {
        for n in [
            "summary.json",
            "displacements.csv",
            ".summary.json.partial",
            "model.pvd",
            "model_12.vtu",
        ] {
            assert!(ours(n), "{n}");
        }
        for n in [
            "notes.txt",
            "summary.json.bak",
            "results.json",
            "model_.vtu",
        ] {
            assert!(!ours(n), "{n}");
        }
        for n in [
            "displacements.csv",
            "node-print-TIP.csv",
            "el-file.csv",
            "node-print-x0-totals.csv",
        ] {
            assert!(ours_in_step(n), "{n}");
        }
        for n in ["notes.csv", "el-file.txt"] {
            assert!(!ours_in_step(n), "{n}");
        }
        assert!(step_folder("step-12") && !step_folder("step-") && !step_folder("step-a"));
    }
}
