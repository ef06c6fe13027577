//! Element kernel benchmarks (issue: workspace foundation; thesis §2.4.3 timings).
//!
//! Per-element time of internal force + strains + stresses + tangent for each (kind, rule):
//! the single-element kernel, the batched kernel on 1 and 2 threads, and the plain
//! per-quadrature-point nalgebra implementation (B explicit, Bᵀ C B) as the baseline.
//! Figures and ratios go to docs/PERFORMANCE.md.

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use nonlin3d::element::reference::evaluate_reference;
use nonlin3d::element::{
    BatchInput, BatchOutput, ElementKind, ElementOutput, IntegrationRule, Kinematics, ShapeTable,
    Workspace, evaluate, evaluate_batch, evaluate_batch_with,
};
use nonlin3d::laminate::{ShearCoupling, Stiffness, materials};
use nonlin3d_testkit::Lcg;
use std::hint::black_box;
use std::time::Duration;

const CASES: [(ElementKind, IntegrationRule, &str); 4] = [
    (ElementKind::Hex20, IntegrationRule::Gauss2, "hex20_2x2x2"),
    (ElementKind::Hex20, IntegrationRule::Gauss3, "hex20_3x3x3"),
    (ElementKind::Hex8, IntegrationRule::Gauss2, "hex8_2x2x2"),
    (
        ElementKind::Hex8,
        IntegrationRule::SelectiveReduced,
        "hex8_sri",
    ),
];

/// Elements per batch: a thesis-size model (model 6 has ~1 000 Hex20 cells).
const BATCH: usize = 1024;

/// A distorted laminate-like element (2 × 2 × 0.25 mm, corners moved 10 %) with a
/// postbuckling-size displacement field (rotation ~0.1 rad, strains ~0.5 %).
fn element(kind: ElementKind, rng: &mut Lcg) -> (Vec<[f64; 3]>, Vec<[f64; 3]>) {
    let size = [2e-3, 2e-3, 0.25e-3];
    let x: Vec<[f64; 3]> = kind
        .reference_nodes()
        .iter()
        .map(|p| {
            let mut q = [0.0; 3];
            for r in 0..3 {
                q[r] = 0.5 * size[r] * p[r] + 0.1 * 0.25e-3 * rng.uniform(-1.0, 1.0);
            }
            q
        })
        .collect();
    let u = x
        .iter()
        .map(|p| {
            [
                -0.1 * p[2] + 0.005 * p[0],
                0.002 * p[1],
                0.1 * p[0] + 1e-6 * rng.uniform(-1.0, 1.0),
            ]
        })
        .collect();
    (x, u)
}

fn material() -> Stiffness {
    materials::generic_graphite_epoxy()
        .stiffness()
        .and_then(|c| c.rotated_about_z(0.3, ShearCoupling::Exact))
        .unwrap_or_else(|e| panic!("material: {e}"))
}

fn bench_single(c: &mut Criterion) {
    let m = material();
    let mut group = c.benchmark_group("element_single");
    group
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(2))
        .sample_size(30);
    group.throughput(Throughput::Elements(1));
    for (kind, rule, name) in CASES {
        let table = ShapeTable::new(kind, rule).unwrap_or_else(|e| panic!("{e}"));
        let (x, u) = element(kind, &mut Lcg::new(7));
        let mut out = ElementOutput::new(&table);
        let mut ws = Workspace::new(&table);
        eprintln!(
            "{name}: {} flops per element with tangent",
            table.flops_with_tangent()
        );
        group.bench_function(BenchmarkId::new("kernel", name), |b| {
            b.iter(|| {
                evaluate(
                    &table,
                    black_box(&x),
                    black_box(&u),
                    &m,
                    Kinematics::Nonlinear,
                    true,
                    &mut ws,
                    &mut out,
                )
                .unwrap_or_else(|e| panic!("{e}"));
                black_box(&out.tangent);
            })
        });
        group.bench_function(BenchmarkId::new("nalgebra_reference", name), |b| {
            b.iter(|| {
                black_box(
                    evaluate_reference(
                        &table,
                        black_box(&x),
                        black_box(&u),
                        &m,
                        Kinematics::Nonlinear,
                    )
                    .unwrap_or_else(|e| panic!("{e}")),
                )
            })
        });
    }
    group.finish();
}

fn bench_batched(c: &mut Criterion) {
    let m = [material()];
    let mut group = c.benchmark_group("element_batched");
    group
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(3))
        .sample_size(20);
    group.throughput(Throughput::Elements(BATCH as u64));
    for (kind, rule, name) in CASES {
        let table = ShapeTable::new(kind, rule).unwrap_or_else(|e| panic!("{e}"));
        let mut rng = Lcg::new(11);
        let (mut coords, mut disp) = (Vec::new(), Vec::new());
        for _ in 0..BATCH {
            let (x, u) = element(kind, &mut rng);
            coords.extend(x);
            disp.extend(u);
        }
        let material_of = vec![0; BATCH];
        let input = BatchInput {
            coords: &coords,
            disp: &disp,
            materials: &m,
            material_of: &material_of,
        };
        let mut out = BatchOutput::new(&table, BATCH, true);
        for threads in [1usize, 2] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap_or_else(|e| panic!("{e}"));
            group.bench_function(
                BenchmarkId::new(format!("{name}_stored_threads"), threads),
                |b| {
                    b.iter(|| {
                        pool.install(|| {
                            evaluate_batch(&table, &input, Kinematics::Nonlinear, &mut out)
                        })
                        .unwrap_or_else(|e| panic!("{e}"));
                        black_box(&out.tangents);
                    })
                },
            );
            // Streamed: each element's output consumed while in cache (what assembly does).
            group.bench_function(
                BenchmarkId::new(format!("{name}_streamed_threads"), threads),
                |b| {
                    b.iter(|| {
                        let sums = pool
                            .install(|| {
                                evaluate_batch_with(
                                    &table,
                                    &input,
                                    Kinematics::Nonlinear,
                                    true,
                                    || 0.0,
                                    |s, _, o| *s += o.tangent[0] + o.forces[0],
                                )
                            })
                            .unwrap_or_else(|e| panic!("{e}"));
                        black_box(sums);
                    })
                },
            );
        }
    }
    group.finish();
}

criterion_group!(benches, bench_single, bench_batched);
criterion_main!(benches);
