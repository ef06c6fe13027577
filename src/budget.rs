//! How much memory a run may use, and how much a model will need before it is built
//! (docs/RELIABILITY.md, "Memory and model size").
//!
//! The limit is the tightest of `--max-memory`, the memory the machine has available
//! (`MemAvailable` in /proc/meminfo), the process's address-space limit (RLIMIT_AS, read from
//! /proc/self/limits) and its cgroup's limit (v2 `memory.max`, v1 `memory.limit_in_bytes`),
//! each less what is already in use ([`Limit`]). What is not there (another OS, no cgroup) is
//! skipped.
//!
//! Before meshing, [`check_scene`] estimates the model from the scene's counts alone: nodes,
//! DOFs and tangent nonzeros exactly (closed forms of the generators, `count.rs`), the factor's
//! entries from a fit to faer's and the profile solver's counts, and the bytes of the run; it
//! refuses a scene that could not fit even with the factor at a quarter of its estimate. After the
//! pattern is built, the solver's symbolic analysis gives the factor's exact size and refuses
//! before the numeric phase allocates ([`nonlin3d_solver::budget`]); [`install`] points the
//! solvers at the same limit.

mod count;
mod limits;

pub use limits::{Bound, Limit, LimitKind, Readings};

use crate::Error;
use crate::scene::{Geometry, Scene, SolverName};
use nonlin3d_element::ElementKind;
use nonlin3d_mesh::{EmbeddedParams, Mesh, ThroughWidthParams};
use nonlin3d_solver::MemoryBudget;
use nonlin3d_solver::budget::format_bytes;
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};

const MIB: u64 = 1 << 20;

/// Reads a memory size: a number with an optional unit, `B`, `K`/`M`/`G`/`T` and
/// `KiB`/`MiB`/`GiB`/`TiB` (powers of 1024), or `kB`/`MB`/`GB`/`TB` (powers of 1000), as in
/// "2GiB", "500MB", "1.5G" or "1073741824".
pub fn parse_size(text: &str) -> Result<u64, Error> {
    let bad = |reason: &str| Error::MemorySize {
        text: text.to_string(),
        reason: reason.to_string(),
    };
    let t = text.trim();
    let split = t
        .find(|c: char| !(c.is_ascii_digit() || c == '.'))
        .unwrap_or(t.len());
    let (number, unit) = (&t[..split], t[split..].trim());
    let value: f64 = number
        .parse()
        .map_err(|_| bad("expected a number and a unit, e.g. 2GiB, 500MB, 1.5G"))?;
    let scale: f64 = match unit.to_ascii_lowercase().as_str() {
        "" | "b" => 1.0,
        "k" | "kib" => 1024.0,
        "m" | "mib" => 1024.0 * 1024.0,
        "g" | "gib" => 1024.0 * 1024.0 * 1024.0,
        "t" | "tib" => 1024.0 * 1024.0 * 1024.0 * 1024.0,
        "kb" => 1e3,
        "mb" => 1e6,
        "gb" => 1e9,
        "tb" => 1e12,
        _ => return Err(bad("unknown unit (B, K, M, G, T, KiB … TiB, kB … TB)")),
    };
    let bytes = value * scale;
    if !(bytes >= 1.0 && bytes < u64::MAX as f64) {
        return Err(bad("must be at least 1 byte and below 16 EiB"));
    }
    Ok(bytes.round() as u64)
}

/// `--max-memory` of this process (0: none).
static MAX_MEMORY: AtomicU64 = AtomicU64::new(0);

/// Sets `--max-memory` for this process and makes the solvers check their factor against
/// [`limit`] at every analysis. The command-line program calls it once; a program using the
/// library calls it to get the same protection.
pub fn install(max_memory: Option<u64>) {
    MAX_MEMORY.store(max_memory.unwrap_or(0), Ordering::Relaxed);
    nonlin3d_solver::set_memory_budget(Some(Arc::new(|| {
        limit().tightest().map(|b| {
            MemoryBudget::new(
                usize::try_from(b.left()).unwrap_or(usize::MAX),
                b.to_string(),
            )
        })
    })));
}

/// The limits now, with the installed `--max-memory`.
pub fn limit() -> Limit {
    let max = MAX_MEMORY.load(Ordering::Relaxed);
    Limit::from_readings((max > 0).then_some(max), &Readings::read())
}

