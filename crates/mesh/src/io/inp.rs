//! Abaqus/CalculiX input decks (`.inp`): writer.
//!
//! Written: `*HEADING`, `*NODE`, `*ELEMENT` (C3D8 / C3D20), `*NSET` and `*ELSET` for the mesh's
//! sets, `*SURFACE, TYPE=ELEMENT` for its face sets, `*MATERIAL` with `*ELASTIC` (ISO,
//! ENGINEERING CONSTANTS, ORTHO or ANISO), one `*ORIENTATION` (rectangular, rotated about z) per
//! distinct ply angle, `*SOLID SECTION` per (material, ply angle) group, and `*STEP`s (optionally
//! `NLGEOM`) with `*STATIC`, `*BOUNDARY`, `*CLOAD` and output requests; crack-face contact
//! (`*SURFACE INTERACTION`, `*SURFACE BEHAVIOR`, `*CONTACT PAIR`) by [`contact_cards`], which
//! the caller places before the first step. Node and element ids are
//! the mesh's indices + 1. CalculiX 2.20 runs the decks unchanged (tested when `ccx` is present;
//! CI installs it).

use crate::{Mesh, MeshError};
use nonlin3d_element::ElementKind;

#[path = "inp_contact.rs"]
mod contact;
pub use contact::{
    INTERACTION, LOWER_FACES, Penalty, UPPER_FACES, add_crack_surfaces, contact_cards, face_nodes,
    face_surface,
};
use nonlin3d_laminate::{Orthotropic, Stiffness};
use std::collections::BTreeMap;
use std::fmt::Write as _;

/// Elastic behaviour of a deck material.
#[derive(Debug, Clone, PartialEq)]
pub enum InpElastic {
    /// `*ELASTIC, TYPE=ISO`: E, ν.
    Isotropic {
        /// Young's modulus, Pa.
        e: f64,
        /// Poisson ratio.
        nu: f64,
    },
    /// `*ELASTIC, TYPE=ENGINEERING CONSTANTS` in the material (ply) axes.
    Engineering(Orthotropic),
    /// `*ELASTIC, TYPE=ORTHO`: the nine constants D1111, D1122, D2222, D1133, D2233, D3333,
    /// D1212, D1313, D2323 of a stiffness with no normal–shear or shear–shear coupling (an error
    /// otherwise: use ANISO).
    Orthotropic(Box<Stiffness>),
    /// `*ELASTIC, TYPE=ANISO`: a full 6×6 stiffness (engineering shears, nonlin3d's order is
    /// converted to Abaqus's 11, 22, 33, 12, 13, 23).
    Anisotropic(Box<Stiffness>),
}

/// A named deck material; cells refer to it by their `material` index.
#[derive(Debug, Clone, PartialEq)]
pub struct InpMaterial {
    /// Name (letters, digits, `_`, `-`).
    pub name: String,
    /// Elastic behaviour.
    pub elastic: InpElastic,
}

/// `*BOUNDARY`: DOFs `first..=last` (1 = x, 2 = y, 3 = z) of node set `nset` set to `value`.
#[derive(Debug, Clone, PartialEq)]
pub struct InpBoundary {
    /// Node set name (one of the mesh's).
    pub nset: String,
    /// First DOF, 1–3.
    pub first: u8,
    /// Last DOF, 1–3.
    pub last: u8,
    /// Prescribed displacement, m.
    pub value: f64,
}

/// `*CLOAD`: force `value` (N) on DOF `dof` (1–3) of node `node` (0-based mesh index).
#[derive(Debug, Clone, PartialEq)]
pub struct InpCload {
    /// Node (0-based).
    pub node: usize,
    /// DOF, 1–3.
    pub dof: u8,
    /// Force, N.
    pub value: f64,
}

/// A static step.
#[derive(Debug, Clone, PartialEq)]
pub struct InpStep {
    /// `NLGEOM` (geometric nonlinearity) on.
    pub nlgeom: bool,
    /// Initial increment and step period (`*STATIC` data line).
    pub increment: f64,
    /// Step period.
    pub period: f64,
    /// Boundary conditions of the step.
    pub boundaries: Vec<InpBoundary>,
    /// Concentrated loads of the step.
    pub cloads: Vec<InpCload>,
}

