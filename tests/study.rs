//! `nonlin3d study` end to end on a tiny study (seconds): the files it writes and what they
//! hold, the references from the family, the Pareto flags, bad knobs refused before anything
//! runs. The Richardson and Pareto kernels have their unit tests beside them
//! (`src/study/richardson.rs`, `src/study/pareto.rs`).

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn tmp(name: &str) -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("study-{name}"));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn nonlin3d(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_nonlin3d"))
        .current_dir(dir)
        .args(args)
        .output()
        .unwrap()
}

/// One level past buckling, no contact: the smallest run that has a front to measure.
const KNOBS: &str = r#"
title = "tiny study"
[common.loads]
strains = [-0.004]
[common.contact]
crack_faces = "off"

[[case]]
name = "coarse"
family = true
mesh = { slices = 4, inside = 2, outside = 2, base_layers = 1 }

[[case]]
name = "medium"
family = true
mesh = { slices = 4, inside = 3, outside = 3, base_layers = 1 }

[[case]]
name = "fine"
family = true
mesh = { slices = 6, inside = 3, outside = 3, base_layers = 1 }

[[case]]
name = "hex8, bfgs"
mesh = { element = "hex8", slices = 4, inside = 2, outside = 2, base_layers = 1 }
analysis = { integration = "selective-reduced", newton = "bfgs" }
"#;

fn setup(name: &str, knobs: &str) -> (PathBuf, Output) {
    let dir = tmp(name);
    std::fs::write(dir.join("scene.toml"), nonlin3d::scene::THESIS_SCENE).unwrap();
    std::fs::write(dir.join("knobs.toml"), knobs).unwrap();
    let out = nonlin3d(
        &dir,
        &[
            "study",
            "scene.toml",
            "--knobs",
            "knobs.toml",
            "--out",
            "st",
            "--jobs",
            "2",
        ],
    );
    (dir, out)
}

#[test]
fn a_tiny_study_writes_its_files_and_they_agree() {
    let (dir, out) = setup("tiny", KNOBS);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{stdout}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let st = dir.join("st");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(st.join("study.json")).unwrap()).unwrap();
    let cases = json["cases"].as_array().unwrap();
    let names: Vec<&str> = cases.iter().map(|c| c["name"].as_str().unwrap()).collect();
    assert_eq!(names, ["coarse", "medium", "fine", "hex8, bfgs"]);
    for c in cases {
        assert!(c["failed"].is_null(), "{c}");
        assert!(c["dofs"].as_u64().unwrap() > 0 && c["wall_s"].as_f64().unwrap() > 0.0);
        // Each case ran on one thread of its own: its CPU time cannot exceed its wall time
        // (5 % for the clocks' granularity).
        let cpu = c["cpu_s"].as_f64().unwrap();
        assert!(
            cpu > 0.0 && cpu <= 1.05 * c["wall_s"].as_f64().unwrap() + 0.01,
            "{c}"
        );
    }
    // The family's DOFs rise coarse → fine, so h falls; the knobs are recorded.
    let dofs: Vec<u64> = cases[..3]
        .iter()
        .map(|c| c["dofs"].as_u64().unwrap())
        .collect();
    assert!(dofs[0] < dofs[1] && dofs[1] < dofs[2], "{dofs:?}");
    assert!(
        cases[3]["knobs"]
            .as_str()
            .unwrap()
            .contains("newton=\"bfgs\"")
    );
    // G_T max's reference: Richardson's limit or the finest value, and each case's error is
    // its value against it.
    let refs = json["references"].as_array().unwrap();
    assert_eq!(refs[0]["quantity"], "g_t_max");
    let r = refs[0]["fit"]["reference"].as_f64().unwrap();
    for c in cases {
        let v = c["values"]["g_t_max"].as_f64().unwrap();
        let e = c["errors"]["g_t_max"].as_f64().unwrap();
        assert!((e - (v - r) / r.abs()).abs() < 1e-12, "{c}");
    }
    // A non-asymptotic fit says why.
    for f in refs.iter().map(|r| &r["fit"]).filter(|f| !f.is_null()) {
        assert_eq!(
            f["asymptotic"].as_bool().unwrap(),
            f["note"].is_null(),
            "{f}"
        );
    }
    // The Pareto flags: a flagged case is dominated by none; an unflagged one by some.
    let pt = |c: &serde_json::Value| {
        (
            c["cpu_s"].as_f64().unwrap(),
            c["worst_g_error"].as_f64().unwrap(),
        )
    };
    for c in cases {
        let (t, e) = pt(c);
        let dominated = cases.iter().any(|o| {
            let (t2, e2) = pt(o);
            t2 <= t && e2 <= e && (t2 < t || e2 < e)
        });
        assert_eq!(c["pareto"].as_bool().unwrap(), !dominated, "{c}");
    }
    // The CSV: a header and a row per case, the quoted name read back whole.
    let csv = std::fs::read_to_string(st.join("study.csv")).unwrap();
    let lines: Vec<&str> = csv.lines().collect();
    assert_eq!(lines.len(), 5);
    assert!(lines[0].starts_with("case,family,h,dofs,wall_s,cpu_s"));
    assert!(
        lines[4].starts_with("\"hex8, bfgs\",false,"),
        "{}",
        lines[4]
    );
    // The plot: the front and its axes with units.
    let svg = std::fs::read_to_string(st.join("study.svg")).unwrap();
    for needle in [
        "Pareto front",
        "CPU time of the case, one thread (s)",
        "(%)",
        "coarse",
    ] {
        assert!(svg.contains(needle), "study.svg lacks {needle:?}");
    }
    // The terminal table names every case and the references.
    for needle in [
        "coarse",
        "hex8, bfgs",
        "references (family of 3 meshes",
        "G_T max",
    ] {
        assert!(stdout.contains(needle), "{stdout}");
    }
}

#[test]
fn bad_knobs_are_refused_before_anything_runs() {
    let bad = KNOBS.replace("slices = 6", "slice = 6");
    let (dir, out) = setup("bad", &bad);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("case 'fine'") && stderr.contains("slice"),
        "{stderr}"
    );
    assert!(!dir.join("st").exists());
    let (_, out) = setup(
        "unknown",
        &KNOBS.replace("[common.contact]", "[common.geometry]"),
    );
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("geometry") && stderr.contains("knobs"),
        "{stderr}"
    );
}
