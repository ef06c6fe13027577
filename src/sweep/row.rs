//! One row of a study's table: a case's parameters, status and results (written by
//! [`super::merge`], drawn by the study plot).

use serde::Serialize;
use serde_json::Value;
use std::collections::BTreeMap;

/// One case of the study table. G in J/m², S in mm, strains as applied (compression
/// negative); the G values at the case's last (largest) level.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Row {
    /// Case id.
    pub case: usize,
    /// `complete`, `failed`, `incomplete` or `missing`.
    pub status: String,
    /// The swept fields' values.
    pub parameters: BTreeMap<String, Value>,
    /// The last level's applied strain (or load, N, for a plate).
    pub strain: Option<f64>,
    /// Largest G_T over the front points whose faces are not overlapped, at the last level.
    pub g_t_max: Option<f64>,
    /// Its S, mm.
    pub g_t_max_s_mm: Option<f64>,
    /// G_I at S = 0 (the front's point on the y axis), last level.
    pub g_i_s0: Option<f64>,
    /// G_II at S = 0, last level.
    pub g_ii_s0: Option<f64>,
    /// The crack faces behind S = 0: `open`, `overlapped` (G there not physical) or `closed`.
    pub faces_s0: Option<String>,
    /// The buckling strain lies between this (last value on the stable trivial path) …
    pub buckling_from: Option<f64>,
    /// … and this (first value found unstable): the inertia guard's bracket, or the levels
    /// around the one that took the perturbation.
    pub buckling_to: Option<f64>,
    /// Critical strain of the scene's growth criterion (results.json `critical.strain`).
    pub critical_strain: Option<f64>,
    /// Where, S in mm.
    pub critical_s_mm: Option<f64>,
    /// Wall time of the case's run, s (results.json `provenance.wall_s.total`); written to
    /// `study-wall.csv` only, so that study.csv and study.json do not depend on the run.
    #[serde(skip)]
    pub wall_s: Option<f64>,
    /// Why a failed case stopped.
    pub error: Option<String>,
}
