//! The Mattiasson elastica (tests/decks/mattiasson.inp): a slender C3D20 cantilever under a dead
//! tip load in ten NLGEOM increments to PL²/EI = 10, against the closed form by elliptic
//! integrals (Mattiasson 1981), and the iterations the increments' extrapolated starts need.

use nonlin3d::deck::{IncrementStart, StepOptions, StepResult, solve_deck};
use std::collections::BTreeMap;

/// Carlson's R_F(x, y, z) by duplication (Numerical Recipes' `rf`; error ~ tol⁶ = 1e-18).
fn rf(mut x: f64, mut y: f64, mut z: f64) -> f64 {
    loop {
        let (sx, sy, sz) = (x.sqrt(), y.sqrt(), z.sqrt());
        let lam = sx * (sy + sz) + sy * sz;
        x = 0.25 * (x + lam);
        y = 0.25 * (y + lam);
        z = 0.25 * (z + lam);
        let ave = (x + y + z) / 3.0;
        let (dx, dy, dz) = ((ave - x) / ave, (ave - y) / ave, (ave - z) / ave);
        if dx.abs().max(dy.abs()).max(dz.abs()) < 1e-3 {
            let e2 = dx * dy - dz * dz;
            let e3 = dx * dy * dz;
            return (1.0 + (e2 / 24.0 - 0.1 - 3.0 * e3 / 44.0) * e2 + e3 / 14.0) / ave.sqrt();
        }
    }
}

/// Carlson's R_D(x, y, z) by duplication (Numerical Recipes' `rd`).
fn rd(mut x: f64, mut y: f64, mut z: f64) -> f64 {
    let (mut sum, mut fac) = (0.0, 1.0);
    loop {
        let (sx, sy, sz) = (x.sqrt(), y.sqrt(), z.sqrt());
        let lam = sx * (sy + sz) + sy * sz;
        sum += fac / (sz * (z + lam));
        fac *= 0.25;
        x = 0.25 * (x + lam);
        y = 0.25 * (y + lam);
        z = 0.25 * (z + lam);
        let ave = 0.2 * (x + y + 3.0 * z);
        let (dx, dy, dz) = ((ave - x) / ave, (ave - y) / ave, (ave - z) / ave);
        if dx.abs().max(dy.abs()).max(dz.abs()) < 1e-3 {
            let (c1, c2, c3, c4) = (3.0 / 14.0, 1.0 / 6.0, 9.0 / 22.0, 3.0 / 26.0);
            let (c5, c6) = (0.25 * c3, 1.5 * c4);
            let ea = dx * dy;
            let eb = dz * dz;
            let ec = ea - eb;
            let ed = ea - 6.0 * eb;
            let ee = ed + ec + ec;
            let series = 1.0
                + ed * (-c1 + c5 * ed - c6 * dz * ee)
                + dz * (c2 * ee + dz * (-c3 * ec + dz * c4 * ea));
            return 3.0 * sum + fac * series / (ave * ave.sqrt());
        }
    }
}

/// Incomplete elliptic integrals F(φ, k) and E(φ, k), k² = `m`.
fn elliptic(phi: f64, m: f64) -> (f64, f64) {
    let (s, c) = phi.sin_cos();
    let (x, y) = (c * c, 1.0 - m * s * s);
    let f = s * rf(x, y, 1.0);
    (f, f - m / 3.0 * s * s * s * rd(x, y, 1.0))
}

/// The elastica under a dead tip load P, α = PL²/EI: (u/L, w/L), the tip's shortening and
/// deflection. EI θ'' = −P cos θ with θ(0) = 0, θ'(L) = 0; with k² = (1 + sin θ₀)/2 and
/// 1 + sin θ = 2k² sin²φ: √α = K(k) − F(φ₁, k), sin φ₁ = 1/(√2 k), the tip angle θ₀ by
/// bisection; u/L = 1 − √(2 sin θ₀/α), w/L = 1 − 2(E(k) − E(φ₁, k))/√α.
fn elastica(alpha: f64) -> (f64, f64) {
    let at = |t0: f64| {
        let m = (1.0 + t0.sin()) / 2.0;
        let phi1 = (1.0 / (2.0 * m).sqrt()).asin();
        let (k, e) = elliptic(std::f64::consts::FRAC_PI_2, m);
        let (f1, e1) = elliptic(phi1, m);
        (k - f1 - alpha.sqrt(), e - e1)
    };
    let (mut lo, mut hi) = (1e-9, std::f64::consts::FRAC_PI_2 - 1e-12);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if at(mid).0 < 0.0 { lo = mid } else { hi = mid }
    }
    let t0 = 0.5 * (lo + hi);
    let u = 1.0 - (2.0 * t0.sin() / alpha).sqrt();
    (u, 1.0 - 2.0 * at(t0).1 / alpha.sqrt())
}

/// Mattiasson's table (1981), u/L and w/L at PL²/EI = 1 … 10, five digits.
const PUBLISHED: [(f64, f64); 10] = [
    (0.05643, 0.30172),
    (0.16064, 0.49346),
    (0.25442, 0.60325),
    (0.32894, 0.66996),
    (0.38763, 0.71379),
    (0.43459, 0.74457),
    (0.47293, 0.76737),
    (0.50483, 0.78498),
    (0.53182, 0.79906),
    (0.55500, 0.81061),
];

