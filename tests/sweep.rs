//! Parametric studies from the command line (`[sweep]`, `nonlin3d sweep plan|run|status|merge`,
//! `nonlin3d run` on a scene with `[sweep]`), on a coarse through-width scene of four cases
//! (about 0.3 s of CPU each): the plan, the runs in one and in two workers (the merged tables
//! equal byte for byte), one case at a time, resuming after a deleted
//! or killed case, failed cases in the table, bad input refused with nothing left behind. The
//! tables hold no wall time (that is study-wall.csv), so they compare byte for byte.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// Four cases: a ∈ {10, 15} mm × h ∈ {0.3, 0.4} mm, two strain levels, a criterion.
const STUDY: &str = r#"title = "sweep test"
[geometry]
kind = "through-width"
a_mm = 15.0
length_mm = 50.0
width_mm = 1.0
h_mm = 0.4
base_mm = 4.0
[material]
kind = "named"
name = "generic-graphite-epoxy"
homogenize = "quasi-isotropic"
[mesh]
inside = 6
outside = 4
across = 1
[loads]
strains = [-0.001, -0.002]
[criterion]
kind = "power-law"
g_ic = 10.0
g_iic = 30.0
[sweep]
"geometry.a_mm" = [10.0, 15.0]
"geometry.h_mm" = [0.3, 0.4]
"#;

fn tmp(name: &str) -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("sweep-{name}"));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn nonlin3d(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_nonlin3d"))
        .args(args)
        .output()
        .unwrap()
}

fn ok(args: &[&str]) -> String {
    let o = nonlin3d(args);
    assert!(
        o.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    String::from_utf8_lossy(&o.stdout).into_owned()
}

fn p(path: &Path) -> &str {
    path.to_str().unwrap()
}

fn scene(dir: &Path, text: &str) -> PathBuf {
    let path = dir.join("study.toml");
    std::fs::write(&path, text).unwrap();
    path
}

fn results(dir: &Path, case: usize) -> serde_json::Value {
    let text = std::fs::read_to_string(dir.join(format!("cases/{case:04}/results.json"))).unwrap();
    serde_json::from_str(&text).unwrap()
}

#[test]
fn one_worker_and_two_merge_to_the_same_table() {
    let d = tmp("workers");
    let s = scene(&d, STUDY);
    let (one, two) = (d.join("one"), d.join("two"));
    // `run` on a scene with [sweep]: plan, run (a worker per core), merge.
    let out = ok(&["run", p(&s), "--out", p(&two), "--threads", "2"]);
    assert!(out.contains("has a [sweep]: 4 cases planned"), "{out}");
    ok(&["sweep", "plan", p(&s), "--out", p(&one)]);
    let plan: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(one.join("plan.json")).unwrap()).unwrap();
    assert_eq!(plan["cases"].as_array().unwrap().len(), 4);
    // The last field varies fastest.
    assert_eq!(plan["cases"][1]["parameters"]["geometry.a_mm"], 10.0);
    assert_eq!(plan["cases"][1]["parameters"]["geometry.h_mm"], 0.4);
    ok(&["sweep", "run", p(&one), "--jobs", "1"]);
    let status = ok(&["sweep", "status", p(&one)]);
    assert!(status.trim_end().ends_with("4 complete"), "{status}");
    ok(&["sweep", "merge", p(&one)]);
    let read = |dir: &Path, f: &str| std::fs::read_to_string(dir.join(f)).unwrap();
    let csv = read(&one, "study.csv");
    // The tables hold no wall time (study-wall.csv does): equal byte for byte.
    assert_eq!(csv, read(&two, "study.csv"));
    assert_eq!(read(&one, "study.json"), read(&two, "study.json"));
    assert_eq!(read(&one, "study.svg"), read(&two, "study.svg"));
    assert!(!csv.contains("wall_s") && !read(&one, "study.json").contains("wall_s"));
    let wall = read(&one, "study-wall.csv");
    assert_eq!(wall.lines().next(), Some("case,status,wall_s"));
    for (case, line) in wall.lines().skip(1).enumerate() {
        let w = results(&one, case)["provenance"]["wall_s"]["total"].as_f64();
        assert_eq!(line, format!("{case},complete,{}", w.unwrap()));
    }
    assert_eq!(csv.lines().count(), 5, "{csv}");
    // Each row is its case's results.json: G_I at S = 0 of the last level.
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    for (case, line) in csv.lines().skip(1).enumerate() {
        let cells: Vec<&str> = line.split(',').collect();
        assert_eq!(cells[col("status")], "complete");
        let r = results(&one, case);
        let last = r["levels"].as_array().unwrap().last().unwrap();
        let at0 = last["front"]
            .as_array()
            .unwrap()
            .iter()
            .find(|f| f["s_mm"] == 0.0)
            .unwrap();
        assert_eq!(
            cells[col("g_i_s0")].parse::<f64>().unwrap(),
            at0["g_i"].as_f64().unwrap()
        );
        // Buckling is bracketed below the last level (−0.002) and the criterion reached.
        let to: f64 = cells[col("buckling_to")].parse().unwrap();
        assert!(to < 0.0 && to > -0.002, "{line}");
        assert!(!cells[col("critical_strain")].is_empty(), "{line}");
    }
}

