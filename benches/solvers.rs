//! Criterion benchmarks of the sparse solvers (issue: sparse solvers) on structured Hex20
//! elasticity matrices: symbolic analysis, numeric factorisation and solve for the profile
//! solver (RCM) and faer LDLᵀ (AMD, nested dissection) on 1 and 2 threads, with the dense
//! matmul of the same machine as the yardstick. The size sweep up to 150 k DOF with memory figures is
//! `benches/solver_report.rs`; figures in docs/PERFORMANCE.md.

#[path = "../tests/common/mod.rs"]
mod common;

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use nonlin3d::solver::{
    FaerMode, FaerOrdering, FaerSolver, FaerSplit, LinearSolver, ProfileLdlt, SymmetricMatrix,
};
use std::hint::black_box;
use std::time::Duration;

fn bench_phases(c: &mut Criterion, name: &str, k: &SymmetricMatrix, profile: bool) {
    let mut group = c.benchmark_group(format!("solver_{name}"));
    group
        .sample_size(10)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(4));
    // faer with AMD and with nested dissection, each on 1 and 2 threads.
    let mut solvers: Vec<(String, Box<dyn LinearSolver>)> = Vec::new();
    for (ordering, name) in [
        (FaerOrdering::Amd, "amd"),
        (FaerOrdering::NestedDissection, "nd"),
    ] {
        for threads in [1, 2] {
            // Unsplit, faer's kernels on the threads named at every size (the defaults would
            // split from 5 k DOF and keep the kernels on one thread below 20 k).
            let mut s = FaerSolver::new(FaerMode::Ldlt)
                .with_ordering(ordering)
                .with_threads(threads);
            s.split = FaerSplit::Off;
            s.kernel_threads_from = 0;
            solvers.push((format!("faer_ldlt_{name}_{threads}thread"), Box::new(s)));
        }
    }
    if profile {
        solvers.insert(0, ("profile_rcm".into(), Box::new(ProfileLdlt::new())));
    }
    for (label, mut s) in solvers {
        let analysis = s.analyze(k.pattern()).unwrap_or_else(|e| panic!("{e}"));
        group.throughput(Throughput::Elements(analysis.flops as u64));
        group.bench_function(BenchmarkId::new("symbolic", &label), |b| {
            b.iter(|| black_box(s.analyze(k.pattern()).unwrap_or_else(|e| panic!("{e}"))))
        });
        group.bench_function(BenchmarkId::new("numeric", &label), |b| {
            b.iter(|| black_box(s.factorize(k).unwrap_or_else(|e| panic!("{e}"))))
        });
        let mut rhs = vec![1.0; k.n()];
        group.throughput(Throughput::Elements(k.n() as u64));
        group.bench_function(BenchmarkId::new("solve", &label), |b| {
            b.iter(|| {
                rhs.fill(1.0);
                s.solve_in_place(&mut rhs, 1)
                    .unwrap_or_else(|e| panic!("{e}"));
                black_box(&rhs);
            })
        });
    }
    group.finish();
}

fn bench_solvers(c: &mut Criterion) {
    // ~11 k DOF cube-like block and a ~54 k DOF laminate-like plate (16:1 elements).
    bench_phases(
        c,
        "hex20_11k",
        &common::clamped_box_stiffness([12, 12, 5], [2e-3, 2e-3, 1e-3]),
        true,
    );
    bench_phases(
        c,
        "hex20_laminate_54k",
        &common::clamped_box_stiffness([30, 30, 4], [2e-3, 2e-3, 0.125e-3]),
        false,
    );
}

fn bench_dense(c: &mut Criterion) {
    use faer::{Accum, Mat, Par};
    let n = 1024;
    let a = Mat::<f64>::from_fn(n, n, |i, j| ((i * 7 + j * 3) % 13) as f64 - 6.0);
    let mut out = Mat::<f64>::zeros(n, n);
    let mut group = c.benchmark_group("dense_matmul_1024");
    group
        .sample_size(10)
        .throughput(Throughput::Elements(2 * (n as u64).pow(3)));
    for threads in [1usize, 2] {
        let par = if threads > 1 {
            Par::rayon(threads)
        } else {
            Par::Seq
        };
        group.bench_function(BenchmarkId::new("faer_threads", threads), |b| {
            b.iter(|| {
                faer::linalg::matmul::matmul(
                    out.as_mut(),
                    Accum::Replace,
                    a.as_ref(),
                    a.as_ref(),
                    1.0,
                    par,
                )
            })
        });
    }
    group.finish();
}

/// y = A x over the pattern's 3×3 node blocks (`matvec`) against the column loop it
/// reproduces bit for bit (`matvec_by_columns`): the product mixed precision's refinement
/// and conjugate gradients run once per step.
fn bench_matvec(c: &mut Criterion) {
    let k = common::clamped_box_stiffness([30, 30, 4], [2e-3, 2e-3, 0.125e-3]);
    let n = k.n();
    let x: Vec<f64> = (0..n).map(|i| ((i * 7) % 13) as f64 - 6.0).collect();
    let mut y = vec![0.0; n];
    let mut group = c.benchmark_group("matvec_hex20_laminate_54k");
    group.throughput(Throughput::Elements(2 * k.values().len() as u64));
    group.bench_function("node_blocks", |b| {
        b.iter(|| {
            k.matvec(black_box(&x), &mut y)
                .unwrap_or_else(|e| panic!("{e}"))
        })
    });
    group.bench_function("columns", |b| {
        b.iter(|| {
            k.matvec_by_columns(black_box(&x), &mut y)
                .unwrap_or_else(|e| panic!("{e}"))
        })
    });
    group.finish();
}

criterion_group!(benches, bench_dense, bench_solvers, bench_matvec);
criterion_main!(benches);
