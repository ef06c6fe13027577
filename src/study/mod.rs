//! Speed against error (`nonlin3d study`, docs/ACCURACY.md §4): a scene run over a list of
//! knob settings, each case timed on one thread, and the error of each case's G_T max, G_I and
//! G_II at S = 0 and at the largest S (the scene's last level), and of its bifurcation strain,
//! against references extrapolated from a refinement family by Richardson
//! ([`richardson::fit`]); the cases no other beats on both time and error form the Pareto
//! front ([`pareto::front`]).
//!
//! The knobs file ([`Plan`]): `[common]` tables merged into the scene for every case (e.g.
//! `[common.loads] strains = [-0.004]`), then one `[[case]]` per setting with its own
//! `mesh`, `analysis`, `contact` and `substructure` tables, merged over the scene's (any field
//! those tables of a scene accept is a knob), `family = true` for the members of the
//! refinement family and optionally their size `h`.

pub mod pareto;
pub mod richardson;
mod run;
mod write;

pub use run::{Event, run};
pub use write::{svg, table, write_all};

use crate::scene::ErrorEstimateName;
use crate::{Error, Scene};
use serde::{Deserialize, Serialize};

/// The knobs file of a study (TOML, docs/ACCURACY.md §4).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Plan {
    /// A line for the reports (default: the scene's title).
    #[serde(default)]
    pub title: Option<String>,
    /// Merged into the scene for every case.
    #[serde(default)]
    pub common: Common,
    /// The cases, in the order reported.
    #[serde(rename = "case")]
    pub cases: Vec<CaseSpec>,
}

/// Tables merged into the scene for every case: the knob tables and `loads` (to cut a sweep
/// down to the levels the study needs).
#[derive(Debug, Clone, PartialEq, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Common {
    /// `[loads]` fields.
    #[serde(default)]
    pub loads: Option<toml::Table>,
    /// The knob tables.
    #[serde(flatten)]
    pub knobs: Knobs,
}

/// The scene tables a case may change (flattened into [`Common`] and [`CaseSpec`], whose
/// `deny_unknown_fields` refuses any other table).
#[derive(Debug, Clone, PartialEq, Default, Deserialize, Serialize)]
pub struct Knobs {
    /// `[mesh]` fields.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mesh: Option<toml::Table>,
    /// `[analysis]` fields.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub analysis: Option<toml::Table>,
    /// `[contact]` fields.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub contact: Option<toml::Table>,
    /// `[substructure]` fields.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub substructure: Option<toml::Table>,
}

impl Knobs {
    /// The scene tables by name, in the order described and merged.
    fn tables(&self) -> [(&'static str, Option<&toml::Table>); 4] {
        [
            ("mesh", self.mesh.as_ref()),
            ("analysis", self.analysis.as_ref()),
            ("contact", self.contact.as_ref()),
            ("substructure", self.substructure.as_ref()),
        ]
    }
}

/// One `[[case]]`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CaseSpec {
    /// The case's name in tables and plots.
    pub name: String,
    /// A member of the refinement family that gives the references.
    #[serde(default)]
    pub family: bool,
    /// The family member's mesh size for Richardson (any unit, the same for all members).
    /// Unset: N^(−1/d) with N the DOFs and d = 3 (d = 2 for a through-width strip).
    #[serde(default)]
    pub h: Option<f64>,
    /// Its knob tables.
    #[serde(flatten)]
    pub knobs: Knobs,
}

