//! `.inp` writer ↔ reader: round trips, located errors, and a fuzz over mutated decks.

use nonlin3d_element::ElementKind;
use nonlin3d_laminate::materials;
use nonlin3d_mesh::inp::{
    InpBoundary, InpCload, InpDeck, InpElastic, InpMaterial, InpStep, inp_string,
};
use nonlin3d_mesh::{
    BoxParams, EmbeddedParams, Mesh, NodeRef, embedded_delamination, read_inp, structured_box,
};
use proptest::prelude::*;

fn two_materials() -> Vec<InpMaterial> {
    vec![
        InpMaterial {
            name: "BASE".into(),
            elastic: InpElastic::Isotropic { e: 207e9, nu: 0.3 },
        },
        InpMaterial {
            name: "PLY".into(),
            elastic: InpElastic::Engineering(materials::generic_graphite_epoxy()),
        },
    ]
}

fn deck_for(mesh: &Mesh, steps: Vec<InpStep>) -> String {
    let mats = two_materials();
    inp_string(&InpDeck {
        heading: "round trip".into(),
        mesh,
        materials: &mats,
        steps,
    })
    .unwrap()
}

fn step() -> InpStep {
    InpStep {
        nlgeom: true,
        increment: 0.1,
        period: 1.0,
        boundaries: vec![
            InpBoundary {
                nset: "x0".into(),
                first: 1,
                last: 3,
                value: 0.0,
            },
            InpBoundary {
                nset: "x1".into(),
                first: 1,
                last: 1,
                value: -1e-5,
            },
        ],
        cloads: vec![InpCload {
            node: 3,
            dof: 3,
            value: -2.5,
        }],
    }
}

fn assign_plies(mesh: &mut Mesh) {
    let top: Vec<usize> = mesh
        .cell_sets
        .get("sublaminate")
        .cloned()
        .unwrap_or_else(|| (0..mesh.cells.len() / 2).collect());
    for c in top {
        mesh.cells[c].material = 1;
        mesh.cells[c].ply_angle_deg = 45.0;
    }
}

#[test]
fn structured_box_round_trips_exactly() {
    let mut p = BoxParams::new(ElementKind::Hex20, [3, 2, 2], [3e-3, 2e-3, 1e-3]);
    p.grading = [0.5, 1.0, 1.0];
    let mut mesh = structured_box(&p).unwrap();
    assign_plies(&mut mesh);
    let model = read_inp(&deck_for(&mesh, vec![step()])).unwrap();
    // Every coordinate of this mesh has a short exact representation: bit-for-bit equal.
    let exact = mesh
        .nodes
        .iter()
        .flatten()
        .all(|v| format!("{v:?}").len() <= 20);
    for (a, b) in mesh.nodes.iter().zip(&model.mesh.nodes) {
        if exact {
            assert_eq!(a, b);
        } else {
            assert!(
                a.iter()
                    .zip(b)
                    .all(|(x, y)| (x - y).abs() <= 1e-12 * x.abs().max(1e-3))
            );
        }
    }
    assert_eq!(model.mesh.cells, mesh.cells);
    // The writer adds NALL (all nodes, for its output requests); everything else is the mesh's.
    let mut read_sets = model.mesh.node_sets.clone();
    assert_eq!(
        read_sets.remove("NALL").map(|s| s.len()),
        Some(mesh.nodes.len())
    );
    assert_eq!(read_sets, mesh.node_sets);
    assert_eq!(model.mesh.cell_sets["all"], mesh.cell_sets["all"]);
    assert_eq!(model.node_ids, (1..=mesh.nodes.len()).collect::<Vec<_>>());
    assert_eq!(model.materials, two_materials());
    assert_eq!(model.steps.len(), 1);
    let s = &model.steps[0];
    assert!(s.nlgeom);
    assert_eq!((s.procedure.initial, s.procedure.period), (0.1, 1.0));
    assert_eq!(s.boundaries.len(), 2);
    assert_eq!(s.boundaries[1].value, -1e-5);
    assert_eq!(s.cloads[0].target, NodeRef::Node(3));
    assert_eq!(s.cloads[0].value, -2.5);
}

