//! Hard cases (issue 21, part 2): each converges to the answer small steps give on the same
//! mesh, or stops with a located, typed error; never a NaN, never a silent wrong state.
//!
//! Every case runs twice on one coarse mesh (the reference 30 mm circle's generator with 4
//! slices, 2 rings inside and outside the front, one base layer: 1185 DOFs): as written (the
//! default largest increment, 0.25 of the largest strain, or one step) and with small steps
//! (increments of 0.05 of it). The table in docs/VALIDATION.md ("Hard cases") holds the
//! iterations, cutbacks, times and results of both runs.
//!
//! Tolerance of the comparison: both runs converge each level to ‖r‖∞ ≤ 1e-8·F (the relative
//! criterion of `NewtonSettings::default`), so on the same branch their states differ by about
//! 1e-8 of the displacement scale, and G (force × opening, §2.8) by about 2e-8 relative; 1e-5
//! relative leaves room for the conditioning of the near-incompressible and strongly
//! orthotropic cases (measured: at most 3e-8 relative apart) and is still far below the
//! difference between branches (the flat and the buckled state differ by 100 %).

use nonlin3d::results::{LevelResult, Results};
use nonlin3d::{Error, Scene};

/// The coarse mesh of every case.
const MESH: &str = "slices = 4\ninside = 2\noutside = 2\nbase_layers = 1";
/// The homogeneous quasi-isotropic laminate of chapter 5.
const QI: &str =
    "kind = \"named\"\nname = \"generic-graphite-epoxy\"\nhomogenize = \"quasi-isotropic\"";
/// Isotropic, nearly incompressible.
const NU_499: &str = "kind = \"isotropic\"\ne_gpa = 50.0\nnu = 0.499";
/// Plies with E11/E22 = 50, fibres along the load.
const ORTHO_50: &str = "kind = \"orthotropic\"\ne11_gpa = 150.0\ne22_gpa = 3.0\ne33_gpa = 3.0\n\
    nu12 = 0.3\nnu13 = 0.3\nnu23 = 0.45\ng12_gpa = 2.0\ng13_gpa = 2.0\ng23_gpa = 1.0";

/// One case: the delamination's semi-axes and sublaminate (mm), the material, mesh lines
/// added to [`MESH`], the strains, the largest increment.
struct Case {
    a_mm: f64,
    b_mm: f64,
    h_mm: f64,
    material: &'static str,
    mesh: &'static str,
    strains: &'static str,
    max_increment: f64,
}

const CIRCLE: Case = Case {
    a_mm: 15.0,
    b_mm: 15.0,
    h_mm: 0.4,
    material: QI,
    mesh: "",
    strains: "[-0.002, -0.004]",
    max_increment: 0.25,
};

impl Case {
    /// The scene with the largest increment `max_increment`.
    fn scene(&self, max_increment: f64) -> Scene {
        let text = format!(
            "title = \"hard case\"\n[geometry]\nkind = \"embedded\"\na_mm = {}\nb_mm = {}\n\
             h_mm = {}\nbase_mm = 4.0\nw_mm = 50.0\n[material]\n{}\n[mesh]\n{MESH}\n{}\n\
             [loads]\nstrains = {}\n[analysis]\nmax_increment = {max_increment}\n\
             max_attempts = 400\n",
            self.a_mm, self.b_mm, self.h_mm, self.material, self.mesh, self.strains
        );
        Scene::from_toml(&text).unwrap_or_else(|e| panic!("{e}\n{text}"))
    }

    /// Runs the case as written and with small steps.
    fn run(&self) -> (Result<Results, Error>, Result<Results, Error>) {
        let go = |inc| nonlin3d::Analysis::new(self.scene(inc))?.run();
        (go(self.max_increment), go(0.05))
    }
}

/// No NaN anywhere in a level's record.
fn finite(l: &LevelResult) -> bool {
    l.centre_deflection_mm.is_finite()
        && l.displacements.iter().all(|x| x.is_finite())
        && l.front
            .iter()
            .all(|r| [r.g_i, r.g_ii, r.g_iii].iter().all(|g| g.is_finite()))
}

/// (w centre mm, G_T max over the open points, G_I and G_II at S = 0) of the last level.
fn answer(r: &Results) -> [f64; 4] {
    let l = r.levels.last().expect("a level");
    let gt = l
        .front
        .iter()
        .filter(|f| f.is_open())
        .map(|f| f.g_t)
        .fold(0.0, f64::max);
    [l.centre_deflection_mm, gt, l.front[0].g_i, l.front[0].g_ii]
}

