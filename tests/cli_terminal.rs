//! The command line in a terminal (issue: what an FE user expects of the command line): run in
//! a pseudo-terminal made by `script` (util-linux), the progress bar redraws at least once a
//! second during a long level and shows Newton's iterations as they happen; `-q` prints
//! nothing on success; with output piped (no terminal) no bar is drawn.

use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

fn tmp(name: &str) -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("cli-terminal-{name}"));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// The reference scene on `slices` slices with one level at `strain`.
fn scene(dir: &Path, slices: usize, strain: &str) -> PathBuf {
    let text = nonlin3d::scene::THESIS_SCENE
        .replace("slices = 8", &format!("slices = {slices}"))
        .replace(
            "strains = [-0.001, -0.002, -0.003, -0.004, -0.005]",
            &format!("strains = [{strain}]"),
        );
    let p = dir.join("scene.toml");
    std::fs::write(&p, text).unwrap();
    p
}

/// Runs `args` of nonlin3d in a pseudo-terminal; returns its exit code and what it wrote
/// there, as (seconds since the start, bytes) chunks in the order they came.
fn in_terminal(args: &[&str]) -> (Option<i32>, Vec<(f64, Vec<u8>)>) {
    let quoted: Vec<String> = std::iter::once(env!("CARGO_BIN_EXE_nonlin3d"))
        .chain(args.iter().copied())
        .map(|a| format!("'{}'", a.replace('\'', r"'\''")))
        .collect();
    // -q: no "Script started" lines; -f: flush as it comes; -e: the command's exit code. The
    // terminal is 120 columns wide (a pty made without one has no size).
    let command = format!("stty cols 120 rows 40; exec {}", quoted.join(" "));
    let mut child = Command::new("script")
        .args(["-qfec", &command, "/dev/null"])
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .spawn()
        .expect("`script` (util-linux) runs the CLI in a pseudo-terminal");
    let mut out = child.stdout.take().unwrap();
    let t0 = Instant::now();
    let mut chunks = Vec::new();
    let mut buf = [0u8; 65536];
    loop {
        match out.read(&mut buf) {
            Ok(0) | Err(_) => break,
            Ok(n) => chunks.push((t0.elapsed().as_secs_f64(), buf[..n].to_vec())),
        }
    }
    (child.wait().unwrap().code(), chunks)
}

/// The bar's frames: the text between carriage returns, with the time its chunk came.
fn frames(chunks: &[(f64, Vec<u8>)]) -> Vec<(f64, String)> {
    let mut out = Vec::new();
    for (t, bytes) in chunks {
        for part in String::from_utf8_lossy(bytes).split('\r') {
            if !part.trim().is_empty() {
                out.push((*t, part.to_string()));
            }
        }
    }
    out
}

/// A level of some seconds (6 slices, one level at ε = −0.004: the unstable trivial path, the
/// perturbation, 50-odd Newton iterations; 3 s of CPU on this machine): while it is solved the
/// bar redraws at least once a second (a tick every 100 ms) and names the Newton iteration in
/// progress; the run succeeds and prints its table after the bar is gone.
#[test]
fn the_bar_moves_during_a_long_level_and_shows_the_iterations() {
    let dir = tmp("long");
    // 32 slices on one thread: the run takes 2.7 s on the machine of 2026-11-30 (20 slices
    // had taken 3.6–3.8 s on an earlier, slower one, and there a level of 1.42 s, under the
    // 1.5 s asked for below; 12 and 16 slices fell short before), long enough for the tick to
    // show on a machine faster still.
    let scene = scene(&dir, 32, "-0.004");
    let out = dir.join("out");
    let (code, chunks) = in_terminal(&[
        "--threads",
        "1",
        "run",
        "--out",
        out.to_str().unwrap(),
        scene.to_str().unwrap(),
    ]);
    assert_eq!(code, Some(0));
    let frames = frames(&chunks);
    // The level's frames: from the first that names an iteration to the table.
    let solving: Vec<&(f64, String)> = frames
        .iter()
        .skip_while(|(_, f)| !f.contains("iteration"))
        .take_while(|(_, f)| !f.contains("results in"))
        .collect();
    let (first, last) = (solving[0].0, solving[solving.len() - 1].0);
    assert!(
        last - first > 1.5,
        "the level took {:.2} s: too short to show a steady tick",
        last - first
    );
    let gap = solving
        .windows(2)
        .map(|w| w[1].0 - w[0].0)
        .fold(0.0, f64::max);
    assert!(gap < 1.0, "no redraw for {gap:.2} s during the level");
    // Redraws with nothing new from Newton (the same message, a new spinner or clock): the
    // steady tick, which keeps the bar alive through an iteration longer than a second.
    let message = |f: &str| f.split_once("level").map(|(_, m)| m.to_string());
    let ticks = solving
        .windows(2)
        .filter(|w| message(&w[0].1).is_some() && message(&w[0].1) == message(&w[1].1))
        .count();
    // A tick every 0.1 s gives up to 10 such redraws a second (91 in a 9.5 s level on the
    // loaded 2-core machine; 2 in all without the tick): asking for 2 a second leaves room
    // for a busy machine and still fails without the tick.
    let seconds = last - first;
    assert!(
        ticks as f64 >= 2.0 * seconds,
        "{ticks} redraws without news in {seconds:.2} s: no steady tick"
    );
    // Newton's iterations show as they happen: several distinct residuals on the bar.
    let mut shown: Vec<&str> = solving
        .iter()
        .filter_map(|(_, f)| f.split("‖r‖").nth(1))
        .collect();
    shown.dedup();
    assert!(shown.len() >= 5, "{shown:?}");
    let text: String = frames.iter().map(|(_, f)| f.as_str()).collect();
    assert!(text.contains("level 1/1"), "{text}");
    assert!(text.contains("results in"), "{text}");
}