/// A deck: mesh, materials, steps.
#[derive(Debug, Clone)]
pub struct InpDeck<'a> {
    /// First `*HEADING` line.
    pub heading: String,
    /// The mesh.
    pub mesh: &'a Mesh,
    /// Materials indexed by the cells' `material`.
    pub materials: &'a [InpMaterial],
    /// Steps in order.
    pub steps: Vec<InpStep>,
}

fn bad(reason: String) -> MeshError {
    MeshError::Parameter {
        name: "inp deck",
        reason,
    }
}

fn check_name(name: &str) -> Result<(), MeshError> {
    let ok = !name.is_empty()
        && name.len() <= 80
        && name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-');
    if ok {
        Ok(())
    } else {
        Err(bad(format!(
            "name '{name}' must be 1–80 letters, digits, '_' or '-'"
        )))
    }
}

/// Writes `ids` (1-based) 16 per line.
fn id_lines(s: &mut String, ids: impl Iterator<Item = usize>) {
    let ids: Vec<usize> = ids.collect();
    for chunk in ids.chunks(16) {
        let line: Vec<String> = chunk.iter().map(|i| i.to_string()).collect();
        let _ = writeln!(s, "{}", line.join(", "));
    }
}

/// A number as CalculiX reads it: its fields are at most 20 characters (Fortran `f20.0`). The
/// shortest representation that reads back to the same f64 when it fits (so decks round-trip
/// exactly), else 13 significant digits, e.g. `-6.896551724138e-1` (`-1.234567890123e-10` is
/// 19 characters).
fn num(v: f64) -> String {
    let exact = format!("{v:?}");
    if exact.len() <= 20 {
        exact
    } else {
        format!("{v:.12e}")
    }
}

/// Abaqus's order of the 9 ORTHO constants as (row, col) of nonlin3d's Voigt matrix:
/// D1111 D1122 D2222 D1133 D2233 D3333 D1212 D1313 D2323.
pub(crate) const ORTHO_ORDER: [(usize, usize); 9] = [
    (0, 0),
    (0, 1),
    (1, 1),
    (0, 2),
    (1, 2),
    (2, 2),
    (3, 3),
    (5, 5),
    (4, 4),
];

/// Abaqus's order of the 21 ANISO constants as (row, col) of nonlin3d's Voigt matrix
/// (0 xx, 1 yy, 2 zz, 3 xy, 4 yz, 5 xz).
pub(crate) const ANISO_ORDER: [(usize, usize); 21] = [
    (0, 0),
    (0, 1),
    (1, 1),
    (0, 2),
    (1, 2),
    (2, 2),
    (0, 3),
    (1, 3),
    (2, 3),
    (3, 3),
    (0, 5),
    (1, 5),
    (2, 5),
    (3, 5),
    (5, 5),
    (0, 4),
    (1, 4),
    (2, 4),
    (3, 4),
    (5, 4),
    (4, 4),
];

/// The deck as text: heading, mesh (nodes, elements, sets, surfaces), materials, sections with
/// their orientations, steps; each written by one function below, in that order.
pub fn inp_string(deck: &InpDeck<'_>) -> Result<String, MeshError> {
    check_deck(deck)?;
    let m = deck.mesh;
    let mut s = String::new();
    let _ = writeln!(s, "*HEADING\n{}", deck.heading.replace('\n', " "));
    write_nodes(&mut s, m);
    write_elements(&mut s, m);
    write_sets(&mut s, m);
    for mat in deck.materials {
        write_material(&mut s, mat)?;
    }
    write_sections(&mut s, deck);
    for (k, step) in deck.steps.iter().enumerate() {
        write_step(&mut s, m, k, step)?;
    }
    Ok(s)
}

/// What the deck needs before a line is written: a valid mesh, material and set names the
/// readers accept, and a material for every cell's index.
fn check_deck(deck: &InpDeck<'_>) -> Result<(), MeshError> {
    let m = deck.mesh;
    m.validate()?;
    for mat in deck.materials {
        check_name(&mat.name)?;
    }
    for name in m
        .node_sets
        .keys()
        .chain(m.cell_sets.keys())
        .chain(m.face_sets.keys())
    {
        check_name(name)?;
    }
    if let Some(c) = m
        .cells
        .iter()
        .position(|c| c.material >= deck.materials.len())
    {
        return Err(bad(format!(
            "cell {c} uses material {} of {}",
            m.cells[c].material,
            deck.materials.len()
        )));
    }
    Ok(())
}

