//! What an analysis returns; serialised as `results.json` (schema in docs/SCENES.md).

use crate::model::Model;
use nonlin3d_newton::{IncrementReport, Termination};
use nonlin3d_vcct::FrontRelease;
use serde::Serialize;

mod accuracy;
mod factor;
mod mixed;
mod overlap;

pub use accuracy::{AccuracyReport, GError, LevelError, MeshChoice, MeshRule};
pub use factor::FactorSummary;
pub use mixed::MixedSummary;

/// The state of the crack faces one element behind a front point.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Faces {
    /// Apart (opening ≥ 0): G is the closure energy of a physical state.
    Open,
    /// Passing through each other (opening < 0): contact would act there, which this analysis
    /// does not model (thesis §2.7), so G at the point is not physical.
    Overlapped,
    /// Held in contact (the pair behind the point is closed, `[contact]`, §2.7): G_I = 0,
    /// G_II and G_III from the contact-consistent nodal forces.
    Closed,
}

impl Faces {
    /// `open` or `overlapped`, as written in results.json and the front CSVs.
    pub fn as_str(self) -> &'static str {
        match self {
            Self::Open => "open",
            Self::Overlapped => "overlapped",
            Self::Closed => "closed",
        }
    }
}

/// One front corner node in a results table (lengths in mm, G in J/m²).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct FrontRow {
    /// Perimeter coordinate S, mm.
    pub s_mm: f64,
    /// θ, degrees.
    pub theta_deg: f64,
    /// x, mm.
    pub x_mm: f64,
    /// y, mm.
    pub y_mm: f64,
    /// Δa, mm.
    pub delta_a_mm: f64,
    /// G_I, J/m². Physical only where `faces` is [`Faces::Open`]; at an overlapped point it is
    /// the closure product of a state whose faces penetrate, of either sign and no meaning.
    pub g_i: f64,
    /// G_II, J/m² (physical only where `faces` is [`Faces::Open`]).
    pub g_ii: f64,
    /// G_III, J/m² (physical only where `faces` is [`Faces::Open`]).
    pub g_iii: f64,
    /// G_T, J/m² (physical only where `faces` is [`Faces::Open`]).
    pub g_t: f64,
    /// Whether the crack faces one element behind this point are apart (`open`) or pass
    /// through each other (`overlapped`: the thesis's dashed stretches, §5.1). Without contact
    /// (§2.7) an overlapped point's G values are not physical.
    pub faces: Faces,
    /// Opening w(upper) − w(lower) one element behind the front, mm (negative: overlap).
    pub opening_mm: f64,
    /// Closure area, mm².
    pub area_mm2: f64,
    /// Front node (0-based mesh index).
    pub node: usize,
    /// Failure index of the scene's mixed-mode criterion (≥ 1: growth), if one was given and
    /// the faces here are open.
    pub failure_index: Option<f64>,
    /// The estimated discretisation error of G here, J/m² (`[mesh] error_estimate`,
    /// docs/ACCURACY.md §3): absent when no estimate was made.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub error: Option<GError>,
}

impl FrontRow {
    /// From a VCCT result.
    pub fn new(r: &FrontRelease) -> Self {
        Self {
            s_mm: r.s * 1e3,
            theta_deg: r.theta_deg,
            x_mm: r.x * 1e3,
            y_mm: r.y * 1e3,
            delta_a_mm: r.delta_a * 1e3,
            g_i: r.g_i,
            g_ii: r.g_ii,
            g_iii: r.g_iii,
            g_t: r.g_t,
            faces: if r.open() {
                Faces::Open
            } else {
                Faces::Overlapped
            },
            opening_mm: r.opening * 1e3,
            area_mm2: r.area * 1e6,
            node: r.node,
            failure_index: None,
            error: None,
        }
    }

    /// Whether this point's G values are physical: the faces behind it are apart, or held in
    /// contact (not overlapped).
    pub fn is_open(&self) -> bool {
        self.faces != Faces::Overlapped
    }

