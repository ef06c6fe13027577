//! Abaqus/CalculiX input decks: reader for a documented subset (docs/DECKS.md lists every
//! keyword and parameter and what becomes of it).
//!
//! Nothing read is dropped in silence. Each keyword and parameter is either honoured (it is in
//! the [`InpModel`] and the solver acts on it), accepted and listed in [`InpModel::not_used`]
//! (data a static mechanical step does not use: `*HEADING`, `*DENSITY`, `*EXPANSION`, …), or
//! refused with an error naming the file, line, keyword and parameter. Step-level settings that
//! CalculiX carries from one step to the next (NLGEOM, `*CONTROLS`, output requests and their
//! frequency) are resolved here, so each [`ReadStep`] holds the values in force in it.
//!
//! [`read_inp`] reads text; [`read_inp_file`] reads a file and resolves `*INCLUDE, INPUT=` relative
//! to the including file's folder.

mod contact;
mod lexer;
mod model;
mod output;
mod riks;
mod sections;
mod step;

use crate::MeshError;
use crate::inp::InpMaterial;
use crate::model::Mesh;
use lexer::{Keyword, Line, Loc, logical_lines};
use nonlin3d_element::CylindricalAxes;
use std::collections::{BTreeMap, HashMap};
use std::path::Path;

pub use contact::ContactPairs;

/// Where a boundary condition or load applies.
#[derive(Debug, Clone, PartialEq)]
pub enum NodeRef {
    /// A node set by name (as the mesh's `node_sets` spells it).
    Set(String),
    /// One node (0-based mesh index).
    Node(usize),
}

/// A `*BOUNDARY` data line.
#[derive(Debug, Clone, PartialEq)]
pub struct ReadBoundary {
    /// Target nodes.
    pub target: NodeRef,
    /// First DOF (1–3; 4–6 refused: no rotational DOFs on solids).
    pub first: u8,
    /// Last DOF.
    pub last: u8,
    /// Value (0 when omitted; not used with `fixed`).
    pub value: f64,
    /// `AMPLITUDE=`: the value is value·A(t) instead of a ramp from the previous value.
    pub amplitude: Option<String>,
    /// `FIXED`: held at the displacement the node has at the start of the step.
    pub fixed: bool,
    /// Line in the deck (for messages).
    pub line: usize,
}

/// A `*CLOAD` data line.
#[derive(Debug, Clone, PartialEq)]
pub struct ReadCload {
    /// Target nodes.
    pub target: NodeRef,
    /// DOF 1–3.
    pub dof: u8,
    /// Force, N (per node of a set).
    pub value: f64,
    /// `AMPLITUDE=`: the force is value·A(t) instead of a ramp from the previous value.
    pub amplitude: Option<String>,
    /// Line in the deck (for messages).
    pub line: usize,
}

/// `*STATIC` and its data line, with CalculiX's defaults and adjustments applied.
#[derive(Debug, Clone, PartialEq)]
pub struct StaticData {
    /// Initial time increment.
    pub initial: f64,
    /// Step time period.
    pub period: f64,
    /// Smallest increment (automatic incrementation).
    pub min: f64,
    /// Largest increment.
    pub max: f64,
    /// `DIRECT`: fixed increments of `initial`, no cutback.
    pub direct: bool,
    /// `TIME RESET`: the step's total time runs from (total time at its start − period), so the
    /// total time does not advance over it (CalculiX's reading).
    pub time_reset: bool,
    /// `TOTAL TIME AT START=`.
    pub total_time_at_start: Option<f64>,
    /// `*STATIC, RIKS`: an arc-length step (its data line; `initial` … `max` then unused).
    pub riks: Option<RiksData>,
}

