//! How `solve` factorises (`nonlin3d::deck::Strategy`) and CalculiX's I_0 / I_R controls, on the
//! smallest clamped-plate deck of issue 20 (`tests/decks/plate_n4.inp`, written by
//! `cargo bench --bench plate_decks -- n=4 layers=2 write=tests/decks/plate_n4.inp`: 1 335
//! DOF, 10 NLGEOM increments of `*STATIC, DIRECT` to w₀/h ≈ 3).

use nonlin3d::deck::{StepOptions, StepResult, Strategy, solve_deck};
use nonlin3d::mesh::read_inp;

fn plate(edit: &dyn Fn(String) -> String) -> nonlin3d::mesh::InpModel {
    read_inp(&edit(
        std::fs::read_to_string("tests/decks/plate_n4.inp").unwrap(),
    ))
    .unwrap()
}

fn solve(model: &nonlin3d::mesh::InpModel, strategy: Strategy) -> StepResult {
    let options = StepOptions {
        strategy,
        ..Default::default()
    };
    solve_deck(model, &options).unwrap().remove(0)
}

fn total(r: &StepResult, f: &dyn Fn(&nonlin3d::deck::IncrementSummary) -> usize) -> usize {
    r.increments.iter().map(f).sum()
}

#[test]
fn the_default_factorises_less_for_the_same_answer_and_inertia() {
    let model = plate(&|s| s);
    let full = solve(&model, Strategy::Full);
    let auto = solve(&model, Strategy::default());
    // Both land on the deck's ten increments, every attempt converged (no full-Newton redo).
    for r in [&full, &auto] {
        assert_eq!(r.increments.len(), 10);
        assert!(r.increments.iter().all(|i| i.converged));
    }
    // Full Newton factorises once an iteration (35); BFGS once an increment for its inertia,
    // plus the first tangent and one refactorisation where the membrane stiffening starts
    // (12): a new tangent only when an iteration more than doubles ‖r‖∞
    // (`BFGS_REFACTOR_RATIO`). Refactorising whenever ‖r‖∞ fell by less than half made 16.
    let (f_full, f_auto) = (
        total(&full, &|i| i.factorisations),
        total(&auto, &|i| i.factorisations),
    );
    assert_eq!(f_full, total(&full, &|i| i.iterations));
    assert!(2 * f_auto <= f_full, "{f_auto} against {f_full}");
    assert!(
        f_auto <= auto.increments.len() + 2,
        "{f_auto} factorisations"
    );
    // The same negative-pivot information at every converged increment (a stable plate: 0).
    for (a, b) in full.increments.iter().zip(&auto.increments) {
        assert_eq!(a.negative_pivots, Some(0));
        assert_eq!(b.negative_pivots, a.negative_pivots);
    }
    // Same answer: both stop at ‖r‖∞ ≤ 1e-8 of the largest force (the clamp's ≈ 2.8 kN
    // membrane reaction, so ≤ 3e-5 N); with the plate's tangent compliance below
    // w₀/P ≈ 3e-3 mm/N that moves u by < 1e-7 mm, 1e-7 of w₀ = 1.3 mm: 1e-6 of max |u|.
    let scale = full
        .displacements
        .iter()
        .flatten()
        .fold(0.0f64, |a, v| a.max(v.abs()));
    let diff = full
        .displacements
        .iter()
        .flatten()
        .zip(auto.displacements.iter().flatten())
        .fold(0.0f64, |a, (x, y)| a.max((x - y).abs()));
    assert!(diff <= 1e-6 * scale, "{diff} against {scale}");
}

#[test]
fn i_r_stops_a_slow_attempt_and_the_increment_is_cut_back() {
    // Automatic increments (no DIRECT): full Newton from rest needs 6 iterations for 0.1.
    let automatic = |s: String| s.replace("*STATIC, DIRECT", "*STATIC");
    let plain = solve(&plate(&automatic), Strategy::default());
    assert!(plain.increments[0].converged, "{:?}", plain.increments[0]);
    // Its residuals: 41, 4004, 74, 122, 3.7, 0.022, 2.5e-7 N. I_R = 2, I_C = 5: after two
    // iterations the last ratio, 74/4004, kept down to 1e-8 of the force (≈ 3e-5 N) needs
    // 2 + ln(3e-5/74)/ln(74/4004) ≈ 6 iterations, more than 5: cut back by D_C = 0.5.
    let controlled = plate(&|s| {
        automatic(s).replace(
            "*STATIC\n",
            "*CONTROLS, PARAMETERS=TIME INCREMENTATION\n, 2, , 5\n*STATIC\n",
        )
    });
    let r = solve(&controlled, Strategy::default());
    let first = &r.increments[0];
    assert!(
        !first.converged && first.termination.contains("too slow"),
        "{first:?}"
    );
    assert_eq!(first.iterations, 2);
    assert!(
        (r.increments[1].step_time - 0.05).abs() < 1e-12,
        "{:?}",
        r.increments[1]
    );
    assert!(r.complete);
}
