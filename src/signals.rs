//! SIGINT and SIGTERM for the `nonlin3d` program, taken by one thread with sigwait(2).
//!
//! [`block`] runs first in `main`, before any other thread exists: both signals are blocked in
//! the main thread, and every thread made later (rayon's pool, the companion runs, faer's
//! kernels) inherits the mask, so neither signal is ever handled inside the computation. One
//! thread ([`wait`]) takes them with sigwait(2):
//!
//! - before a run or a deck solve has armed it ([`stop_on`]), a signal ends the program with
//!   the signal's default action, as if nothing had been installed;
//! - once armed, the first signal writes results.json (summary.json) as it stands with
//!   `"stopped": "interrupted by …"` and exits 130 (SIGINT) or 143 (SIGTERM); a second one
//!   while that is written exits at once.
//!
//! A child inherits the mask, and std does not reset it. So the Slurm commands the sweep
//! runs (`squeue`, `sacct`, `sbatch`) are started with an empty mask
//! (src/sweep/cluster.rs, `command`).
//!
//! Why not handlers: METIS's GKlib installs its own SIGTERM and SIGABRT handlers for the
//! length of every METIS call, and its handler longjmps to the call's start on the thread it
//! runs on. A SIGTERM delivered during an ordering to any other thread crashed the program
//! (SIGSEGV, nothing written); one delivered to METIS's own thread could jump out of malloc
//! and hang it (crates/solver/src/metis.rs, "Signals"). A blocked signal is delivered to no
//! thread: it waits for sigwait, whatever disposition GKlib has set meanwhile.

use nonlin3d::output::InterruptHandle;
use std::sync::Mutex;

/// The run's (or deck solve's) writer for an interrupted end; None until one is armed.
static ARMED: Mutex<Option<InterruptHandle>> = Mutex::new(None);

/// The signals taken: SIGINT (exit 130) and SIGTERM (exit 143).
#[cfg(unix)]
fn both() -> libc::sigset_t {
    // SAFETY: sigemptyset/sigaddset initialise and fill a set we own.
    unsafe {
        let mut set: libc::sigset_t = std::mem::zeroed();
        libc::sigemptyset(&mut set);
        libc::sigaddset(&mut set, libc::SIGINT);
        libc::sigaddset(&mut set, libc::SIGTERM);
        set
    }
}

/// Blocks SIGINT and SIGTERM in this thread (and so in every thread it or its descendants
/// create) and starts the thread that takes them. Call it first in `main`.
#[cfg(unix)]
pub fn block() -> Result<(), nonlin3d::Error> {
    let set = both();
    // SAFETY: changing this thread's mask with a set initialised above.
    let rc = unsafe { libc::pthread_sigmask(libc::SIG_BLOCK, &set, std::ptr::null_mut()) };
    if rc != 0 {
        return Err(nonlin3d::Error::Signal(std::io::Error::from_raw_os_error(
            rc,
        )));
    }
    std::thread::Builder::new()
        .name("signals".into())
        .spawn(move || wait(set))
        .map_err(nonlin3d::Error::Signal)?;
    Ok(())
}

#[cfg(not(unix))]
pub fn block() -> Result<(), nonlin3d::Error> {
    Ok(())
}

/// Arms the interrupted end: from now on the first signal writes `handle`'s state.
pub fn stop_on(handle: InterruptHandle) {
    *ARMED.lock().unwrap_or_else(|e| e.into_inner()) = Some(handle);
}

/// The signal thread: takes each blocked signal as it comes.
#[cfg(unix)]
fn wait(set: libc::sigset_t) {
    let mut stopping = false;
    loop {
        let mut sig: libc::c_int = 0;
        // SAFETY: sigwait on a set of signals this thread (like every other) blocks.
        if unsafe { libc::sigwait(&set, &mut sig) } != 0 {
            continue;
        }
        let (name, code) = if sig == libc::SIGINT {
            ("SIGINT", 130)
        } else {
            ("SIGTERM", 143)
        };
        if stopping {
            // A second signal while the first one's state is written: at once.
            std::process::exit(code);
        }
        let armed = ARMED.lock().unwrap_or_else(|e| e.into_inner()).clone();
        let Some(handle) = armed else {
            default_action(sig);
            std::process::exit(code);
        };
        stopping = true;
        // The state is written on its own thread, so that this one can take a second signal
        // (a thread that cannot be started: exit now, as a second signal would).
        let writer = std::thread::Builder::new()
            .name("stop".into())
            .spawn(move || {
                let kept = handle.stop(name);
                eprintln!(
                    "\nnonlin3d: interrupted by {name}{}",
                    if kept {
                        "; the levels converged so far are kept (results.json: \"complete\": false)"
                    } else {
                        ""
                    }
                );
                std::process::exit(code);
            });
        if writer.is_err() {
            std::process::exit(code);
        }
    }
}

/// Ends the process by `sig`'s default action (terminate), as without any handling: the
/// disposition set to the default, the signal unblocked in this thread and raised to it.
#[cfg(unix)]
fn default_action(sig: libc::c_int) {
    // SAFETY: standard calls on a standard signal; `one` is initialised before use.
    unsafe {
        libc::signal(sig, libc::SIG_DFL);
        let mut one: libc::sigset_t = std::mem::zeroed();
        libc::sigemptyset(&mut one);
        libc::sigaddset(&mut one, sig);
        libc::pthread_sigmask(libc::SIG_UNBLOCK, &one, std::ptr::null_mut());
        libc::raise(sig);
    }
}