/// The data line of `*STATIC, RIKS` (Abaqus), with Abaqus's defaults applied. Arc lengths are
/// in scaled load–displacement space: the first increment's load proportionality factor is
/// `initial / period`.
#[derive(Debug, Clone, PartialEq)]
pub struct RiksData {
    /// Initial arc length increment Δl_in (0 → the total arc length `period`).
    pub initial: f64,
    /// Total arc length scale factor l_period (0 → 1).
    pub period: f64,
    /// Smallest arc length increment (0 → min(Δl_in, 1e-5·l_period)).
    pub min: f64,
    /// Largest arc length increment (none → unbounded).
    pub max: f64,
    /// Maximum load proportionality factor λ_end: the step ends once |λ| reaches it.
    pub max_lpf: Option<f64>,
    /// Node (mesh index), DOF (1–3) and value of the displacement that ends the step once
    /// crossed.
    pub monitor: Option<(usize, u8, f64)>,
    /// `DIRECT`: the arc length stays Δl_in, no cutback.
    pub direct: bool,
}

impl Default for StaticData {
    /// CalculiX's defaults without a data line: one increment of the whole period 1.
    fn default() -> Self {
        Self {
            initial: 1.0,
            period: 1.0,
            min: 1e-6,
            max: 1e30,
            direct: false,
            time_reset: false,
            total_time_at_start: None,
            riks: None,
        }
    }
}

/// `*CONTROLS` values in force in a step (None: nonlin3d's default, docs/DECKS.md).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Controls {
    /// `PARAMETERS=FIELD` R_n: converged when the largest residual force ≤ R_n × the force scale.
    pub residual_ratio: Option<f64>,
    /// `PARAMETERS=FIELD` C_n: and the largest correction ≤ C_n × the largest displacement.
    pub correction_ratio: Option<f64>,
    /// `TIME INCREMENTATION` I_0: from this iteration on, a residual that stays above the one
    /// two iterations back for two iterations is divergence (cut back by D_F).
    pub divergence_check: Option<usize>,
    /// I_R: from this iteration on, a logarithmic estimate of the iterations to convergence
    /// above I_C is too slow convergence (cut back by D_C).
    pub slow_check: Option<usize>,
    /// `TIME INCREMENTATION` I_C: iterations before an increment is cut back.
    pub max_iterations: Option<usize>,
    /// I_L: more iterations than this shrink the next increment by D_B.
    pub slow_iterations: Option<usize>,
    /// I_G: two increments in a row with at most this many iterations grow the next by D_D.
    pub easy_iterations: Option<usize>,
    /// I_A: cutbacks allowed per increment.
    pub max_cutbacks: Option<usize>,
    /// D_F: cutback factor after divergence.
    pub diverged_cutback: Option<f64>,
    /// D_C: cutback factor after too many iterations.
    pub slow_cutback: Option<f64>,
    /// D_B: next-increment factor after a slow increment.
    pub slow_shrink: Option<f64>,
    /// D_D: growth factor.
    pub grow: Option<f64>,
}

/// What an output request asks for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum OutputKind {
    /// `*NODE PRINT` (CalculiX's .dat).
    NodePrint,
    /// `*NODE FILE` / `*NODE OUTPUT` (CalculiX's .frd).
    NodeFile,
    /// `*EL PRINT`.
    ElPrint,
    /// `*EL FILE` / `*ELEMENT OUTPUT`.
    ElFile,
}

/// A variable an output request lists.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum OutputVariable {
    /// Displacements.
    U,
    /// Nodal forces (CalculiX's RF: the internal force at the node, its reaction where it is
    /// constrained).
    Rf,
    /// Stresses at the integration points (Cauchy; small-strain σ = Cε in linear steps).
    S,
}

/// `TOTALS=` of a `*NODE PRINT`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Totals {
    /// Per node only.
    #[default]
    No,
    /// Per node and the sum over the set.
    Yes,
    /// The sum only.
    Only,
}

