//! Abaqus/CalculiX input decks: reader for a documented subset.
//!
//! Keywords read: `*HEADING`, `*NODE`, `*ELEMENT` (TYPE=C3D8, C3D20, C3D20R), `*NSET` and
//! `*ELSET` (lists or GENERATE), `*MATERIAL`, `*ELASTIC` (TYPE=ISO, ORTHO, ENGINEERING CONSTANTS,
//! ANISO), `*ORIENTATION` (SYSTEM=RECTANGULAR, rotations about z only), `*SOLID SECTION`,
//! `*BOUNDARY`, `*CLOAD`, `*STEP` (NLGEOM, INC), `*STATIC`, `*AMPLITUDE` (tabular pairs),
//! `*END STEP`. Accepted and ignored: output requests (`*NODE PRINT`, `*NODE FILE`, `*EL PRINT`,
//! `*EL FILE`, `*OUTPUT`, `*NODE OUTPUT`, `*ELEMENT OUTPUT`), `*SURFACE` data. Anything else is
//! an error naming the keyword and its line; so is any malformed line. Deck ids are kept.

use crate::MeshError;
use crate::inp::{InpElastic, InpMaterial};
use crate::model::{Cell, Mesh};
use nonlin3d_element::ElementKind;
use nonlin3d_laminate::{Orthotropic, Stiffness};
use std::collections::{BTreeMap, HashMap};

/// Where a boundary condition or load applies.
#[derive(Debug, Clone, PartialEq)]
pub enum NodeRef {
    /// A node set by name.
    Set(String),
    /// One node (0-based mesh index).
    Node(usize),
}

/// A `*BOUNDARY` line.
#[derive(Debug, Clone, PartialEq)]
pub struct ReadBoundary {
    /// Target nodes.
    pub target: NodeRef,
    /// First DOF (1–3; 4–6 rejected: no rotational DOFs on solids).
    pub first: u8,
    /// Last DOF.
    pub last: u8,
    /// Value (0 when omitted).
    pub value: f64,
}

/// A `*CLOAD` line.
#[derive(Debug, Clone, PartialEq)]
pub struct ReadCload {
    /// Target nodes.
    pub target: NodeRef,
    /// DOF 1–3.
    pub dof: u8,
    /// Force, N.
    pub value: f64,
}

/// A `*STEP` … `*END STEP` block.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ReadStep {
    /// NLGEOM on.
    pub nlgeom: bool,
    /// INC= (maximum increments), if given.
    pub max_increments: Option<usize>,
    /// `*STATIC` data line (initial increment, period, min, max), as given.
    pub static_line: Vec<f64>,
    /// `AMPLITUDE=` of the step's loads, if any.
    pub amplitude: Option<String>,
    /// Boundary conditions.
    pub boundaries: Vec<ReadBoundary>,
    /// Concentrated loads.
    pub cloads: Vec<ReadCload>,
}

/// What a deck holds.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct InpModel {
    /// The mesh; each cell's `material` and `ply_angle_deg` come from its `*SOLID SECTION`.
    pub mesh: Mesh,
    /// Deck id of each node.
    pub node_ids: Vec<usize>,
    /// Deck id of each element.
    pub element_ids: Vec<usize>,
    /// Whether each element was declared with reduced integration (C3D20R).
    pub reduced: Vec<bool>,
    /// Materials in deck order.
    pub materials: Vec<InpMaterial>,
    /// Boundary conditions given before the first step.
    pub initial_boundaries: Vec<ReadBoundary>,
    /// Steps.
    pub steps: Vec<ReadStep>,
    /// Tabular amplitudes: name → (time, value) pairs.
    pub amplitudes: BTreeMap<String, Vec<(f64, f64)>>,
}

/// A `*SOLID SECTION`, resolved after the whole deck is read.
struct Section {
    line: usize,
    elset: String,
    material: String,
    orientation: Option<String>,
}

/// One keyword line: name (upper case, single spaces) and parameters (upper-case keys).
struct Keyword {
    name: String,
    params: HashMap<String, String>,
    line: usize,
}

fn err(keyword: &str, line: usize, reason: impl Into<String>) -> MeshError {
    MeshError::Parameter {
        name: "inp",
        reason: format!("line {line} ({keyword}): {}", reason.into()),
    }
}

fn parse_keyword(text: &str, line: usize) -> Keyword {
    let mut parts = text[1..].split(',');
    let name = parts
        .next()
        .unwrap_or("")
        .split_whitespace()
        .collect::<Vec<_>>()
        .join(" ")
        .to_uppercase();
    let mut params = HashMap::new();
    for p in parts {
        let mut kv = p.splitn(2, '=');
        let key = kv.next().unwrap_or("").trim().to_uppercase();
        let value = kv.next().unwrap_or("").trim().to_string();
        if !key.is_empty() {
            params.insert(key, value);
        }
    }
    Keyword { name, params, line }
}

