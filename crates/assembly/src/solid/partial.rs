//! Internal forces of some cells alone (the door VCCT needs), and the re-attribution of an
//! element error to its mesh cell.

use super::Assembler;
use crate::AssemblyError;
use nonlin3d_element::{ElementError, ElementOutput, Kinematics, Workspace, evaluate};

/// Re-attributes a batch error (group-local element index) to the mesh cell.
pub(crate) fn relocate(err: ElementError, cells: &[usize]) -> ElementError {
    relabel(err, |e| e.and_then(|e| cells.get(e).copied()))
}

/// Replaces the element index of an error by `cell(index)`.
pub(crate) fn relabel(
    err: ElementError,
    cell: impl Fn(Option<usize>) -> Option<usize>,
) -> ElementError {
    match err {
        ElementError::NonPositiveJacobian {
            element,
            point,
            xi,
            det,
        } => ElementError::NonPositiveJacobian {
            element: cell(element),
            point,
            xi,
            det,
        },
        ElementError::NonFiniteInput {
            element,
            what,
            node,
            value,
        } => ElementError::NonFiniteInput {
            element: cell(element),
            what,
            node,
            value,
        },
        ElementError::CoupledTransverseShear {
            element,
            material,
            coupling,
        } => ElementError::CoupledTransverseShear {
            element: cell(element),
            material,
            coupling,
        },
        ElementError::MaterialAtPoint {
            element,
            material,
            point,
            x,
            reason,
        } => ElementError::MaterialAtPoint {
            element: cell(element),
            material,
            point,
            x,
            reason,
        },
        other => other,
    }
}

impl Assembler {
    /// Internal forces of the listed cells alone, f = Σ_cells ∫ Bᵀ S dV, node-major over the
    /// whole model, with `kinematics` (which may differ from the assembler's own): the forces a
    /// part of the model exerts at its nodes, as VCCT needs for the cells above the
    /// delamination plane (thesis §2.8: linear or nonlinear strain–displacement relations).
    pub fn partial_internal(
        &self,
        cells: &[usize],
        u: &[f64],
        kinematics: Kinematics,
    ) -> Result<Vec<f64>, AssemblyError> {
        if u.len() != self.n {
            return Err(AssemblyError::Length {
                what: "displacements",
                expected: self.n,
                got: u.len(),
            });
        }
        let mut f = vec![0.0; self.n];
        for &c in cells {
            let &(gi, i) = self.place.get(c).ok_or(AssemblyError::Length {
                what: "cell index",
                expected: self.place.len(),
                got: c,
            })?;
            let g = &self.groups[gi];
            let nn = g.table.nodes();
            let coords = &g.coords[i * nn..(i + 1) * nn];
            let disp: Vec<[f64; 3]> = self.dofs[c]
                .chunks_exact(3)
                .map(|d| [u[d[0]], u[d[1]], u[d[2]]])
                .collect();
            let mut out = ElementOutput::new(&g.table);
            let mut ws = Workspace::new(&g.table);
            evaluate(
                &g.table,
                coords,
                &disp,
                &self.stiffness[g.material_of[i]],
                kinematics,
                false,
                &mut ws,
                &mut out,
            )
            .map_err(|e| relabel(e, |_| Some(c)))?;
            for (a, &d) in self.dofs[c].iter().enumerate() {
                f[d] += out.forces[a];
            }
        }
        Ok(f)
    }
}
