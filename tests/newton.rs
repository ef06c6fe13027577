//! Newton path following on finite element models (issue: assembly and Newton): determinism,
//! convergence rate, robustness to large steps, modified Newton; bifurcation detection is in
//! tests/newton_bifurcation.rs.

mod common;

use common::structural_problem;
use nonlin3d::element::{ElementKind, IntegrationRule};
use nonlin3d::laminate::materials;
use nonlin3d::mesh::{BoxParams, Mesh, structured_box};
use nonlin3d::newton::{
    NewtonError, NewtonSettings, PathSolver, Stepping, StructuralProblem, follow_path,
    follow_path_from, follow_path_with,
};
use nonlin3d::solver::SolverKind;

/// Cantilever 30 × 5 × 4 mm (6 × 2 × 2 Hex20), clamped at x = 0, tip load `p` (N) along z.
fn cantilever(p: f64) -> (Mesh, StructuralProblem) {
    let mesh = structured_box(&BoxParams::new(
        ElementKind::Hex20,
        [6, 2, 2],
        [30e-3, 5e-3, 4e-3],
    ))
    .unwrap();
    let steel = materials::steel().stiffness().unwrap();
    let mut problem = structural_problem(
        &mesh,
        steel,
        IntegrationRule::Gauss2,
        &[("x0", 0), ("x0", 1), ("x0", 2)],
    );
    let tip = &mesh.node_sets["x1"];
    for &n in tip {
        problem.add_load(3 * n + 2, p / tip.len() as f64).unwrap();
    }
    (mesh, problem)
}

#[test]
fn assembly_is_bitwise_identical_on_1_and_2_threads() {
    let (_, problem) = cantilever(-1000.0);
    let u: Vec<f64> = (0..problem.assembler().n())
        .map(|i| 1e-5 * ((i * 37 % 101) as f64 / 101.0 - 0.5))
        .collect();
    let mut results = Vec::new();
    for threads in [1, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let mut k = problem.assembler().new_tangent();
        let a = pool
            .install(|| problem.assembler().assemble(&u, Some(&mut k)))
            .unwrap();
        results.push((a, k));
    }
    assert!(
        results[0].0 == results[1].0,
        "internal forces differ between 1 and 2 threads"
    );
    assert!(
        results[0].1 == results[1].1,
        "tangents differ between 1 and 2 threads"
    );
}

#[test]
fn full_newton_converges_quadratically() {
    let (_, mut problem) = cantilever(-3000.0);
    let mut u = vec![0.0; problem.assembler().n()];
    // One step to the full load from rest: several iterations, the last ones quadratic.
    let settings = NewtonSettings {
        force_tolerance: 1e-9,
        relative_tolerance: 0.0,
        line_search: false,
        ..NewtonSettings::default()
    };
    let path = follow_path(
        &mut problem,
        &mut u,
        &[1.0],
        &settings,
        &Stepping {
            initial: 1.0,
            ..Stepping::default()
        },
    )
    .unwrap();
    let a = &path.attempts[0];
    assert!(a.converged());
    let r: Vec<f64> = std::iter::once(a.initial_residual)
        .chain(a.iterations.iter().map(|i| i.residual))
        .collect();
    eprintln!("residual history: {r:?}");
    // Order estimate p = log(r_{k+1}/r_k) / log(r_k/r_{k−1}) over the last three residuals above
    // the round-off floor (100 × the final residual, where the iteration stagnates at ~1e-9 N):
    // 2 for Newton; accept ≥ 1.7.
    let floor = 100.0 * r.last().copied().unwrap_or(0.0);
    let useful: Vec<f64> = r.iter().copied().filter(|&x| x > floor).collect();
    assert!(useful.len() >= 3, "{r:?}");
    let n = useful.len();
    let p = (useful[n - 1] / useful[n - 2]).ln() / (useful[n - 2] / useful[n - 3]).ln();
    eprintln!("convergence order {p:.2}");
    assert!(p > 1.7, "convergence order {p} from {useful:?}");
}

