//! What a deck must satisfy before anything is solved (docs/RELIABILITY.md, "Decks"), checked
//! as scenes are: at least one `*STEP`; every element's Jacobian determinant positive at each
//! integration point of its rule and not negative at its nodes; materials that give a
//! stiffness; loads that CalculiX would accept; the command's options. A deck that fails here is
//! bad input (`nonlin3d solve` exits 2); the reader has already refused what it cannot read,
//! unknown parameters and empty sets in use.

use super::StepOptions;
use super::loads::History;
use crate::Error;
use nonlin3d_element::{ElementKind, IntegrationRule, Material};
use nonlin3d_laminate::{Orthotropic, Stiffness};
use nonlin3d_mesh::inp::InpElastic;
use nonlin3d_mesh::{InpModel, Mesh, MeshError};
use std::collections::BTreeMap;

/// A checked deck, ready for the assembler: the mesh with one material per distinct (deck
/// material, orientation), and the Hex20 rule.
pub(crate) struct Prepared {
    pub mesh: Mesh,
    pub materials: Vec<Material>,
    pub rule: IntegrationRule,
}

/// A deck that passed [`check`], with what its solve needs from the checks, so that
/// [`solve_checked_with`](super::solve_checked_with) does not repeat them.
pub struct Checked {
    pub(crate) prepared: Prepared,
    /// The deck's node and element counts, to tell a `Checked` of another deck.
    pub(crate) counts: (usize, usize),
}

impl std::fmt::Debug for Checked {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Checked")
            .field("nodes", &self.counts.0)
            .field("elements", &self.counts.1)
            .field("hex20_rule", &self.prepared.rule)
            .finish()
    }
}

/// Checks `model` and `options` as [`solve_deck`](super::solve_deck) would before solving:
/// the checked deck, or the first problem located by line (element id and line for a
/// Jacobian).
pub fn check(model: &InpModel, options: &StepOptions) -> Result<Checked, Error> {
    Ok(Checked {
        prepared: prepare(model, options)?,
        counts: (model.mesh.nodes.len(), model.mesh.cells.len()),
    })
}

/// The checks of [`check`], and what the solver needs from them.
pub(crate) fn prepare(model: &InpModel, options: &StepOptions) -> Result<Prepared, Error> {
    if model.steps.is_empty() {
        return Err(deck_error(
            "end of deck",
            "*STEP",
            "the deck has no step: nothing would be solved (nonlin3d solves the *STEP … *END \
             STEP blocks, each with *STATIC)",
        ));
    }
    if let Some(f) = options.initial_increment
        && !(f > 0.0 && f <= 1.0)
    {
        return Err(Error::InitialIncrement { value: f });
    }
    let rule = hex20_rule(model)?;
    jacobians(model, rule)?;
    let (mesh, materials) = oriented(model)?;
    // The step definitions CalculiX refuses (a DOF loaded twice in a step with different
    // amplitudes) are found before the first step is solved, not when its turn comes.
    let mut history = History::new(model);
    let zero = vec![0.0; 3 * model.mesh.nodes.len()];
    for step in &model.steps {
        history.begin_step(model, step, &zero)?;
    }
    Ok(Prepared {
        mesh,
        materials,
        rule,
    })
}

fn deck_error(at: &str, what: &str, reason: impl Into<String>) -> Error {
    Error::Mesh(MeshError::Deck {
        at: at.into(),
        what: what.into(),
        reason: reason.into(),
    })
}

/// The stiffness of a deck material.
fn stiffness(e: &InpElastic) -> Result<Stiffness, Error> {
    Ok(match e {
        InpElastic::Isotropic { e, nu } => Orthotropic::isotropic(*e, *nu).stiffness()?,
        InpElastic::Engineering(o) => o.stiffness()?,
        InpElastic::Orthotropic(s) | InpElastic::Anisotropic(s) => **s,
    })
}

/// The mesh with one material per distinct (deck material, orientation), each rotated to its
/// axes (rectangular: once; cylindrical: at each integration point, by the element kernel), and
/// no ply angles; and those materials.
fn oriented(model: &InpModel) -> Result<(Mesh, Vec<Material>), Error> {
    let base: Vec<Stiffness> = model
        .materials
        .iter()
        .map(|m| {
            stiffness(&m.elastic)
                .map_err(|e| deck_error(&format!("material {}", m.name), "*ELASTIC", e.to_string()))
        })
        .collect::<Result<_, _>>()?;
    let mut mesh = model.mesh.clone();
    // Key: material, cylindrical (or not), the nine numbers of the axes (a and b's direction).
    let mut index: BTreeMap<(usize, bool, [u64; 9]), usize> = BTreeMap::new();
    let mut materials = Vec::new();
    for (c, cell) in mesh.cells.iter_mut().enumerate() {
        let cylindrical = model.cylindrical.get(c).copied().flatten();
        let r = model.orientations.get(c).copied().unwrap_or([
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
        ]);
        let numbers: Vec<f64> = match cylindrical {
            Some(a) => a
                .origin()
                .into_iter()
                .chain(a.direction())
                .chain([0.0; 3])
                .collect(),
            None => r.iter().flatten().copied().collect(),
        };
        let bits: Vec<u64> = numbers.iter().map(|v| v.to_bits()).collect();
        let key = (
            cell.material,
            cylindrical.is_some(),
            bits.try_into().unwrap_or([0; 9]),
        );
        let id = match index.get(&key) {
            Some(&id) => id,
            None => {
                let local = base[cell.material];
                materials.push(match cylindrical {
                    Some(axes) => Material::Cylindrical { local, axes },
                    None => Material::Uniform(local.rotated(&r)?),
                });
                index.insert(key, materials.len() - 1);
                materials.len() - 1
            }
        };
        cell.material = id;
        cell.ply_angle_deg = 0.0;
    }
    Ok((mesh, materials))
}