/// The case converges, without NaN, to a stable state that is the small-step answer
/// (relative 1e-5 of each quantity's scale; see the module's derivation).
fn converges_to_the_small_step_answer(case: &Case) -> Results {
    let (big, small) = case.run();
    let (big, small) = (big.unwrap(), small.unwrap());
    for r in [&big, &small] {
        assert!(r.levels.iter().all(finite), "NaN in a level");
        let last = r.levels.last().unwrap();
        assert_eq!(last.convergence.stable, Some(true), "{:?}", r.warnings);
    }
    let (a, b) = (answer(&big), answer(&small));
    // Scales: w against the sublaminate (h), G against the largest G of the two, at least
    // 1e-3 J/m² (a flat state's G is round-off, ~1e-22 J/m²; buckled ones here exceed 1 J/m²).
    let g = a[1].max(b[1]).max(1e-3);
    let scale = [case.h_mm, g, g, g];
    for k in 0..4 {
        assert!(
            (a[k] - b[k]).abs() <= 1e-5 * scale[k],
            "quantity {k}: {} (as written) against {} (small steps)",
            a[k],
            b[k]
        );
    }
    big
}

/// Buckled: the sublaminate lifted off the base by more than h/4 and G_T above 1 J/m².
fn buckled(r: &Results, h_mm: f64) {
    let [w, gt, ..] = answer(r);
    assert!(
        w > 0.25 * h_mm && gt > 1.0,
        "w = {w} mm, G_T max = {gt} J/m²"
    );
}

/// ε = −0.02, about 12 times the buckling strain (§5.4's extreme case): G_T of thousands of
/// J/m², a centre deflection of four sublaminate thicknesses.
#[test]
fn far_past_buckling() {
    let case = Case {
        strains: "[-0.005, -0.01, -0.015, -0.02]",
        ..CIRCLE
    };
    let r = converges_to_the_small_step_answer(&case);
    buckled(&r, case.h_mm);
}

/// The whole sweep in one load step, straight to −0.005.
#[test]
fn one_step_to_minus_0_005() {
    let case = Case {
        strains: "[-0.005]",
        max_increment: 1.0,
        ..CIRCLE
    };
    let r = converges_to_the_small_step_answer(&case);
    buckled(&r, case.h_mm);
}

/// One displacement-controlled step from below the bifurcation (−0.0012, about 0.7 ε_cr on
/// this mesh) to above it (−0.0025): the inertia changes within the step and the perturbation
/// protocol redoes it onto the buckled branch.
#[test]
fn one_step_across_the_bifurcation() {
    let case = Case {
        strains: "[-0.0012, -0.0025]",
        max_increment: 1.0,
        ..CIRCLE
    };
    let r = converges_to_the_small_step_answer(&case);
    assert_eq!(r.model.perturbed_at, Some(-0.0025));
    buckled(&r, case.h_mm);
}

/// Just above buckling, ε = 1.05 ε_cr: the bifurcation is first bracketed on this mesh by a
/// fine sweep (increments of 1 % of −0.0025), then the level 1.05 ε_cr run alone: the branch
/// the perturbation must find has a small restoring stiffness there (§3.2).
#[test]
fn just_above_buckling() {
    let probe = Case {
        strains: "[-0.0025]",
        max_increment: 0.01,
        ..CIRCLE
    };
    let r = nonlin3d::Analysis::new(probe.scene(0.01))
        .unwrap()
        .run()
        .unwrap();
    let crossing = r.levels[0].convergence.bifurcation.unwrap();
    let critical = 0.5 * (crossing.from + crossing.to);
    let strains = format!("[{:.8}]", 1.05 * critical);
    let case = Case {
        strains: Box::leak(strains.into_boxed_str()),
        max_increment: 0.25,
        ..CIRCLE
    };
    let r = converges_to_the_small_step_answer(&case);
    assert!(r.model.perturbed_at.is_some());
    // Just past ε_cr the buckled amplitude grows like √(ε/ε_cr − 1) (√0.05 ≈ 0.22 of its scale):
    // lifted, but less than at 1.5 ε_cr.
    let [w, gt, ..] = answer(&r);
    assert!(w > 0.05 * case.h_mm && gt > 0.0, "w = {w} mm, G_T = {gt}");
}

/// An ellipse b/a = 3 on the unmodified conformal map (eq. 3.1.1), whose inner cells degrade
/// with the aspect ratio.
#[test]
fn ellipse_b_over_a_3_on_the_conformal_map() {
    let case = Case {
        a_mm: 10.0,
        b_mm: 30.0,
        mesh: "elliptic_map = \"conformal\"",
        ..CIRCLE
    };
    let r = converges_to_the_small_step_answer(&case);
    buckled(&r, case.h_mm);
}

/// Distorted elements: a front grading of 0.1 (the ring at the front a tenth of the innermost:
/// aspect ratios past 10 in the radial–thickness plane) on the coarse rings.
#[test]
fn distorted_elements() {
    let case = Case {
        mesh: "front_grading = 0.1",
        ..CIRCLE
    };
    let r = converges_to_the_small_step_answer(&case);
    buckled(&r, case.h_mm);
}

