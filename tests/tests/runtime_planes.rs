//! The simulator's planes are values (`Switchable<Depth16>`,
//! `Switchable<Wid8>`, `RuntimeDither`): a frame it renders equals, byte for
//! byte in colour and depth, the same frame rendered with the planes and
//! dither fixed by type as firmware names them — for random commands of
//! every kind, several formats, planes on and off, every dither.

use proptest::prelude::*;
use tilerast::coverage::Ruf8;
use tilerast::prelude::*;
use tilerast_sim::render::{render_as, AA_GROUPS, SIM_GROUPS};
use tilerast_sim::{render, AaKind, Config, FormatKind, Rendered};
use tilerast_tests::{config, windowed_commands};

/// Random commands of every kind, window IDs 0..3 over two window fills;
/// edge flags cleared (the simulator clears them without area AA).
fn commands(seed: u64) -> Vec<Command> {
    let mut cmds = windowed_commands(seed, 14);
    for c in &mut cmds {
        if let Command::Triangle { v, .. } = c {
            v.iter_mut().for_each(|v| v.edge_flag = false);
        }
    }
    cmds
}

fn cfg(format: FormatKind, depth: bool, wid: bool, dither: u8) -> Config {
    let mut c = config(90, 70, format);
    c.tile = (32, 24);
    c.depth = depth;
    c.wid = wid;
    c.dither = dither;
    c
}

fn same(runtime: &Rendered, fixed: &Rendered) -> Result<(), TestCaseError> {
    prop_assert_eq!(&runtime.raw, &fixed.raw);
    prop_assert_eq!(&runtime.depth, &fixed.depth);
    prop_assert_eq!(runtime.bits_per_pixel, fixed.bits_per_pixel);
    Ok(())
}

/// The simulator's path against `render_as` with the planes fixed by type
/// (`AreaAa`: the simulator's tile without a coverage plane).
macro_rules! check {
    ($cmds:expr, $fmt:ident, $f:ty, $depth:literal $z:ty, $wid:literal $w:ty, $side:literal $d:ty) => {{
        let c = cfg(FormatKind::$fmt, $depth, $wid, $side);
        let runtime = render(&c, $cmds).unwrap();
        let fixed = render_as::<$f, $z, $w, $d, tilerast::area::AreaAa, FullPrecision, SIM_GROUPS>(
            &c, $cmds, 0,
        )
        .unwrap();
        same(&runtime, &fixed)?;
    }};
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(tilerast_tests::cases(16)))]
    #[test]
    fn values_draw_what_types_draw(seed in any::<u64>()) {
        let cmds = &commands(seed);
        check!(cmds, Rgb565, Rgb565Format, true Depth16, true Wid8, 4 Bayer4);
        check!(cmds, Rgb565, Rgb565Format, false NoDepth, false NoWid, 4 Bayer4);
        check!(cmds, Rgb888, Rgb888Format, false NoDepth, false NoWid, 0 NoDither);
        check!(cmds, Binary, BinaryFormat, true Depth16, false NoWid, 16 Bayer<4>);
        check!(cmds, Gray8, Gray8Format, false NoDepth, true Wid8, 8 Bayer8);
        check!(cmds, Rgb444, Rgb444Format, true Depth16, false NoWid, 2 Bayer2);
    }

    #[test]
    fn values_draw_what_types_draw_with_coverage_planes(seed in any::<u64>(), wid in any::<bool>()) {
        let cmds = &commands(seed);
        let mut c = cfg(FormatKind::Rgb565, true, wid, 4);
        c.aa = AaKind::Ruf8;
        let runtime = render(&c, cmds).unwrap();
        let fixed = if wid {
            render_as::<Rgb565Format, Depth16, Wid8, Bayer4, Ruf8, FullPrecision, AA_GROUPS>(&c, cmds, 0)
        } else {
            render_as::<Rgb565Format, Depth16, NoWid, Bayer4, Ruf8, FullPrecision, AA_GROUPS>(&c, cmds, 0)
        }
        .unwrap();
        same(&runtime, &fixed)?;
    }
}

/// A dither side the simulator has no matrix for is refused, not drawn
/// undithered.
#[test]
fn an_unknown_dither_side_is_an_error() {
    for side in [3u8, 5, 32] {
        assert!(render(&cfg(FormatKind::Rgb565, true, false, side), &[]).is_err());
    }
}
