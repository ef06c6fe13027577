//! Nothing lost, nothing wrong accepted, for decks (issue items 1 and 4; docs/RELIABILITY.md,
//! "Decks"): `nonlin3d solve` refuses an inverted element, a deck without a step and an empty
//! set in use with exit status 2 before solving; writes each increment as it converges; a
//! failed step, SIGINT or SIGTERM leaves every converged increment with `"complete": false`
//! and the reason in `"stopped"`; SIGKILL never leaves a summary.json that claims to be
//! complete; no half-written file is ever visible. Exit codes: 0, 1, 2, 130, 143.

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::time::{Duration, Instant};

/// Three NLGEOM steps of 50 fixed increments each (tests/decks/README.md).
const SLOW: &str = "tests/decks/three_steps.inp";

fn tmp(name: &str) -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("deck-{name}"));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// `text` as `dir/deck.inp`, beside the mesh it includes.
fn deck_in(dir: &Path, text: &str) -> PathBuf {
    std::fs::copy(
        "tests/decks/cantilever_mesh.inp",
        dir.join("cantilever_mesh.inp"),
    )
    .unwrap();
    let p = dir.join("deck.inp");
    std::fs::write(&p, text).unwrap();
    p
}

fn command(deck: &Path, out: &Path) -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_nonlin3d"));
    c.arg("solve").arg(deck).arg("--out").arg(out);
    c
}

fn solve(deck: &Path, out: &Path) -> Output {
    command(deck, out).output().unwrap()
}

fn start(deck: &Path, out: &Path, threads: usize) -> Child {
    command(deck, out)
        .arg("--threads")
        .arg(threads.to_string())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap()
}

fn line_of(text: &str, start: &str) -> usize {
    text.lines().position(|l| l.starts_with(start)).unwrap() + 1
}

fn summary(out: &Path) -> serde_json::Value {
    let text = std::fs::read_to_string(out.join("summary.json")).unwrap();
    serde_json::from_str(&text).unwrap_or_else(|e| panic!("summary.json does not parse: {e}"))
}

/// Every file in the output folder and its step folders parses as what it claims to be (a CSV
/// has the same number of fields on every line), and none is a leftover temporary.
fn all_files_whole(out: &Path) {
    for entry in std::fs::read_dir(out).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            all_files_whole(&path);
            continue;
        }
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        assert!(!name.ends_with(".partial"), "leftover {name}");
        let text = std::fs::read_to_string(&path).unwrap();
        if name.ends_with(".json") {
            serde_json::from_str::<serde_json::Value>(&text).unwrap();
        } else if name.ends_with(".csv") {
            assert!(text.ends_with('\n'), "{name} cut short");
            let cols = text.lines().next().unwrap().split(',').count();
            assert!(text.lines().all(|l| l.split(',').count() == cols), "{name}");
        }
    }
}

/// What summary.json says agrees with the files: a step's displacements exist exactly when it
/// is complete, each table holds the increments listed for it, and the last step's
/// displacements at the top only after a complete solve.
fn files_agree_with_summary(out: &Path, v: &serde_json::Value) {
    for s in v["steps"].as_array().unwrap() {
        let k = s["step"].as_u64().unwrap();
        let d = out.join(format!("step-{k}/displacements.csv"));
        assert_eq!(s["complete"] == true, d.exists(), "step {k}: {d:?}");
        for o in s["outputs"].as_array().unwrap() {
            let text = std::fs::read_to_string(out.join(o["file"].as_str().unwrap())).unwrap();
            let mut written: Vec<u64> = text
                .lines()
                .skip(1)
                .map(|l| l.split(',').next().unwrap().parse().unwrap())
                .collect();
            written.dedup();
            let listed: Vec<u64> = o["increments"]
                .as_array()
                .unwrap()
                .iter()
                .map(|i| i.as_u64().unwrap())
                .collect();
            assert_eq!(written, listed, "{}", o["file"]);
        }
    }
    assert_eq!(
        v["complete"] == true,
        out.join("displacements.csv").exists()
    );
}

/// Waits until summary.json satisfies `ready` (or the child ends).
fn wait_until(
    out: &Path,
    child: &mut Child,
    what: &str,
    ready: impl Fn(&serde_json::Value) -> bool,
) {
    let t = Instant::now();
    while t.elapsed() < Duration::from_secs(120) {
        if child.try_wait().unwrap().is_some() {
            panic!("the solve ended before {what}");
        }
        if let Ok(text) = std::fs::read_to_string(out.join("summary.json"))
            && let Ok(v) = serde_json::from_str::<serde_json::Value>(&text)
            && ready(&v)
        {
            return;
        }
        std::thread::sleep(Duration::from_millis(10));
    }
    panic!("not {what} after 120 s");
}