#[test]
fn embedded_delamination_round_trips_with_ply_angles() {
    let mut mesh = embedded_delamination(&EmbeddedParams {
        slices: 4,
        ..EmbeddedParams::thesis_reference()
    })
    .unwrap();
    assign_plies(&mut mesh);
    let model = read_inp(&deck_for(&mesh, vec![])).unwrap();
    assert_eq!(
        model.mesh.cells, mesh.cells,
        "connectivity, materials and ply angles"
    );
    for (a, b) in mesh.nodes.iter().zip(&model.mesh.nodes) {
        // 13 significant digits where the exact form does not fit CalculiX's 20 characters.
        assert!(a.iter().zip(b).all(|(x, y)| (x - y).abs() <= 1e-12 * 0.05));
    }
    assert_eq!(
        model.mesh.node_sets["crack_upper"].len(),
        mesh.node_sets["crack_upper"].len()
    );
}

fn error_text(deck: &str) -> String {
    read_inp(deck).unwrap_err().to_string()
}

#[test]
fn errors_name_the_keyword_and_line() {
    let base = "*NODE\n1, 0, 0, 0\n2, 1, 0, 0\n";
    let e = error_text(&format!("{base}*DYNAMIC\n0.1, 1.\n"));
    assert!(
        e.contains("line 4") && e.contains("DYNAMIC") && e.contains("not supported"),
        "{e}"
    );
    let e = error_text("*NODE\n1, 0, zero, 0\n");
    assert!(
        e.contains("line 2") && e.contains("'zero' is not a number"),
        "{e}"
    );
    let e = error_text(&format!(
        "{base}*ELEMENT, TYPE=C3D8, ELSET=A\n1, 1, 2, 3, 4, 5, 6, 7, 8\n"
    ));
    assert!(
        e.contains("line 5") && e.contains("node 3 is not defined"),
        "{e}"
    );
    let e = error_text(&format!("{base}*ELEMENT, TYPE=C3D4\n"));
    assert!(e.contains("C3D4"), "{e}");
    let e = error_text(&format!("{base}*STEP\n*STATIC\n"));
    assert!(e.contains("missing *END STEP"), "{e}");
    let e = error_text(&format!("{base}*BOUNDARY\nNOPE, 1, 3\n"));
    assert!(e.contains("line 5") && e.contains("node set 'NOPE'"), "{e}");
}

#[test]
fn generate_sets_and_initial_boundaries() {
    let mut deck = String::from("*NODE\n");
    for i in 1..=8 {
        deck.push_str(&format!(
            "{i}, {}, {}, {}\n",
            i % 2,
            (i / 2) % 2,
            (i / 4) % 2
        ));
    }
    deck.push_str("*ELEMENT, TYPE=C3D8, ELSET=E\n10, 1, 2, 4, 3, 5, 6, 8, 7\n*NSET, NSET=BOTTOM, GENERATE\n1, 4\n*NSET, NSET=ODD, GENERATE\n1, 7, 2\n");
    deck.push_str("*MATERIAL, NAME=AL\n*ELASTIC\n72e9, 0.33\n*SOLID SECTION, ELSET=E, MATERIAL=AL\n*BOUNDARY\nBOTTOM, 3\n");
    let m = read_inp(&deck).unwrap();
    assert_eq!(m.mesh.node_sets["BOTTOM"], vec![0, 1, 2, 3]);
    assert_eq!(m.mesh.node_sets["ODD"], vec![0, 2, 4, 6]);
    assert_eq!(m.element_ids, vec![10]);
    assert_eq!(m.initial_boundaries.len(), 1);
    assert_eq!(m.initial_boundaries[0].first, 3);
    assert_eq!(
        m.materials[0].elastic,
        InpElastic::Isotropic { e: 72e9, nu: 0.33 }
    );
}

