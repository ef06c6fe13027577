//! Newton path following on finite element models (issue: assembly and Newton): determinism,
//! convergence rate, robustness to large steps, modified Newton, and bifurcation detection.

mod common;

use common::structural_problem;
use nonlin3d::element::{ElementKind, IntegrationRule};
use nonlin3d::laminate::materials;
use nonlin3d::mesh::{
    BoxParams, Mesh, ThroughWidthParams, structured_box, through_width_delamination,
};
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

/// The through-width model of `p` (optionally with a strip imperfection of `imperfection` m),
/// steel, u = 0 on x = 0, v = 0 on y = 0 and y = W, w = 0 on z = 0, u = −ε_max·L on x = L at
/// λ = 1.
fn compressed_through_width(
    p: &ThroughWidthParams,
    eps_max: f64,
    imperfection: f64,
) -> (Mesh, StructuralProblem) {
    let (mut mesh, _) = through_width_delamination(p).unwrap();
    if imperfection != 0.0 {
        mesh.apply_imperfection(
            p.base,
            "crack_lower",
            nonlin3d::mesh::Imperfection::Strip { a: p.a },
            imperfection,
        )
        .unwrap();
    }
    let steel = materials::steel().stiffness().unwrap();
    let mut problem = structural_problem(
        &mesh,
        steel,
        IntegrationRule::Gauss2,
        &[("x0", 0), ("y0", 1), ("y1", 1), ("z0", 2)],
    );
    for &n in &mesh.node_sets["x1"] {
        problem.prescribe_value(3 * n, -eps_max * p.length).unwrap();
    }
    (mesh, problem)
}

/// Thesis §3.2 through-width model under compression, perfect geometry: the trivial path's
/// tangent loses positive definiteness (one negative pivot appears) at the sublaminate's
/// buckling strain, which for a clamped column of length ℓ = 2a and thickness h in plane strain
/// is ε_c = π²h²/(3ℓ²). The base's compliance makes the ends less than clamped, so the detected
/// strain lies somewhat below; the issue asks for 10 %.
#[test]
fn through_width_bifurcation_from_inertia_matches_the_clamped_column() {
    let p = ThroughWidthParams {
        outside: 8,
        ..ThroughWidthParams::example()
    };
    let ell = 2.0 * p.a;
    let eps_c = std::f64::consts::PI.powi(2) * p.h * p.h / (3.0 * ell * ell);
    let eps_max = 1.5 * eps_c;
    let (_, mut problem) = compressed_through_width(&p, eps_max, 0.0);
    let mut u = vec![0.0; problem.assembler().n()];
    let levels: Vec<f64> = (1..=30).map(|k| k as f64 / 30.0).collect();
    let stepping = Stepping {
        initial: 1.0 / 30.0,
        max: 1.0 / 30.0,
        ..Stepping::default()
    };
    let path = follow_path(
        &mut problem,
        &mut u,
        &levels,
        &NewtonSettings::default(),
        &stepping,
    )
    .unwrap();
    let changes = path.inertia_changes();
    eprintln!("inertia changes (λ before, λ after, pivots): {changes:?}; ε_c = {eps_c:e}");
    let &(l0, l1, p0, p1) = changes.first().expect("a bifurcation below 1.5 ε_c");
    assert_eq!((p0, p1), (0, 1));
    let detected = 0.5 * (l0 + l1) * eps_max;
    let ratio = detected / eps_c;
    eprintln!("detected ε_b = {detected:e} = {ratio:.3} ε_c");
    assert!(
        (0.9..1.1).contains(&ratio),
        "bifurcation strain {detected:e} vs clamped column {eps_c:e}"
    );
}