/// Step 1 complete.
fn after_step_1(v: &serde_json::Value) -> bool {
    v["steps"][0]["complete"] == true
}

/// Step 2 a fifth done.
fn within_step_2(v: &serde_json::Value) -> bool {
    v["steps"][1]["increments"]
        .as_array()
        .is_some_and(|i| i.len() >= 10)
}

fn signal(child: &Child, name: &str) {
    let ok = Command::new("kill")
        .args([&format!("-{name}"), &child.id().to_string()])
        .status()
        .unwrap()
        .success();
    assert!(ok, "kill -{name}");
}

/// Two corners of element 1 of the cantilever swapped: 2 ↔ 4 makes det J negative at
/// integration points; 1 ↔ 2 keeps it positive at all 27 (the kernels integrate it, and the
/// answer changes: max |u_z| 4.32 mm against 4.77 mm) but folds the element at its corners.
/// Both are refused with the element's deck id and line, before anything is written.
#[test]
fn an_inverted_element_is_refused_by_id_and_line() {
    let dir = tmp("inverted");
    let base = std::fs::read_to_string("tests/decks/cantilever_nlgeom.inp").unwrap();
    let first = "1, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10,";
    let line = line_of(&base, first);
    for (swapped, at) in [
        ("1, 1, 4, 3, 2, 5, 6, 7, 8, 9, 10,", "integration point"),
        ("1, 2, 1, 3, 4, 5, 6, 7, 8, 9, 10,", "at its node"),
    ] {
        let deck = dir.join("inverted.inp");
        std::fs::write(&deck, base.replacen(first, swapped, 1)).unwrap();
        let out = dir.join("out");
        let o = solve(&deck, &out);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{err}");
        let want = format!("line {line}, *ELEMENT data: element 1 (C3D20): Jacobian determinant");
        assert!(
            err.contains(&want) && err.contains(at),
            "{want} … {at} not in {err}"
        );
        assert!(!out.exists(), "output written for a deck that was refused");
    }
}

#[test]
fn a_deck_without_a_step_is_refused() {
    let dir = tmp("no-step");
    let text = std::fs::read_to_string("tests/decks/cantilever_nlgeom.inp").unwrap();
    let end = text.find("*STEP").unwrap();
    let deck = dir.join("no-step.inp");
    std::fs::write(&deck, &text[..end]).unwrap();
    let o = solve(&deck, &dir.join("out"));
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("*STEP") && err.contains("no step"), "{err}");
}

/// A set with no members named by a `*CLOAD`: refused with the line of the load, the set and
/// the line that defined it.
#[test]
fn an_empty_set_in_use_is_refused() {
    let dir = tmp("empty-set");
    let text = std::fs::read_to_string(SLOW)
        .unwrap()
        .replacen("*MATERIAL", "*NSET, NSET=NOTHING\n*MATERIAL", 1)
        .replacen("x1, 3, -50.", "NOTHING, 3, -50.", 1);
    let deck = deck_in(&dir, &text);
    let o = solve(&deck, &dir.join("out"));
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    let want = format!(
        "line {}, *CLOAD data: node set 'NOTHING' (defined at line {}) is empty",
        line_of(&text, "NOTHING, 3"),
        line_of(&text, "*NSET, NSET=NOTHING")
    );
    assert!(err.contains(&want), "{want} not in {err}");
}

/// Step 2 may take one increment (`INC=1`) but needs 50: the solve stops there with exit 1;
/// step 1 and step 2's increments so far stay, with the error located (step, line, INC=1).
#[test]
fn a_failed_step_keeps_the_converged_ones() {
    let dir = tmp("failed-step");
    let base = std::fs::read_to_string(SLOW).unwrap();
    let second = base.match_indices("*STEP\n").next().unwrap().0;
    let text = format!("{}*STEP, INC=1\n{}", &base[..second], &base[second + 6..]);
    let deck = deck_in(&dir, &text);
    let out = dir.join("out");
    let o = solve(&deck, &out);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    let v = summary(&out);
    assert_eq!(v["complete"], false);
    let stopped = v["stopped"].as_str().unwrap();
    let want = format!("error: step 2 (line {})", line_of(&text, "*STEP, INC=1"));
    assert!(
        stopped.starts_with(&want) && stopped.contains("INC=1"),
        "{stopped}"
    );
    let steps = v["steps"].as_array().unwrap();
    assert_eq!(steps.len(), 2);
    assert_eq!(steps[0]["complete"], true);
    assert_eq!(steps[0]["increments"].as_array().unwrap().len(), 50);
    assert_eq!(steps[1]["complete"], false);
    assert!(!steps[1]["increments"].as_array().unwrap().is_empty());
    all_files_whole(&out);
    files_agree_with_summary(&out, &v);
}

