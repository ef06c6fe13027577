//! One input through the pipeline in-process, as the `nonlin3d` program would take it, and the
//! class of what came out.
//!
//! Scenes: read (UTF-8) → `Scene::from_toml` (parse and validate) → `analysis::build_model`
//! (mesh; every node finite) → `export::deck_of` and `mesh::read_inp` of the exported deck
//! (models up to [`DOF_LIMIT`]) → `Analysis::run` of a reduced scene (below) → every number of
//! the `Results` finite, then `report::table`, `report::front_csv` and the JSON serialisation.
//!
//! Decks: read → `mesh::read_inp` → `deck::solve_deck` with the `nonlin3d solve` defaults
//! (models up to [`DOF_LIMIT`]) → every displacement, load factor and residual finite.
//!
//! The reduced scene keeps whatever the mutation changed and shrinks what it did not, so one
//! case costs tenths of a second: an unchanged `[mesh]` gets `slices = 2`, unchanged loads become
//! one level at a quarter of the first strain (or the first transverse load), unchanged
//! `[analysis]` settings get `max_increment = 1` (one increment). Changed loads keep at most two
//! levels from the first that differs.

use crate::mutate::Format;
use nonlin3d::newton::NewtonSettings;
use nonlin3d::scene::Geometry;
use nonlin3d::{Results, Scene};
use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

/// Models above this many DOFs are built (and exported) but not solved.
pub const DOF_LIMIT: usize = 20_000;

/// What a case ended with.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Class {
    /// Every stage passed; every number finite.
    Ok,
    /// Refused with an error whose message reads as words.
    TypedError,
    /// An error message with Debug formatting in it (`Some(`, `None`, `Foo { a: `, `[1.0, `).
    DebugMessage,
    /// An error with an empty message.
    EmptyMessage,
    /// A panic, caught.
    Panic,
    /// The process died (abort, signal, memory ceiling).
    Abort,
    /// No answer within the time limit.
    Hang,
    /// A non-finite number in an output.
    NonFinite,
}

impl Class {
    /// All classes, in report order.
    pub const ALL: [Self; 8] = [
        Self::Ok,
        Self::TypedError,
        Self::DebugMessage,
        Self::EmptyMessage,
        Self::Panic,
        Self::Abort,
        Self::Hang,
        Self::NonFinite,
    ];

    /// The name used in reports and in the worker protocol.
    pub fn name(self) -> &'static str {
        match self {
            Self::Ok => "ok",
            Self::TypedError => "typed error",
            Self::DebugMessage => "debug-formatted message",
            Self::EmptyMessage => "empty message",
            Self::Panic => "panic",
            Self::Abort => "abort/signal",
            Self::Hang => "hang",
            Self::NonFinite => "non-finite output",
        }
    }

    /// The class of a name.
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|c| c.name() == name)
    }

    /// Whether the class is a failure of the program (not of the input).
    pub fn is_failure(self) -> bool {
        !matches!(self, Self::Ok | Self::TypedError)
    }
}

/// The outcome of one case.
#[derive(Debug, Clone)]
pub struct Outcome {
    /// Its class.
    pub class: Class,
    /// The last stage entered.
    pub stage: String,
    /// The error or panic message, or what was not finite.
    pub message: String,
    /// Where a panic happened (file:line:column).
    pub location: String,
    /// The nonlin3d frames of a panic's backtrace, innermost first.
    pub frames: Vec<String>,
    /// DOFs of the model built (0: none).
    pub dofs: usize,
    /// Whether the solve stage ran to the end.
    pub solved: bool,
}

const STAGES: [&str; 6] = ["read", "parse", "mesh", "export", "solve", "output"];
static STAGE: AtomicUsize = AtomicUsize::new(0);

/// Whether stages are announced on stdout (`@@fuzz stage`), for the parent to name the stage
/// of a hang or abort.
pub static ANNOUNCE: AtomicBool = AtomicBool::new(false);

