//! Substructuring cost on the thesis's reference plate (30 mm circle, Hex20, 2 263 nodes) and
//! on a refined one (16 slices, two sublaminate layers); thesis Fig. 3.2.2's partition: the sublaminate inside the front offset inward by ℓ = h is
//! nonlinear, the rest linear): the condensation by the partial factorisation with the interface
//! last (the default, with each ordering of the interior) and by K_ii's factor and blocked
//! multi-RHS solves at block widths 16, 64 and all, and one Newton
//! iteration (residual + tangent assembly, factorisation, solve) on the nonlinear region with
//! the superelement against the same on the whole model. The sizes are printed first.
//!
//! Run: `cargo bench -p nonlin3d-substructure --bench condense`.

use criterion::{Criterion, criterion_group, criterion_main};
use nonlin3d_assembly::{Assembler, Constraints, System};
use nonlin3d_element::{IntegrationRule, Kinematics};
use nonlin3d_laminate::{ShearCoupling, materials};
use nonlin3d_mesh::{EmbeddedParams, Mesh, embedded_delamination, names};
use nonlin3d_solver::{FaerOrdering, LinearSolver, SolverKind};
use nonlin3d_substructure::{CondenseSettings, Partition, condense};
use std::hint::black_box;
use std::time::Duration;

fn assembler(mesh: &Mesh) -> Assembler {
    let steel = materials::steel()
        .stiffness()
        .unwrap_or_else(|e| panic!("{e}"));
    Assembler::new(
        mesh,
        &[steel],
        ShearCoupling::Exact,
        IntegrationRule::Gauss2,
        IntegrationRule::Gauss2,
        Kinematics::Nonlinear,
    )
    .unwrap_or_else(|e| panic!("{e}"))
}

/// The reference plate, its §3.2 supports (u = 0 on x = 0, symmetry on y = 0 and z = 0,
/// u = −W·0.3 % on x = W) and the thesis's partition with ℓ = h.
fn plate(p: &EmbeddedParams) -> (Mesh, Constraints, Partition) {
    let mesh = embedded_delamination(p).unwrap_or_else(|e| panic!("{e}"));
    let mut c = Constraints::new(3 * mesh.nodes.len());
    let fix = |c: &mut Constraints, set: &str, r: usize| {
        c.fix_nodes(&mesh.node_sets[set], r)
            .unwrap_or_else(|e| panic!("{e}"))
    };
    fix(&mut c, names::X0, 0);
    fix(&mut c, names::Y0, 1);
    fix(&mut c, names::Z0, 2);
    for &v in &mesh.node_sets[names::X1] {
        c.prescribe(3 * v, -0.003 * p.w)
            .unwrap_or_else(|e| panic!("{e}"));
    }
    // Nonlinear: sublaminate cells whose centre lies inside the front circle offset by ℓ = h.
    let inner = p.a - p.h;
    let nonlinear: Vec<usize> = mesh.cell_sets[names::SUBLAMINATE]
        .iter()
        .copied()
        .filter(|&cell| {
            let x = mesh.cell_coordinates(cell);
            let n = x.len() as f64;
            let (cx, cy) = (
                x.iter().map(|p| p[0]).sum::<f64>() / n,
                x.iter().map(|p| p[1]).sum::<f64>() / n,
            );
            cx.hypot(cy) < inner
        })
        .collect();
    let part = Partition::from_nonlinear_cells(&mesh, &nonlinear).unwrap_or_else(|e| panic!("{e}"));
    (mesh, c, part)
}

/// One Newton iteration on `system` at u = 0, λ = 0.5: residual and tangent, factorisation,
/// solve (the symbolic analysis done once outside).
fn iteration(system: &System, solver: &mut dyn LinearSolver) -> f64 {
    let u = vec![0.0; system.n()];
    let mut k = system.new_tangent();
    let e = system
        .evaluate(&u, 0.5, Some(&mut k))
        .unwrap_or_else(|e| panic!("{e}"));
    solver.factorize(&k).unwrap_or_else(|e| panic!("{e}"));
    let mut du = e.residual;
    solver
        .solve_in_place(&mut du, 1)
        .unwrap_or_else(|e| panic!("{e}"));
    du[0]
}