/// An output request in force in a step.
#[derive(Debug, Clone, PartialEq)]
pub struct OutputRequest {
    /// Kind.
    pub kind: OutputKind,
    /// The node set (node requests) or element set (element requests); None = all.
    pub set: Option<String>,
    /// Variables in the order listed.
    pub variables: Vec<OutputVariable>,
    /// `TOTALS=` (node prints of RF).
    pub totals: Totals,
    /// Element variables in each element's material axes (CalculiX's default for `*EL PRINT`;
    /// `GLOBAL=NO` on `*EL FILE`) instead of global axes.
    pub local_axes: bool,
    /// Line of the keyword.
    pub line: usize,
}

/// A `*STEP` … `*END STEP` block with the settings in force in it.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ReadStep {
    /// Line of `*STEP`.
    pub line: usize,
    /// NLGEOM in force (CalculiX keeps it on in later steps).
    pub nlgeom: bool,
    /// `INC=`: most increments (CalculiX's default 100).
    pub max_increments: usize,
    /// `*STATIC`.
    pub procedure: StaticData,
    /// `*BOUNDARY, OP=NEW` on the step's first `*BOUNDARY`: earlier boundary conditions removed.
    pub boundary_op_new: bool,
    /// `*CLOAD, OP=NEW` on the step's first `*CLOAD`: earlier loads set to zero.
    pub cload_op_new: bool,
    /// Boundary conditions.
    pub boundaries: Vec<ReadBoundary>,
    /// Concentrated loads.
    pub cloads: Vec<ReadCload>,
    /// `*CONTROLS` in force.
    pub controls: Controls,
    /// Output requests in force.
    pub outputs: Vec<OutputRequest>,
    /// Output every this many increments (and at the end of the step); CalculiX keeps one
    /// frequency for all requests, the last `FREQUENCY=` given.
    pub output_frequency: usize,
}

/// A tabular `*AMPLITUDE`.
#[derive(Debug, Clone, PartialEq)]
pub struct Amplitude {
    /// (time, value) pairs, times increasing; `SHIFTX`/`SHIFTY` applied.
    pub points: Vec<(f64, f64)>,
    /// `TIME=TOTAL TIME`: evaluated at the total time instead of the step time.
    pub total_time: bool,
}

impl Amplitude {
    /// The value at step time `step_time` of a step that started at total time `step_start`:
    /// linear between points, the first (last) value before (after) them.
    pub fn at(&self, step_time: f64, step_start: f64) -> f64 {
        let t = if self.total_time {
            step_start + step_time
        } else {
            step_time
        };
        let p = &self.points;
        let Some(first) = p.first() else { return 0.0 };
        if t <= first.0 {
            return first.1;
        }
        for w in p.windows(2) {
            let ((t0, v0), (t1, v1)) = (w[0], w[1]);
            if t <= t1 {
                return if t1 > t0 {
                    v0 + (v1 - v0) * (t - t0) / (t1 - t0)
                } else {
                    v1
                };
            }
        }
        p.last().map_or(0.0, |l| l.1)
    }
}

/// Something a deck gave that a static mechanical analysis does not use, listed rather than
/// dropped.
#[derive(Debug, Clone, PartialEq)]
pub struct NotUsed {
    /// `line N` or `FILE line N`.
    pub at: String,
    /// The keyword (and parameter).
    pub keyword: String,
    /// Why it does not matter here.
    pub reason: String,
}

