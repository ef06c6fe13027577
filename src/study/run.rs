//! Running a study's cases side by side (rayon), each on a one-thread pool of its own so that
//! its CPU time is that of one thread and the cases' times compare.

use super::{CaseResult, G_QUANTITIES, Plan, QUANTITIES, Quantities, Reference, Study};
use super::{describe, pareto, richardson};
use crate::scene::Geometry;
use crate::{Error, Scene};
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

/// What [`run`] reports as it goes (from the worker threads).
#[derive(Debug, Clone, Copy)]
pub enum Event<'a> {
    /// Case `index` (in the knobs file's order) started.
    Started {
        /// Index.
        index: usize,
        /// Its name.
        name: &'a str,
    },
    /// Case `index` ended (converged or failed); `done` of `total` have.
    Finished {
        /// Index.
        index: usize,
        /// What it gave (errors not yet filled in).
        case: &'a CaseResult,
        /// Cases ended so far.
        done: usize,
        /// Cases in all.
        total: usize,
    },
}

/// Runs every case of `plan` on `scene`, `jobs` at a time (0: rayon's thread count), and
/// measures them against the family's references. A case that fails is kept with its error;
/// bad knobs stop the study before anything runs.
pub fn run(
    scene: &Scene,
    plan: &Plan,
    jobs: usize,
    progress: &(dyn Fn(Event) + Sync),
) -> Result<Study, Error> {
    let scenes = plan.scenes(scene)?;
    let n = scenes.len();
    let jobs = if jobs == 0 {
        rayon::current_num_threads()
    } else {
        jobs
    }
    .clamp(1, n);
    // Largest first by the budget's factor estimate, so the side-by-side runs end together.
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by_key(|&k| {
        std::cmp::Reverse(crate::budget::estimate_scene(&scenes[k]).factor_entries)
    });
    let next = AtomicUsize::new(0);
    let done = AtomicUsize::new(0);
    let slots: Vec<Mutex<Option<CaseResult>>> = (0..n).map(|_| Mutex::new(None)).collect();
    let worker = || {
        loop {
            let i = next.fetch_add(1, Ordering::SeqCst);
            let Some(&k) = order.get(i) else { break };
            let spec = &plan.cases[k];
            progress(Event::Started {
                index: k,
                name: &spec.name,
            });
            let mut case = measure(&scenes[k]);
            case.name = spec.name.clone();
            case.knobs = describe(&spec.knobs);
            case.family = spec.family;
            case.h = spec.h;
            progress(Event::Finished {
                index: k,
                case: &case,
                done: done.fetch_add(1, Ordering::SeqCst) + 1,
                total: n,
            });
            *slots[k].lock().unwrap_or_else(|e| e.into_inner()) = Some(case);
        }
    };
    match rayon::ThreadPoolBuilder::new().num_threads(jobs).build() {
        Ok(pool) => pool.scope(|s| {
            for _ in 0..jobs {
                s.spawn(|_| worker());
            }
        }),
        Err(_) => worker(),
    }
    let mut cases: Vec<CaseResult> = slots
        .into_iter()
        .filter_map(|m| m.into_inner().unwrap_or_else(|e| e.into_inner()))
        .collect();
    let strip = matches!(scene.geometry, Geometry::ThroughWidth { .. });
    let given = plan.cases.iter().any(|c| c.family && c.h.is_some());
    let d = if strip { 2.0 } else { 3.0 };
    for c in cases.iter_mut().filter(|c| c.family && c.h.is_none()) {
        c.h = Some((c.dofs.max(1) as f64).powf(-1.0 / d));
    }
    let references = references(&cases);
    judge(&mut cases, &references);
    let worst_over = counted(&references);
    Ok(Study {
        title: plan.title.clone().unwrap_or_else(|| scene.title.clone()),
        scene: scene.title.clone(),
        jobs,
        family_size: if given {
            "given".into()
        } else {
            format!("dofs^(-1/{d})")
        },
        cases,
        references,
        worst_over,
    })
}

