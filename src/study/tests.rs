//! The knobs file: tables merged into the scene field by field (a case over `[common]` over
//! the scene), unknown fields refused naming the case and the field; study.csv's quoting.

#![allow(clippy::unwrap_used)]

use super::*;
use crate::scene::{CrackFacesName, ErrorEstimateName, NewtonName};

const PLAN: &str = r#"
[common.loads]
strains = [-0.004]
[common.mesh]
inside = 3
[common.contact]
crack_faces = "off"

[[case]]
name = "sliced"
mesh = { slices = 4 }

[[case]]
name = "bfgs, contact on"
analysis = { newton = "bfgs" }
contact = { crack_faces = "on" }
"#;

#[test]
fn knobs_merge_into_the_scene_field_by_field_case_over_common() {
    let base = Scene::thesis_reference().unwrap();
    // The base must differ from every knob set below, or the test could not fail.
    assert_eq!(base.mesh.slices, Some(8));
    assert_ne!(base.mesh.inside, Some(3));
    assert!(base.mesh.element.is_some());
    assert_eq!(base.loads.strains.len(), 5);
    assert_eq!(base.analysis.newton, NewtonName::Full);
    assert_ne!(base.contact.crack_faces, CrackFacesName::On);
    let plan = Plan::from_toml(PLAN).unwrap();
    let scenes = plan.scenes(&base).unwrap();
    assert_eq!(scenes.len(), 2);
    for s in &scenes {
        // [common] in every case; the fields no knob names kept from the scene.
        assert_eq!(s.loads.strains, [-0.004]);
        assert_eq!(s.mesh.inside, Some(3));
        assert_eq!(s.mesh.element, base.mesh.element);
        assert_eq!(s.geometry, base.geometry);
        assert_eq!(s.analysis.integration, base.analysis.integration);
        assert_eq!(s.analysis.threads, 1);
    }
    let (sliced, other) = (&scenes[0], &scenes[1]);
    assert_eq!(sliced.mesh.slices, Some(4));
    assert_eq!(sliced.contact.crack_faces, CrackFacesName::Off);
    assert_eq!(sliced.analysis.newton, NewtonName::Full);
    // The case's table over [common]'s of the same name, the scene's slices kept.
    assert_eq!(other.mesh.slices, Some(8));
    assert_eq!(other.contact.crack_faces, CrackFacesName::On);
    assert_eq!(other.analysis.newton, NewtonName::Bfgs);
    assert_eq!(describe(&plan.cases[0].knobs), "mesh.slices=4");
    assert_eq!(
        describe(&plan.cases[1].knobs),
        r#"analysis.newton="bfgs" contact.crack_faces="on""#
    );
}

#[test]
fn study_cases_skip_the_error_estimate_unless_asked() {
    // The scene as `nonlin3d run` reads it names no estimate (the run's default is the
    // companion); the study's cases keep it where their levels start from the companion's
    // (it pays for itself), run without it elsewhere (a plate, arc length), and a case or
    // [common.mesh] that names it has it its way.
    let base = Scene::thesis_reference().unwrap();
    assert_eq!(base.mesh.error_estimate, None);
    let plan = Plan::from_toml(
        "[[case]]\nname = \"plain\"\n\n[[case]]\nname = \"off\"\n\
         mesh = { error_estimate = \"off\" }\n\n[[case]]\nname = \"arc\"\n\
         analysis = { path = \"arc-length\" }\n",
    )
    .unwrap();
    let scenes = plan.scenes(&base).unwrap();
    let estimates: Vec<_> = scenes.iter().map(|s| s.mesh.error_estimate).collect();
    assert_eq!(
        estimates,
        [
            Some(ErrorEstimateName::Companion),
            Some(ErrorEstimateName::Off),
            Some(ErrorEstimateName::Off)
        ]
    );
    let plan = Plan::from_toml(
        "[[case]]\nname = \"plain\"\n\n[[case]]\nname = \"asks\"\n\
         mesh = { error_estimate = \"companion\" }\n",
    )
    .unwrap();
    // A scene that names the estimate itself keeps it in every case but one that names it.
    let mut named = base.clone();
    named.mesh.error_estimate = Some(ErrorEstimateName::Off);
    let scenes = plan.scenes(&named).unwrap();
    let estimates: Vec<_> = scenes.iter().map(|s| s.mesh.error_estimate).collect();
    assert_eq!(
        estimates,
        [
            Some(ErrorEstimateName::Off),
            Some(ErrorEstimateName::Companion)
        ]
    );
    // [common.mesh] for every case.
    let common =
        Plan::from_toml("[common.mesh]\nerror_estimate = \"off\"\n\n[[case]]\nname = \"a\"\n")
            .unwrap();
    let scenes = common.scenes(&base).unwrap();
    assert_eq!(scenes[0].mesh.error_estimate, Some(ErrorEstimateName::Off));
}