/// Increments status.sta lists as converged: written on the solving thread as each converges,
/// before its files (on two or more threads, the files are written by a thread of their own).
fn converged_in_status(out: &Path) -> usize {
    std::fs::read_to_string(out.join("status.sta"))
        .unwrap()
        .lines()
        .filter(|l| l.split(',').nth(5) == Some("converged"))
        .count()
}

/// Increments summary.json lists as converged.
fn converged_in_summary(v: &serde_json::Value) -> usize {
    v["steps"]
        .as_array()
        .unwrap()
        .iter()
        .flat_map(|s| s["increments"].as_array().unwrap())
        .filter(|i| i["converged"] == true)
        .count()
}

/// Sends SIG`name` to a solve on `threads` threads once step 1 is complete and once step 2 is
/// under way: exit `code`, summary.json parses, says `"complete": false` and names the
/// signal, every increment converged before the signal (status.sta) is there (on two threads:
/// the writer thread's backlog written before the stopped state) and every file is whole and
/// agrees with it.
fn interrupted(name: &str, code: i32, threads: usize) {
    for (point, ready) in [
        (
            "after step 1",
            after_step_1 as fn(&serde_json::Value) -> bool,
        ),
        ("within step 2", within_step_2),
    ] {
        let out = tmp(&format!("signal-{name}-{}", point.replace(' ', "-"))).join("out");
        let mut child = start(Path::new(SLOW), &out, threads);
        wait_until(&out, &mut child, point, ready);
        let v0 = summary(&out);
        let converged = converged_in_status(&out);
        signal(&child, name);
        let status = child.wait().unwrap();
        assert_eq!(status.code(), Some(code), "SIG{name} {point}");
        let v = summary(&out);
        assert_eq!(v["complete"], false);
        assert_eq!(v["stopped"], format!("interrupted by SIG{name}"));
        let steps = v["steps"].as_array().unwrap();
        assert_eq!(steps[0]["complete"], true);
        assert!((1..=3).contains(&steps.len()));
        assert!(steps.last().unwrap()["complete"] == false || steps.len() < 3);
        // Nothing seen before the signal is lost.
        let count = |v: &serde_json::Value| -> usize {
            v["steps"]
                .as_array()
                .unwrap()
                .iter()
                .map(|s| s["increments"].as_array().unwrap().len())
                .sum()
        };
        assert!(count(&v) >= count(&v0), "{point}");
        assert!(
            converged_in_summary(&v) >= converged,
            "{point}: {} converged increments in summary.json, {converged} in status.sta \
             before SIG{name}",
            converged_in_summary(&v)
        );
        all_files_whole(&out);
        files_agree_with_summary(&out, &v);
    }
}

#[test]
fn sigint_keeps_the_converged_increments() {
    // Two threads: the files written by a thread of their own.
    interrupted("INT", 130, 2);
}

#[test]
fn sigterm_keeps_the_converged_increments() {
    // One thread: the files written where each increment is reported.
    interrupted("TERM", 143, 1);
}

/// SIGKILL cannot be caught: whatever is on disk parses and does not claim to be complete.
#[test]
fn sigkill_leaves_nothing_that_claims_to_be_complete() {
    let out = tmp("signal-KILL").join("out");
    let mut child = start(Path::new(SLOW), &out, 2);
    wait_until(&out, &mut child, "within step 2", within_step_2);
    child.kill().unwrap();
    child.wait().unwrap();
    let v = summary(&out);
    assert_eq!(v["complete"], false);
    assert!(v["stopped"].is_null());
    assert_eq!(v["steps"][0]["complete"], true);
    assert!(!out.join("displacements.csv").exists());
    // A step folder's displacements are written before the summary that lists the step as
    // complete: at most the step after the last listed one can have them without the summary
    // saying so yet. None can exist for a step not reached.
    let complete = v["steps"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|s| s["complete"] == true)
        .count();
    for k in complete + 2..=3 {
        assert!(!out.join(format!("step-{k}/displacements.csv")).exists());
    }
}

