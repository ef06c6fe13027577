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
    gradients_soa: Vec<f64>,
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
        // Structure of arrays per station: ∂N/∂ξ for all nodes, then ∂N/∂η, then ∂N/∂ζ
        // (the thesis's DL vector, eq. 2.4.1.2), so the kernels run along the nodes.
        let mut gradients_soa = vec![0.0; stations.len() * 3 * nn];
        for g in 0..stations.len() {
            for m in 0..nn {
                for r in 0..3 {
                    gradients_soa[g * 3 * nn + r * nn + m] = gradients[g * nn + m][r];
                }
            }
        }
        let t_rows = stations.iter().map(Station::components).sum();
        Ok(Self {
            kind,
            rule,
            stations,
            values,
            gradients,
            gradients_soa,
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

    /// ∂N^m/∂ξ_r at station `g` as three contiguous runs over the nodes (r-major, length
    /// 3·NS): the layout the kernels use.
    pub fn gradients_by_direction(&self, g: usize) -> &[f64] {
        let n3 = 3 * self.nodes();
        &self.gradients_soa[g * n3..(g + 1) * n3]
    }

    /// Rows of the stacked T matrix, Σ over stations of the components integrated there
    /// (48 for 2×2×2, 162 for 3×3×3, 34 for the selective-reduced Hex8).
    pub fn t_rows(&self) -> usize {
        self.t_rows
    }

    /// Floating-point operations (a fused multiply-add counts 2) of one [`evaluate`] call
    /// with the tangent, counting only useful work: per station the Jacobian, its inverse,
    /// the global gradients, ∇u, strains, stresses, forces (≈ 84·NS + 250), T = Qᵀ B √w
    /// (57 per DOF for six components), the geometric stiffness (15·NS + 5·NS(NS+1)/2), and
    /// once the lower triangle of TᵀT (rows·n(n+1)).
    ///
    /// [`evaluate`]: crate::evaluate
    pub fn flops_with_tangent(&self) -> u64 {
        let ns = self.nodes() as u64;
        let nd = self.dofs() as u64;
        let per_station: u64 = self
            .stations
            .iter()
            .map(|s| {
                let c = s.components() as u64;
                // T: Σ_{s} (c − s) FMAs per DOF plus the √w scaling.
                let t = nd * (c * (c + 1) + c);
                84 * ns + 250 + t + 15 * ns + 5 * ns * (ns + 1) / 2
            })
            .sum();
        per_station + self.t_rows as u64 * nd * (nd + 1)
    }

    /// Row stride of the stacked T matrix: the DOF count rounded up to a multiple of 8 so
    /// the T^T·T kernel reads whole SIMD blocks.
    pub fn t_stride(&self) -> usize {
        self.dofs().div_ceil(8) * 8
    }
}
