//! Newton iteration cost on the thesis's plate model (issue: assembly and Newton): time of one
//! assembly of residual + tangent, one factorisation and one solve, for Hex20 embedded
//! delamination models of ~10 k and ~100 k DOF; the bare batched kernel on the same cells (the
//! assembly's ceiling); and CalculiX 2.20 on the same NLGEOM deck (if `ccx` is on PATH), per
//! converged increment. One run per figure (the large model takes seconds).
//!
//! Run: `cargo bench --bench newton_report`.

use nonlin3d::assembly::{Assembler, Constraints};
use nonlin3d::element::{BatchInput, IntegrationRule, Kinematics, ShapeTable, evaluate_batch_with};
use nonlin3d::laminate::{ShearCoupling, materials};
use nonlin3d::mesh::inp::{
    InpBoundary, InpCload, InpDeck, InpElastic, InpMaterial, InpStep, inp_string,
};
use nonlin3d::mesh::names;
use nonlin3d::mesh::{EmbeddedParams, Mesh, embedded_delamination};
use nonlin3d::newton::{NewtonSettings, Stepping, StructuralProblem, follow_path};
use nonlin3d::solver::SolverKind;
use std::time::Instant;

#[path = "shared/plates.rs"]
mod plates;

fn best<T>(reps: usize, mut f: impl FnMut() -> T) -> (f64, T) {
    let mut t_best = f64::INFINITY;
    let mut out = None;
    for _ in 0..reps {
        let t = Instant::now();
        let r = f();
        t_best = t_best.min(t.elapsed().as_secs_f64());
        out = Some(r);
    }
    match out {
        Some(o) => (t_best, o),
        None => panic!("reps must be ≥ 1"),
    }
}

