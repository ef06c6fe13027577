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
use crate::model::Model;
use crate::results::{Faces, FrontRow, LevelResult, ModelSummary, Results, Timings};
use nonlin3d_assembly::{StressRules, nodal_fields};
use nonlin3d_element::{Kinematics, Material};
use nonlin3d_laminate::ShearCoupling;
use nonlin3d_mesh::Mesh;
use nonlin3d_mesh::names::{CRACK_LOWER, CRACK_UPPER};
use nonlin3d_mesh::vtu::{Field, lines_vtu_string, pvd_string, vtu_string};
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

/// Units of the fields of a VTU: a suffix for the field names and the factor from the model's
/// units (SI for a scene's model) for lengths, stresses and forces.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Units {
    /// Lengths (coordinates, displacements, openings): suffix and factor.
    pub length: (&'static str, f64),
    /// Stresses: suffix and factor.
    pub stress: (&'static str, f64),
    /// Forces: suffix and factor.
    pub force: (&'static str, f64),
}

impl Units {
    /// A scene's run: the model in m, Pa, N written in mm, MPa, N (the scenes' units; G in
    /// J/m² in the front files).
    pub const MM_MPA_N: Self = Self {
        length: ("_mm", 1e3),
        stress: ("_MPa", 1e-6),
        force: ("_N", 1.0),
    };
    /// A deck's solve: the deck's own units, unconverted and unnamed (a deck, like CalculiX,
    /// has none).
    pub const DECK: Self = Self {
        length: ("", 1.0),
        stress: ("", 1.0),
        force: ("", 1.0),
    };
}

fn flat6(v: &[[f64; 6]], f: f64) -> Vec<f64> {
    v.iter().flatten().map(|x| x * f).collect()
}

/// The VTU text of state `u` (three displacements per node, model units): the mesh split along
/// material regions (`nonlin3d_assembly::nodal_fields`) with point fields `node` (`node_ids`
/// of the model's nodes, or the 0-based index), `displacement`, `strain_green_lagrange`
/// (tensor components xx, yy, zz, xy, yz, xz), `stress_pk2`, `stress_cauchy`, `reaction`
/// (internal nodal force), `crack_opening` (u(upper) − u(lower) on both faces of each pair of
/// the `crack_upper`/`crack_lower` sets, global x, y, z; only when the mesh has them), each
/// with the units' suffix; cell fields `material`, `ply_angle_deg` and the cell means of the
/// strain and stresses under the same names.
pub fn state_vtu<M: Copy + Into<Material>>(
    mesh: &Mesh,
    rules: &StressRules<'_, M>,
    u: &[f64],
    node_ids: Option<&[usize]>,
    units: Units,
) -> Result<String, Error> {
    let nf = nodal_fields(mesh, rules, u)?;
    let (ls, lf) = units.length;
    let (ss, sf) = units.stress;
    let (fs, ff) = units.force;
    let mut out_mesh = nf.mesh;
    for p in &mut out_mesh.nodes {
        *p = p.map(|x| x * lf);
    }
    let nodes = &nf.point_node;
    let gather3 = |v: &dyn Fn(usize) -> [f64; 3], f: f64| -> Vec<f64> {
        nodes.iter().flat_map(|&n| v(n).map(|x| x * f)).collect()
    };
    let label: Vec<f64> = nodes
        .iter()
        .map(|&n| node_ids.and_then(|ids| ids.get(n)).copied().unwrap_or(n) as f64)
        .collect();
    let disp = gather3(&|n| [u[3 * n], u[3 * n + 1], u[3 * n + 2]], lf);
    let reaction = gather3(&|n| nf.forces[n], ff);
    let names = [
        format!("displacement{ls}"),
        "strain_green_lagrange".to_string(),
        format!("stress_pk2{ss}"),
        format!("stress_cauchy{ss}"),
        format!("reaction{fs}"),
        format!("crack_opening{ls}"),
    ];
    let (strain, pk2, cauchy) = (
        flat6(&nf.strain, 1.0),
        flat6(&nf.pk2, sf),
        flat6(&nf.cauchy, sf),
    );
    let mut points = vec![
        Field {
            name: "node",
            components: 1,
            values: &label,
        },
        Field {
            name: &names[0],
            components: 3,
            values: &disp,
        },
        Field {
            name: &names[1],
            components: 6,
            values: &strain,
        },
        Field {
            name: &names[2],
            components: 6,
            values: &pk2,
        },
        Field {
            name: &names[3],
            components: 6,
            values: &cauchy,
        },
        Field {
            name: &names[4],
            components: 3,
            values: &reaction,
        },
    ];
    let opening;
    if let (Some(up), Some(low)) = (
        mesh.node_sets.get(CRACK_UPPER),
        mesh.node_sets.get(CRACK_LOWER),
    ) {
        let mut jump = vec![[0.0; 3]; mesh.nodes.len()];
        for (&a, &b) in up.iter().zip(low) {
            let d = [0, 1, 2].map(|r| u[3 * a + r] - u[3 * b + r]);
            jump[a] = d;
            jump[b] = d;
        }
        opening = gather3(&|n| jump[n], lf);
        points.push(Field {
            name: &names[5],
            components: 3,
            values: &opening,
        });
    }
    let (cs, cp, cc) = (
        flat6(&nf.cell_strain, 1.0),
        flat6(&nf.cell_pk2, sf),
        flat6(&nf.cell_cauchy, sf),
    );
    let cells = [
        Field {
            name: &names[1],
            components: 6,
            values: &cs,
        },
        Field {
            name: &names[2],
            components: 6,
            values: &cp,
        },
        Field {
            name: &names[3],
            components: 6,
            values: &cc,
        },
    ];
    Ok(vtu_string(&out_mesh, &points, &cells)?)
}

/// The front of one level as line segments through its points in the rows' (S) order, with
/// point fields `s_mm`, `G_I_J_m2`, `G_II_J_m2`, `G_III_J_m2`, `G_T_J_m2` (J/m², the values of
/// results.json), `mode_mix` = (G_II + G_III)/G_T (0 where G_T = 0) and `open` (1 where the
/// faces are open, 0 where they overlap); points at the front nodes, mm.
pub fn front_vtu(mesh: &Mesh, front: &[FrontRow]) -> Result<String, Error> {
    let points: Vec<[f64; 3]> = front
        .iter()
        .map(|r| {
            mesh.nodes
                .get(r.node)
                .copied()
                .unwrap_or([r.x_mm * 1e-3, r.y_mm * 1e-3, 0.0])
        })
        .map(|p| p.map(|x| x * 1e3))
        .collect();
    let segments: Vec<[usize; 2]> = (1..front.len()).map(|i| [i - 1, i]).collect();
    let col = |f: &dyn Fn(&FrontRow) -> f64| -> Vec<f64> { front.iter().map(f).collect() };
    let cols = [
        ("s_mm", col(&|r| r.s_mm)),
        ("G_I_J_m2", col(&|r| r.g_i)),
        ("G_II_J_m2", col(&|r| r.g_ii)),
        ("G_III_J_m2", col(&|r| r.g_iii)),
        ("G_T_J_m2", col(&|r| r.g_t)),
        (
            "mode_mix",
            col(&|r| {
                if r.g_t == 0.0 {
                    0.0
                } else {
                    (r.g_ii + r.g_iii) / r.g_t
                }
            }),
        ),
        (
            "open",
            col(&|r| if r.faces == Faces::Open { 1.0 } else { 0.0 }),
        ),
    ];
    let fields: Vec<Field<'_>> = cols
        .iter()
        .map(|(name, v)| Field {
            name,
            components: 1,
            values: v,
        })
        .collect();
    Ok(lines_vtu_string(&points, &segments, &fields)?)
}

/// Writes level `k`'s `model_K.vtu` ([`state_vtu`], mm, MPa, N) and `front_K.vtu`
/// ([`front_vtu`]) into `dir`.
pub fn write_level_vtu(
    dir: &Path,
    model: &Model,
    level: &LevelResult,
    k: usize,
) -> Result<(), Error> {
    let rules = StressRules {
        materials: &model.materials,
        coupling: ShearCoupling::Exact,
        hex20_rule: model.rule,
        hex8_rule: model.rule,
        kinematics: Kinematics::Nonlinear,
    };
    let text = state_vtu(
        &model.mesh,
        &rules,
        &level.displacements,
        None,
        Units::MM_MPA_N,
    )?;
    write_atomic(&dir.join(format!("model_{k}.vtu")), text.as_bytes())?;
    let text = front_vtu(&model.mesh, &level.front)?;
    write_atomic(&dir.join(format!("front_{k}.vtu")), text.as_bytes())
}

/// Writes `model.pvd` and `front.pvd` in `dir`: one step per level, at |value|.
pub fn write_pvds(dir: &Path, levels: &[LevelResult]) -> Result<(), Error> {
    for (stem, pvd) in [("model", "model.pvd"), ("front", "front.pvd")] {
        let steps: Vec<(f64, String)> = levels
            .iter()
            .enumerate()
            .map(|(k, l)| (l.value.abs(), format!("{stem}_{k}.vtu")))
            .collect();
        write_atomic(&dir.join(pvd), pvd_string(&steps)?.as_bytes())?;
    }
    Ok(())
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
            },
            levels: Vec::new(),
            critical: None,
            timings: Timings {
                mesh_s: 0.0,
                setup_s: 0.0,
                solve_s: 0.0,
                vcct_s: 0.0,
                output_s: 0.0,
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
