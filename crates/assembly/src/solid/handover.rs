//! Cells across a split, evaluated once: the part that owns a cell's highest-ranked node
//! evaluates it and hands the values a lower part owns (the forces of the cell's nodes there,
//! then its share of the tangent, `share::Pack`) over through a slot of a shared buffer.
//!
//! The owner meets such a cell near the start of its sweep (its highest rank is among the
//! part's lowest), the reader near the end of its own (the cell's highest rank is past the
//! part), so the reader rarely waits. It never waits on work that has not started: a reader
//! that finds a slot empty claims it and evaluates the cell itself, and the owner then leaves
//! the slot alone. Either way the reader scatters the same bits (the kernel is deterministic
//! per cell), so the assembly stays bitwise independent of the thread count and of timing.

use std::marker::PhantomData;
use std::sync::atomic::{AtomicU8, Ordering};

/// A slot's region of the buffer.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Slot {
    /// First value.
    pub(crate) start: usize,
    /// Number of values.
    pub(crate) len: usize,
}

/// Which cells cross the splits of one assembly and where each is handed over, for one split.
#[derive(Debug, Default)]
pub(crate) struct HandOverPlan {
    /// The split (part boundaries in rank) the plan was made for.
    pub(crate) key: Vec<usize>,
    /// `[part][group]`: the group's cells (group-local, sweep order) with a node in the part
    /// and their highest rank past it, each with its slot and its place in the part's list.
    pub(crate) incoming: Vec<Vec<Vec<(usize, usize, usize)>>>,
    /// `[part][group]`: the cells the part evaluates that lower parts read, each with its slot
    /// and the reading part, in sweep order.
    pub(crate) outgoing: Vec<Vec<Vec<(usize, usize, usize)>>>,
    /// Slot regions when tangents are handed over (forces and rows) …
    pub(crate) with_tangent: Vec<Slot>,
    /// … and when only forces are.
    pub(crate) forces_only: Vec<Slot>,
}

impl HandOverPlan {
    /// The slots for an assembly with or without the tangent, and the buffer length they need.
    pub(crate) fn slots(&self, tangent: bool) -> (&[Slot], usize) {
        let slots = if tangent {
            &self.with_tangent
        } else {
            &self.forces_only
        };
        (slots, slots.last().map_or(0, |s| s.start + s.len))
    }
}

const EMPTY: u8 = 0;
const WRITING: u8 = 1;
const READY: u8 = 2;
const TAKEN: u8 = 3;

/// The slots of one assembly over a buffer the slots tile without overlap.
pub(crate) struct Mailbox<'a> {
    slots: &'a [Slot],
    states: Vec<AtomicU8>,
    ptr: *mut f64,
    _borrow: PhantomData<&'a mut [f64]>,
}

// SAFETY: the buffer is borrowed mutably for the mailbox's life, so nothing else reaches it.
// A slot's region is written only by the thread that moved its state EMPTY → WRITING (one
// compare-exchange succeeds per slot) and read only after the writer's Release store of
// READY has been seen with Acquire; regions of different slots are disjoint (checked in
// `new`). No region is ever written and read at the same time.
unsafe impl Sync for Mailbox<'_> {}
// SAFETY: as for `Sync`: the pointer is only the borrowed buffer.
unsafe impl Send for Mailbox<'_> {}

/// Puts an abandoned write back to EMPTY (a panic inside `fill`), so a reader evaluates the
/// cell itself instead of waiting for ever.
struct Unwinding<'s>(Option<&'s AtomicU8>);

impl Drop for Unwinding<'_> {
    fn drop(&mut self) {
        if let Some(state) = self.0 {
            state.store(EMPTY, Ordering::Release);
        }
    }
}

impl<'a> Mailbox<'a> {
    /// Empty slots over `buffer`. Panics if a slot leaves the buffer or two overlap (an
    /// internal layout error, never user input).
    pub(crate) fn new(slots: &'a [Slot], buffer: &'a mut [f64]) -> Self {
        let mut order: Vec<&Slot> = slots.iter().collect();
        order.sort_unstable_by_key(|s| s.start);
        let mut end = 0;
        for s in order {
            assert!(
                s.start >= end && s.start + s.len <= buffer.len(),
                "hand-over slots overlap or leave the buffer"
            );
            end = s.start + s.len;
        }
        Self {
            slots,
            states: slots.iter().map(|_| AtomicU8::new(EMPTY)).collect(),
            ptr: buffer.as_mut_ptr(),
            _borrow: PhantomData,
        }
    }