/// The size of a model, before it is built.
#[derive(Debug, Clone, PartialEq)]
pub struct Estimate {
    /// Nodes (exact).
    pub nodes: u64,
    /// Cells (exact).
    pub cells: u64,
    /// DOFs, 3 per node (exact).
    pub dofs: u64,
    /// Stored entries of the tangent's lower triangle (exact).
    pub tangent_nonzeros: u64,
    /// Entries of the factor (estimated; see [`estimate_scene`]).
    pub factor_entries: u64,
    /// Which factor.
    pub factor: &'static str,
    /// Bytes of the mesh alone (building it, or exporting it).
    pub mesh_bytes: u64,
    /// Bytes of the whole run at its peak, with the factor as estimated.
    pub bytes: u64,
    /// A lower bound: the factor at a quarter of its estimate and the rest at its smallest
    /// measured rate, below the measured peak of every scene, so a scene refused on it would
    /// not have fitted. (The estimate is fitted to AMD; the default ordering keeps the smaller
    /// of AMD and nested dissection, whose factors measured 0.60–0.84 of AMD's, so the factor
    /// can fall to 0.75 · 0.60 = 0.45 of the estimate: half was not a bound any more.)
    pub bytes_at_least: u64,
}

/// Peak resident bytes of a run beyond the factor, per tangent nonzero: the pattern, the
/// tangent, the assembler's maps and faer's scratch. Measured 45–50 (Hex20) and 55–57 (Hex8)
/// bytes per nonzero on 14 scenes of 0.1–8 M nonzeros (mesh and vectors included); the
/// estimate takes 56 plus the mesh and vectors, the lower bound 40 alone.
const BYTES_PER_NONZERO: u64 = 56;
const BYTES_PER_NONZERO_AT_LEAST: u64 = 40;

/// Peak resident bytes of building (or exporting) a mesh, per node plus cell (measured 340
/// on the 32 k-node scenes), and the process itself.
const MESH_BYTES_PER_ITEM: u64 = 400;
const PROCESS_BYTES: u64 = 4 * MIB;

impl Estimate {
    /// The estimate with `factor_entries` as the factor, and the lower bound with `factor_low`.
    fn new(
        c: count::Counts,
        factor: &'static str,
        factor_entries: u128,
        factor_low: u128,
        levels: usize,
    ) -> Self {
        let sat = |x: u128| u64::try_from(x).unwrap_or(u64::MAX);
        let mesh = PROCESS_BYTES as u128 + MESH_BYTES_PER_ITEM as u128 * (c.nodes + c.cells);
        // Solution vectors kept per level, and a dozen working vectors.
        let vectors = 8 * 3 * c.nodes * (levels as u128 + 12);
        let rest = mesh + vectors + BYTES_PER_NONZERO as u128 * c.tangent_nonzeros;
        let rest_low =
            PROCESS_BYTES as u128 + BYTES_PER_NONZERO_AT_LEAST as u128 * c.tangent_nonzeros;
        Self {
            nodes: sat(c.nodes),
            cells: sat(c.cells),
            dofs: sat(3 * c.nodes),
            tangent_nonzeros: sat(c.tangent_nonzeros),
            factor_entries: sat(factor_entries),
            factor,
            mesh_bytes: sat(mesh),
            bytes: sat(rest + 8 * factor_entries),
            bytes_at_least: sat(rest_low + 8 * factor_low),
        }
    }
}

