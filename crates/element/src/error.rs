//! The error type of `nonlin3d-element`.

use crate::{ElementKind, IntegrationRule};

/// What can go wrong in an element kernel. Each variant says where: the element (its index in
/// a batch, `None` for a single-element call), the station (quadrature point) or node.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ElementError {
    /// det J ≤ 0 (or not finite) at a quadrature point: the element is inverted or degenerate.
    #[error(
        "{}: Jacobian determinant {det:e} ≤ 0 at quadrature point {point} (ξ, η, ζ) = {}: the element is inverted or degenerate",
        which(*element),
        triple(xi)
    )]
    NonPositiveJacobian {
        /// Element index in a batch.
        element: Option<usize>,
        /// Station index in the rule's order.
        point: usize,
        /// Reference coordinates of the station.
        xi: [f64; 3],
        /// The determinant found.
        det: f64,
    },
    /// A coordinate or displacement is NaN or infinite.
    #[error("{}: {what} of its node {node} are not finite: {}", which(*element), triple(value))]
    NonFiniteInput {
        /// Element index in a batch.
        element: Option<usize>,
        /// `"coordinates"` or `"displacements"`.
        what: &'static str,
        /// Local node index (Abaqus order).
        node: usize,
        /// The offending triple.
        value: [f64; 3],
    },
    /// A buffer or input has the wrong length.
    #[error("{what}: expected length {expected}, got {got}")]
    LengthMismatch {
        /// Which input.
        what: &'static str,
        /// Length required.
        expected: usize,
        /// Length given.
        got: usize,
    },
    /// The rule does not exist for this element (the selective-reduced rule is Hex8-only).
    #[error("the {} integration rule is not defined for {} elements", rule_name(*rule), kind_name(*kind))]
    UnsupportedRule {
        /// The element kind.
        kind: ElementKind,
        /// The rule.
        rule: IntegrationRule,
    },
    /// The selective-reduced rule splits the energy into ε1–ε4 and ε5–ε6 parts; it needs
    /// C_ij = 0 between the two groups (the thesis's assumption, eq. 2.1.5).
    #[error(
        "{}: material {material} couples γyz/γxz with ε1–ε4 (relative {coupling:e}); the selective-reduced rule needs them decoupled",
        which(*element)
    )]
    CoupledTransverseShear {
        /// Element index in a batch.
        element: Option<usize>,
        /// Material index.
        material: usize,
        /// max |C_ij| (i < 4 ≤ j) relative to the largest diagonal entry.
        coupling: f64,
    },
    /// A material given in axes that vary with the position is not a valid stiffness once
    /// turned to the axes at a quadrature point (it lost definiteness to round-off).
    #[error(
        "{}: material {material} turned to its axes at quadrature point {point}, {}, is not a valid stiffness: {reason}",
        which(*element),
        triple(x)
    )]
    MaterialAtPoint {
        /// Element index in a batch.
        element: Option<usize>,
        /// Material index.
        material: usize,
        /// Station index in the rule's order.
        point: usize,
        /// Global coordinates of the station.
        x: [f64; 3],
        /// What is wrong with the turned stiffness.
        reason: String,
    },
    /// A material index is out of range.
    #[error("element {element}: material index {material} out of range ({count} materials)")]
    MaterialIndex {
        /// Element index.
        element: usize,
        /// The index given.
        material: usize,
        /// Number of materials.
        count: usize,
    },
}

/// "element 19", or "the element" for a single-element call.
fn which(element: Option<usize>) -> String {
    element.map_or_else(|| "the element".to_string(), |e| format!("element {e}"))
}

/// "(x, y, z)" with each entry in shortest round-trip form.
fn triple(v: &[f64; 3]) -> String {
    format!("({}, {}, {})", v[0], v[1], v[2])
}

fn kind_name(kind: ElementKind) -> &'static str {
    match kind {
        ElementKind::Hex8 => "Hex8",
        ElementKind::Hex20 => "Hex20",
    }
}

fn rule_name(rule: IntegrationRule) -> &'static str {
    match rule {
        IntegrationRule::Gauss2 => "2×2×2 Gauss",
        IntegrationRule::Gauss3 => "3×3×3 Gauss",
        IntegrationRule::SelectiveReduced => "selective-reduced",
    }
}

impl ElementError {
    /// The same error, attributed to element `e` of a batch.
    pub fn at_element(self, e: usize) -> Self {
        match self {
            Self::NonPositiveJacobian { point, xi, det, .. } => Self::NonPositiveJacobian {
                element: Some(e),
                point,
                xi,
                det,
            },
            Self::NonFiniteInput {
                what, node, value, ..
            } => Self::NonFiniteInput {
                element: Some(e),
                what,
                node,
                value,
            },
            Self::CoupledTransverseShear {
                material, coupling, ..
            } => Self::CoupledTransverseShear {
                element: Some(e),
                material,
                coupling,
            },
            Self::MaterialAtPoint {
                material,
                point,
                x,
                reason,
                ..
            } => Self::MaterialAtPoint {
                element: Some(e),
                material,
                point,
                x,
                reason,
            },
            other => other,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Messages are for users: no `Some(…)`, `None` or `[…]` from Debug formatting.
    #[test]
    fn messages_read_as_words() {
        let errors = [
            ElementError::NonPositiveJacobian {
                element: Some(19),
                point: 3,
                xi: [0.5, -0.5, 0.5],
                det: -2e-9,
            },
            ElementError::NonFiniteInput {
                element: None,
                what: "displacements",
                node: 4,
                value: [f64::NAN, 0.0, 1.0],
            },
            ElementError::UnsupportedRule {
                kind: ElementKind::Hex20,
                rule: IntegrationRule::SelectiveReduced,
            },
            ElementError::NonPositiveJacobian {
                element: None,
                point: 0,
                xi: [0.0; 3],
                det: 0.0,
            }
            .at_element(7),
        ];
        let text: Vec<String> = errors.iter().map(|e| e.to_string()).collect();
        for t in &text {
            assert!(
                !t.contains("Some(") && !t.contains("None") && !t.contains('['),
                "{t}"
            );
        }
        assert!(text[0].starts_with("element 19: "), "{}", text[0]);
        assert!(text[1].starts_with("the element: "), "{}", text[1]);
        assert!(text[2].contains("selective-reduced") && text[2].contains("Hex20"));
        assert!(text[3].starts_with("element 7: "), "{}", text[3]);
    }
}
