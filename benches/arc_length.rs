//! Arc-length path following against load control (issue 21 §3): the shallow two-bar truss
//! through both limit points by arc length (to w = 2.5h; load control cannot pass the limit
//! point, so its reference is the path up to λ = 0.95, the same load factors as the arc
//! length converged to below it) and one run of the reference scene on 4 slices (strains
//! −0.001, −0.003, the bifurcation and the perturbation protocol inside) with
//! `path = "arc-length"` against `path = "load"`. Figures and ratios in docs/PERFORMANCE.md.
//!
//! Run: `cargo bench --bench arc_length`.

use criterion::{Criterion, criterion_group, criterion_main};
use nonlin3d::newton::{
    ArcLength, NewtonError, NewtonSettings, NonlinearProblem, SignRule, Stepping,
    follow_arc_length, follow_path_from,
};
use nonlin3d::solver::{SymmetricMatrix, SymmetricPattern};
use std::hint::black_box;
use std::sync::Arc;
use std::time::Duration;

/// The shallow truss of crates/newton/tests/arc_length.rs: two bars of EA = 1 from (±1, 0) to
/// an apex at h = 0.1, P(w) = EA·w(h − w)(2h − w)/ℓ₀³, the reference load P_max.
struct Truss;

const H: f64 = 0.1;

fn l0() -> f64 {
    (1.0 + H * H).sqrt()
}

fn p_max() -> f64 {
    2.0 * H.powi(3) / (3.0 * 3f64.sqrt() * l0().powi(3))
}

impl NonlinearProblem for Truss {
    fn n(&self) -> usize {
        1
    }
    fn pattern(&self) -> Arc<SymmetricPattern> {
        Arc::new(SymmetricPattern::from_dof_lists(1, &[vec![0]]).unwrap_or_else(|e| panic!("{e}")))
    }
    fn prescribe(&self, _u: &mut [f64], _lambda: f64) {}
    fn evaluate(
        &mut self,
        u: &[f64],
        lambda: f64,
        r: &mut [f64],
        tangent: Option<&mut SymmetricMatrix>,
    ) -> Result<f64, NewtonError> {
        let w = u[0];
        let force = w * (H - w) * (2.0 * H - w) / l0().powi(3);
        r[0] = force - lambda * p_max();
        if let Some(t) = tangent {
            t.set_zero();
            t.add(
                0,
                0,
                (2.0 * H * H - 6.0 * H * w + 3.0 * w * w) / l0().powi(3),
            )
            .unwrap_or_else(|e| panic!("{e}"));
        }
        Ok((lambda * p_max())
            .abs()
            .max(force.abs())
            .max(1e-3 * p_max()))
    }
}

/// The arc to w = 2.5h (both limit points), arcs 0.1 to 0.2; the load factors it converged to
/// below λ = 0.95.
fn truss_arc(sign: SignRule) -> Vec<f64> {
    let arc = ArcLength {
        initial: 0.1,
        max: 0.2,
        sign,
        monitor: Some((0, 2.5 * H)),
        max_increments: 400,
        ..ArcLength::default()
    };
    let mut u = vec![0.0];
    let mut below = Vec::new();
    let mut rising = true;
    follow_arc_length(
        &mut Truss,
        &mut u,
        0.0,
        &NewtonSettings::default(),
        &arc,
        &mut |i, _, _| {
            rising &= i.lambda < 0.95 && i.delta_lambda > 0.0;
            if rising {
                below.push(i.lambda);
            }
            false
        },
    )
    .unwrap_or_else(|e| panic!("{e}"));
    below
}

fn bench_truss(c: &mut Criterion) {
    let targets = truss_arc(SignRule::Combined);
    let mut g = c.benchmark_group("arc_length/truss");
    g.sample_size(50).measurement_time(Duration::from_secs(3));
    for (name, sign) in [
        ("arc_through_limit_combined", SignRule::Combined),
        ("arc_through_limit_inertia", SignRule::Inertia),
        ("arc_through_limit_direction", SignRule::Direction),
    ] {
        g.bench_function(name, |b| b.iter(|| black_box(truss_arc(sign))));
    }
    g.bench_function("load_to_0.95", |b| {
        b.iter(|| {
            let mut u = vec![0.0];
            follow_path_from(
                &mut Truss,
                &mut u,
                0.0,
                &targets,
                &NewtonSettings::default(),
                &Stepping::default(),
            )
            .unwrap_or_else(|e| panic!("{e}"));
            black_box(u)
        })
    });
    g.finish();
}

/// The reference scene on 4 slices at −0.001 and −0.003, `path` as given.
fn scene(path: &str) -> nonlin3d::Scene {
    let text = nonlin3d::scene::THESIS_SCENE
        .replace("slices = 8", "slices = 4")
        .replace(
            "strains = [-0.001, -0.002, -0.003, -0.004, -0.005]",
            "strains = [-0.001, -0.003]",
        )
        .replace("[analysis]", &format!("[analysis]\npath = \"{path}\""));
    nonlin3d::Scene::from_toml(&text).unwrap_or_else(|e| panic!("{e}"))
}

fn bench_scene(c: &mut Criterion) {
    let mut g = c.benchmark_group("arc_length/scene_4_slices");
    g.sample_size(10).measurement_time(Duration::from_secs(20));
    for path in ["load", "arc-length"] {
        g.bench_function(path, |b| {
            b.iter(|| {
                let r = nonlin3d::Analysis::new(scene(path))
                    .and_then(|a| a.run())
                    .unwrap_or_else(|e| panic!("{e}"));
                black_box(r.levels.len())
            })
        });
    }
    g.finish();
}

criterion_group!(benches, bench_truss, bench_scene);
criterion_main!(benches);
