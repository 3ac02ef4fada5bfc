//! A frame rendered in tiles is byte-identical to the same frame rendered as
//! one big tile — for tile sizes that do not divide the screen.

use proptest::prelude::*;
use tilerast::prelude::*;
use tilerast_sim::{render, FormatKind, Scene};
use tilerast_tests::{config, scene, tri, vsub, windowed_commands, Rng};

#[test]
fn demo_scene_is_tile_size_independent() {
    let s = Scene::load(scene("demo.toml")).unwrap();
    let mut whole = s.config;
    whole.tile = (whole.width, whole.height);
    let reference = render(&whole, &s.commands).unwrap();
    for tile in [(64, 32), (37, 23), (1, 240), (240, 1), (7, 241), (100, 100)] {
        let mut c = s.config;
        c.tile = (tile.0.min(c.width), tile.1.min(c.height));
        let r = render(&c, &s.commands).unwrap();
        assert_eq!(r.raw, reference.raw, "tile {tile:?}");
        assert_eq!(r.depth, reference.depth, "tile {tile:?}");
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(tilerast_tests::cases(24)))]
    #[test]
    fn random_frames_are_tile_size_independent(seed in any::<u64>(), tw in 1u16..90, th in 1u16..70, fmt in 0usize..5, dither in prop::sample::select(vec![0u8, 2, 4, 8])) {
        let formats = [FormatKind::Rgb888, FormatKind::Rgb565, FormatKind::Rgb444, FormatKind::Gray8, FormatKind::Binary];
        let mut c = config(90, 70, formats[fmt]);
        c.depth = true;
        c.wid = true;
        c.dither = dither;
        let cmds = windowed_commands(seed, 12);
        let whole = render(&c, &cmds).unwrap();
        c.tile = (tw, th);
        let tiled = render(&c, &cmds).unwrap();
        prop_assert_eq!(&tiled.raw, &whole.raw);
        prop_assert_eq!(&tiled.depth, &whole.depth);
    }
}

#[test]
fn a_triangle_far_beyond_the_screen_is_clipped_per_tile() {
    // Covers the whole guard band; every screen pixel is inside.
    let lim = 8191 * 16;
    let cmds = [tri(
        [
            vsub(-lim, -lim, 100, [255; 3]),
            vsub(lim, -lim, 100, [255; 3]),
            vsub(0, lim, 100, [255; 3]),
        ],
        0,
    )];
    let mut c = config(64, 48, FormatKind::Rgb888);
    c.tile = (13, 11);
    let r = render(&c, &cmds).unwrap();
    assert!(r.raw.iter().all(|&p| p == 0xFFFFFF));
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(tilerast_tests::cases(64)))]
    /// Flat triangles in a tile without Z, window ID or dither take the
    /// slice-fill rows (one packed colour, no row start per row, the host's
    /// overlapping block stores): they cover the pixels, in the colour, that
    /// the per-pixel loop of a tile with a Z plane draws, every fragment
    /// passing (each triangle nearer than the last). Horizontal edges,
    /// slivers, triangles beyond the tile on any side, tiles anywhere.
    #[test]
    fn flat_triangles_fill_what_the_pixel_loop_draws(seed in any::<u64>(), tx in -40i32..40, ty in -40i32..40) {
        type Flat = Tile<{ groups(48, 40) }, Rgb565Format>;
        type Deep = Tile<{ groups(48, 40) }, Planes<Rgb565Format, Depth16>>;
        let mut rng = Rng::new(seed);
        let area = Rect::new(tx, ty, 48, 40);
        let (mut flat, mut deep) = (Box::<Flat>::default(), Box::<Deep>::default());
        flat.begin(area, &Clear::default()).unwrap();
        deep.begin(area, &Clear::default()).unwrap();
        for i in 0..12u16 {
            let c = [rng.byte(), rng.byte(), rng.byte()];
            let mut p = [(); 3].map(|_| (rng.range(-80 * 16, 130 * 16), rng.range(-80 * 16, 120 * 16)));
            if rng.byte() < 64 {
                p[1].1 = p[0].1; // a horizontal edge
            }
            let cmd = tri(p.map(|(x, y)| vsub(x, y, 60000 - 1000 * i, c)), 0);
            flat.draw(&cmd).unwrap();
            deep.draw(&cmd).unwrap();
        }
        prop_assert!(flat.colors().eq(deep.colors()));
    }
}