#[test]
fn modified_newton_converges_to_the_same_state() {
    let (_, mut full) = cantilever(-2000.0);
    let (_, mut modified) = cantilever(-2000.0);
    let (mut u1, mut u2) = (
        vec![0.0; full.assembler().n()],
        vec![0.0; modified.assembler().n()],
    );
    let tight = NewtonSettings {
        force_tolerance: 1e-7,
        relative_tolerance: 0.0,
        ..NewtonSettings::default()
    };
    follow_path(&mut full, &mut u1, &[1.0], &tight, &Stepping::default()).unwrap();
    let m = NewtonSettings {
        refactor_every: 4,
        max_iterations: 60,
        ..tight
    };
    let path = follow_path(&mut modified, &mut u2, &[1.0], &m, &Stepping::default()).unwrap();
    let scale = u1.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    let diff = u1
        .iter()
        .zip(&u2)
        .fold(0.0f64, |a, (p, q)| a.max((p - q).abs()));
    // Both converged to 1e-7 N on a stiffness of ~1e8 N/m: displacements agree to ~1e-15 m
    // absolute; assert 1e-9 relative.
    assert!(diff < 1e-9 * scale, "{diff:e} vs {scale:e}");
    // Modified Newton reuses factorisations: some iterations have no pivot record.
    assert!(
        path.attempts
            .iter()
            .flat_map(|a| &a.iterations)
            .any(|i| i.negative_pivots.is_none())
    );
}

/// Modified Newton with the tangent kept across increments (thesis §2.1: "for several
/// increments") and BFGS updates of it reach the full Newton state with fewer factorisations
/// than increments; a BFGS direction with pairs is used at least once.
#[test]
fn kept_tangent_and_bfgs_reach_the_full_newton_state_with_fewer_factorisations() {
    let tight = NewtonSettings {
        force_tolerance: 1e-7,
        relative_tolerance: 0.0,
        ..NewtonSettings::default()
    };
    let stepping = Stepping {
        initial: 0.125,
        max: 0.125,
        ..Stepping::default()
    };
    let (_, mut full) = cantilever(-500.0);
    let mut u_full = vec![0.0; full.assembler().n()];
    follow_path(&mut full, &mut u_full, &[1.0], &tight, &stepping).unwrap();
    let scale = u_full.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    let kept = NewtonSettings {
        keep_tangent: true,
        refactor_every: usize::MAX,
        refactor_ratio: 0.9,
        max_iterations: 100,
        ..tight.clone()
    };
    let bfgs = NewtonSettings {
        quasi_newton: 20,
        line_search: false,
        refactor_ratio: 2.0,
        ..kept.clone()
    };
    for (label, settings) in [("kept tangent", kept), ("BFGS", bfgs)] {
        let (_, mut problem) = cantilever(-500.0);
        let mut u = vec![0.0; problem.assembler().n()];
        let path = follow_path(&mut problem, &mut u, &[1.0], &settings, &stepping).unwrap();
        let iterations: Vec<_> = path.attempts.iter().flat_map(|a| &a.iterations).collect();
        let factorisations = iterations
            .iter()
            .filter(|i| i.negative_pivots.is_some())
            .count();
        let increments = path.attempts.iter().filter(|a| a.converged()).count();
        for a in &path.attempts {
            let h: Vec<String> = a
                .iterations
                .iter()
                .map(|i| {
                    let f = if i.negative_pivots.is_some() { "F" } else { "" };
                    format!("{:.1e}{f}", i.residual)
                })
                .collect();
            eprintln!(
                "  λ {:.3}: {:.1e} → {}",
                a.lambda,
                a.initial_residual,
                h.join(" ")
            );
        }
        eprintln!(
            "{label}: {increments} increments, {} iterations, {factorisations} factorisations",
            iterations.len()
        );
        assert_eq!(increments, 8, "{label}");
        // Every increment after the first starts on the tangent kept from the one before.
        assert!(
            path.attempts[1..].iter().all(|a| a
                .iterations
                .first()
                .is_some_and(|i| i.negative_pivots.is_none())),
            "{label}"
        );
        if settings.quasi_newton > 0 {
            // Plain modified Newton stalls at a ratio ≈ 0.9 here and refactors once per
            // increment; the BFGS pairs make the kept tangent last.
            assert!(factorisations < increments / 2, "{label}: {factorisations}");
            assert!(iterations.iter().any(|i| i.bfgs_pairs > 0), "{label}");
        }
        // Both at 1e-7 N on a stiffness of ~1e8 N/m: ~1e-15 m apart; assert 1e-9 relative.
        let diff = u
            .iter()
            .zip(&u_full)
            .fold(0.0f64, |a, (p, q)| a.max((p - q).abs()));
        assert!(diff < 1e-9 * scale, "{label}: {diff:e} vs {scale:e}");
    }
    // A non-positive refactor ratio is refused.
    let (_, mut problem) = cantilever(-500.0);
    let mut u = vec![0.0; problem.assembler().n()];
    let bad = NewtonSettings {
        refactor_ratio: 0.0,
        ..NewtonSettings::default()
    };
    assert!(matches!(
        follow_path(&mut problem, &mut u, &[1.0], &bad, &stepping),
        Err(NewtonError::Setting { .. })
    ));
}