/// `*NODE, NSET=NALL`: id (index + 1) and x, y, z.
fn write_nodes(s: &mut String, m: &Mesh) {
    s.push_str("*NODE, NSET=NALL\n");
    for (i, x) in m.nodes.iter().enumerate() {
        let _ = writeln!(s, "{}, {}, {}, {}", i + 1, num(x[0]), num(x[1]), num(x[2]));
    }
}

/// `*ELEMENT` blocks, C3D8 then C3D20, in the elsets EC3D8 / EC3D20: id (index + 1), nodes.
fn write_elements(s: &mut String, m: &Mesh) {
    for (kind, name) in [(ElementKind::Hex8, "C3D8"), (ElementKind::Hex20, "C3D20")] {
        let cells: Vec<usize> = (0..m.cells.len())
            .filter(|&c| m.cells[c].kind == kind)
            .collect();
        if cells.is_empty() {
            continue;
        }
        let _ = writeln!(s, "*ELEMENT, TYPE={name}, ELSET=E{name}");
        for c in cells {
            let ids: Vec<String> = std::iter::once(c + 1)
                .chain(m.cells[c].nodes.iter().map(|n| n + 1))
                .map(|v| v.to_string())
                .collect();
            // At most 16 entries per line; a trailing comma continues the element.
            let lines: Vec<String> = ids.chunks(16).map(|ch| ch.join(", ")).collect();
            let _ = writeln!(s, "{}", lines.join(",\n"));
        }
    }
}

/// The mesh's sets: `*NSET`, `*ELSET`, and `*SURFACE, TYPE=ELEMENT` (faces as `S1`…`S6`).
fn write_sets(s: &mut String, m: &Mesh) {
    for (name, set) in &m.node_sets {
        let _ = writeln!(s, "*NSET, NSET={name}");
        id_lines(s, set.iter().map(|n| n + 1));
    }
    for (name, set) in &m.cell_sets {
        let _ = writeln!(s, "*ELSET, ELSET={name}");
        id_lines(s, set.iter().map(|c| c + 1));
    }
    for (name, set) in &m.face_sets {
        let _ = writeln!(s, "*SURFACE, NAME={name}, TYPE=ELEMENT");
        for &(c, f) in set {
            let _ = writeln!(s, "{}, S{}", c + 1, f + 1);
        }
    }
}

/// `*MATERIAL` and its `*ELASTIC` card (ISO, ENGINEERING CONSTANTS, ORTHO or ANISO); an
/// invalid orthotropic material, or shear coupling under ORTHO, is an error naming it.
fn write_material(s: &mut String, mat: &InpMaterial) -> Result<(), MeshError> {
    let _ = writeln!(s, "*MATERIAL, NAME={}", mat.name);
    match &mat.elastic {
        InpElastic::Isotropic { e, nu } => {
            let _ = writeln!(s, "*ELASTIC, TYPE=ISO\n{}, {}", num(*e), num(*nu));
        }
        InpElastic::Engineering(o) => {
            o.validate()
                .map_err(|e| bad(format!("material {}: {e}", mat.name)))?;
            let _ = writeln!(
                s,
                "*ELASTIC, TYPE=ENGINEERING CONSTANTS\n{}, {}, {}, {}, {}, {}, {}, {}\n{}",
                num(o.e11),
                num(o.e22),
                num(o.e33),
                num(o.nu12),
                num(o.nu13),
                num(o.nu23),
                num(o.g12),
                num(o.g13),
                num(o.g23)
            );
        }
        InpElastic::Orthotropic(c) => write_ortho(s, &mat.name, c)?,
        InpElastic::Anisotropic(c) => {
            let v: Vec<String> = ANISO_ORDER.iter().map(|&(i, j)| num(c.c()[i][j])).collect();
            let _ = writeln!(s, "*ELASTIC, TYPE=ANISO");
            for chunk in v.chunks(8) {
                let _ = writeln!(s, "{}", chunk.join(", "));
            }
        }
    }
    Ok(())
}

/// `*ELASTIC, TYPE=ORTHO`: the nine constants in [`ORTHO_ORDER`]; refused when a shear couples
/// to anything (an off-diagonal entry in a shear row or column above 1e-12 of the largest
/// diagonal entry), which ORTHO cannot hold.
fn write_ortho(s: &mut String, name: &str, c: &Stiffness) -> Result<(), MeshError> {
    let k = c.c();
    let scale = (0..6).map(|i| k[i][i]).fold(0.0, f64::max);
    let coupled = (0..6)
        .flat_map(|i| (0..6).map(move |j| (i, j)))
        .any(|(i, j)| (i >= 3 || j >= 3) && i != j && k[i][j].abs() > 1e-12 * scale);
    if coupled {
        return Err(bad(format!(
            "material {name}: ORTHO needs no shear coupling; use ANISO"
        )));
    }
    let v: Vec<String> = ORTHO_ORDER.iter().map(|&(i, j)| num(k[i][j])).collect();
    let _ = writeln!(s, "*ELASTIC, TYPE=ORTHO\n{}\n{}", v[..8].join(", "), v[8]);
    Ok(())
}

