//! `.inp` keywords as CalculiX reads them: refusals naming line, keyword and parameter, data
//! read and not used listed with its line, *INCLUDE paths, steps inheriting loads and
//! boundaries, *STATIC, RIKS with Abaqus's defaults.

use nonlin3d_mesh::read_inp;

/// A one-element deck: a unit C3D8 cube, sets BOTTOM (z = 0) and TOP (z = 1), material AL.
fn cube() -> String {
    let mut d = String::from("*HEADING\ncube\n*NODE, NSET=ALLN\n");
    for (i, p) in [
        [0, 0, 0],
        [1, 0, 0],
        [1, 1, 0],
        [0, 1, 0],
        [0, 0, 1],
        [1, 0, 1],
        [1, 1, 1],
        [0, 1, 1],
    ]
    .iter()
    .enumerate()
    {
        d.push_str(&format!("{}, {}, {}, {}\n", i + 1, p[0], p[1], p[2]));
    }
    d.push_str(
        "*ELEMENT, TYPE=C3D8, ELSET=E\n1, 1, 2, 3, 4, 5, 6, 7, 8\n*NSET, NSET=BOTTOM\n1, 2, 3, 4\n\
         *NSET, NSET=TOP\n5, 6, 7, 8\n*MATERIAL, NAME=AL\n*ELASTIC\n70e9, 0.33\n\
         *SOLID SECTION, ELSET=E, MATERIAL=AL\n",
    );
    d
}

/// The deck's line count so far: the next line's number is this + 1.
fn lines(d: &str) -> usize {
    d.lines().count()
}

const STEP: &str = "*STEP, NLGEOM\n*STATIC\n0.5, 1.\n*BOUNDARY\nBOTTOM, 1, 3\n";