/// §3.2: into the postbuckled branch by the perturbation protocol (transverse load converged
/// with the first compression level above buckling, then removed at once) and by a small
/// initial imperfection (strip shape, 5 % of h). Both must land on the same buckled branch, its
/// amplitude growing with strain like the clamped column's A = (2ℓ/π)·√(ε − ε_b), ε_b the
/// bifurcation strain found above (inextensional postbuckling; the base compliance shifts ε_b).
#[test]
fn postbuckled_branch_by_perturbation_and_by_imperfection() {
    use nonlin3d::newton::perturbed_path;
    let p = ThroughWidthParams {
        outside: 8,
        ..ThroughWidthParams::example()
    };
    let ell = 2.0 * p.a;
    let eps_c = std::f64::consts::PI.powi(2) * p.h * p.h / (3.0 * ell * ell);
    let eps_max = 1.6 * eps_c;
    let levels = [1.1, 1.2, 1.3, 1.45, 1.6].map(|f| f * eps_c / eps_max);
    let setup = |imperfection: f64| {
        let (mesh, problem) = compressed_through_width(&p, eps_max, imperfection);
        // The sublaminate's top nodes on the symmetry plane x = 0 (where the deflection peaks).
        let top: Vec<usize> = (0..mesh.nodes.len())
            .filter(|&n| {
                mesh.nodes[n][0] == 0.0
                    && (mesh.nodes[n][2] - (p.base + p.h + imperfection.max(0.0))).abs() < 1e-9
            })
            .collect();
        assert!(!top.is_empty());
        (problem, top)
    };
    let stepping = Stepping {
        initial: 0.1,
        max: 0.2,
        ..Stepping::default()
    };
    let settings = NewtonSettings::default();
    // Perturbation: 1 N across the 1 mm strip (0.5 N on this half model) lifts the perfect
    // sublaminate by ~0.1 h at the first level.
    let (mut problem, top) = setup(0.0);
    let per_node = 0.5 / top.len() as f64;
    let perturbation: Vec<(usize, f64)> = top.iter().map(|&n| (3 * n + 2, per_node)).collect();
    let mut u = vec![0.0; problem.assembler().n()];
    let path = perturbed_path(
        &mut problem,
        &mut u,
        &perturbation,
        &levels,
        &settings,
        &stepping,
    )
    .unwrap();
    let deflection = |state: &[f64], top: &[usize]| {
        top.iter().map(|&n| state[3 * n + 2]).sum::<f64>() / top.len() as f64
    };
    let w_pert: Vec<f64> = path
        .states
        .iter()
        .map(|(_, s)| deflection(s, &top))
        .collect();
    // Imperfection: 5 % of h, small steps through the bifurcation (without contact the faces
    // may interpenetrate, so a coarse step can jump to the mirror branch below).
    let amplitude = 0.05 * p.h;
    let (mut imperfect, top_i) = setup(amplitude);
    let mut ui = vec![0.0; imperfect.assembler().n()];
    let fine = Stepping {
        initial: 0.02,
        max: 0.05,
        ..Stepping::default()
    };
    let path_i = follow_path(&mut imperfect, &mut ui, &levels, &settings, &fine).unwrap();
    let w_imp: Vec<f64> = path_i
        .states
        .iter()
        .map(|(_, s)| deflection(s, &top_i) + amplitude)
        .collect();
    let eps_b = 0.975 * eps_c; // the bifurcation strain measured above
    eprintln!(
        "| ε/ε_c | w/h perturbation | w/h imperfection 5 % | w/h clamped column (2ℓ/π)√(ε − ε_b) |"
    );
    let factors = [1.1, 1.2, 1.3, 1.45, 1.6];
    let theory: Vec<f64> = factors
        .iter()
        .map(|&f| 2.0 * ell / std::f64::consts::PI * (f * eps_c - eps_b).sqrt())
        .collect();
    for (k, &f) in factors.iter().enumerate() {
        eprintln!(
            "| {f} | {:.3} | {:.3} | {:.3} |",
            w_pert[k] / p.h,
            w_imp[k] / p.h,
            theory[k] / p.h
        );
    }
    for k in 0..factors.len() {
        // The perturbed solution stays buckled after the load is removed and grows with strain,
        assert!(w_pert[k] > 0.2 * p.h);
        if k > 0 {
            assert!(w_pert[k] > w_pert[k - 1]);
        }
        // follows the clamped column's inextensional amplitude within 20 % (the sublaminate is
        // not inextensible and its ends rotate with the base),
        assert!(
            (w_pert[k] / theory[k] - 1.0).abs() < 0.2,
            "{} vs {}",
            w_pert[k],
            theory[k]
        );
        // and the imperfect path converges onto the same branch as the strain grows: the
        // imperfection's share falls from ~30 % near ε_b to below 15 % from 1.3 ε_c on.
        assert!(w_imp[k] > w_pert[k]);
        if factors[k] >= 1.3 {
            assert!(
                w_imp[k] / w_pert[k] - 1.0 < 0.15,
                "imperfect {} vs perturbed {}",
                w_imp[k],
                w_pert[k]
            );
        }
    }
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
