//! A frame rendered in tiles is byte-identical to the same frame rendered as
//! one big tile — for tile sizes that do not divide the screen.

use proptest::prelude::*;
use tilerast::prelude::*;
use tilerast_sim::{render, FormatKind, Scene};
use tilerast_tests::{config, scene, tri, vsub, Rng};

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

fn random_commands(seed: u64, n: usize) -> Vec<Command> {
    let mut rng = Rng::new(seed);
    let mut cmds = vec![
        Command::WidFill {
            rect: Rect::new(0, 0, 50, 40),
            wid: 1,
        },
        Command::WidFill {
            rect: Rect::new(30, 20, 60, 50),
            wid: 2,
        },
    ];
    for _ in 0..n {
        let wid = rng.range(0, 3) as u8;
        let state = State {
            wid,
            plane_mask: if rng.range(0, 4) == 0 {
                0xF0F0F0
            } else {
                u32::MAX
            },
        };
        let c = |rng: &mut Rng| Rgb::new(rng.byte(), rng.byte(), rng.byte());
        cmds.push(match rng.range(0, 4) {
            0 => Command::Fill {
                rect: Rect::new(
                    rng.range(-20, 90) as i32,
                    rng.range(-20, 70) as i32,
                    rng.range(0, 60) as u32,
                    rng.range(0, 40) as u32,
                ),
                color: c(&mut rng),
                state,
            },
            1 => {
                let len = rng.range(0, 150) as u16;
                let span = SpanCmd {
                    x: rng.range(-60, 90) as i32,
                    y: rng.range(-5, 70) as i32,
                    len,
                    color: [ColorFix::from_num(rng.range(0, 256)); 3],
                    dcolor: [ColorStep::ZERO; 3],
                    z: ZFix::from_num(rng.range(0, 65536)),
                    dz: ZStep::ZERO,
                };
                Command::Span { span, state }
            }
            _ => {
                let mut v = || {
                    vsub(
                        rng.range(-400, 1800),
                        rng.range(-400, 1400),
                        rng.range(0, 65536) as u16,
                        [rng.byte(), rng.byte(), rng.byte()],
                    )
                };
                let v = [v(), v(), v()];
                Command::Triangle { v, state }
            }
        });
    }
    cmds
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]
    #[test]
    fn random_frames_are_tile_size_independent(seed in any::<u64>(), tw in 1u16..90, th in 1u16..70, fmt in 0usize..5, dither in prop::sample::select(vec![0u8, 2, 4, 8])) {
        let formats = [FormatKind::Rgb888, FormatKind::Rgb565, FormatKind::Rgb444, FormatKind::Gray8, FormatKind::Binary];
        let mut c = config(90, 70, formats[fmt]);
        c.depth = true;
        c.wid = true;
        c.dither = dither;
        let cmds = random_commands(seed, 12);
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
