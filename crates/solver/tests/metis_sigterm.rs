//! A SIGTERM sent to the thread that runs METIS, during the call, is neither taken by METIS nor
//! lost (crates/solver/src/metis.rs, "Signals"). GKlib's handler, in force for the length of
//! the call, longjmps back into the call: taken on the calling thread it turned the call into
//! `METIS_ERROR` and could jump out of malloc (this test hung once so). The calling thread now
//! blocks SIGTERM during the call: the signal waits, METIS ends normally, and the caller's own
//! handler sees it once the mask is back.
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

/// Three times: SIGTERM sent to the METIS thread at 20 %, 50 % and 80 % of a first call's
/// time. Each call must return the same order as the first (METIS never took the signal) and
/// this test's handler must see the signal after it; at least one must have been sent before
/// its call ended (on a loaded machine a late one is only an ordinary signal).
#[test]
fn a_sigterm_during_metis_waits_for_the_call_and_reaches_the_callers_handler() {
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
    let first = metis_nested_dissection(&p).unwrap();
    let whole = t0.elapsed();
    let mut during = 0;
    for share in [0.2, 0.5, 0.8] {
        TERM.store(false, Ordering::SeqCst);
        // SAFETY: pthread_self of this thread, used by the signalling thread while this one
        // is alive (it joins below).
        let me = unsafe { libc::pthread_self() } as usize;
        let sender = std::thread::spawn(move || {
            std::thread::sleep(whole.mul_f64(share));
            // SAFETY: a standard signal to a live thread of this process.
            unsafe { libc::pthread_kill(me as libc::pthread_t, libc::SIGTERM) };
            Instant::now()
        });
        let result = metis_nested_dissection(&p);
        let ended = Instant::now();
        let sent = sender.join().unwrap();
        let order = result.unwrap_or_else(|e| panic!("METIS took the signal at {share}: {e}"));
        assert_eq!(order.forward(), first.forward(), "at {share}");
        // The signal is pending until the mask is back, then handled before the call returns
        // to us; give it a moment all the same.
        let deadline = Instant::now() + Duration::from_secs(2);
        while !TERM.load(Ordering::SeqCst) && Instant::now() < deadline {
            std::thread::sleep(Duration::from_millis(5));
        }
        assert!(
            TERM.load(Ordering::SeqCst),
            "the SIGTERM at {share} was lost"
        );
        during += usize::from(sent < ended);
    }
    assert!(
        during > 0,
        "no signal was sent during a call (METIS took {whole:?})"
    );
}