#[test]
fn a_deleted_or_killed_case_is_run_again_and_only_it() {
    let d = tmp("resume");
    let s = scene(&d, STUDY);
    let dir = d.join("study");
    // One case alone, as a job-array task runs it.
    ok(&["sweep", "plan", p(&s), "--out", p(&dir)]);
    ok(&["sweep", "run", p(&dir), "--case", "2"]);
    let status = ok(&["sweep", "status", p(&dir)]);
    assert!(status.contains("1 complete, 3 missing"), "{status}");
    let bad = nonlin3d(&["sweep", "run", p(&dir), "--case", "4"]);
    assert_eq!(bad.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&bad.stderr).contains("--case 4: the study has cases 0 to 3"));
    ok(&["sweep", "run", p(&dir)]);
    ok(&["sweep", "merge", p(&dir)]);
    let before = std::fs::read_to_string(dir.join("study.csv")).unwrap();
    // Case 1 deleted, case 3 killed mid-run (results.json says incomplete).
    std::fs::remove_dir_all(dir.join("cases/0001")).unwrap();
    let path = dir.join("cases/0003/results.json");
    let text = std::fs::read_to_string(&path).unwrap();
    std::fs::write(
        &path,
        text.replacen("\"complete\": true", "\"complete\": false", 1),
    )
    .unwrap();
    let status = ok(&["sweep", "status", p(&dir)]);
    assert!(
        status.contains("2 complete, 1 incomplete, 1 missing"),
        "{status}"
    );
    let untouched = std::fs::metadata(dir.join("cases/0000/results.json"))
        .unwrap()
        .modified()
        .unwrap();
    // `run` on the scene again: the same plan is kept, the deleted case planned again.
    let o = nonlin3d(&["run", p(&s), "--out", p(&dir)]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let log = String::from_utf8_lossy(&o.stderr);
    assert_eq!(log.matches("complete already").count(), 2, "{log}");
    let again = std::fs::metadata(dir.join("cases/0000/results.json"))
        .unwrap()
        .modified()
        .unwrap();
    assert_eq!(untouched, again);
    let after = std::fs::read_to_string(dir.join("study.csv")).unwrap();
    assert_eq!(before, after);
}

#[test]
fn a_failed_case_is_listed_with_its_error() {
    let d = tmp("failed");
    // Two cases; the second's mesh would need thousands of GiB: refused by the memory estimate, at once.
    let text = STUDY.replace(
        "\"geometry.h_mm\" = [0.3, 0.4]\n",
        "\"mesh.inside\" = [6, 9000]\n\"mesh.across\" = [1, 9000]\n\
         zip = [[\"geometry.a_mm\", \"mesh.inside\", \"mesh.across\"]]\n",
    );
    let s = scene(&d, &text);
    let dir = d.join("study");
    let o = nonlin3d(&["run", p(&s), "--out", p(&dir)]);
    assert_eq!(o.status.code(), Some(1));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("1 of 2 cases failed (the first, case 1:"),
        "{err}"
    );
    let status = ok(&["sweep", "status", p(&dir)]);
    assert!(status.contains("1 complete, 1 failed"), "{status}");
    assert!(status.contains("would not fit in memory"), "{status}");
    let csv = std::fs::read_to_string(dir.join("study.csv")).unwrap();
    let row = csv.lines().nth(2).unwrap();
    assert!(row.starts_with("1,failed,15.0,9000,9000,,"), "{row}");
    assert!(row.contains("would not fit in memory"), "{row}");
}

