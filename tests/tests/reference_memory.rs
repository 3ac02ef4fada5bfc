//! Finding 5 of issue 12: `reference --samples 64` on a legal 4096x8 scene
//! needed 4.2 GB. The supersampled reference now works in blocks of at
//! most `SAMPLE_BUDGET` samples; a counting allocator measures its peak.

use std::path::Path;
use tilerast_sim::{reference, Scene};
use tilerast_tests::memory::{peak_of, Counting};

#[global_allocator]
static A: Counting = Counting;

#[test]
fn reference_samples_64_on_4096x8_is_bounded() {
    let src = "[screen]\nwidth = 4096\nheight = 8\nformat = \"rgb888\"\n\n\
               [[command]]\nkind = \"triangle\"\nv = [[0, 0, 0, 255, 0, 0], [4096, 1, 0, 0, 255, 0], [10, 8, 0, 0, 0, 255]]\n";
    let s = Scene::parse(src, Path::new(".")).unwrap();
    let (r, peak) = peak_of(|| reference::supersample(&s.config, &s.commands, 64));
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
