//! What the command line shows while it solves: a progress bar on stderr (a level of `run`, a
//! step of `solve`, with the increment, attempt, iteration and ‖r‖ of the Newton iteration in
//! progress and a steady tick, so it moves during a long level), one line per Newton iteration
//! with `-v`, nothing with `-q`; the bar only when stderr is a terminal. Newton's records come
//! through `tracing` ([`nonlin3d::log::NewtonLayer`]) and also go to the output folder's
//! `status.sta` and `convergence.cvg`.

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use nonlin3d::log::{NewtonEvent, Record, StatusFiles, Tracker};
use std::io::IsTerminal;
use std::sync::{Arc, Mutex};
use std::time::Duration;

/// How much the command prints.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Verbosity {
    /// `-q`: nothing but errors.
    Quiet,
    /// The bar (on a terminal), the table, warnings.
    Normal,
    /// `-v`: also one line per Newton iteration and per attempt.
    Verbose,
}

/// Bar positions per unit (level or step): the bar moves within a unit as its increments
/// converge.
const TICKS: u64 = 1000;

/// The progress bar, the `-v` lines and the status files of one command.
pub struct Monitor {
    bar: ProgressBar,
    verbosity: Verbosity,
    tracker: Tracker,
    files: Option<StatusFiles>,
    /// `level` or `step`.
    unit_name: &'static str,
    units: usize,
    /// A failure to append to the status files (reported once, at the end).
    file_error: Option<nonlin3d::Error>,
}

/// A [`Monitor`] shared with the `tracing` layer.
pub type Shared = Arc<Mutex<Monitor>>;

impl Monitor {
    /// A monitor for units named `unit_name`; the bar is drawn only for [`Verbosity::Normal`]
    /// and [`Verbosity::Verbose`] on a terminal, and ticks every 100 ms from now on.
    pub fn new(verbosity: Verbosity, unit_name: &'static str) -> Self {
        let bar = if verbosity == Verbosity::Quiet || !std::io::stderr().is_terminal() {
            ProgressBar::hidden()
        } else {
            ProgressBar::with_draw_target(Some(TICKS), ProgressDrawTarget::stderr())
        };
        bar.set_style(
            ProgressStyle::with_template(
                "{spinner} {elapsed_precise} {bar:12} {prefix} {wide_msg}",
            )
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
        );
        if !bar.is_hidden() {
            bar.enable_steady_tick(Duration::from_millis(100));
        }
        Self {
            bar,
            verbosity,
            tracker: Tracker::new(),
            files: None,
            unit_name,
            units: 1,
            file_error: None,
        }
    }

    /// Shared, for [`layer`].
    pub fn shared(self) -> Shared {
        Arc::new(Mutex::new(self))
    }

    /// Newton's records go to `files` from now on.
    pub fn write_to(&mut self, files: StatusFiles) {
        self.files = Some(files);
    }

    /// What the bar says before the first unit (building the model, …).
    pub fn message(&self, text: String) {
        self.bar.set_message(text);
    }

    /// `units` levels or steps to solve.
    pub fn units(&mut self, units: usize) {
        self.units = units.max(1);
        self.bar.set_length(self.units as u64 * TICKS);
        self.show_unit();
    }

    /// Unit `unit` (1-based) starts; `done` of it is already done (0 … 1).
    pub fn begin(&mut self, unit: usize, done: f64) {
        self.tracker.begin(unit);
        let at = (unit.saturating_sub(1) as f64 + done.clamp(0.0, 1.0)) * TICKS as f64;
        self.bar
            .set_position((at as u64).min(self.units as u64 * TICKS));
        self.show_unit();
    }

    fn show_unit(&self) {
        self.bar.set_prefix(format!(
            "{} {}/{}",
            self.unit_name,
            self.tracker.unit().min(self.units),
            self.units
        ));
    }

    /// Prints a line of the command's own (not with `-q`), above the bar.
    pub fn say(&self, line: &str) {
        if self.verbosity != Verbosity::Quiet {
            self.bar.suspend(|| println!("{line}"));
        }
    }