fn enter(stage: &str) {
    let k = STAGES.iter().position(|s| *s == stage).unwrap_or(0);
    STAGE.store(k, Ordering::SeqCst);
    if ANNOUNCE.load(Ordering::Relaxed) {
        crate::worker::say(&format!("@@fuzz stage 0 \"{stage}\""));
    }
}

/// The stage last entered.
pub fn current_stage() -> &'static str {
    STAGES[STAGE.load(Ordering::SeqCst)]
}

/// A panic as the hook saw it.
#[derive(Debug, Clone, Default)]
pub struct PanicRecord {
    /// The payload.
    pub message: String,
    /// file:line:column.
    pub location: String,
    /// nonlin3d frames.
    pub frames: Vec<String>,
}

/// The first panic since the last [`take_panic`].
pub static PANIC: Mutex<Option<PanicRecord>> = Mutex::new(None);

/// Replaces the panic hook: panics are recorded (message, location, the nonlin3d frames of the
/// backtrace) for the case's outcome instead of printed.
pub fn record_panics() {
    std::panic::set_hook(Box::new(|info| {
        let payload = info.payload();
        let message = payload
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| payload.downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "(non-string payload)".into());
        let location = info
            .location()
            .map(|l| format!("{}:{}:{}", l.file(), l.line(), l.column()))
            .unwrap_or_default();
        let trace = std::backtrace::Backtrace::force_capture().to_string();
        let frames = nonlin3d_frames(&trace);
        if let Ok(mut slot) = PANIC.lock()
            && slot.is_none()
        {
            *slot = Some(PanicRecord {
                message,
                location,
                frames,
            });
        }
    }));
}

/// Takes the recorded panic, if any.
pub fn take_panic() -> Option<PanicRecord> {
    PANIC.lock().ok().and_then(|mut s| s.take())
}

/// `function (file:line)` for the frames of a backtrace (short or full format) whose source
/// lies in the workspace's own code (`crates/…`, `src/…`), innermost first, at most eight.
pub fn nonlin3d_frames(trace: &str) -> Vec<String> {
    let root = concat!(env!("CARGO_MANIFEST_DIR"), "/");
    let mut out = Vec::new();
    let mut function = "";
    for l in trace.lines().map(str::trim) {
        if let Some(place) = l.strip_prefix("at ") {
            let place = place
                .strip_prefix(root)
                .or(place.strip_prefix("./"))
                .unwrap_or(place);
            let place = place
                .rsplit_once(':')
                .map_or(place, |(file_line, _)| file_line);
            if (place.starts_with("crates/") || place.starts_with("src/")) && out.len() < 8 {
                out.push(format!("{function} ({place})"));
            }
        } else if let Some((n, f)) = l.split_once(": ")
            && n.trim().parse::<usize>().is_ok()
        {
            function = f.split_once(" - ").map_or(f, |(_, name)| name);
        }
    }
    out
}

/// Whether an error message shows Debug formatting: `Some(`, `None`, `Ok(`, `Err(`, a struct
/// literal `Name { field: `, or a bracketed list of floats. Lines of a TOML error that quote the
/// input (`3 | a = …`) are skipped: they show the user's text, not ours.
pub fn debug_formatted(message: &str) -> bool {
    message
        .lines()
        .filter(|l| {
            let t = l.trim_start();
            let digits = t.chars().take_while(char::is_ascii_digit).count();
            !t[digits..].trim_start().starts_with('|')
        })
        .any(|l| {
            let b = l.as_bytes();
            // `None` as a word, but not opening a sentence ("None of the plies …").
            let word = |w: &str| {
                l.match_indices(w).any(|(i, _)| {
                    let before = i.checked_sub(1).map(|j| b[j]);
                    let after = b.get(i + w.len());
                    let sentence = l[..i].trim_end();
                    let glued = before.is_some_and(|c| c.is_ascii_alphanumeric())
                        || after.is_some_and(|c| c.is_ascii_alphanumeric());
                    !(glued || sentence.is_empty() || sentence.ends_with('.'))
                })
            };
            l.contains("Some(")
                || l.contains("Ok(")
                || l.contains("Err(")
                || word("None")
                || struct_literal(l)
                || tuple_variant(l)
                || float_list(l)
        })
}