#[test]
fn bad_studies_are_refused_naming_the_field_and_leave_nothing() {
    let d = tmp("bad");
    for (from, to, words) in [
        (
            "\"geometry.h_mm\"",
            "\"geometry.hh_mm\"",
            "\"geometry.hh_mm\" = 0.3: unknown field `hh_mm`",
        ),
        ("[0.3, 0.4]", "[]", "\"geometry.h_mm\" = []: an empty list"),
        (
            "[0.3, 0.4]",
            "[0.3, \"thick\"]",
            "\"geometry.h_mm\" = \"thick\": invalid type",
        ),
        (
            "[0.3, 0.4]",
            "[0.3, -0.4]",
            "case 1 (geometry.a_mm = 10.0, geometry.h_mm = -0.4)",
        ),
        (
            "\"geometry.h_mm\" = [0.3, 0.4]",
            "zip = [[\"geometry.a_mm\", \"x\"]]",
            "zip names 'x'",
        ),
    ] {
        let s = scene(&d, &STUDY.replace(from, to));
        let dir = d.join("study");
        let o = nonlin3d(&["sweep", "plan", p(&s), "--out", p(&dir)]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{to}: {err}");
        assert!(err.contains(words), "{to}: {err}");
        // Nothing half-planned: neither the folder nor a temporary beside it.
        let left: Vec<_> = std::fs::read_dir(&d)
            .unwrap()
            .flatten()
            .map(|e| e.file_name())
            .collect();
        assert_eq!(left, [std::ffi::OsString::from("study.toml")], "{to}");
    }
    // A folder holding something else, or another study's plan, is not planned over.
    let s = scene(&d, STUDY);
    let dir = d.join("study");
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("notes.txt"), "mine").unwrap();
    let o = nonlin3d(&["sweep", "plan", p(&s), "--out", p(&dir)]);
    assert_eq!(o.status.code(), Some(2));
    assert_eq!(
        std::fs::read_to_string(dir.join("notes.txt")).unwrap(),
        "mine"
    );
    std::fs::remove_file(dir.join("notes.txt")).unwrap();
    ok(&["sweep", "plan", p(&s), "--out", p(&dir)]);
    let other = scene(&d, &STUDY.replace("[10.0, 15.0]", "[10.0, 12.0]"));
    let o = nonlin3d(&["sweep", "plan", p(&other), "--out", p(&dir)]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("holds another study's plan"));
    // A folder that is not a study.
    let o = nonlin3d(&["sweep", "status", p(&d)]);
    assert_eq!(o.status.code(), Some(2));
}

/// `export` (and every command that takes one scene) refuses a study by saying what it is and
/// what to run, not with toml's "unknown field `sweep`"; a planned case's scene.toml exports.
#[test]
fn export_of_a_study_says_what_to_do() {
    let d = tmp("export");
    let path = scene(&d, STUDY);
    let inp = d.join("study.inp");
    let o = nonlin3d(&["export", p(&path), "--inp", p(&inp)]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("[sweep] table") && err.contains("sweep plan"),
        "{err}"
    );
    assert!(!err.contains("unknown field"), "{err}");
    assert!(!inp.exists());
    let plan = d.join("plan");
    ok(&["sweep", "plan", p(&path), "--out", p(&plan)]);
    let case = plan.join("cases/0000/scene.toml");
    ok(&["export", p(&case), "--inp", p(&inp)]);
    assert!(inp.exists());
}