fn bench(cr: &mut Criterion) {
    let reference = EmbeddedParams::thesis_reference();
    // Twice the slices and two sublaminate layers: a longer, thicker interface.
    let refined = EmbeddedParams {
        slices: 16,
        sub_layers: 2,
        ..EmbeddedParams::thesis_reference()
    };
    for (name, params, blocks) in [
        ("reference plate", &reference, &[16, 64, 0][..]),
        ("refined plate", &refined, &[16, 64, 0][..]),
    ] {
        let (mesh, c, part) = plate(params);
        let linear = assembler(part.linear_mesh());
        let done = condense(&part, &linear, &c, &CondenseSettings::default())
            .unwrap_or_else(|e| panic!("{e}"));
        let r = &done.report;
        println!(
            "{name}: {} DOF; linear region {} cells, interface {} DOF, interior {} free + {} \
             prescribed DOF, K_ii factor {} entries; nonlinear region {} cells, {} DOF; \
             asymmetry {:.1e}; condensation s (assembly, factor, solves) {:.3?}",
            3 * mesh.nodes.len(),
            part.linear_cells().len(),
            r.interface_dofs,
            r.interior_dofs,
            r.prescribed_dofs,
            r.factor_entries,
            part.nonlinear_cells().len(),
            3 * part.nonlinear_nodes().len(),
            r.asymmetry,
            r.seconds
        );
        let mut g = cr.benchmark_group("condense");
        g.measurement_time(Duration::from_secs(6)).sample_size(10);
        // K_red from the partial factorisation (the default) against K_ii's factor and block
        // solves of `block` columns.
        g.bench_function(format!("{name}, partial factorisation"), |b| {
            let s = CondenseSettings::default();
            b.iter(|| black_box(condense(&part, &linear, &c, &s).map(|d| d.report.block)))
        });
        for &block in blocks {
            g.bench_function(format!("{name}, block {block}"), |b| {
                let s = CondenseSettings {
                    block,
                    schur: false,
                    ..CondenseSettings::default()
                };
                b.iter(|| black_box(condense(&part, &linear, &c, &s).map(|d| d.report.block)))
            });
        }
        // The interior's ordering in the partial factorisation (Auto: METIS).
        for (label, ordering) in [
            ("amd", FaerOrdering::Amd),
            ("nested dissection", FaerOrdering::NestedDissection),
            ("metis", FaerOrdering::Metis),
        ] {
            let s = CondenseSettings {
                ordering,
                ..CondenseSettings::default()
            };
            g.bench_function(format!("{name}, ordering {label}"), |b| {
                b.iter(|| black_box(condense(&part, &linear, &c, &s).map(|d| d.report.block)))
            });
        }
        g.finish();

        let whole = System::builder(c.clone())
            .contribution(assembler(&mesh))
            .build()
            .unwrap_or_else(|e| panic!("{e}"));
        let sub = System::builder(
            part.nonlinear_constraints(&c)
                .unwrap_or_else(|e| panic!("{e}")),
        )
        .contribution(assembler(part.nonlinear_mesh()))
        .contribution(done.superelement.clone())
        .build()
        .unwrap_or_else(|e| panic!("{e}"));
        let mut g = cr.benchmark_group("newton iteration");
        g.measurement_time(Duration::from_secs(6)).sample_size(10);
        for (kind, system) in [("monolithic", &whole), ("superelement", &sub)] {
            let mut solver = SolverKind::FaerLdlt.build();
            solver
                .analyze(system.pattern())
                .unwrap_or_else(|e| panic!("{e}"));
            g.bench_function(format!("{name}, {kind}"), |b| {
                b.iter(|| black_box(iteration(system, &mut *solver)))
            });
        }
        g.finish();
    }
}

criterion_group!(benches, bench);
criterion_main!(benches);
