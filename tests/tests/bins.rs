//! Binning cannot change a pixel: a frame rendered through bins of any
//! capacity — ample, too small for the frame (bands, more passes), too small
//! for one tile (that tile replays the whole list), or none — equals the
//! frame rendered without bins, for display lists in RAM and encoded in
//! flash alike.

use proptest::prelude::*;
use tilerast::prelude::*;
use tilerast::wire::SceneHeader;
use tilerast_sim::Scene;
use tilerast_tests::{frame_raw, random_command, scene, Rng};

type DemoTile = Tile<{ groups(64, 32) }, Planes<Rgb444Format, Depth16, Wid8, Bayer8>>;

#[test]
fn the_demo_from_flash_is_the_same_through_any_bins() {
    let bytes = Scene::load(scene("demo.toml")).unwrap().encode().unwrap();
    let (h, cmds) = SceneHeader::parse(&bytes).unwrap();
    let mut frame = h.frame((64, 32)).unwrap();
    frame.clear = h.clear;
    let (plain, none) = frame_raw::<256, DemoTileConfig, _, 0, 0>(&frame, &cmds);
    assert_eq!((none.bin_passes, none.unbinned_tiles), (0, 32));
    // Ample: one pass.
    let (raw, st) = frame_raw::<256, DemoTileConfig, _, 16384, 32>(&frame, &cmds);
    assert_eq!(raw, plain);
    assert_eq!((st.bin_passes, st.unbinned_tiles), (1, 0));
    assert_eq!(st.replayed, none.replayed, "the same (tile, command) pairs");
    // Too small for the frame: bands, each laid out flat from the
    // overflowing pass's counts, with 16-bit keys (fewer than 2^16
    // commands), so a band holds up to four times the entries.
    let (raw, st) = frame_raw::<256, DemoTileConfig, _, 1024, 32>(&frame, &cmds);
    assert_eq!(raw, plain);
    assert!(st.bin_passes > 2 && st.unbinned_tiles == 0, "{st:?}");
    assert!((2049..=4096).contains(&st.bin_peak), "{st:?}");
    let pairs = st.replayed as usize;
    assert!(
        st.bin_passes as usize <= 1 + pairs.div_ceil(1024),
        "{pairs} pairs in {st:?}"
    );
    // Too small for some tiles alone: those replay the whole list.
    let (raw, st) = frame_raw::<256, DemoTileConfig, _, 64, 4>(&frame, &cmds);
    assert_eq!(raw, plain);
    assert!(st.unbinned_tiles > 0 && st.unbinned_tiles < 32, "{st:?}");
}

type DemoTileConfig = Planes<Rgb444Format, Depth16, Wid8, Bayer8>;

/// Keys of 2^16 and more (a list of 70,000 commands) stay whole in the
/// bands: they are not packed two to a word.
#[test]
fn wide_keys_are_binned_whole() {
    let mut rng = Rng::new(7);
    let cmds: Vec<Command> = (0..70_000u32)
        .map(|k| {
            let (x, y) = ((rng.next_u64() % 64) as i32, (rng.next_u64() % 32) as i32);
            let c = Rgb::new(k as u8, (k >> 8) as u8, (k >> 16) as u8);
            Command::fill(Rect::new(x, y, 1 + k % 3, 1 + k % 2), c)
        })
        .collect();
    let frame = Frame::new(64, 32, 8, 8).unwrap();
    type C = Planes<Rgb888Format, NoDepth, NoWid, NoDither>;
    let (plain, _) = frame_raw::<8, C, _, 0, 0>(&frame, &cmds[..]);
    let (raw, st) = frame_raw::<8, C, _, 8192, 32>(&frame, &cmds[..]);
    assert!(st.bin_passes > 2 && st.unbinned_tiles == 0, "{st:?}");
    assert!(st.bin_peak <= 2 * 8192, "{st:?}");
    assert!(raw == plain, "keys above 2^16 were cut");
}