/// `-q` on a successful run and a successful solve: nothing at all on the terminal, and the
/// outputs written.
#[test]
fn quiet_prints_nothing_on_success() {
    let dir = tmp("quiet");
    let scene = scene(&dir, 4, "-0.001");
    let out = dir.join("run");
    let (code, chunks) = in_terminal(&[
        "run",
        "-q",
        "--out",
        out.to_str().unwrap(),
        scene.to_str().unwrap(),
    ]);
    assert_eq!(code, Some(0));
    let printed: Vec<u8> = chunks.into_iter().flat_map(|(_, b)| b).collect();
    assert!(printed.is_empty(), "{}", String::from_utf8_lossy(&printed));
    assert!(out.join("results.json").exists());
    let deck = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/decks/uniaxial_box.inp");
    let out = dir.join("solve");
    let (code, chunks) = in_terminal(&[
        "-q",
        "solve",
        deck.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, Some(0));
    let printed: Vec<u8> = chunks.into_iter().flat_map(|(_, b)| b).collect();
    assert!(printed.is_empty(), "{}", String::from_utf8_lossy(&printed));
    assert!(out.join("summary.json").exists());
}

/// Without a terminal (stderr piped, as in CI) no bar is drawn: stderr stays empty on a
/// successful run; with `-v` it holds one line per Newton iteration, as many as
/// `convergence.cvg` has records.
#[test]
fn piped_output_has_no_bar_and_verbose_has_a_line_per_iteration() {
    let dir = tmp("piped");
    let scene = scene(&dir, 4, "-0.001");
    let out = dir.join("out");
    let run = |extra: &[&str]| {
        let t = Instant::now();
        let o = Command::new(env!("CARGO_BIN_EXE_nonlin3d"))
            .arg("run")
            .args(extra)
            .arg("--out")
            .arg(&out)
            .arg(&scene)
            .output()
            .unwrap();
        assert!(o.status.success());
        assert!(t.elapsed() < Duration::from_secs(120));
        o
    };
    let plain = run(&[]);
    assert!(
        plain.stderr.is_empty(),
        "{}",
        String::from_utf8_lossy(&plain.stderr)
    );
    assert!(String::from_utf8_lossy(&plain.stdout).contains("results in"));
    let verbose = run(&["-v"]);
    let err = String::from_utf8_lossy(&verbose.stderr);
    // The run's own iterations, one line each as in convergence.cvg; the error estimate's
    // companion's are labelled and not in the file.
    let (companion, own): (Vec<&str>, Vec<&str>) = err
        .lines()
        .filter(|l| l.contains(" iteration "))
        .partition(|l| l.starts_with("companion mesh: "));
    let cvg = std::fs::read_to_string(out.join("convergence.cvg")).unwrap();
    assert!(!own.is_empty() && !companion.is_empty(), "{err}");
    assert_eq!(own.len(), cvg.lines().count() - 1, "{err}");
}
