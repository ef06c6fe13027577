//! Stresses at the integration points of listed cells, for output (thesis §2.1: the kernels'
//! second Piola–Kirchhoff stresses S = C ε of the Green–Lagrange strain, pushed forward to
//! Cauchy stresses σ = F S Fᵀ / det F with F = I + ∂u/∂X; small-strain σ = C ε with linear
//! kinematics). Off the hot path: one element evaluation per listed cell, no tangent.

use crate::AssemblyError;
use nonlin3d_element::{
    ElementKind, ElementOutput, IntegrationRule, Kinematics, Material, ShapeTable, Workspace,
    evaluate,
};
use nonlin3d_laminate::{ShearCoupling, Stiffness};
use nonlin3d_mesh::Mesh;

/// How the stresses of a mesh are evaluated: the same materials, rules and kinematics as the
/// [`Assembler`](crate::Assembler) built from the same arguments.
#[derive(Debug, Clone, Copy)]
pub struct StressRules<'a, M = Stiffness> {
    /// Materials in ply axes, by `cell.material`, rotated about z by each cell's ply angle
    /// (stiffnesses, or [`Material`]s whose axes may vary with the position).
    pub materials: &'a [M],
    /// Rotation coupling, as for the assembler.
    pub coupling: ShearCoupling,
    /// Rule of Hex20 cells.
    pub hex20_rule: IntegrationRule,
    /// Rule of Hex8 cells.
    pub hex8_rule: IntegrationRule,
    /// Kinematics.
    pub kinematics: Kinematics,
}

/// Stresses of each cell in `cells` at each station of its rule (in the rule's order: ξ fastest,
/// then η, then ζ), global axes, components xx, yy, zz, xy, yz, xz: Cauchy for nonlinear
/// kinematics, σ = C ε for linear. `u` holds three displacements per node. Stations of the
/// selective-reduced Hex8 rule carry only the components integrated there.
pub fn station_stresses<M: Copy + Into<Material>>(
    mesh: &Mesh,
    rules: &StressRules<'_, M>,
    u: &[f64],
    cells: &[usize],
) -> Result<Vec<Vec<[f64; 6]>>, AssemblyError> {
    if u.len() != 3 * mesh.nodes.len() {
        return Err(AssemblyError::Length {
            what: "displacements",
            expected: 3 * mesh.nodes.len(),
            got: u.len(),
        });
    }
    let mut tables: Vec<(ElementKind, ShapeTable, Workspace, ElementOutput)> = Vec::new();
    let mut out = Vec::with_capacity(cells.len());
    for &c in cells {
        let cell = mesh.cells.get(c).ok_or(AssemblyError::Length {
            what: "cell index",
            expected: mesh.cells.len(),
            got: c,
        })?;
        let material = cell_material(mesh, rules, c)?;
        let k = match tables.iter().position(|t| t.0 == cell.kind) {
            Some(k) => k,
            None => {
                let rule = match cell.kind {
                    ElementKind::Hex20 => rules.hex20_rule,
                    ElementKind::Hex8 => rules.hex8_rule,
                };
                let table = ShapeTable::new(cell.kind, rule)?;
                let ws = Workspace::new(&table);
                let eo = ElementOutput::new(&table);
                tables.push((cell.kind, table, ws, eo));
                tables.len() - 1
            }
        };
        let (_, table, ws, eo) = &mut tables[k];
        let x = mesh.cell_coordinates(c);
        let d = mesh.cell_displacements(c, u);
        evaluate(table, &x, &d, &material, rules.kinematics, false, ws, eo)
            .map_err(|e| e.at_element(c))?;
        let mut cell_out = Vec::with_capacity(table.stations().len());
        for (g, s) in eo.stresses.iter().enumerate() {
            cell_out.push(match rules.kinematics {
                Kinematics::Linear => *s,
                Kinematics::Nonlinear => cauchy(s, &deformation_gradient(table, g, &x, &d)),
            });
        }
        out.push(cell_out);
    }
    Ok(out)
}