impl Plan {
    /// Parses a knobs file; errors name the line and field, and the case of an unknown one.
    pub fn from_toml(text: &str) -> Result<Self, Error> {
        let plan: Self = toml::from_str(text).map_err(|e| {
            // Under `flatten`, toml places an unknown field at its table's header only.
            let e = e.to_string();
            match unknown_field(text, &e) {
                Some(named) => Error::Scene(format!("{named}\n{e}")),
                None => Error::Scene(e),
            }
        })?;
        if plan.cases.is_empty() {
            return Err(Error::Scene("no [[case]]".into()));
        }
        for (k, c) in plan.cases.iter().enumerate() {
            if plan.cases[..k].iter().any(|o| o.name == c.name) {
                return Err(Error::Scene(format!("two cases named '{}'", c.name)));
            }
            if let Some(h) = c.h
                && !(h.is_finite() && h > 0.0)
            {
                return Err(Error::Scene(format!("case '{}': h = {h}: > 0", c.name)));
            }
        }
        let given = plan.cases.iter().filter(|c| c.family && c.h.is_some());
        let members = plan.cases.iter().filter(|c| c.family).count();
        if given.count() % members.max(1) != 0 {
            return Err(Error::Scene(
                "give h on every family case or on none".into(),
            ));
        }
        Ok(plan)
    }

    /// Reads a knobs file.
    pub fn read(path: &std::path::Path) -> Result<Self, Error> {
        let text = std::fs::read_to_string(path).map_err(|source| Error::Io {
            path: path.to_path_buf(),
            source,
        })?;
        Self::from_toml(&text).map_err(|e| match e {
            Error::Scene(m) => Error::Scene(format!("knobs {}: {m}", path.display())),
            other => other,
        })
    }

    /// The scene of every case: `scene` with `[common]` and the case's tables merged in,
    /// validated; one factorisation thread each (the cases run side by side); the error
    /// estimate's companion only where it pays for itself (where the case's levels start
    /// from it) unless the scene, `[common.mesh]` or the case names `error_estimate` (the
    /// study measures each case's error against its family itself, docs/ACCURACY.md §4).
    pub fn scenes(&self, scene: &Scene) -> Result<Vec<Scene>, Error> {
        let base = toml::Table::try_from(scene).map_err(|e| Error::Scene(e.to_string()))?;
        let mut common = base;
        if let Some(loads) = &self.common.loads {
            merge(&mut common, "loads", loads);
        }
        merge_knobs(&mut common, &self.common.knobs);
        self.cases
            .iter()
            .map(|c| {
                let mut t = common.clone();
                merge_knobs(&mut t, &c.knobs);
                let mut s: Scene = toml::Value::Table(t)
                    .try_into()
                    .map_err(|e| Error::Scene(format!("case '{}': {e}", c.name)))?;
                s.validate()
                    .map_err(|e| Error::Scene(format!("case '{}': {e}", c.name)))?;
                s.analysis.threads = 1;
                let estimate = match seeded(&s) {
                    true => ErrorEstimateName::Companion,
                    false => ErrorEstimateName::Off,
                };
                s.mesh.error_estimate = Some(s.mesh.error_estimate.unwrap_or(estimate));
                Ok(s)
            })
            .collect()
    }
}

/// Whether a case's levels would start from its companion's (nested iteration: `start =
/// "companion"`, load control, no substructure, an embedded, edge or through-width model),
/// where the companion costs less than it saves: one thread, the reference circle on the
/// default mesh 3.5 against 12.6 CPU s without it, the five-level 30 × 60 mm ellipse 9.3
/// against 12.8, the thesis circle 2.5 against 3.1 (docs/ACCURACY.md §4). Elsewhere it adds
/// 12–44 % (§3).
fn seeded(s: &Scene) -> bool {
    use crate::scene::{Geometry, PartitionName, PathName, StartName};
    s.analysis.start == StartName::Companion
        && s.analysis.path == PathName::Load
        && s.substructure.partition == PartitionName::None
        && matches!(
            s.geometry,
            Geometry::Embedded { .. } | Geometry::Edge { .. } | Geometry::ThroughWidth { .. }
        )
}

/// The fields of `[common]` and of a `[[case]]` besides the knob tables, as their structs name
/// them (for messages).
const COMMON_FIELDS: [&str; 1] = ["loads"];
const CASE_FIELDS: [&str; 3] = ["name", "family", "h"];

