//! Step keywords: `*STEP`, `*STATIC`, `*BOUNDARY`, `*CLOAD`, `*CONTROLS`, output requests,
//! `*END STEP`, with what CalculiX carries from one step to the next.

use super::lexer::{Keyword, Line, Loc, fields, float, int, int_param};
use super::model::no_data;
use super::riks::riks_without_amplitudes;
use super::{
    Controls, NodeRef, OutputKind, OutputRequest, ReadBoundary, ReadCload, ReadStep, Reader,
    StaticData,
};
use crate::MeshError;

/// What CalculiX keeps from one step to the next.
#[derive(Debug, Clone)]
pub(crate) struct Carried {
    pub nlgeom: bool,
    pub controls: Controls,
    pub outputs: Vec<OutputRequest>,
    pub frequency: usize,
}

impl Default for Carried {
    fn default() -> Self {
        Self {
            nlgeom: false,
            controls: Controls::default(),
            outputs: Vec::new(),
            frequency: 1,
        }
    }
}

/// The step being read.
pub(crate) struct StepState {
    pub at: Loc,
    pub step: ReadStep,
    pub has_static: bool,
    pub seen_boundary: bool,
    pub seen_cload: bool,
    /// Output kinds already given in this step (their first card resets the carried ones).
    pub seen_outputs: Vec<OutputKind>,
}

/// CalculiX's `*CONTROLS, PARAMETERS=TIME INCREMENTATION` defaults (I_0 … I_A on line 1, D_F …
/// W_G on line 2) and `PARAMETERS=FIELD` defaults (R_n … R_l).
const TIME_LINE_1: [(&str, f64); 8] = [
    ("I_0", 4.0),
    ("I_R", 8.0),
    ("I_P", 9.0),
    ("I_C", 16.0),
    ("I_L", 10.0),
    ("I_G", 4.0),
    ("I_S", 0.0),
    ("I_A", 5.0),
];
const TIME_LINE_2: [(&str, f64); 8] = [
    ("D_F", 0.25),
    ("D_C", 0.5),
    ("D_B", 0.75),
    ("D_A", 0.85),
    ("D_S", 0.0),
    ("D_H", 0.0),
    ("D_D", 1.5),
    ("W_G", 0.0),
];
const FIELD_LINE: [(&str, f64); 8] = [
    ("R_n", 0.005),
    ("C_n", 0.01),
    ("q_0", 0.0),
    ("q_u", 0.0),
    ("R_P", 0.02),
    ("epsilon", 1e-5),
    ("C_epsilon", 1e-3),
    ("R_l", 1e-8),
];

impl Reader {
    /// Handles `kw` if it is a step keyword; Ok(false) if it is not one of these keywords.
    pub(crate) fn step_keyword(&mut self, kw: &Keyword, data: &[Line]) -> Result<bool, MeshError> {
        match kw.name.as_str() {
            "STEP" => self.begin_step(kw, data)?,
            "STATIC" => self.static_procedure(kw, data)?,
            "BOUNDARY" => self.boundary(kw, data)?,
            "CLOAD" => self.cload(kw, data)?,
            "CONTROLS" => self.controls(kw, data)?,
            "NODE PRINT" => self.output(kw, data, OutputKind::NodePrint)?,
            "NODE FILE" | "NODE OUTPUT" => self.output(kw, data, OutputKind::NodeFile)?,
            "EL PRINT" => self.output(kw, data, OutputKind::ElPrint)?,
            "EL FILE" | "ELEMENT OUTPUT" => self.output(kw, data, OutputKind::ElFile)?,
            "OUTPUT" => {
                kw.allow(&["FIELD", "HISTORY", "FREQUENCY"])?;
                if kw.get("FREQUENCY").is_some() {
                    return Err(kw.param_error(
                        "FREQUENCY",
                        "give FREQUENCY= on *NODE FILE / *EL FILE / *NODE PRINT / *EL PRINT",
                    ));
                }
                no_data(kw, data)?;
                self.not_used(
                    &kw.at,
                    kw.what(),
                    "Abaqus output-database block: its *NODE OUTPUT / *ELEMENT OUTPUT are read \
                     as *NODE FILE / *EL FILE, as CalculiX does",
                );
            }
            "END STEP" => {
                kw.allow(&[])?;
                no_data(kw, data)?;
                let s = self
                    .step
                    .take()
                    .ok_or_else(|| kw.error("*END STEP without *STEP"))?;
                if !s.has_static {
                    return Err(super::lexer::deck_error(
                        &s.at,
                        "*STEP",
                        "the step has no *STATIC procedure",
                    ));
                }
                let mut step = s.step;
                if step.procedure.riks.is_some() {
                    riks_without_amplitudes(&s.at, &step)?;
                }
                step.controls = self.carried.controls.clone();
                step.outputs = self.carried.outputs.clone();
                step.output_frequency = self.carried.frequency;
                self.m.steps.push(step);
            }
            _ => return Ok(false),
        }
        Ok(true)
    }

