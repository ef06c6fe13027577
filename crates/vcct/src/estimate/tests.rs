//! Tests of the error estimate (`estimate`): closed-form sequences, the floor, the checks,
//! and the coarser companions' term.
use super::*;
use approx::assert_relative_eq;

/// G(S) on a mesh of size h converging as G∞(S) + C(S)·h^p (a closed-form sequence).
fn sequence(n: usize, h: f64, p: f64) -> (Vec<f64>, Vec<Modes>) {
    let at: Vec<f64> = (0..=n).map(|k| k as f64 / n as f64).collect();
    let g = at
        .iter()
        .map(|&s| {
            let exact = [100.0 * (1.0 - s), 50.0 * s, 5.0, 155.0 - 45.0 * s];
            let coeff = [-40.0, 30.0 * (1.0 - 2.0 * s), 2.0, -10.0 - 20.0 * s];
            Modes::from_array(std::array::from_fn(|m| exact[m] + coeff[m] * h.powf(p)))
        })
        .collect();
    (at, g)
}

/// The estimate on `run` from `comp` (every point open).
fn estimate(run: (&[f64], &[Modes]), comp: (&[f64], &[Modes]), rule: Rule) -> Vec<Modes> {
    companion(
        FrontG {
            at: run.0,
            g: run.1,
            open: None,
        },
        FrontG {
            at: comp.0,
            g: comp.1,
            open: None,
        },
        rule,
    )
    .unwrap_or_default()
}

/// The smallest estimate over the true error over every point and mode of a sequence
/// converging at order p (mesh h against 2h), and the largest.
fn ratios(p: f64, rule: Rule) -> (f64, f64) {
    let (h, n) = (0.3, 8);
    let (fa, fg) = sequence(n, h, p);
    let (ca, cg) = sequence(n / 2, 2.0 * h, p);
    let est = estimate((&fa, &fg), (&ca, &cg), rule);
    let (_, exact) = sequence(n, 0.0, 1.0);
    assert_eq!(est.len(), n + 1);
    let mut r = (f64::INFINITY, 0.0f64);
    for (e, (g, x)) in est.iter().zip(fg.iter().zip(&exact)) {
        for (ev, (gv, xv)) in e.array().iter().zip(g.array().iter().zip(x.array())) {
            let err = (gv - xv).abs();
            if err > 1e-9 {
                r = (r.0.min(ev / err), r.1.max(ev / err));
            }
        }
    }
    r
}

#[test]
fn the_estimate_is_richardson_with_the_rules_order() {
    // Error of M: C·h^p; M − M/2 = C·h^p·(2^p − 1): the estimate a·|ΔG| over the error is
    // a·(2^p − 1) at every point and mode (linear coefficients in S: the interpolation is
    // exact; 1e-9 relative is round-off on 100 J/m²). It brackets for p ≥ log2(1 + 1/a):
    // 1.585 with the split kept (a = 0.5), 0.874 with everything halved (a = 1.2).
    for (rule, p_min) in [(Rule::SPLIT_KEPT, 3f64.log2()), (Rule::ALL_HALVED, 0.874)] {
        let rule = Rule { floor: 0.0, ..rule };
        for p in [0.8, 1.0, 1.5, 2.0, 3.0] {
            let (lo, hi) = ratios(p, rule);
            let want = rule.scale * (2f64.powf(p) - 1.0);
            assert_relative_eq!(lo, want, max_relative = 1e-9);
            assert_relative_eq!(hi, want, max_relative = 1e-9);
            assert_eq!(lo >= 1.0, p >= p_min, "{rule:?} p {p}: ratio {lo}");
        }
    }
}

#[test]
fn the_rule_follows_the_companion() {
    assert_eq!(
        Rule::for_companion(CompanionKind::FarFieldKept),
        Rule::FAR_FIELD_KEPT
    );
    assert_eq!(
        Rule::for_companion(CompanionKind::SplitKept),
        Rule::SPLIT_KEPT
    );
    assert_eq!(
        Rule::for_companion(CompanionKind::AllHalved),
        Rule::ALL_HALVED
    );
    // A companion that keeps the split is nearer the asymptotic range: its difference is
    // divided (p > 1), the other's enlarged (p < 1).
    let kept = [CompanionKind::FarFieldKept, CompanionKind::SplitKept].map(Rule::for_companion);
    let halved = Rule::for_companion(CompanionKind::AllHalved);
    assert!(
        kept.iter().all(|k| k.scale < 1.0) && halved.scale > 1.0,
        "{kept:?} {halved:?}"
    );
}

#[test]
fn the_floor_covers_a_difference_that_crosses_zero() {
    // G_II's coefficient 30·(1 − 2S) is zero at S = 0.5: the difference there is 0 but the
    // estimate keeps a·c times the difference of G_T at its peak (S = 0: |C_T|·h·(2 − 1)).
    let (h, p) = (0.2, 1.0);
    let rule = Rule::ALL_HALVED;
    let (fa, fg) = sequence(4, h, p);
    let (ca, cg) = sequence(2, 2.0 * h, p);
    let est = estimate((&fa, &fg), (&ca, &cg), rule);
    let peak = 10.0 * h; // |C_T(0)|·(2h − h)
    let (a, c) = (rule.scale, rule.floor);
    assert_relative_eq!(est[2].g_ii, a * c * peak, max_relative = 1e-9);
    // Elsewhere the larger of the two, scaled.
    assert_relative_eq!(est[0].g_i, a * 40.0 * h, max_relative = 1e-9);
}

