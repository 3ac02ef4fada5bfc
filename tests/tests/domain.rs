//! Property tests over the whole documented input domain (the numeric
//! contract, `tilerast::numeric`): triangles in every class — huge (vertices
//! anywhere in the guard band, out to `COORD_LIMIT`), tiny (inside one
//! pixel), slivers, near-collinear, exactly collinear and coincident — spans
//! with any position, length, start and step, and lines with end points
//! anywhere in the domain. The test profile has overflow checks on, so any
//! wrap-around in the pipeline panics and fails the case.
//!
//! Properties: no panic; invalid input is an `Err`, never garbage; a
//! triangle covers exactly the reference's pixel centres with colour and Z
//! within the stated bounds at any tiling (so nothing is written outside the
//! triangle or the tile); nothing is written outside the command's window.

use proptest::prelude::*;
use tilerast::numeric::COORD_LIMIT;
use tilerast::prelude::*;
use tilerast_sim::{reference, render, FormatKind};
use tilerast_tests::{check_triangle, config, tri, vsub, COLOR_BOUND, Z_BOUND};

/// Screen of the properties: 96x64 pixels.
const W: u16 = 96;
const H: u16 = 64;
/// The coordinate domain in sub-pixels: `[-LIM, LIM)`.
const LIM: i64 = COORD_LIMIT as i64 * 16;

fn attrs() -> impl Strategy<Value = ([u16; 3], [[u8; 3]; 3])> {
    // Depths up to 65534: 65535 is the clear value, which no fragment passes.
    (
        prop::array::uniform3(prop_oneof![Just(0u16), Just(65534u16), 0u16..65535]),
        prop::array::uniform3(prop::array::uniform3(prop_oneof![
            Just(0u8),
            Just(255u8),
            any::<u8>()
        ])),
    )
}

fn on_screen() -> impl Strategy<Value = (i64, i64)> {
    (-64i64..(W as i64 * 16 + 64), -64i64..(H as i64 * 16 + 64))
}

/// Vertex positions of one class, in sub-pixels.
fn positions() -> impl Strategy<Value = [(i64, i64); 3]> {
    let anywhere = (-LIM..LIM, -LIM..LIM);
    prop_oneof![
        // Huge: anywhere in the domain, including its exact limits.
        prop::array::uniform3(prop_oneof![
            anywhere.clone(),
            prop::sample::select(vec![
                (-LIM, -LIM),
                (LIM - 1, -LIM),
                (-LIM, LIM - 1),
                (LIM - 1, LIM - 1)
            ]),
        ]),
        // Tiny: inside one pixel.
        (on_screen(), prop::array::uniform3((0i64..16, 0i64..16)))
            .prop_map(|((x, y), d)| d.map(|(dx, dy)| (x + dx, y + dy))),
        // Sliver: the third vertex within 2 sub-pixels of the others' line.
        (
            on_screen(),
            (-LIM / 4..LIM / 4, -LIM / 4..LIM / 4),
            0i64..=1024,
            (-2i64..=2, -2i64..=2)
        )
            .prop_map(|(p, (dx, dy), t, e)| {
                [
                    p,
                    (p.0 + dx, p.1 + dy),
                    (p.0 + dx * t / 1024 + e.0, p.1 + dy * t / 1024 + e.1),
                ]
            }),
        // Collinear (e = 0) and near-collinear (one sub-pixel off).
        (
            on_screen(),
            (-100i64..100, -100i64..100),
            -200i64..200,
            -200i64..200,
            -1i64..=1
        )
            .prop_map(|(p, d, a, b, e)| [
                p,
                (p.0 + a * d.0, p.1 + a * d.1),
                (p.0 + b * d.0 + e, p.1 + b * d.1)
            ]),
        // Coincident vertices.
        (on_screen(), (-LIM..LIM, -LIM..LIM)).prop_map(|(p, q)| [p, p, q]),
        // Ordinary, around the screen.
        prop::array::uniform3(on_screen()),
    ]
}

fn triangle() -> impl Strategy<Value = [Vertex; 3]> {
    (positions(), attrs())
        .prop_map(|(p, (z, c))| [0, 1, 2].map(|i| vsub(p[i].0, p[i].1, z[i], c[i])))
}

