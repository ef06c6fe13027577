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
//! with a > b"). ν does not enter k_b for a clamped edge. No published table of clamped elliptic
//! plates was in reach; the published anchor is the clamped circle under equibiaxial strain,
//! N_cr = j₁,₁²·D/R² (Timoshenko & Gere), which the same model meets with the same error as the
//! uniaxial circle meets the Ritz value.
//!
//! The FE onset is the strain where the trivial (unbuckled) path's tangent first has a negative
//! pivot (Sylvester's law of inertia), bracketed by bisection to 0.2 %.

use nonlin3d::Scene;
use nonlin3d::analysis::{build_model, build_problem, load_factors, settings};
use nonlin3d::mesh::names;
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

/// The strain magnitude where the trivial path's tangent first has a negative pivot. With
/// `equibiaxial`, the face y = W is moved with the face x = W (v = y·ε there), so the box is
/// strained ε_x = ε_y = ε instead of ε_x = ε with free lateral contraction.
fn fe_onset(scene: &Scene, guess: f64, equibiaxial: bool) -> f64 {
    let model = build_model(scene).unwrap();
    let mut problem = build_problem(scene, &model).unwrap();
    let (_, reference) = load_factors(scene);
    if equibiaxial {
        for &n in &model.mesh.node_sets[names::Y1] {
            let y = model.mesh.nodes[n][1];
            problem.prescribe_value(3 * n + 1, y * reference).unwrap();
        }
    }
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
    let fe = fe_onset(&scene(a_mm, b_mm, slices), reference, false);
    let err = fe / reference - 1.0;
    eprintln!(
        "a/b = {}: FE {fe:.4e}, plate {reference:.4e}, error {:+.2} %",
        a_mm / b_mm,
        100.0 * err
    );
    err
}

/// j₁,₁, the first zero of the Bessel function J₁ (Abramowitz & Stegun, *Handbook of
/// Mathematical Functions*, 1964, Table 9.5).
const J11: f64 = 3.831_705_970_207_512;

/// Relative error of the FE onset of the circle of radius R under equibiaxial strain against
/// the published clamped circular plate. w = J₀(kr) − J₀(kR) with w'(R) = 0 gives J₁(kR) = 0,
/// so N_cr = j₁,₁²·D/R² = 14.682·D/R², the value Timoshenko & Gere give for the clamped
/// circular plate under uniform compression (*Theory of Elastic Stability*, 2nd ed., 1961).
/// The laminate strained ε_x = ε_y = ε loads the sublaminate with N = E·h·ε/(1 − ν) in every
/// direction, so ε_cr = j₁,₁²·D/R²·(1 − ν)/(E·h) = j₁,₁²/(12(1 + ν))·(h/R)².
fn published_circle_error(r_mm: f64, slices: usize) -> f64 {
    let reference = J11 * J11 / (12.0 * (1.0 + NU)) * (H_MM / r_mm).powi(2);
    let fe = fe_onset(&scene(r_mm, r_mm, slices), reference, true);
    let err = fe / reference - 1.0;
    eprintln!(
        "circle, equibiaxial: FE {fe:.4e}, j11 plate {reference:.4e}, error {:+.2} %",
        100.0 * err
    );
    err
}

/// The circle against a published coefficient sets the yardstick. No published table of
/// clamped elliptic plates was in reach (docs/VALIDATION.md lists where we looked), so the
/// ellipses are held to the Ritz reference, and the Ritz reference is tied to the published
/// circle through one model:
///
/// 1. The circle under equibiaxial strain against j₁,₁² (published, exact): within 3 %. What
///    separates the solid model from the plate: the base is not a rigid clamp (the front
///    rotates, an O(h/R) effect), the sublaminate shears (Mindlin's factor
///    1/(1 + N_cr/(κGh)), N_cr/(κGh) = 14.68·E·h²/(12(1 − ν²)·R²·κG) = 0.17 % at h/R = 0.02,
///    κ = 5/6, G = E/2.6), 8 slices of Hex20 discretise the mode; measured −0.68 %.
/// 2. The same circle under uniaxial strain against the Ritz k_b = 27.2216 misses by the same
///    amount within 0.5 %: 0.2 % for the two bisections (each midpoint within 0.1 %) and 0.3 %
///    for the different mode (cos 2θ terms) on the same mesh, a part of the −0.7 % total. A
///    Ritz reference off by more than that would show here. Measured: −0.68 % both.
/// 3. Every ellipse within the published circle's error, plus the bisection's 0.2 % and 1 %
///    for the coarser resolution of the long semi-axis by the same slice count.
///
/// Before the a > b fix the a/b = 2 onset was not even bracketed (the front lay at 1.3 a);
/// with eq. 3.1.1 inside the delamination instead of eq. 3.1.2, a/b = 1/2 was +5.8 % and 1/3
/// +10 % (docs/VALIDATION.md).
#[test]
fn elliptic_onset_matches_the_clamped_plate() {
    let published = published_circle_error(10.0, 8);
    assert!(
        published.abs() < 0.03,
        "equibiaxial circle off the published clamped plate (j11²) by {published}"
    );
    let ritz = onset_error(10.0, 10.0, 8);
    assert!(
        (ritz - published).abs() <= 0.005,
        "uniaxial circle off the Ritz plate by {ritz}, equibiaxial off j11² by {published}"
    );
    let band = published.abs() + 0.002 + 0.01;
    for (a, b) in [(10.0, 30.0), (10.0, 20.0), (20.0, 10.0), (30.0, 10.0)] {
        let err = onset_error(a, b, 8);
        assert!(
            err.abs() <= band,
            "a/b = {}: error {err} beyond the circle's band {band}",
            a / b
        );
    }
}