/// The mesh counts of a scene as the generators will use them (defaults filled in), each with
/// its field name, and the model's counts.
fn scene_counts(scene: &Scene) -> (count::Counts, u128, f64, Vec<String>) {
    let c = &scene.mesh;
    let kind = c.element.map_or(ElementKind::Hex20, |e| e.kind());
    let hex20 = kind == ElementKind::Hex20;
    let mut fields = Vec::new();
    let mut field = |name: &str, set: Option<usize>, default: usize| {
        let v = set.unwrap_or(default);
        let tail = if set.is_some() { "" } else { " (default)" };
        fields.push(format!("mesh.{name} = {v}{tail}"));
        v
    };
    let (counts, short_side) = match &scene.geometry {
        Geometry::ThroughWidth { .. } => {
            let d = ThroughWidthParams::example();
            let inside = field("inside", c.inside, d.inside);
            let outside = field("outside", c.outside, d.outside);
            let across = field("across", c.across, d.across);
            let sub = field("sub_layers", c.sub_layers, d.sub_layers);
            let base = field("base_layers", c.base_layers, d.base_layers);
            let t = count::through_width(inside, outside, across, base + sub, base, hex20);
            (t, Some(if hex20 { 2 * across + 1 } else { across + 1 }))
        }
        _ => {
            let d = EmbeddedParams::thesis_reference();
            let slices = field("slices", c.slices, d.slices);
            let inside = field("inside", c.inside, d.radial_inside);
            let outside = field("outside", c.outside, d.radial_outside);
            let base = field("base_layers", c.base_layers, d.base_layers);
            let (layers, split) = match &scene.layup {
                Some(l) => {
                    fields.push(format!(
                        "{} sublaminate and {} base plies (layup)",
                        l.sublaminate.len(),
                        l.base_below.len()
                    ));
                    let below = base + l.base_below.len();
                    (below + l.sublaminate.len(), below)
                }
                None => {
                    let sub = field("sub_layers", c.sub_layers, d.sub_layers);
                    (base + sub, base)
                }
            };
            // A front band carries 3·slices arcs on its rings and its transitions, which the
            // closed form cannot count: counted as if every ring had them, a bound from above
            // (the default mesh: 18 444 DOF counted as 31 005, where the plain count gave 9 333
            // and a Slurm request below the run's peak). A layer band, counted as full layers
            // everywhere, is bounded from above already.
            let arcs = match c.front_band {
                Some(_) => {
                    fields.push(format!(
                        "mesh.front_band: counted as {} slices on every ring",
                        3 * slices
                    ));
                    3 * slices
                }
                None => slices,
            };
            let e = count::embedded(arcs, inside, outside, layers, split, hex20);
            (e, None)
        }
    };
    fields.push(format!(
        "mesh.element = {}{}",
        if hex20 { "hex20" } else { "hex8" },
        if c.element.is_some() {
            ""
        } else {
            " (default)"
        }
    ));
    // The section's entities (2-D vertices and mid-edges) and the width of the section in
    // entities: √entities for the embedded quarter disc, the width across for the strip.
    let entities = counts.section_entities;
    let root = (entities as f64).sqrt();
    let width = short_side.map_or(root, |s| root.min(s as f64));
    (counts, entities, width, fields)
}

/// Factor entries from the section: with t = nodes/entities the nodes through the thickness,
/// a column of the section carries 3t DOFs, and
/// - faer (AMD): F ≈ c·(3t)²·entities·2·log₂ w (nested-dissection growth), c = 3.2 (Hex20),
///   2.4 (Hex8);
/// - profile (RCM): F ≈ c·(3t)²·entities·w (a band w columns wide), c = 1.1 (Hex20), 0.85
///   (Hex8);
///
/// with w the section's width in entities. Fitted on 14 scenes of 0.2–140 M factor entries:
/// faer's count is 0.75–1.13 times the estimate above 2 M entries (0.35 on a 1-cell-wide strip
/// of 0.2 M), the envelope 0.9–1.2 times.
fn factor_estimate(
    c: &count::Counts,
    entities: u128,
    width: f64,
    hex20: bool,
    profile: bool,
) -> u128 {
    let t = c.nodes as f64 / entities.max(1) as f64;
    let columns = (3.0 * t).powi(2) * entities as f64;
    let f = match (profile, hex20) {
        (false, true) => 3.2 * columns * 2.0 * width.max(2.0).log2(),
        (false, false) => 2.4 * columns * 2.0 * width.max(2.0).log2(),
        (true, true) => 1.1 * columns * width,
        (true, false) => 0.85 * columns * width,
    };
    // Never less than the tangent's own lower triangle, which the factor contains.
    (f.min(1e36) as u128).max(c.tangent_nonzeros)
}

/// The size of `scene`'s model and run, from its counts alone (nothing is meshed), on the mesh
/// that runs (`[mesh] accuracy` and the default mesh resolved to knobs first). Nodes, cells,
/// DOFs and tangent nonzeros are exact, except with a front band (counted as its fine slices on
/// every ring) or a layer band (counted as full layers everywhere): bounds from above there;
/// the factor is estimated (`factor_estimate`).
pub fn estimate_scene(scene: &Scene) -> Estimate {
    // The mesh that runs: `[mesh] accuracy`'s or the default mesh's knobs (a scene the
    // resolution refuses is estimated as written; the run itself reports the refusal).
    let resolved = crate::analysis::estimate::resolve_mesh(scene).map(|(s, _)| s);
    let scene = resolved.as_ref().unwrap_or(scene);
    let (counts, entities, width, _) = scene_counts(scene);
    let hex20 = scene
        .mesh
        .element
        .is_none_or(|e| e.kind() == ElementKind::Hex20);
    let profile = scene.analysis.solver == SolverName::Profile;
    let factor = factor_estimate(&counts, entities, width, hex20, profile);
    let levels = scene
        .loads
        .strains
        .len()
        .max(scene.loads.transverse_n.len());
    let name = if profile {
        "profile LDLᵀ envelope"
    } else {
        "faer LDLᵀ factor"
    };
    Estimate::new(counts, name, factor, factor / 4, levels)
}