/// What a deck holds.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct InpModel {
    /// The mesh; each cell's `material` comes from its `*SOLID SECTION`, `ply_angle_deg` from
    /// its orientation when that is a rotation about z (0 otherwise: see `orientations`).
    pub mesh: Mesh,
    /// Deck id of each node.
    pub node_ids: Vec<usize>,
    /// Deck id of each element.
    pub element_ids: Vec<usize>,
    /// Where each element was defined: `line N`, or `FILE line N` in an included file (for
    /// messages about an element).
    pub element_at: Vec<String>,
    /// Whether each element was declared with reduced integration (C3D20R).
    pub reduced: Vec<bool>,
    /// Materials in deck order.
    pub materials: Vec<InpMaterial>,
    /// Material axes of each cell: columns are the local 1, 2, 3 axes in global coordinates
    /// (identity without an orientation).
    pub orientations: Vec<[[f64; 3]; 3]>,
    /// Name of each cell's orientation, if any.
    pub orientation_names: Vec<Option<String>>,
    /// The axes of each cell whose orientation is cylindrical (`SYSTEM=CYLINDRICAL`): they
    /// vary with the position, local 1 radial, 2 tangential, 3 axial
    /// ([`CylindricalAxes::axes_at`]); `orientations` holds identity for such cells.
    pub cylindrical: Vec<Option<CylindricalAxes>>,
    /// Boundary conditions given before the first step (ramped in the first step from zero,
    /// as CalculiX does).
    pub initial_boundaries: Vec<ReadBoundary>,
    /// Steps.
    pub steps: Vec<ReadStep>,
    /// Tabular amplitudes by name (upper case).
    pub amplitudes: BTreeMap<String, Amplitude>,
    /// Keywords and parameters accepted but not used, in deck order.
    pub not_used: Vec<NotUsed>,
    /// Frictionless contact: the node pairs of each `*CONTACT PAIR` data line (matching faces).
    pub contact: Vec<ContactPairs>,
}

/// Reads a deck from text (`*INCLUDE` needs a file: use [`read_inp_file`]).
pub fn read_inp(text: &str) -> Result<InpModel, MeshError> {
    read_lines(logical_lines(text, None)?)
}

/// Reads a deck file, resolving `*INCLUDE, INPUT=` relative to the including file.
pub fn read_inp_file(path: &Path) -> Result<InpModel, MeshError> {
    let text = std::fs::read_to_string(path).map_err(|e| MeshError::Deck {
        at: path.display().to_string(),
        what: "deck".into(),
        reason: format!("cannot read it: {e}"),
    })?;
    read_lines(logical_lines(&text, Some(path))?)
}

/// A set named by a boundary condition, load or output request.
pub(crate) struct SetUse {
    /// The data line or keyword line that names it.
    pub at: Loc,
    /// `*BOUNDARY data`, `*NODE PRINT, NSET`, ….
    pub what: String,
    /// Node set (true) or element set.
    pub nodes: bool,
    /// The mesh spelling.
    pub name: String,
}

/// The reader's state between keywords.
#[derive(Default)]
pub(crate) struct Reader {
    pub m: InpModel,
    pub node_index: HashMap<usize, usize>,
    pub elem_index: HashMap<usize, usize>,
    /// Upper-case set name → the spelling stored in the mesh.
    pub node_set_names: HashMap<String, String>,
    pub cell_set_names: HashMap<String, String>,
    pub orientations: HashMap<String, sections::Axes>,
    pub sections: Vec<sections::Section>,
    /// Where each element was defined.
    pub element_at: Vec<Loc>,
    /// Where each set (by kind, node sets `true`, and upper-case name) was first defined.
    pub set_at: HashMap<(bool, String), Loc>,
    /// Sets that a `*BOUNDARY`, `*CLOAD` or output request uses, checked non-empty at the end.
    pub set_uses: Vec<SetUse>,
    /// Materials given `*ELASTIC`.
    pub elastic_given: Vec<bool>,
    /// The step being read.
    pub step: Option<step::StepState>,
    /// Carried from step to step as CalculiX does.
    pub carried: step::Carried,
    /// Surfaces, interactions and contact pairs read so far.
    pub contact: contact::ContactCards,
}

