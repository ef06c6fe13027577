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
