//! The output folder as a user meets it (issue: what an FE user expects of the outputs): a
//! second run into the same folder leaves nothing of the first that it did not write itself and
//! never removes a user's file; an unwritable `--out` fails before anything is computed, naming
//! the path; `solve` has its own default folder; results.json and summary.json say where they
//! came from (program, input hash, the scene with every default filled in, solver, times,
//! memory); `status.sta` and `convergence.cvg` hold a line per attempt and per iteration.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn tmp(name: &str) -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("cli-outputs-{name}"));
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

/// The reference scene on 4 slices with the given strain list, written to `dir/NAME`.
fn scene(dir: &Path, name: &str, strains: &str) -> PathBuf {
    let text = nonlin3d::scene::THESIS_SCENE
        .replace("slices = 8", "slices = 4")
        .replace(
            "strains = [-0.001, -0.002, -0.003, -0.004, -0.005]",
            &format!("strains = {strains}"),
        );
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

/// Every file below `dir` (one level of subfolders), relative.
fn files(dir: &Path) -> BTreeSet<String> {
    let mut out = BTreeSet::new();
    for e in std::fs::read_dir(dir).unwrap().flatten() {
        let name = e.file_name().to_string_lossy().into_owned();
        if e.file_type().unwrap().is_dir() {
            for i in std::fs::read_dir(e.path()).unwrap().flatten() {
                out.insert(format!("{name}/{}", i.file_name().to_string_lossy()));
            }
        } else {
            out.insert(name);
        }
    }
    out
}

fn json(path: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

/// The files manifest.json lists.
fn manifest(dir: &Path) -> BTreeSet<String> {
    json(&dir.join("manifest.json"))["files"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| f.as_str().unwrap().to_string())
        .collect()
}

/// Two levels, then one level into the same folder, with a user's files put there between
/// (one named like ours): afterwards the folder holds exactly the second run's files (its
/// manifest), the manifest itself and the user's files — no `front_1.csv` or `model_1.vtu`
/// of the first run.
#[test]
fn a_second_run_leaves_no_file_of_the_first() {
    let dir = tmp("rerun");
    let first = scene(&dir, "two.toml", "[-0.001, -0.002]");
    let o = nonlin3d(
        &dir,
        &["run", "-q", "--out", "out", first.to_str().unwrap()],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let out = dir.join("out");
    assert!(out.join("front_1.csv").exists() && out.join("model_1.vtu").exists());
    assert_eq!(files(&out), {
        let mut m = manifest(&out);
        m.insert("manifest.json".into());
        m
    });
    std::fs::write(out.join("notes.txt"), "the user's").unwrap();
    std::fs::write(out.join("front_9.csv"), "the user's, named like ours").unwrap();
    let second = scene(&dir, "one.toml", "[-0.001]");
    let o = nonlin3d(
        &dir,
        &["run", "-q", "--out", "out", second.to_str().unwrap()],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let mut expected = manifest(&out);
    assert!(
        !expected.contains("front_9.csv"),
        "a user's file listed as ours"
    );
    expected.extend(["manifest.json", "notes.txt", "front_9.csv"].map(String::from));
    assert_eq!(files(&out), expected);
    assert!(!out.join("front_1.csv").exists() && !out.join("model_1.vtu").exists());
    // A third run removes the second's files and still keeps the user's.
    let o = nonlin3d(
        &dir,
        &["run", "-q", "--out", "out", second.to_str().unwrap()],
    );
    assert!(o.status.success());
    assert!(out.join("notes.txt").exists() && out.join("front_9.csv").exists());
}

/// The same for `solve`: a three-step deck, then a one-step deck into the same folder: no
/// `step-3/` is left, and no VTU of the first beyond the second's.
#[test]
fn a_second_solve_leaves_no_step_of_the_first() {
    let dir = tmp("resolve");
    let decks = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/decks");
    let two = decks.join("three_steps.inp");
    let one = decks.join("uniaxial_box.inp");
    let o = nonlin3d(
        &dir,
        &["solve", two.to_str().unwrap(), "--out", "out", "-q"],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let out = dir.join("out");
    let steps = json(&out.join("summary.json"))["steps"]
        .as_array()
        .unwrap()
        .len();
    assert!(steps >= 2, "the deck has {steps} steps");
    assert!(out.join(format!("step-{steps}")).exists());
    let o = nonlin3d(
        &dir,
        &["solve", one.to_str().unwrap(), "--out", "out", "-q"],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let mut expected = manifest(&out);
    expected.insert("manifest.json".into());
    assert_eq!(files(&out), expected);
    assert!(!out.join(format!("step-{steps}")).exists());
}

/// An `--out` that cannot be made (below a regular file) fails with exit 2 before the analysis:
/// the message names the path, nothing is printed on stdout (not even the scene's title) and
/// no status file is started; the same for `solve`.
#[test]
fn an_unwritable_out_fails_before_the_analysis() {
    let dir = tmp("unwritable");
    std::fs::write(dir.join("file"), "").unwrap();
    let bad = dir.join("file/out");
    let o = nonlin3d(&dir, &["run", "--out", bad.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains(&bad.display().to_string()), "{err}");
    assert!(
        o.stdout.is_empty(),
        "{}",
        String::from_utf8_lossy(&o.stdout)
    );
    let deck = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/decks/uniaxial_box.inp");
    let o = nonlin3d(
        &dir,
        &[
            "solve",
            deck.to_str().unwrap(),
            "--out",
            bad.to_str().unwrap(),
        ],
    );
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains(&bad.display().to_string()), "{err}");
    assert!(o.stdout.is_empty());
}

/// `solve` without `--out` writes to `nonlin3d-solve-out`, not to run's `nonlin3d-out`.
#[test]
fn solve_has_its_own_default_folder() {
    let dir = tmp("default");
    let deck = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/decks/uniaxial_box.inp");
    let o = nonlin3d(&dir, &["solve", "-q", deck.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(dir.join("nonlin3d-solve-out/summary.json").exists());
    assert!(!dir.join("nonlin3d-out").exists());
}

/// results.json's provenance: this program's version, the scene's SHA-256 (as `sha256sum`
/// prints it), the scene with every default filled in (it reads back as the same scene), the
/// solver, the threads, a total time at least the solve's and a peak memory above the
/// model's own size.
#[test]
fn results_say_where_they_came_from() {
    let dir = tmp("provenance");
    let path = scene(&dir, "scene.toml", "[-0.001]");
    let o = nonlin3d(&dir, &["run", "-q", "--out", "out", path.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v = json(&dir.join("out/results.json"));
    let p = &v["provenance"];
    assert_eq!(
        p["program"],
        format!("nonlin3d {}", env!("CARGO_PKG_VERSION"))
    );
    let sum = Command::new("sha256sum").arg(&path).output().unwrap();
    let sum = String::from_utf8_lossy(&sum.stdout);
    assert_eq!(p["input"]["sha256"], sum.split_whitespace().next().unwrap());
    let text = std::fs::read_to_string(&path).unwrap();
    let scene = nonlin3d::Scene::from_toml(&text).unwrap();
    let resolved: nonlin3d::Scene = serde_json::from_value(p["scene"].clone()).unwrap();
    assert_eq!(resolved, scene);
    // Every default is written out: the resolved scene names keys the file does not.
    assert!(p["scene"]["analysis"]["max_attempts"].is_number());
    assert!(!text.contains("max_attempts"));
    assert!(p["solver"].as_str().unwrap().contains("LDL"));
    assert!(p["threads"].as_u64().unwrap() >= 1);
    let total = p["wall_s"]["total"].as_f64().unwrap();
    assert!(total >= v["timings"]["solve_s"].as_f64().unwrap());
    // The model's DOFs as f64 alone: a lower bound on the peak.
    let dofs = v["model"]["dofs"].as_u64().unwrap();
    assert!(p["peak_memory_bytes"].as_u64().unwrap() > 8 * dofs);
}

/// A deck's status files against its summary.json: `status.sta` has one line per attempt of
/// every step and `convergence.cvg` one per Newton iteration, with the same counts as the
/// summary's increments; summary.json carries the deck's SHA-256.
#[test]
fn status_files_agree_with_the_summary() {
    let dir = tmp("status");
    let deck = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/decks/amplitude_cload.inp");
    let o = nonlin3d(
        &dir,
        &["solve", "-q", deck.to_str().unwrap(), "--out", "out"],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let out = dir.join("out");
    let v = json(&out.join("summary.json"));
    let (mut attempts, mut iterations) = (0, 0);
    for step in v["steps"].as_array().unwrap() {
        for inc in step["increments"].as_array().unwrap() {
            attempts += 1;
            iterations += inc["iterations"].as_u64().unwrap() as usize;
        }
    }
    let sta = std::fs::read_to_string(out.join("status.sta")).unwrap();
    let cvg = std::fs::read_to_string(out.join("convergence.cvg")).unwrap();
    assert!(sta.starts_with("step,increment,attempt,"));
    assert_eq!(sta.lines().count() - 1, attempts, "{sta}");
    assert_eq!(cvg.lines().count() - 1, iterations, "{cvg}");
    // The last line of each step is its last converged increment.
    let steps = v["steps"].as_array().unwrap().len();
    assert!(sta.lines().any(|l| l.starts_with(&format!("{steps},"))));
    let sum = Command::new("sha256sum").arg(&deck).output().unwrap();
    let sum = String::from_utf8_lossy(&sum.stdout);
    assert_eq!(
        v["provenance"]["input"]["sha256"],
        sum.split_whitespace().next().unwrap()
    );
}
