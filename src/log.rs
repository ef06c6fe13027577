//! What Newton does, iteration by iteration, as data: a `tracing` layer ([`NewtonLayer`]) that
//! turns the events of [`nonlin3d_newton`] (target [`nonlin3d_newton::TRACE_TARGET`]) into
//! [`NewtonEvent`]s, a [`Tracker`] that numbers them by level (or step), increment and attempt,
//! and the files they go to in an output folder ([`StatusFiles`]): `status.sta`, one line per
//! attempt, and `convergence.cvg`, one line per iteration — CalculiX's `.sta` and `.cvg` in
//! spirit, as CSV. Nothing here prints: the command line draws its progress bar and its `-v`
//! lines from the same records.
//!
//! Both files are appended a line at a time, each line written whole and flushed, so a run
//! killed at any instant leaves files whose every complete line is a record.

use crate::Error;
use nonlin3d_newton::TRACE_TARGET;
use std::fs::File;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};
use std::time::Instant;
use tracing::field::{Field, Visit};

/// One event of Newton's, read off its `tracing` fields.
#[derive(Debug, Clone, PartialEq)]
pub enum NewtonEvent {
    /// An iteration ended.
    Iteration {
        /// Load factor λ of the attempt.
        lambda: f64,
        /// 1-based iteration within the attempt.
        iteration: usize,
        /// ‖r‖∞ after the iteration, N.
        residual: f64,
        /// ‖αΔu‖∞ of the accepted step (m in a scene's model, the deck's length unit in a deck).
        correction: f64,
        /// Negative pivots of the factorisation made for this iteration (None: an older one
        /// served).
        negative_pivots: Option<usize>,
    },
    /// An attempt ended (converged or to be cut back).
    Attempt {
        /// Load factor λ.
        lambda: f64,
        /// Iterations it took.
        iterations: usize,
        /// Whether it converged.
        converged: bool,
        /// How it ended, in words.
        termination: String,
    },
    /// Path following refused the converged attempt just reported (the inertia guard) and
    /// cuts back.
    Refused {
        /// Load factor λ.
        lambda: f64,
        /// Why, in words.
        termination: String,
    },
}

/// The fields of one event.
#[derive(Default)]
struct Fields {
    event: String,
    termination: String,
    numbers: Vec<(&'static str, f64)>,
    converged: bool,
}

impl Fields {
    fn number(&self, name: &str) -> f64 {
        self.numbers
            .iter()
            .find(|(n, _)| *n == name)
            .map_or(f64::NAN, |(_, v)| *v)
    }

    fn count(&self, name: &str) -> usize {
        let v = self.number(name);
        if v.is_finite() && v >= 0.0 {
            v as usize
        } else {
            0
        }
    }

    fn event(self) -> Option<NewtonEvent> {
        let lambda = self.number("lambda");
        match self.event.as_str() {
            "iteration" => Some(NewtonEvent::Iteration {
                lambda,
                iteration: self.count("iteration"),
                residual: self.number("residual"),
                correction: self.number("correction"),
                negative_pivots: (self.number("negative_pivots") >= 0.0)
                    .then(|| self.count("negative_pivots")),
            }),
            "attempt" => Some(NewtonEvent::Attempt {
                lambda,
                iterations: self.count("iterations"),
                converged: self.converged,
                termination: self.termination,
            }),
            "refused" => Some(NewtonEvent::Refused {
                lambda,
                termination: self.termination,
            }),
            _ => None,
        }
    }
}

impl Visit for Fields {
    fn record_f64(&mut self, field: &Field, value: f64) {
        self.numbers.push((field.name(), value));
    }
    fn record_i64(&mut self, field: &Field, value: i64) {
        self.numbers.push((field.name(), value as f64));
    }
    fn record_u64(&mut self, field: &Field, value: u64) {
        self.numbers.push((field.name(), value as f64));
    }
    fn record_bool(&mut self, field: &Field, value: bool) {
        if field.name() == "converged" {
            self.converged = value;
        }
    }
    fn record_str(&mut self, field: &Field, value: &str) {
        match field.name() {
            "event" => self.event = value.into(),
            "termination" => self.termination = value.into(),
            _ => {}
        }
    }
    fn record_debug(&mut self, field: &Field, value: &dyn std::fmt::Debug) {
        // `termination = %…` arrives here, formatted with Display.
        self.record_str(field, &format!("{value:?}"));
    }
}

/// What receives the companions' events ([`NewtonLayer::with_companion`]): the companion's
/// depth (1: the run's companion, [`COMPANION_SPAN`]; 2: the companion's own,
/// [`COARSER_COMPANION_SPAN`]) and the event.
type CompanionSink = Box<dyn Fn(usize, NewtonEvent) + Send + Sync>;

/// A `tracing` layer that hands every event of Newton's to `sink` as a [`NewtonEvent`]; those
/// of the error estimate's companion run ([`COMPANION_SPAN`]) go to the companion's sink, if
/// one is given, and nowhere else.
pub struct NewtonLayer<F> {
    sink: F,
    companion: Option<CompanionSink>,
}

impl<F: Fn(NewtonEvent) + Send + Sync + 'static> NewtonLayer<F> {
    /// A layer calling `sink` once per Newton event of the run, on the thread that solves.
    pub fn new(sink: F) -> Self {
        Self {
            sink,
            companion: None,
        }
    }

