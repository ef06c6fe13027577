//! The error estimate's companion mesh runs beside the main sweep when the run has two or more
//! threads (src/analysis.rs, `rayon::in_place_scope`), after it on one thread. The companion is
//! an independent run and every kernel and factorisation gives the same bits on any thread
//! count, so the two orders must agree bit for bit: G, its estimated error per point, the
//! displacements and the accuracy report. No tolerance: any difference is a defect (a shared
//! state between the two runs, or a result that depends on the thread that computed it).

mod common;

use nonlin3d::results::Results;
use nonlin3d::{Analysis, Scene};

/// The reference circle on the tiny mesh of tests/error_estimate.rs (1 773 DOF, companion
/// 2 slices), two levels: below the bifurcation and past it (the §3.2 protocol and contact
/// `auto`), error estimate on (the scene's default).
fn scene() -> Scene {
    Scene::from_toml(&common::tiny_scene_text("[-0.001, -0.004]")).unwrap()
}

/// The scene run inside a pool of `threads` threads (all cores asked: `threads = 0`).
fn run_on(threads: usize) -> Results {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    pool.install(|| Analysis::new(scene()).unwrap().run().unwrap())
}

/// Every number of a level that the estimate or the sweep writes, as bits.
fn bits(r: &Results) -> Vec<u64> {
    let mut out = Vec::new();
    for l in &r.levels {
        out.push(l.centre_deflection_mm.to_bits());
        out.extend(l.displacements.iter().map(|x| x.to_bits()));
        for p in &l.front {
            out.extend([p.g_i, p.g_ii, p.g_iii, p.g_t].map(f64::to_bits));
            let e = p.error.expect("every point carries an estimate");
            out.extend([e.g_i, e.g_ii, e.g_iii, e.g_t].map(f64::to_bits));
        }
        // No summary on an unbuckled level (its G is round-off): marked, so both runs must
        // agree on which levels have one.
        match l.error_estimate {
            Some(e) => out.extend([e.max_j_m2, e.relative].map(f64::to_bits)),
            None => out.push(u64::MAX),
        }
    }
    out
}

#[test]
fn the_companion_beside_the_sweep_gives_the_sequential_bits() {
    let one = run_on(1);
    let two = run_on(2);
    assert_eq!(one.levels.len(), 2);
    // −0.001 is unbuckled (G round-off: no summary), −0.004 buckled.
    assert!(one.levels[0].error_estimate.is_none());
    assert!(one.levels[1].error_estimate.is_some());
    let (a, b) = (
        one.accuracy.as_ref().unwrap(),
        two.accuracy.as_ref().unwrap(),
    );
    assert!(a.unavailable.is_none() && b.unavailable.is_none());
    assert_eq!(a.companion_dofs, b.companion_dofs);
    assert_eq!(
        a.worst_relative.map(f64::to_bits),
        b.worst_relative.map(f64::to_bits)
    );
    assert_eq!(bits(&one), bits(&two));
    assert_eq!(one.warnings, two.warnings);
}