fn tiling() -> impl Strategy<Value = (u16, u16)> {
    (1u16..=W, 1u16..=H)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(tilerast_tests::cases(400)))]

    /// Coverage equals the reference's; colour and Z within the contract's
    /// bounds; at any tiling.
    #[test]
    fn triangles_in_every_class_match_the_reference(v in triangle(), tile in tiling()) {
        check_triangle(W, H, tile, v)?;
    }

    /// Inside a window, a triangle draws what it draws without one; outside
    /// it, nothing (colour and depth stay the clear values).
    #[test]
    fn triangles_stay_inside_their_window(v in triangle(), tile in tiling(), win in (0i32..96, 0i32..64, 1u32..96, 1u32..64)) {
        let mut c = config(W, H, FormatKind::Rgb888);
        c.depth = true;
        c.tile = tile;
        let free = render(&c, &[tri(v, 0)]).unwrap();
        c.wid = true;
        let rect = Rect::new(win.0, win.1, win.2, win.3);
        let r = render(&c, &[Command::WidFill { rect, wid: 1 }, tri(v, 1)]).unwrap();
        for i in 0..r.raw.len() {
            let (x, y) = ((i % W as usize) as i32, (i / W as usize) as i32);
            if rect.intersect(&Rect::new(x, y, 1, 1)).is_some() {
                prop_assert_eq!((r.raw[i], r.depth[i]), (free.raw[i], free.depth[i]));
            } else {
                prop_assert_eq!((r.raw[i], r.depth[i]), (0, 65535), "pixel {},{} outside the window", x, y);
            }
        }
    }

    /// Any span: refused with an error, or drawn at any tiling within the
    /// bounds of the f64 reference on its row and nowhere else.
    #[test]
    fn spans_anywhere_are_exact_or_refused(
        x in prop_oneof![-(LIM / 16)..(LIM / 16), -200i64..200],
        y in prop_oneof![-(LIM / 16)..(LIM / 16), -2i64..66],
        len in prop_oneof![any::<u16>(), 0u16..300],
        ramp in prop::array::uniform4((any::<u32>(), any::<i32>(), 0u32..256, 0u32..256)),
        valid in any::<bool>(),
        tile in tiling(),
    ) {
        let last = (len as i64 - 1).max(1);
        // A valid ramp runs from a to b over the span; otherwise raw bits.
        let pick = |(bits, step, a, b): (u32, i32, u32, u32), scale: u32| {
            if valid {
                let (a, b) = (((a * scale) as i64) << 16, ((b * scale) as i64) << 16);
                (a as u32, ((b - a) / last) as i32)
            } else {
                (bits, step)
            }
        };
        let c = [pick(ramp[0], 1), pick(ramp[1], 1), pick(ramp[2], 1)];
        let z = pick(ramp[3], 256);
        let span = SpanCmd {
            x: x as i32,
            y: y as i32,
            len,
            color: c.map(|(a, _)| ColorFix::from_bits(a)),
            dcolor: c.map(|(_, d)| ColorStep::from_bits(d)),
            z: ZFix::from_bits(z.0),
            dz: ZStep::from_bits(z.1),
            alpha: 255,
        };
        let cmd = [Command::Span { span, state: State::default() }];
        let mut cfg = config(W, H, FormatKind::Rgb888);
        cfg.depth = true;
        cfg.tile = tile;
        let ours = render(&cfg, &cmd);
        match span.validate() {
            Err(e) => prop_assert_eq!(ours.err(), Some(e)),
            Ok(()) => {
                let ours = ours.unwrap();
                let exact = reference::render(&cfg, &cmd);
                for i in 0..ours.raw.len() {
                    let (px, py) = ((i % W as usize) as i64, (i / W as usize) as i64);
                    let inside = py == y && px >= x && px < x + len as i64;
                    let written = ours.depth[i] != 65535 || ours.raw[i] != 0;
                    if !inside {
                        prop_assert!(!written, "pixel {},{} outside the span", px, py);
                        continue;
                    }
                    let p = ours.raw[i];
                    for (k, e) in [(p >> 16) & 255, (p >> 8) & 255, p & 255].iter().zip(exact.color[i]) {
                        prop_assert!((*k as f64 - e).abs() <= COLOR_BOUND, "colour {} vs {}", k, e);
                    }
                    // A fragment at 65535 fails the test against the clear value.
                    if exact.depth[i] < 65534.5 {
                        prop_assert!((ours.depth[i] as f64 - exact.depth[i]).abs() <= Z_BOUND);
                    }
                }
            }
        }
    }

    /// Lines with end points anywhere in the domain (and one past it):
    /// refused past it; otherwise the same pixels at any tiling, Bresenham
    /// or Wu, solid or styled.
    #[test]
    fn lines_anywhere_are_tile_independent_or_refused(
        p in prop::array::uniform2(prop_oneof![(-LIM..LIM, -LIM..LIM), (-LIM - 2..LIM + 2, -LIM - 2..LIM + 2), (-200i64..1700, -200i64..1200)]),
        antialias in any::<bool>(),
        pattern in any::<u16>(),
        tile in tiling(),
    ) {
        let pt = |(x, y): (i64, i64)| (Coord::from_bits(x as i32), Coord::from_bits(y as i32));
        let line = LineCmd {
            p0: pt(p[0]),
            p1: pt(p[1]),
            z: [100, 60000],
            color: Rgb::new(255, 200, 100),
            style: LineStyle { pattern, scale: 0, phase: 0 },
            antialias,
        };
        let cmd = [Command::Line { line, state: State::default() }];
        let in_domain = p.iter().all(|&(x, y)| (-LIM..LIM).contains(&x) && (-LIM..LIM).contains(&y));
        prop_assert_eq!(line.validate().is_ok(), in_domain);
        let mut cfg = config(W, H, FormatKind::Rgb565);
        cfg.depth = true;
        let whole = render(&cfg, &cmd);
        cfg.tile = tile;
        let tiled = render(&cfg, &cmd);
        if in_domain {
            let (whole, tiled) = (whole.unwrap(), tiled.unwrap());
            prop_assert_eq!(whole.raw, tiled.raw);
            prop_assert_eq!(whole.depth, tiled.depth);
        } else {
            prop_assert_eq!(whole.err(), Some(Error::CoordOutOfRange));
            prop_assert_eq!(tiled.err(), Some(Error::CoordOutOfRange));
        }
    }
}
