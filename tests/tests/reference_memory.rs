//! Finding 5 of issue 12: `reference --samples 64` on a legal 4096x8 scene
//! needed 4.2 GB. The supersampled reference now works in blocks of at
//! most `SAMPLE_BUDGET` samples; a counting allocator measures its peak.

use std::alloc::{GlobalAlloc, Layout, System};
use std::path::Path;
use std::sync::atomic::{AtomicUsize, Ordering::Relaxed};
use tilerast_sim::{reference, Scene};

struct Counting;
static NOW: AtomicUsize = AtomicUsize::new(0);
static PEAK: AtomicUsize = AtomicUsize::new(0);

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

#[global_allocator]
static A: Counting = Counting;

#[test]
fn reference_samples_64_on_4096x8_is_bounded() {
    let src = "[screen]\nwidth = 4096\nheight = 8\nformat = \"rgb888\"\n\n\
               [[command]]\nkind = \"triangle\"\nv = [[0, 0, 0, 255, 0, 0], [4096, 1, 0, 0, 255, 0], [10, 8, 0, 0, 0, 255]]\n";
    let s = Scene::parse(src, Path::new(".")).unwrap();
    let base = NOW.load(Relaxed);
    PEAK.store(base, Relaxed);
    let r = reference::supersample(&s.config, &s.commands, 64);
    let peak = PEAK.load(Relaxed) - base;
    // 33 bytes per budgeted sample, plus the 4096x8 result.
    let bound = 33 * reference::SAMPLE_BUDGET as usize + 64 * 4096 * 8;
    assert!(peak <= bound, "peak {peak} bytes > {bound}");
    // Blocks join seamlessly: one pixel per block gives the same picture
    // as whole rows.
    let small = src.replace("width = 4096", "width = 40");
    let n = Scene::parse(&small, Path::new(".")).unwrap();
    let rows = reference::supersample_within(&n.config, &n.commands, 8, 1 << 20).to_image();
    let pixels = reference::supersample_within(&n.config, &n.commands, 8, 1).to_image();
    assert!(r.to_image().get(5, 4) != [0, 0, 0]);
    for y in 0..8 {
        for x in 0..40 {
            assert_eq!(rows.get(x, y), pixels.get(x, y), "({x}, {y})");
        }
    }
}
