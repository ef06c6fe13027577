//! The condensed linear region as "just another element" (thesis §2.6): a constant dense
//! stiffness K_red on the interface DOFs and a condensed load, a [`Contribution`] to the
//! nonlinear region's [`System`](nonlin3d_assembly::System).

use crate::SubstructureError;
use nonlin3d_assembly::{AssemblyError, Contribution};
use nonlin3d_solver::{SymmetricMatrix, SymmetricPattern};
use std::sync::Arc;

/// The condensed load f_c(λ) = λ (`load` + `prescribed`) + `dead` on the interface DOFs
/// (superelement order). Sign convention: an external force on the nonlinear region's
/// interface nodes, positive along the axes — what the linear region, loaded and with its
/// interior prescribed values imposed while the interface is held at u_b = 0, pushes on the
/// interface with (the interface reaction of that clamped problem, reversed):
///
/// - `load` = −K_bi K_ii⁻¹ f_i per unit λ (the interior's nodal loads, carried to Γ);
/// - `prescribed` = −(K_bp − K_bi K_ii⁻¹ K_ip) v per unit λ, v the interior's prescribed values
///   at λ = 1 (e.g. u = W·ε on x = W: a strain sweep scales it, no new condensation);
/// - `dead` = the same two for the λ-independent parts (dead loads, ramp bases).
#[derive(Debug, Clone, PartialEq)]
pub struct CondensedLoad {
    /// Per unit λ, from the interior's nodal loads.
    pub load: Vec<f64>,
    /// Per unit λ, from the interior's prescribed values.
    pub prescribed: Vec<f64>,
    /// λ-independent part.
    pub dead: Vec<f64>,
}

/// A superelement: K_red (dense, symmetric) on `dofs` of the nonlinear system, with
/// f_int = K_red u_b, ∂f_int/∂u = K_red, E = ½ u_bᵀ K_red u_b, and f_ext(λ) the
/// [`CondensedLoad`].
#[derive(Debug, Clone)]
pub struct Superelement {
    dofs: Vec<usize>,
    /// Row-major, dofs.len()².
    k: Vec<f64>,
    load: CondensedLoad,
    /// Scale of the prescribed part of the load (1 = as condensed).
    prescribed_scale: f64,
    /// The adopted pattern and the positions of the lower-triangle entries in it (row-major,
    /// None above the diagonal).
    map: Option<(Arc<SymmetricPattern>, Vec<Option<usize>>)>,
}

impl Superelement {
    /// A superelement of stiffness `k` (row-major, `dofs.len()`², symmetric) and load `load`
    /// on `dofs`.
    pub fn new(
        dofs: Vec<usize>,
        k: Vec<f64>,
        load: CondensedLoad,
    ) -> Result<Self, SubstructureError> {
        let nb = dofs.len();
        for (what, got, expected) in [
            ("superelement stiffness entries", k.len(), nb * nb),
            ("condensed load (nodal loads)", load.load.len(), nb),
            (
                "condensed load (prescribed values)",
                load.prescribed.len(),
                nb,
            ),
            ("condensed load (dead)", load.dead.len(), nb),
        ] {
            if got != expected {
                return Err(SubstructureError::Length {
                    what,
                    expected,
                    got,
                });
            }
        }
        Ok(Self {
            dofs,
            k,
            load,
            prescribed_scale: 1.0,
            map: None,
        })
    }

    /// The DOFs (in the nonlinear system's numbering).
    pub fn dofs(&self) -> &[usize] {
        &self.dofs
    }

    /// K_red, row-major.
    pub fn stiffness(&self) -> &[f64] {
        &self.k
    }

    /// The condensed load's parts.
    pub fn load(&self) -> &CondensedLoad {
        &self.load
    }

    /// Scales the part of the condensed load due to the interior's prescribed values, e.g.
    /// to a new end strain without condensing again (they are linear in the values).
    pub fn set_prescribed_scale(&mut self, scale: f64) {
        self.prescribed_scale = scale;
    }

    /// K_red · (v at the DOFs).
    fn product(&self, v: &[f64]) -> Vec<f64> {
        let nb = self.dofs.len();
        let vb: Vec<f64> = self.dofs.iter().map(|&d| v[d]).collect();
        (0..nb)
            .map(|a| {
                self.k[a * nb..(a + 1) * nb]
                    .iter()
                    .zip(&vb)
                    .map(|(k, x)| k * x)
                    .sum()
            })
            .collect()
    }

    /// Checks `v` reaches every DOF.
    fn check(&self, what: &'static str, v: &[f64]) -> Result<(), AssemblyError> {
        match self.dofs.iter().max() {
            Some(&d) if d >= v.len() => Err(AssemblyError::Length {
                what,
                expected: d + 1,
                got: v.len(),
            }),
            _ => Ok(()),
        }
    }
}

impl Contribution for Superelement {
    /// One dense block over the interface DOFs.
    fn couplings(&self) -> Vec<Vec<usize>> {
        vec![self.dofs.clone()]
    }

    /// Precomputes the position of every lower-triangle entry in the system's pattern.
    fn adopt(&mut self, pattern: &Arc<SymmetricPattern>) -> Result<(), AssemblyError> {
        self.map = Some((pattern.clone(), pattern.scatter_map(&self.dofs)?));
        Ok(())
    }

    fn add(
        &self,
        u: &[f64],
        internal: &mut [f64],
        tangent: Option<&mut SymmetricMatrix>,
    ) -> Result<f64, AssemblyError> {
        self.check("displacements", u)?;
        self.check("internal forces", internal)?;
        let f = self.product(u);
        let mut energy = 0.0;
        for (&d, fd) in self.dofs.iter().zip(&f) {
            internal[d] += fd;
            energy += 0.5 * fd * u[d];
        }
        if let Some(t) = tangent {
            match &self.map {
                Some((p, map)) if Arc::ptr_eq(p, t.pattern()) => {
                    t.scatter_add_mapped(map, &self.k)?
                }
                _ => t.scatter_add(&self.dofs, &self.k)?,
            }
        }
        Ok(energy)
    }

    fn add_product(&self, _u: &[f64], v: &[f64], y: &mut [f64]) -> Result<(), AssemblyError> {
        self.check("product vector", v)?;
        self.check("product", y)?;
        for (&d, x) in self.dofs.iter().zip(self.product(v)) {
            y[d] += x;
        }
        Ok(())
    }

    /// f_ext += λ (load + s·prescribed) + dead, s the prescribed scale.
    fn add_external(&self, lambda: f64, f_ext: &mut [f64]) {
        let l = &self.load;
        for (a, &d) in self.dofs.iter().enumerate() {
            if let Some(f) = f_ext.get_mut(d) {
                *f += lambda * (l.load[a] + self.prescribed_scale * l.prescribed[a]) + l.dead[a];
            }
        }
    }
}
