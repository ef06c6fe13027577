//! `nonlin3d solve` against CalculiX on the clamped-plate decks of issue 20 (docs/PERFORMANCE.md,
//! "Clamped-plate decks against CalculiX"): thesis §4.1's transversely loaded plate, a steel
//! disc of radius a = 15 mm and thickness h = 0.4 mm clamped at r = a, under a central point
//! load P, as a quarter model with symmetry planes x = 0 and y = 0. The load, P = 1 625 N (a
//! quarter of it on the quarter model, at the mid-plane node of the axis), gives w₀/h = 3 by
//! eq. 4.1.1, w₀/h + 0.443 (w₀/h)³ = 0.217 P a²/(E h⁴); it is reached in 10 NLGEOM increments
//! of `*STATIC, DIRECT` 0.1, 1, so that both programs land on the same ten states.
//!
//! Mesh: C3D20R (the 2×2×2 rule nonlin3d uses for them) on an O-grid of the quarter disc — a
//! square core [0, c]², c = 0.4 a, of m × m cells and two curved blocks of m × k cells between
//! the core and the arc (ruled between the core's edge and the arc), m = n/2 and k = 3n/4, so
//! n² cells a layer, `layers` through the thickness (default 4). n = 12, 20, 32, 48 give
//! 9 117, 24 297, 60 747, 134 883 DOF.
//!
//! `cargo bench --bench plate_decks -- n=12,20 threads=1,2 ccx`: for each n writes the deck,
//! runs `nonlin3d solve --threads T` (the release binary) and, with `ccx`, `ccx` with
//! OMP_NUM_THREADS = CCX_NPROC_EQUATION = T back to back, checks that the centre deflection and
//! the clamp's total reaction agree at every increment (relative to the largest value of each,
//! `tol=`, default 1e-5: CalculiX's default criterion) and prints wall and CPU time and the ratio per thread count.
//! `ccx_field=R_n,C_n` also runs CalculiX on a copy of the deck with `*CONTROLS,
//! PARAMETERS=FIELD` R_n, C_n (e.g. `1e-5,1e-4`: its answer then agrees with nonlin3d's within
//! 1e-6, the "same converged answer", where its default criterion leaves 3.2e-6 at the
//! first increment) and prints that run's time, iterations, ratio and agreement beside the
//! default run's (`tol_field=`, default 1e-6).
//! `write=FILE` (with one n) only writes the deck; `newton=full|modified|bfgs` is passed on to
//! `solve`; `layers=L` sets the layers; `keep` keeps the scratch folder.

use std::collections::HashMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

/// Young's modulus (MPa = N/mm²), Poisson's ratio, radius and thickness (mm) of thesis §4.1.
const E: f64 = 207_000.0;
const NU: f64 = 0.3;
const A: f64 = 15.0;
const H: f64 = 0.4;

/// The load for w₀/h = 3 by eq. 4.1.1: (3 + 0.443·27)·E h⁴/(0.217 a²) = 1 625 N.
fn load() -> f64 {
    (3.0 + 0.443 * 27.0) * E * H.powi(4) / (0.217 * A * A)
}

/// Nodes deduplicated by position (blocks share their edges) and C3D20R cells.
#[derive(Default)]
struct Mesh {
    nodes: Vec<[f64; 3]>,
    index: HashMap<[i64; 3], usize>,
    cells: Vec<[usize; 20]>,
}

impl Mesh {
    fn node(&mut self, p: [f64; 3]) -> usize {
        let key = p.map(|x| (x * 1e7).round() as i64);
        let next = self.nodes.len();
        *self.index.entry(key).or_insert_with(|| {
            self.nodes.push(p);
            next
        })
    }

