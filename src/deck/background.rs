//! `nonlin3d solve`'s files written on a thread of their own while the next increment is
//! solved (solves on two or more threads). The solving thread hands each report over as an
//! owned copy of its [`StepResult`] and goes on; the writer thread runs
//! [`DeckOutput::progress`] on the reports in their order. What [`DeckOutput`] promises holds
//! as it is (every file whole, `summary.json` written after the files it lists). What changes
//! is when: the folder lags the solve by at most two reports (one being written, one
//! queued), and a signal's stop waits for them ([`crate::output::Backlog`]) before it writes
//! the stopped state, so every increment converged before the signal is kept.
//!
//! On two threads this takes the VTU files' nodal fields, formatting and writes (about 0.4 s
//! of a 24 k-DOF deck's ten increments) off the thread the solve waits on; on one thread the
//! files are written where they are reported, as before (docs/PERFORMANCE.md).

use super::{DeckOutput, Progress, StepResult};
use crate::Error;
use std::sync::Mutex;
use std::sync::mpsc::sync_channel;

/// A report, owned: the writer thread's copy.
enum Job {
    Increment(StepResult),
    Step(StepResult),
    Failed(StepResult),
}

impl Job {
    fn of(p: Progress<'_>) -> Self {
        match p {
            Progress::Increment(r) => Self::Increment(r.clone()),
            Progress::Step(r) => Self::Step(r.clone()),
            Progress::Failed(r) => Self::Failed(r.clone()),
        }
    }

    fn progress(&self) -> Progress<'_> {
        match self {
            Self::Increment(r) => Progress::Increment(r),
            Self::Step(r) => Progress::Step(r),
            Self::Failed(r) => Progress::Failed(r),
        }
    }
}

/// Runs `solve` with an observer that hands every report to a writer thread running
/// [`DeckOutput::progress`] on `output`, and waits for the writer at the end. Returns
/// `solve`'s result and the writer's: the writer stops at its first error, and the solve is
/// stopped by that error at its next report (a failure after the last report is the second
/// result). If the thread cannot be started, every report is written on this thread.
pub fn write_in_background<R>(
    output: &mut DeckOutput<'_>,
    solve: impl FnOnce(&mut dyn FnMut(Progress<'_>) -> Result<(), Error>) -> R,
) -> (R, Result<(), Error>) {
    let backlog = output.interrupt_handle().backlog();
    let failed: Mutex<Option<Error>> = Mutex::new(None);
    let take_failure = || failed.lock().unwrap_or_else(|e| e.into_inner()).take();
    output.set_background(true);
    let shared = Mutex::new(output);
    let write = |p: Progress<'_>| shared.lock().unwrap_or_else(|e| e.into_inner()).progress(p);
    // One report queued beside the one being written: the solve waits rather than letting
    // copies of the state pile up.
    let (jobs, queue) = sync_channel::<Job>(1);
    let result = std::thread::scope(|scope| {
        let writer = std::thread::Builder::new()
            .name("output".into())
            .spawn_scoped(scope, || {
                for job in queue {
                    let written = write(job.progress());
                    backlog.done();
                    if let Err(e) = written {
                        *failed.lock().unwrap_or_else(|e| e.into_inner()) = Some(e);
                        break;
                    }
                }
                backlog.close();
            });
        let Ok(writer) = writer else {
            backlog.close();
            return solve(&mut |p| write(p));
        };
        let mut jobs = Some(jobs);
        let result = solve(&mut |p| {
            if let Some(e) = take_failure() {
                return Err(e);
            }
            let Some(sender) = &jobs else {
                return Err(Error::OutputLock);
            };
            backlog.sent();
            if sender.send(Job::of(p)).is_err() {
                // The writer ended: its error, if it left one.
                jobs = None;
                backlog.done();
                return Err(take_failure().unwrap_or(Error::OutputLock));
            }
            Ok(())
        });
        drop(jobs);
        // A panic in the writer (a bug) is the solve's panic.
        if let Err(panic) = writer.join() {
            std::panic::resume_unwind(panic);
        }
        result
    });
    (result, take_failure().map_or(Ok(()), Err))
}
