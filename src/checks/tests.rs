//! Tests of the scene checks (`checks`).
#![allow(clippy::unwrap_used)]
use crate::Scene;

fn reference() -> Scene {
    Scene::thesis_reference().unwrap()
}

/// A 30 mm through-width strip of the reference laminate.
fn through_width() -> crate::scene::Geometry {
    crate::scene::Geometry::ThroughWidth {
        a_mm: 15.0,
        length_mm: 60.0,
        width_mm: 5.0,
        h_mm: 0.4,
        base_mm: 4.0,
    }
}

fn message(s: &Scene) -> String {
    s.validate().unwrap_err().to_string()
}

#[test]
fn a_delamination_too_large_for_the_model_is_named_in_mm() {
    let mut s = reference();
    if let crate::scene::Geometry::Embedded { a_mm, b_mm, .. } = &mut s.geometry {
        *a_mm = 30.0;
        *b_mm = 42.0;
    }
    let m = message(&s);
    // W = 50 mm, 1.4 × 42 = 58.8 mm: the fields and the numbers in mm.
    assert!(m.contains("geometry.w_mm = 50 mm"), "{m}");
    assert!(m.contains("max(a_mm, b_mm)"), "{m}");
    assert!(m.contains("58.8"), "{m}");
    assert!(!m.contains("transition·"), "{m}");
}

#[test]
fn a_front_element_is_positive_and_not_for_through_width_models() {
    let mut s = reference();
    s.mesh.front_element_mm = Some(-0.1);
    assert!(message(&s).contains("mesh.front_element_mm = -0.1"));
    s.mesh.front_element_mm = Some(0.1);
    assert!(s.validate().is_ok());
    s.geometry = through_width();
    let m = message(&s);
    assert!(m.contains("through-width"), "{m}");
    s.mesh.front_element_mm = None;
    s.mesh.slices = None;
    s.mesh.front_band = Some([2, 2]);
    let m = message(&s);
    assert!(m.contains("mesh.front_band = [2, 2]"), "{m}");
    s.mesh.front_band = None;
    s.mesh.layer_band = Some([1, 1]);
    let m = message(&s);
    assert!(m.contains("mesh.layer_band = [1, 1]"), "{m}");
}

#[test]
fn counts_out_of_range_are_refused_before_meshing() {
    for (field, value) in [
        ("sub_layers", usize::MAX),
        ("inside", 4_294_967_297),
        ("slices", 0),
        ("slices", 7),
    ] {
        let mut s = reference();
        let slot = match field {
            "sub_layers" => &mut s.mesh.sub_layers,
            "inside" => &mut s.mesh.inside,
            _ => &mut s.mesh.slices,
        };
        *slot = Some(value);
        let m = message(&s);
        assert!(m.contains(&format!("mesh.{field} = {value}")), "{m}");
    }
}

/// Strains beyond ±0.1 are refused by index and value (they ground on for minutes before
/// failing); ±0.1 itself passes.
#[test]
fn strains_beyond_a_tenth_are_refused() {
    for (e, refused) in [
        (-0.1, false),
        (0.1, false),
        (-0.5, true),
        (2.0, true),
        (-3.0, true),
    ] {
        let mut s = reference();
        s.loads.strains = vec![-0.001, e];
        let r = s.validate();
        assert_eq!(r.is_err(), refused, "{e}: {r:?}");
        if let Err(m) = r {
            let m = m.to_string();
            assert!(m.contains(&format!("loads.strains[1] = {e}")), "{m}");
            assert!(m.contains("outside the material law"), "{m}");
        }
    }
}

/// Graphite/epoxy (ratio 39) and a ratio of exactly 10⁶ pass; 10¹² (fuzz case 50177) and a
/// zero shear modulus are refused with the field names.
#[test]
fn moduli_too_far_apart_are_refused() {
    let ortho = |e11: f64, g23: f64| crate::scene::MaterialSpec::Orthotropic {
        e11_gpa: e11,
        e22_gpa: 10.2,
        e33_gpa: 10.2,
        nu12: 0.3,
        nu13: 0.3,
        nu23: 0.49,
        g12_gpa: 5.52,
        g13_gpa: 5.52,
        g23_gpa: g23,
        homogenize: crate::scene::Homogenize::None,
    };
    assert!(super::material(&ortho(134.0, 3.43)).is_ok());
    assert!(super::material(&ortho(3.43e6, 3.43)).is_ok());
    let m = super::material(&ortho(1e6, 1e-6)).unwrap_err().to_string();
    assert!(
        m.contains("e11_gpa = 1000000 GPa") && m.contains("g23_gpa = 0.000001"),
        "{m}"
    );
    let m = super::material(&ortho(134.0, 0.0)).unwrap_err().to_string();
    assert!(m.contains("material.g23_gpa = 0"), "{m}");
}

#[test]
fn suspicious_input_is_warned_about() {
    assert!(super::warnings(&reference()).is_empty());
    let mut s = reference();
    s.loads.strains = vec![0.002, -0.08];
    if let crate::scene::Geometry::Embedded { h_mm, .. } = &mut s.geometry {
        *h_mm = 100.0;
    }
    let w = super::warnings(&s).join("\n");
    for part in ["is tensile", "above 5 %", "not thinner than", "thick for"] {
        assert!(w.contains(part), "{part}: {w}");
    }
}

#[test]
fn controls_and_loads_the_model_would_ignore_are_refused() {
    let mut s = reference();
    s.mesh.across = Some(2);
    assert!(message(&s).contains("mesh.across"));
    let mut s = reference();
    s.loads.transverse_n = vec![10.0];
    assert!(message(&s).contains("loads.transverse_n"));
}

#[test]
fn curved_edges_are_refused_where_there_are_no_curves_to_follow() {
    let mut s = reference();
    s.mesh.curved_edges = Some(true);
    assert!(s.validate().is_ok());
    s.mesh.element = Some(crate::scene::ElementName::Hex8);
    let m = message(&s);
    assert!(
        m.contains("mesh.curved_edges = true") && m.contains("Hex8"),
        "{m}"
    );
    s.mesh.element = None;
    s.mesh.slices = None;
    s.geometry = through_width();
    let m = message(&s);
    assert!(m.contains("through-width"), "{m}");
    s.mesh.curved_edges = Some(false);
    assert!(s.validate().is_ok(), "{}", message(&s));
}