    fn begin_step(&mut self, kw: &Keyword, data: &[Line]) -> Result<(), MeshError> {
        if self.step.is_some() {
            return Err(kw.error("*STEP inside a step (missing *END STEP)"));
        }
        kw.allow(&["NLGEOM", "INC"])?;
        no_data(kw, data)?;
        if self
            .m
            .steps
            .last()
            .is_some_and(|s| s.procedure.riks.is_some())
        {
            return Err(kw.error(
                "a step after a *STATIC, RIKS step is not supported (its loads end at the load \
                 proportionality factor reached, not at the step's values)",
            ));
        }
        let nlgeom = match kw.get("NLGEOM") {
            None => self.carried.nlgeom,
            Some(_) => kw.flag("NLGEOM")?,
        };
        if self.carried.nlgeom && !nlgeom {
            return Err(kw.param_error(
                "NLGEOM",
                "a geometrically linear step after an NLGEOM step is not supported",
            ));
        }
        self.carried.nlgeom = nlgeom;
        let max_increments = int_param(kw, "INC")?.unwrap_or(100);
        if max_increments == 0 {
            return Err(kw.param_error("INC", "must be at least 1"));
        }
        self.step = Some(StepState {
            at: kw.at.clone(),
            step: ReadStep {
                line: kw.at.line,
                nlgeom,
                max_increments,
                ..Default::default()
            },
            has_static: false,
            seen_boundary: false,
            seen_cload: false,
            seen_outputs: Vec::new(),
        });
        Ok(())
    }

    pub(crate) fn current(&mut self, kw: &Keyword) -> Result<&mut StepState, MeshError> {
        self.step
            .as_mut()
            .ok_or_else(|| kw.error(format!("{} outside a step", kw.what())))
    }

    /// `*STATIC` with CalculiX's defaults and adjustments (statics.f): period 0 → 1, initial
    /// 0 → the period, minimum below 1e-6 × period → min(initial, 1e-6 × period), maximum 0 →
    /// unbounded, initial above maximum → maximum (not with DIRECT).
    fn static_procedure(&mut self, kw: &Keyword, data: &[Line]) -> Result<(), MeshError> {
        if kw.get("RIKS").is_some() {
            return self.riks_procedure(kw, data);
        }
        kw.allow(&["DIRECT", "SOLVER", "TIME RESET", "TOTAL TIME AT START"])?;
        let direct = kw.flag("DIRECT")?;
        let time_reset = kw.flag("TIME RESET")?;
        let total_time_at_start = super::lexer::float_param(kw, "TOTAL TIME AT START")?;
        if let Some(s) = kw.get("SOLVER") {
            self.not_used(
                &kw.at,
                format!("*STATIC, SOLVER={s}"),
                "nonlin3d uses its own sparse direct solver",
            );
        }
        let st = self.current(kw)?;
        if st.has_static {
            return Err(kw.error("a second *STATIC in one step"));
        }
        st.has_static = true;
        let mut p = StaticData {
            direct,
            time_reset,
            total_time_at_start,
            ..StaticData::default()
        };
        if data.len() > 1 {
            return Err(kw.data_error(&data[1].at, "one data line expected"));
        }
        if let Some(l) = data.first() {
            let f = fields(&l.text);
            if f.len() > 5 {
                return Err(kw.data_error(&l.at, "expected: initial, period, minimum, maximum"));
            }
            if f.get(4).is_some_and(|s| !s.is_empty()) {
                return Err(kw.data_error(
                    &l.at,
                    "field 5 (initial fluid increment) is for CFD and not supported",
                ));
            }
            let get = |i: usize| -> Result<f64, MeshError> {
                match f.get(i) {
                    Some(s) if !s.is_empty() => float(kw, &l.at, s),
                    _ => Ok(0.0),
                }
            };
            let (tinc, tper, tmin, tmax) = (get(0)?, get(1)?, get(2)?, get(3)?);
            if tper < 0.0 || tinc < 0.0 {
                return Err(kw.data_error(&l.at, "negative period or increment"));
            }
            p.period = if tper > 0.0 { tper } else { 1.0 };
            p.initial = if tinc > 0.0 { tinc } else { p.period };
            if p.initial > p.period {
                return Err(kw.data_error(&l.at, "initial increment exceeds the step period"));
            }
            p.min = tmin;
            p.max = tmax;
            if !direct {
                if tmin.abs() < 1e-6 * p.period {
                    p.min = p.initial.min(1e-6 * p.period);
                }
                if tmax.abs() < 1e-10 {
                    p.max = 1e30;
                }
                p.initial = p.initial.min(p.max.abs());
            }
        }
        let linear_detail = !st.step.nlgeom && (direct || !data.is_empty());
        st.step.procedure = p;
        if linear_detail {
            self.not_used(
                &kw.at,
                "*STATIC increments".into(),
                "a linear step is solved in one increment to the end of its period, as CalculiX \
                 does",
            );
        }
        Ok(())
    }