    /// Back to SI (for criteria).
    pub fn release(&self) -> FrontRelease {
        FrontRelease {
            node: self.node,
            s: self.s_mm * 1e-3,
            theta_deg: self.theta_deg,
            x: self.x_mm * 1e-3,
            y: self.y_mm * 1e-3,
            delta_a: self.delta_a_mm * 1e-3,
            area: self.area_mm2 * 1e-6,
            g_i: self.g_i,
            g_ii: self.g_ii,
            g_iii: self.g_iii,
            g_t: self.g_t,
            opening: self.opening_mm * 1e-3,
        }
    }
}

/// Convergence of one level.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Convergence {
    /// Attempts (converged or cut back), including the perturbation removal.
    pub attempts: usize,
    /// Converged increments.
    pub increments: usize,
    /// Newton iterations over all attempts.
    pub iterations: usize,
    /// Final residual ‖r‖∞, N.
    pub residual_n: f64,
    /// Negative pivots of the tangent at the level's converged state (0: stable equilibrium;
    /// more: the state is unstable — e.g. the unbuckled path past a bifurcation — and is not
    /// what a real structure would show). None: not computed.
    pub negative_pivots: Option<usize>,
    /// `negative_pivots == 0`: the converged state is a stable equilibrium. None: unknown.
    pub stable: Option<bool>,
    /// The level was redone with full Newton after BFGS landed on the branch buckled into
    /// the base (`newton = "bfgs"` only).
    pub full_newton_fallback: bool,
    /// A bifurcation (or limit point) crossed in this level: the tangent gained negative
    /// pivots between two applied values, kept after the step had been cut down to bracket it
    /// (the inertia guard). None: none crossed.
    pub bifurcation: Option<Crossing>,
    /// Converged increments refused by the inertia guard (a stable state gaining negative
    /// pivots over a large step) and redone with smaller steps.
    pub refused_increments: usize,
    /// The §3.2 perturbation was applied and removed at this level on this mesh.
    pub perturbed: bool,
    /// The level started from the error estimate's companion mesh's converged state at the
    /// same level (nested iteration, `[analysis] start = "companion"`): its iterations are
    /// this mesh's from that start, and its `bifurcation` is the one the companion crossed.
    pub seeded: bool,
    /// The level was followed on this mesh from its previous state with the companion's
    /// contact set at the same level installed first (nested iteration past the seeded levels,
    /// src/analysis_seed.rs `Seeds::followed_set`).
    pub companion_set: bool,
}

/// Where the path crossed a bifurcation: between `from` and `to` (strain, or load N) the
/// count of negative pivots of the tangent went from `negative_pivots_before` to
/// `negative_pivots_after`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Crossing {
    /// Last value with the lower count.
    pub from: f64,
    /// First value with the higher count.
    pub to: f64,
    /// Negative pivots before.
    pub negative_pivots_before: usize,
    /// Negative pivots after.
    pub negative_pivots_after: usize,
}

/// One strain (or load) level.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LevelResult {
    /// Applied strain ε_x (or, for the plate, the load P in N).
    pub value: f64,
    /// Transverse displacement w of the sublaminate's top surface at the centre of the
    /// delamination (x = y = 0), mm: the base's deflection included.
    pub centre_deflection_mm: f64,
    /// Largest crack-face separation w(upper face) − w(lower face) over the delamination, mm
    /// (the sublaminate's deflection off the base, Fig. 5.1.1); negative when the largest is an
    /// overlap.
    pub max_face_separation_mm: f64,
    /// Convergence data.
    pub convergence: Convergence,
    /// The front table.
    pub front: Vec<FrontRow>,
    /// What crack-face contact did at this level (absent when it did not act).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub contact: Option<ContactSummary>,
    /// The discretisation-error estimate over the front (absent when none was made).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub error_estimate: Option<LevelError>,
    /// Nodal displacements (node-major, m): for VTU output, not serialised.
    #[serde(skip)]
    pub displacements: Vec<f64>,
}