#[test]
fn a_complete_solve_says_so_and_cleans_what_an_earlier_one_left() {
    let dir = tmp("complete");
    let out = dir.join("out");
    std::fs::create_dir_all(out.join("step-7")).unwrap();
    std::fs::create_dir_all(out.join("step-8")).unwrap();
    std::fs::write(out.join("step-7/node-print-OLD.csv"), "stale").unwrap();
    std::fs::write(out.join("step-8/displacements.csv"), "stale").unwrap();
    std::fs::write(out.join("step-8/notes.txt"), "the user's").unwrap();
    std::fs::write(out.join("notes.txt"), "the user's").unwrap();
    let o = solve(Path::new("tests/decks/amplitude_cload.inp"), &out);
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let v = summary(&out);
    assert_eq!(v["complete"], true);
    assert!(v["stopped"].is_null());
    assert!(!out.join("step-7").exists(), "stale output kept");
    assert!(
        !out.join("step-8/displacements.csv").exists(),
        "stale output kept"
    );
    assert!(out.join("step-8/notes.txt").exists() && out.join("notes.txt").exists());
    all_files_whole(&out);
    files_agree_with_summary(&out, &v);
}

/// An output folder that cannot be made (a path below a regular file) is bad input, found
/// before the solve.
#[test]
fn an_output_folder_that_cannot_be_written_exits_2() {
    let dir = tmp("bad-out");
    std::fs::write(dir.join("file"), "").unwrap();
    let o = solve(Path::new(SLOW), &dir.join("file/out"));
    assert_eq!(o.status.code(), Some(2));
    assert!(
        String::from_utf8_lossy(&o.stdout)
            .lines()
            .all(|l| !l.starts_with("step "))
    );
}

/// Every file of a solve, by path under `out` (summary.json without its provenance and thread
/// count; status.sta and convergence.cvg without their wall-clock column).
fn files_of(out: &Path) -> std::collections::BTreeMap<PathBuf, String> {
    let mut files = std::collections::BTreeMap::new();
    let mut folders = vec![out.to_path_buf()];
    while let Some(dir) = folders.pop() {
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                folders.push(path);
                continue;
            }
            let name = path.file_name().unwrap().to_string_lossy().into_owned();
            let text = std::fs::read_to_string(&path).unwrap();
            let text = match name.as_str() {
                "summary.json" => {
                    let mut v: serde_json::Value = serde_json::from_str(&text).unwrap();
                    v["provenance"] = serde_json::Value::Null;
                    v["threads"] = serde_json::Value::Null;
                    v.to_string()
                }
                "status.sta" | "convergence.cvg" => {
                    let header = text.lines().next().unwrap();
                    let wall = header.split(',').position(|c| c == "wall_s").unwrap();
                    text.lines()
                        .map(|l| {
                            let mut cells: Vec<&str> = l.split(',').collect();
                            cells.remove(wall);
                            cells.join(",") + "\n"
                        })
                        .collect()
                }
                _ => text,
            };
            files.insert(path.strip_prefix(out).unwrap().to_path_buf(), text);
        }
    }
    files
}

/// On two threads the files are written by a thread of their own while the solve goes on; on
/// one, where each increment is reported. Both write the same files with the same bytes (the
/// VTUs, the print tables, the displacements, summary.json but for its timings).
#[test]
fn the_files_are_the_same_whether_written_beside_the_solve_or_in_it() {
    let deck = Path::new("tests/decks/el_print_nlgeom.inp");
    let outs: Vec<PathBuf> = [1, 2]
        .iter()
        .map(|threads| {
            let out = tmp(&format!("writer-threads-{threads}")).join("out");
            let o = command(deck, &out)
                .args(["-q", "--threads", &threads.to_string()])
                .output()
                .unwrap();
            assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
            out
        })
        .collect();
    let (one, two) = (files_of(&outs[0]), files_of(&outs[1]));
    assert!(one.keys().any(|p| p.to_string_lossy().ends_with(".vtu")));
    assert!(one.keys().any(|p| p.starts_with("step-1")));
    assert_eq!(
        one.keys().collect::<Vec<_>>(),
        two.keys().collect::<Vec<_>>()
    );
    for (path, text) in &one {
        assert!(text == &two[path], "{} differs", path.display());
    }
}
