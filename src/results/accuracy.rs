//! The accuracy part of the results (issue 25, docs/ACCURACY.md §3): the estimated error of G
//! per front point and per level, and the mesh a target or the default chose.

use serde::Serialize;

/// The estimated discretisation error (±) of each G at a front point, J/m².
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct GError {
    /// ±G_I.
    pub g_i: f64,
    /// ±G_II.
    pub g_ii: f64,
    /// ±G_III.
    pub g_iii: f64,
    /// ±G_T.
    pub g_t: f64,
}

/// A level's error estimate over its front (the points whose faces are not overlapped).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct LevelError {
    /// The largest ±G over the points and modes, J/m².
    pub max_j_m2: f64,
    /// The level's G_T max, J/m², the scale of the relative error.
    pub g_t_max_j_m2: f64,
    /// max_j_m2 / g_t_max_j_m2: the level's relative error, compared with `[mesh] accuracy`.
    pub relative: f64,
}

/// What `[mesh] accuracy` chose and what the error estimate found (results.json `accuracy`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct AccuracyReport {
    /// `companion` or `off`.
    pub error_estimate: String,
    /// DOFs of the companion mesh (null: no estimate).
    pub companion_dofs: Option<usize>,
    /// Seconds the companion run took (null: no estimate).
    pub companion_s: Option<f64>,
    /// Levels the companion started from its own, coarser companion's states (nested
    /// companions: a companion of 5 000 DOF or more; 0: it followed every level itself; null:
    /// no estimate).
    pub companion_seeded_levels: Option<usize>,
    /// DOFs of the companion's own coarser companion whose difference from the companion
    /// entered the estimate (docs/ACCURACY.md §3d; null: not used — no such companion, as
    /// with `start = "path"` or a companion under 5 000 DOF, or a rule measured without it).
    pub coarser_companion_dofs: Option<usize>,
    /// Why there is no estimate although one was asked for (the companion run failed).
    pub unavailable: Option<String>,
    /// The largest relative error estimate over the levels (null: no estimate).
    pub worst_relative: Option<f64>,
    /// `[mesh] accuracy`, the target (null: none given).
    pub target: Option<f64>,
    /// Whether worst_relative ≤ target (null: no target or no estimate).
    pub met: Option<bool>,
    /// The mesh the target chose (null: no target).
    pub chosen_mesh: Option<MeshChoice>,
}

/// Why the mesh of a [`MeshChoice`] was chosen.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum MeshRule {
    /// `[mesh] accuracy`: the cheapest table row within the target.
    Target,
    /// No mesh knob and no target: the default mesh (`nonlin3d_mesh::DEFAULT_MESH`).
    Default,
}

/// The knobs `[mesh] accuracy` or the default mesh set (the row scaled to the model), after
/// the scene's explicit knobs overrode them.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MeshChoice {
    /// `target` (`[mesh] accuracy`) or `default` (a scene without mesh knobs).
    pub rule: MeshRule,
    /// The measured worst error of the chosen row (relative to the converged G_T max).
    pub table_error: f64,
    /// Whether a row of the table meets the target (false: the finest row, short of it).
    pub table_meets_target: bool,
    /// Slices.
    pub slices: usize,
    /// Rings inside the front.
    pub inside: usize,
    /// Rings outside the front.
    pub outside: usize,
    /// Sublaminate layers.
    pub sub_layers: usize,
    /// Base layers.
    pub base_layers: usize,
    /// Front element, mm (null: the thesis grading).
    pub front_element_mm: Option<f64>,
    /// Front band `[inside, outside]` (null: none).
    pub front_band: Option<[usize; 2]>,
    /// Layer band `[inside, outside]` (null: none).
    pub layer_band: Option<[usize; 2]>,
    /// Whether the rings' mid-edge nodes sit on the mapped curves (`[mesh] curved_edges`).
    pub curved_edges: bool,
    /// The knobs the scene gave explicitly, which override the table's.
    pub overridden: Vec<String>,
}

impl MeshChoice {
    /// The choice of `row`'s knobs as scaled to a model (`chosen`), none overridden but those
    /// named.
    pub(crate) fn of(
        chosen: &nonlin3d_mesh::EmbeddedParams,
        row: &nonlin3d_mesh::AccuracyRow,
        meets: bool,
        rule: MeshRule,
        overridden: Vec<String>,
    ) -> Self {
        Self {
            rule,
            table_error: row.worst,
            table_meets_target: meets,
            slices: chosen.slices,
            inside: chosen.radial_inside,
            outside: chosen.radial_outside,
            sub_layers: chosen.sub_layers,
            base_layers: chosen.base_layers,
            front_element_mm: chosen.front_element.map(|e| e * 1e3),
            front_band: chosen.front_band.map(|b| [b.inside, b.outside]),
            layer_band: chosen.layer_band.map(|b| [b.inside, b.outside]),
            curved_edges: chosen.mid_edges == nonlin3d_mesh::MidEdges::Mapped,
            overridden,
        }
    }
}