#[test]
fn the_floor_takes_the_peak_over_the_open_points_only() {
    // Three points; the last is overlapped with the largest G_T (300 J/m², off by 50 on
    // the companion); the open peak is the first (200, off by 10). The floor at the
    // middle point (difference 0) is a·c·10, not a·c·50; with every point open a·c·50.
    let at = [0.0, 0.5, 1.0];
    let g_t = |v: f64| Modes {
        g_t: v,
        ..Modes::default()
    };
    let run = [g_t(200.0), g_t(50.0), g_t(300.0)];
    let comp = [g_t(190.0), g_t(50.0), g_t(250.0)];
    let rule = Rule::SPLIT_KEPT;
    let c = rule.scale * rule.floor;
    let open = [true, true, false];
    let est = |open: Option<&[bool]>| {
        companion(
            FrontG {
                at: &at,
                g: &run,
                open,
            },
            FrontG {
                at: &at,
                g: &comp,
                open: None,
            },
            rule,
        )
        .unwrap_or_default()
    };
    assert_relative_eq!(est(Some(&open))[1].g_t, c * 10.0, max_relative = 1e-12);
    assert_relative_eq!(est(None)[1].g_t, c * 50.0, max_relative = 1e-12);
    // None open: the peak over all points again.
    assert_relative_eq!(
        est(Some(&[false; 3]))[1].g_t,
        c * 50.0,
        max_relative = 1e-12
    );
    // Flags that do not match the points are refused.
    let e = companion(
        FrontG {
            at: &at,
            g: &run,
            open: Some(&[true]),
        },
        FrontG {
            at: &at,
            g: &comp,
            open: None,
        },
        rule,
    );
    assert!(e.is_err_and(|e| e.to_string().contains("1 open/overlapped flags for 3")));
}

#[test]
fn fronts_of_different_points_are_matched_by_position() {
    // A run of 3 points against a companion of 5: the differences interpolated in S.
    let at = [0.0, 0.5, 1.0];
    let g = [Modes::default(); 3];
    let cat = [0.0, 0.25, 0.5, 0.75, 1.0];
    let cg: Vec<Modes> = cat
        .iter()
        .map(|&s| Modes {
            g_t: 4.0 * s,
            ..Modes::default()
        })
        .collect();
    let est = companion(
        FrontG {
            at: &at,
            g: &g,
            open: None,
        },
        FrontG {
            at: &cat,
            g: &cg,
            open: None,
        },
        Rule {
            scale: 1.0,
            floor: 0.0,
            coarser: None,
        },
    )
    .unwrap_or_default();
    let t: Vec<f64> = est.iter().map(|e| e.g_t).collect();
    assert_eq!(t, vec![0.0, 2.0, 4.0]);
}

#[test]
fn mismatched_or_unordered_fronts_are_refused_with_the_reason() {
    let g = [Modes::default(); 2];
    let e = companion(
        FrontG {
            at: &[0.0, 1.0, 2.0],
            g: &g,
            open: None,
        },
        FrontG {
            at: &[0.0, 1.0],
            g: &g,
            open: None,
        },
        Rule::ALL_HALVED,
    );
    assert!(e.is_err_and(|e| e.to_string().contains("3 positions for 2 G values")));
    let e = companion(
        FrontG {
            at: &[0.0, 1.0],
            g: &g,
            open: None,
        },
        FrontG {
            at: &[1.0, 0.0],
            g: &g,
            open: None,
        },
        Rule::ALL_HALVED,
    );
    assert!(e.is_err_and(|e| e.to_string().contains("companion's front")));
    let e = companion(
        FrontG {
            at: &[0.0, 1.0],
            g: &g,
            open: None,
        },
        FrontG {
            at: &[0.0, 1.0],
            g: &g,
            open: None,
        },
        Rule {
            scale: 0.0,
            floor: 0.2,
            coarser: None,
        },
    );
    assert!(e.is_err_and(|e| e.to_string().contains("the scale 0 > 0")));
}

/// The coarser companions' term: b·|G(M/2) − G(M/4)| at M/4's points, interpolated to the
/// run's positions; the companion's G is interpolated to M/4's points first. Two
/// estimates of one point combine mode by mode.
#[test]
fn the_coarser_term_is_the_two_companions_difference_scaled() {
    let g_t = |v: f64| Modes {
        g_i: 0.5 * v,
        g_ii: 0.5 * v,
        g_iii: 0.0,
        g_t: v,
    };
    // Companion on 0, ½, 1; coarser on 0, 1: at 0 and 1 the differences are 10 and 30.
    let (cat, cg) = ([0.0, 0.5, 1.0], [g_t(100.0), g_t(80.0), g_t(60.0)]);
    let (kat, kg) = ([0.0, 1.0], [g_t(90.0), g_t(90.0)]);
    fn front<'a>(at: &'a [f64], g: &'a [Modes]) -> FrontG<'a> {
        FrontG { at, g, open: None }
    }
    let (c, k) = (&cg[..], &kg[..]);
    let est = coarser(&[0.0, 0.25, 1.0], front(&cat, c), front(&kat, k), 0.27).unwrap();
    let t: Vec<f64> = est.iter().map(|e| e.g_t).collect();
    for (got, want) in t.iter().zip([0.27 * 10.0, 0.27 * 15.0, 0.27 * 30.0]) {
        assert_relative_eq!(*got, want, max_relative = 1e-12);
    }
    assert_relative_eq!(est[1].g_i, 0.27 * 7.5, max_relative = 1e-12);
    let both = g_t(1.0).larger(Modes {
        g_i: 3.0,
        ..Modes::default()
    });
    assert_eq!((both.g_i, both.g_ii, both.g_t), (3.0, 0.5, 1.0));
    assert!(coarser(&[0.0], front(&cat, c), front(&kat, k), 0.0).is_err());
    assert!(coarser(&[0.0], front(&cat, c), front(&[0.0], k), 0.27).is_err());
}
