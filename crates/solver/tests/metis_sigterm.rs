//! A SIGTERM that arrives while METIS orders is not lost (crates/solver/src/metis.rs,
//! "Signals"). GKlib's handler takes a signal sent during the call and turns it into
//! `METIS_ERROR`. The wrapper must then send SIGTERM on to the process once the caller's
//! handlers are back. Without that, `nonlin3d solve` ran to the end after a SIGTERM (exit 0;
//! seen in tests/deck_reliability.rs under CI's load).
//!
//! This file holds one test, so it runs in a process of its own: the test installs its own
//! SIGTERM handler, and no other test may see it.
#![cfg(unix)]
#![allow(clippy::unwrap_used)]

use nonlin3d_solver::{SymmetricPattern, metis_nested_dissection};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

static TERM: AtomicBool = AtomicBool::new(false);

extern "C" fn on_term(_: libc::c_int) {
    TERM.store(true, Ordering::SeqCst);
}

/// The test sends SIGTERM to the thread that runs METIS, part-way through a call as long as a
/// first call took. The signal may land inside METIS (GKlib's handler turns it into an error,
/// which the wrapper passes on) or outside it (this test's handler). Either way this test's
/// handler must see it, and a call that failed must have passed the signal on. The test tries
/// up to five times to land it inside the call.
#[test]
fn a_sigterm_during_metis_reaches_the_callers_handler() {
    // SAFETY: installing a handler that only stores to an atomic (async-signal-safe).
    unsafe {
        let mut act: libc::sigaction = std::mem::zeroed();
        act.sa_sigaction = on_term as *const () as usize;
        libc::sigemptyset(&mut act.sa_mask);
        assert_eq!(
            libc::sigaction(libc::SIGTERM, &act, std::ptr::null_mut()),
            0
        );
    }
    let (n, lists) = nonlin3d_testkit::hex20_dof_lists([40, 40, 12]);
    let p = SymmetricPattern::from_dof_lists(n, &lists).unwrap();
    let t0 = Instant::now();
    metis_nested_dissection(&p).unwrap();
    let whole = t0.elapsed();
    let mut landed_inside = false;
    for _ in 0..5 {
        TERM.store(false, Ordering::SeqCst);
        // SAFETY: pthread_self of this thread, used by the signalling thread while this one
        // is alive (it joins below).
        let me = unsafe { libc::pthread_self() } as usize;
        let sender = std::thread::spawn(move || {
            std::thread::sleep(whole.mul_f64(0.6));
            // SAFETY: a standard signal to a live thread of this process.
            unsafe { libc::pthread_kill(me as libc::pthread_t, libc::SIGTERM) };
        });
        let result = metis_nested_dissection(&p);
        sender.join().unwrap();
        // The signal is handled by the time pthread_kill returned and the call ended; give a
        // process-directed re-send a moment to be delivered.
        let deadline = Instant::now() + Duration::from_secs(2);
        while !TERM.load(Ordering::SeqCst) && Instant::now() < deadline {
            std::thread::sleep(Duration::from_millis(5));
        }
        assert!(
            TERM.load(Ordering::SeqCst),
            "the SIGTERM was lost (METIS {})",
            if result.is_ok() {
                "succeeded"
            } else {
                "failed"
            }
        );
        if result.is_err() {
            landed_inside = true;
            break;
        }
    }
    assert!(
        landed_inside,
        "no signal landed inside METIS in 5 tries (METIS took {whole:?})"
    );
}