#[test]
fn the_closed_form_reproduces_mattiasson_s_table() {
    for (i, &(u, w)) in PUBLISHED.iter().enumerate() {
        let (cu, cw) = elastica(i as f64 + 1.0);
        // The table's last digit: ±5e-6 rounding.
        assert!(
            (cu - u).abs() <= 5.1e-6 && (cw - w).abs() <= 5.1e-6,
            "{i}: {cu} {cw}"
        );
    }
}

const L: f64 = 0.1;

fn solve(start: IncrementStart) -> Vec<StepResult> {
    let model =
        nonlin3d::mesh::read_inp_file(std::path::Path::new("tests/decks/mattiasson.inp")).unwrap();
    let options = StepOptions {
        start,
        ..Default::default()
    };
    solve_deck(&model, &options).unwrap()
}

/// The tip's mean (ux, uz) per step time from the `*NODE PRINT, NSET=TIP` table: the mean of
/// the tip face's eight nodes is its centroid's (the face stays plane and turns rigidly).
fn tip(step: &StepResult) -> BTreeMap<u64, (f64, f64)> {
    let table = &step.outputs[0].csv;
    let mut lines = table.lines();
    let head: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| head.iter().position(|h| *h == name).unwrap();
    let (t, ux, uz) = (col("step_time"), col("ux"), col("uz"));
    let mut sums: BTreeMap<u64, (f64, f64, f64)> = BTreeMap::new();
    for line in lines {
        let v: Vec<f64> = line.split(',').map(|x| x.parse().unwrap()).collect();
        let e = sums.entry(v[t].to_bits()).or_default();
        *e = (e.0 + v[ux], e.1 + v[uz], e.2 + 1.0);
    }
    sums.into_iter()
        .map(|(k, (x, z, n))| (k, (x / n, z / n)))
        .collect()
}

/// Ten increments on the deck's grid t = 0.1 … 1 (PL²/EI = 1 … 10), each against the closed
/// form. Tolerance 1e-3·L, from the model rather than the solver (Newton converges to 1e-8 of
/// the load): shear flexibility, absent from the elastica, adds 3EI/(κGAL²) = 0.6 (h/L)² =
/// 2.4e-4 of the deflection (ν = 0, κ = 5/6, h/L = 1/50); the C3D20 field, quadratic along
/// each of the 40 elements, interpolates the turning centre line to O((l_e/L)²) = 6.3e-4 of
/// it; 8.7e-4·L for deflections below L, rounded up. Measured: 4.8e-4·L at PL²/EI = 10.
#[test]
fn the_deck_follows_the_elastica_on_the_deck_s_increments() {
    let steps = solve(IncrementStart::default());
    let step = &steps[0];
    let converged: Vec<_> = step.increments.iter().filter(|i| i.converged).collect();
    assert_eq!(converged.len(), 10, "{:?}", step.increments);
    let tips = tip(step);
    assert_eq!(tips.len(), 10);
    for (k, inc) in converged.iter().enumerate() {
        let alpha = k as f64 + 1.0;
        // The increments land on the grid of the *STATIC initial increment (0.1·k to
        // rounding of the sums).
        assert!(
            (inc.step_time - alpha / 10.0).abs() < 1e-12,
            "{}",
            inc.step_time
        );
        let (ux, uz) = tips[&inc.step_time.to_bits()];
        let (u, w) = elastica(alpha);
        assert!(
            (-ux / L - u).abs() < 1e-3,
            "α = {alpha}: u/L {} against {u}",
            -ux / L
        );
        assert!(
            (-uz / L - w).abs() < 1e-3,
            "α = {alpha}: w/L {} against {w}",
            -uz / L
        );
    }
}

/// Iterations: CalculiX 2.20 needs 51 for this deck (tests/decks/mattiasson.ccx.dat's run:
/// 6, 7, 8, 6, 6, 5, 4, 3, 3, 3 in ten increments) at its residual criterion R_n = 0.005;
/// nonlin3d converges to 1e-8 of the load, which from 0.005 takes Newton's quadratic rate two
/// more iterations (0.005² = 2.5e-5, then ≈ 6e-10): at most 51 + 2·10 = 71. The linear start
/// with the line search (the old default) took 147 in 21 increments (a failed attempt
/// among them); the extrapolated start without the line search 63.
#[test]
fn extrapolated_starts_take_at_most_calculix_s_iterations_plus_two_per_increment() {
    let count = |start| -> (usize, usize) {
        let steps = solve(start);
        let incs = &steps[0].increments;
        (incs.iter().map(|i| i.iterations).sum(), incs.len())
    };
    let (ours, attempts) = count(IncrementStart::default());
    assert!(
        ours <= 71 && attempts == 10,
        "{ours} iterations in {attempts} attempts"
    );
    let (old, _) = count(IncrementStart {
        extrapolation: 1,
        guarded: false,
        line_search: true,
    });
    assert!(old > 71, "the old start: {old}");
}