/// A `PathSolver` kept over two levels (as a scene sweep does): the stability test at the end
/// of the first level leaves its factorisation, and with a kept tangent the second level's
/// first iteration solves with it instead of factoring (a fresh solver per level factors
/// there); the state is the full-Newton one. A session is remade for another solver kind.
#[test]
fn a_session_carries_the_stability_factorisation_into_the_next_level() {
    let tight = NewtonSettings {
        force_tolerance: 1e-7,
        relative_tolerance: 0.0,
        ..NewtonSettings::default()
    };
    let stepping = Stepping {
        initial: 0.25,
        max: 0.25,
        ..Stepping::default()
    };
    let (_, mut full) = cantilever(-500.0);
    let mut u_full = vec![0.0; full.assembler().n()];
    follow_path(&mut full, &mut u_full, &[1.0], &tight, &stepping).unwrap();
    let scale = u_full.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    let bfgs = NewtonSettings {
        keep_tangent: true,
        refactor_every: usize::MAX,
        quasi_newton: 20,
        line_search: false,
        refactor_ratio: 2.0,
        max_iterations: 100,
        ..tight.clone()
    };
    // First iteration of the second level: factored there or not, for both ways.
    let mut first_factors = Vec::new();
    for carried in [true, false] {
        let (_, mut problem) = cantilever(-500.0);
        let mut u = vec![0.0; problem.assembler().n()];
        let mut session = PathSolver::new(&problem, bfgs.solver).unwrap();
        follow_path_with(
            &mut problem,
            &mut u,
            0.0,
            &[0.5],
            &bfgs,
            &stepping,
            &mut session,
        )
        .unwrap();
        assert_eq!(session.inertia_at(&mut problem, &u, 0.5).unwrap(), 0);
        assert!(session.is_factored());
        let second = if carried {
            follow_path_with(
                &mut problem,
                &mut u,
                0.5,
                &[1.0],
                &bfgs,
                &stepping,
                &mut session,
            )
        } else {
            follow_path_from(&mut problem, &mut u, 0.5, &[1.0], &bfgs, &stepping)
        }
        .unwrap();
        let first = &second.attempts[0].iterations[0];
        first_factors.push(first.negative_pivots.is_some());
        // Both at 1e-7 N on a stiffness of ~1e8 N/m: assert 1e-9 of the largest deflection.
        let diff = u
            .iter()
            .zip(&u_full)
            .fold(0.0f64, |a, (p, q)| a.max((p - q).abs()));
        assert!(
            diff < 1e-9 * scale,
            "carried {carried}: {diff:e} vs {scale:e}"
        );
    }
    assert_eq!(first_factors, [false, true]);
    // Another solver kind: the session is made anew (and still converges).
    let (_, mut problem) = cantilever(-500.0);
    let mut u = vec![0.0; problem.assembler().n()];
    let mut session = PathSolver::new(&problem, SolverKind::Profile).unwrap();
    let faer = NewtonSettings {
        solver: SolverKind::FaerLdlt,
        ..tight
    };
    follow_path_with(
        &mut problem,
        &mut u,
        0.0,
        &[1.0],
        &faer,
        &stepping,
        &mut session,
    )
    .unwrap();
    assert_eq!(session.kind(), SolverKind::FaerLdlt);
}

