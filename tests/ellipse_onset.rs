//! Onset of local buckling of elliptic sublaminates for a > b, a = b and a < b against the
//! clamped elliptic plate (issue: no silent wrong answers, part 1; docs/VALIDATION.md).
//!
//! An isotropic sublaminate of the base's material over an embedded delamination
//! x²/a² + y²/b² < 1, the laminate compressed by ε_x with free lateral contraction, is under
//! uniaxial stress (σ_y = 0) before it buckles; as a plate clamped along the ellipse it buckles
//! at ε_cr = k_b/(12(1 − ν²))·(h/b)², k_b = N_cr b²/D (b across the load). The quarter model's
//! symmetry planes admit only modes even in x and y, so k_b is that of the lowest such mode:
//! from a Rayleigh–Ritz solution, w = (1 − x²/a² − y²/b²)²·Σ c_mn x^m y^n to 20th order, converged
//! to eight digits and checked by Morley plate elements to 2e-4 (docs/VALIDATION.md, "Ellipses
//! with a > b"). ν does not enter k_b for a clamped edge.
//!
//! The FE onset is the strain where the trivial (unbuckled) path's tangent first has a negative
//! pivot (Sylvester's law of inertia), bracketed by bisection to 0.2 %.

use nonlin3d::Scene;
use nonlin3d::analysis::{build_model, build_problem, load_factors, settings};
use nonlin3d::newton::{Stepping, follow_path, negative_pivots_at};

/// (a/b, k_b) of the lowest mode even in x and y under uniaxial stress along a: Rayleigh–Ritz,
/// M = 16 and 20 agree to the digits given (tests/reference/ellipse_ritz.py). Not the overall
/// lowest mode for a/b ≥ 2: the mode odd in x is 0.2 % lower at a/b = 2 (22.3935), which the
/// quarter model's symmetry plane x = 0 excludes.
const K_B: [(f64, f64); 5] = [
    (1.0 / 3.0, 106.425539),
    (0.5, 54.135962),
    (1.0, 27.221587),
    (2.0, 22.440479),
    (3.0, 20.380396),
];

fn k_b(a_over_b: f64) -> f64 {
    K_B.iter()
        .find(|(r, _)| (r - a_over_b).abs() < 1e-9)
        .map_or(f64::NAN, |&(_, k)| k)
}

const H_MM: f64 = 0.2;
const NU: f64 = 0.3;

/// The scene: aluminium-like isotropic laminate, h = 0.2 mm over H = 2 mm, W = 2.5 max(a, b).
fn scene(a_mm: f64, b_mm: f64, slices: usize) -> Scene {
    let w = 2.5 * a_mm.max(b_mm);
    Scene::from_toml(&format!(
        r#"
title = "elliptic onset {a_mm} x {b_mm}"
[geometry]
kind = "embedded"
a_mm = {a_mm}
b_mm = {b_mm}
h_mm = {H_MM}
base_mm = 2.0
w_mm = {w}
[material]
kind = "isotropic"
e_gpa = 70.0
nu = {NU}
[mesh]
slices = {slices}
[loads]
strains = [-0.002]
perturbation_n = 0.0
"#
    ))
    .unwrap()
}

/// The strain magnitude where the trivial path's tangent first has a negative pivot.
fn fe_onset(scene: &Scene, guess: f64) -> f64 {
    let model = build_model(scene).unwrap();
    let mut problem = build_problem(scene, &model).unwrap();
    let (_, reference) = load_factors(scene);
    let (newton, _) = settings(scene);
    let one_step = Stepping {
        initial: 1.0,
        max: 1.0,
        ..Stepping::default()
    };
    let mut unstable = |strain: f64| {
        let lambda = -strain / reference;
        let mut u = vec![0.0; problem.assembler().n()];
        follow_path(&mut problem, &mut u, &[lambda], &newton, &one_step).unwrap();
        negative_pivots_at(&mut problem, &u, lambda, newton.solver).unwrap() > 0
    };
    let (mut lo, mut hi) = (0.5 * guess, 1.5 * guess);
    assert!(!unstable(lo) && unstable(hi), "onset not bracketed");
    while hi - lo > 2e-3 * lo {
        let mid = 0.5 * (lo + hi);
        if unstable(mid) { hi = mid } else { lo = mid }
    }
    0.5 * (lo + hi)
}

/// Relative error of the FE onset against the clamped plate.
fn onset_error(a_mm: f64, b_mm: f64, slices: usize) -> f64 {
    let reference = k_b(a_mm / b_mm) / (12.0 * (1.0 - NU * NU)) * (H_MM / b_mm).powi(2);
    let fe = fe_onset(&scene(a_mm, b_mm, slices), reference);
    let err = fe / reference - 1.0;
    eprintln!(
        "a/b = {}: FE {fe:.4e}, plate {reference:.4e}, error {:+.2} %",
        a_mm / b_mm,
        100.0 * err
    );
    err
}

/// The circle's error sets the yardstick (the base is not a rigid clamp, the solid sublaminate
/// shears, the mesh discretises: measured −0.7 %, bounded here by 3 %); the ellipses must land
/// within it, plus the bisection's 0.2 % and 1 % for the coarser resolution of the long
/// semi-axis by the same slice count. Before the a > b fix the a/b = 2 onset was not even
/// bracketed (the front lay at 1.3 a); with eq. 3.1.1 inside the delamination instead of
/// eq. 3.1.2, a/b = 1/2 was +5.8 % and 1/3 +10 % (docs/VALIDATION.md).
#[test]
fn elliptic_onset_matches_the_clamped_plate() {
    let circle = onset_error(10.0, 10.0, 8);
    assert!(
        circle.abs() < 0.03,
        "circle off the clamped plate by {circle}"
    );
    let band = circle.abs() + 0.002 + 0.01;
    for (a, b) in [(10.0, 30.0), (10.0, 20.0), (20.0, 10.0), (30.0, 10.0)] {
        let err = onset_error(a, b, 8);
        assert!(
            err.abs() <= band,
            "a/b = {}: error {err} beyond the circle's band {band}",
            a / b
        );
    }
}