fn fields(line: &str) -> Vec<&str> {
    line.split(',')
        .map(str::trim)
        .filter(|f| !f.is_empty())
        .collect()
}

fn float(kw: &Keyword, line: usize, f: &str) -> Result<f64, MeshError> {
    let v: f64 = f
        .replace(['d', 'D'], "e")
        .parse()
        .map_err(|_| err(&kw.name, line, format!("'{f}' is not a number")))?;
    if v.is_finite() {
        Ok(v)
    } else {
        Err(err(&kw.name, line, format!("'{f}' is not finite")))
    }
}

fn int(kw: &Keyword, line: usize, f: &str) -> Result<usize, MeshError> {
    f.parse().map_err(|_| {
        err(
            &kw.name,
            line,
            format!("'{f}' is not a non-negative integer"),
        )
    })
}

/// Reads a deck from text.
pub fn read_inp(text: &str) -> Result<InpModel, MeshError> {
    // Logical lines: comments dropped, element continuation lines joined.
    let mut lines: Vec<(usize, String)> = Vec::new();
    for (i, raw) in text.lines().enumerate() {
        let l = raw.trim();
        if l.is_empty() || l.starts_with("**") {
            continue;
        }
        match lines.last_mut() {
            Some((_, prev))
                if !l.starts_with('*') && prev.ends_with(',') && !prev.starts_with('*') =>
            {
                prev.push(' ');
                prev.push_str(l);
            }
            _ => lines.push((i + 1, l.to_string())),
        }
    }
    let mut m = InpModel::default();
    let mut node_index: HashMap<usize, usize> = HashMap::new();
    let mut elem_index: HashMap<usize, usize> = HashMap::new();
    let mut orientations: HashMap<String, f64> = HashMap::new();
    let mut sections: Vec<Section> = Vec::new();
    let mut step: Option<ReadStep> = None;
    let mut i = 0;
    while i < lines.len() {
        let (ln, text) = &lines[i];
        if !text.starts_with('*') {
            return Err(err("data", *ln, "data line outside any keyword"));
        }
        let kw = parse_keyword(text, *ln);
        let start = i + 1;
        let mut end = start;
        while end < lines.len() && !lines[end].1.starts_with('*') {
            end += 1;
        }
        let data = &lines[start..end];
        match kw.name.as_str() {
            "HEADING" => {}
            "NODE" => {
                for (l, d) in data {
                    let f = fields(d);
                    if f.len() < 4 {
                        return Err(err(&kw.name, *l, "expected: id, x, y, z"));
                    }
                    let id = int(&kw, *l, f[0])?;
                    if node_index.insert(id, m.mesh.nodes.len()).is_some() {
                        return Err(err(&kw.name, *l, format!("node {id} defined twice")));
                    }
                    m.mesh.nodes.push([
                        float(&kw, *l, f[1])?,
                        float(&kw, *l, f[2])?,
                        float(&kw, *l, f[3])?,
                    ]);
                    m.node_ids.push(id);
                }
                if let Some(set) = kw.params.get("NSET") {
                    let ids: Vec<usize> = data
                        .iter()
                        .filter_map(|(_, d)| {
                            fields(d).first().and_then(|f| f.parse::<usize>().ok())
                        })
                        .filter_map(|id| node_index.get(&id).copied())
                        .collect();
                    m.mesh.node_sets.entry(set.clone()).or_default().extend(ids);
                }
            }
            "ELEMENT" => {
                let ty = kw
                    .params
                    .get("TYPE")
                    .map(|t| t.to_uppercase())
                    .unwrap_or_default();
                let (kind, reduced) = match ty.as_str() {
                    "C3D8" => (ElementKind::Hex8, false),
                    "C3D20" => (ElementKind::Hex20, false),
                    "C3D20R" => (ElementKind::Hex20, true),
                    other => {
                        return Err(err(
                            &kw.name,
                            kw.line,
                            format!("element type '{other}' not supported (C3D8, C3D20, C3D20R)"),
                        ));
                    }
                };
                let mut added = Vec::new();
                for (l, d) in data {
                    let f = fields(d);
                    if f.len() != kind.nodes() + 1 {
                        return Err(err(
                            &kw.name,
                            *l,
                            format!(
                                "{ty} needs an id and {} nodes, got {} fields",
                                kind.nodes(),
                                f.len()
                            ),
                        ));
                    }
                    let id = int(&kw, *l, f[0])?;
                    let mut nodes = Vec::with_capacity(kind.nodes());
                    for g in &f[1..] {
                        let n = int(&kw, *l, g)?;
                        nodes.push(*node_index.get(&n).ok_or_else(|| {
                            err(&kw.name, *l, format!("node {n} is not defined"))
                        })?);
                    }
                    if elem_index.insert(id, m.mesh.cells.len()).is_some() {
                        return Err(err(&kw.name, *l, format!("element {id} defined twice")));
                    }
                    added.push(m.mesh.cells.len());
                    m.mesh.cells.push(Cell {
                        kind,
                        nodes,
                        material: usize::MAX,
                        ply_angle_deg: 0.0,
                    });
                    m.element_ids.push(id);
                    m.reduced.push(reduced);
                }
                if let Some(set) = kw.params.get("ELSET") {
                    m.mesh
                        .cell_sets
                        .entry(set.clone())
                        .or_default()
                        .extend(added);
                }
            }
            "NSET" | "ELSET" => {
                let key = if kw.name == "NSET" { "NSET" } else { "ELSET" };
                let name = kw
                    .params
                    .get(key)
                    .cloned()
                    .ok_or_else(|| err(&kw.name, kw.line, format!("{key}= missing")))?;
                let mut ids = Vec::new();
                for (l, d) in data {
                    let f = fields(d);
                    if kw.params.contains_key("GENERATE") {
                        if f.len() < 2 || f.len() > 3 {
                            return Err(err(&kw.name, *l, "GENERATE needs first, last[, step]"));
                        }
                        let (a, b) = (int(&kw, *l, f[0])?, int(&kw, *l, f[1])?);
                        let s = if f.len() == 3 { int(&kw, *l, f[2])? } else { 1 };
                        if s == 0 || b < a || (b - a) / s > 10_000_000 {
                            return Err(err(&kw.name, *l, "GENERATE range invalid"));
                        }
                        ids.extend((a..=b).step_by(s));
                    } else {
                        for g in f {
                            ids.push(int(&kw, *l, g)?);
                        }
                    }
                }
                let (index, target) = if key == "NSET" {
                    (&node_index, &mut m.mesh.node_sets)
                } else {
                    (&elem_index, &mut m.mesh.cell_sets)
                };
                let mut mapped = Vec::with_capacity(ids.len());
                for id in ids {
                    mapped.push(*index.get(&id).ok_or_else(|| {
                        err(
                            &kw.name,
                            kw.line,
                            format!(
                                "{} {id} in set {name} is not defined",
                                if key == "NSET" { "node" } else { "element" }
                            ),
                        )
                    })?);
                }
                target.entry(name).or_default().extend(mapped);
            }
            "MATERIAL" => {
                let name = kw
                    .params
                    .get("NAME")
                    .cloned()
                    .ok_or_else(|| err(&kw.name, kw.line, "NAME= missing"))?;
                m.materials.push(InpMaterial {
                    name,
                    elastic: InpElastic::Isotropic {
                        e: f64::NAN,
                        nu: f64::NAN,
                    },
                });
            }
            "ELASTIC" => {
                let mat = m
                    .materials
                    .last_mut()
                    .ok_or_else(|| err(&kw.name, kw.line, "*ELASTIC outside a *MATERIAL"))?;
                let mut v = Vec::new();
                for (l, d) in data {
                    for f in fields(d) {
                        v.push(float(&kw, *l, f)?);
                    }
                }
                let ty = kw
                    .params
                    .get("TYPE")
                    .map(|t| t.to_uppercase())
                    .unwrap_or_else(|| "ISO".into());
                let need = |n: usize| {
                    if v.len() < n {
                        Err(err(
                            &kw.name,
                            kw.line,
                            format!("TYPE={ty} needs {n} constants, got {}", v.len()),
                        ))
                    } else {
                        Ok(())
                    }
                };
                mat.elastic = match ty.as_str() {
                    "ISO" | "ISOTROPIC" => {
                        need(2)?;
                        InpElastic::Isotropic { e: v[0], nu: v[1] }
                    }
                    "ENGINEERING CONSTANTS" => {
                        need(9)?;
                        let o = Orthotropic {
                            e11: v[0],
                            e22: v[1],
                            e33: v[2],
                            nu12: v[3],
                            nu13: v[4],
                            nu23: v[5],
                            g12: v[6],
                            g13: v[7],
                            g23: v[8],
                        };
                        o.validate()
                            .map_err(|e| err(&kw.name, kw.line, e.to_string()))?;
                        InpElastic::Engineering(o)
                    }
                    "ORTHO" | "ORTHOTROPIC" | "ANISO" | "ANISOTROPIC" => {
                        let ortho = ty.starts_with("ORTHO");
                        need(if ortho { 9 } else { 21 })?;
                        let mut c = [[0.0; 6]; 6];
                        let order: &[(usize, usize)] = if ortho {
                            &crate::inp::ORTHO_ORDER
                        } else {
                            &crate::inp::ANISO_ORDER
                        };
                        for (&(r, col), &val) in order.iter().zip(&v) {
                            c[r][col] = val;
                            c[col][r] = val;
                        }
                        let s =
                            Stiffness::new(c).map_err(|e| err(&kw.name, kw.line, e.to_string()))?;
                        InpElastic::Anisotropic(Box::new(s))
                    }
                    other => {
                        return Err(err(
                            &kw.name,
                            kw.line,
                            format!("elastic TYPE={other} not supported"),
                        ));
                    }
                };
            }
            "ORIENTATION" => {
                let name = kw
                    .params
                    .get("NAME")
                    .cloned()
                    .ok_or_else(|| err(&kw.name, kw.line, "NAME= missing"))?;
                if kw
                    .params
                    .get("SYSTEM")
                    .is_some_and(|s| !s.eq_ignore_ascii_case("RECTANGULAR"))
                {
                    return Err(err(
                        &kw.name,
                        kw.line,
                        "only SYSTEM=RECTANGULAR is supported",
                    ));
                }
                let (l, d) = data
                    .first()
                    .ok_or_else(|| err(&kw.name, kw.line, "data line missing"))?;
                let f = fields(d);
                if f.len() < 6 {
                    return Err(err(&kw.name, *l, "expected a1, a2, a3, b1, b2, b3"));
                }
                let v: Vec<f64> = f[..6]
                    .iter()
                    .map(|x| float(&kw, *l, x))
                    .collect::<Result<_, _>>()?;
                // Rotation about z only: a in the xy plane, b in the xy plane.
                if v[2].abs() > 1e-12 * v[0].hypot(v[1])
                    || v[5].abs() > 1e-12 * v[3].hypot(v[4])
                    || v[0].hypot(v[1]) == 0.0
                {
                    return Err(err(
                        &kw.name,
                        *l,
                        "only orientations rotated about z are supported",
                    ));
                }
                orientations.insert(name, v[1].atan2(v[0]).to_degrees());
            }
            "SOLID SECTION" => {
                let elset = kw
                    .params
                    .get("ELSET")
                    .cloned()
                    .ok_or_else(|| err(&kw.name, kw.line, "ELSET= missing"))?;
                let mat = kw
                    .params
                    .get("MATERIAL")
                    .cloned()
                    .ok_or_else(|| err(&kw.name, kw.line, "MATERIAL= missing"))?;
                sections.push(Section {
                    line: kw.line,
                    elset,
                    material: mat,
                    orientation: kw.params.get("ORIENTATION").cloned(),
                });
            }
            "STEP" => {
                if step.is_some() {
                    return Err(err(
                        &kw.name,
                        kw.line,
                        "*STEP inside a step (missing *END STEP)",
                    ));
                }
                let nlgeom = kw
                    .params
                    .get("NLGEOM")
                    .is_some_and(|v| v.is_empty() || v.eq_ignore_ascii_case("YES"));
                let max_increments = kw
                    .params
                    .get("INC")
                    .map(|v| int(&kw, kw.line, v))
                    .transpose()?;
                step = Some(ReadStep {
                    nlgeom,
                    max_increments,
                    ..Default::default()
                });
            }
            "STATIC" => {
                let s = step
                    .as_mut()
                    .ok_or_else(|| err(&kw.name, kw.line, "*STATIC outside a step"))?;
                if let Some((l, d)) = data.first() {
                    s.static_line = fields(d)
                        .iter()
                        .map(|f| float(&kw, *l, f))
                        .collect::<Result<_, _>>()?;
                }
            }
            "BOUNDARY" | "CLOAD" => {
                if let (Some(s), Some(a)) = (step.as_mut(), kw.params.get("AMPLITUDE")) {
                    s.amplitude = Some(a.clone());
                }
                for (l, d) in data {
                    let f = fields(d);
                    if f.len() < 2 {
                        return Err(err(&kw.name, *l, "expected a node or node set and a DOF"));
                    }
                    let target = match f[0].parse::<usize>() {
                        Ok(id) => NodeRef::Node(*node_index.get(&id).ok_or_else(|| {
                            err(&kw.name, *l, format!("node {id} is not defined"))
                        })?),
                        Err(_) => {
                            if !m.mesh.node_sets.contains_key(f[0]) {
                                return Err(err(
                                    &kw.name,
                                    *l,
                                    format!("node set '{}' is not defined", f[0]),
                                ));
                            }
                            NodeRef::Set(f[0].to_string())
                        }
                    };
                    let dof = |x: &str| -> Result<u8, MeshError> {
                        let d = int(&kw, *l, x)?;
                        if (1..=3).contains(&d) {
                            Ok(d as u8)
                        } else {
                            Err(err(
                                &kw.name,
                                *l,
                                format!("DOF {d} not supported (solids have 1–3)"),
                            ))
                        }
                    };
                    if kw.name == "BOUNDARY" {
                        let first = dof(f[1])?;
                        let last = if f.len() > 2 { dof(f[2])? } else { first };
                        let value = if f.len() > 3 {
                            float(&kw, *l, f[3])?
                        } else {
                            0.0
                        };
                        if last < first {
                            return Err(err(&kw.name, *l, "last DOF before first"));
                        }
                        let b = ReadBoundary {
                            target,
                            first,
                            last,
                            value,
                        };
                        match step.as_mut() {
                            Some(s) => s.boundaries.push(b),
                            None => m.initial_boundaries.push(b),
                        }
                    } else {
                        if f.len() < 3 {
                            return Err(err(&kw.name, *l, "expected node, DOF, value"));
                        }
                        let c = ReadCload {
                            target,
                            dof: dof(f[1])?,
                            value: float(&kw, *l, f[2])?,
                        };
                        step.as_mut()
                            .ok_or_else(|| err(&kw.name, *l, "*CLOAD outside a step"))?
                            .cloads
                            .push(c);
                    }
                }
            }
            "AMPLITUDE" => {
                let name = kw
                    .params
                    .get("NAME")
                    .cloned()
                    .ok_or_else(|| err(&kw.name, kw.line, "NAME= missing"))?;
                let mut v = Vec::new();
                for (l, d) in data {
                    for f in fields(d) {
                        v.push(float(&kw, *l, f)?);
                    }
                }
                if v.len() % 2 == 1 {
                    return Err(err(
                        &kw.name,
                        kw.line,
                        "odd number of values: expected (time, value) pairs",
                    ));
                }
                m.amplitudes
                    .insert(name, v.chunks(2).map(|p| (p[0], p[1])).collect());
            }
            "END STEP" => {
                let s = step
                    .take()
                    .ok_or_else(|| err(&kw.name, kw.line, "*END STEP without *STEP"))?;
                m.steps.push(s);
            }
            "NODE PRINT" | "NODE FILE" | "EL PRINT" | "EL FILE" | "OUTPUT" | "NODE OUTPUT"
            | "ELEMENT OUTPUT" | "SURFACE" => {}
            other => return Err(err(other, kw.line, "keyword not supported")),
        }
        i = end;
    }
    if step.is_some() {
        return Err(err(
            "STEP",
            lines.last().map_or(0, |l| l.0),
            "deck ends inside a step (missing *END STEP)",
        ));
    }
    // Sections: material index and ply angle per cell.
    for sec in sections {
        let line = sec.line;
        let mat = &sec.material;
        let mi = m
            .materials
            .iter()
            .position(|x| x.name.eq_ignore_ascii_case(mat))
            .ok_or_else(|| {
                err(
                    "SOLID SECTION",
                    line,
                    format!("material '{mat}' not defined"),
                )
            })?;
        let angle = match &sec.orientation {
            None => 0.0,
            Some(or) => *orientations.get(or).ok_or_else(|| {
                err(
                    "SOLID SECTION",
                    line,
                    format!("orientation '{or}' not defined"),
                )
            })?,
        };
        let cells = m.mesh.cell_sets.get(&sec.elset).cloned().ok_or_else(|| {
            err(
                "SOLID SECTION",
                line,
                format!("element set '{}' not defined", sec.elset),
            )
        })?;
        for c in cells {
            m.mesh.cells[c].material = mi;
            m.mesh.cells[c].ply_angle_deg = angle;
        }
    }
    if let Some(c) = m.mesh.cells.iter().position(|c| c.material == usize::MAX) {
        return Err(err(
            "SOLID SECTION",
            0,
            format!("element {} has no section", m.element_ids[c]),
        ));
    }
    for set in m
        .mesh
        .node_sets
        .values_mut()
        .chain(m.mesh.cell_sets.values_mut())
    {
        set.sort_unstable();
        set.dedup();
    }
    m.mesh.validate()?;
    Ok(m)
}
