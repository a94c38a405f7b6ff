//! Software prefetch of a value's bytes into the caches, ahead of its use.
//!
//! The assembly reads each element's data once per iteration, behind a pointer the
//! hardware prefetchers cannot follow; asking for the next elements' lines while one is
//! evaluated hides the memory latency once the model outgrows the caches.

/// The most lines asked for per value (1 kB): a larger value's first lines only.
const MAX_LINES: usize = 16;

/// Asks for the cache lines of `value` (a hint: no effect on results, none on other
/// targets than x86-64).
#[inline(always)]
pub fn prefetch<T: ?Sized>(value: &T) {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{_MM_HINT_T0, _mm_prefetch};
        let start = value as *const T as *const u8 as usize;
        let end = start + std::mem::size_of_val(value);
        let mut line = start & !63;
        for _ in 0..MAX_LINES {
            if line >= end {
                break;
            }
            // SAFETY: prefetching is a hint; it does not fault on any address.
            unsafe { _mm_prefetch::<_MM_HINT_T0>(line as *const i8) };
            line += 64;
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = value;
}
