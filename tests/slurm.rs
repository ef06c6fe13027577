//! Studies on a Slurm cluster (`nonlin3d sweep plan --slurm`, `sweep submit [--failed]`,
//! `sweep status`, docs/CLUSTER.md).
//!
//! `a_study_runs_through_slurm_and_survives_a_cancelled_task` needs a running cluster
//! (`.ci/slurm-up.sh` starts a one-node one on 127.0.0.1; export the SLURM_CONF it prints): an
//! 8-case coarse sweep planned with --slurm, submitted, one array task cancelled mid-run, the
//! study completed with `submit --failed`, merged, and equal byte for byte to a local
//! `sweep run` of the same plan. Without `sbatch` on PATH it is skipped with the reason
//! printed, unless NONLIN3D_REQUIRE_SLURM=1 (set by .ci/run), which makes that a failure.
//!
//! The other tests stand in for the Slurm commands with scripts on a PATH of their own: the
//! script's contents, a missing or failing sbatch, a case folder that cannot be written, and
//! `status` with no scheduler to ask.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::time::{Duration, Instant};

/// Eight cases zipped along a: seven coarse ones (6 × 1 elements, ~0.3 s each) and a last one
/// 40 × 4 elements (~5 s here), long enough to be cancelled while it runs.
const STUDY: &str = r#"title = "slurm test"
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
strains = [-0.001, -0.002, -0.003, -0.004]
[criterion]
kind = "power-law"
g_ic = 10.0
g_iic = 30.0
[sweep]
"geometry.a_mm" = [8.0, 9.0, 10.0, 11.0, 12.0, 13.0, 14.0, 15.0]
"mesh.inside" = [6, 6, 6, 6, 6, 6, 6, 40]
"mesh.across" = [1, 1, 1, 1, 1, 1, 1, 4]
zip = [["geometry.a_mm", "mesh.inside", "mesh.across"]]
"#;

fn tmp(name: &str) -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("slurm-{name}"));
    unlock(&d);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Clears the immutable flag a test may have left (a run stopped part-way).
fn unlock(d: &Path) {
    if d.exists() {
        let _ = Command::new("chattr").args(["-R", "-i"]).arg(d).output();
    }
}

fn nonlin3d(args: &[&str], path: Option<&Path>) -> Output {
    let mut c = Command::new(env!("CARGO_BIN_EXE_nonlin3d"));
    c.args(args);
    if let Some(p) = path {
        c.env("PATH", p);
    }
    c.output().unwrap()
}

