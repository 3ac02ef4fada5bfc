//! A counting allocator for memory-bound tests: a test binary installs
//! [`Counting`] as its global allocator, then [`peak_of`] measures the most
//! a closure held allocated at once beyond what was allocated before it.

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering::Relaxed};
use std::sync::Mutex;

/// The system allocator, counting the bytes allocated now and their peak.
///
/// ```ignore
/// #[global_allocator]
/// static A: tilerast_tests::memory::Counting = tilerast_tests::memory::Counting;
/// ```
pub struct Counting;

static NOW: AtomicUsize = AtomicUsize::new(0);
static PEAK: AtomicUsize = AtomicUsize::new(0);
/// One measurement at a time (tests of a binary run on several threads).
static ONE: Mutex<()> = Mutex::new(());

// SAFETY: every call is forwarded unchanged to the system allocator; the
// counters are only statistics.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, l: Layout) -> *mut u8 {
        let n = NOW.fetch_add(l.size(), Relaxed) + l.size();
        PEAK.fetch_max(n, Relaxed);
        // SAFETY: forwarded unchanged to the system allocator.
        unsafe { System.alloc(l) }
    }
    unsafe fn dealloc(&self, p: *mut u8, l: Layout) {
        NOW.fetch_sub(l.size(), Relaxed);
        // SAFETY: `p` came from `alloc` with the same layout.
        unsafe { System.dealloc(p, l) }
    }
}

/// Runs `f` and returns its result and the peak of bytes allocated at once
/// while it ran, beyond those allocated when it started (other threads'
/// allocations count too: measurements are serialised, and a test binary
/// that measures should keep its other tests small).
pub fn peak_of<R>(f: impl FnOnce() -> R) -> (R, usize) {
    let _one = ONE.lock().unwrap_or_else(|e| e.into_inner());
    let base = NOW.load(Relaxed);
    PEAK.store(base, Relaxed);
    let r = f();
    (r, PEAK.load(Relaxed).saturating_sub(base))
}
