//! A software prefetch hint, for the random-access tables of the renderer (photon grid,
//! radiance cache) whose misses dominate a camera sample when nothing else hides them.

/// Asks the CPU to bring the cache line holding `value` into all cache levels. A hint only:
/// it never faults, never changes a result, and does nothing on targets without one.
#[inline(always)]
pub fn prefetch<T>(value: &T) {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: `_mm_prefetch` requires SSE, which every x86_64 target has, and it never
    // dereferences: it may be given any address, and this one is a live reference.
    unsafe {
        use std::arch::x86_64::{_MM_HINT_T0, _mm_prefetch};
        _mm_prefetch::<_MM_HINT_T0>(std::ptr::from_ref(value).cast::<i8>());
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = value;
}