impl LevelResult {
    /// Assembles a level's record.
    pub fn new(
        value: f64,
        centre: f64,
        peak: f64,
        attempts: &[IncrementReport],
        front: &[FrontRelease],
        displacements: Vec<f64>,
    ) -> Self {
        let converged: Vec<&IncrementReport> = attempts.iter().filter(|a| a.converged()).collect();
        let last = attempts.last();
        Self {
            value,
            centre_deflection_mm: centre * 1e3,
            max_face_separation_mm: peak * 1e3,
            convergence: Convergence {
                attempts: attempts.len(),
                increments: converged.len(),
                iterations: attempts.iter().map(|a| a.iterations.len()).sum(),
                residual_n: last
                    .and_then(|a| a.iterations.last().map(|i| i.residual))
                    .or(last.map(|a| a.initial_residual))
                    .unwrap_or(0.0),
                negative_pivots: converged.last().and_then(|a| a.negative_pivots()),
                stable: None,
                full_newton_fallback: false,
                bifurcation: None,
                refused_increments: attempts
                    .iter()
                    .filter(|a| matches!(a.termination, Termination::InertiaChanged { .. }))
                    .count(),
                perturbed: false,
                seeded: false,
                companion_set: false,
            },
            front: front.iter().map(FrontRow::new).collect(),
            contact: None,
            error_estimate: None,
            displacements,
        }
    }

    /// The front row with the largest value of `g` among the points whose faces are open (the
    /// physical ones); `None` if there is none.
    pub fn peak(&self, g: impl Fn(&FrontRow) -> f64) -> Option<&FrontRow> {
        self.front
            .iter()
            .filter(|r| r.is_open())
            .max_by(|a, b| g(a).total_cmp(&g(b)))
    }

    /// Marks the front points that contact holds closed (the states of
    /// [`nonlin3d_vcct::respect_contact`], one per row in order).
    pub fn set_face_states(&mut self, states: &[nonlin3d_vcct::FaceState]) {
        for (row, s) in self.front.iter_mut().zip(states) {
            if *s == nonlin3d_vcct::FaceState::Closed {
                row.faces = Faces::Closed;
            }
        }
    }

    /// Records the negative pivots of the tangent at the converged state and whether it is
    /// stable (none: a stable equilibrium, Sylvester's law of inertia).
    pub fn set_negative_pivots(&mut self, pivots: Option<usize>) {
        self.convergence.negative_pivots = pivots;
        self.convergence.stable = pivots.map(|p| p == 0);
    }

    /// Front points whose crack faces overlap (G there not physical without contact).
    pub fn overlapped(&self) -> usize {
        self.front.iter().filter(|r| !r.is_open()).count()
    }
}

/// Model size.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ModelSummary {
    /// Nodes.
    pub nodes: usize,
    /// Cells.
    pub cells: usize,
    /// DOFs.
    pub dofs: usize,
    /// Front corner nodes.
    pub front_points: usize,
    /// Perturbation force available on the quarter model, N.
    pub perturbation_n: Option<f64>,
    /// The level (strain) at which the perturbation was applied: the first whose trivial state
    /// had negative pivots. None: the path never lost stability.
    pub perturbed_at: Option<f64>,
    /// The superelement(s) and the nonlinear problem's size, with `[substructure]`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub substructure: Option<crate::substructure::SubstructureSummary>,
}

/// Wall-clock seconds per stage.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Timings {
    /// Mesh generation.
    pub mesh_s: f64,
    /// Assembler (pattern, colouring, materials) and constraints.
    pub setup_s: f64,
    /// Newton over all levels.
    pub solve_s: f64,
    /// VCCT over all levels.
    pub vcct_s: f64,
    /// Writing outputs (filled in by the writer).
    pub output_s: f64,
    /// Threads of the factorisation (`analysis.threads`, 0 resolved to the rayon pool's,
    /// which assembly uses); the results do not depend on it.
    pub threads: usize,
    /// What mixed precision did (`solver = "faer-mixed"`, or `auto` with full Newton); absent
    /// with an f64 solver.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mixed_precision: Option<MixedSummary>,
    /// The main mesh's systems as their last analyses found them (the level loop's, then the
    /// contact loop's if contact engaged): equations, ordering, factor size and flops.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub factor: Vec<FactorSummary>,
}