/// What was too large, the estimate, the limit, and what sets the size.
#[derive(Debug, Clone, PartialEq)]
pub struct Refusal {
    /// "the analysis", "the mesh", "the deck's solve".
    pub what: &'static str,
    /// The estimate.
    pub estimate: Estimate,
    /// The tightest limit.
    pub bound: Bound,
    /// Bytes compared with what the limit leaves.
    pub needed: u64,
    /// The fields that set the size, as the user wrote them (or the deck's counts).
    pub fields: String,
}

impl std::fmt::Display for Refusal {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let e = &self.estimate;
        let b = |x: u64| format_bytes(x.into());
        write!(
            f,
            "{} would not fit in memory: {} nodes, {} DOFs, {} tangent nonzeros and about {} \
             entries in the {} need about {} (at least {}), more than the {} left under {}; \
             the size comes from {}: lower them, or raise the limit",
            self.what,
            e.nodes,
            e.dofs,
            e.tangent_nonzeros,
            e.factor_entries,
            e.factor,
            b(e.bytes),
            b(self.needed),
            b(self.bound.left()),
            self.bound,
            self.fields
        )
    }
}

fn refuse(
    what: &'static str,
    e: Estimate,
    needed: u64,
    limit: &Limit,
    fields: String,
) -> Result<Estimate, Error> {
    match limit.tightest() {
        Some(bound) if needed > bound.left() => Err(Error::TooLarge(Box::new(Refusal {
            what,
            estimate: e,
            bound: *bound,
            needed,
            fields,
        }))),
        _ => Ok(e),
    }
}

/// Refuses `scene` before anything is meshed if its analysis could not fit under `limit` even
/// with the factor at a quarter of its estimate ([`Estimate::bytes_at_least`]); the exact check follows
/// in the solver's symbolic analysis. Call before building the model.
pub fn check_scene(scene: &Scene, limit: &Limit) -> Result<Estimate, Error> {
    let e = estimate_scene(scene);
    let (_, _, _, fields) = scene_counts(scene);
    let needed = e.bytes_at_least;
    refuse("the analysis", e, needed, limit, fields.join(", "))
}

/// How many times the estimated run must fit in what the memory limit leaves for its solver
/// analyses to wait for their first use ([`analysis_may_wait`]): the run, its companions
/// (together no larger than the run: each coarser mesh about a third of the one above) and
/// the estimate's own error (its factor 0.75–1.2 of faer's above 2 M entries).
const ROOM_TO_WAIT: u64 = 4;

/// Whether `scene`'s solver analyses may wait for their first factorisation
/// (`nonlin3d_newton::PathSolver::deferred`): the analysis is where the factor's exact size is
/// checked against the limit, so it is made first unless the estimated run fits
/// `ROOM_TO_WAIT` (4) times in what the limit leaves. (Deferred near the limit, a 33 k-node
/// scene under 1 GiB of address space went on to build its contact system while its
/// companions grew, and died in an allocation inside faer instead of being refused.)
pub fn analysis_may_wait(scene: &Scene, limit: &Limit) -> bool {
    let needed = estimate_scene(scene).bytes.saturating_mul(ROOM_TO_WAIT);
    limit.tightest().is_none_or(|b| needed <= b.left())
}

/// Refuses `scene` if building its mesh alone (what `export` does) could not fit under `limit`.
pub fn check_mesh(scene: &Scene, limit: &Limit) -> Result<Estimate, Error> {
    let e = estimate_scene(scene);
    let (_, _, _, fields) = scene_counts(scene);
    let needed = e.mesh_bytes;
    refuse("the mesh", e, needed, limit, fields.join(", "))
}

/// Refuses the solve of a deck's `mesh` if it could not fit under `limit`. The tangent's
/// nonzeros are counted exactly from the connectivity; the factor is taken as at least the
/// tangent's lower triangle (the factor contains it) and estimated at 12 times it (the
/// generated models measure 6–24 times).
pub fn check_deck(mesh: &Mesh, limit: &Limit) -> Result<Estimate, Error> {
    let counts = count::of_mesh(mesh);
    let nonzeros = counts.tangent_nonzeros;
    let e = Estimate::new(counts, "faer LDLᵀ factor", 12 * nonzeros, nonzeros, 1);
    let needed = e.bytes_at_least;
    let fields = format!("the deck's {} nodes and {} elements", e.nodes, e.cells);
    refuse("the deck's solve", e, needed, limit, fields)
}

#[cfg(test)]
mod tests;