/// `Singular("…")` or `Diverged(3)`: an enum's tuple variant as `{:?}` prints it (a CamelCase
/// name directly followed by a parenthesis).
fn tuple_variant(l: &str) -> bool {
    l.match_indices('(').any(|(i, _)| {
        let name: String = l[..i]
            .chars()
            .rev()
            .take_while(char::is_ascii_alphanumeric)
            .collect();
        let mut chars = name.chars().rev();
        name.len() >= 2
            && chars.next().is_some_and(|c| c.is_ascii_uppercase())
            && chars.any(|c| c.is_ascii_lowercase())
    })
}

/// `Name { field: ` as `{:?}` prints a struct.
fn struct_literal(l: &str) -> bool {
    l.match_indices(" { ").any(|(i, _)| {
        let name_ok = l[..i]
            .rsplit(|c: char| !c.is_alphanumeric() && c != '_')
            .next()
            .is_some_and(|n| n.chars().next().is_some_and(char::is_uppercase));
        let rest = &l[i + 3..];
        let field: String = rest
            .chars()
            .take_while(|c| c.is_alphanumeric() || *c == '_')
            .collect();
        name_ok && !field.is_empty() && rest[field.len()..].starts_with(':')
    })
}

/// `[1.0, ` or `[-0.5, `: a slice or array printed with `{:?}` (Display has none for them).
fn float_list(l: &str) -> bool {
    l.match_indices('[').any(|(i, _)| {
        let rest = l[i + 1..].trim_start_matches('-');
        let int = rest.chars().take_while(char::is_ascii_digit).count();
        int > 0 && rest[int..].starts_with('.') && {
            let frac = rest[int + 1..]
                .chars()
                .take_while(char::is_ascii_digit)
                .count();
            frac > 0 && rest[int + 1 + frac..].starts_with(", ")
        }
    })
}

fn refused(stage: &str, message: String, dofs: usize) -> Outcome {
    let class = if message.trim().is_empty() {
        Class::EmptyMessage
    } else if debug_formatted(&message) {
        Class::DebugMessage
    } else {
        Class::TypedError
    };
    Outcome {
        class,
        stage: stage.into(),
        message,
        location: String::new(),
        frames: Vec::new(),
        dofs,
        solved: false,
    }
}

fn finished(class: Class, message: String, dofs: usize, solved: bool) -> Outcome {
    Outcome {
        class,
        stage: current_stage().into(),
        message,
        location: String::new(),
        frames: Vec::new(),
        dofs,
        solved,
    }
}

/// Runs one input through its pipeline (panics propagate: the caller catches them).
pub fn run_input(format: Format, bytes: &[u8], original: Option<&str>) -> Outcome {
    enter("read");
    let text = match std::str::from_utf8(bytes) {
        Ok(t) => t,
        // What `nonlin3d run` prints for such a file: the io::Error of `read_to_string`.
        Err(_) => {
            let e = std::io::Error::new(
                std::io::ErrorKind::InvalidData,
                "stream did not contain valid UTF-8",
            );
            return refused("read", e.to_string(), 0);
        }
    };
    match format {
        Format::Scene => scene(text, original),
        Format::Deck => deck(text),
    }
}