/// Every refusal names the line, the keyword and the parameter (or data field) concerned.
#[test]
fn refusals_name_line_keyword_and_parameter() {
    let cases: Vec<(String, &str, &str)> = vec![
        (
            "*NSET, NSET=z0, BOGUSPARAM=7\n1\n".into(),
            "*NSET, BOGUSPARAM",
            "not supported",
        ),
        (
            format!("{STEP}*END STEP\n").replace(
                "*STATIC\n0.5, 1.\n",
                "*STATIC, RIKS\n0.1, 1., , , 2., 70, 3, 0.5\n",
            ),
            "*STATIC data",
            "node 70",
        ),
        (
            format!("{STEP}*END STEP\n").replace(
                "*STATIC\n0.5, 1.\n",
                "*STATIC, RIKS\n0.1, 1., , , 2., 7, 3\n",
            ),
            "*STATIC data",
            "go together",
        ),
        (
            format!("{STEP}*END STEP\n")
                .replace("*STATIC\n0.5, 1.\n", "*STATIC, RIKS\n0.1, 1., 0.2\n"),
            "*STATIC data",
            "out of order",
        ),
        (
            format!("{STEP}*END STEP\n").replace("*STATIC\n", "*STATIC, RIKS, TIME RESET\n"),
            "*STATIC, TIME RESET",
            "not supported",
        ),
        (
            format!("{STEP}*CLOAD, AMPLITUDE=A\nTOP, 3, 1.\n*END STEP\n")
                .replace("*STEP", "*AMPLITUDE, NAME=A\n0, 0, 1, 1\n*STEP")
                .replace("*STATIC\n", "*STATIC, RIKS\n"),
            "*CLOAD data",
            "load proportionality factor",
        ),
        (
            format!("{STEP}*END STEP\n{STEP}*END STEP\n").replacen(
                "*STATIC\n",
                "*STATIC, RIKS\n",
                1,
            ),
            "*STEP",
            "after a *STATIC, RIKS step",
        ),
        (
            format!("{STEP}*CLOAD, FOLLOWER\nTOP, 3, 1.\n*END STEP\n"),
            "*CLOAD, FOLLOWER",
            "follower",
        ),
        (
            format!("{STEP}*CLOAD, OP=NEW, TIME DELAY=0.1\nTOP, 3, 1.\n*END STEP\n"),
            "*CLOAD, TIME DELAY",
            "not supported",
        ),
        (
            format!("{STEP}*BOUNDARY, OP=NEW\nTOP, 1\n*END STEP\n"),
            "*BOUNDARY, OP",
            "first *BOUNDARY",
        ),
        (
            format!("{STEP}*BOUNDARY, USER\nTOP, 1\n*END STEP\n"),
            "*BOUNDARY, USER",
            "not supported",
        ),
        (
            format!("{STEP}*DLOAD\nE, P6, 1.\n*END STEP\n"),
            "*DLOAD",
            "keyword not supported",
        ),
        (
            format!("{STEP}*TEMPERATURE\nALLN, 300.\n*END STEP\n"),
            "*TEMPERATURE",
            "keyword not supported",
        ),
        (
            format!("*CONTROLS, PARAMETERS=LINE SEARCH\n4\n{STEP}*END STEP\n"),
            "*CONTROLS, PARAMETERS",
            "LINE SEARCH",
        ),
        (
            format!("*CONTROLS, PARAMETERS=FIELD\n0.005, 0.01, 5.\n{STEP}*END STEP\n"),
            "*CONTROLS data",
            "q_0 = 5.",
        ),
        (
            format!("*CONTROLS, PARAMETERS=TIME INCREMENTATION\n6, 3, 7\n{STEP}*END STEP\n"),
            "*CONTROLS data",
            "I_P = 7",
        ),
        (
            format!("{STEP}*NODE PRINT, NSET=TOP, TIME POINTS=T\nU\n*END STEP\n"),
            "*NODE PRINT, TIME POINTS",
            "not supported",
        ),
        (
            format!("{STEP}*NODE PRINT, NSET=TOP\nNT\n*END STEP\n"),
            "*NODE PRINT data",
            "NT",
        ),
        (
            format!("{STEP}*EL PRINT, ELSET=E\nS, PEEQ\n*END STEP\n"),
            "*EL PRINT data",
            "PEEQ",
        ),
        (
            format!("{STEP}*EL FILE, NSET=TOP\nS\n*END STEP\n"),
            "*EL FILE, NSET",
            "not supported",
        ),
        (
            format!("{STEP}*NODE PRINT, NSET=TOP, TOTALS=YES\nU, RF\n*END STEP\n"),
            "*NODE PRINT, TOTALS",
            "RF alone",
        ),
        (
            "*ORIENTATION, NAME=C, SYSTEM=CYLINDRICAL\n0, 0, 0, 0, 0, 1\n3, 30.\n".into(),
            "*ORIENTATION data",
            "rectangular systems only",
        ),
        (
            "*STEP, PERTURBATION\n".into(),
            "*STEP, PERTURBATION",
            "not supported",
        ),
        (
            format!("{STEP}*END STEP\n*STEP, NLGEOM=NO\n*STATIC\n*END STEP\n"),
            "*STEP, NLGEOM",
            "after an NLGEOM step",
        ),
        (
            format!("{STEP}*CLOAD, AMPLITUDE=NOPE\nTOP, 3, 1.\n*END STEP\n"),
            "*CLOAD, AMPLITUDE",
            "not defined",
        ),
        (
            format!("{STEP}*CLOAD\nTOP, 3, 1., 7\n*END STEP\n"),
            "*CLOAD data",
            "expected",
        ),
        (
            format!("{STEP}*END STEP\n").replace("0.5, 1.\n", "0.5, 1., , , 0.1\n"),
            "*STATIC data",
            "fluid",
        ),
        (
            "*AMPLITUDE, NAME=A, USER\n".into(),
            "*AMPLITUDE, USER",
            "not supported",
        ),
        (
            "*AMPLITUDE, NAME=A, VALUE=ABSOLUTE\n0, 0, 1, 1\n".into(),
            "*AMPLITUDE, VALUE",
            "not supported",
        ),
        (
            "*PLASTIC\n1e8, 0.\n".into(),
            "*PLASTIC",
            "keyword not supported",
        ),
        (
            "*INCLUDE, INPUT=other.inp\n".into(),
            "*INCLUDE, INPUT",
            "read_inp_file",
        ),
    ];
    for (tail, what, why) in cases {
        let deck = cube() + &tail;
        // The offending line is the first line of the tail that the message names.
        let e = read_inp(&deck).unwrap_err().to_string();
        eprintln!("{e}");
        let line = e
            .split_once("line ")
            .and_then(|(_, r)| r.split(',').next())
            .and_then(|n| n.parse::<usize>().ok())
            .unwrap_or(0);
        assert!(
            line > lines(&cube()) && e.contains(what) && e.contains(why),
            "{tail}\n→ {e}"
        );
        let text = deck.lines().nth(line - 1).unwrap_or("");
        let keyword = what
            .split(',')
            .next()
            .unwrap()
            .split(' ')
            .take(2)
            .collect::<Vec<_>>()
            .join(" ");
        let keyword = keyword.trim_end_matches(" data");
        assert!(
            text.to_uppercase().starts_with(keyword) || what.ends_with(" data"),
            "line {line} is '{text}', not {what}: {e}"
        );
    }
}