    /// The cells of one block: `map` takes (ξ, η) ∈ [0, 1]² to the plane, `cells` per
    /// direction; the cells are oriented so that their Jacobian is positive.
    fn block(&mut self, map: &dyn Fn(f64, f64) -> [f64; 2], cells: [usize; 2], layers: usize) {
        // Corner order of C3D20: four at the bottom counter-clockwise, four at the top, then
        // the mid-side nodes of the bottom, the top, and the vertical edges.
        const CORNERS: [[f64; 3]; 8] = [
            [0., 0., 0.],
            [1., 0., 0.],
            [1., 1., 0.],
            [0., 1., 0.],
            [0., 0., 1.],
            [1., 0., 1.],
            [1., 1., 1.],
            [0., 1., 1.],
        ];
        const EDGES: [[usize; 2]; 12] = [
            [0, 1],
            [1, 2],
            [2, 3],
            [3, 0],
            [4, 5],
            [5, 6],
            [6, 7],
            [7, 4],
            [0, 4],
            [1, 5],
            [2, 6],
            [3, 7],
        ];
        let [ni, nj] = cells;
        for l in 0..layers {
            for j in 0..nj {
                for i in 0..ni {
                    let at = |xi: f64, eta: f64, zeta: f64| -> [f64; 3] {
                        let [x, y] = map((i as f64 + xi) / ni as f64, (j as f64 + eta) / nj as f64);
                        [x, y, H * (l as f64 + zeta) / layers as f64]
                    };
                    // Orientation: (∂x/∂ξ × ∂x/∂η)_z at the centre.
                    let (c, d) = (at(0.5, 0.5, 0.0), (at(0.6, 0.5, 0.0), at(0.5, 0.6, 0.0)));
                    let cross =
                        (d.0[0] - c[0]) * (d.1[1] - c[1]) - (d.0[1] - c[1]) * (d.1[0] - c[0]);
                    let local = |p: [f64; 3]| if cross > 0.0 { p } else { [p[1], p[0], p[2]] };
                    let mut cell = [0; 20];
                    for (k, q) in CORNERS.iter().enumerate() {
                        let q = local(*q);
                        cell[k] = self.node(at(q[0], q[1], q[2]));
                    }
                    for (k, [p, q]) in EDGES.iter().enumerate() {
                        let (p, q) = (local(CORNERS[*p]), local(CORNERS[*q]));
                        let m = [0, 1, 2].map(|r| 0.5 * (p[r] + q[r]));
                        cell[8 + k] = self.node(at(m[0], m[1], m[2]));
                    }
                    self.cells.push(cell);
                }
            }
        }
    }
}

/// The O-grid of the quarter disc, n² cells a layer (n divisible by 4).
fn mesh(n: usize, layers: usize) -> Mesh {
    let (m, k) = (n / 2, 3 * n / 4);
    let c = 0.4 * A;
    let mut mesh = Mesh::default();
    mesh.block(&|s, t| [c * s, c * t], [m, m], layers);
    // Between the core's edge x = c (s along it) and the arc θ = s·π/4, ruled in t.
    let outer = move |s: f64, t: f64| {
        let th = s * std::f64::consts::FRAC_PI_4;
        [
            (1.0 - t) * c + t * A * th.cos(),
            (1.0 - t) * c * s + t * A * th.sin(),
        ]
    };
    mesh.block(&|s, t| outer(s, t), [m, k], layers);
    mesh.block(
        &|s, t| {
            let p = outer(s, t);
            [p[1], p[0]]
        },
        [m, k],
        layers,
    );
    mesh
}

/// The deck for `n` and `layers`.
fn deck(n: usize, layers: usize) -> String {
    assert!(
        n.is_multiple_of(4) && n > 0,
        "n = {n}: a positive multiple of 4"
    );
    assert!(
        layers.is_multiple_of(2),
        "layers = {layers}: even (the load sits on the mid-plane)"
    );
    let mesh = mesh(n, layers);
    let mut s = String::new();
    let p = load();
    let _ = writeln!(
        s,
        "*HEADING\nClamped circular plate (thesis 4.1), quarter model: a = {A} mm, h = {H} mm, \
         steel, P = {p:.1} N (w0/h = 3 by eq. 4.1.1), n = {n}, {layers} layers, C3D20R\n\
         ** Written by benches/plate_decks.rs (nonlin3d): cargo bench --bench plate_decks -- \
         n={n} layers={layers} write=FILE"
    );
    s.push_str("*NODE, NSET=NALL\n");
    for (i, x) in mesh.nodes.iter().enumerate() {
        let _ = writeln!(s, "{}, {:.12}, {:.12}, {:.12}", i + 1, x[0], x[1], x[2]);
    }
    s.push_str("*ELEMENT, TYPE=C3D20R, ELSET=EALL\n");
    for (e, cell) in mesh.cells.iter().enumerate() {
        let ids: Vec<String> = cell.iter().map(|v| (v + 1).to_string()).collect();
        // At most 16 entries a line: the 20 nodes over two lines.
        let _ = writeln!(
            s,
            "{}, {},\n{}",
            e + 1,
            ids[..15].join(", "),
            ids[15..].join(", ")
        );
    }
    let set = |s: &mut String, name: &str, pick: &dyn Fn(&[f64; 3]) -> bool| {
        let _ = writeln!(s, "*NSET, NSET={name}");
        let ids: Vec<String> = (0..mesh.nodes.len())
            .filter(|&i| pick(&mesh.nodes[i]))
            .map(|i| (i + 1).to_string())
            .collect();
        for line in ids.chunks(16) {
            let _ = writeln!(s, "{}", line.join(", "));
        }
    };
    let tol = 1e-6;
    set(&mut s, "XSYM", &|x| x[0].abs() < tol);
    set(&mut s, "YSYM", &|x| x[1].abs() < tol);
    set(&mut s, "CLAMP", &|x| (x[0].hypot(x[1]) - A).abs() < tol);
    set(&mut s, "CENTRE", &|x| {
        x[0].abs() < tol && x[1].abs() < tol && (x[2] - 0.5 * H).abs() < tol
    });
    let _ = writeln!(
        s,
        "*MATERIAL, NAME=STEEL\n*ELASTIC\n{E}, {NU}\n*SOLID SECTION, ELSET=EALL, MATERIAL=STEEL\n\
         *BOUNDARY\nXSYM, 1, 1\nYSYM, 2, 2\nCLAMP, 1, 3\n\
         *STEP, NLGEOM, INC=100\n*STATIC, DIRECT\n0.1, 1.0\n*CLOAD\nCENTRE, 3, {:.6}\n\
         *NODE PRINT, NSET=CENTRE\nU\n*NODE PRINT, NSET=CLAMP, TOTALS=ONLY\nRF\n*END STEP",
        -0.25 * p
    );
    s
}