    /// The companion runs' events to `sink`, with the companion's depth (1: the run's
    /// companion; 2: the companion's own, src/analysis_seed.rs "nested companions"): the
    /// progress bar shows them; the status files do not hold them.
    pub fn with_companion(
        mut self,
        sink: impl Fn(usize, NewtonEvent) + Send + Sync + 'static,
    ) -> Self {
        self.companion = Some(Box::new(sink));
        self
    }
}

/// The span a run of the error estimate's companion mesh goes in (src/analysis_estimate.rs):
/// its Newton events are its own, not the run's, and [`NewtonLayer`] keeps them apart (they
/// were numbered as the run's levels in `status.sta`, `convergence.cvg` and the `-v` lines).
pub const COMPANION_SPAN: &str = "companion";

/// The span a companion's own companion runs in (nested companions, src/analysis_seed.rs):
/// on another thread than the companion's, so it is told by its name, not by nesting.
pub const COARSER_COMPANION_SPAN: &str = "coarser companion";

impl<S, F> tracing_subscriber::Layer<S> for NewtonLayer<F>
where
    S: tracing::Subscriber + for<'a> tracing_subscriber::registry::LookupSpan<'a>,
    F: Fn(NewtonEvent) + Send + Sync + 'static,
{
    fn on_event(&self, event: &tracing::Event<'_>, ctx: tracing_subscriber::layer::Context<'_, S>) {
        if event.metadata().target() != TRACE_TARGET {
            return;
        }
        let depth = ctx.event_scope(event).map_or(0, |scope| {
            scope
                .map(|span| match span.name() {
                    COMPANION_SPAN => 1,
                    COARSER_COMPANION_SPAN => 2,
                    _ => 0,
                })
                .max()
                .unwrap_or(0)
        });
        let mut fields = Fields::default();
        event.record(&mut fields);
        match (fields.event(), depth) {
            (Some(e), 0) => (self.sink)(e),
            (Some(e), depth) => {
                if let Some(sink) = &self.companion {
                    sink(depth, e);
                }
            }
            (None, _) => {}
        }
    }
}

/// An attempt or an iteration, numbered: `unit` is the level of a run (or the step of a deck),
/// 1-based; `increment` counts the converged increments of the unit (the one in progress
/// included), `attempt` every attempt of the unit.
#[derive(Debug, Clone, PartialEq)]
pub struct Record {
    /// Level (run) or step (deck), 1-based.
    pub unit: usize,
    /// Increment within the unit, 1-based.
    pub increment: usize,
    /// Attempt within the unit, 1-based (cut-back attempts included).
    pub attempt: usize,
    /// Seconds since the [`Tracker`] was made.
    pub time_s: f64,
    /// The event.
    pub event: NewtonEvent,
}

/// Numbers Newton's events by unit, increment and attempt.
#[derive(Debug, Clone)]
pub struct Tracker {
    unit: usize,
    attempts: usize,
    converged: usize,
    in_attempt: bool,
    start: Instant,
}

impl Default for Tracker {
    fn default() -> Self {
        Self::new()
    }
}

impl Tracker {
    /// Unit 1, nothing counted; the clock starts now.
    pub fn new() -> Self {
        Self {
            unit: 1,
            attempts: 0,
            converged: 0,
            in_attempt: false,
            start: Instant::now(),
        }
    }