/// Where the unknown field of toml's `message` stands in `text`: the table (`[common]` or the
/// case by name), the field and the fields that table takes.
fn unknown_field(text: &str, message: &str) -> Option<String> {
    let field = message.split("unknown field `").nth(1)?.split('`').next()?;
    let raw: toml::Table = toml::from_str(text).ok()?;
    let knobs = Knobs::default().tables().map(|(name, _)| name);
    let check = |table: String, value: &toml::Value, own: &[&str]| {
        let known = own.contains(&field) || knobs.contains(&field);
        (!known && value.get(field).is_some()).then(|| {
            format!(
                "{table}: unknown field `{field}`; it takes {}, {}",
                own.join(", "),
                knobs.join(", ")
            )
        })
    };
    let common = raw
        .get("common")
        .and_then(|c| check("[common]".into(), c, &COMMON_FIELDS));
    common.or_else(|| {
        let cases = raw.get("case")?.as_array()?;
        cases.iter().enumerate().find_map(|(k, c)| {
            let table = match c.get("name").and_then(toml::Value::as_str) {
                Some(name) => format!("case '{name}'"),
                None => format!("case {}", k + 1),
            };
            check(table, c, &CASE_FIELDS)
        })
    })
}

/// The knobs of a case as one line (`mesh.slices=8 analysis.newton="bfgs"`).
pub fn describe(knobs: &Knobs) -> String {
    let mut out = Vec::new();
    for (name, t) in knobs.tables() {
        for (k, v) in t.into_iter().flatten() {
            out.push(format!("{name}.{k}={v}"));
        }
    }
    out.join(" ")
}

/// Merges each knob table given into the scene's table of that name ([`merge`]).
fn merge_knobs(scene: &mut toml::Table, knobs: &Knobs) {
    for (name, t) in knobs.tables() {
        if let Some(t) = t {
            merge(scene, name, t);
        }
    }
}

/// Sets every field of `over` in the table `scene[name]` (made if absent), recursively.
fn merge(scene: &mut toml::Table, name: &str, over: &toml::Table) {
    let slot = scene
        .entry(name)
        .or_insert_with(|| toml::Value::Table(toml::Table::new()));
    if !slot.is_table() {
        *slot = toml::Value::Table(toml::Table::new());
    }
    if let toml::Value::Table(t) = slot {
        for (k, v) in over {
            match v {
                toml::Value::Table(inner) => merge(t, k, inner),
                _ => {
                    t.insert(k.clone(), v.clone());
                }
            }
        }
    }
}

/// What a study measures of one run, at the scene's last level (J/m² and strain).
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize)]
pub struct Quantities {
    /// Largest G_T along the front over the points whose faces are not overlapped.
    pub g_t_max: Option<f64>,
    /// G_I at S = 0.
    pub g_i_s0: Option<f64>,
    /// G_II at S = 0.
    pub g_ii_s0: Option<f64>,
    /// G_I at the largest S.
    pub g_i_send: Option<f64>,
    /// G_II at the largest S.
    pub g_ii_send: Option<f64>,
    /// The strain at which the path lost stability: the middle of the bracket the inertia
    /// guard kept (`convergence.bifurcation`, from … to), of the first level that crossed one.
    pub bifurcation_strain: Option<f64>,
}

/// Names and labels of the [`Quantities`], in [`Quantities::values`]' order.
pub const QUANTITIES: [(&str, &str); 6] = [
    ("g_t_max", "G_T max"),
    ("g_i_s0", "G_I(0)"),
    ("g_ii_s0", "G_II(0)"),
    ("g_i_send", "G_I(end)"),
    ("g_ii_send", "G_II(end)"),
    ("bifurcation_strain", "eps_bif"),
];

/// How many of [`QUANTITIES`] are energy release rates (the first ones).
pub const G_QUANTITIES: usize = 5;