/// Accepted and listed: data a static mechanical step does not use, each with its line.
#[test]
fn unused_data_is_listed_with_its_line() {
    let deck = cube().replace(
        "*ELASTIC\n70e9, 0.33\n",
        "*ELASTIC\n70e9, 0.33, 293.\n*DENSITY\n2.7e3\n*EXPANSION, ZERO=293.\n2.3e-5\n",
    ) + "*PHYSICAL CONSTANTS, ABSOLUTE ZERO=-273.15\n*INITIAL CONDITIONS, TYPE=TEMPERATURE\nALLN, 293.\n"
        + "*SURFACE, NAME=S1\nE, S2\n"
        + STEP
        + "*END STEP\n";
    let deck = deck.replace("*STATIC\n0.5, 1.\n", "*STATIC, SOLVER=SPOOLES\n0.5, 1.\n");
    let m = read_inp(&deck).unwrap();
    let listed: Vec<String> = m
        .not_used
        .iter()
        .map(|n| format!("{} {}", n.at, n.keyword))
        .collect();
    let line_of = |s: &str| deck.lines().position(|l| l.starts_with(s)).unwrap() + 1;
    for (kw, first) in [
        ("*HEADING", "*HEADING"),
        ("*ELASTIC temperature", "70e9"),
        ("*DENSITY", "*DENSITY"),
        ("*EXPANSION", "*EXPANSION"),
        ("*PHYSICAL CONSTANTS", "*PHYSICAL"),
        ("*INITIAL CONDITIONS, TYPE=TEMPERATURE", "*INITIAL"),
        ("*SURFACE", "*SURFACE"),
        ("*STATIC, SOLVER=SPOOLES", "*STATIC"),
    ] {
        let want = format!("line {} {kw}", line_of(first));
        assert!(
            listed.iter().any(|l| l.starts_with(&want)),
            "{want} not in {listed:?}"
        );
    }
    assert_eq!(listed.len(), 8, "{listed:?}");
}

