//! Alpha blending (seed 001 §IV.4, `tilerast::command::Blend`) against the
//! exact blend, and its depth rules.
//!
//! **The bound.** The weight is `round(256 α / 255)` in 1/256, off the exact
//! `α` by at most `(0.5 + 1/255) / 256`, which moves a blend of colours
//! `|C_src - C_dst| <= 255` apart by at most 0.502 LSB; dropping 8 of the
//! difference's 16 fraction bits costs under 2^-8 LSB; the interpolated
//! source and weight drift by the Gouraud bound's 2^-5 + 2^-10 at most;
//! then the result is rounded (0.5). Over a destination the core holds
//! exactly (a flat fill, 8-bit channels), a translucent fragment is within
//! `BLEND_BOUND` = 0.502 + 2^-8 + 2^-5 + 2^-10 + 0.5 ≈ 1.04 LSB of the f64
//! reference's `α C_src + (1 - α) C_dst`.

use proptest::prelude::*;
use tilerast::prelude::*;
use tilerast_sim::{Config, FormatKind};
use tilerast_tests::{config, vsub};

const BLEND_BOUND: f64 = 0.502 + 1.0 / 256.0 + 1.0 / 32.0 + 1.0 / 1024.0 + 0.5;

fn cfg(depth: bool) -> Config {
    let mut c = config(64, 48, FormatKind::Rgb888);
    c.depth = depth;
    c.tile = (24, 16);
    c
}

fn rgb(p: u32) -> [f64; 3] {
    [(p >> 16) & 255, (p >> 8) & 255, p & 255].map(|v| v as f64)
}

/// Largest channel error of the core against the f64 reference, over the
/// pixels `only` selects.
fn max_error(c: &Config, cmds: &[Command]) -> f64 {
    let ours = tilerast_sim::render(c, cmds).unwrap();
    let exact = tilerast_sim::reference::render(c, cmds);
    let mut max = 0.0f64;
    for (i, p) in ours.raw.iter().enumerate() {
        for (g, e) in rgb(*p).iter().zip(exact.color[i]) {
            max = max.max((g - e).abs());
        }
    }
    max
}

fn background(c: [u8; 3]) -> Command {
    Command::fill(Rect::new(0, 0, 64, 48), Rgb::new(c[0], c[1], c[2]))
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(tilerast_tests::cases(200)))]

    /// A translucent fill over a flat background: the exact blend of two
    /// flat colours, within the bound, on every pixel; α = 255 replaces and
    /// α = 0 keeps the background, exactly.
    #[test]
    fn translucent_fill_is_the_exact_blend(bg in any::<[u8; 3]>(), fg in any::<[u8; 3]>(), alpha in any::<u8>()) {
        let glass = Command::Fill { rect: Rect::new(3, 2, 50, 40), color: Rgb::new(fg[0], fg[1], fg[2]), alpha, state: State::default() }.blend(Blend::Alpha);
        let c = cfg(false);
        let err = max_error(&c, &[background(bg), glass]);
        prop_assert!(err <= BLEND_BOUND, "error {} > {}", err, BLEND_BOUND);
        let ours = tilerast_sim::render(&c, &[background(bg), glass]).unwrap();
        let inside = rgb(ours.raw[10 * 64 + 10]);
        if alpha == 255 {
            prop_assert_eq!(inside, fg.map(|v| v as f64));
        }
        if alpha == 0 {
            prop_assert_eq!(inside, bg.map(|v| v as f64));
        }
    }

    /// Translucent Gouraud triangles with per-vertex opacity over a flat
    /// background, tiled: colour and opacity interpolated, within the bound.
    #[test]
    fn translucent_triangle_is_within_bound(
        bg in any::<[u8; 3]>(),
        p in prop::array::uniform3((-200i64..1200, -200i64..900)),
        c in any::<[[u8; 3]; 3]>(),
        a in any::<[u8; 3]>(),
        z_write in any::<bool>(),
    ) {
        let v = core::array::from_fn(|k| vsub(p[k].0, p[k].1, 100, c[k]).with_alpha(a[k]));
        let mode = if z_write { Blend::AlphaZWrite } else { Blend::Alpha };
        let glass = Command::triangle(v).blend(mode);
        let err = max_error(&cfg(true), &[background(bg), glass]);
        prop_assert!(err <= BLEND_BOUND, "error {} > {}", err, BLEND_BOUND);
    }

    /// A translucent span (constant α) over a flat background.
    #[test]
    fn translucent_span_is_within_bound(bg in any::<[u8; 3]>(), alpha in any::<u8>(), x in -20i32..60, len in 1u16..90) {
        let span = SpanCmd {
            x, y: 7, len,
            color: [ColorFix::from_num(200), ColorFix::from_num(10), ColorFix::from_num(0)],
            dcolor: [ColorStep::from_num(-2), ColorStep::from_num(2.5), ColorStep::from_num(0.125)],
            z: ZFix::from_num(10), dz: ZStep::ZERO, alpha,
        };
        let err = max_error(&cfg(true), &[background(bg), Command::span(span).blend(Blend::Alpha)]);
        prop_assert!(err <= BLEND_BOUND, "error {} > {}", err, BLEND_BOUND);
    }
}

fn quad(z: u16, color: [u8; 3], alpha: u8) -> [Command; 2] {
    let v = |x: i64, y: i64| vsub(x * 16, y * 16, z, color).with_alpha(alpha);
    [
        Command::triangle([v(4, 4), v(40, 4), v(4, 30)]),
        Command::triangle([v(40, 4), v(40, 30), v(4, 30)]),
    ]
}