fn scene(text: &str, original: Option<&str>) -> Outcome {
    enter("parse");
    let scene = match Scene::from_toml(text) {
        Ok(s) => s,
        Err(e) => return refused("parse", e.to_string(), 0),
    };
    enter("mesh");
    let model = match nonlin3d::analysis::build_model(&scene) {
        Ok(m) => m,
        Err(e) => return refused("mesh", e.to_string(), 0),
    };
    let dofs = 3 * model.mesh.nodes.len();
    if let Some(n) = model
        .mesh
        .nodes
        .iter()
        .position(|p| p.iter().any(|x| !x.is_finite()))
    {
        let message = format!("mesh node {n} at {:?}", model.mesh.nodes[n]);
        return finished(Class::NonFinite, message, dofs, false);
    }
    // `nonlin3d export` and `nonlin3d run` are separate commands: a refused export does not
    // stop the solve, and is the outcome if the solve succeeds.
    let mut export_error = None;
    if dofs <= DOF_LIMIT {
        enter("export");
        match nonlin3d::export::deck_of(&scene, &model) {
            Ok(deck) => {
                if let Err(e) = nonlin3d::mesh::read_inp(&deck) {
                    export_error = Some(format!("reading the exported deck back: {e}"));
                }
            }
            Err(e) => export_error = Some(e.to_string()),
        }
    }
    let base = original.and_then(|o| Scene::from_toml(o).ok());
    let reduced = reduce(&scene, base.as_ref());
    let solved = if reduced.mesh == scene.mesh && dofs > DOF_LIMIT {
        false
    } else {
        enter("solve");
        let results = match nonlin3d::Analysis::new(reduced).and_then(|a| a.run()) {
            Ok(r) => r,
            Err(e) => return refused("solve", e.to_string(), dofs),
        };
        enter("output");
        if let Some(what) = non_finite_result(&results) {
            return finished(Class::NonFinite, what, dofs, true);
        }
        let table = nonlin3d::report::table(&results);
        let csv: usize = (0..results.levels.len())
            .map(|k| nonlin3d::report::front_csv(&results, k).len())
            .sum();
        let json = serde_json::to_string(&results);
        if table.is_empty() || csv == 0 || json.is_err() {
            let message = "results could not be written".into();
            return finished(Class::NonFinite, message, dofs, true);
        }
        true
    };
    match export_error {
        Some(message) => refused("export", message, dofs),
        None => finished(Class::Ok, String::new(), dofs, solved),
    }
}

/// The scene actually solved: see the module documentation.
pub fn reduce(scene: &Scene, base: Option<&Scene>) -> Scene {
    let mut s = scene.clone();
    let Some(base) = base else { return s };
    let through = matches!(s.geometry, Geometry::ThroughWidth { .. });
    if s.mesh == base.mesh && !through {
        s.mesh.slices = Some(2);
    }
    let plate = matches!(s.geometry, Geometry::Plate { .. });
    let same_loads = s.loads == base.loads;
    let (mine, theirs) = if plate {
        (&mut s.loads.transverse_n, &base.loads.transverse_n)
    } else {
        (&mut s.loads.strains, &base.loads.strains)
    };
    if same_loads {
        let first = mine.first().copied().unwrap_or(0.0);
        *mine = vec![if plate { first } else { 0.25 * first }];
    } else {
        let from = (0..mine.len())
            .find(|&k| theirs.get(k) != Some(&mine[k]))
            .unwrap_or(0);
        *mine = mine.iter().skip(from).take(2).copied().collect();
        if mine.is_empty() {
            mine.extend(theirs.first());
        }
    }
    if s.analysis == base.analysis {
        s.analysis.max_increment = 1.0;
    }
    s
}

/// The first non-finite number of a run's results, named.
fn non_finite_result(r: &Results) -> Option<String> {
    let bad = |name: String, v: f64| (!v.is_finite()).then(|| format!("{name} = {v}"));
    for (k, l) in r.levels.iter().enumerate() {
        let c = &l.convergence;
        let scalars = [
            ("value", l.value),
            ("centre_deflection_mm", l.centre_deflection_mm),
            ("max_face_separation_mm", l.max_face_separation_mm),
            ("convergence.residual_n", c.residual_n),
        ];
        for (name, v) in scalars {
            if let Some(m) = bad(format!("levels[{k}].{name}"), v) {
                return Some(m);
            }
        }
        for (j, row) in l.front.iter().enumerate() {
            let fields = [
                ("s_mm", row.s_mm),
                ("theta_deg", row.theta_deg),
                ("x_mm", row.x_mm),
                ("y_mm", row.y_mm),
                ("delta_a_mm", row.delta_a_mm),
                ("g_i", row.g_i),
                ("g_ii", row.g_ii),
                ("g_iii", row.g_iii),
                ("g_t", row.g_t),
                ("opening_mm", row.opening_mm),
                ("area_mm2", row.area_mm2),
                ("failure_index", row.failure_index.unwrap_or(0.0)),
            ];
            for (name, v) in fields {
                if let Some(m) = bad(format!("levels[{k}].front[{j}].{name}"), v) {
                    return Some(m);
                }
            }
        }
        if let Some(d) = l.displacements.iter().position(|v| !v.is_finite()) {
            return Some(format!(
                "levels[{k}].displacements[{d}] = {}",
                l.displacements[d]
            ));
        }
    }
    let optional = [
        ("critical.strain", r.critical.map(|c| c.strain)),
        ("critical.s_mm", r.critical.map(|c| c.s_mm)),
        ("model.perturbation_n", r.model.perturbation_n),
        ("model.perturbed_at", r.model.perturbed_at),
    ];
    optional
        .into_iter()
        .find_map(|(name, v)| bad(name.into(), v.unwrap_or(0.0)))
}

