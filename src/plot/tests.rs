//! The plots' texts: every legend entry and axis label is in the SVG (a figure that loses its
//! legend fails here), and the files are well-formed XML.

#![allow(clippy::unwrap_used)]

use super::*;
use crate::results::{Critical, LevelResult, ModelSummary, Timings};
use nonlin3d_vcct::FrontRelease;

fn point(s_mm: f64, g_i: f64, opening: f64) -> FrontRelease {
    FrontRelease {
        node: 0,
        s: s_mm * 1e-3,
        theta_deg: 0.0,
        x: 0.0,
        y: 0.0,
        delta_a: 1e-3,
        area: 1e-6,
        g_i,
        g_ii: 0.5 * g_i,
        g_iii: 0.0,
        g_t: 1.5 * g_i,
        opening,
    }
}

/// Two strain levels, front points open, overlapped (opening < 0) and closed by contact; an
/// index at the open points and an onset at the second level.
fn results() -> Results {
    let levels: Vec<LevelResult> = [(-0.001, 10.0), (-0.002, 60.0)]
        .iter()
        .map(|&(e, g)| {
            let front = [
                point(0.0, g, 1e-4),
                point(5.0, 0.8 * g, 1e-4),
                point(10.0, 0.5 * g, -1e-4),
                point(15.0, 0.1 * g, 1e-4),
            ];
            let mut l = LevelResult::new(e, 0.1 * e, -0.05 * e, &[], &front, vec![]);
            l.front[3].faces = Faces::Closed;
            for r in &mut l.front {
                r.failure_index = r.is_open().then(|| r.g_t / 60.0);
            }
            l
        })
        .collect();
    Results {
        title: "synthetic circle".into(),
        quantity: "strain".into(),
        complete: true,
        stopped: None,
        model: ModelSummary {
            nodes: 0,
            cells: 0,
            dofs: 0,
            front_points: 4,
            perturbation_n: None,
            perturbed_at: None,
            substructure: None,
        },
        levels,
        warnings: vec![],
        accuracy: None,
        critical: Some(Critical {
            strain: -0.0016,
            after: None,
            s_mm: 0.0,
            level: 1,
            index: 1.5,
            mode_mix: 1.0 / 3.0,
            g_i: 60.0,
            g_ii: 30.0,
            g_iii: 0.0,
        }),
        timings: Timings {
            mesh_s: 0.0,
            setup_s: 0.0,
            solve_s: 0.0,
            vcct_s: 0.0,
            output_s: 0.0,
            threads: 1,
            mixed_precision: None,
            factor: Vec::new(),
        },
        model_data: None,
        coarser: None,
        provenance: None,
    }
}

/// Every `<text>` of an SVG, after checking that the file parses as XML.
fn texts(path: &Path) -> Vec<String> {
    let svg = std::fs::read_to_string(path).unwrap();
    let doc = roxmltree::Document::parse(&svg).unwrap();
    doc.descendants()
        .filter(|n| n.has_tag_name("text"))
        .map(|n| n.text().unwrap_or("").to_string())
        .collect()
}

fn contains(texts: &[String], wanted: &str) -> bool {
    texts.iter().any(|t| t.contains(wanted))
}

#[test]
fn every_figure_names_its_markers_axes_and_levels() {
    let dir = std::env::temp_dir().join(format!("nonlin3d-plots-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let r = results();
    let g = dir.join("g_t.svg");
    release_rate_plot(&r, &g, "G_T", |r| r.g_t).unwrap();
    let f = dir.join("failure_index.svg");
    failure_index_plot(&r, &f).unwrap();
    let d = dir.join("deflection.svg");
    deflection_plot(&r, &d).unwrap();
    let o = dir.join("overview.svg");
    overview_plot(&r, &o).unwrap();
    let markers = [
        "faces open: G physical",
        "faces overlap (dashed): G not physical,",
        "faces held closed by contact: G_I = 0",
    ];
    let levels = ["ε_x = -0.001", "ε_x = -0.002"];
    for (path, y_axis) in [
        (&g, "G_T, energy release rate (J/m²)"),
        (&o, "G_T, total energy release rate (J/m²)"),
    ] {
        let t = texts(path);
        for wanted in markers.iter().chain(&levels) {
            assert!(
                contains(&t, wanted),
                "{}: no {wanted:?} in {t:?}",
                path.display()
            );
        }
        assert!(contains(
            &t,
            "S, arc length along the front from the x axis (mm)"
        ));
        assert!(contains(&t, y_axis), "{}", path.display());
        assert!(contains(
            &t,
            "synthetic circle — ε_x = -0.001 … -0.002 (2 levels)"
        ));
    }
    // The failure index: no index where the faces overlap, so no overlap entry.
    let t = texts(&f);
    for wanted in [
        markers[0],
        markers[2],
        levels[0],
        levels[1],
        "failure index of the scene's criterion (–)",
        "index = 1: growth onset",
        "growth onset ε_x = -0.0016 at S = 0.00 mm",
        "(cross: index 1.50 at ε_x = -0.002,",
        "mode mix (G_II + G_III)/G_T = 0.33 there)",
    ] {
        assert!(
            contains(&t, wanted),
            "failure index: no {wanted:?} in {t:?}"
        );
    }
    assert!(!contains(&t, markers[1]));
    for path in [&d, &o] {
        let t = texts(path);
        for wanted in [
            "applied compressive strain |ε_x| (–)",
            "deflection (mm)",
            "|w| at the centre, sublaminate top (base included)",
            "largest crack-face separation |w_upper − w_lower|",
        ] {
            assert!(contains(&t, wanted), "{}: no {wanted:?}", path.display());
        }
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn titles_name_loads_in_newtons() {
    let mut r = results();
    r.quantity = "load_n".into();
    r.levels.truncate(1);
    r.levels[0].value = 100.0;
    assert_eq!(applied(&r), "P = 100 N");
    r.levels.push(r.levels[0].clone());
    r.levels[1].value = 300.0;
    assert_eq!(applied(&r), "P = 100 … 300 N (2 levels)");
    assert_eq!(applied_axis(&r), "applied load P (N)");
}