    /// The evaluating part: fills slot `k` with `fill` and publishes it, unless its reader has
    /// already claimed the cell (then nothing happens).
    pub(crate) fn publish(&self, k: usize, fill: impl FnOnce(&mut [f64])) {
        let state = &self.states[k];
        if state
            .compare_exchange(EMPTY, WRITING, Ordering::Acquire, Ordering::Relaxed)
            .is_err()
        {
            return;
        }
        let s = self.slots[k];
        // SAFETY: in the buffer (checked in `new`), disjoint from every other slot, and this
        // thread alone won EMPTY → WRITING: no other reference to the region exists until READY.
        let region = unsafe { std::slice::from_raw_parts_mut(self.ptr.add(s.start), s.len) };
        let guard = Unwinding(Some(state));
        fill(region);
        std::mem::forget(guard);
        state.store(READY, Ordering::Release);
    }

    /// Hints the lines of slot `k` (its values may not be written yet: a hint reads nothing).
    pub(crate) fn prefetch(&self, k: usize) {
        let s = self.slots[k];
        for o in (0..s.len).step_by(8) {
            nonlin3d_element::prefetch_line(self.ptr.wrapping_add(s.start + o));
        }
    }

    /// The reading part: slot `k`'s values once published (waiting while they are being
    /// written), or None when nobody had started on them: the caller then evaluates the cell
    /// itself and the slot stays claimed.
    pub(crate) fn take(&self, k: usize) -> Option<&[f64]> {
        let state = &self.states[k];
        let mut spins = 0u32;
        loop {
            match state.compare_exchange(EMPTY, TAKEN, Ordering::Acquire, Ordering::Acquire) {
                Ok(_) => return None,
                Err(READY) => {
                    let s = self.slots[k];
                    // SAFETY: READY was stored with Release after the region's last write and
                    // seen here with Acquire; the region is never written again.
                    return Some(unsafe {
                        std::slice::from_raw_parts(self.ptr.add(s.start), s.len)
                    });
                }
                // WRITING: the owner is copying a few kB; TAKEN cannot be seen (one reader).
                Err(_) => {
                    spins += 1;
                    if spins < 1 << 10 {
                        std::hint::spin_loop();
                    } else {
                        std::thread::yield_now();
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_published_slot_is_read_and_an_untouched_one_is_claimed() {
        let slots = [Slot { start: 0, len: 2 }, Slot { start: 2, len: 3 }];
        let mut buffer = vec![0.0; 5];
        let mail = Mailbox::new(&slots, &mut buffer);
        mail.publish(0, |r| r.copy_from_slice(&[1.0, 2.0]));
        assert_eq!(mail.take(0), Some(&[1.0, 2.0][..]));
        assert_eq!(mail.take(1), None);
        // Claimed by its reader: the owner's values are not written.
        mail.publish(1, |r| r.fill(9.0));
        drop(mail);
        assert_eq!(buffer, [1.0, 2.0, 0.0, 0.0, 0.0]);
    }

    #[test]
    fn a_reader_waits_for_a_slot_being_written_on_another_thread() {
        let slots: Vec<Slot> = (0..64)
            .map(|k| Slot {
                start: 4 * k,
                len: 4,
            })
            .collect();
        let mut buffer = vec![0.0; 256];
        let mail = Mailbox::new(&slots, &mut buffer);
        let (got, ()) = rayon::join(
            || {
                (0..64)
                    .map(|k| mail.take(k).map(<[f64]>::to_vec))
                    .collect::<Vec<_>>()
            },
            || (0..64).for_each(|k| mail.publish(k, |r| r.fill(k as f64))),
        );
        // Each slot is either read whole, as published, or claimed by the reader.
        for (k, g) in got.iter().enumerate() {
            if let Some(v) = g {
                assert_eq!(v, &vec![k as f64; 4]);
            }
        }
    }

    #[test]
    fn a_panicking_writer_leaves_the_slot_to_its_reader() {
        let slots = [Slot { start: 0, len: 1 }];
        let mut buffer = vec![0.0; 1];
        let mail = Mailbox::new(&slots, &mut buffer);
        let hit = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            mail.publish(0, |_| panic!("fill failed"))
        }));
        assert!(hit.is_err());
        assert_eq!(mail.take(0), None);
    }

    #[test]
    #[should_panic(expected = "overlap")]
    fn overlapping_slots_are_refused() {
        let slots = [Slot { start: 0, len: 2 }, Slot { start: 1, len: 2 }];
        let mut buffer = vec![0.0; 3];
        let _ = Mailbox::new(&slots, &mut buffer);
    }
}