fn deck(text: &str) -> Outcome {
    enter("parse");
    let model = match nonlin3d::mesh::read_inp(text) {
        Ok(m) => m,
        Err(e) => return refused("parse", e.to_string(), 0),
    };
    let dofs = 3 * model.mesh.nodes.len();
    if let Some(n) = model
        .mesh
        .nodes
        .iter()
        .position(|p| p.iter().any(|x| !x.is_finite()))
    {
        let message = format!("node {} at {:?}", model.node_ids[n], model.mesh.nodes[n]);
        return finished(Class::NonFinite, message, dofs, false);
    }
    if dofs > DOF_LIMIT {
        return finished(Class::Ok, String::new(), dofs, false);
    }
    enter("solve");
    // The defaults of `nonlin3d solve`: 1e-4 N, the deck's own *STATIC increments.
    let options = nonlin3d::deck::StepOptions {
        newton: NewtonSettings {
            force_tolerance: 1e-4,
            ..NewtonSettings::default()
        },
        initial_increment: None,
        ..Default::default()
    };
    let steps = match nonlin3d::deck::solve_deck(&model, &options) {
        Ok(s) => s,
        Err(e) => return refused("solve", e.to_string(), dofs),
    };
    enter("output");
    for s in &steps {
        for (k, d) in s.displacements.iter().enumerate() {
            if d.iter().any(|x| !x.is_finite()) {
                let id = model.node_ids.get(k).copied().unwrap_or(k);
                let message = format!("step {}: displacement of node {id} = {d:?}", s.step);
                return finished(Class::NonFinite, message, dofs, true);
            }
        }
        for (k, inc) in s.increments.iter().enumerate() {
            if !inc.step_time.is_finite() || inc.residuals.iter().any(|r| !r.is_finite()) {
                let message = format!(
                    "step {}: increment {k} (summary.json): step time {}, residuals {:?}",
                    s.step, inc.step_time, inc.residuals
                );
                return finished(Class::NonFinite, message, dofs, true);
            }
        }
    }
    finished(Class::Ok, String::new(), dofs, true)
}

#[cfg(test)]
mod tests {
    use super::debug_formatted;

    #[test]
    fn debug_formatting_is_told_from_words() {
        assert!(debug_formatted("cell 3 (face Some(2)) does not exist"));
        assert!(debug_formatted(
            "det J = -1e0 ≤ 0 at reference point [-1.0, 1.0, 0.5]"
        ));
        assert!(debug_formatted("bad Orthotropic { e11: 1.0 }"));
        assert!(debug_formatted("increment None"));
        assert!(debug_formatted("(last attempt: Singular(\"zero pivot\"))"));
        assert!(!debug_formatted(
            "None of the plies fit; {x} and [1, 2] are fine"
        ));
        assert!(!debug_formatted(
            "quadrature point 3 (ξ, η, ζ) = (-0.7, 0.7, 0) of C3D20 (hex)"
        ));
        assert!(!debug_formatted(
            "TOML parse error at line 3\n3 | a = Some(1)\n  | ^"
        ));
    }
}
