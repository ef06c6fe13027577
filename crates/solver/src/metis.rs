//! METIS's nested dissection (Karypis & Kumar 1998, `METIS_NodeND` of METIS 5.1, built from
//! source by the `metis-sys` crate) on the node graph of a finite-element pattern.
//!
//! The pattern is compressed to nodes first, as for [`crate::nested_dissection`] (the 3 DOFs
//! of a node are one vertex of weight 3), METIS orders the vertices (multilevel node
//! bisection with node-based FM refinement, several separators tried per level, minimum
//! degree on the small parts) and each vertex expands back to its DOFs in place.
//!
//! Determinism: METIS's random generator is one process-wide state, seeded at each call from
//! its options, so calls are serialised by a lock and the seed is fixed: the same pattern gives
//! the same order on every call and from any thread or thread count.
//!
//! Signals: every METIS entry point installs GKlib's own SIGABRT/SIGTERM handlers (its error
//! exit) for the length of the call and puts back the previous ones with `signal()`, which
//! loses their flags; the handlers in force before the call are saved and restored here with
//! `sigaction`. GKlib's handler longjmps to the start of the call *on the thread it runs on*
//! (its jump buffers are thread-local). So a SIGTERM handled during the call
//!
//! - on another thread jumps through an unset buffer: the process crashed (SIGSEGV, shown by
//!   a process-directed SIGTERM while another thread ordered);
//! - on the calling thread jumps out of whatever METIS was doing, malloc included, and can
//!   leave a lock held (a hang, seen once in this crate's signal test).
//!
//! The calling thread therefore blocks SIGTERM for the length of the call (a signal sent to
//! it waits, and reaches the caller's handler once the mask is back), and a program that
//! handles SIGTERM with more than one thread must keep it blocked in all of them and take it
//! with sigwait(2), as the `nonlin3d` program does (its src/signals.rs): a blocked signal is
//! delivered to no thread, whatever disposition GKlib has set meanwhile. SIGABRT is left as it
//! is: GKlib raises it on its own thread when an allocation fails (`gk_malloc`), which METIS
//! turns into `METIS_ERROR_MEMORY`. GKlib's error exits that raise SIGTERM instead are reached
//! only through options this wrapper leaves at METIS's defaults (unknown coarsening or
//! initial-partition types, graphs stored on disk), never by a graph.

use crate::nested::compress;
use crate::{Permutation, SolverError, SymmetricPattern};
use metis_sys as ffi;
use std::sync::Mutex;

/// The seed of METIS's random generator (its default, −1, means 4321; fixed explicitly so that
/// a change of METIS's default cannot move the order).
pub const METIS_SEED: i32 = 4321;

/// Serialises METIS calls: its random state and GKlib's signal handlers are process-wide.
static METIS_LOCK: Mutex<()> = Mutex::new(());