#[test]
fn a_huge_single_step_converges_by_cutback_or_fails_located_never_nan() {
    // 60 kN on the tip: the linear deflection is three times the span.
    let (_, mut problem) = cantilever(-60_000.0);
    let mut u = vec![0.0; problem.assembler().n()];
    let stepping = Stepping {
        initial: 1.0,
        min: 1e-3,
        ..Stepping::default()
    };
    match follow_path(
        &mut problem,
        &mut u,
        &[1.0],
        &NewtonSettings::default(),
        &stepping,
    ) {
        Ok(path) => {
            assert!(u.iter().all(|x| x.is_finite()));
            let cutbacks = path.attempts.iter().filter(|a| !a.converged()).count();
            eprintln!(
                "converged after {cutbacks} cutbacks in {} attempts",
                path.attempts.len()
            );
        }
        Err(NewtonError::Cutback {
            reached, target, ..
        }) => {
            assert!(reached < target && reached.is_finite());
        }
        Err(e) => panic!("unexpected error {e}"),
    }
    assert!(u.iter().all(|x| x.is_finite()));
}

#[test]
fn displacement_criterion_adds_iterations_never_removes_them() {
    let (_, mut a) = cantilever(-2000.0);
    let (_, mut b) = cantilever(-2000.0);
    let (mut ua, mut ub) = (vec![0.0; a.assembler().n()], vec![0.0; b.assembler().n()]);
    let residual_only = NewtonSettings {
        force_tolerance: 1e-2,
        ..NewtonSettings::default()
    };
    let both = NewtonSettings {
        displacement_tolerance: 1e-12,
        ..residual_only.clone()
    };
    let pa = follow_path(
        &mut a,
        &mut ua,
        &[1.0],
        &residual_only,
        &Stepping {
            initial: 1.0,
            ..Stepping::default()
        },
    )
    .unwrap();
    let pb = follow_path(
        &mut b,
        &mut ub,
        &[1.0],
        &both,
        &Stepping {
            initial: 1.0,
            ..Stepping::default()
        },
    )
    .unwrap();
    let (na, nb) = (
        pa.attempts[0].iterations.len(),
        pb.attempts[0].iterations.len(),
    );
    assert!(nb > na, "{nb} vs {na} iterations");
    let last = pb.attempts[0].iterations.last().unwrap();
    let umax = ub.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    assert!(last.increment <= 1e-12 * umax);
}

/// `Stepping::max_attempts` bounds the attempts towards one target: a cantilever path that
/// needs 4 increments of Δλ = 0.25 is stopped after 2 with `NewtonError::Attempts` naming the
/// λ reached (0.5), and goes through with a limit of 4 (each converged increment is one
/// attempt here: the load is small enough that none is cut back).
#[test]
fn the_attempt_limit_stops_a_path_and_names_where() {
    use nonlin3d::newton::NewtonError;
    let stepping = |max_attempts| Stepping {
        initial: 0.25,
        max: 0.25,
        max_attempts,
        ..Stepping::default()
    };
    let (_, mut problem) = cantilever(-300.0);
    let mut u = vec![0.0; problem.assembler().n()];
    let settings = NewtonSettings::default();
    match follow_path(&mut problem, &mut u, &[1.0], &settings, &stepping(2)) {
        Err(e @ NewtonError::Attempts { .. }) => {
            let NewtonError::Attempts {
                reached, attempts, ..
            } = e
            else {
                unreachable!()
            };
            assert_eq!((reached, attempts), (0.5, 2));
            assert!(e.to_string().contains("after 2 increment attempts"), "{e}");
        }
        other => panic!("expected the attempt limit, got {other:?}"),
    }
    let (_, mut problem) = cantilever(-300.0);
    let mut u = vec![0.0; problem.assembler().n()];
    let path = follow_path(&mut problem, &mut u, &[1.0], &settings, &stepping(4)).unwrap();
    assert_eq!(path.attempts.len(), 4);
}