/// The integration rule of Hex20 cells: 2×2×2 for C3D20R, 3×3×3 for C3D20.
fn hex20_rule(model: &InpModel) -> Result<IntegrationRule, Error> {
    let hex20: Vec<(usize, bool)> = model
        .mesh
        .cells
        .iter()
        .zip(&model.reduced)
        .enumerate()
        .filter(|(_, (c, _))| c.kind == ElementKind::Hex20)
        .map(|(i, (_, &r))| (i, r))
        .collect();
    if let (Some(&(a, _)), Some(&(b, _))) = (
        hex20.iter().find(|(_, r)| *r),
        hex20.iter().find(|(_, r)| !*r),
    ) {
        return Err(deck_error(
            &at(model, a.max(b)),
            "*ELEMENT data",
            format!(
                "the deck mixes C3D20R (element {}) and C3D20 (element {}); nonlin3d uses one \
                 rule per element kind",
                model.element_ids[a], model.element_ids[b]
            ),
        ));
    }
    Ok(if hex20.first().is_some_and(|&(_, r)| r) {
        IntegrationRule::Gauss2
    } else {
        IntegrationRule::Gauss3
    })
}

/// Where element `c` was defined.
fn at(model: &InpModel, c: usize) -> String {
    model
        .element_at
        .get(c)
        .cloned()
        .unwrap_or_else(|| "deck".into())
}

/// The deck's name of element `c`'s type.
fn type_name(model: &InpModel, c: usize) -> &'static str {
    match (model.mesh.cells[c].kind, model.reduced.get(c).copied()) {
        (ElementKind::Hex8, _) => "C3D8",
        (ElementKind::Hex20, Some(true)) => "C3D20R",
        (ElementKind::Hex20, _) => "C3D20",
    }
}

