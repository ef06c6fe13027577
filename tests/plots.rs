//! The figures and the growth onset of a run as a user gets them (issue 22 plots, issue 21 §4):
//! one CLI run of the reference circle on 4 slices at ε = −0.001, −0.003, −0.005 with a
//! Benzeggagh–Kenane criterion. Every SVG parses as XML and names its axes (with units), its
//! levels and every kind of front marker drawn; the failure index column of `front_K.csv` is
//! results.json's; the critical strain's location, level, index and mode mix agree with the
//! front table of that level.

use std::path::{Path, PathBuf};
use std::process::Command;

fn run(name: &str) -> (PathBuf, String) {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("plots-{name}"));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let scene = nonlin3d::scene::THESIS_SCENE
        .replace("slices = 8", "slices = 4")
        .replace(
            "strains = [-0.001, -0.002, -0.003, -0.004, -0.005]",
            "strains = [-0.001, -0.003, -0.005]",
        )
        + "\n[criterion]\nkind = \"benzeggagh-kenane\"\ng_ic = 100.0\ng_iic = 500.0\neta = 2.0\n";
    std::fs::write(dir.join("s.toml"), scene).unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_nonlin3d"))
        .current_dir(&dir)
        .args(["run", "--out", "out", "s.toml"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    (
        dir.join("out"),
        String::from_utf8_lossy(&o.stdout).into_owned(),
    )
}

/// Every `<text>` of an SVG, after checking that it parses as XML.
fn texts(path: &Path) -> Vec<String> {
    let svg = std::fs::read_to_string(path).unwrap();
    let doc = roxmltree::Document::parse(&svg)
        .unwrap_or_else(|e| panic!("{}: not XML: {e}", path.display()));
    doc.descendants()
        .filter(|n| n.has_tag_name("text"))
        .map(|n| n.text().unwrap_or("").to_string())
        .collect()
}

fn has(texts: &[String], wanted: &str) -> bool {
    texts.iter().any(|t| t.contains(wanted))
}

#[test]
fn figures_and_the_growth_onset_of_a_run() {
    let (out, stdout) = run("onset");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("results.json")).unwrap()).unwrap();
    let levels = json["levels"].as_array().unwrap();
    assert_eq!(levels.len(), 3);
    let faces = |state: &str| {
        levels
            .iter()
            .flat_map(|l| l["front"].as_array().unwrap())
            .any(|r| r["faces"] == state)
    };
    // The legend entries the face states of this run call for, and no other.
    let markers = [
        ("open", "faces open: G physical"),
        ("overlapped", "faces overlap (dashed): G not physical,"),
        ("closed", "faces held closed by contact: G_I = 0"),
    ];
    let title = "30 mm circular embedded delamination (thesis Fig. 5.1.3) — ε_x = -0.001 … -0.005 (3 levels)";
    for (file, y_axis) in [
        ("g_i.svg", "G_I, energy release rate (J/m²)"),
        ("g_ii.svg", "G_II, energy release rate (J/m²)"),
        ("g_t.svg", "G_T, energy release rate (J/m²)"),
        ("overview.svg", "G_T, total energy release rate (J/m²)"),
    ] {
        let t = texts(&out.join(file));
        assert!(has(&t, y_axis), "{file}: no {y_axis:?}");
        assert!(has(
            &t,
            "S, arc length along the front from the x axis (mm)"
        ));
        assert!(has(&t, title), "{file}: no title {title:?} in {t:?}");
        for level in ["ε_x = -0.001", "ε_x = -0.003", "ε_x = -0.005"] {
            assert!(has(&t, level), "{file}: no legend entry {level:?}");
        }
        for (state, entry) in markers {
            assert_eq!(has(&t, entry), faces(state), "{file}: {state} {entry:?}");
        }
    }
    for file in ["deflection.svg", "overview.svg"] {
        let t = texts(&out.join(file));
        for wanted in [
            "applied compressive strain |ε_x| (–)",
            "deflection (mm)",
            "|w| at the centre, sublaminate top (base included)",
        ] {
            assert!(has(&t, wanted), "{file}: no {wanted:?}");
        }
    }
    let t = texts(&out.join("failure_index.svg"));
    for wanted in [
        "failure index of the scene's criterion (–)",
        "index = 1: growth onset",
        "(cross: index 2.",
    ] {
        assert!(has(&t, wanted), "failure_index.svg: no {wanted:?} in {t:?}");
    }

    // front_K.csv's failure_index column is results.json's, point by point. Both files write
    // the shortest round-trip form of the same f64; serde_json reads it back without its
    // `float_roundtrip` feature, within 1 ulp: 1e-15 relative.
    for (k, level) in levels.iter().enumerate() {
        let csv = std::fs::read_to_string(out.join(format!("front_{k}.csv"))).unwrap();
        let mut lines = csv.lines();
        let head: Vec<&str> = lines.next().unwrap().split(',').collect();
        let col = head.iter().position(|h| *h == "failure_index").unwrap();
        let front = level["front"].as_array().unwrap();
        let rows: Vec<&str> = lines.collect();
        assert_eq!(rows.len(), front.len());
        for (row, r) in rows.iter().zip(front) {
            let cell = row.split(',').nth(col).unwrap();
            match r["failure_index"].as_f64() {
                Some(f) => {
                    let v: f64 = cell.parse().unwrap();
                    assert!(
                        (v - f).abs() <= 1e-15 * f.abs(),
                        "level {k}: {v} against {f}"
                    );
                }
                None => assert_eq!(cell, "", "level {k}"),
            }
        }
    }

    // The critical strain: between the levels around it (B–K with these toughnesses reaches 1
    // at S = 0 between −0.003 and −0.005, tests/pipeline.rs), the point's index and mode mix
    // those of its front row at the first level reaching 1.
    let c = &json["critical"];
    let level = c["level"].as_u64().unwrap() as usize;
    assert_eq!(level, 2);
    let strain = c["strain"].as_f64().unwrap();
    assert!(strain < -0.003 && strain > -0.005, "{strain}");
    let row = levels[level]["front"]
        .as_array()
        .unwrap()
        .iter()
        .find(|r| r["s_mm"] == c["s_mm"])
        .unwrap();
    // The same f64s read back twice: equal. The mode mix (G_II + G_III)/(G_I + G_II + G_III)
    // from values read within 1 ulp each: a few ulps, 1e-14 relative.
    assert_eq!(c["index"], row["failure_index"]);
    let g = |k: &str| row[k].as_f64().unwrap();
    assert_eq!(c["g_i"].as_f64().unwrap(), g("g_i"));
    let mix = (g("g_ii") + g("g_iii")) / (g("g_i") + (g("g_ii") + g("g_iii")));
    assert!((c["mode_mix"].as_f64().unwrap() - mix).abs() <= 1e-14 * mix);
    assert!(
        stdout.contains(&format!("mode mix (G_II + G_III)/G_T = {mix:.3}")),
        "{stdout}"
    );
}