/// A small valid deck to mutate.
/// A set that a `*BOUNDARY`, `*CLOAD` or output request names and that has no members would act
/// on nothing: refused with the line that uses it, the keyword, the set and where it was
/// defined. Each element keeps the line it was defined on, for later messages.
#[test]
fn an_empty_set_in_use_is_refused_and_elements_keep_their_lines() {
    let mut base = String::from("*NODE\n");
    for i in 1..=8 {
        base.push_str(&format!(
            "{i}, {}, {}, {}\n",
            i % 2,
            (i / 2) % 2,
            (i / 4) % 2
        ));
    }
    // Lines 1–9 nodes; 10–11 the element; 12 the empty set; 13 a used one.
    base.push_str("*ELEMENT, TYPE=C3D8, ELSET=E\n10, 1, 2, 4, 3, 5, 6, 8, 7\n*NSET, NSET=NONE\n");
    base.push_str("*NSET, NSET=BOTTOM, GENERATE\n1, 4\n*ELSET, ELSET=NOEL\n");
    base.push_str(
        "*MATERIAL, NAME=AL\n*ELASTIC\n72e9, 0.33\n*SOLID SECTION, ELSET=E, MATERIAL=AL\n",
    );
    let step = |body: &str| format!("{base}*STEP\n*STATIC\n{body}*END STEP\n");
    let line_of =
        |deck: &str, start: &str| deck.lines().position(|l| l.starts_with(start)).unwrap() + 1;
    let ok = read_inp(&step("*BOUNDARY\nBOTTOM, 3\n")).unwrap();
    assert_eq!(ok.element_at, ["line 11"]);
    for (body, used, what) in [
        (
            "*BOUNDARY\nBOTTOM, 3\nnone, 1, 3\n",
            "none, 1",
            "*BOUNDARY data",
        ),
        ("*CLOAD\nNONE, 3, 1.\n", "NONE, 3", "*CLOAD data"),
        (
            "*NODE PRINT, NSET=none\nU\n",
            "*NODE PRINT",
            "*NODE PRINT, NSET",
        ),
        (
            "*EL PRINT, ELSET=NOEL\nS\n",
            "*EL PRINT",
            "*EL PRINT, ELSET",
        ),
    ] {
        let deck = step(body);
        let e = error_text(&deck);
        let set = if what.starts_with("*EL") {
            "element set 'NOEL'"
        } else {
            "node set 'NONE'"
        };
        let defined = line_of(
            &deck,
            if what.starts_with("*EL") {
                "*ELSET, ELSET=NOEL"
            } else {
                "*NSET, NSET=NONE"
            },
        );
        let want = format!(
            "line {}, {what}: {set} (defined at line {defined}) is empty",
            line_of(&deck, used)
        );
        assert!(e.contains(&want), "{want} not in {e}");
    }
    // Model data too.
    let e = error_text(&format!("{base}*BOUNDARY\nNONE, 1\n"));
    assert!(
        e.contains("node set 'NONE'") && e.contains("is empty"),
        "{e}"
    );
}

fn sample_deck() -> String {
    let mut mesh = structured_box(&BoxParams::new(
        ElementKind::Hex20,
        [2, 1, 1],
        [2e-3, 1e-3, 1e-3],
    ))
    .unwrap();
    assign_plies(&mut mesh);
    deck_for(&mesh, vec![step()])
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 512, .. ProptestConfig::default() })]

    /// Whatever a deck is mutated into, the reader answers Ok or a located error; it never
    /// panics (a panic fails the test).
    #[test]
    fn mutated_decks_never_panic(
        ops in proptest::collection::vec((0u8..5, any::<usize>(), any::<char>()), 1..6),
    ) {
        let mut lines: Vec<String> = sample_deck().lines().map(String::from).collect();
        for (op, at, ch) in ops {
            if lines.is_empty() {
                break;
            }
            let k = at % lines.len();
            match op {
                0 => { lines.remove(k); }
                1 => { let l = lines[k].clone(); lines.insert(k, l); }
                2 => {
                    let mut chars: Vec<char> = lines[k].chars().collect();
                    if !chars.is_empty() {
                        let p = at % chars.len();
                        chars[p] = ch;
                    }
                    lines[k] = chars.into_iter().collect();
                }
                3 => { let keep = at % (lines[k].chars().count() + 1); lines[k] = lines[k].chars().take(keep).collect(); }
                _ => { let j = (at / 7) % lines.len(); lines.swap(k, j); }
            }
        }
        let deck = lines.join("\n");
        match read_inp(&deck) {
            Ok(m) => prop_assert!(m.mesh.validate().is_ok()),
            Err(e) => prop_assert!(e.to_string().contains("line") || e.to_string().contains("node") || e.to_string().contains("cell")),
        }
    }
}

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