/// Onset of growth by the scene's criterion.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Critical {
    /// Critical applied strain, interpolated between the levels around the onset — or, when
    /// `after` is set, the first level whose failure index is ≥ 1.
    pub strain: f64,
    /// Set when the level before released nothing (still below the bifurcation): the onset
    /// then lies between `after` and `strain` and is not interpolated (it would fall below the
    /// bifurcation); add levels between them to locate it.
    pub after: Option<f64>,
    /// Where: S, mm.
    pub s_mm: f64,
    /// The first level whose largest failure index is ≥ 1 (0-based, as `front_K.csv`'s K).
    pub level: usize,
    /// The failure index there (≥ 1).
    pub index: f64,
    /// Mode mix (G_II + G_III)/G_T of that point at that level (0: pure mode I, 1: pure
    /// shear), the front VTU's `mode_mix`.
    pub mode_mix: f64,
    /// G_I, G_II, G_III of that point at that level, J/m².
    pub g_i: f64,
    /// G_II, J/m².
    pub g_ii: f64,
    /// G_III, J/m².
    pub g_iii: f64,
}

impl Results {
    /// Warnings that follow from the levels: every level whose crack faces pass through each
    /// other (overlapped front points, §2.7), every level whose converged state is unstable
    /// (negative pivots), and a stronger one when the last level is.
    pub fn stability_warnings(&self) -> Vec<String> {
        let what = if self.quantity == "strain" {
            "strain"
        } else {
            "load (N)"
        };
        let mut out = overlap::overlap_warnings(&self.levels, what);
        let unstable: Vec<&LevelResult> = self
            .levels
            .iter()
            .filter(|l| l.convergence.stable == Some(false))
            .collect();
        for l in &unstable {
            out.push(format!(
                "level at {what} {}: the converged state is unstable ({} negative pivots of the \
                 tangent): a real structure would not stay in it; its deflection and G describe \
                 an equilibrium it would leave",
                l.value,
                l.convergence.negative_pivots.unwrap_or(0)
            ));
        }
        if let Some(last) = self.levels.last()
            && last.convergence.stable == Some(false)
        {
            out.push(match (self.model.perturbation_n, self.model.perturbed_at) {
                (Some(p), Some(at)) => format!(
                    "the run ends on an unstable state (at {what} {}): the perturbation \
                     ({p:.3e} N, applied at {what} {at}) did not carry the sublaminate onto the \
                     buckled branch; add a level just past the bifurcation, give a larger \
                     loads.perturbation_n, or an initial imperfection (loads.imperfection_mm)",
                    last.value
                ),
                _ => format!(
                    "the run ends on an unstable state (at {what} {}); with loads.perturbation_n \
                     = 0 the unbuckled path is followed past its bifurcation — give a \
                     perturbation load (or leave it unset for the automatic one) to follow the \
                     buckled branch",
                    last.value
                ),
            });
        }
        out
    }
}

/// The levels of a coarser companion mesh and its DOFs, or why it has none.
#[derive(Debug, Clone)]
pub(crate) struct CoarserRun {
    /// Its DOFs (0 when it failed before its model was made).
    pub(crate) dofs: usize,
    /// Its levels, as many as the run's when it finished.
    pub(crate) levels: Vec<LevelResult>,
    /// Why it stopped, when it failed (its error as the terminal would show it).
    pub(crate) failure: Option<String>,
}

