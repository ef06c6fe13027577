//! Model-data keywords: nodes, elements, sets, materials, orientations, sections, amplitudes,
//! and the data a static mechanical step does not use (accepted and listed).

use super::lexer::{Keyword, Line, Loc, fields, float, float_param, int};
use super::sections::{Axes, Section, cylindrical_axes, rectangular_axes};
use super::{Amplitude, Reader};
use crate::MeshError;
use crate::inp::{InpElastic, InpMaterial};
use crate::model::Cell;
use nonlin3d_element::ElementKind;
use nonlin3d_laminate::{Orthotropic, Stiffness};

/// Keywords accepted and listed with the reason they do not matter to a static mechanical
/// step; any parameter is accepted with them (none changes the answer).
const NOT_USED: &[(&str, &str)] = &[
    ("HEADING", "title only"),
    (
        "DENSITY",
        "mass: a static step has no inertia or gravity load",
    ),
    (
        "EXPANSION",
        "thermal expansion: no temperature field is applied (*TEMPERATURE is refused)",
    ),
    ("CONDUCTIVITY", "heat transfer only"),
    ("SPECIFIC HEAT", "heat transfer only"),
    ("PHYSICAL CONSTANTS", "not used by a mechanical step"),
    ("PREPRINT", "echo of the input in CalculiX's .dat file"),
];

impl Reader {
    /// Handles `kw` if it is model data; Ok(false) if it is not one of these keywords.
    pub(crate) fn model_keyword(&mut self, kw: &Keyword, data: &[Line]) -> Result<bool, MeshError> {
        if let Some((_, reason)) = NOT_USED.iter().find(|(k, _)| *k == kw.name) {
            let reason = match (kw.name.as_str(), data.first()) {
                ("HEADING", Some(l)) => format!("{reason}: {}", l.text),
                _ => reason.to_string(),
            };
            self.not_used(&kw.at, kw.what(), &reason);
            return Ok(true);
        }
        let mesh_data = matches!(
            kw.name.as_str(),
            "NODE" | "ELEMENT" | "MATERIAL" | "ELASTIC" | "ORIENTATION" | "SOLID SECTION"
        );
        if mesh_data && (self.step.is_some() || !self.m.steps.is_empty()) {
            return Err(kw.error("model data after the first *STEP"));
        }
        match kw.name.as_str() {
            "NODE" => self.node(kw, data)?,
            "ELEMENT" => self.element(kw, data)?,
            "NSET" | "ELSET" => self.set(kw, data)?,
            "MATERIAL" => {
                kw.allow(&["NAME"])?;
                let name = kw.require("NAME")?.to_string();
                if self.material_index(&name).is_some() {
                    return Err(kw.error(format!("material {name} defined twice")));
                }
                self.m.materials.push(InpMaterial {
                    name,
                    elastic: InpElastic::Isotropic {
                        e: f64::NAN,
                        nu: f64::NAN,
                    },
                });
                self.elastic_given.push(false);
                no_data(kw, data)?;
            }
            "ELASTIC" => self.elastic(kw, data)?,
            "ORIENTATION" => {
                kw.allow(&["NAME", "SYSTEM"])?;
                let name = kw.require("NAME")?.to_uppercase();
                let axes = match kw.choice("SYSTEM", &["RECTANGULAR", "R", "CYLINDRICAL", "C"])? {
                    Some(s) if s.starts_with('C') => Axes::Cylindrical(cylindrical_axes(kw, data)?),
                    _ => Axes::Fixed(rectangular_axes(kw, data)?),
                };
                self.orientations.insert(name, axes);
            }
            "SOLID SECTION" => {
                kw.allow(&["ELSET", "MATERIAL", "ORIENTATION"])?;
                self.sections.push(Section {
                    at: kw.at.clone(),
                    elset: kw.require("ELSET")?.to_string(),
                    material: kw.require("MATERIAL")?.to_string(),
                    orientation: kw.get("ORIENTATION").map(str::to_uppercase),
                });
                if let Some(l) = data.first() {
                    self.not_used(
                        &l.at,
                        "*SOLID SECTION data".into(),
                        "thickness of 1-D/2-D sections: solid elements do not use it",
                    );
                }
                if data.len() > 1 {
                    return Err(kw.data_error(&data[1].at, "one data line expected"));
                }
            }
            "AMPLITUDE" => self.amplitude(kw, data)?,
            "INITIAL CONDITIONS" => {
                kw.allow(&["TYPE"])?;
                match kw.choice("TYPE", &["TEMPERATURE"])? {
                    Some(_) => self.not_used(
                        &kw.at,
                        "*INITIAL CONDITIONS, TYPE=TEMPERATURE".into(),
                        "no temperature change is applied, so no thermal strain",
                    ),
                    None => return Err(kw.error("TYPE= missing")),
                }
            }
            _ => return Ok(false),
        }
        Ok(true)
    }

