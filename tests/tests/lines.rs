//! Bresenham lines: the core draws exactly the reference's pixels (the pixel
//! containing the ideal line at each pixel centre along the major axis, end
//! point excluded), at every tiling, and behaves at the extremes.

use proptest::prelude::*;
use tilerast::numeric::COORD_LIMIT;
use tilerast::prelude::*;
use tilerast_sim::{reference, render, FormatKind};
use tilerast_tests::config;

fn pt(x: i64, y: i64) -> (Coord, Coord) {
    (Coord::from_bits(x as i32), Coord::from_bits(y as i32))
}

fn line(p0: (i64, i64), p1: (i64, i64), style: LineStyle) -> Command {
    let line = LineCmd {
        p0: pt(p0.0, p0.1),
        p1: pt(p1.0, p1.1),
        z: [1000, 3000],
        color: Rgb::new(255, 255, 255),
        style,
    };
    Command::Line {
        line,
        state: State::default(),
    }
}

/// The pixels a frame of lines lights, in the core and in the reference.
fn lit(w: u16, h: u16, tile: (u16, u16), cmds: &[Command]) -> (Vec<bool>, Vec<bool>, f64) {
    let mut c = config(w, h, FormatKind::Rgb888);
    c.depth = true;
    c.tile = tile;
    let ours = render(&c, cmds).unwrap();
    let exact = reference::render(&c, cmds);
    let mut max_z = 0.0f64;
    for i in 0..ours.depth.len() {
        if ours.raw[i] != 0 && exact.depth[i].is_finite() {
            max_z = max_z.max((ours.depth[i] as f64 - exact.depth[i]).abs());
        }
    }
    (
        ours.raw.iter().map(|&p| p != 0).collect(),
        exact.color.iter().map(|c| c[0] > 0.0).collect(),
        max_z,
    )
}

fn count(v: &[bool]) -> usize {
    v.iter().filter(|&&b| b).count()
}

fn pixels(w: u16, cmds: &[Command], h: u16) -> Vec<(usize, usize)> {
    let (ours, _, _) = lit(w, h, (w, h), cmds);
    (0..ours.len())
        .filter(|&i| ours[i])
        .map(|i| (i % w as usize, i / w as usize))
        .collect()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(tilerast_tests::cases(200)))]
    #[test]
    fn lines_match_the_reference_at_any_tiling(
        p0 in (-3000i64..4000, -3000i64..3000), p1 in (-3000i64..4000, -3000i64..3000),
        pattern in any::<u16>(), scale in 0u8..4, phase in 0u16..64, tw in 1u16..60, th in 1u16..40,
    ) {
        let style = LineStyle { pattern, scale, phase };
        let cmds = [line(p0, p1, style)];
        let (ours, exact, z) = lit(60, 40, (tw, th), &cmds);
        prop_assert_eq!(ours, exact);
        prop_assert!(z <= 0.5 + 1.0 / 1024.0, "Z error {}", z);
    }
}

#[test]
fn axis_aligned_and_diagonal_lines() {
    let c = |x: i64| 16 * x + 8; // pixel centre
                                 // Horizontal through centres: columns 2..9 (end excluded), row 3.
    assert_eq!(
        pixels(
            12,
            &[line((c(2), c(3)), (c(10), c(3)), LineStyle::SOLID)],
            12
        ),
        (2..10).map(|x| (x, 3)).collect::<Vec<_>>()
    );
    // Vertical, drawn upwards: rows 9 down to 3 (the end point, row 2, excluded).
    let mut v = pixels(
        12,
        &[line((c(5), c(9)), (c(5), c(2)), LineStyle::SOLID)],
        12,
    );
    v.sort();
    assert_eq!(v, (3..10).map(|y| (5, y)).collect::<Vec<_>>());
    // 45 degrees: the diagonal.
    let mut d = pixels(
        12,
        &[line((c(1), c(1)), (c(9), c(9)), LineStyle::SOLID)],
        12,
    );
    d.sort();
    assert_eq!(d, (1..9).map(|i| (i, i)).collect::<Vec<_>>());
}