/// Plies with E11/E22 = 50 on Hex20 (2×2×2) and Hex8 (2×2×2): both converge to their small-step
/// answers.
#[test]
fn strongly_orthotropic_hex20_and_hex8() {
    for mesh in ["", "element = \"hex8\""] {
        let case = Case {
            material: ORTHO_50,
            mesh,
            ..CIRCLE
        };
        let r = converges_to_the_small_step_answer(&case);
        buckled(&r, case.h_mm);
    }
}

/// ν = 0.499 on Hex8 (full 2×2×2 integration): the element locks in volume and the
/// sublaminate does not buckle by −0.004 (no negative pivot at any converged state, measured
/// on 4 slices too); the answer is the small-step one, with no NaN.
#[test]
fn nearly_incompressible_hex8() {
    let case = Case {
        material: NU_499,
        mesh: "element = \"hex8\"",
        ..CIRCLE
    };
    let r = converges_to_the_small_step_answer(&case);
    assert_eq!(r.model.perturbed_at, None);
}

/// ν = 0.499 on Hex20 (2×2×2) on the coarse mesh: buckles at −0.004 like the small steps.
#[test]
fn nearly_incompressible_hex20() {
    let case = Case {
        material: NU_499,
        ..CIRCLE
    };
    let r = converges_to_the_small_step_answer(&case);
    buckled(&r, case.h_mm);
}

/// A very thin sublaminate, h = 0.1 mm over a 60 mm delamination (ε_cr ≈ −2.5e-5 on this
/// mesh: the bifurcation is crossed at −0.000125 within the first level, −0.0005): the
/// perturbation applied at that first level, 20 times past buckling, lifts the sublaminate
/// (w = 0.56 mm, stable, G_T = 1.05 J/m²; its outer ring overlaps the base, so `auto` contact
/// engages from that state); level 2 is buckled and stable too (0.72 mm). Level 3 (−0.002)
/// converges, after 18 contact passes, to an unstable equilibrium (one negative pivot):
/// the centre pushed 0.056 mm into the base and G_T max ≈ 620 J/m², fifty times the
/// sublaminate's stored energy per unit area ½·C₁₁·ε²·h ≈ 12 J/m². Until the energy line
/// search (docs/PERFORMANCE.md, "The companion chain started first, and the energy line
/// search") it stopped with a located error instead:
/// a contact pass at λ = 0.75 did not converge and its fallback could not take a 1e-4 step.
/// Reproducer: tests/hard_cases/thin_0p1mm_60mm.toml; docs/VALIDATION.md "Hard cases".
#[test]
#[ignore = "open: level 3 (−0.002) of h = 0.1 mm over 60 mm ends on an unstable equilibrium \
            (one negative pivot, flagged), not on the buckled branch"]
fn very_thin_sublaminate() {
    let text = include_str!("hard_cases/thin_0p1mm_60mm.toml");
    let r = nonlin3d::Analysis::new(Scene::from_toml(text).unwrap())
        .unwrap()
        .run()
        .unwrap();
    buckled(&r, 0.1);
}

/// What the very thin sublaminate does today, asserted so a change is seen: the first two
/// levels buckled, stable and finite (w above h/4 = 0.025 mm and G_T above 0 — the flat state
/// the perturbation used to fall back to under contact has w < 0.003 mm and G_T ~ 1e-20 J/m²),
/// then level 3 on an equilibrium the run flags: reported unstable, with the warning that
/// names its strain and the one at the end of the run, and finite — not a NaN and not a
/// silent unstable state.
#[test]
fn very_thin_sublaminate_buckles_then_ends_on_a_flagged_unstable_state() {
    let text = include_str!("hard_cases/thin_0p1mm_60mm.toml");
    let r = nonlin3d::Analysis::new(Scene::from_toml(text).unwrap())
        .unwrap()
        .run()
        .unwrap();
    assert_eq!(r.levels.len(), 3);
    for l in &r.levels[..2] {
        assert!(finite(l));
        assert_eq!(l.convergence.stable, Some(true));
        assert!(l.centre_deflection_mm > 0.025, "{}", l.centre_deflection_mm);
        let gt = l.front.iter().map(|f| f.g_t).fold(0.0, f64::max);
        assert!(gt > 0.1, "G_T = {gt} J/m²");
    }
    let last = &r.levels[2];
    assert!(finite(last));
    assert_eq!(last.convergence.stable, Some(false));
    let flagged = |needle: &str| r.warnings.iter().any(|w| w.contains(needle));
    assert!(
        flagged("strain -0.002: the converged state is unstable")
            && flagged("the run ends on an unstable state"),
        "{:?}",
        r.warnings
    );
}
