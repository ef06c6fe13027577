//! One-shot solver report over problem sizes (issue: sparse solvers): for structured Hex20
//! elasticity matrices of ~1 k to ~150 k DOF and a laminate-like thin model, the time of
//! symbolic analysis, numeric factorisation and one solve, factor entries, flops, GFLOP/s and
//! peak memory, for the profile solver (RCM) and faer LDLᵀ (AMD, nested dissection) on 1 and 2
//! threads, plus the dense matmul GFLOP/s of this machine in the same run. Each case runs once (the large ones
//! take seconds); criterion covers the small cases in `benches/solvers.rs`.
//!
//! Run: `cargo bench --bench solver_report` (add `-- quick` to stop at ~50 k DOF,
//! `-- only=laminate` to run the cases whose name contains that text, `-- noprofile` to leave
//! out the profile solver, `-- noamd` to leave out faer with AMD, `-- mixed` to add faer ND
//! with an f32 factor refined in f64, `-- split` to add faer ND split at the top separator
//! (`FaerSplit::Halves`, halves on two threads), `-- splitmixed` to add the split with f32
//! halves refined in f64, `-- metis` to add faer with METIS's order (and the `split`,
//! `mixed` and `splitmixed` rows on METIS's order beside ND's; `nond` leaves ND's out;
//! `nowhole` keeps only those rows, not the unsplit METIS ones; `two` keeps only their
//! two-thread rows),
//! `-- directions` to add faer (ND, and METIS's order with `metis`) keeping an f32 copy of each f64 factor
//! for direction solves (`FaerDirections::Single`: its numeric time includes the copy, its
//! solve and backward error are those of `solve_direction_in_place`),
//! `-- auto` to add faer with `FaerOrdering::Auto` (its symbolic time is every candidate's
//! analysis, its label the order chosen), `-- nond` to leave out faer with our nested
//! dissection, `-- rounds=N` to run every solver of a case N times in
//! turn, so that ratios between solvers come from neighbouring runs on a busy machine).
//! Before each faer row, a `tree of …` line gives its supernode tree: supernodes, the widest,
//! W = Σ c², the critical path cp (the costliest leaf-to-root chain) and W/cp, the most that
//! running subtrees side by side could divide the factorisation's time by.
//! The last column is the normwise backward error ‖b − A x‖∞ / (‖A‖∞‖x‖∞ + ‖b‖∞) of the
//! solve.

#[path = "../tests/common/mod.rs"]
mod common;
#[path = "shared/plates.rs"]
mod plates;

use nonlin3d::element::IntegrationRule;
use nonlin3d::laminate::materials;
use nonlin3d::mesh::{
    EmbeddedParams, Mesh, ThroughWidthParams, embedded_delamination, names,
    through_width_delamination,
};
use nonlin3d::solver::{
    FaerDirections, FaerMode, FaerOrdering, FaerPrecision, FaerSolver, FaerSplit, LinearSolver,
    ProfileLdlt, SymmetricMatrix,
};
use std::time::Instant;

/// A memory figure of this process from /proc/self/status (`VmHWM` peak, `VmRSS` current), MiB.
fn status_mib(key: &str) -> f64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with(key))
                .and_then(|l| l.split_whitespace().nth(1)?.parse::<f64>().ok())
        })
        .map_or(f64::NAN, |kb| kb / 1024.0)
}
fn peak_mib() -> f64 {
    status_mib("VmHWM")
}
fn current_mib() -> f64 {
    status_mib("VmRSS")
}
/// CPU seconds of this process so far, all threads (`/proc/self/stat` utime + stime, in
/// ticks of 1/100 s).
fn cpu_seconds() -> f64 {
    std::fs::read_to_string("/proc/self/stat")
        .ok()
        .and_then(|s| {
            // Fields after the command name (which ends with the last ')'): utime is the 12th.
            let rest = &s[s.rfind(')')? + 2..];
            let f: Vec<&str> = rest.split_whitespace().collect();
            Some((f.get(11)?.parse::<f64>().ok()? + f.get(12)?.parse::<f64>().ok()?) / 100.0)
        })
        .unwrap_or(f64::NAN)
}

/// The 1-minute load average.
fn load_average() -> String {
    std::fs::read_to_string("/proc/loadavg")
        .ok()
        .and_then(|s| s.split_whitespace().next().map(str::to_owned))
        .unwrap_or_default()
}

/// Resets VmHWM (Linux `clear_refs` 5).
fn reset_peak() {
    let _ = std::fs::write("/proc/self/clear_refs", "5");
}