    /// The unit (level or step, 1-based) whose events come next: the counts start anew.
    pub fn begin(&mut self, unit: usize) {
        if unit != self.unit {
            self.unit = unit;
            self.attempts = 0;
            self.converged = 0;
            self.in_attempt = false;
        }
    }

    /// The unit now.
    pub fn unit(&self) -> usize {
        self.unit
    }

    /// Seconds since the tracker was made.
    pub fn elapsed_s(&self) -> f64 {
        self.start.elapsed().as_secs_f64()
    }

    /// Numbers `event`.
    pub fn record(&mut self, event: NewtonEvent) -> Record {
        if !self.in_attempt && !matches!(event, NewtonEvent::Refused { .. }) {
            self.attempts += 1;
            self.in_attempt = true;
        }
        let increment = self.converged + 1;
        match &event {
            NewtonEvent::Iteration { .. } => {}
            NewtonEvent::Attempt { converged, .. } => {
                self.in_attempt = false;
                self.converged += usize::from(*converged);
            }
            NewtonEvent::Refused { .. } => self.converged = self.converged.saturating_sub(1),
        }
        let increment = match event {
            NewtonEvent::Refused { .. } => self.converged + 1,
            _ => increment,
        };
        Record {
            unit: self.unit,
            increment,
            attempt: self.attempts.max(1),
            time_s: self.elapsed_s(),
            event,
        }
    }
}

/// The name of `status.sta` in an output folder.
pub const STATUS_FILE: &str = "status.sta";
/// The name of `convergence.cvg` in an output folder.
pub const CONVERGENCE_FILE: &str = "convergence.cvg";

/// `status.sta` and `convergence.cvg` of an output folder, appended as the run goes; a clone
/// writes to the same files.
#[derive(Debug, Clone)]
pub struct StatusFiles {
    inner: Arc<Mutex<(File, File)>>,
    dir: PathBuf,
}

fn io(path: &Path) -> impl FnOnce(std::io::Error) -> Error + '_ {
    move |source| Error::Io {
        path: path.to_path_buf(),
        source,
    }
}

/// One CSV line through the `csv` crate (quoted where a field needs it); a line break inside a
/// field (a termination's text) becomes a space, so that each record stays on one line.
fn line(fields: &[String]) -> String {
    crate::report::Csv::line(fields.iter().map(|f| f.replace('\n', " ")))
}

impl StatusFiles {
    /// Creates (truncates) both files in `dir` with their header lines; `unit` names the first
    /// column (`level` for a run, `step` for a deck).
    pub fn create(dir: &Path, unit: &str) -> Result<Self, Error> {
        let open = |name: &str, header: String| -> Result<File, Error> {
            let p = dir.join(name);
            let mut f = File::create(&p).map_err(io(&p))?;
            f.write_all(header.as_bytes()).map_err(io(&p))?;
            Ok(f)
        };
        let sta = open(
            STATUS_FILE,
            format!("{unit},increment,attempt,lambda,iterations,result,wall_s,termination\n"),
        )?;
        let cvg = open(
            CONVERGENCE_FILE,
            format!(
                "{unit},increment,attempt,iteration,lambda,residual_n,correction,\
                 negative_pivots,wall_s\n"
            ),
        )?;
        Ok(Self {
            inner: Arc::new(Mutex::new((sta, cvg))),
            dir: dir.to_path_buf(),
        })
    }

