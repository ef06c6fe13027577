//! A state's VTU (nodal strains and stresses recovered from every cell, then about thirty
//! Float64 values per point as inline binary): what a deck solve writes at every
//! converged increment, on the main thread between increments. Figures go to
//! docs/PERFORMANCE.md ("What the second thread waits for").
//!
//! Run: `cargo bench --bench output`.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use nonlin3d::assembly::StressRules;
use nonlin3d::element::{IntegrationRule, Kinematics};
use nonlin3d::fields::{Units, state_vtu};
use nonlin3d::laminate::{ShearCoupling, materials};
use nonlin3d::mesh::{EmbeddedParams, embedded_delamination};
use std::hint::black_box;
use std::time::Duration;

fn bench_state_vtu(c: &mut Criterion) {
    let mut group = c.benchmark_group("state_vtu");
    group
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(4))
        .sample_size(15);
    let p = EmbeddedParams {
        slices: 12,
        ..EmbeddedParams::thesis_reference()
    };
    let mesh = embedded_delamination(&p).unwrap_or_else(|e| panic!("{e}"));
    let steel = [materials::steel()
        .stiffness()
        .unwrap_or_else(|e| panic!("{e}"))];
    let rules = StressRules {
        materials: &steel,
        coupling: ShearCoupling::Exact,
        hex20_rule: IntegrationRule::Gauss3,
        hex8_rule: IntegrationRule::Gauss2,
        kinematics: Kinematics::Nonlinear,
    };
    let n = 3 * mesh.nodes.len();
    let u: Vec<f64> = (0..n).map(|i| 1e-5 * (0.37 * i as f64).sin()).collect();
    group.throughput(Throughput::Elements(mesh.cells.len() as u64));
    group.bench_function(format!("plate_10k_{n}_dof"), |b| {
        b.iter(|| state_vtu(black_box(&mesh), &rules, &u, None, Units::MM_MPA_N))
    });
    group.finish();
}

criterion_group!(benches, bench_state_vtu);
criterion_main!(benches);
