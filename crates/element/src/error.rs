//! The error type of `nonlin3d-element`.

use crate::{ElementKind, IntegrationRule};

/// What can go wrong in an element kernel. Each variant says where: the element (its index in
/// a batch, `None` for a single-element call), the station (quadrature point) or node.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ElementError {
    /// det J ≤ 0 (or not finite) at a quadrature point: the element is inverted or degenerate.
    #[error(
        "element {element:?}: Jacobian determinant {det} ≤ 0 at quadrature point {point} (ξ = {xi:?})"
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
    #[error("element {element:?}: {what} of node {node} is not finite: {value:?}")]
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
    #[error("integration rule {rule:?} is not defined for {kind:?}")]
    UnsupportedRule {
        /// The element kind.
        kind: ElementKind,
        /// The rule.
        rule: IntegrationRule,
    },
    /// The selective-reduced rule splits the energy into ε1–ε4 and ε5–ε6 parts; it needs
    /// C_ij = 0 between the two groups (the thesis's assumption, eq. 2.1.5).
    #[error(
        "element {element:?}: material {material} couples γyz/γxz with ε1–ε4 (relative {coupling:e}); the selective-reduced rule needs them decoupled"
    )]
    CoupledTransverseShear {
        /// Element index in a batch.
        element: Option<usize>,
        /// Material index.
        material: usize,
        /// max |C_ij| (i < 4 ≤ j) relative to the largest diagonal entry.
        coupling: f64,
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
            other => other,
        }
    }
}