    pub(crate) fn material_index(&self, name: &str) -> Option<usize> {
        self.m
            .materials
            .iter()
            .position(|x| x.name.eq_ignore_ascii_case(name))
    }

    fn node(&mut self, kw: &Keyword, data: &[Line]) -> Result<(), MeshError> {
        kw.allow(&["NSET"])?;
        let mut added = Vec::with_capacity(data.len());
        for l in data {
            let f = fields(&l.text);
            if f.len() < 2 || f.len() > 4 {
                return Err(kw.data_error(&l.at, "expected: id, x[, y[, z]]"));
            }
            let id = int(kw, &l.at, f[0])?;
            let mut x = [0.0; 3];
            for (r, s) in f[1..].iter().enumerate() {
                if !s.is_empty() {
                    x[r] = float(kw, &l.at, s)?;
                }
            }
            if self
                .node_index
                .insert(id, self.m.mesh.nodes.len())
                .is_some()
            {
                return Err(kw.data_error(&l.at, format!("node {id} defined twice")));
            }
            added.push(self.m.mesh.nodes.len());
            self.m.mesh.nodes.push(x);
            self.m.node_ids.push(id);
        }
        if let Some(name) = kw.get("NSET") {
            self.add_to_set(true, name, added, &kw.at);
        }
        Ok(())
    }

    fn element(&mut self, kw: &Keyword, data: &[Line]) -> Result<(), MeshError> {
        kw.allow(&["TYPE", "ELSET"])?;
        let ty = kw.require("TYPE")?.to_uppercase();
        let (kind, reduced) = match ty.as_str() {
            "C3D8" => (ElementKind::Hex8, false),
            "C3D20" => (ElementKind::Hex20, false),
            "C3D20R" => (ElementKind::Hex20, true),
            other => {
                return Err(kw.param_error(
                    "TYPE",
                    format!("element type '{other}' not supported (C3D8, C3D20, C3D20R)"),
                ));
            }
        };
        let mut added = Vec::new();
        for l in data {
            let f: Vec<&str> = fields(&l.text);
            if f.len() != kind.nodes() + 1 {
                return Err(kw.data_error(
                    &l.at,
                    format!(
                        "{ty} needs an id and {} nodes, got {} fields",
                        kind.nodes(),
                        f.len()
                    ),
                ));
            }
            let id = int(kw, &l.at, f[0])?;
            let mut nodes = Vec::with_capacity(kind.nodes());
            for g in &f[1..] {
                let n = int(kw, &l.at, g)?;
                nodes.push(
                    *self
                        .node_index
                        .get(&n)
                        .ok_or_else(|| kw.data_error(&l.at, format!("node {n} is not defined")))?,
                );
            }
            if self
                .elem_index
                .insert(id, self.m.mesh.cells.len())
                .is_some()
            {
                return Err(kw.data_error(&l.at, format!("element {id} defined twice")));
            }
            added.push(self.m.mesh.cells.len());
            self.m.mesh.cells.push(Cell {
                kind,
                nodes,
                material: usize::MAX,
                ply_angle_deg: 0.0,
            });
            self.m.element_ids.push(id);
            self.element_at.push(l.at.clone());
            self.m.reduced.push(reduced);
        }
        if let Some(name) = kw.get("ELSET") {
            self.add_to_set(false, name, added, &kw.at);
        }
        Ok(())
    }