fn dense_matmul_gflops(threads: usize) -> f64 {
    use faer::{Accum, Mat, Par};
    let n = 1536;
    let a = Mat::<f64>::from_fn(n, n, |i, j| ((i * 7 + j * 3) % 13) as f64 - 6.0);
    let b = a.clone();
    let mut c = Mat::<f64>::zeros(n, n);
    let par = if threads > 1 {
        Par::rayon(threads)
    } else {
        Par::Seq
    };
    let mut best = f64::INFINITY;
    for _ in 0..5 {
        let t = Instant::now();
        faer::linalg::matmul::matmul(c.as_mut(), Accum::Replace, a.as_ref(), b.as_ref(), 1.0, par);
        best = best.min(t.elapsed().as_secs_f64());
    }
    std::hint::black_box(&c);
    2.0 * (n as f64).powi(3) / best / 1e9
}

/// faer LDLᵀ unsplit on `ordering`, its own kernels on `threads` at every size (the rows say
/// what they measure: the defaults would split from `SPLIT_FROM_DOFS` and keep faer's kernels
/// on one thread below `KERNEL_THREADS_FROM_DOFS`).
fn whole(ordering: FaerOrdering, threads: usize) -> FaerSolver {
    let mut s = FaerSolver::new(FaerMode::Ldlt)
        .with_ordering(ordering)
        .with_threads(threads);
    s.split = FaerSplit::Off;
    s.kernel_threads_from = 0;
    s
}

/// Where a case's matrix comes from.
enum Source {
    /// `common::clamped_box_stiffness` with these cells and sizes.
    Box([usize; 3], [f64; 3]),
    /// `common::anchor_box_stiffness`: the box as `factor_anchor.py` builds it for PARDISO and
    /// CHOLMOD (z = 0 clamped, the clamped DOFs out of the pattern).
    Anchor([usize; 3], [f64; 3]),
    /// The embedded-delamination plate (steel, symmetry planes x0, y0, z0 fixed), tangent at
    /// zero displacement.
    Plate(EmbeddedParams),
    /// The through-width delamination model (steel, x0 clamped), tangent at zero displacement.
    Through(ThroughWidthParams),
}

impl Source {
    fn matrix(&self) -> SymmetricMatrix {
        let (mesh, fixes): (Mesh, &[(&str, usize)]) = match self {
            Self::Box(n, h) => return common::clamped_box_stiffness(*n, *h),
            Self::Anchor(n, h) => return common::anchor_box_stiffness(*n, *h),
            Self::Plate(p) => (
                embedded_delamination(p).unwrap_or_else(|e| panic!("{e}")),
                &[(names::X0, 0), (names::Y0, 1), (names::Z0, 2)],
            ),
            Self::Through(p) => (
                through_width_delamination(p)
                    .unwrap_or_else(|e| panic!("{e}"))
                    .0,
                &[(names::X0, 0), (names::X0, 1), (names::X0, 2)],
            ),
        };
        let steel = materials::steel()
            .stiffness()
            .unwrap_or_else(|e| panic!("{e}"));
        let problem = common::structural_problem(&mesh, steel, IntegrationRule::Gauss2, fixes);
        let u = vec![0.0; problem.assembler().n()];
        let mut k = problem.assembler().new_tangent();
        problem
            .assembler()
            .residual(&u, 1.0, problem.constraints(), Some(&mut k))
            .unwrap_or_else(|e| panic!("{e}"));
        k
    }
}

struct Row {
    case: String,
    dofs: usize,
    solver: String,
    symbolic: f64,
    numeric: f64,
    numeric_cpu: f64,
    solve: f64,
    entries: usize,
    lower: usize,
    flops: f64,
    peak: f64,
    load: String,
    negative: usize,
    backward_error: f64,
}

/// ‖b − A x‖∞ / (‖A‖∞‖x‖∞ + ‖b‖∞).
fn backward_error(k: &SymmetricMatrix, x: &[f64], b: &[f64]) -> f64 {
    let n = k.n();
    let (cp, ri, v) = (k.pattern().col_ptr(), k.pattern().row_idx(), k.values());
    let mut rows = vec![0.0f64; n];
    for j in 0..n {
        for p in cp[j]..cp[j + 1] {
            rows[ri[p]] += v[p].abs();
            if ri[p] != j {
                rows[j] += v[p].abs();
            }
        }
    }
    let norm = |w: &[f64]| w.iter().fold(0.0f64, |m, a| m.max(a.abs()));
    let mut ax = vec![0.0; n];
    k.matvec(x, &mut ax).unwrap_or_else(|e| panic!("{e}"));
    let r: Vec<f64> = ax.iter().zip(b).map(|(a, b)| b - a).collect();
    norm(&r) / (norm(&rows) * norm(x) + norm(b))
}

