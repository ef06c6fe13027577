//! Mixed precision (f32 factor, f64 refinement) on laminate stiffness matrices: quasi-isotropic
//! graphite/epoxy Hex20 cantilevers of 16 × 3 × 4 cells, 0.125 mm thick (one ply per cell
//! layer), clamped at x = 0, with cells 4:1 or 16:1 in plan (the bench's laminate). Thinner
//! cells make the stiffness more ill-conditioned: refinement contracts the error by about
//! cond(A)·ε₃₂ per step, so it converges on the 4:1 model and stalls on the 16:1 one, where
//! conjugate gradients preconditioned by the same f32 factor take over; only a target below
//! what f64 arithmetic can reach makes the solver fall back to its f64 factor.

mod common;

use nonlin3d::solver::{
    FaerMode, FaerOrdering, FaerPrecision, FaerSolver, LinearSolver, SymmetricMatrix,
};

fn laminate(aspect: f64) -> SymmetricMatrix {
    let h = 0.125e-3;
    common::clamped_box_stiffness([16, 3, 4], [aspect * h, aspect * h, h])
}

/// (x, backward error ‖b − A x‖∞ / (‖A‖∞‖x‖∞ + ‖b‖∞), solver) for a unit transverse load on
/// every DOF 2 mod 3.
fn solve(a: &SymmetricMatrix, precision: FaerPrecision) -> (Vec<f64>, f64, FaerSolver) {
    // Our nested dissection, the order these expectations were measured with: with METIS's
    // (which `Auto` now picks here) the 16:1 laminate's f32 factor meets a negative pivot
    // once the pivot floor is off (`a_thin_laminate_falls_back_to_f64`), before refinement.
    let mut s = FaerSolver::new(FaerMode::Ldlt).with_ordering(FaerOrdering::NestedDissection);
    s.precision = precision;
    s.analyze(a.pattern()).unwrap();
    assert_eq!(s.factorize(a).unwrap().negative_pivots, 0);
    let b: Vec<f64> = (0..a.n())
        .map(|i| f64::from(u8::from(i % 3 == 2)))
        .collect();
    let mut x = b.clone();
    s.solve_in_place(&mut x, 1).unwrap();
    let mut ax = vec![0.0; a.n()];
    a.matvec(&x, &mut ax).unwrap();
    let inf = |v: &[f64]| v.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let r: Vec<f64> = ax.iter().zip(&b).map(|(p, q)| q - p).collect();
    let mut rows = vec![0.0; a.n()];
    for (j, (&lo, &hi)) in a
        .pattern()
        .col_ptr()
        .iter()
        .zip(&a.pattern().col_ptr()[1..])
        .enumerate()
    {
        for k in lo..hi {
            let (i, v) = (a.pattern().row_idx()[k], a.values()[k].abs());
            rows[i] += v;
            if i != j {
                rows[j] += v;
            }
        }
    }
    (x.clone(), inf(&r) / (inf(&rows) * inf(&x) + inf(&b)), s)
}

/// Mixed precision refined to `tolerance`, the pivot floor off (to exercise refinement alone).
fn mixed(tolerance: f64) -> FaerPrecision {
    FaerPrecision::Mixed {
        tolerance,
        pivot_floor: 0.0,
    }
}

/// max |x − x64| / max |x64|.
fn relative_difference(x: &[f64], x64: &[f64]) -> f64 {
    let scale = x64.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let diff = x
        .iter()
        .zip(x64)
        .fold(0.0f64, |m, (p, q)| m.max((p - q).abs()));
    eprintln!("relative difference {:.1e}", diff / scale);
    diff / scale
}

/// 4:1 cells: the f32 factor is kept (pivot floor off, to exercise refinement alone) and
/// refinement reaches the 1e-14 backward error target. Both solutions then have backward error
/// ≤ 1e-14, so they differ by at most 2·cond(A)·1e-14 relative; refinement converging at all
/// means cond(A)·ε₃₂ < 1, cond(A) < 1.7e7, so 1e-6 is a safe bound.
#[test]
fn refinement_reaches_the_f64_solution_on_a_laminate() {
    let a = laminate(4.0);
    let (x64, omega64, _) = solve(&a, FaerPrecision::Double);
    let (x, omega, s) = solve(&a, mixed(1e-14));
    let m = s.mixed_stats();
    eprintln!("f64 backward error {omega64:.1e}, mixed {omega:.1e}, {m:?}");
    assert_eq!((m.single_factorizations, m.double_factorizations), (1, 0));
    assert!(omega <= 1e-14, "{omega}");
    assert!(relative_difference(&x, &x64) <= 1e-6);
}