#[test]
fn unknown_fields_are_refused_naming_the_case_and_the_field() {
    for (text, table, field) in [
        (
            PLAN.replace("mesh = { slices = 4 }", "meshes = { slices = 4 }"),
            "case 'sliced'",
            "meshes",
        ),
        (
            PLAN.replace("[common.mesh]", "[common.geometry]"),
            "[common]",
            "geometry",
        ),
        (
            PLAN.replace(
                "name = \"bfgs, contact on\"",
                "name = \"bfgs\"\nfamliy = true",
            ),
            "case 'bfgs'",
            "famliy",
        ),
    ] {
        let e = Plan::from_toml(&text).unwrap_err().to_string();
        assert!(
            e.contains(&format!("{table}: unknown field `{field}`; it takes")),
            "{e}"
        );
        // toml's own report follows, with the line of the table.
        assert!(e.contains("TOML parse error at line"), "{e}");
    }
    // A field of the wrong type is toml's report alone, at its line.
    let text = PLAN.replace("name = \"sliced\"", "name = \"sliced\"\nh = \"x\"");
    let e = Plan::from_toml(&text).unwrap_err().to_string();
    assert!(e.contains("line 11") && !e.contains("unknown field"), "{e}");
}

fn case(name: &str, knobs: &str, failed: Option<&str>) -> CaseResult {
    let q = Quantities::from_values([Some(12.5), Some(0.25), None, None, None, Some(-2e-3)]);
    CaseResult {
        name: name.into(),
        knobs: knobs.into(),
        family: failed.is_none(),
        h: None,
        dofs: 600,
        wall_s: 1.5,
        cpu_s: Some(1.25),
        iterations: 9,
        values: q,
        errors: q,
        worst_g_error: Some(0.01),
        pareto: false,
        failed: failed.map(Into::into),
    }
}

/// study.csv: plain fields bare, a field with a comma, a quote or a line break quoted with its
/// quotes doubled (RFC 4180), so every row reads back to the header's length, fields whole.
#[test]
fn the_csv_quotes_the_fields_that_need_it() {
    let knobs = r#"mesh.slices=4 analysis.newton="bfgs""#;
    let study = Study {
        title: "t".into(),
        scene: "s".into(),
        jobs: 1,
        family_size: "given".into(),
        cases: vec![
            case("coarse", "mesh.slices=4", None),
            case("hex8, \"bfgs\"", knobs, Some("diverged\nat level 2")),
        ],
        references: vec![],
        worst_over: vec![],
    };
    let text = write::csv(&study);
    let lines: Vec<&str> = text.lines().collect();
    assert!(lines[0].starts_with("case,family,h,dofs,wall_s,cpu_s,iterations,g_t_max,"));
    assert!(lines[0].ends_with(",worst_g_error,pareto,failed,knobs"));
    assert_eq!(
        lines[1],
        "coarse,true,,600,1.5000,1.2500,9,1.25000000e1,2.50000000e-1,,,,-2.00000000e-3,\
         1.25000000e1,2.50000000e-1,,,,-2.00000000e-3,1.00000000e-2,false,,mesh.slices=4"
    );
    assert!(
        lines[2].starts_with(r#""hex8, ""bfgs""",false,"#),
        "{}",
        lines[2]
    );
    let mut reader = csv::Reader::from_reader(text.as_bytes());
    let header = reader.headers().unwrap().clone();
    let rows: Vec<csv::StringRecord> = reader.records().map(Result::unwrap).collect();
    assert_eq!(rows.len(), 2);
    assert!(rows.iter().all(|r| r.len() == header.len()));
    let column = |name: &str| header.iter().position(|h| h == name).unwrap();
    assert_eq!(&rows[1][column("case")], "hex8, \"bfgs\"");
    assert_eq!(&rows[1][column("failed")], "diverged\nat level 2");
    assert_eq!(&rows[1][column("knobs")], knobs);
}