    /// The node or node set in the first field of a data line (a set is recorded, to be
    /// checked non-empty at the end of the deck).
    fn target(&mut self, kw: &Keyword, l: &Line, f: &str) -> Result<NodeRef, MeshError> {
        match f.parse::<usize>() {
            Ok(id) => Ok(NodeRef::Node(*self.node_index.get(&id).ok_or_else(
                || kw.data_error(&l.at, format!("node {id} is not defined")),
            )?)),
            Err(_) => {
                let name = self.node_set(f).cloned().ok_or_else(|| {
                    kw.data_error(&l.at, format!("node set '{f}' is not defined"))
                })?;
                self.use_set(&l.at, format!("*{} data", kw.name), true, &name);
                Ok(NodeRef::Set(name))
            }
        }
    }

    fn amplitude_param(&self, kw: &Keyword) -> Result<Option<String>, MeshError> {
        let Some(name) = kw.get("AMPLITUDE") else {
            return Ok(None);
        };
        let name = name.to_uppercase();
        if self.m.amplitudes.contains_key(&name) {
            Ok(Some(name))
        } else {
            Err(kw.param_error(
                "AMPLITUDE",
                format!("amplitude '{name}' is not defined (above)"),
            ))
        }
    }

    /// `OP=NEW|MOD`: whether NEW, refused on other than the step's first card of its kind
    /// (CalculiX ignores it there) and outside steps.
    fn op_new(&mut self, kw: &Keyword, first: bool) -> Result<bool, MeshError> {
        let new = kw
            .choice("OP", &["NEW", "MOD"])?
            .is_some_and(|o| o == "NEW");
        if new && self.step.is_none() {
            return Err(kw.param_error("OP", "OP=NEW outside a step"));
        }
        if new && !first {
            return Err(kw.param_error(
                "OP",
                format!("OP=NEW only on the first {} of a step", kw.what()),
            ));
        }
        Ok(new)
    }

    fn dof(kw: &Keyword, l: &Line, x: &str) -> Result<u8, MeshError> {
        let d = int(kw, &l.at, x)?;
        if (1..=3).contains(&d) {
            Ok(d as u8)
        } else {
            Err(kw.data_error(&l.at, format!("DOF {d} not supported (solids have 1–3)")))
        }
    }

    fn boundary(&mut self, kw: &Keyword, data: &[Line]) -> Result<(), MeshError> {
        kw.allow(&["OP", "AMPLITUDE", "FIXED"])?;
        let first = self.step.as_ref().is_some_and(|s| !s.seen_boundary);
        let new = self.op_new(kw, first)?;
        let amplitude = self.amplitude_param(kw)?;
        let fixed = kw.flag("FIXED")?;
        let mut read = Vec::with_capacity(data.len());
        for l in data {
            let f = fields(&l.text);
            if f.len() < 2 || f.len() > 4 {
                return Err(kw.data_error(
                    &l.at,
                    "expected: node or set, first DOF[, last DOF[, value]]",
                ));
            }
            let target = self.target(kw, l, f[0])?;
            let first = Self::dof(kw, l, f[1])?;
            let last = match f.get(2) {
                Some(s) if !s.is_empty() => Self::dof(kw, l, s)?,
                _ => first,
            };
            if last < first {
                return Err(kw.data_error(&l.at, "last DOF before first"));
            }
            let value = match f.get(3) {
                Some(s) if !s.is_empty() => {
                    if fixed {
                        return Err(kw.data_error(&l.at, "FIXED takes no value"));
                    }
                    float(kw, &l.at, s)?
                }
                _ => 0.0,
            };
            read.push(ReadBoundary {
                target,
                first,
                last,
                value,
                amplitude: amplitude.clone(),
                fixed,
                line: l.at.line,
            });
        }
        match self.step.as_mut() {
            Some(s) => {
                s.seen_boundary = true;
                s.step.boundary_op_new |= new;
                s.step.boundaries.extend(read);
            }
            None => self.m.initial_boundaries.extend(read),
        }
        Ok(())
    }