/// `*INCLUDE, INPUT=` relative to the including file, nested; errors name the included file.
#[test]
fn includes_resolve_relative_to_the_including_file() {
    let dir = std::env::temp_dir().join(format!("nonlin3d-include-{}", std::process::id()));
    std::fs::create_dir_all(dir.join("sub")).unwrap();
    let cube = cube();
    let (mesh, rest) = cube.split_at(cube.find("*MATERIAL").unwrap());
    std::fs::write(dir.join("sub/mesh.inp"), mesh).unwrap();
    std::fs::write(dir.join("sub/outer.inp"), "*INCLUDE, INPUT=mesh.inp\n").unwrap();
    std::fs::write(
        dir.join("deck.inp"),
        format!("*INCLUDE, INPUT=sub/outer.inp\n{rest}{STEP}*END STEP\n"),
    )
    .unwrap();
    let m = nonlin3d_mesh::read_inp_file(&dir.join("deck.inp")).unwrap();
    assert_eq!(m.mesh.nodes.len(), 8);
    assert_eq!(m.steps.len(), 1);
    // An error inside the included file names it and its line.
    std::fs::write(
        dir.join("sub/mesh.inp"),
        mesh.replace("*NSET, NSET=TOP", "*NSET, NSET=TOP, X=1"),
    )
    .unwrap();
    let e = nonlin3d_mesh::read_inp_file(&dir.join("deck.inp"))
        .unwrap_err()
        .to_string();
    let line = mesh
        .lines()
        .position(|l| l.starts_with("*NSET, NSET=TOP"))
        .unwrap()
        + 1;
    assert!(
        e.contains(&format!("mesh.inp line {line}, *NSET, X")),
        "{e}"
    );
    // A file including itself.
    std::fs::write(dir.join("sub/outer.inp"), "*INCLUDE, INPUT=outer.inp\n").unwrap();
    let e = nonlin3d_mesh::read_inp_file(&dir.join("deck.inp"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("includes itself"), "{e}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// CalculiX's rules for what a step inherits: NLGEOM, *CONTROLS, output requests (the first
/// card of a kind in a step replaces the inherited ones) and one output frequency; sets that
/// list sets; OP=NEW flags.
#[test]
fn steps_inherit_as_calculix_does() {
    let deck = cube()
        + "*NSET, NSET=BOTH\nBOTTOM, TOP\n*ELSET, ELSET=E2\nE\n"
        + "*CONTROLS, PARAMETERS=FIELD\n1e-6, 1e-3\n"
        + STEP
        + "*NODE PRINT, NSET=TOP, FREQUENCY=3\nU\n*EL PRINT, ELSET=E2\nS\n*END STEP\n"
        + "*STEP\n*STATIC\n*CLOAD, OP=NEW\nTOP, 3, 1.\n*NODE PRINT, NSET=BOTH\nRF\n*END STEP\n"
        + "*CONTROLS, RESET\n*STEP, INC=7\n*STATIC, DIRECT\n0.25, 1.\n*BOUNDARY, OP=NEW\nBOTTOM, 3\n*END STEP\n";
    let m = read_inp(&deck).unwrap();
    assert_eq!(m.mesh.node_sets["BOTH"].len(), 8);
    assert_eq!(m.mesh.cell_sets["E2"], vec![0]);
    let s = &m.steps;
    assert!(s.iter().all(|s| s.nlgeom));
    assert_eq!(s[0].controls.residual_ratio, Some(1e-6));
    assert_eq!(s[1].controls.correction_ratio, Some(1e-3));
    assert_eq!(s[2].controls, nonlin3d_mesh::Controls::default());
    assert_eq!(
        s.iter().map(|s| s.output_frequency).collect::<Vec<_>>(),
        [3, 3, 3]
    );
    let kinds = |k: usize| {
        s[k].outputs
            .iter()
            .map(|o| (o.kind, o.set.clone().unwrap()))
            .collect::<Vec<_>>()
    };
    use nonlin3d_mesh::OutputKind::*;
    assert_eq!(
        kinds(0),
        [(NodePrint, "TOP".into()), (ElPrint, "E2".into())]
    );
    assert_eq!(
        kinds(1),
        [(ElPrint, "E2".into()), (NodePrint, "BOTH".into())]
    );
    assert_eq!(kinds(2), kinds(1));
    assert!(s[1].cload_op_new && !s[1].boundary_op_new);
    assert!(s[2].boundary_op_new && s[2].procedure.direct && s[2].max_increments == 7);
    assert_eq!(s[0].procedure.period, 1.0);
    assert_eq!(s[0].max_increments, 100);
}

/// `*STATIC, RIKS` is read with Abaqus's data line and defaults: Δl_in, l_period, Δl_min,
/// Δl_max, λ_end and the monitored node (as a mesh index), DOF and value; without a line the
/// defaults 1, 1, 1e-5, unbounded.
#[test]
fn riks_steps_are_read_with_abaqus_defaults() {
    let riks = |line: &str| {
        let deck = cube()
            + &format!("{STEP}*END STEP\n")
                .replace("*STATIC\n0.5, 1.\n", &format!("*STATIC, RIKS\n{line}"));
        read_inp(&deck).unwrap().steps[0]
            .procedure
            .riks
            .clone()
            .unwrap()
    };
    let r = riks("0.05, 2., , 0.5, 3., 7, 3, -0.25\n");
    assert_eq!(
        (r.initial, r.period, r.min, r.max, r.max_lpf),
        (0.05, 2.0, 2e-5, 0.5, Some(3.0))
    );
    assert_eq!(r.monitor, Some((6, 3, -0.25)));
    assert!(!r.direct);
    let d = riks("");
    assert_eq!((d.initial, d.period, d.min), (1.0, 1.0, 1e-5));
    assert!(d.max.is_infinite() && d.max_lpf.is_none() && d.monitor.is_none());
}