/// Runs one scene on a one-thread pool, timing it.
fn measure(scene: &Scene) -> CaseResult {
    let t0 = Instant::now();
    let go = || {
        let c0 = thread_cpu_s();
        let r = crate::analysis::run(scene, &mut |_| Ok(()));
        (r, thread_cpu_s().zip(c0).map(|(b, a)| b - a))
    };
    let (outcome, cpu_s) = match rayon::ThreadPoolBuilder::new().num_threads(1).build() {
        Ok(pool) => pool.install(go),
        Err(_) => go(),
    };
    let wall_s = t0.elapsed().as_secs_f64();
    let mut case = CaseResult {
        name: String::new(),
        knobs: String::new(),
        family: false,
        h: None,
        dofs: 0,
        wall_s,
        cpu_s,
        iterations: 0,
        values: Quantities::default(),
        errors: Quantities::default(),
        worst_g_error: None,
        pareto: false,
        failed: None,
    };
    match outcome {
        Ok(r) => {
            case.dofs = r.model.dofs;
            case.iterations = r.levels.iter().map(|l| l.convergence.iterations).sum();
            case.values = Quantities::of(&r);
        }
        Err(e) => case.failed = Some(e.to_string()),
    }
    case
}

/// CPU seconds the calling thread has run (Linux: the first field of
/// `/proc/thread-self/schedstat`, nanoseconds on a CPU); None where unavailable.
fn thread_cpu_s() -> Option<f64> {
    let text = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
    let ns: f64 = text.split_whitespace().next()?.parse().ok()?;
    Some(ns * 1e-9)
}

/// The reference of each quantity from the family members that ran, coarse to fine (h
/// decreasing; a member whose h is not below the previous one is left out).
fn references(cases: &[CaseResult]) -> Vec<Reference> {
    let mut family: Vec<&CaseResult> = cases
        .iter()
        .filter(|c| c.family && c.failed.is_none() && c.h.is_some())
        .collect();
    family.sort_by(|a, b| b.h.unwrap_or(0.0).total_cmp(&a.h.unwrap_or(0.0)));
    family.dedup_by(|b, a| b.h >= a.h);
    QUANTITIES
        .iter()
        .enumerate()
        .map(|(i, (name, _))| {
            let points: Vec<(f64, f64)> = family
                .iter()
                .filter_map(|c| Some((c.h?, c.values.values()[i]?)))
                .collect();
            Reference {
                quantity: name,
                fit: richardson::fit(&points),
            }
        })
        .collect()
}

/// The G quantities that set a case's worst error: those whose reference is at least
/// [`SMALL`] of the reference G_T max (a relative error of a G near zero, e.g. G_II where the
/// front runs across the load, says nothing of the mesh).
pub(crate) fn counted(references: &[Reference]) -> Vec<&'static str> {
    let peak = references
        .first()
        .and_then(|r| r.fit.as_ref())
        .map_or(0.0, |f| f.reference.abs());
    references[..G_QUANTITIES]
        .iter()
        .filter(|r| {
            r.fit
                .as_ref()
                .is_some_and(|f| f.reference.abs() >= SMALL * peak)
        })
        .map(|r| r.quantity)
        .collect()
}

/// See [`counted`].
pub const SMALL: f64 = 0.1;

/// Fills in each case's relative errors, worst G error (over the [`counted`] quantities) and
/// place on the Pareto front (CPU time, or wall time where there is none, against the worst
/// G error).
fn judge(cases: &mut [CaseResult], references: &[Reference]) {
    let counted = counted(references);
    for c in cases.iter_mut().filter(|c| c.failed.is_none()) {
        let v = c.values.values();
        let mut e = [None; 6];
        for (i, r) in references.iter().enumerate() {
            if let (Some(x), Some(f)) = (v[i], &r.fit)
                && f.reference != 0.0
            {
                e[i] = Some((x - f.reference) / f.reference.abs());
            }
        }
        c.errors = Quantities::from_values(e);
        c.worst_g_error = e[..G_QUANTITIES]
            .iter()
            .zip(QUANTITIES)
            .filter(|(_, (name, _))| counted.contains(name))
            .filter_map(|(x, _)| x.map(f64::abs))
            .max_by(f64::total_cmp);
    }
    let points: Vec<Option<(f64, f64)>> = cases
        .iter()
        .map(|c| Some((c.cpu_s.unwrap_or(c.wall_s), c.worst_g_error?)))
        .collect();
    for (c, on) in cases.iter_mut().zip(pareto::front(&points)) {
        c.pareto = on;
    }
}