/// det J (J_rc = Σ_m ∂N^m/∂ξ_r x^m_c, thesis eq. 2.4.1.1) > 0 at every integration point of
/// each element's rule (C3D20 3×3×3, C3D20R and C3D8 2×2×2), where the stiffness is
/// integrated, and det J ≥ −1e-6 × its mean over those points at
/// every node: an element whose corners are out of order can be positive at all its points and
/// still fold over itself near a corner (two neighbouring corners of a C3D20 swapped do), and
/// its answer is then wrong without a word. The tolerance at the nodes lets a collapsed
/// (degenerate) element, det J = 0 at its collapsed corner, through.
fn jacobians(model: &InpModel, hex20_rule: IntegrationRule) -> Result<(), Error> {
    let points =
        |rule: IntegrationRule| -> Vec<[f64; 3]> { rule.stations().iter().map(|s| s.xi).collect() };
    let (p2, p3) = (
        points(IntegrationRule::Gauss2),
        points(IntegrationRule::Gauss3),
    );
    for (c, cell) in model.mesh.cells.iter().enumerate() {
        let x = model.mesh.cell_coordinates(c);
        let (rule, n) = match (cell.kind, hex20_rule) {
            (ElementKind::Hex20, IntegrationRule::Gauss3) => (&p3, 3),
            _ => (&p2, 2),
        };
        let fail = |reason: String| {
            deck_error(
                &at(model, c),
                "*ELEMENT data",
                format!(
                    "element {} ({}): {reason}: the element is inverted or its nodes are not in \
                     {} order",
                    model.element_ids[c],
                    type_name(model, c),
                    type_name(model, c)
                ),
            )
        };
        let mut sum = 0.0;
        for (g, &xi) in rule.iter().enumerate() {
            let det = cell.kind.jacobian_determinant(xi, &x)?;
            if det.is_nan() || det <= 0.0 {
                return Err(fail(format!(
                    "Jacobian determinant {det:.3e} ≤ 0 at integration point {} of {} \
                     ({n}×{n}×{n} rule; ξ, η, ζ = {:.3}, {:.3}, {:.3})",
                    g + 1,
                    rule.len(),
                    xi[0],
                    xi[1],
                    xi[2]
                )));
            }
            sum += det;
        }
        let mean = sum / rule.len() as f64;
        for (k, &xi) in cell.kind.reference_nodes().iter().enumerate() {
            let det = cell.kind.jacobian_determinant(xi, &x)?;
            if det.is_nan() || det < -1e-6 * mean {
                return Err(fail(format!(
                    "Jacobian determinant {det:.3e} < 0 at its node {} (deck node {}), while \
                     {mean:.3e} on average at its integration points",
                    k + 1,
                    model.node_ids[cell.nodes[k]]
                )));
            }
        }
    }
    Ok(())
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;
    use nonlin3d_element::HEX20_NODES;

    /// A deck of C3D20 unit cubes on the nodes 1–20 (the reference order): each of
    /// `elements` (type, node order), then `step` in the one step.
    fn deck(elements: &[(&str, [usize; 20])], step: &str) -> InpModel {
        let mut deck = String::from("*NODE\n");
        for (i, p) in HEX20_NODES.iter().enumerate() {
            deck.push_str(&format!("{}, {}, {}, {}\n", i + 1, p[0], p[1], p[2]));
        }
        for (k, (ty, order)) in elements.iter().enumerate() {
            let ids: Vec<String> = order.iter().map(ToString::to_string).collect();
            deck.push_str(&format!(
                "*ELEMENT, TYPE={ty}, ELSET=E\n{}, {},\n{}\n",
                k + 7,
                ids[..15].join(", "),
                ids[15..].join(", ")
            ));
        }
        deck.push_str(&format!(
            "*NSET, NSET=BASE\n1, 2, 3, 4\n*MATERIAL, NAME=M\n*ELASTIC\n1e5, 0.3\n\
             *SOLID SECTION, ELSET=E, MATERIAL=M\n*AMPLITUDE, NAME=A\n0, 0, 1, 1\n\
             *STEP\n*STATIC\n*BOUNDARY\nBASE, 1, 3\n{step}*END STEP\n"
        ));
        nonlin3d_mesh::read_inp(&deck).unwrap()
    }

    /// One C3D20 unit cube, element 7, its nodes listed in `order`.
    fn cube(order: &[usize; 20]) -> InpModel {
        deck(&[("C3D20", *order)], "")
    }

    fn order() -> [usize; 20] {
        std::array::from_fn(|i| i + 1)
    }

    #[test]
    fn a_valid_element_passes() {
        assert!(check(&cube(&order()), &StepOptions::default()).is_ok());
    }

    /// Corners 2 and 4 swapped: det J < 0 at integration points; the error names the deck's
    /// element id and the line of its data (line 23: `*NODE`, 20 nodes, `*ELEMENT`, then
    /// the data).
    #[test]
    fn an_inverted_element_is_named_by_id_and_line() {
        let mut o = order();
        o.swap(1, 3);
        let e = check(&cube(&o), &StepOptions::default())
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("line 23, *ELEMENT data: element 7 (C3D20): Jacobian determinant")
                && e.contains("integration point"),
            "{e}"
        );
    }

    /// Corners 1 and 2 swapped: positive at all 27 integration points (so the kernels would
    /// integrate it without complaint) but folded at its corners; refused at a node.
    #[test]
    fn an_element_folded_between_its_points_is_refused_at_a_node() {
        let mut o = order();
        o.swap(0, 1);
        let m = cube(&o);
        let x = m.mesh.cell_coordinates(0);
        for s in IntegrationRule::Gauss3.stations() {
            assert!(ElementKind::Hex20.jacobian_determinant(s.xi, &x).unwrap() > 0.0);
        }
        let e = check(&m, &StepOptions::default()).unwrap_err().to_string();
        assert!(
            e.starts_with("line 23, *ELEMENT data: element 7 (C3D20)") && e.contains("at its node"),
            "{e}"
        );
    }

    /// The other input errors are found before solving too, with their line.
    #[test]
    fn mixed_rules_conflicting_loads_bad_materials_and_increments_are_refused() {
        let options = StepOptions::default();
        let e = check(
            &deck(&[("C3D20", order()), ("C3D20R", order())], ""),
            &options,
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.starts_with("line 26, *ELEMENT data: the deck mixes C3D20R (element 8) and C3D20"),
            "{e}"
        );
        let loads = "*CLOAD\n5, 3, 1.\n*CLOAD, AMPLITUDE=A\n5, 3, 1.\n";
        let e = check(&deck(&[("C3D20", order())], loads), &options)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("*CLOAD") && e.contains("different amplitudes"),
            "{e}"
        );
        let mut m = cube(&order());
        m.materials[0].elastic = InpElastic::Isotropic { e: 1e5, nu: 0.5 };
        let e = check(&m, &options).unwrap_err().to_string();
        assert!(e.starts_with("material M, *ELASTIC: "), "{e}");
        for f in [0.0, 1.5] {
            let options = StepOptions {
                initial_increment: Some(f),
                ..StepOptions::default()
            };
            let e = check(&cube(&order()), &options).unwrap_err().to_string();
            assert!(e.contains("initial increment"), "{e}");
        }
    }

    #[test]
    fn a_deck_without_a_step_is_refused() {
        let mut m = cube(&order());
        m.steps.clear();
        let e = check(&m, &StepOptions::default()).unwrap_err().to_string();
        assert!(e.contains("*STEP") && e.contains("no step"), "{e}");
    }
}