/// One solver on `k`: analysis, numeric factorisation and a solve (a direction solve,
/// `solve_direction_in_place`, if `direction`).
fn run(
    case: &str,
    k: &SymmetricMatrix,
    s: &mut dyn LinearSolver,
    label: String,
    direction: bool,
) -> Option<Row> {
    let n = k.n();
    let before = current_mib();
    reset_peak();
    let t = Instant::now();
    let analysis = match s.analyze(k.pattern()) {
        Ok(a) => a,
        Err(e) => {
            println!("| {case} | {n} | {label} | {e} | | | | | | | | | | |");
            return None;
        }
    };
    let symbolic = t.elapsed().as_secs_f64();
    // The supernode tree (faer's supernodal factors): how far threads could take it.
    if let Some(tree) = analysis.tree {
        println!(
            "tree of {case}, {label} ({}): {} supernodes, widest {} columns, W {:.2} G, critical \
             path {:.2} G (W/cp {:.2}), largest supernode {:.2} G",
            analysis.ordering,
            tree.supernodes,
            tree.widest,
            tree.flops * 1e-9,
            tree.critical_path_flops * 1e-9,
            tree.parallelism(),
            tree.largest_supernode_flops * 1e-9
        );
    }
    // Small systems take milliseconds: best of several runs there, one run for large ones.
    let reps = if n < 20_000 { 15 } else { 1 };
    let (mut numeric, mut solve) = (f64::INFINITY, f64::INFINITY);
    let mut numeric_cpu = f64::NAN;
    let mut f = None;
    let mut omega = 0.0;
    for _ in 0..reps {
        let (t, c) = (Instant::now(), cpu_seconds());
        f = Some(s.factorize(k).ok()?);
        let (wall, cpu) = (t.elapsed().as_secs_f64(), cpu_seconds() - c);
        if wall < numeric {
            numeric = wall;
            numeric_cpu = cpu;
        }
        let mut b = vec![1.0; n];
        let t = Instant::now();
        if direction {
            s.solve_direction_in_place(&mut b, 1).ok()?;
        } else {
            s.solve_in_place(&mut b, 1).ok()?;
        }
        solve = solve.min(t.elapsed().as_secs_f64());
        omega = backward_error(k, &b, &vec![1.0; n]);
    }
    let f = f?;
    let peak = peak_mib() - before;
    Some(Row {
        case: case.into(),
        dofs: n,
        solver: label,
        symbolic,
        numeric,
        numeric_cpu,
        solve,
        entries: analysis.factor_entries,
        lower: analysis.lower_nonzeros,
        flops: f.flops,
        peak,
        load: load_average(),
        negative: f.negative_pivots,
        backward_error: omega,
    })
}