#[test]
fn the_demo_tile_type_holds_a_demo_tile() {
    assert_eq!(DemoTile::CAPACITY, 64 * 32);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(tilerast_tests::cases(32)))]
    #[test]
    fn random_lists_are_the_same_through_any_bins(seed in any::<u64>(), tw in 1u16..40, th in 1u16..40, n in 0usize..40) {
        let mut rng = Rng::new(seed);
        let cmds: Vec<Command> = (0..n).map(|_| random_command(&mut rng, 0)).collect();
        let frame = Frame::new(100, 80, tw, th).unwrap();
        type C = Planes<Rgb888Format, Depth16, NoWid, Bayer4>;
        let (plain, _) = frame_raw::<200, C, _, 0, 0>(&frame, &cmds[..]);
        let (a, _) = frame_raw::<200, C, _, 4096, 256>(&frame, &cmds[..]);
        let (b, _) = frame_raw::<200, C, _, 7, 3>(&frame, &cmds[..]);
        let (c, _) = frame_raw::<200, C, _, 1, 1>(&frame, &cmds[..]);
        prop_assert_eq!(&a, &plain);
        prop_assert_eq!(&b, &plain);
        prop_assert_eq!(&c, &plain);
    }
}

/// What binning reads of an encoded list (a mesh's triangles from their
/// positions alone) is each command's bounds, in every antialiasing mode
/// and culling mode (a culled triangle has none).
#[test]
fn encoded_bounds_are_the_commands_bounds() {
    for name in ["demo.toml", "area.toml", "ruf.toml", "teapot.toml"] {
        let bytes = Scene::load(scene(name)).unwrap().encode().unwrap();
        let (_, cmds) = SceneHeader::parse(&bytes).unwrap();
        for (cells, area) in [(false, false), (true, false), (false, true)] {
            for cull in [Cull::None, Cull::Back, Cull::Front] {
                let mut want = vec![];
                cmds.each_keyed(|k, c| {
                    let b = if c.culled_by(cull) {
                        None
                    } else if cells || area && c.edge_flagged() {
                        c.coverage_bounds()
                    } else {
                        c.bounds()
                    };
                    want.push((k, b));
                })
                .unwrap();
                let mut got = vec![];
                cmds.each_bounds(cells, area, cull, |k, b| got.push((k, b)))
                    .unwrap();
                assert!(want.len() > 10, "{name}");
                assert_eq!(got, want, "{name} cells {cells} area {area} {cull:?}");
                // The teapot is drawn two-sided: each mode drops some.
                if cull != Cull::None && name == "teapot.toml" {
                    let kept = got.iter().filter(|(_, b)| b.is_some()).count();
                    assert!(kept < want.len(), "{name}: {cull:?} culled nothing");
                }
            }
        }
    }
}

/// Binning a band, an encoded mesh drops a triangle whose rows miss the
/// band before reading its columns (`each_bounds_in`): a command that
/// meets the band keeps its bounds, and one reported `None` misses it.
#[test]
fn encoded_bounds_in_a_band_keep_every_command_that_meets_it() {
    let bytes = Scene::load(scene("demo.toml")).unwrap().encode().unwrap();
    let (_, cmds) = SceneHeader::parse(&bytes).unwrap();
    let mut all = vec![];
    cmds.each_bounds(false, false, Cull::None, |k, b| all.push((k, b)))
        .unwrap();
    for rows in [0..32, 32..96, 100..101, 200..240, -50..0] {
        let mut got = vec![];
        cmds.each_bounds_in(false, false, Cull::None, rows.clone(), |k, b| {
            got.push((k, b))
        })
        .unwrap();
        assert_eq!(got.len(), all.len());
        let mut dropped = 0;
        for (&(k, g), &(k2, w)) in got.iter().zip(&all) {
            assert_eq!(k, k2);
            let meets =
                w.is_some_and(|r| r.y1() > rows.start as i64 && (r.y as i64) < rows.end as i64);
            if meets {
                assert_eq!(g, w, "key {k} rows {rows:?}");
            } else if g.is_none() {
                dropped += 1;
            }
        }
        assert!(dropped > 0, "rows {rows:?}: nothing dropped");
    }
}

/// The encoded demo through bins small enough to take several bands (each
/// binning only the rows it meets) renders exactly as without bins.
#[test]
fn encoded_demo_is_the_same_through_banded_bins() {
    let bytes = Scene::load(scene("demo.toml")).unwrap().encode().unwrap();
    let (h, cmds) = SceneHeader::parse(&bytes).unwrap();
    let frame = h.frame((32, 32)).unwrap();
    type C = Planes<Rgb888Format, Depth16, NoWid, NoDither>;
    let (plain, _) = frame_raw::<{ 32 * 32 / 8 }, C, _, 0, 0>(&frame, &cmds);
    let (banded, stats) = frame_raw::<{ 32 * 32 / 8 }, C, _, 600, 64>(&frame, &cmds);
    assert!(stats.bin_passes >= 3, "{stats:?}");
    assert_eq!(stats.unbinned_tiles, 0);
    assert!(banded == plain, "banded bins changed the frame");
}