fn plate(p: &EmbeddedParams) -> (Mesh, StructuralProblem) {
    let mesh = embedded_delamination(p).unwrap_or_else(|e| panic!("{e}"));
    let steel = materials::steel()
        .stiffness()
        .unwrap_or_else(|e| panic!("{e}"));
    let assembler = Assembler::new(
        &mesh,
        &[steel],
        ShearCoupling::Exact,
        IntegrationRule::Gauss2,
        IntegrationRule::Gauss2,
        Kinematics::Nonlinear,
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let mut c = Constraints::new(assembler.n());
    let fix = |c: &mut Constraints, set: &str, r: usize| {
        c.fix_nodes(&mesh.node_sets[set], r)
            .unwrap_or_else(|e| panic!("{e}"))
    };
    fix(&mut c, names::X0, 0);
    fix(&mut c, names::Y0, 1);
    fix(&mut c, names::Z0, 2);
    let top = mesh.node_sets[names::CENTER_TOP][0];
    c.add_load(3 * top + 2, 0.25 * 150.0)
        .unwrap_or_else(|e| panic!("{e}"));
    (
        mesh.clone(),
        StructuralProblem::new(assembler, c).unwrap_or_else(|e| panic!("{e}")),
    )
}

fn main() {
    let cases = [
        (
            "plate ~10 k DOF (12 slices)",
            EmbeddedParams {
                slices: 12,
                ..EmbeddedParams::thesis_reference()
            },
        ),
        (
            "plate ~100 k DOF (24 slices, 10 + 12 radial, 3 + 6 layers)",
            plates::plate_89k(),
        ),
    ];
    println!(
        "| model | DOF | cells | assembly (f + K) ms | bare kernel ms | kernel/assembly | factorisation ms | solve ms | iteration ms |"
    );
    println!("|---|---:|---:|---:|---:|---:|---:|---:|---:|");
    for (name, p) in &cases {
        let (mesh, mut problem) = plate(p);
        let n = problem.assembler().n();
        let u = vec![0.0; n];
        let mut k = problem.assembler().new_tangent();
        let (t_asm, _) = best(3, || {
            problem
                .assembler()
                .residual(&u, 1.0, problem.constraints(), Some(&mut k))
                .unwrap_or_else(|e| panic!("{e}"))
        });
        // The same element work streamed to a consumer that only touches the outputs.
        let table = ShapeTable::new(
            nonlin3d::element::ElementKind::Hex20,
            IntegrationRule::Gauss2,
        )
        .unwrap_or_else(|e| panic!("{e}"));
        let coords: Vec<[f64; 3]> = (0..mesh.cells.len())
            .flat_map(|c| mesh.cell_coordinates(c))
            .collect();
        let disp = vec![[0.0; 3]; coords.len()];
        let mats = [materials::steel()
            .stiffness()
            .unwrap_or_else(|e| panic!("{e}"))];
        let of = vec![0usize; mesh.cells.len()];
        let input = BatchInput {
            coords: &coords,
            disp: &disp,
            materials: &mats,
            material_of: &of,
        };
        let (t_kernel, _) = best(3, || {
            evaluate_batch_with(
                &table,
                &input,
                Kinematics::Nonlinear,
                true,
                || 0.0,
                |s, _, o| *s += o.tangent[0],
            )
            .unwrap_or_else(|e| panic!("{e}"))
        });
        let mut solver = SolverKind::FaerLdlt.build();
        solver
            .analyze(problem.assembler().pattern())
            .unwrap_or_else(|e| panic!("{e}"));
        let (t_fact, _) = best(3, || solver.factorize(&k).unwrap_or_else(|e| panic!("{e}")));
        let mut b = vec![1.0; n];
        let (t_solve, _) = best(3, || {
            solver
                .solve_in_place(&mut b, 1)
                .unwrap_or_else(|e| panic!("{e}"))
        });
        println!(
            "| {name} | {n} | {} | {:.1} | {:.1} | {:.2} | {:.1} | {:.1} | {:.1} |",
            mesh.cells.len(),
            1e3 * t_asm,
            1e3 * t_kernel,
            t_kernel / t_asm,
            1e3 * t_fact,
            1e3 * t_solve,
            1e3 * (t_asm + t_fact + t_solve)
        );
        // Whole nonlinear solve of the 10 k model against CalculiX on the same deck.
        if n < 20_000 {
            let stepping = Stepping {
                initial: 0.25,
                max: 0.25,
                ..Stepping::default()
            };
            let strategies = [
                ("full Newton", NewtonSettings::default()),
                (
                    "modified Newton, tangent kept across increments",
                    NewtonSettings {
                        keep_tangent: true,
                        refactor_every: usize::MAX,
                        max_iterations: 60,
                        ..NewtonSettings::default()
                    },
                ),
                (
                    "BFGS (20 pairs), tangent kept across increments, with line search",
                    NewtonSettings {
                        keep_tangent: true,
                        refactor_every: usize::MAX,
                        quasi_newton: 20,
                        max_iterations: 60,
                        ..NewtonSettings::default()
                    },
                ),
                (
                    "BFGS (20 pairs), tangent kept across increments, no line search, refactor when ‖r‖ doubles",
                    NewtonSettings {
                        keep_tangent: true,
                        refactor_every: usize::MAX,
                        quasi_newton: 20,
                        line_search: false,
                        refactor_ratio: 2.0,
                        max_iterations: 60,
                        ..NewtonSettings::default()
                    },
                ),
            ];
            println!();
            let mut reference: Option<Vec<f64>> = None;
            let mut per_increment = Vec::new();
            for (label, settings) in &strategies {
                let mut u = vec![0.0; n];
                let t = Instant::now();
                let path = follow_path(&mut problem, &mut u, &[1.0], settings, &stepping)
                    .unwrap_or_else(|e| panic!("{e}"));
                let ours = t.elapsed().as_secs_f64();
                let incs = path.attempts.iter().filter(|a| a.converged()).count();
                let iters: usize = path.attempts.iter().map(|a| a.iterations.len()).sum();
                let facts = path
                    .attempts
                    .iter()
                    .flat_map(|a| &a.iterations)
                    .filter(|i| i.negative_pivots.is_some())
                    .count();
                let wmax = u.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
                let diff = reference.as_ref().map_or(0.0, |r| {
                    r.iter()
                        .zip(&u)
                        .fold(0.0_f64, |m, (a, b)| m.max((a - b).abs()))
                        / wmax
                });
                reference.get_or_insert(u);
                println!(
                    "nonlin3d, {name}, {label}: {incs} increments, {iters} iterations, {facts} factorisations, {:.2} s, {:.3} s per increment, max |Δu| against full Newton {diff:.1e} of max |u|",
                    ours,
                    ours / incs as f64
                );
                per_increment.push((label, ours / incs as f64));
            }
            if std::process::Command::new("ccx").arg("-v").output().is_ok() {
                let steel = materials::steel();
                let mats = [InpMaterial {
                    name: "STEEL".into(),
                    elastic: InpElastic::Isotropic {
                        e: steel.e11,
                        nu: steel.nu12,
                    },
                }];
                let top = mesh.node_sets[names::CENTER_TOP][0];
                let step = InpStep {
                    nlgeom: true,
                    increment: 0.25,
                    period: 1.0,
                    boundaries: vec![
                        InpBoundary {
                            nset: names::X0.into(),
                            first: 1,
                            last: 1,
                            value: 0.0,
                        },
                        InpBoundary {
                            nset: names::Y0.into(),
                            first: 2,
                            last: 2,
                            value: 0.0,
                        },
                        InpBoundary {
                            nset: names::Z0.into(),
                            first: 3,
                            last: 3,
                            value: 0.0,
                        },
                    ],
                    cloads: vec![InpCload {
                        node: top,
                        dof: 3,
                        value: 37.5,
                    }],
                };
                // C3D20R: the same 2×2×2 rule as nonlin3d's Hex20 here.
                let deck = inp_string(&InpDeck {
                    heading: "plate".into(),
                    mesh: &mesh,
                    materials: &mats,
                    steps: vec![step],
                })
                .unwrap_or_else(|e| panic!("{e}"))
                .replace("TYPE=C3D20,", "TYPE=C3D20R,");
                let dir = std::env::temp_dir().join("nonlin3d-ccx-plate");
                let _ = std::fs::create_dir_all(&dir);
                std::fs::write(dir.join("plate.inp"), deck).unwrap_or_else(|e| panic!("{e}"));
                let t = Instant::now();
                let out = std::process::Command::new("ccx")
                    .args(["-i", "plate"])
                    .current_dir(&dir)
                    .env("OMP_NUM_THREADS", "1")
                    .output();
                let theirs = t.elapsed().as_secs_f64();
                let sta = std::fs::read_to_string(dir.join("plate.sta")).unwrap_or_default();
                let ccx_incs = sta
                    .lines()
                    .filter(|l| {
                        l.split_whitespace().count() >= 6 && l.trim_start().starts_with('1')
                    })
                    .count()
                    .max(1);
                println!(
                    "CalculiX 2.20 (1 thread), same deck as C3D20R: {ccx_incs} increments, {theirs:.2} s, {:.3} s per increment (exit {:?})",
                    theirs / ccx_incs as f64,
                    out.map(|o| o.status.code()),
                );
                for (label, t) in &per_increment {
                    println!(
                        "  ratio per converged increment, {label}: {:.1}×",
                        (theirs / ccx_incs as f64) / t
                    );
                }
            }
        }
    }
}