    /// Adds mesh indices to a node (`nodes`) or element set, creating it with this spelling
    /// (and remembering `at`, where it was first defined).
    fn add_to_set(&mut self, nodes: bool, name: &str, items: Vec<usize>, at: &Loc) {
        self.set_at
            .entry((nodes, name.to_uppercase()))
            .or_insert_with(|| at.clone());
        let (names, sets) = if nodes {
            (&mut self.node_set_names, &mut self.m.mesh.node_sets)
        } else {
            (&mut self.cell_set_names, &mut self.m.mesh.cell_sets)
        };
        let key = names
            .entry(name.to_uppercase())
            .or_insert_with(|| name.to_string())
            .clone();
        sets.entry(key).or_default().extend(items);
    }

    /// `*NSET` / `*ELSET`: ids, GENERATE ranges, or names of sets of the same kind.
    fn set(&mut self, kw: &Keyword, data: &[Line]) -> Result<(), MeshError> {
        let nodes = kw.name == "NSET";
        let key = if nodes { "NSET" } else { "ELSET" };
        kw.allow(&[key, "GENERATE"])?;
        let name = kw.require(key)?.to_string();
        let generate = kw.flag("GENERATE")?;
        let what = if nodes { "node" } else { "element" };
        let mut items = Vec::new();
        for l in data {
            let f: Vec<&str> = fields(&l.text)
                .into_iter()
                .filter(|s| !s.is_empty())
                .collect();
            if generate {
                if f.len() < 2 || f.len() > 3 {
                    return Err(kw.data_error(&l.at, "GENERATE needs first, last[, step]"));
                }
                let (a, b) = (int(kw, &l.at, f[0])?, int(kw, &l.at, f[1])?);
                let s = if f.len() == 3 {
                    int(kw, &l.at, f[2])?
                } else {
                    1
                };
                if s == 0 || b < a || (b - a) / s > 10_000_000 {
                    return Err(kw.data_error(&l.at, "GENERATE range invalid"));
                }
                for id in (a..=b).step_by(s) {
                    items.push(self.lookup(nodes, id).ok_or_else(|| {
                        kw.data_error(&l.at, format!("{what} {id} in set {name} is not defined"))
                    })?);
                }
                continue;
            }
            for g in f {
                if let Ok(id) = g.parse::<usize>() {
                    items.push(self.lookup(nodes, id).ok_or_else(|| {
                        kw.data_error(&l.at, format!("{what} {id} in set {name} is not defined"))
                    })?);
                    continue;
                }
                // A set listed by name: its members (CalculiX allows sets of the same kind).
                let found = if nodes {
                    self.node_set(g).and_then(|s| self.m.mesh.node_sets.get(s))
                } else {
                    self.cell_set(g).and_then(|s| self.m.mesh.cell_sets.get(s))
                };
                let members = found.cloned().ok_or_else(|| {
                    kw.data_error(
                        &l.at,
                        format!("'{g}' is neither a {what} id nor a defined {what} set"),
                    )
                })?;
                items.extend(members);
            }
        }
        self.add_to_set(nodes, &name, items, &kw.at);
        Ok(())
    }

    fn lookup(&self, nodes: bool, id: usize) -> Option<usize> {
        if nodes {
            self.node_index.get(&id).copied()
        } else {
            self.elem_index.get(&id).copied()
        }
    }