    /// Appends `record` to the file it belongs to (one `write` of the whole line).
    pub fn append(&self, record: &Record) -> Result<(), Error> {
        let Record {
            unit,
            increment,
            attempt,
            time_s,
            event,
        } = record;
        let (unit, increment, attempt) =
            (unit.to_string(), increment.to_string(), attempt.to_string());
        let time = format!("{time_s:.3}");
        let (line, name) = match event {
            NewtonEvent::Iteration {
                lambda,
                iteration,
                residual,
                correction,
                negative_pivots,
            } => (
                line(&[
                    unit,
                    increment,
                    attempt,
                    iteration.to_string(),
                    format!("{lambda:e}"),
                    format!("{residual:e}"),
                    format!("{correction:e}"),
                    negative_pivots.map_or(String::new(), |p| p.to_string()),
                    time,
                ]),
                CONVERGENCE_FILE,
            ),
            NewtonEvent::Attempt {
                lambda,
                iterations,
                converged,
                termination,
            } => (
                line(&[
                    unit,
                    increment,
                    attempt,
                    format!("{lambda:e}"),
                    iterations.to_string(),
                    if *converged { "converged" } else { "cut back" }.to_string(),
                    time,
                    termination.clone(),
                ]),
                STATUS_FILE,
            ),
            NewtonEvent::Refused {
                lambda,
                termination,
            } => (
                line(&[
                    unit,
                    increment,
                    attempt,
                    format!("{lambda:e}"),
                    String::new(),
                    "refused".to_string(),
                    time,
                    termination.clone(),
                ]),
                STATUS_FILE,
            ),
        };
        let mut files = self.inner.lock().map_err(|_| Error::OutputLock)?;
        let file = if name == STATUS_FILE {
            &mut files.0
        } else {
            &mut files.1
        };
        let path = self.dir.join(name);
        file.write_all(line.as_bytes()).map_err(io(&path))?;
        file.flush().map_err(io(&path))
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;
    use tracing_subscriber::layer::SubscriberExt;

    /// Newton's events, through the layer, come out as records numbered by increment and
    /// attempt, and land in the files line by line.
    #[test]
    fn newton_events_become_numbered_lines() {
        let seen = Arc::new(Mutex::new(Vec::new()));
        // The events as crates/newton/src/solve.rs emits them (the CLI tests read a real
        // run's files); one of another target is ignored.
        let subscriber = tracing_subscriber::registry().with(NewtonLayer::new({
            let sink = seen.clone();
            move |e| sink.lock().unwrap().push(e)
        }));
        tracing::subscriber::with_default(subscriber, || {
            tracing::debug!(target: TRACE_TARGET, event = "iteration", lambda = 0.5,
                iteration = 1usize, residual = 2.0, correction = 0.1, step = 1.0,
                negative_pivots = -1i64, tolerance = 1e-8);
            tracing::debug!(target: TRACE_TARGET, event = "attempt", lambda = 0.5,
                iterations = 1usize, converged = true, termination = %"converged");
            tracing::debug!(target: "elsewhere", event = "attempt", lambda = 9.0);
        });
        let events = seen.lock().unwrap().clone();
        assert_eq!(events.len(), 2, "{events:?}");
        assert_eq!(
            events[0],
            NewtonEvent::Iteration {
                lambda: 0.5,
                iteration: 1,
                residual: 2.0,
                correction: 0.1,
                negative_pivots: None
            }
        );
        let dir = std::env::temp_dir().join(format!("nonlin3d-log-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let files = StatusFiles::create(&dir, "level").unwrap();
        let mut tracker = Tracker::new();
        for e in events {
            files.append(&tracker.record(e)).unwrap();
        }
        let sta = std::fs::read_to_string(dir.join(STATUS_FILE)).unwrap();
        let cvg = std::fs::read_to_string(dir.join(CONVERGENCE_FILE)).unwrap();
        assert!(
            sta.lines()
                .nth(1)
                .unwrap()
                .starts_with("1,1,1,5e-1,1,converged,")
        );
        assert!(
            cvg.lines()
                .nth(1)
                .unwrap()
                .starts_with("1,1,1,1,5e-1,2e0,1e-1,,")
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// Attempts are counted per unit; a cut-back attempt keeps the increment number, a
    /// refused one takes its increment back.
    #[test]
    fn increments_and_attempts_are_counted_per_unit() {
        let attempt = |converged| NewtonEvent::Attempt {
            lambda: 1.0,
            iterations: 3,
            converged,
            termination: String::new(),
        };
        let mut t = Tracker::new();
        let r = t.record(attempt(false));
        assert_eq!((r.increment, r.attempt), (1, 1));
        let r = t.record(attempt(true));
        assert_eq!((r.increment, r.attempt), (1, 2));
        let r = t.record(NewtonEvent::Refused {
            lambda: 1.0,
            termination: String::new(),
        });
        assert_eq!((r.increment, r.attempt), (1, 2));
        let r = t.record(attempt(true));
        assert_eq!((r.increment, r.attempt), (1, 3));
        let r = t.record(attempt(true));
        assert_eq!((r.increment, r.attempt), (2, 4));
        t.begin(2);
        let r = t.record(attempt(true));
        assert_eq!((r.unit, r.increment, r.attempt), (2, 1, 1));
    }
}