/// The material of cell `c` in global axes: its material rotated about z by its ply angle.
pub(crate) fn cell_material<M: Copy + Into<Material>>(
    mesh: &Mesh,
    rules: &StressRules<'_, M>,
    c: usize,
) -> Result<Material, AssemblyError> {
    let cell = &mesh.cells[c];
    let base: Material = rules
        .materials
        .get(cell.material)
        .map(|&m| m.into())
        .ok_or(AssemblyError::Material {
            cell: c,
            material: cell.material,
            count: rules.materials.len(),
        })?;
    Ok(if cell.ply_angle_deg == 0.0 {
        base
    } else {
        base.rotated_about_z(cell.ply_angle_deg.to_radians(), rules.coupling)?
    })
}

/// F = I + ∂u/∂X at station `g`: ∂N/∂X = J⁻ᵀ ∂N/∂ξ with J_ij = Σ_a x_a,i ∂N_a/∂ξ_j.
pub(crate) fn deformation_gradient(
    table: &ShapeTable,
    g: usize,
    x: &[[f64; 3]],
    d: &[[f64; 3]],
) -> [[f64; 3]; 3] {
    let dn = table.gradients(g);
    let mut j = [[0.0; 3]; 3];
    let mut h = [[0.0; 3]; 3];
    for (a, grad) in dn.iter().enumerate() {
        for r in 0..3 {
            for s in 0..3 {
                j[r][s] += x[a][r] * grad[s];
                h[r][s] += d[a][r] * grad[s];
            }
        }
    }
    // ∂u/∂X = (∂u/∂ξ) J⁻¹.
    let ji = inverse(&j);
    let mut f = [[0.0; 3]; 3];
    for r in 0..3 {
        for s in 0..3 {
            f[r][s] = if r == s { 1.0 } else { 0.0 };
            for k in 0..3 {
                f[r][s] += h[r][k] * ji[k][s];
            }
        }
    }
    f
}

fn det(a: &[[f64; 3]; 3]) -> f64 {
    a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1])
        - a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0])
        + a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0])
}

fn inverse(a: &[[f64; 3]; 3]) -> [[f64; 3]; 3] {
    let d = det(a);
    let c =
        |r0: usize, r1: usize, c0: usize, c1: usize| a[r0][c0] * a[r1][c1] - a[r0][c1] * a[r1][c0];
    [
        [c(1, 2, 1, 2) / d, -c(0, 2, 1, 2) / d, c(0, 1, 1, 2) / d],
        [-c(1, 2, 0, 2) / d, c(0, 2, 0, 2) / d, -c(0, 1, 0, 2) / d],
        [c(1, 2, 0, 1) / d, -c(0, 2, 0, 1) / d, c(0, 1, 0, 1) / d],
    ]
}

/// σ = F S Fᵀ / det F, Voigt order xx, yy, zz, xy, yz, xz.
pub(crate) fn cauchy(s: &[f64; 6], f: &[[f64; 3]; 3]) -> [f64; 6] {
    let t = [[s[0], s[3], s[5]], [s[3], s[1], s[4]], [s[5], s[4], s[2]]];
    let j = det(f);
    let mut sig = [[0.0; 3]; 3];
    for r in 0..3 {
        for q in 0..3 {
            let mut v = 0.0;
            for a in 0..3 {
                for b in 0..3 {
                    v += f[r][a] * t[a][b] * f[q][b];
                }
            }
            sig[r][q] = v / j;
        }
    }
    [
        sig[0][0], sig[1][1], sig[2][2], sig[0][1], sig[1][2], sig[0][2],
    ]
}

#[cfg(test)]
mod tests {
    use super::*;
    use nonlin3d_laminate::materials;
    use nonlin3d_mesh::{BoxParams, structured_box};