#[test]
fn zero_length_and_single_pixel_lines() {
    assert!(pixels(8, &[line((40, 40), (40, 40), LineStyle::SOLID)], 8).is_empty());
    // Sub-pixel length not reaching a centre: nothing. Starting on a centre
    // (40 = 16 * 2 + 8) or crossing one: one pixel.
    assert!(pixels(8, &[line((41, 40), (46, 40), LineStyle::SOLID)], 8).is_empty());
    assert_eq!(
        pixels(8, &[line((40, 40), (46, 40), LineStyle::SOLID)], 8),
        [(2, 2)]
    );
    assert_eq!(
        pixels(8, &[line((38, 40), (46, 41), LineStyle::SOLID)], 8),
        [(2, 2)]
    );
}

#[test]
fn closed_polyline_draws_each_corner_once() {
    // A square outline as four segments: every pixel of the outline exactly once.
    let c = |x: i64| 16 * x + 8;
    let corners = [
        (c(1), c(1)),
        (c(8), c(1)),
        (c(8), c(6)),
        (c(1), c(6)),
        (c(1), c(1)),
    ];
    let cmds: Vec<Command> = corners
        .windows(2)
        .map(|s| line(s[0], s[1], LineStyle::SOLID))
        .collect();
    let px = pixels(10, &cmds, 8);
    assert_eq!(
        px.len(),
        2 * 7 + 2 * 5,
        "perimeter pixels, no doubles: {px:?}"
    );
    let mut sorted = px.clone();
    sorted.sort();
    sorted.dedup();
    assert_eq!(sorted.len(), px.len());
}

#[test]
fn style_phase_continues_along_a_polyline() {
    // Collinear segments with passed-on phase draw what one line draws.
    let style = LineStyle {
        pattern: 0b0011_1000_1111_0110,
        scale: 2,
        phase: 5,
    };
    let y = 16 * 3 + 8;
    let whole = LineCmd {
        p0: pt(8, y),
        p1: pt(16 * 50 + 8, y),
        z: [0, 0],
        color: Rgb::new(255, 255, 255),
        style,
    };
    let first = LineCmd {
        p1: pt(16 * 17 + 8, y),
        ..whole
    };
    let second = LineCmd {
        p0: first.p1,
        style: LineStyle {
            phase: first.next_phase(),
            ..style
        },
        ..whole
    };
    let st = State::default();
    let a = pixels(
        64,
        &[Command::Line {
            line: whole,
            state: st,
        }],
        8,
    );
    let b = pixels(
        64,
        &[
            Command::Line {
                line: first,
                state: st,
            },
            Command::Line {
                line: second,
                state: st,
            },
        ],
        8,
    );
    assert_eq!(a, b);
    assert!(
        a.len() < 50 && !a.is_empty(),
        "the pattern has gaps: {}",
        a.len()
    );
}

#[test]
fn long_lines_far_outside_clip_like_lines_ending_on_the_screen_edge() {
    // Slope 1/4 from 1000 px left of the screen to 2000 px right of it. Its
    // crossings with x = 0 and x = W lie on the sub-pixel grid, so the same
    // line can be given with its endpoints moved onto the screen edges.
    let (w, h) = (256u16, 64u16);
    let y_at = |x: i64| 16 * 32 + x / 4;
    let far = line(
        (-16 * 1000, y_at(-16 * 1000)),
        (16 * 2256, y_at(16 * 2256)),
        LineStyle::SOLID,
    );
    let near = line((0, y_at(0)), (16 * 256, y_at(16 * 256)), LineStyle::SOLID);
    let a = pixels(w, &[far], h);
    assert_eq!(a, pixels(w, &[near], h));
    // Row floor(32 + c / 4 + 1/8) stays on the 64-row screen for c <= 127.
    assert_eq!(a.len(), 128);
    // A 10,000-pixel line across a 4096-wide screen in tiles: no panic, one
    // pixel per on-screen column.
    let long = line((-16 * 3000, 8), (16 * 7000, 16 * 3 + 8), LineStyle::SOLID);
    let (ours, exact, _) = lit(4096, 4, (1000, 4), &[long]);
    assert_eq!(ours, exact);
    assert_eq!(count(&ours), 4096);
    // Endpoints at the coordinate limits.
    let lim = COORD_LIMIT as i64 * 16;
    let corner = line((-lim, -lim), (lim - 1, lim - 1), LineStyle::SOLID);
    assert_eq!(corner.validate(), Ok(()));
    let (ours, exact, _) = lit(64, 64, (17, 13), &[corner]);
    assert_eq!(ours, exact);
    assert_eq!(count(&ours), 64);
    assert_eq!(
        line((-lim - 1, 0), (0, 0), LineStyle::SOLID).validate(),
        Err(Error::CoordOutOfRange)
    );
}