fn read_lines(lines: Vec<Line>) -> Result<InpModel, MeshError> {
    let mut r = Reader::default();
    let mut i = 0;
    while i < lines.len() {
        let line = &lines[i];
        if !line.text.starts_with('*') {
            return Err(lexer::deck_error(
                &line.at,
                "data line",
                "data line outside any keyword",
            ));
        }
        let kw = Keyword::parse(&line.text, line.at.clone());
        let mut end = i + 1;
        while end < lines.len() && !lines[end].text.starts_with('*') {
            end += 1;
        }
        let data = &lines[i + 1..end];
        if !r.model_keyword(&kw, data)?
            && !r.contact_keyword(&kw, data)?
            && !r.step_keyword(&kw, data)?
        {
            return Err(kw.error("keyword not supported (docs/DECKS.md lists what nonlin3d reads)"));
        }
        i = end;
    }
    if let Some(s) = &r.step {
        return Err(lexer::deck_error(
            &s.at,
            "*STEP",
            "deck ends inside a step (missing *END STEP)",
        ));
    }
    r.finish()
}

impl Reader {
    /// Lists `kw` (with its data) as accepted but not used.
    pub(crate) fn not_used(&mut self, at: &Loc, keyword: String, reason: &str) {
        self.m.not_used.push(NotUsed {
            at: at.to_string(),
            keyword,
            reason: reason.to_string(),
        });
    }

    /// The mesh spelling of node set `name` (case-insensitive, as CalculiX).
    pub(crate) fn node_set(&self, name: &str) -> Option<&String> {
        self.node_set_names.get(&name.to_uppercase())
    }

    /// The mesh spelling of element set `name`.
    pub(crate) fn cell_set(&self, name: &str) -> Option<&String> {
        self.cell_set_names.get(&name.to_uppercase())
    }

    /// Records that `what` at `at` uses set `name` (mesh spelling).
    pub(crate) fn use_set(&mut self, at: &Loc, what: String, nodes: bool, name: &str) {
        self.set_uses.push(SetUse {
            at: at.clone(),
            what,
            nodes,
            name: name.to_string(),
        });
    }

    /// A set that a boundary condition, load or output request names must have members: an
    /// empty one would constrain, load or print nothing without a word.
    fn check_set_uses(&self) -> Result<(), MeshError> {
        for u in &self.set_uses {
            let sets = if u.nodes {
                &self.m.mesh.node_sets
            } else {
                &self.m.mesh.cell_sets
            };
            if sets.get(&u.name).is_some_and(|s| !s.is_empty()) {
                continue;
            }
            let kind = if u.nodes { "node" } else { "element" };
            let defined = self
                .set_at
                .get(&(u.nodes, u.name.to_uppercase()))
                .map(|at| format!(" (defined at {at})"))
                .unwrap_or_default();
            return Err(lexer::deck_error(
                &u.at,
                &u.what,
                format!(
                    "{kind} set '{}'{defined} is empty: it would act on nothing",
                    u.name
                ),
            ));
        }
        Ok(())
    }

    fn finish(mut self) -> Result<InpModel, MeshError> {
        self.resolve_sections()?;
        self.check_set_uses()?;
        self.resolve_contact()?;
        self.m.element_at = self.element_at.iter().map(ToString::to_string).collect();
        for set in self
            .m
            .mesh
            .node_sets
            .values_mut()
            .chain(self.m.mesh.cell_sets.values_mut())
        {
            set.sort_unstable();
            set.dedup();
        }
        self.m.mesh.validate()?;
        Ok(self.m)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn amplitudes_interpolate_and_hold_their_ends() {
        let a = Amplitude {
            points: vec![(0.0, 0.0), (0.5, 1.0), (1.0, 0.5)],
            total_time: false,
        };
        assert_eq!(a.at(0.25, 3.0), 0.5);
        assert_eq!(a.at(0.75, 3.0), 0.75);
        assert_eq!(a.at(2.0, 3.0), 0.5);
        assert_eq!(a.at(-1.0, 3.0), 0.0);
        let t = Amplitude {
            total_time: true,
            ..a.clone()
        };
        // Step 2 of period 1 starts at total time 1: the table is past its end.
        assert_eq!(t.at(0.25, 1.0), 0.5);
        assert_eq!(t.at(0.25, 0.0), 0.5);
    }
}
