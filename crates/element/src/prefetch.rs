//! Cache-line hints spread over an element's tangent product.
//!
//! An owner-computes assembly (`nonlin3d-assembly`) adds each element's tangent into a global
//! sparse matrix right after evaluating it; at 100 k DOF that matrix (56 MB) is far larger than
//! the caches and every element's adds wait on a few hundred lines from L3 or DRAM. Issuing
//! those lines as prefetches between the register blocks of Σ TᵀT (thesis eq. 2.3.3), a few
//! per block, lets the FMA-bound product hide the memory latency of the adds that follow.
//! The hints change no result: a prefetch never faults and writes nothing.

/// The cache lines to bring in while one element is evaluated: `base + offset` (in `f64`s) for
/// each offset, a few after each register block of the tangent product. The addresses are
/// never dereferenced, only prefetched, so any `base` is safe; only speed depends on it.
#[derive(Clone, Copy, Debug)]
pub struct Prefetch<'a> {
    base: *const f64,
    offsets: &'a [u32],
}

impl Prefetch<'static> {
    /// No hints.
    pub const NONE: Self = Self {
        base: std::ptr::null(),
        offsets: &[],
    };
}

impl<'a> Prefetch<'a> {
    /// Hints for the lines holding `base[offset]` for each of `offsets`, in the given order.
    pub fn new(base: *const f64, offsets: &'a [u32]) -> Self {
        Self { base, offsets }
    }

    /// Number of hints.
    pub fn len(&self) -> usize {
        self.offsets.len()
    }

    /// Whether there are no hints.
    pub fn is_empty(&self) -> bool {
        self.offsets.is_empty()
    }

    /// Issues hints `from..to` (clamped to the list): the kernel spreads them over the
    /// tangent product; a caller may issue a list itself (`issue(0, usize::MAX)`) ahead of
    /// work that does not go through the kernel.
    #[inline(always)]
    pub fn issue(&self, from: usize, to: usize) {
        let to = to.min(self.offsets.len());
        for &o in self.offsets.get(from..to).unwrap_or(&[]) {
            prefetch_line(self.base.wrapping_add(o as usize));
        }
    }
}

/// Brings the cache line holding `*p` towards the core (a hint: `p` is never dereferenced,
/// any address is safe, only speed depends on it). For the scattered lookups of an assembly
/// (column starts, force entries) issued one element before they are needed.
#[inline(always)]
pub fn prefetch_line<T>(p: *const T) {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: a prefetch has no architectural effect and never faults, whatever the address
    // (Intel SDM and AMD APM, PREFETCHh); SSE is part of x86-64.
    unsafe {
        use std::arch::x86_64::{_MM_HINT_T0, _mm_prefetch};
        _mm_prefetch::<_MM_HINT_T0>(p.cast());
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = p;
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hints_at_any_address_are_harmless() {
        let offsets = [0u32, 7, 1 << 30, u32::MAX];
        let wild = Prefetch::new(std::ptr::null(), &offsets);
        wild.issue(0, 10);
        let v = [1.0f64; 8];
        let near = Prefetch::new(v.as_ptr(), &offsets[..2]);
        near.issue(1, 2);
        assert_eq!(
            (wild.len(), near.len(), Prefetch::NONE.is_empty()),
            (4, 2, true)
        );
        assert_eq!(v, [1.0; 8]);
    }
}