fn ok(args: &[&str], path: Option<&Path>) -> String {
    let o = nonlin3d(args, path);
    assert!(
        o.status.success(),
        "{args:?}: {}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    String::from_utf8_lossy(&o.stdout).into_owned()
}

/// Runs `args`, expecting exit 2 (bad input); the message.
fn refused(args: &[&str], path: Option<&Path>) -> String {
    let o = nonlin3d(args, path);
    assert_eq!(
        o.status.code(),
        Some(2),
        "{args:?}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn p(path: &Path) -> &str {
    path.to_str().unwrap()
}

fn scene(dir: &Path, text: &str) -> PathBuf {
    let path = dir.join("study.toml");
    std::fs::write(&path, text).unwrap();
    path
}

/// A folder of stand-in commands (`name` → shell script body), to be the whole PATH.
fn fake_path(dir: &Path, commands: &[(&str, &str)]) -> PathBuf {
    use std::os::unix::fs::PermissionsExt;
    let bin = dir.join("bin");
    std::fs::create_dir_all(&bin).unwrap();
    for (name, body) in commands {
        let f = bin.join(name);
        std::fs::write(&f, format!("#!/bin/sh\n{body}\n")).unwrap();
        std::fs::set_permissions(&f, std::fs::Permissions::from_mode(0o755)).unwrap();
    }
    bin
}

#[test]
fn the_script_asks_for_an_array_with_estimated_resources() {
    let d = tmp("script");
    let s = scene(&d, STUDY);
    let out = d.join("study");
    let said = ok(
        &[
            "sweep",
            "plan",
            p(&s),
            "--out",
            p(&out),
            "--slurm",
            "--per-task",
            "3",
            "--max-parallel",
            "2",
            "--partition",
            "short",
            "--account",
            "lab",
        ],
        None,
    );
    assert!(said.contains("3 array tasks of 3 case(s)"), "{said}");
    let script = std::fs::read_to_string(out.join("slurm/sweep.sbatch")).unwrap();
    let abs = out.canonicalize().unwrap();
    for line in [
        "#SBATCH --array=0-2%2".to_string(),
        "#SBATCH --partition=short".into(),
        "#SBATCH --account=lab".into(),
        format!("#SBATCH --output={}/slurm/logs/%A_%a.out", abs.display()),
        format!("dir='{}'", abs.display()),
        "per_task=3".into(),
        "cases=8".into(),
    ] {
        assert!(script.contains(&line), "{line} not in\n{script}");
    }
    // The script runs anywhere: task 0 of 3 (cases 0, 3 and 6, in one process) by hand, as
    // Slurm would.
    let task = Command::new("bash")
        .arg(out.join("slurm/sweep.sbatch"))
        .env("SLURM_ARRAY_TASK_ID", "0")
        .current_dir(&d)
        .output()
        .unwrap();
    assert!(task.status.success(), "{task:?}");
    let status = ok(&["sweep", "status", p(&out)], None);
    for k in 0..8 {
        let line = status
            .lines()
            .find(|l| l.trim_start().starts_with(&format!("{k} ")))
            .unwrap();
        let want = if k % 3 == 0 { "complete" } else { "missing" };
        assert!(line.contains(want), "case {k}: {status}");
    }
    let e = refused(&["sweep", "run", p(&out), "--cases", "6-8/2"], None);
    assert!(
        e.contains("--cases 6-8/2: the study has cases 0 to 7"),
        "{e}"
    );
    let e = refused(&["sweep", "run", p(&out), "--cases", "1-5/0"], None);
    assert!(e.contains("FIRST-LAST/STEP"), "{e}");
    let settings: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("slurm/slurm.json")).unwrap())
            .unwrap();
    // Memory: the largest case (case 7, 40 × 4 elements) sets it, times 1.5, in 64 MiB steps.
    let bytes = settings["case_bytes"].as_f64().unwrap();
    let mem = settings["mem_mib"].as_f64().unwrap();
    assert!(mem >= 1.5 * bytes / 1048576.0 && mem >= 256.0, "{settings}");
    assert!(
        mem < 1.5 * bytes / 1048576.0 + 64.0 || mem == 256.0,
        "{settings}"
    );
    assert!(
        script.contains(&format!("#SBATCH --mem={mem}M")),
        "{script}"
    );
    // Time: at least the 5-minute floor, or 3 × 3 cases × the largest case's estimate.
    let case_s = settings["case_seconds"].as_f64().unwrap();
    let want = (9.0 * case_s).max(300.0);
    let time = settings["time"].as_str().unwrap();
    let secs: Vec<f64> = time.split(':').map(|x| x.parse().unwrap()).collect();
    let secs = secs[0] * 3600.0 + secs[1] * 60.0 + secs[2];
    assert!(secs >= want && secs < want + 60.0, "{time} for {want} s");
    // --time replaces the estimate; a plan with bad options is refused before anything.
    let again = d.join("again");
    ok(
        &[
            "sweep",
            "plan",
            p(&s),
            "--out",
            p(&again),
            "--slurm",
            "--per-task",
            "1",
            "--time",
            "1-00:30:00",
        ],
        None,
    );
    let script = std::fs::read_to_string(again.join("slurm/sweep.sbatch")).unwrap();
    assert!(script.contains("#SBATCH --time=1-00:30:00\n#"), "{script}");
    assert!(script.contains("#SBATCH --array=0-7\n"), "{script}");
    let bad = d.join("bad");
    for args in [
        vec!["--slurm", "--time", "25:61:00"],
        vec!["--slurm", "--per-task", "0"],
        vec!["--slurm", "--partition", "a b"],
    ] {
        let mut a = vec!["sweep", "plan", p(&s), "--out", p(&bad)];
        a.extend(args);
        let e = refused(&a, None);
        assert!(e.contains("--"), "{e}");
        assert!(!bad.exists());
    }
}