/// Everything a run produces.
#[derive(Debug, Clone, Serialize)]
pub struct Results {
    /// The scene's title.
    pub title: String,
    /// What `value` of each level is: `strain` or `load_n`.
    pub quantity: String,
    /// Every requested level converged and every output was written. `false` in files written
    /// while the run goes, and in those a failed or interrupted run leaves.
    pub complete: bool,
    /// Why the run stopped early (`error: …`, `interrupted by SIGINT`); null when complete.
    pub stopped: Option<String>,
    /// Model size.
    pub model: ModelSummary,
    /// Per level.
    pub levels: Vec<LevelResult>,
    /// What the reader must know before trusting the numbers (unstable levels, …); also
    /// printed under the terminal table.
    pub warnings: Vec<String>,
    /// Critical strain by the scene's criterion, if one was given and reached.
    pub critical: Option<Critical>,
    /// The error estimate and the mesh `[mesh] accuracy` chose (absent: neither asked for).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub accuracy: Option<AccuracyReport>,
    /// Stage timings.
    pub timings: Timings,
    /// The model (mesh and front), for VTU output; not serialised.
    #[serde(skip)]
    pub model_data: Option<Model>,
    /// A companion's own coarser companion, where one ran (src/analysis_seed.rs, "Nested
    /// companions"): its levels enter the run's error estimate (docs/ACCURACY.md §3d); not
    /// serialised.
    #[serde(skip)]
    pub(crate) coarser: Option<CoarserRun>,
    /// Where the results came from (set by the writer of the output folder).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub provenance: Option<Provenance>,
}

/// Where a result came from: results.json's and summary.json's `provenance`
/// ([`crate::provenance`] fills it in).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Provenance {
    /// `nonlin3d VERSION`.
    pub program: String,
    /// The command line as given.
    pub command: Vec<String>,
    /// The working folder the command ran in.
    pub working_dir: String,
    /// The input file (scene or deck) with its SHA-256; None for the built-in reference scene.
    pub input: Option<InputFile>,
    /// The scene as solved, every default filled in (None for a deck).
    pub scene: Option<serde_json::Value>,
    /// The linear solver.
    pub solver: String,
    /// Its fill-reducing ordering.
    pub ordering: String,
    /// Threads of the parallel assembly (rayon's pool).
    pub threads: usize,
    /// Start, seconds since 1970-01-01 UTC.
    pub started_unix_s: u64,
    /// Wall-clock seconds per stage (`total` from the start of the command to the last write).
    pub wall_s: std::collections::BTreeMap<String, f64>,
    /// Peak resident memory of the process so far (Linux `VmHWM`), bytes; None elsewhere.
    pub peak_memory_bytes: Option<u64>,
}

/// An input file as read.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct InputFile {
    /// The path as given on the command line.
    pub path: String,
    /// SHA-256 of its bytes, hex (`sha256sum FILE` prints the same).
    pub sha256: String,
    /// Its size, bytes.
    pub bytes: u64,
}

/// What contact did at one level (results.json `contact`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ContactSummary {
    /// Active-set passes (re-solves after the first solve), refreshes of the normals included.
    pub passes: usize,
    /// Pairs closed at the converged state.
    pub pairs_closed: usize,
    /// Largest compressive nodal contact force over the pairs, N.
    pub max_force_n: f64,
    /// Largest recovered contact pressure over the pairs, MPa (compressive positive; the
    /// release test's quantity, exact for a uniform pressure on linear and quadratic faces).
    pub max_pressure_mpa: f64,
    /// Largest overlap −g of any pair after the loop, along the contact normal, mm (0: none);
    /// at most the contact tolerance.
    pub max_penetration_mm: f64,
    /// Newton iterations of the level's contact loop: the first solve (path following with the
    /// previous level's set) and every pass; on the level where `auto` engages, the passes only
    /// (the first solve is the one without contact, in `convergence.iterations`).
    pub iterations: usize,
    /// Wall time of the first solve, s (where `auto` engages: of the solve without contact).
    pub first_s: f64,
    /// Each pass in order.
    pub pass_log: Vec<ContactPass>,
}

/// One pass of the active-set loop (results.json `contact.pass_log`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ContactPass {
    /// Pairs the pass closed.
    pub closed: usize,
    /// Pairs the pass opened.
    pub opened: usize,
    /// Same set held again with the current normals (the held gaps overlapped along them).
    pub refresh: bool,
    /// The set was changed at a Newton iterate near equilibrium, not at a converged state
    /// (`[contact] inexact_passes`).
    pub inexact: bool,
    /// Newton iterations of the re-solve.
    pub iterations: usize,
    /// Wall time, s.
    pub seconds: f64,
}