fn main() {
    let quick = std::env::args().any(|a| a == "quick");
    println!(
        "dense matmul 1536³ (faer): {:.1} GFLOP/s on 1 thread, {:.1} GFLOP/s on 2 threads",
        dense_matmul_gflops(1),
        dense_matmul_gflops(2)
    );
    println!();
    println!(
        "| case | DOF | solver | symbolic ms | numeric ms (best of 15 below 20 k DOF) | numeric CPU s (all threads) | load | solve ms | factor entries | nnz(L) | GFLOP | GFLOP/s | peak MiB | neg. pivots | backward error |"
    );
    println!("|---|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|");
    let has = |flag: &str| std::env::args().any(|a| a == flag);
    let rounds: usize = std::env::args()
        .find_map(|a| a.strip_prefix("rounds=").and_then(|r| r.parse().ok()))
        .unwrap_or(1);
    let mut boxes: Vec<(&str, [usize; 3], [f64; 3])> = vec![
        ("cube 2×2×1", [2, 2, 1], [2e-3, 2e-3, 1e-3]),
        ("cube 3×3×2", [3, 3, 2], [2e-3, 2e-3, 1e-3]),
        ("cube 4×4×2", [4, 4, 2], [2e-3, 2e-3, 1e-3]),
        ("cube 6×6×3", [6, 6, 3], [2e-3, 2e-3, 1e-3]),
        ("cube 9×9×4", [9, 9, 4], [2e-3, 2e-3, 1e-3]),
        ("cube 12×12×5 (~10 k)", [12, 12, 5], [2e-3, 2e-3, 1e-3]),
        (
            "laminate 30×30×4, 16:1 (~50 k)",
            [30, 30, 4],
            [2e-3, 2e-3, 0.125e-3],
        ),
        ("cube 20×20×8 (~50 k)", [20, 20, 8], [2e-3, 2e-3, 1e-3]),
    ];
    if !quick {
        boxes.push(("cube 30×30×12 (~150 k)", [30, 30, 12], [2e-3, 2e-3, 1e-3]));
        boxes.push((
            "laminate 55×55×3, 16:1 (~140 k)",
            [55, 55, 3],
            [2e-3, 2e-3, 0.125e-3],
        ));
    }
    let mut cases: Vec<(String, Source)> = boxes
        .into_iter()
        .map(|(name, n, h)| (name.to_owned(), Source::Box(n, h)))
        .collect();
    // The cube as the PARDISO/CHOLMOD anchor script builds it (its fill figures are of this
    // pattern, not of the x = 0-clamped box above).
    cases.push((
        "cube 20×20×8, anchor's matrix (z = 0 clamped, decoupled)".into(),
        Source::Anchor([20, 20, 8], [2e-3, 2e-3, 1e-3]),
    ));
    // The scene meshes: the embedded-delamination plate at the thesis's reference size and at
    // the 89 k-DOF size of `benches/newton_report.rs`, and a through-width model 24 cells across.
    cases.push((
        "plate, embedded delamination, 12 slices (~10 k)".into(),
        Source::Plate(EmbeddedParams {
            slices: 12,
            ..EmbeddedParams::thesis_reference()
        }),
    ));
    cases.push((
        "through-width, 24 across (~25 k)".into(),
        Source::Through(ThroughWidthParams {
            across: 24,
            width: 12e-3,
            ..ThroughWidthParams::example()
        }),
    ));
    if !quick {
        cases.push((
            "plate, embedded delamination, 24 slices (~89 k)".into(),
            Source::Plate(plates::plate_89k()),
        ));
    }
    // `only=TEXT` keeps the cases whose name contains TEXT.
    let only = std::env::args().find_map(|a| a.strip_prefix("only=").map(str::to_owned));
    cases.retain(|c| only.as_deref().is_none_or(|o| c.0.contains(o)));
    for (case, source) in cases {
        let case = case.as_str();
        let k = source.matrix();
        // faer with each ordering on 1 and 2 threads, side by side in one run.
        let mut solvers: Vec<(Box<dyn LinearSolver>, String)> = Vec::new();
        for (ordering, name) in [
            (FaerOrdering::Amd, "AMD"),
            (FaerOrdering::NestedDissection, "ND"),
            (FaerOrdering::Metis, "METIS"),
        ] {
            let skip = match ordering {
                FaerOrdering::Amd => has("noamd"),
                FaerOrdering::NestedDissection => has("nond"),
                _ => !has("metis") || has("nowhole"),
            };
            if skip {
                continue;
            }
            for threads in [1, 2] {
                solvers.push((
                    Box::new(whole(ordering, threads)),
                    format!(
                        "faer LDLᵀ {name}, {threads} thread{}",
                        if threads > 1 { "s" } else { "" }
                    ),
                ));
            }
        }
        // The profile solver (RCM): only where its envelope fits the 3 GiB cap and its time is
        // reasonable (analysis reports TooLarge otherwise); `noprofile` skips it.
        if !std::env::args().any(|a| a == "noprofile") {
            solvers.insert(
                0,
                (Box::new(ProfileLdlt::new()), "profile LDLᵀ (RCM)".into()),
            );
        }
        // The tree-level split (two halves on two threads, `FaerSplit::Halves`) in f64, and
        // mixed precision (f32 factor refined in f64) unsplit and split.
        let mut faers: Vec<(FaerSolver, String)> = Vec::new();
        // On our nested dissection's order (unless `nond`) and on METIS's (with `metis`).
        let split_orderings: Vec<(FaerOrdering, &str)> = [
            (FaerOrdering::NestedDissection, "ND", !has("nond")),
            (FaerOrdering::Metis, "METIS", has("metis")),
        ]
        .into_iter()
        .filter_map(|(o, n, keep)| keep.then_some((o, n)))
        .collect();
        for (flag, split, precision, name) in [
            ("split", FaerSplit::Halves, FaerPrecision::Double, "split"),
            (
                "mixed",
                FaerSplit::Off,
                FaerPrecision::mixed(),
                "mixed f32/f64",
            ),
            (
                "splitmixed",
                FaerSplit::Halves,
                FaerPrecision::mixed(),
                "split mixed f32/f64",
            ),
        ] {
            if !has(flag) {
                continue;
            }
            for &(ordering, oname) in &split_orderings {
                for threads in [1, 2] {
                    if has("two") && threads == 1 {
                        continue;
                    }
                    let mut s = whole(ordering, threads);
                    s.precision = precision;
                    s.split = split;
                    faers.push((
                        s,
                        format!(
                            "faer LDLᵀ {oname} {name}, {threads} thread{}",
                            if threads > 1 { "s" } else { "" }
                        ),
                    ));
                }
            }
        }
        if has("directions") {
            for &(ordering, oname) in &split_orderings {
                let mut s = whole(ordering, 1);
                s.directions = FaerDirections::Single;
                faers.push((s, format!("faer LDLᵀ {oname}, 1 thread, f32 directions")));
            }
        }
        // The split's shape: the two threads' work and the join's (what decides whether a
        // deeper split would balance better).
        for &(ordering, oname) in split_orderings
            .iter()
            .filter(|_| has("split") || has("splitmixed"))
        {
            let mut s = FaerSolver::new(FaerMode::Ldlt).with_ordering(ordering);
            s.split = FaerSplit::Halves;
            if let Ok(whole) = s.analyze(k.pattern())
                && let (Some((n0, n1, ns)), Some([w0, w1, ws])) = (s.split_sizes(), s.split_work())
            {
                println!(
                    "split of {case} ({oname}): interiors {n0} / {n1} DOF, separator {ns}; Σc² halves {:.2} / {:.2} G (ratio {:.3}), S {:.2} G; unsplit {:.2} G",
                    w0 / 1e9,
                    w1 / 1e9,
                    w0.max(w1) / w0.min(w1),
                    ws / 1e9,
                    whole.flops / 1e9
                );
            }
        }
        // `Auto` on 2 threads, kept apart to name the order it chose.
        let mut autos: Vec<(FaerSolver, String)> = Vec::new();
        if has("auto") {
            autos.push((
                FaerSolver::new(FaerMode::Ldlt).with_threads(2),
                "faer LDLᵀ Auto, the default (split from 5 k DOF), 2 threads".into(),
            ));
        }
        for _ in 0..rounds {
            let mut rows = Vec::new();
            for (s, label) in &mut solvers {
                rows.extend(run(case, &k, s.as_mut(), label.clone(), false));
            }
            for (s, label) in &mut autos {
                if let Some(mut r) = run(case, &k, s, label.clone(), false) {
                    r.solver += &format!(" (chose {:?})", s.chosen_ordering());
                    rows.push(r);
                }
            }
            for (s, label) in &mut faers {
                let direction = s.directions == FaerDirections::Single;
                if let Some(mut r) = run(case, &k, s, label.clone(), direction) {
                    if s.precision != FaerPrecision::Double {
                        let m = s.mixed_stats();
                        r.solver += &format!(
                            " (f32 factors {}, f64 {}{}, refinement steps {})",
                            m.single_factorizations,
                            m.double_factorizations,
                            m.last_fallback
                                .map(|w| format!(": {w}"))
                                .unwrap_or_default(),
                            m.refinement_steps
                        );
                    }
                    // On free cores the split takes the longer half plus the join.
                    if let Some([h0, h1, join]) = s.split_times() {
                        r.solver += &format!(
                            " [halves {h0:.3} / {h1:.3} CPU s, join {join:.3} s: critical path {:.3} s{}]",
                            h0.max(h1) + join,
                            s.split_fallback()
                                .map(|w| format!("; fell back: {w}"))
                                .unwrap_or_default()
                        );
                    }
                    rows.push(r);
                }
            }
            for r in rows {
                println!(
                    "| {} | {} | {} | {:.3} | {:.3} | {:.2} | {} | {:.3} | {} | {} | {:.2} | {:.1} | {:.0} | {} | {:.1e} |",
                    r.case,
                    r.dofs,
                    r.solver,
                    1e3 * r.symbolic,
                    1e3 * r.numeric,
                    r.numeric_cpu,
                    r.load,
                    1e3 * r.solve,
                    r.entries,
                    r.lower,
                    r.flops / 1e9,
                    r.flops / r.numeric / 1e9,
                    r.peak,
                    r.negative,
                    r.backward_error
                );
            }
        }
    }
}