/// METIS nested-dissection order of `pattern`'s DOFs (`forward[new] = old`).
///
/// Errors: a node graph with more than `i32::MAX` vertices or adjacency entries (METIS's
/// 32-bit indices), METIS running out of memory, or any other METIS failure.
pub fn metis_nested_dissection(pattern: &SymmetricPattern) -> Result<Permutation, SolverError> {
    let (members, graph) = compress(pattern);
    let nv = graph.n();
    if nv <= 1 {
        return Permutation::from_forward((0..pattern.n()).collect());
    }
    let to_idx = |v: usize, what: &'static str| -> Result<i32, SolverError> {
        i32::try_from(v).map_err(|_| SolverError::TooLarge {
            what,
            entries: v,
            limit: i32::MAX as usize,
        })
    };
    let mut nvtxs = to_idx(nv, "METIS's node graph (vertices)")?;
    to_idx(graph.adj.len(), "METIS's node graph (adjacency entries)")?;
    let mut xadj: Vec<i32> = graph.xadj.iter().map(|&x| x as i32).collect();
    let mut adjncy: Vec<i32> = graph.adj.iter().map(|&x| x as i32).collect();
    let mut vwgt: Vec<i32> = graph.vw.iter().map(|&w| w as i32).collect();
    let mut options = [0 as ffi::idx_t; ffi::METIS_NOPTIONS as usize];
    let mut perm = vec![0 as ffi::idx_t; nv];
    let mut iperm = vec![0 as ffi::idx_t; nv];
    let status = {
        // A poisoned lock only means another METIS call panicked: the state it guards is
        // re-seeded by every call.
        let _guard = METIS_LOCK.lock().unwrap_or_else(|e| e.into_inner());
        let _blocked = SigtermBlocked::block();
        let signals = SavedHandlers::save();
        // SAFETY: the arrays have the lengths METIS_NodeND reads and writes (xadj nv + 1,
        // adjncy xadj[nv], vwgt/perm/iperm nv, options METIS_NOPTIONS); indices were checked
        // to fit idx_t (i32) above; METIS keeps no pointer after returning.
        let status = unsafe {
            ffi::METIS_SetDefaultOptions(options.as_mut_ptr());
            options[ffi::moptions_et_METIS_OPTION_SEED as usize] = METIS_SEED;
            options[ffi::moptions_et_METIS_OPTION_NUMBERING as usize] = 0;
            ffi::METIS_NodeND(
                &mut nvtxs,
                xadj.as_mut_ptr(),
                adjncy.as_mut_ptr(),
                vwgt.as_mut_ptr(),
                options.as_mut_ptr(),
                perm.as_mut_ptr(),
                iperm.as_mut_ptr(),
            )
        };
        // GKlib's handlers out first, then SIGTERM unblocked (`_blocked`'s drop).
        drop(signals);
        status
    };
    match status {
        s if s == ffi::rstatus_et_METIS_OK => {}
        s if s == ffi::rstatus_et_METIS_ERROR_MEMORY => {
            return Err(SolverError::OutOfMemory {
                what: "METIS's nested dissection",
                bytes: 4 * (xadj.len() + adjncy.len() + 4 * nv),
            });
        }
        s => {
            return Err(SolverError::Metis(format!(
                "METIS_NodeND returned {s} on a graph of {nv} nodes"
            )));
        }
    }
    // METIS: perm[new] = old vertex.
    let mut forward = Vec::with_capacity(pattern.n());
    for &v in &perm {
        let v = usize::try_from(v).ok().filter(|&v| v < nv).ok_or_else(|| {
            SolverError::Metis(format!("METIS returned vertex {v} out of 0..{nv}"))
        })?;
        forward.extend_from_slice(&members[v]);
    }
    Permutation::from_forward(forward)
}

/// SIGTERM blocked in this thread while it lives, the thread's previous mask put back on drop.
struct SigtermBlocked {
    #[cfg(unix)]
    previous: Option<libc::sigset_t>,
}

impl SigtermBlocked {
    fn block() -> Self {
        #[cfg(unix)]
        // SAFETY: a set initialised by sigemptyset, and this thread's own mask.
        unsafe {
            let mut set: libc::sigset_t = std::mem::zeroed();
            libc::sigemptyset(&mut set);
            libc::sigaddset(&mut set, libc::SIGTERM);
            let mut previous: libc::sigset_t = std::mem::zeroed();
            let ok = libc::pthread_sigmask(libc::SIG_BLOCK, &set, &mut previous) == 0;
            Self {
                previous: ok.then_some(previous),
            }
        }
        #[cfg(not(unix))]
        Self {}
    }
}

impl Drop for SigtermBlocked {
    fn drop(&mut self) {
        #[cfg(unix)]
        if let Some(previous) = &self.previous {
            // SAFETY: restoring the mask pthread_sigmask gave back above.
            unsafe {
                libc::pthread_sigmask(libc::SIG_SETMASK, previous, std::ptr::null_mut());
            }
        }
    }
}

/// The SIGABRT and SIGTERM dispositions in force before a METIS call, put back on drop.
struct SavedHandlers {
    #[cfg(unix)]
    saved: Vec<(libc::c_int, libc::sigaction)>,
}

impl SavedHandlers {
    fn save() -> Self {
        #[cfg(unix)]
        {
            let mut saved = Vec::new();
            for sig in [libc::SIGABRT, libc::SIGTERM] {
                // SAFETY: querying a disposition (null new action) into a zeroed struct.
                unsafe {
                    let mut old: libc::sigaction = std::mem::zeroed();
                    if libc::sigaction(sig, std::ptr::null(), &mut old) == 0 {
                        saved.push((sig, old));
                    }
                }
            }
            Self { saved }
        }
        #[cfg(not(unix))]
        Self {}
    }
}

impl Drop for SavedHandlers {
    fn drop(&mut self) {
        #[cfg(unix)]
        for (sig, old) in &self.saved {
            // SAFETY: re-installing a disposition the kernel gave us, flags included.
            unsafe {
                libc::sigaction(*sig, old, std::ptr::null_mut());
            }
        }
    }
}

#[cfg(test)]
mod tests;