/// One `*ORIENTATION` (rectangular, rotated about z by the ply angle) per distinct ply angle,
/// and one `*SOLID SECTION` per (material, ply angle) group of cells, on an elset SECTIONg.
fn write_sections(s: &mut String, deck: &InpDeck<'_>) {
    let mut groups: BTreeMap<(usize, u64), Vec<usize>> = BTreeMap::new();
    for (c, cell) in deck.mesh.cells.iter().enumerate() {
        groups
            .entry((cell.material, cell.ply_angle_deg.to_bits()))
            .or_default()
            .push(c);
    }
    let mut orientations: BTreeMap<u64, usize> = BTreeMap::new();
    for (_, bits) in groups.keys() {
        let next = orientations.len();
        orientations.entry(*bits).or_insert(next);
    }
    for (&bits, &k) in &orientations {
        let t = f64::from_bits(bits).to_radians();
        let (sn, cs) = t.sin_cos();
        let _ = writeln!(
            s,
            "*ORIENTATION, NAME=OR{k}, SYSTEM=RECTANGULAR\n{}, {}, 0., {}, {}, 0.",
            num(cs),
            num(sn),
            num(-sn),
            num(cs)
        );
    }
    for (g, ((mat, bits), cells)) in groups.iter().enumerate() {
        let _ = writeln!(s, "*ELSET, ELSET=SECTION{g}");
        id_lines(s, cells.iter().map(|c| c + 1));
        let _ = writeln!(
            s,
            "*SOLID SECTION, ELSET=SECTION{g}, MATERIAL={}, ORIENTATION=OR{}",
            deck.materials[*mat].name, orientations[bits]
        );
    }
}

/// Step k: `*STEP` (NLGEOM when asked), `*STATIC`, `*BOUNDARY`, `*CLOAD` and the output
/// requests (U at the nodes, S in the elements); an unknown node set, a DOF outside 1–3 or a
/// non-finite value is an error naming the step.
fn write_step(s: &mut String, m: &Mesh, k: usize, step: &InpStep) -> Result<(), MeshError> {
    if !(step.increment > 0.0 && step.period >= step.increment) {
        return Err(bad(format!(
            "step {k}: increment {} and period {} must satisfy 0 < increment ≤ period",
            step.increment, step.period
        )));
    }
    // *STATIC: initial increment, period, minimum (1e-5 of the period), maximum (the period).
    let _ = writeln!(
        s,
        "*STEP{}\n*STATIC\n{}, {}, {}, {}",
        if step.nlgeom { ", NLGEOM" } else { "" },
        num(step.increment),
        num(step.period),
        num(1e-5 * step.period),
        num(step.period)
    );
    if !step.boundaries.is_empty() {
        s.push_str("*BOUNDARY\n");
    }
    for b in &step.boundaries {
        if !m.node_sets.contains_key(&b.nset) {
            return Err(bad(format!(
                "step {k}: boundary on unknown node set '{}'",
                b.nset
            )));
        }
        if !(1..=3).contains(&b.first) || !(b.first..=3).contains(&b.last) || !b.value.is_finite() {
            return Err(bad(format!("step {k}: boundary {b:?} invalid")));
        }
        let _ = writeln!(s, "{}, {}, {}, {}", b.nset, b.first, b.last, num(b.value));
    }
    if !step.cloads.is_empty() {
        s.push_str("*CLOAD\n");
    }
    for l in &step.cloads {
        if l.node >= m.nodes.len() || !(1..=3).contains(&l.dof) || !l.value.is_finite() {
            return Err(bad(format!("step {k}: load {l:?} invalid")));
        }
        let _ = writeln!(s, "{}, {}, {}", l.node + 1, l.dof, num(l.value));
    }
    s.push_str("*NODE PRINT, NSET=NALL\nU\n*NODE FILE\nU\n*EL FILE\nS\n*END STEP\n");
    Ok(())
}
