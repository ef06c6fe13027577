//! The `nonlin3d` program's eigen-check (thesis §2.5) gives the zero-energy mode counts the
//! element theory predicts for a distorted element of each kind and rule.

use nonlin3d::element::{ElementKind, IntegrationRule};

#[test]
fn eigen_check_counts_match_theory() {
    let rows = nonlin3d::eigen_check::run().unwrap();
    let count = |k, r| {
        rows.iter()
            .find(|row| row.kind == k && row.rule == r)
            .map(|row| row.zero_modes)
    };
    assert_eq!(count(ElementKind::Hex20, IntegrationRule::Gauss2), Some(12));
    assert_eq!(count(ElementKind::Hex20, IntegrationRule::Gauss3), Some(6));
    assert_eq!(count(ElementKind::Hex8, IntegrationRule::Gauss2), Some(6));
    // Distorted selective-reduced Hex8: between the 6 rigid-body modes and the 8 of the
    // undistorted element; this distortion leaves one spurious mode exactly zero.
    assert_eq!(
        count(ElementKind::Hex8, IntegrationRule::SelectiveReduced),
        Some(7)
    );
    for row in &rows {
        // Under compressive pre-stress only the three translations remain zero-energy.
        assert_eq!(row.zero_modes_stressed, 3, "{row:?}");
        assert!(
            row.first_nonzero > 1e-8 && row.first_nonzero < 1.0,
            "{row:?}"
        );
    }
    let text = nonlin3d::eigen_check::report(&rows);
    assert!(text.contains("Hex20") && text.contains("SelectiveReduced"));
}

#[test]
fn quasi_isotropic_material_is_transversely_isotropic() {
    let c = nonlin3d::eigen_check::quasi_isotropic().unwrap();
    let k = c.c();
    // (±45/0/90)s average: in-plane isotropic, C11 = C22, C44 = (C11 − C12)/2 to round-off.
    assert!((k[0][0] - k[1][1]).abs() < 1e-9 * k[0][0]);
    assert!((k[3][3] - 0.5 * (k[0][0] - k[0][1])).abs() < 1e-9 * k[0][0]);
}

/// `nonlin3d -q eigen-check` prints nothing and succeeds; without -q the table is printed.
#[test]
fn quiet_eigen_check_prints_nothing() {
    let run = |args: &[&str]| {
        let o = std::process::Command::new(env!("CARGO_BIN_EXE_nonlin3d"))
            .args(args)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        (o.stdout, o.stderr)
    };
    let (out, err) = run(&["-q", "eigen-check"]);
    assert!(
        out.is_empty() && err.is_empty(),
        "{}",
        String::from_utf8_lossy(&out)
    );
    let (out, _) = run(&["eigen-check"]);
    assert!(!out.is_empty());
}
