//! Shape data tabulated once per element kind and rule (thesis §2.4.1 eq. 2.4.1.2: "the
//! ∂N^m/∂δ_r are invariant, so they are calculated only once"; deal.II `FEValues`).

use crate::{ElementError, ElementKind, IntegrationRule, Station};

/// Shape values and reference gradients at every station of a rule, plus the layout the
/// kernels use. Build once per (kind, rule) and share it across elements and threads.
#[derive(Debug, Clone, PartialEq)]
pub struct ShapeTable {
    kind: ElementKind,
    rule: IntegrationRule,
    stations: Vec<Station>,
    values: Vec<f64>,
    gradients: Vec<[f64; 3]>,
    t_rows: usize,
}

impl ShapeTable {
    /// Tabulates `kind` at the stations of `rule`; an unsupported pair is an error.
    pub fn new(kind: ElementKind, rule: IntegrationRule) -> Result<Self, ElementError> {
        if !rule.supports(kind) {
            return Err(ElementError::UnsupportedRule { kind, rule });
        }
        let stations = rule.stations();
        let nn = kind.nodes();
        let mut values = vec![0.0; stations.len() * nn];
        let mut gradients = vec![[0.0; 3]; stations.len() * nn];
        for (g, s) in stations.iter().enumerate() {
            kind.shape_values(s.xi, &mut values[g * nn..(g + 1) * nn]);
            kind.shape_gradients(s.xi, &mut gradients[g * nn..(g + 1) * nn]);
        }
        let t_rows = stations.iter().map(Station::components).sum();
        Ok(Self {
            kind,
            rule,
            stations,
            values,
            gradients,
            t_rows,
        })
    }

    /// Element kind.
    pub fn kind(&self) -> ElementKind {
        self.kind
    }

    /// Integration rule.
    pub fn rule(&self) -> IntegrationRule {
        self.rule
    }

    /// Number of nodes.
    pub fn nodes(&self) -> usize {
        self.kind.nodes()
    }

    /// Number of DOFs (3 per node).
    pub fn dofs(&self) -> usize {
        self.kind.dofs()
    }

    /// The stations (quadrature points with their strain components).
    pub fn stations(&self) -> &[Station] {
        &self.stations
    }

    /// N^m at station `g`.
    pub fn values(&self, g: usize) -> &[f64] {
        let nn = self.nodes();
        &self.values[g * nn..(g + 1) * nn]
    }

    /// ∂N^m/∂ξ_r at station `g`.
    pub fn gradients(&self, g: usize) -> &[[f64; 3]] {
        let nn = self.nodes();
        &self.gradients[g * nn..(g + 1) * nn]
    }

    /// Rows of the stacked T matrix, Σ over stations of the components integrated there
    /// (48 for 2×2×2, 162 for 3×3×3, 34 for the selective-reduced Hex8).
    pub fn t_rows(&self) -> usize {
        self.t_rows
    }

    /// Row stride of the stacked T matrix: the DOF count rounded up to a multiple of 8 so
    /// the T^T·T kernel reads whole SIMD blocks.
    pub fn t_stride(&self) -> usize {
        self.dofs().div_ceil(8) * 8
    }
}