fn pixel(cmds: &[Command]) -> [u8; 3] {
    let img = tilerast_sim::render(&cfg(true), cmds).unwrap().image;
    img.get(20, 16)
}

#[test]
fn depth_rules_of_translucent_commands() {
    let bg = background([0, 0, 255]);
    let glass = |mode| quad(100, [255, 0, 0], 128).map(|c| c.blend(mode));
    let wall = quad(200, [0, 255, 0], 255);
    // `Alpha` tests Z but does not write it: an opaque wall drawn after it,
    // behind it, still covers the pixel.
    let mut cmds = vec![bg];
    cmds.extend(glass(Blend::Alpha));
    cmds.extend(wall);
    assert_eq!(pixel(&cmds), [0, 255, 0]);
    // `AlphaZWrite` writes it: the wall behind is hidden, the blend stays.
    let mut cmds = vec![bg];
    cmds.extend(glass(Blend::AlphaZWrite));
    cmds.extend(wall);
    assert_eq!(pixel(&cmds), [128, 0, 127]);
    // Behind an opaque surface a translucent one is not drawn at all.
    let mut cmds = vec![bg];
    cmds.extend(quad(50, [9, 9, 9], 255));
    cmds.extend(glass(Blend::Alpha));
    assert_eq!(pixel(&cmds), [9, 9, 9]);
    // In front of it, it blends over it (back to front).
    let mut cmds = vec![bg];
    cmds.extend(wall);
    cmds.extend(glass(Blend::Alpha));
    assert_eq!(pixel(&cmds), [128, 127, 0]);
}

#[test]
fn opaque_commands_ignore_alpha() {
    let bg = background([0, 0, 255]);
    let mut solid = vec![bg];
    solid.extend(quad(100, [255, 0, 0], 255));
    let mut clear = vec![bg];
    clear.extend(quad(100, [255, 0, 0], 0));
    let c = cfg(true);
    assert_eq!(
        tilerast_sim::render(&c, &solid).unwrap().raw,
        tilerast_sim::render(&c, &clear).unwrap().raw
    );
}

#[test]
fn alpha_costs_no_command_bytes() {
    // Opacity lives in the padding of `Vertex`, `SpanCmd` and the fill;
    // the blend mode in `State`'s: blending added no byte to a command (60
    // before and after it). The textured triangle (a tag, texture index,
    // opacity, three shades, three 16-byte `TexVertex` and the 8-byte
    // `State`) made it 64; the same on 64-bit hosts and on the Cortex-M
    // (no field is pointer-sized).
    assert_eq!(core::mem::size_of::<Vertex>(), 16);
    assert_eq!(core::mem::size_of::<State>(), 8);
    assert_eq!(core::mem::size_of::<SpanCmd>(), 44);
    assert_eq!(core::mem::size_of::<Command>(), 64);
}

#[test]
fn blend_error_over_every_alpha_and_background() {
    // Every opacity over every background level (a 0..=255 ramp drawn by
    // a span: exact integers), for sources at both ends and between: the
    // largest error against the exact blend, before and after rounding.
    let mut c = config(256, 1, FormatKind::Rgb888);
    c.tile = (64, 1);
    let ramp = SpanCmd {
        x: 0,
        y: 0,
        len: 256,
        color: [ColorFix::ZERO; 3],
        dcolor: [ColorStep::ONE; 3],
        z: ZFix::ZERO,
        dz: ZStep::ZERO,
        alpha: 255,
    };
    let mut max = 0.0f64;
    for fg in [0u8, 1, 77, 128, 200, 254, 255] {
        for alpha in 0..=255u8 {
            let glass = Command::Fill {
                rect: Rect::new(0, 0, 256, 1),
                color: Rgb::new(fg, fg, fg),
                alpha,
                state: State::default(),
            }
            .blend(Blend::Alpha);
            let ours = tilerast_sim::render(&c, &[Command::span(ramp), glass]).unwrap();
            for (bg, p) in ours.raw.iter().enumerate() {
                let a = alpha as f64 / 255.0;
                let exact = a * fg as f64 + (1.0 - a) * bg as f64;
                max = max.max((rgb(*p)[0] - exact).abs());
            }
        }
    }
    println!("blend error over every α and background: {max:.4} LSB (bound {BLEND_BOUND:.4})");
    assert!(max <= BLEND_BOUND);
}

#[test]
fn tiles_without_alpha_blending_draw_translucent_commands_opaque() {
    use tilerast::fragment::AlphaBlending;
    type Plain = Planes<Rgb888Format, Depth16>;
    type Glass = Planes<Rgb888Format, Depth16, NoWid, NoDither, NoAa, FullPrecision, AlphaBlending>;
    let v = |x: i32, y: i32| {
        Vertex::new(
            Coord::from_num(x),
            Coord::from_num(y),
            5,
            Rgb::new(255, 0, 0),
        )
        .with_alpha(100)
    };
    let glass = Command::triangle([v(0, 0), v(16, 0), v(0, 16)]).blend(Blend::Alpha);
    let bg = Command::fill(Rect::new(0, 0, 16, 16), Rgb::new(0, 0, 255));
    let mut plain: Tile<32, Plain> = Tile::new();
    let mut blended: Tile<32, Glass> = Tile::new();
    plain
        .begin(Rect::new(0, 0, 16, 16), &Clear::default())
        .unwrap();
    blended
        .begin(Rect::new(0, 0, 16, 16), &Clear::default())
        .unwrap();
    for cmd in [bg, glass] {
        plain.draw(&cmd).unwrap();
        blended.draw(&cmd).unwrap();
    }
    assert_eq!(plain.raw(2, 2), Some(0xFF0000));
    assert_eq!(blended.raw(2, 2), Some(0x64009B));
}