/// The DOF count of a deck (3 a node).
fn dof(deck: &str) -> usize {
    let nodes = deck.split("*NODE, NSET=NALL\n").nth(1).unwrap_or("");
    3 * nodes.lines().take_while(|l| !l.starts_with('*')).count()
}

/// CPU seconds of the waited-for children of this process so far (user + system, from
/// /proc/self/stat, in clock ticks of 1/100 s).
fn children_cpu() -> f64 {
    let stat = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
    let after = stat.rsplit(')').next().unwrap_or("");
    let f: Vec<&str> = after.split_whitespace().collect();
    // Fields 16 and 17 of stat (cutime, cstime) are 14 and 15 after the ")".
    let tick = |i: usize| f.get(i).and_then(|v| v.parse::<f64>().ok()).unwrap_or(0.0);
    (tick(13) + tick(14)) / 100.0
}

/// Wall and CPU seconds of a command; panics with its output if it fails.
fn timed(cmd: &mut Command) -> (f64, f64) {
    let cpu0 = children_cpu();
    let t0 = Instant::now();
    let out = cmd.output().unwrap_or_else(|e| panic!("{cmd:?}: {e}"));
    let wall = t0.elapsed().as_secs_f64();
    assert!(
        out.status.success(),
        "{cmd:?} failed: {}\n{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    (wall, children_cpu() - cpu0)
}

/// Per increment (by total time): the centre's uz and the clamp's total x reaction (the
/// membrane force; the z reaction only balances the load).
type Answers = Vec<(f64, f64, f64)>;

/// From nonlin3d's output tables.
fn ours(dir: &Path) -> Answers {
    let read = |name: &str| -> Vec<Vec<f64>> {
        let text = std::fs::read_to_string(dir.join("step-1").join(name))
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        text.lines()
            .skip(1)
            .map(|l| {
                l.split(',')
                    .map(|v| v.trim().parse().unwrap_or(f64::NAN))
                    .collect()
            })
            .collect()
    };
    let centre = read("node-print-CENTRE.csv");
    let clamp = read("node-print-CLAMP-totals.csv");
    centre
        .iter()
        .zip(&clamp)
        .map(|(c, r)| (c[2], c[6], r[3]))
        .collect()
}

/// Newton iterations and factorisations of a `solve` (summary.json, every attempt).
fn our_counts(dir: &Path) -> (u64, u64) {
    let text = std::fs::read_to_string(dir.join("summary.json")).unwrap_or_default();
    let v: serde_json::Value = serde_json::from_str(&text).unwrap_or_default();
    let mut counts = (0, 0);
    for i in v["steps"]
        .as_array()
        .into_iter()
        .flatten()
        .flat_map(|s| s["increments"].as_array().cloned().unwrap_or_default())
    {
        counts.0 += i["iterations"].as_u64().unwrap_or(0);
        counts.1 += i["factorisations"].as_u64().unwrap_or(0);
    }
    counts
}

/// CalculiX's iterations (its .sta; one factorisation each).
fn their_iterations(sta: &Path) -> u64 {
    let text = std::fs::read_to_string(sta).unwrap_or_default();
    text.lines()
        .filter_map(|l| l.split_whitespace().nth(3)?.parse::<u64>().ok())
        .sum()
}

/// From CalculiX's .dat.
fn theirs(dat: &Path) -> Answers {
    let text = std::fs::read_to_string(dat).unwrap_or_else(|e| panic!("{}: {e}", dat.display()));
    let mut w = Vec::new();
    let mut rf = Vec::new();
    let mut block = "";
    let mut time = f64::NAN;
    for line in text.lines() {
        if line.contains(" for set ") {
            block = if line.contains("displacements") {
                "u"
            } else {
                "rf"
            };
            time = line
                .split_whitespace()
                .last()
                .and_then(|t| t.parse().ok())
                .unwrap_or(f64::NAN);
            continue;
        }
        let v: Vec<f64> = line
            .split_whitespace()
            .filter_map(|t| t.parse().ok())
            .collect();
        match (block, v.len()) {
            ("u", 4) => w.push((time, v[3])),
            ("rf", 3) => rf.push(v[0]),
            _ => {}
        }
    }
    w.iter().zip(&rf).map(|(&(t, w), &r)| (t, w, r)).collect()
}

/// Largest difference of the centre deflections and of the reactions over the increments, each
/// relative to the largest value of its kind.
fn agreement(a: &Answers, b: &Answers) -> (f64, f64) {
    assert_eq!(
        a.len(),
        b.len(),
        "increments: {} against {}",
        a.len(),
        b.len()
    );
    let rel = |f: &dyn Fn(&(f64, f64, f64)) -> f64| {
        let scale = a.iter().map(|x| f(x).abs()).fold(0.0, f64::max);
        let d = a.iter().zip(b).map(|(x, y)| {
            assert!((x.0 - y.0).abs() < 1e-9, "times {} and {}", x.0, y.0);
            (f(x) - f(y)).abs()
        });
        d.fold(0.0, f64::max) / scale
    };
    (rel(&|x| x.1), rel(&|x| x.2))
}

/// One CalculiX run: wall and CPU s, its iterations, and its answers' differences from `mine`
/// ([`agreement`]).
struct CalculixRun {
    wall: f64,
    cpu: f64,
    iterations: u64,
    diff: (f64, f64),
}

/// `ccx -i job` in `dir` on `threads` threads, compared with `mine`.
fn calculix(dir: &Path, job: &str, threads: usize, mine: &Answers) -> CalculixRun {
    let (wall, cpu) = timed(
        Command::new("ccx")
            .args(["-i", job])
            .current_dir(dir)
            .env("OMP_NUM_THREADS", threads.to_string())
            .env("CCX_NPROC_EQUATION", threads.to_string()),
    );
    CalculixRun {
        wall,
        cpu,
        iterations: their_iterations(&dir.join(format!("{job}.sta"))),
        diff: agreement(mine, &theirs(&dir.join(format!("{job}.dat")))),
    }
}

fn main() {
    let args: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| a != "--bench")
        .collect();
    let value = |key: &str| args.iter().find_map(|a| a.strip_prefix(&format!("{key}=")));
    let list = |key: &str, default: &str| -> Vec<usize> {
        value(key)
            .unwrap_or(default)
            .split(',')
            .map(|v| v.parse().unwrap_or_else(|_| panic!("{key}={v}: a number")))
            .collect()
    };
    let ns = list("n", "12");
    let layers = list("layers", "4")[0];
    if let Some(file) = value("write") {
        std::fs::write(file, deck(ns[0], layers)).unwrap_or_else(|e| panic!("{file}: {e}"));
        return;
    }
    let threads = list("threads", "1,2");
    // CalculiX stops at its default criterion (R_n = 0.005 of the average force): its first
    // increment, five iterations from rest, ends 4.4e-6 mm (3.3e-6 of the last w₀) from the
    // tight answer on n = 12, so 1e-5 is what its tolerance justifies; the others agree within
    // 1e-6.
    let tol: f64 = value("tol").map_or(1e-5, |v| v.parse().unwrap_or(1e-5));
    let mut disagreed = false;
    let with_ccx = args.iter().any(|a| a == "ccx");
    // CalculiX again, converged to the same answer (its FIELD controls, on a copy of the deck).
    let field = value("ccx_field").map(|v| {
        let f: Vec<f64> = v
            .split(',')
            .map(|x| {
                x.parse()
                    .unwrap_or_else(|_| panic!("ccx_field={v}: R_n,C_n"))
            })
            .collect();
        assert!(f.len() == 2, "ccx_field={v}: R_n,C_n");
        (f[0], f[1])
    });
    let tol_field: f64 = value("tol_field").map_or(1e-6, |v| v.parse().unwrap_or(1e-6));
    let newton = value("newton");
    let scratch = std::env::temp_dir().join(format!("nonlin3d-plate-decks-{}", std::process::id()));
    let exe = PathBuf::from(env!("CARGO_BIN_EXE_nonlin3d"));
    let load = std::fs::read_to_string("/proc/loadavg").unwrap_or_default();
    println!("load average at start: {}", load.trim());
    let field_head = field.map_or(String::new(), |(r, c)| {
        format!(
            " CalculiX R_n = {r:e}, C_n = {c:e}: wall / CPU, s | its iterations | ratio (wall) | \
             centre w, rel. diff |"
        )
    });
    println!(
        "| n | DOF | threads | nonlin3d wall / CPU, s | iterations / factorisations | CalculiX wall / CPU, s | CalculiX iterations | ratio (wall) | centre w, rel. diff | reaction, rel. diff |{field_head} load |"
    );
    println!(
        "|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|{}---|",
        if field.is_some() {
            "---:|---:|---:|---:|"
        } else {
            ""
        }
    );
    for &n in &ns {
        let dir = scratch.join(format!("n{n}"));
        std::fs::create_dir_all(&dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display()));
        let text = deck(n, layers);
        let inp = dir.join("plate.inp");
        std::fs::write(&inp, &text).unwrap_or_else(|e| panic!("{}: {e}", inp.display()));
        if let Some((r, c)) = field {
            let tight = text.replacen(
                "*STATIC, DIRECT",
                &format!("*CONTROLS, PARAMETERS=FIELD\n{r:e}, {c:e}\n*STATIC, DIRECT"),
                1,
            );
            let path = dir.join("plate_field.inp");
            std::fs::write(&path, tight).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        }
        for &t in &threads {
            let out = dir.join(format!("nonlin3d-{t}"));
            let mut cmd = Command::new(&exe);
            cmd.args(["-q", "--threads", &t.to_string(), "solve"])
                .arg(&inp)
                .arg("--out")
                .arg(&out);
            if let Some(s) = newton {
                cmd.args(["--newton", s]);
            }
            let (wall, cpu) = timed(&mut cmd);
            let mine = ours(&out);
            let counts = our_counts(&out);
            let mut check = |(dw, dr): (f64, f64), tol: f64, which: &str| {
                if dw > tol || dr > tol {
                    eprintln!("n = {n}: {which} answers differ by more than {tol:e}");
                    disagreed = true;
                }
            };
            let (ccx, diff) = if with_ccx {
                let run = calculix(&dir, "plate", t, &mine);
                check(run.diff, tol, "CalculiX's");
                (Some((run.wall, run.cpu, run.iterations)), Some(run.diff))
            } else {
                (None, None)
            };
            let tight = field.map(|_| {
                let run = calculix(&dir, "plate_field", t, &mine);
                check(run.diff, tol_field, "the tight run's");
                format!(
                    " {:.2} / {:.2} | {} | {:.1}× | {:.1e} |",
                    run.wall,
                    run.cpu,
                    run.iterations,
                    run.wall / wall,
                    run.diff.0
                )
            });
            let load = std::fs::read_to_string("/proc/loadavg").unwrap_or_default();
            let load: Vec<&str> = load.split_whitespace().take(3).collect();
            println!(
                "| {n} | {} | {t} | {wall:.2} / {cpu:.2} | {} / {} | {} | {} | {} | {} | {} |{} {} |",
                dof(&text),
                counts.0,
                counts.1,
                ccx.map_or("—".into(), |(w, c, _)| format!("{w:.2} / {c:.2}")),
                ccx.map_or("—".into(), |(_, _, i)| i.to_string()),
                ccx.map_or("—".into(), |(w, _, _)| format!("{:.1}×", w / wall)),
                diff.map_or("—".into(), |d| format!("{:.1e}", d.0)),
                diff.map_or("—".into(), |d| format!("{:.1e}", d.1)),
                tight.unwrap_or_default(),
                load.join(" ")
            );
            eprintln!(
                "n = {n}, {t} thread(s): w₀/h = {:.4} at the last increment ({} increments)",
                -mine.last().map_or(f64::NAN, |x| x.1) / H,
                mine.len()
            );
        }
    }
    if !args.iter().any(|a| a == "keep") {
        let _ = std::fs::remove_dir_all(&scratch);
    } else {
        println!("kept: {}", scratch.display());
    }
    if disagreed {
        std::process::exit(1);
    }
}