#[test]
fn bad_input_is_refused_and_nothing_is_half_planned_or_submitted() {
    let d = tmp("bad");
    let out = d.join("study");
    // An unknown sweep field and an empty range: nothing planned, no script.
    for (sweep, words) in [
        ("\"geometry.aa_mm\" = [1.0]", "geometry.aa_mm"),
        ("\"geometry.a_mm\" = []", "an empty list"),
    ] {
        let text = STUDY.split("[sweep]").next().unwrap().to_string() + "[sweep]\n" + sweep;
        let s = scene(&d, &text);
        let e = refused(&["sweep", "plan", p(&s), "--out", p(&out), "--slurm"], None);
        assert!(e.contains(words), "{e}");
        assert!(!out.exists(), "{sweep}: {out:?} left behind");
        let left: Vec<_> = std::fs::read_dir(&d).unwrap().flatten().collect();
        assert_eq!(left.len(), 1, "{left:?}"); // the scene alone
    }
    let s = scene(&d, STUDY);
    ok(
        &[
            "sweep",
            "plan",
            p(&s),
            "--out",
            p(&out),
            "--slurm",
            "--per-task",
            "1",
        ],
        None,
    );
    let jobs = out.join("slurm/jobs.json");
    // sbatch missing.
    let empty = fake_path(&d.join("none"), &[]);
    let e = refused(&["sweep", "submit", p(&out)], Some(&empty));
    assert!(e.contains("sbatch could not be run"), "{e}");
    assert!(!jobs.exists());
    // sbatch failing: its words in the message.
    let failing = fake_path(
        &d.join("failing"),
        &[(
            "sbatch",
            "echo 'sbatch: error: invalid partition specified' >&2; exit 1",
        )],
    );
    let e = refused(&["sweep", "submit", p(&out)], Some(&failing));
    assert!(e.contains("invalid partition specified"), "{e}");
    assert!(!jobs.exists());
    // A case folder that cannot take a file: refused before sbatch is called.
    let marker = d.join("sbatch-called");
    let working = fake_path(
        &d.join("working"),
        &[(
            "sbatch",
            &format!("echo \"$@\" > '{}'; echo '4242;cluster'", marker.display()),
        )],
    );
    let case3 = out.join("cases/0003");
    let locked = lock(&case3);
    let o = nonlin3d(&["sweep", "submit", p(&out)], Some(&working));
    unlock_one(&case3, locked);
    if let Some(how) = locked {
        assert_eq!(o.status.code(), Some(2), "{how}: {o:?}");
        let e = String::from_utf8_lossy(&o.stderr);
        assert!(e.contains("cases/0003: not writable"), "{e}");
        assert!(!marker.exists() && !jobs.exists());
    } else {
        println!("skipped the unwritable case folder: neither chmod nor chattr could lock it");
        std::fs::remove_file(&jobs).unwrap();
        let _ = std::fs::remove_file(&marker);
    }
    // A working sbatch: the job recorded; without squeue or sacct, status says so.
    let said = ok(&["sweep", "submit", p(&out)], Some(&working));
    assert!(
        said.contains("submitted job 4242 (--array=0-7, 8 tasks)"),
        "{said}"
    );
    let args = std::fs::read_to_string(&marker).unwrap();
    assert_eq!(args.trim(), "--parsable --array=0-7 slurm/sweep.sbatch");
    let recorded: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&jobs).unwrap()).unwrap();
    assert_eq!(recorded["jobs"][0]["job_id"], "4242");
    let status = ok(&["sweep", "status", p(&out)], Some(&working));
    assert!(
        status.contains("(from the results on disk (no squeue or sacct answered))"),
        "{status}"
    );
    assert!(status.trim_end().ends_with("8 missing"), "{status}");
    // A queue that lists the whole array as pending: status says so, a plain submit refuses.
    let queued = fake_path(
        &d.join("working"),
        &[(
            "squeue",
            "for k in 0 1 2 3 4 5 6 7; do echo \"4242|$k|PENDING\"; done",
        )],
    );
    let status = ok(&["sweep", "status", p(&out)], Some(&queued));
    assert!(status.trim_end().ends_with("8 pending"), "{status}");
    let e = refused(&["sweep", "submit", p(&out)], Some(&queued));
    assert!(e.contains("case 0 is pending"), "{e}");
    let said = ok(&["sweep", "submit", p(&out), "--failed"], Some(&queued));
    assert!(said.contains("nothing to submit (8 pending)"), "{said}");
}

