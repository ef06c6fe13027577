//! `nonlin3d sweep run` and `sweep status`: the cases of a plan run into their own folders, as
//! `nonlin3d run` writes them (results.json rewritten after every level, `"complete": true`
//! last, every file atomic: [`crate::output::RunOutput`]). A case whose results.json says
//! complete is never run again, so a study killed at any instant resumes where it stopped; one
//! case (`--case K`) is what a job-array task runs. Cases run in parallel (rayon, `jobs` at a
//! time), each on one solver thread unless asked.

use super::plan::{Case, Plan};
use crate::output::RunOutput;
use crate::{Error, Scene};
use rayon::prelude::*;
use std::path::Path;
use std::time::Instant;

/// What a case's folder says about it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum CaseState {
    /// results.json says `"complete": true`.
    Complete,
    /// The run stopped on an error (results.json's `"stopped"`, or the error that kept it from
    /// writing one).
    Failed(String),
    /// Started but not finished: running now, or killed (results.json `"complete": false`
    /// without an error).
    Incomplete,
    /// Never run: no results.json.
    Missing,
}

impl CaseState {
    /// `complete`, `failed`, `incomplete`, `missing`.
    pub fn name(&self) -> &'static str {
        match self {
            Self::Complete => "complete",
            Self::Failed(_) => "failed",
            Self::Incomplete => "incomplete",
            Self::Missing => "missing",
        }
    }

    /// The error of a failed case.
    pub fn error(&self) -> Option<&str> {
        match self {
            Self::Failed(e) => Some(e),
            _ => None,
        }
    }
}

/// The state of the case in `dir` from its results.json.
pub fn case_state(dir: &Path) -> CaseState {
    let Ok(text) = std::fs::read_to_string(dir.join("results.json")) else {
        return CaseState::Missing;
    };
    let Ok(v) = serde_json::from_str::<serde_json::Value>(&text) else {
        return CaseState::Incomplete;
    };
    if v["complete"].as_bool() == Some(true) {
        return CaseState::Complete;
    }
    match v["stopped"].as_str() {
        Some(s) if s.starts_with("error: ") => CaseState::Failed(s["error: ".len()..].into()),
        _ => CaseState::Incomplete,
    }
}

/// Every case of the study in `dir` with its state.
pub fn status(dir: &Path) -> Result<(Plan, Vec<CaseState>), Error> {
    let plan = Plan::read(dir)?;
    let states = plan
        .cases
        .iter()
        .map(|c| case_state(&plan.case_dir(dir, c)))
        .collect();
    Ok((plan, states))
}

/// How `sweep run` runs the cases.
#[derive(Debug, Clone, Copy, Default)]
pub struct RunOptions {
    /// Cases at once (0: one per core).
    pub jobs: usize,
    /// Solver threads of each case (None: 1, or the scene's own count if it sets one).
    pub threads: Option<usize>,
    /// Only this case (a job-array task) …
    pub case: Option<usize>,
    /// … or, with `case`, the cases from it to this one (a job-array task's chunk, run in one
    /// process: a process per case of 0.15 s cost 1.5 × the wall, docs/PERFORMANCE.md).
    pub last: Option<usize>,
    /// … every `step`-th of them (0 or 1: all).
    pub step: usize,
}

/// What became of one case in [`run`].
#[derive(Debug, Clone, PartialEq)]
pub struct Outcome {
    /// Its id.
    pub id: usize,
    /// Its state after the run.
    pub state: CaseState,
    /// It was complete already and was not run.
    pub skipped: bool,
    /// Wall time of this run of it, s (0 when skipped).
    pub seconds: f64,
}

/// Runs every case of the study in `dir` that is not complete (or only `options.case`, or
/// `case` to `last`, every `step`-th),
/// `done` told of each as it ends; the outcomes in case order.
pub fn run(
    dir: &Path,
    options: RunOptions,
    done: &(dyn Fn(&Case, &Outcome) + Sync),
) -> Result<Vec<Outcome>, Error> {
    let plan = Plan::read(dir)?;
    let n = plan.cases.len();
    let cases: Vec<&Case> = match (options.case, options.last) {
        (None, _) => plan.cases.iter().collect(),
        (Some(k), last) => {
            let l = last.unwrap_or(k);
            let step = options.step.max(1);
            let what = match last {
                Some(l) if step > 1 => format!("--cases {k}-{l}/{step}"),
                Some(l) => format!("--cases {k}-{l}"),
                None => format!("--case {k}"),
            };
            if k > l || l >= n {
                return Err(Error::Sweep(format!(
                    "{what}: the study has cases 0 to {}",
                    n.saturating_sub(1)
                )));
            }
            plan.cases[k..=l].iter().step_by(step).collect()
        }
    };
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(options.jobs)
        .build()
        .map_err(|e| Error::Sweep(format!("--jobs {}: {e}", options.jobs)))?;
    let outcomes = pool.install(|| {
        cases
            .par_iter()
            .with_max_len(1)
            .map(|case| {
                let folder = plan.case_dir(dir, case);
                let outcome = match case_state(&folder) {
                    CaseState::Complete => Outcome {
                        id: case.id,
                        state: CaseState::Complete,
                        skipped: true,
                        seconds: 0.0,
                    },
                    _ => {
                        let t = Instant::now();
                        let state = match run_case(&folder, case, options.threads) {
                            Ok(()) => CaseState::Complete,
                            Err(e) => CaseState::Failed(e.to_string()),
                        };
                        Outcome {
                            id: case.id,
                            state,
                            skipped: false,
                            seconds: t.elapsed().as_secs_f64(),
                        }
                    }
                };
                done(case, &outcome);
                outcome
            })
            .collect()
    });
    Ok(outcomes)
}

/// Runs one case's `scene.toml` into its folder, as `nonlin3d run` does.
fn run_case(folder: &Path, case: &Case, threads: Option<usize>) -> Result<(), Error> {
    use crate::analysis::Progress;
    let t0 = Instant::now();
    let path = folder.join("scene.toml");
    let input = crate::provenance::input_file(&path)?;
    if input.sha256 != case.scene_sha256 {
        return Err(Error::Sweep(format!(
            "{}: changed since it was planned (SHA-256 {} in plan.json): plan again",
            path.display(),
            case.scene_sha256
        )));
    }
    let text = std::fs::read_to_string(&path).map_err(|source| Error::Io {
        path: path.clone(),
        source,
    })?;
    let mut scene = Scene::from_toml(&text)?;
    scene.analysis.threads = match threads {
        Some(n) => n,
        None if scene.analysis.threads == 0 => 1,
        None => scene.analysis.threads,
    };
    let quantity = if matches!(scene.geometry, crate::scene::Geometry::Plate { .. }) {
        "load_n"
    } else {
        "strain"
    };
    let mut output = RunOutput::create(folder, &scene.title, quantity)?;
    let mut provenance = crate::provenance::Provenance::new(
        Some(input),
        serde_json::to_value(&scene).ok(),
        crate::analysis::settings(&scene).0.solver,
    );
    provenance.stage("read", t0.elapsed().as_secs_f64());
    output.set_provenance(provenance)?;
    let outcome = crate::analysis::run(&scene, &mut |p| match p {
        Progress::Built { model, dofs, .. } => output.built(model, dofs),
        Progress::Level { result, .. } => output.level(result),
    });
    match outcome {
        Ok(mut results) => output.finish(&mut results),
        Err(e) => {
            let _ = output.failed(&e);
            Err(e)
        }
    }
}
