//! Assembly throughput against the bare batched kernel (issue: assembly and Newton; target:
//! assembly of r + K at ≥ 80 % of the kernel's throughput on ~100 k-DOF Hex20 models).
//!
//! The thesis's plate model (embedded circular debond, steel), Hex20 2×2×2, nonlinear, at a
//! small displacement field; ~10 k and ~89 k DOF; 1 and 2 threads. Per model and thread count:
//! the bare kernel over every cell (`evaluate_batch_with`, outputs consumed in cache), the
//! assembly of r + K with prefetch hints (the default) and without. The ratio kernel / assembly
//! is the measure. Also the residual r + K with constraints (the base clamped, a tip
//! load: `Assembler::residual`), the figure kept within 5 % across the System split (issue 17),
//! and the same through a `System` holding the solid as its one contribution.
//! Figures go to docs/PERFORMANCE.md.
//!
//! Run: `cargo bench --bench assembly`.

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use nonlin3d::assembly::{Assembler, Constraints, System};
use nonlin3d::element::{
    BatchInput, ElementKind, IntegrationRule, Kinematics, ShapeTable, evaluate_batch_with,
};
use nonlin3d::laminate::{ShearCoupling, materials};
use nonlin3d::mesh::{EmbeddedParams, embedded_delamination};
use std::hint::black_box;
use std::time::Duration;

#[path = "shared/plates.rs"]
mod plates;
use plates::plate_89k;

fn bench_assembly(c: &mut Criterion) {
    let mut group = c.benchmark_group("assembly");
    group
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(4))
        .sample_size(15);
    let models = [
        (
            "plate_10k",
            EmbeddedParams {
                slices: 12,
                ..EmbeddedParams::thesis_reference()
            },
        ),
        ("plate_89k", plate_89k()),
    ];
    let steel = materials::steel()
        .stiffness()
        .unwrap_or_else(|e| panic!("{e}"));
    for (name, p) in models {
        let mesh = embedded_delamination(&p).unwrap_or_else(|e| panic!("{e}"));
        let mut asm = Assembler::new(
            &mesh,
            &[steel],
            ShearCoupling::Exact,
            IntegrationRule::Gauss2,
            IntegrationRule::Gauss2,
            Kinematics::Nonlinear,
        )
        .unwrap_or_else(|e| panic!("{e}"));
        let n = asm.n();
        let u: Vec<f64> = (0..n).map(|i| 1e-5 * (0.37 * i as f64).sin()).collect();
        let mut k = asm.new_tangent();
        let table = ShapeTable::new(ElementKind::Hex20, IntegrationRule::Gauss2)
            .unwrap_or_else(|e| panic!("{e}"));
        let coords: Vec<[f64; 3]> = (0..mesh.cells.len())
            .flat_map(|c| mesh.cell_coordinates(c))
            .collect();
        let disp: Vec<[f64; 3]> = mesh
            .cells
            .iter()
            .flat_map(|c| {
                c.nodes
                    .iter()
                    .map(|&v| [u[3 * v], u[3 * v + 1], u[3 * v + 2]])
            })
            .collect();
        let mats = [steel];
        let of = vec![0usize; mesh.cells.len()];
        let input = BatchInput {
            coords: &coords,
            disp: &disp,
            materials: &mats,
            material_of: &of,
        };
        // The base clamped, a load at the last DOF: the constraints of the residual cases.
        let zmin = mesh
            .nodes
            .iter()
            .map(|p| p[2])
            .fold(f64::INFINITY, f64::min);
        let mut constraints = Constraints::new(n);
        for (v, p) in mesh.nodes.iter().enumerate() {
            if p[2] == zmin {
                constraints
                    .fix_nodes(&[v], 0)
                    .and_then(|_| constraints.fix_nodes(&[v], 1))
                    .and_then(|_| constraints.fix_nodes(&[v], 2))
                    .unwrap_or_else(|e| panic!("{e}"));
            }
        }
        constraints
            .add_load(n - 1, 1.0)
            .unwrap_or_else(|e| panic!("{e}"));
        let system = System::builder(constraints.clone())
            .contribution(
                Assembler::new(
                    &mesh,
                    &[steel],
                    ShearCoupling::Exact,
                    IntegrationRule::Gauss2,
                    IntegrationRule::Gauss2,
                    Kinematics::Nonlinear,
                )
                .unwrap_or_else(|e| panic!("{e}")),
            )
            .build()
            .unwrap_or_else(|e| panic!("{e}"));
        let mut ks = system.new_tangent();
        group.throughput(Throughput::Elements(mesh.cells.len() as u64));
        for threads in [1usize, 2] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap_or_else(|e| panic!("{e}"));
            group.bench_function(
                BenchmarkId::new(format!("{name}_bare_kernel_threads"), threads),
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
            for (hints, label) in [(true, "prefetch"), (false, "no_prefetch")] {
                asm.set_prefetch(hints);
                group.bench_function(
                    BenchmarkId::new(format!("{name}_assemble_{label}_threads"), threads),
                    |b| {
                        b.iter(|| {
                            let a = pool
                                .install(|| asm.assemble(&u, Some(&mut k)))
                                .unwrap_or_else(|e| panic!("{e}"));
                            black_box((a.energy, k.values()[0]));
                        })
                    },
                );
            }
            asm.set_prefetch(true);
            group.bench_function(
                BenchmarkId::new(format!("{name}_residual_threads"), threads),
                |b| {
                    b.iter(|| {
                        let (r, _, e) = pool
                            .install(|| asm.residual(&u, 1.0, &constraints, Some(&mut k)))
                            .unwrap_or_else(|e| panic!("{e}"));
                        black_box((r[0], e, k.values()[0]));
                    })
                },
            );
            group.bench_function(
                BenchmarkId::new(format!("{name}_system_threads"), threads),
                |b| {
                    b.iter(|| {
                        let e = pool
                            .install(|| system.evaluate(&u, 1.0, Some(&mut ks)))
                            .unwrap_or_else(|e| panic!("{e}"));
                        black_box((e.residual[0], e.energy, ks.values()[0]));
                    })
                },
            );
        }
    }
    group.finish();
}

/// The pattern of the 89 k plate from its cells' DOF lists: the node path (every list whole
/// nodes, the generators' case) against the DOF path the same lists take when one more list
/// holds a lone DOF (`SymmetricPattern::from_dof_lists`; the patterns differ only by that
/// DOF's column).
fn bench_pattern(c: &mut Criterion) {
    let mut group = c.benchmark_group("pattern");
    group.sample_size(10);
    let mesh = embedded_delamination(&plate_89k()).unwrap_or_else(|e| panic!("{e}"));
    let n = 3 * mesh.nodes.len();
    let lists = mesh.cell_dofs();
    let mut loose = lists.clone();
    loose.push(vec![n - 1]);
    for (label, l) in [
        ("plate_89k_node_path", &lists),
        ("plate_89k_dof_path", &loose),
    ] {
        group.bench_function(label, |b| {
            b.iter(|| {
                let p = nonlin3d::solver::SymmetricPattern::from_dof_lists(n, l)
                    .unwrap_or_else(|e| panic!("{e}"));
                black_box(p.nnz_lower())
            })
        });
    }
    group.finish();
}

criterion_group!(benches, bench_assembly, bench_pattern);
criterion_main!(benches);