/// Makes `dir` refuse new files: chmod for a user, the immutable flag for root (whom modes do
/// not stop). How, or None when neither works here.
fn lock(dir: &Path) -> Option<&'static str> {
    use std::os::unix::fs::PermissionsExt;
    let probe = dir.join("probe");
    std::fs::set_permissions(dir, std::fs::Permissions::from_mode(0o555)).unwrap();
    if std::fs::write(&probe, b"").is_err() {
        return Some("chmod 555");
    }
    let _ = std::fs::remove_file(&probe);
    std::fs::set_permissions(dir, std::fs::Permissions::from_mode(0o755)).unwrap();
    let chattr = Command::new("chattr").arg("+i").arg(dir).output();
    if chattr.is_ok_and(|o| o.status.success()) && std::fs::write(&probe, b"").is_err() {
        return Some("chattr +i");
    }
    None
}

fn unlock_one(dir: &Path, how: Option<&str>) {
    use std::os::unix::fs::PermissionsExt;
    match how {
        Some("chattr +i") => {
            Command::new("chattr").arg("-i").arg(dir).output().unwrap();
        }
        Some(_) => std::fs::set_permissions(dir, std::fs::Permissions::from_mode(0o755)).unwrap(),
        None => {}
    }
}

/// Whether a cluster answers; the reason when not. With NONLIN3D_REQUIRE_SLURM=1, no cluster
/// is a failure.
fn cluster() -> Result<(), String> {
    let sbatch = Command::new("sbatch").arg("--version").output();
    let why = match sbatch {
        Err(e) => Some(format!("sbatch is not on PATH ({e})")),
        Ok(_) => match Command::new("sinfo").args(["-h", "-o", "%t"]).output() {
            Ok(o) if o.status.success() && !o.stdout.is_empty() => None,
            Ok(o) => Some(format!(
                "sinfo does not answer ({}): start a cluster with .ci/slurm-up.sh and export \
                 the SLURM_CONF it prints",
                String::from_utf8_lossy(&o.stderr).trim()
            )),
            Err(e) => Some(format!("sinfo is not on PATH ({e})")),
        },
    };
    match why {
        None => Ok(()),
        Some(why) if std::env::var("NONLIN3D_REQUIRE_SLURM").as_deref() == Ok("1") => {
            panic!("NONLIN3D_REQUIRE_SLURM=1 but {why}")
        }
        Some(why) => Err(why),
    }
}

/// Polls `done` every 100 ms until it holds, for at most `limit`.
fn wait_for(what: &str, limit: Duration, mut done: impl FnMut() -> bool) {
    let t = Instant::now();
    while !done() {
        assert!(t.elapsed() < limit, "waited {limit:?} for {what}");
        std::thread::sleep(Duration::from_millis(100));
    }
}

/// The job's array tasks still in squeue.
fn queued(job: &str) -> usize {
    let o = Command::new("squeue")
        .args(["-h", "-r", "-o", "%F"])
        .output()
        .unwrap();
    String::from_utf8_lossy(&o.stdout)
        .lines()
        .filter(|l| l.trim() == job)
        .count()
}

fn job_id(said: &str) -> String {
    said.split_whitespace()
        .nth(2)
        .unwrap_or_else(|| panic!("no job id in '{said}'"))
        .to_string()
}

/// The last line of `sweep status` (the counts).
fn counts(dir: &Path) -> String {
    let s = ok(&["sweep", "status", p(dir)], None);
    s.lines().last().unwrap_or_default().to_string()
}