    fn cload(&mut self, kw: &Keyword, data: &[Line]) -> Result<(), MeshError> {
        if kw.get("FOLLOWER").is_some() {
            return Err(kw.param_error(
                "FOLLOWER",
                "follower loads are not supported (the load would keep its direction)",
            ));
        }
        kw.allow(&["OP", "AMPLITUDE"])?;
        let first = self.step.as_ref().is_some_and(|s| !s.seen_cload);
        self.current(kw)?;
        let new = self.op_new(kw, first)?;
        let amplitude = self.amplitude_param(kw)?;
        let mut read = Vec::with_capacity(data.len());
        for l in data {
            let f = fields(&l.text);
            if f.len() < 2 || f.len() > 3 {
                return Err(kw.data_error(&l.at, "expected: node or set, DOF, value"));
            }
            read.push(ReadCload {
                target: self.target(kw, l, f[0])?,
                dof: Self::dof(kw, l, f[1])?,
                value: match f.get(2) {
                    Some(s) if !s.is_empty() => float(kw, &l.at, s)?,
                    _ => 0.0,
                },
                amplitude: amplitude.clone(),
                line: l.at.line,
            });
        }
        let s = self.current(kw)?;
        s.seen_cload = true;
        s.step.cload_op_new |= new;
        s.step.cloads.extend(read);
        Ok(())
    }

    /// `*CONTROLS`: RESET, or the honoured fields of TIME INCREMENTATION and FIELD; a field
    /// nonlin3d does not implement is refused unless empty or equal to CalculiX's default.
    fn controls(&mut self, kw: &Keyword, data: &[Line]) -> Result<(), MeshError> {
        kw.allow(&["RESET", "PARAMETERS"])?;
        if kw.get("RESET").is_some() {
            if kw.get("PARAMETERS").is_some() {
                return Err(kw.param_error("PARAMETERS", "with RESET"));
            }
            no_data(kw, data)?;
            self.carried.controls = Controls::default();
            return Ok(());
        }
        let which = kw
            .choice("PARAMETERS", &["TIME INCREMENTATION", "FIELD"])?
            .ok_or_else(|| kw.error("PARAMETERS= or RESET missing"))?;
        let lines: &[&[(&str, f64); 8]] = if which == "FIELD" {
            &[&FIELD_LINE]
        } else {
            &[&TIME_LINE_1, &TIME_LINE_2]
        };
        if data.len() > lines.len() {
            return Err(kw.data_error(&data[lines.len()].at, "too many data lines"));
        }
        let c = &mut self.carried.controls;
        for (l, names) in data.iter().zip(lines) {
            let f = fields(&l.text);
            if f.len() > 8 {
                return Err(kw.data_error(&l.at, "at most 8 fields"));
            }
            for (s, &(name, default)) in f.iter().zip(names.iter()) {
                if s.is_empty() {
                    continue;
                }
                let v = float(kw, &l.at, s)?;
                let int_of = |v: f64| -> Result<usize, MeshError> {
                    if v >= 0.0 && v.fract() == 0.0 {
                        Ok(v as usize)
                    } else {
                        Err(kw.data_error(&l.at, format!("{name} = {s}: expected an integer")))
                    }
                };
                let positive = |v: f64| -> Result<f64, MeshError> {
                    if v > 0.0 {
                        Ok(v)
                    } else {
                        Err(kw
                            .data_error(&l.at, format!("{name} = {s}: expected a positive value")))
                    }
                };
                match name {
                    "I_0" => c.divergence_check = Some(int_of(v)?.max(1)),
                    "I_R" => c.slow_check = Some(int_of(v)?.max(1)),
                    "I_C" => c.max_iterations = Some(int_of(v)?.max(1)),
                    "I_L" => c.slow_iterations = Some(int_of(v)?),
                    "I_G" => c.easy_iterations = Some(int_of(v)?),
                    "I_A" => c.max_cutbacks = Some(int_of(v)?),
                    "D_F" => c.diverged_cutback = Some(positive(v)?),
                    "D_C" => c.slow_cutback = Some(positive(v)?),
                    "D_B" => c.slow_shrink = Some(positive(v)?),
                    "D_D" => c.grow = Some(positive(v)?),
                    "R_n" => c.residual_ratio = Some(positive(v)?),
                    "C_n" => c.correction_ratio = Some(positive(v)?),
                    _ if v == default => {}
                    _ => {
                        return Err(kw.data_error(
                            &l.at,
                            format!(
                                "*CONTROLS, PARAMETERS={which}: {name} = {s} is not supported \
                                 (only CalculiX's default {default} or an empty field)"
                            ),
                        ));
                    }
                }
            }
        }
        for (name, v) in [("D_F", c.diverged_cutback), ("D_C", c.slow_cutback)] {
            if v.is_some_and(|v| v >= 1.0) {
                return Err(kw.error(format!("{name} must be below 1")));
            }
        }
        if c.grow.is_some_and(|v| v < 1.0) {
            return Err(kw.error("D_D must be at least 1"));
        }
        Ok(())
    }
}
