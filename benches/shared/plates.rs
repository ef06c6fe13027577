//! The scene plates the benches share, included with `#[path]` (a file under
//! `benches/shared/` is not a bench target of its own).

use nonlin3d::mesh::EmbeddedParams;

/// The thesis's plate model at about 89 k DOF (24 slices, 10 + 12 rings, 3 + 6 layers): the
/// scene model of issue 20's "one factorisation ≤ 1 s".
pub fn plate_89k() -> EmbeddedParams {
    EmbeddedParams {
        slices: 24,
        radial_inside: 10,
        radial_outside: 12,
        sub_layers: 3,
        base_layers: 6,
        ..EmbeddedParams::thesis_reference()
    }
}