    fn elastic(&mut self, kw: &Keyword, data: &[Line]) -> Result<(), MeshError> {
        kw.allow(&["TYPE"])?;
        let ty = kw
            .choice(
                "TYPE",
                &[
                    "ISO",
                    "ISOTROPIC",
                    "ENGINEERING CONSTANTS",
                    "ORTHO",
                    "ORTHOTROPIC",
                    "ANISO",
                    "ANISOTROPIC",
                ],
            )?
            .unwrap_or_else(|| "ISO".into());
        let Some(mi) = self.m.materials.len().checked_sub(1) else {
            return Err(kw.error("*ELASTIC outside a *MATERIAL"));
        };
        if self.elastic_given[mi] {
            return Err(kw.error("a second *ELASTIC in one material"));
        }
        let n = match ty.as_str() {
            "ISO" | "ISOTROPIC" => 2,
            "ANISO" | "ANISOTROPIC" => 21,
            _ => 9,
        };
        // n constants and an optional temperature; CalculiX reads a table of several
        // temperatures, which nonlin3d does not interpolate.
        let mut v = Vec::new();
        let mut last = None;
        for l in data {
            for f in fields(&l.text) {
                v.push(if f.is_empty() {
                    0.0
                } else {
                    float(kw, &l.at, f)?
                });
            }
            last = Some(&l.at);
        }
        let at = last.unwrap_or(&kw.at);
        if v.len() < n {
            return Err(kw.data_error(
                at,
                format!("TYPE={ty} needs {n} constants, got {}", v.len()),
            ));
        }
        if v.len() > n + 1 || data.len() > n.div_ceil(8) {
            return Err(kw.data_error(
                at,
                format!(
                    "TYPE={ty} takes {n} constants and one temperature: temperature-dependent \
                     tables are not supported"
                ),
            ));
        }
        if v.len() == n + 1 {
            self.not_used(
                at,
                "*ELASTIC temperature".into(),
                "a single temperature: the constants hold at every temperature",
            );
        }
        let e = |err: nonlin3d_laminate::LaminateError| kw.data_error(at, err.to_string());
        let elastic = match ty.as_str() {
            "ISO" | "ISOTROPIC" => InpElastic::Isotropic { e: v[0], nu: v[1] },
            "ENGINEERING CONSTANTS" => {
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
                o.validate().map_err(e)?;
                InpElastic::Engineering(o)
            }
            _ => {
                let ortho = ty.starts_with("ORTHO");
                let order: &[(usize, usize)] = if ortho {
                    &crate::inp::ORTHO_ORDER
                } else {
                    &crate::inp::ANISO_ORDER
                };
                let mut c = [[0.0; 6]; 6];
                for (&(r, col), &val) in order.iter().zip(&v) {
                    c[r][col] = val;
                    c[col][r] = val;
                }
                let s = Box::new(Stiffness::new(c).map_err(e)?);
                if ortho {
                    InpElastic::Orthotropic(s)
                } else {
                    InpElastic::Anisotropic(s)
                }
            }
        };
        self.m.materials[mi].elastic = elastic;
        self.elastic_given[mi] = true;
        Ok(())
    }

    fn amplitude(&mut self, kw: &Keyword, data: &[Line]) -> Result<(), MeshError> {
        kw.allow(&["NAME", "TIME", "DEFINITION", "SHIFTX", "SHIFTY"])?;
        let name = kw.require("NAME")?.to_uppercase();
        kw.choice("DEFINITION", &["TABULAR"])?;
        let total_time = kw
            .choice("TIME", &["STEP TIME", "TOTAL TIME"])?
            .is_some_and(|t| t == "TOTAL TIME");
        let (dx, dy) = (
            float_param(kw, "SHIFTX")?.unwrap_or(0.0),
            float_param(kw, "SHIFTY")?.unwrap_or(0.0),
        );
        let mut v = Vec::new();
        for l in data {
            for f in fields(&l.text).into_iter().filter(|s| !s.is_empty()) {
                v.push((float(kw, &l.at, f)?, &l.at));
            }
        }
        let at = data.last().map_or(&kw.at, |l| &l.at);
        if v.is_empty() || v.len() % 2 == 1 {
            return Err(kw.data_error(at, "expected (time, value) pairs"));
        }
        let points: Vec<(f64, f64)> = v.chunks(2).map(|p| (p[0].0 + dx, p[1].0 + dy)).collect();
        if let Some(w) = points.windows(2).position(|w| w[1].0 < w[0].0) {
            return Err(kw.data_error(
                v[2 * (w + 1)].1,
                format!(
                    "time {} before the previous {}",
                    points[w + 1].0,
                    points[w].0
                ),
            ));
        }
        if self
            .m
            .amplitudes
            .insert(name.clone(), Amplitude { points, total_time })
            .is_some()
        {
            return Err(kw.error(format!("amplitude {name} defined twice")));
        }
        Ok(())
    }
}

/// Refuses data lines under a keyword that takes none.
pub(crate) fn no_data(kw: &Keyword, data: &[Line]) -> Result<(), MeshError> {
    match data.first() {
        Some(l) => Err(kw.data_error(&l.at, "this keyword takes no data lines")),
        None => Ok(()),
    }
}