/// 16:1 cells: refinement stalls (each step multiplies the error by about cond(A)·ε₃₂ ≳ 0.5),
/// and conjugate gradients preconditioned by the f32 factor (all its pivots positive) reach
/// the 1e-14 target instead, with no f64 factorisation. Both solutions have backward error
/// ≤ 1e-14, so they differ by at most 2·cond(A)·1e-14 relative; cond(A) grows with the
/// square of the cells' aspect (bending against through-thickness stiffness), 16 times the
/// 4:1 model's < 1.7e7 (above): < 2.7e8, so 1e-5 is a safe bound.
#[test]
fn conjugate_gradients_take_over_where_refinement_stalls_on_a_thin_laminate() {
    let a = laminate(16.0);
    let (x64, _, _) = solve(&a, FaerPrecision::Double);
    let (x, omega, s) = solve(&a, mixed(1e-14));
    let m = s.mixed_stats();
    eprintln!("{m:?}");
    assert_eq!((m.single_factorizations, m.double_factorizations), (1, 0));
    assert!(m.conjugate_gradient_steps >= 1, "{m:?}");
    assert!(m.refinement_steps > m.conjugate_gradient_steps, "{m:?}");
    assert!(omega <= 1e-14, "{omega}");
    assert!(relative_difference(&x, &x64) <= 1e-5);
}

/// The same laminate with a target below f64's rounding (1e-30): refinement and then
/// conjugate gradients stall, and the solver falls back to an f64 factor and returns its
/// solution, bit for bit.
#[test]
fn a_thin_laminate_falls_back_to_f64_when_both_stall() {
    let a = laminate(16.0);
    let (x64, _, _) = solve(&a, FaerPrecision::Double);
    let (x, _, s) = solve(&a, mixed(1e-30));
    let m = s.mixed_stats();
    eprintln!("{m:?}");
    assert_eq!(
        m.last_fallback,
        Some("refinement and conjugate gradients stalled")
    );
    assert_eq!((m.single_factorizations, m.double_factorizations), (1, 1));
    assert_eq!(
        m.conjugate_gradient_steps,
        nonlin3d::solver::MAX_CONJUGATE_GRADIENT_STEPS
    );
    assert!(x.iter().zip(&x64).all(|(p, q)| p.to_bits() == q.to_bits()));
}

/// `solve --solver faer-mixed` on the NLGEOM cantilever deck: the same converged displacements as
/// the f64 default, and the solver named in summary.json. Both runs meet the same residual test
/// (‖r‖∞ ≤ 1e-8 of the largest force) at every increment and the f32 factor only changes the
/// path to that residual, so the states differ by far less than 1e-8 of the largest
/// displacement (measured: 3.5e-18 m absolute).
#[test]
fn the_solve_command_takes_the_mixed_solver() {
    let deck = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/decks/cantilever_nlgeom.inp"
    );
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("solve_mixed");
    let _ = std::fs::remove_dir_all(&dir);
    let run = |solver: &str| {
        let out = dir.join(solver);
        let o = std::process::Command::new(env!("CARGO_BIN_EXE_nonlin3d"))
            .args(["solve", deck, "-q", "--solver", solver, "--out"])
            .arg(&out)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let text = std::fs::read_to_string(out.join("displacements.csv")).unwrap();
        let values: Vec<f64> = text
            .lines()
            .skip(1)
            .flat_map(|l| l.split(',').skip(1).map(|x| x.parse::<f64>().unwrap()))
            .collect();
        let summary = std::fs::read_to_string(out.join("summary.json")).unwrap();
        (values, summary)
    };
    let (f64_u, _) = run("faer");
    let (mixed_u, summary) = run("faer-mixed");
    assert_eq!(f64_u.len(), mixed_u.len());
    let largest = f64_u.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    assert!(largest > 0.0);
    for (a, b) in f64_u.iter().zip(&mixed_u) {
        assert!((a - b).abs() <= 1e-8 * largest, "{a} vs {b}");
    }
    assert!(summary.contains("f32 factor refined in f64"), "{summary}");
}
