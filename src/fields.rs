//! The fields of the VTU/PVD files of `nonlin3d run` and `nonlin3d solve` (docs/SCENES.md,
//! "Fields in ParaView"): a state's displacement, Green–Lagrange strain, second
//! Piola–Kirchhoff and Cauchy stresses at the nodes (per material region) and per cell,
//! reactions and crack-face opening ([`state_vtu`]); a level's front with its energy release
//! rates ([`front_vtu`]). A run writes them in mm, MPa, N ([`Units::MM_MPA_N`]), a deck solve in
//! the deck's units ([`Units::DECK`]).

use crate::Error;
use crate::atomic::write_atomic;
use crate::model::Model;
use crate::results::{Faces, FrontRow, LevelResult};
use nonlin3d_assembly::{StressRules, nodal_fields};
use nonlin3d_element::{Kinematics, Material};
use nonlin3d_laminate::ShearCoupling;
use nonlin3d_mesh::Mesh;
use nonlin3d_mesh::names::{CRACK_LOWER, CRACK_UPPER};
use nonlin3d_mesh::vtu::{Field, lines_vtu_string, pvd_string, vtu_string};
use std::path::Path;

/// Units of the fields of a VTU: a suffix for the field names and the factor from the model's
/// units (SI for a scene's model) for lengths, stresses and forces.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Units {
    /// Lengths (coordinates, displacements, openings): suffix and factor.
    pub length: (&'static str, f64),
    /// Stresses: suffix and factor.
    pub stress: (&'static str, f64),
    /// Forces: suffix and factor.
    pub force: (&'static str, f64),
}

impl Units {
    /// A scene's run: the model in m, Pa, N written in mm, MPa, N (the scenes' units; G in
    /// J/m² in the front files).
    pub const MM_MPA_N: Self = Self {
        length: ("_mm", 1e3),
        stress: ("_MPa", 1e-6),
        force: ("_N", 1.0),
    };
    /// A deck's solve: the deck's own units, unconverted and unnamed (a deck, like CalculiX,
    /// has none).
    pub const DECK: Self = Self {
        length: ("", 1.0),
        stress: ("", 1.0),
        force: ("", 1.0),
    };
}

fn flat6(v: &[[f64; 6]], f: f64) -> Vec<f64> {
    v.iter().flatten().map(|x| x * f).collect()
}

/// The VTU text of state `u` (three displacements per node, model units): the mesh split along
/// material regions (`nonlin3d_assembly::nodal_fields`) with point fields `node` (`node_ids`
/// of the model's nodes, or the 0-based index), `displacement`, `strain_green_lagrange`
/// (tensor components xx, yy, zz, xy, yz, xz), `stress_pk2`, `stress_cauchy`, `reaction`
/// (internal nodal force), `crack_opening` (u(upper) − u(lower) on both faces of each pair of
/// the `crack_upper`/`crack_lower` sets, global x, y, z; only when the mesh has them), each
/// with the units' suffix; cell fields `material`, `ply_angle_deg` and the cell means of the
/// strain and stresses under the same names.
pub fn state_vtu<M: Copy + Into<Material>>(
    mesh: &Mesh,
    rules: &StressRules<'_, M>,
    u: &[f64],
    node_ids: Option<&[usize]>,
    units: Units,
) -> Result<String, Error> {
    let nf = nodal_fields(mesh, rules, u)?;
    let (ls, lf) = units.length;
    let (ss, sf) = units.stress;
    let (fs, ff) = units.force;
    let mut out_mesh = nf.mesh;
    for p in &mut out_mesh.nodes {
        *p = p.map(|x| x * lf);
    }
    let nodes = &nf.point_node;
    let gather3 = |v: &dyn Fn(usize) -> [f64; 3], f: f64| -> Vec<f64> {
        nodes.iter().flat_map(|&n| v(n).map(|x| x * f)).collect()
    };
    let label: Vec<f64> = nodes
        .iter()
        .map(|&n| node_ids.and_then(|ids| ids.get(n)).copied().unwrap_or(n) as f64)
        .collect();
    let disp = gather3(&|n| [u[3 * n], u[3 * n + 1], u[3 * n + 2]], lf);
    let reaction = gather3(&|n| nf.forces[n], ff);
    let names = [
        format!("displacement{ls}"),
        "strain_green_lagrange".to_string(),
        format!("stress_pk2{ss}"),
        format!("stress_cauchy{ss}"),
        format!("reaction{fs}"),
        format!("crack_opening{ls}"),
    ];
    let (strain, pk2, cauchy) = (
        flat6(&nf.strain, 1.0),
        flat6(&nf.pk2, sf),
        flat6(&nf.cauchy, sf),
    );
    let mut points = vec![
        Field {
            name: "node",
            components: 1,
            values: &label,
        },
        Field {
            name: &names[0],
            components: 3,
            values: &disp,
        },
        Field {
            name: &names[1],
            components: 6,
            values: &strain,
        },
        Field {
            name: &names[2],
            components: 6,
            values: &pk2,
        },
        Field {
            name: &names[3],
            components: 6,
            values: &cauchy,
        },
        Field {
            name: &names[4],
            components: 3,
            values: &reaction,
        },
    ];
    let opening;
    if let (Some(up), Some(low)) = (
        mesh.node_sets.get(CRACK_UPPER),
        mesh.node_sets.get(CRACK_LOWER),
    ) {
        let mut jump = vec![[0.0; 3]; mesh.nodes.len()];
        for (&a, &b) in up.iter().zip(low) {
            let d = [0, 1, 2].map(|r| u[3 * a + r] - u[3 * b + r]);
            jump[a] = d;
            jump[b] = d;
        }
        opening = gather3(&|n| jump[n], lf);
        points.push(Field {
            name: &names[5],
            components: 3,
            values: &opening,
        });
    }
    let (cs, cp, cc) = (
        flat6(&nf.cell_strain, 1.0),
        flat6(&nf.cell_pk2, sf),
        flat6(&nf.cell_cauchy, sf),
    );
    let cells = [
        Field {
            name: &names[1],
            components: 6,
            values: &cs,
        },
        Field {
            name: &names[2],
            components: 6,
            values: &cp,
        },
        Field {
            name: &names[3],
            components: 6,
            values: &cc,
        },
    ];
    Ok(vtu_string(&out_mesh, &points, &cells)?)
}

/// The front of one level as line segments through its points in the rows' (S) order, with
/// point fields `s_mm`, `G_I_J_m2`, `G_II_J_m2`, `G_III_J_m2`, `G_T_J_m2` (J/m², the values of
/// results.json), `mode_mix` = (G_II + G_III)/G_T (0 where G_T = 0) and `open` (1 where the
/// faces are open, 0 where they overlap); points at the front nodes, mm.
pub fn front_vtu(mesh: &Mesh, front: &[FrontRow]) -> Result<String, Error> {
    let points: Vec<[f64; 3]> = front
        .iter()
        .map(|r| {
            mesh.nodes
                .get(r.node)
                .copied()
                .unwrap_or([r.x_mm * 1e-3, r.y_mm * 1e-3, 0.0])
        })
        .map(|p| p.map(|x| x * 1e3))
        .collect();
    let segments: Vec<[usize; 2]> = (1..front.len()).map(|i| [i - 1, i]).collect();
    let col = |f: &dyn Fn(&FrontRow) -> f64| -> Vec<f64> { front.iter().map(f).collect() };
    let cols = [
        ("s_mm", col(&|r| r.s_mm)),
        ("G_I_J_m2", col(&|r| r.g_i)),
        ("G_II_J_m2", col(&|r| r.g_ii)),
        ("G_III_J_m2", col(&|r| r.g_iii)),
        ("G_T_J_m2", col(&|r| r.g_t)),
        (
            "mode_mix",
            col(&|r| {
                if r.g_t == 0.0 {
                    0.0
                } else {
                    (r.g_ii + r.g_iii) / r.g_t
                }
            }),
        ),
        (
            "open",
            col(&|r| if r.faces == Faces::Open { 1.0 } else { 0.0 }),
        ),
    ];
    let fields: Vec<Field<'_>> = cols
        .iter()
        .map(|(name, v)| Field {
            name,
            components: 1,
            values: v,
        })
        .collect();
    Ok(lines_vtu_string(&points, &segments, &fields)?)
}

/// Writes level `k`'s `model_K.vtu` ([`state_vtu`], mm, MPa, N) and `front_K.vtu`
/// ([`front_vtu`]) into `dir`.
pub fn write_level_vtu(
    dir: &Path,
    model: &Model,
    level: &LevelResult,
    k: usize,
) -> Result<(), Error> {
    write_model_vtu(dir, model, level, k)?;
    write_front_vtu(dir, model, level, k)
}

/// Writes level `k`'s `model_K.vtu` ([`state_vtu`] of its displacements, mm, MPa, N) into
/// `dir` (the stresses recovered at the nodes; 4.6 MB of text at 18 k DOF).
pub fn write_model_vtu(
    dir: &Path,
    model: &Model,
    level: &LevelResult,
    k: usize,
) -> Result<(), Error> {
    let rules = StressRules {
        materials: &model.materials,
        coupling: ShearCoupling::Exact,
        hex20_rule: model.rule,
        hex8_rule: model.rule,
        kinematics: Kinematics::Nonlinear,
    };
    let text = state_vtu(
        &model.mesh,
        &rules,
        &level.displacements,
        None,
        Units::MM_MPA_N,
    )?;
    write_atomic(&dir.join(format!("model_{k}.vtu")), text.as_bytes())
}

/// Writes level `k`'s `front_K.vtu` ([`front_vtu`]: the front with its energy release rates)
/// into `dir`; nothing for a level without a front.
pub fn write_front_vtu(
    dir: &Path,
    model: &Model,
    level: &LevelResult,
    k: usize,
) -> Result<(), Error> {
    if level.front.is_empty() {
        return Ok(());
    }
    let text = front_vtu(&model.mesh, &level.front)?;
    write_atomic(&dir.join(format!("front_{k}.vtu")), text.as_bytes())
}

/// Writes `model.pvd` and `front.pvd` in `dir`: one step per level, at |value| (`front.pvd`
/// lists the levels with a front; none without any).
pub fn write_pvds(dir: &Path, levels: &[LevelResult]) -> Result<(), Error> {
    for (stem, pvd) in [("model", "model.pvd"), ("front", "front.pvd")] {
        let steps: Vec<(f64, String)> = levels
            .iter()
            .enumerate()
            .filter(|(_, l)| stem == "model" || !l.front.is_empty())
            .map(|(k, l)| (l.value.abs(), format!("{stem}_{k}.vtu")))
            .collect();
        if !steps.is_empty() {
            write_atomic(&dir.join(pvd), pvd_string(&steps)?.as_bytes())?;
        }
    }
    Ok(())
}