    /// A uniaxial stretch u = e·x of an isotropic block with free lateral faces is not an
    /// equilibrium, but every station sees the same F = diag(1 + e, 1, 1), so the Cauchy
    /// stress is S·(1 + e)²/(1 + e) on xx and S/(1 + e) on yy, zz with S = C E, E_xx =
    /// e + e²/2 (Green–Lagrange): exact to round-off.
    #[test]
    fn cauchy_stress_of_a_uniform_stretch() {
        let mesh = structured_box(&BoxParams::new(
            ElementKind::Hex20,
            [2, 1, 1],
            [2.0, 1.0, 1.0],
        ))
        .unwrap();
        let steel = materials::steel().stiffness().unwrap();
        let e = 0.01;
        let u: Vec<f64> = mesh
            .nodes
            .iter()
            .flat_map(|p| [e * p[0], 0.0, 0.0])
            .collect();
        for kinematics in [Kinematics::Nonlinear, Kinematics::Linear] {
            let rules = StressRules {
                materials: &[steel],
                coupling: ShearCoupling::Exact,
                hex20_rule: IntegrationRule::Gauss3,
                hex8_rule: IntegrationRule::Gauss2,
                kinematics,
            };
            let s = station_stresses(&mesh, &rules, &u, &[0, 1]).unwrap();
            assert_eq!(s.len(), 2);
            assert_eq!(s[0].len(), 27);
            let strain = match kinematics {
                Kinematics::Nonlinear => e + e * e / 2.0,
                Kinematics::Linear => e,
            };
            let pk2 = steel.stress(&[strain, 0.0, 0.0, 0.0, 0.0, 0.0]);
            let (fx, j) = match kinematics {
                Kinematics::Nonlinear => (1.0 + e, 1.0 + e),
                Kinematics::Linear => (1.0, 1.0),
            };
            for st in s.iter().flatten() {
                assert!((st[0] - pk2[0] * fx * fx / j).abs() < 1e-9 * pk2[0]);
                assert!((st[1] - pk2[1] / j).abs() < 1e-9 * pk2[0]);
                assert!((st[2] - pk2[2] / j).abs() < 1e-9 * pk2[0]);
                assert!(st[3..].iter().all(|v| v.abs() < 1e-9 * pk2[0]));
            }
        }
    }

    /// A rigid rotation by 90° about z carries no stress, Cauchy or not; the second
    /// Piola–Kirchhoff stress of the kernels is zero too (E = 0), so only the push-forward of a
    /// prestretch tells them apart: stretch along x then rotate, σ lies along y.
    #[test]
    fn cauchy_stress_turns_with_the_body() {
        let mesh = structured_box(&BoxParams::new(
            ElementKind::Hex8,
            [1, 1, 1],
            [1.0, 1.0, 1.0],
        ))
        .unwrap();
        let steel = materials::steel().stiffness().unwrap();
        let e = 0.02;
        // x ↦ R·diag(1 + e, 1, 1)·X with R the quarter turn about z: (X, Y) ↦ (−Y, (1 + e) X).
        let u: Vec<f64> = mesh
            .nodes
            .iter()
            .flat_map(|p| [-p[1] - p[0], (1.0 + e) * p[0] - p[1], 0.0])
            .collect();
        let rules = StressRules {
            materials: &[steel],
            coupling: ShearCoupling::Exact,
            hex20_rule: IntegrationRule::Gauss3,
            hex8_rule: IntegrationRule::Gauss2,
            kinematics: Kinematics::Nonlinear,
        };
        let s = station_stresses(&mesh, &rules, &u, &[0]).unwrap();
        let pk2 = steel.stress(&[e + e * e / 2.0, 0.0, 0.0, 0.0, 0.0, 0.0]);
        for st in &s[0] {
            // Along the rotated fibre (y): S_xx (1 + e)² / (1 + e); across it (x): S_yy / (1 + e).
            assert!((st[1] - pk2[0] * (1.0 + e)).abs() < 1e-9 * pk2[0], "{st:?}");
            assert!((st[0] - pk2[1] / (1.0 + e)).abs() < 1e-9 * pk2[0], "{st:?}");
            assert!(st[3].abs() < 1e-9 * pk2[0]);
        }
    }
}