impl Quantities {
    /// The values in [`QUANTITIES`]' order.
    pub fn values(&self) -> [Option<f64>; 6] {
        [
            self.g_t_max,
            self.g_i_s0,
            self.g_ii_s0,
            self.g_i_send,
            self.g_ii_send,
            self.bifurcation_strain,
        ]
    }

    /// From values in [`QUANTITIES`]' order.
    pub fn from_values(v: [Option<f64>; 6]) -> Self {
        Self {
            g_t_max: v[0],
            g_i_s0: v[1],
            g_ii_s0: v[2],
            g_i_send: v[3],
            g_ii_send: v[4],
            bifurcation_strain: v[5],
        }
    }

    /// Measured on a run's results.
    pub fn of(results: &crate::Results) -> Self {
        let last = results.levels.last();
        let by_s = |first: bool| {
            last.and_then(|l| {
                let rows = l.front.iter();
                if first {
                    rows.min_by(|a, b| a.s_mm.total_cmp(&b.s_mm))
                } else {
                    rows.max_by(|a, b| a.s_mm.total_cmp(&b.s_mm))
                }
            })
        };
        let (start, end) = (by_s(true), by_s(false));
        Self {
            g_t_max: last.and_then(|l| l.peak(|r| r.g_t)).map(|r| r.g_t),
            g_i_s0: start.map(|r| r.g_i),
            g_ii_s0: start.map(|r| r.g_ii),
            g_i_send: end.map(|r| r.g_i),
            g_ii_send: end.map(|r| r.g_ii),
            bifurcation_strain: results
                .levels
                .iter()
                .find_map(|l| l.convergence.bifurcation)
                .map(|b| 0.5 * (b.from + b.to)),
        }
    }
}

/// One case as run.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CaseResult {
    /// Its name.
    pub name: String,
    /// Its knobs, as one line.
    pub knobs: String,
    /// A member of the refinement family.
    pub family: bool,
    /// The size Richardson used (family members).
    pub h: Option<f64>,
    /// DOFs of the model.
    pub dofs: usize,
    /// Wall-clock seconds of the run (mesh to VCCT; the cases run side by side, so this
    /// includes waiting for a core).
    pub wall_s: f64,
    /// CPU seconds of the thread that ran it (Linux `/proc/thread-self/schedstat`; None
    /// elsewhere): the time to compare.
    pub cpu_s: Option<f64>,
    /// Newton iterations over all levels.
    pub iterations: usize,
    /// The measured quantities.
    pub values: Quantities,
    /// Relative errors (value − reference)/|reference| against the family's references.
    pub errors: Quantities,
    /// The largest |relative error| of the G quantities: the error of the Pareto plot.
    pub worst_g_error: Option<f64>,
    /// On the Pareto front of (CPU time, worst G error).
    pub pareto: bool,
    /// Why the run failed (the case is then left out of the family and the front).
    pub failed: Option<String>,
}

/// The reference of one quantity.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Reference {
    /// Which quantity ([`QUANTITIES`]).
    pub quantity: &'static str,
    /// The fit over the family (None: no family member has the quantity).
    pub fit: Option<richardson::FamilyFit>,
}

/// A whole study: what `study.json` holds.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Study {
    /// The study's title.
    pub title: String,
    /// The scene's title.
    pub scene: String,
    /// Cases run side by side.
    pub jobs: usize,
    /// How h was taken for the family (`given` or `dofs^(-1/d)`).
    pub family_size: String,
    /// Every case, in the knobs file's order.
    pub cases: Vec<CaseResult>,
    /// The references, per quantity.
    pub references: Vec<Reference>,
    /// The quantities over which each case's worst G error is taken: the G quantities whose
    /// reference is at least a tenth of the reference G_T max.
    pub worst_over: Vec<&'static str>,
}

#[cfg(test)]
mod tests;