#[test]
fn a_study_runs_through_slurm_and_survives_a_cancelled_task() {
    if let Err(why) = cluster() {
        println!("skipped: {why}");
        return;
    }
    let t0 = Instant::now();
    let d = tmp("e2e");
    let s = scene(&d, STUDY);
    let (cluster_dir, local) = (d.join("cluster"), d.join("local"));
    ok(
        &[
            "sweep",
            "plan",
            p(&s),
            "--out",
            p(&cluster_dir),
            "--slurm",
            "--per-task",
            "1",
            "--max-parallel",
            "2",
        ],
        None,
    );
    assert_eq!(counts(&cluster_dir), "8 missing");
    let job = job_id(&ok(&["sweep", "submit", p(&cluster_dir)], None));
    let status = ok(&["sweep", "status", p(&cluster_dir)], None);
    assert!(
        status.contains("(from the results on disk and squeue"),
        "{status}"
    );
    // Case 7 started (its results.json written, not complete): cancel its task.
    let results7 = cluster_dir.join("cases/0007/results.json");
    wait_for("case 7 to start", Duration::from_secs(60), || {
        std::fs::read_to_string(&results7).is_ok_and(|t| t.contains("\"complete\": false"))
    });
    let status = ok(&["sweep", "status", p(&cluster_dir)], None);
    let line7 = status
        .lines()
        .find(|l| l.trim_start().starts_with("7 "))
        .unwrap();
    assert!(line7.contains("running"), "{status}");
    let cancel = Command::new("scancel")
        .arg(format!("{job}_7"))
        .output()
        .unwrap();
    assert!(cancel.status.success(), "{cancel:?}");
    wait_for(
        "the job to leave the queue",
        Duration::from_secs(60),
        || queued(&job) == 0,
    );
    // Seven complete; case 7 failed, as stopped before it finished, its folder incomplete.
    let status = ok(&["sweep", "status", p(&cluster_dir)], None);
    assert!(
        status.trim_end().ends_with("7 complete, 1 failed"),
        "{status}"
    );
    let line7 = status
        .lines()
        .find(|l| l.trim_start().starts_with("7 "))
        .unwrap();
    assert!(line7.contains("stopped before it finished"), "{line7}");
    let r7: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&results7).unwrap()).unwrap();
    assert_eq!(r7["complete"], false);
    let wall: Vec<f64> = (0..7)
        .map(|k| {
            let t = std::fs::read_to_string(cluster_dir.join(format!("cases/{k:04}/results.json")))
                .unwrap();
            let v: serde_json::Value = serde_json::from_str(&t).unwrap();
            v["provenance"]["wall_s"]["total"].as_f64().unwrap()
        })
        .collect();
    // --failed: an array of exactly task 7; the complete cases are not run again (their
    // results.json untouched: the same wall times).
    let said = ok(&["sweep", "submit", p(&cluster_dir), "--failed"], None);
    assert!(said.contains("(--array=7%2, 1 tasks)"), "{said}");
    let again = job_id(&said);
    // Meanwhile, the same plan run here.
    ok(&["sweep", "plan", p(&s), "--out", p(&local)], None);
    ok(&["sweep", "run", p(&local), "--jobs", "1"], None);
    wait_for("the resubmitted task", Duration::from_secs(60), || {
        queued(&again) == 0
    });
    assert_eq!(counts(&cluster_dir), "8 complete");
    for (k, w) in wall.iter().enumerate() {
        let t = std::fs::read_to_string(cluster_dir.join(format!("cases/{k:04}/results.json")))
            .unwrap();
        let v: serde_json::Value = serde_json::from_str(&t).unwrap();
        assert_eq!(
            v["provenance"]["wall_s"]["total"].as_f64(),
            Some(*w),
            "case {k}"
        );
    }
    let logs = std::fs::read_dir(cluster_dir.join("slurm/logs"))
        .unwrap()
        .count();
    assert_eq!(logs, 2 * 9, "an .out and an .err per task run (8 + 1)");
    ok(&["sweep", "merge", p(&cluster_dir)], None);
    ok(&["sweep", "merge", p(&local)], None);
    for f in ["study.csv", "study.json", "study.svg"] {
        let a = std::fs::read(cluster_dir.join(f)).unwrap();
        let b = std::fs::read(local.join(f)).unwrap();
        assert!(a == b, "{f} differs between Slurm and the local run");
    }
    let csv = std::fs::read_to_string(cluster_dir.join("study.csv")).unwrap();
    assert_eq!(csv.matches(",complete,").count(), 8, "{csv}");
    println!("the Slurm study took {:.1} s", t0.elapsed().as_secs_f64());
}