    /// A warning (not with `-q`), on stderr above the bar.
    pub fn warn(&self, line: &str) {
        if self.verbosity != Verbosity::Quiet {
            self.bar.suspend(|| eprintln!("nonlin3d: warning: {line}"));
        }
    }

    /// One of Newton's events: numbered, appended to the status files, shown on the bar and,
    /// with `-v`, printed.
    pub fn newton(&mut self, event: NewtonEvent) {
        let record = self.tracker.record(event);
        if let Some(files) = &self.files
            && let Err(e) = files.append(&record)
            && self.file_error.is_none()
        {
            self.file_error = Some(e);
        }
        if let NewtonEvent::Iteration {
            residual,
            iteration,
            ..
        } = record.event
        {
            self.bar.set_message(format!(
                "iteration {iteration} ‖r‖ {residual:.2e} N (increment {}, attempt {})",
                record.increment, record.attempt
            ));
        }
        if self.verbosity == Verbosity::Verbose {
            let line = self.line(&record);
            self.bar.suspend(|| eprintln!("{line}"));
        }
    }

    /// One of a companion's Newton events (its own run, first or beside this one; `depth` 1
    /// the error estimate's companion mesh, 2 the coarser one it starts from): on the bar and,
    /// with `-v`, printed, but neither numbered as this run's nor written to the status files.
    pub fn companion(&self, depth: usize, event: &NewtonEvent) {
        let name = if depth > 1 {
            "coarser companion"
        } else {
            "companion mesh"
        };
        let line = match event {
            NewtonEvent::Iteration {
                lambda,
                iteration,
                residual,
                ..
            } => {
                self.bar.set_message(format!(
                    "{name}: iteration {iteration} ‖r‖ {residual:.2e} N (λ {lambda:.4})"
                ));
                format!("{name}: λ {lambda:.6} iteration {iteration}: ‖r‖ {residual:.3e} N")
            }
            NewtonEvent::Attempt {
                lambda,
                iterations,
                termination,
                ..
            } => format!("{name}: λ {lambda:.6} {termination} after {iterations} iterations"),
            NewtonEvent::Refused {
                lambda,
                termination,
            } => format!("{name}: λ {lambda:.6} {termination}"),
        };
        if self.verbosity == Verbosity::Verbose {
            self.bar.suspend(|| eprintln!("{line}"));
        }
    }

    /// The `-v` line of a record.
    fn line(&self, r: &Record) -> String {
        let head = format!(
            "{} {} increment {} attempt {}",
            self.unit_name, r.unit, r.increment, r.attempt
        );
        match &r.event {
            NewtonEvent::Iteration {
                lambda,
                iteration,
                residual,
                correction,
                negative_pivots,
            } => format!(
                "{head} iteration {iteration}: λ {lambda:.6} ‖r‖ {residual:.3e} N ‖Δu‖ \
                 {correction:.3e} negative pivots {} time {:.2} s",
                negative_pivots.map_or("-".into(), |p| p.to_string()),
                r.time_s
            ),
            NewtonEvent::Attempt {
                lambda,
                iterations,
                termination,
                ..
            } => format!(
                "{head}: λ {lambda:.6} {termination} after {iterations} iterations, time {:.2} s",
                r.time_s
            ),
            NewtonEvent::Refused {
                lambda,
                termination,
            } => format!("{head}: λ {lambda:.6} {termination}"),
        }
    }

    /// Clears the bar; returns the first error met appending to the status files.
    pub fn finish(&mut self) -> Option<nonlin3d::Error> {
        self.bar.finish_and_clear();
        self.file_error.take()
    }
}

/// The `tracing` layer that feeds `monitor` with Newton's events.
pub fn layer(
    monitor: &Shared,
) -> nonlin3d::log::NewtonLayer<impl Fn(NewtonEvent) + Send + Sync + 'static> {
    let (run, companion) = (monitor.clone(), monitor.clone());
    nonlin3d::log::NewtonLayer::new(move |e| {
        if let Ok(mut m) = run.lock() {
            m.newton(e);
        }
    })
    .with_companion(move |depth, e| {
        if let Ok(m) = companion.lock() {
            m.companion(depth, &e);
        }
    })
}
