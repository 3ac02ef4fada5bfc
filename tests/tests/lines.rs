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
        antialias: false,
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
        antialias: false,
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

fn wu(p0: (i64, i64), p1: (i64, i64)) -> Command {
    let line = LineCmd {
        p0: pt(p0.0, p0.1),
        p1: pt(p1.0, p1.1),
        z: [0, 0],
        color: Rgb::new(255, 255, 255),
        style: LineStyle::SOLID,
        antialias: true,
    };
    Command::Line {
        line,
        state: State::default(),
    }
}

/// A white Wu line on black, RGB888, no dither: the red channel per pixel,
/// and the f64 reference's.
fn wu_frame(cmd: Command, tile: (u16, u16)) -> (Vec<u32>, Vec<f64>) {
    let mut c = config(64, 48, FormatKind::Rgb888);
    c.tile = tile;
    let ours = render(&c, &[cmd]).unwrap();
    let exact = reference::render(&c, &[cmd]);
    (
        ours.raw.iter().map(|p| p >> 16).collect(),
        exact.color.iter().map(|c| c[0]).collect(),
    )
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(tilerast_tests::cases(200)))]
    /// Seed 003 eq. 4: the two pixels of a step share the line's intensity.
    /// Each pixel is within 2.5 LSB of the exact two-point value (the
    /// distance and its product with the coverage are floored to 1/256:
    /// 2/256 of 255; plus 0.5 for rounding). Summed across each column,
    /// intensity equals 255 times the column's coverage along the line
    /// within 2 LSB (the two weights add up to the coverage exactly; each
    /// pixel rounds), at any tiling: no brightening or dimming at the ends
    /// or at tile borders.
    #[test]
    fn wu_intensity_per_step_equals_coverage(
        a in (64i64..960, 64i64..700), b in (64i64..960, 64i64..700), tw in 1u16..64, th in 1u16..48,
    ) {
        let (ours, exact) = wu_frame(wu(a, b), (tw, th));
        for i in 0..ours.len() {
            prop_assert!((ours[i] as f64 - exact[i]).abs() <= 2.5, "pixel {}: {} vs {}", i, ours[i], exact[i]);
        }
        let y_major = (b.1 - a.1).abs() > (b.0 - a.0).abs();
        let (lo, hi) = if y_major { (a.1.min(b.1), a.1.max(b.1)) } else { (a.0.min(b.0), a.0.max(b.0)) };
        for c in 0..if y_major { 48 } else { 64 } {
            let cover = ((hi.min(16 * c + 16) - lo.max(16 * c)).clamp(0, 16)) as f64 / 16.0;
            let sum: u32 = if y_major {
                (0..64).map(|x| ours[(c * 64 + x) as usize]).sum()
            } else {
                (0..48).map(|y| ours[(y * 64 + c) as usize]).sum()
            };
            prop_assert!((sum as f64 - 255.0 * cover).abs() <= 2.0, "column {}: {} vs {}", c, sum, 255.0 * cover);
        }
    }
}

#[test]
fn wu_line_total_intensity_is_its_length() {
    // 10 pixels long, from one pixel centre to another: the end cells are
    // half covered, so the first and last pixels are half bright.
    let (ours, _) = wu_frame(
        wu((16 * 2 + 8, 16 * 5 + 8), (16 * 12 + 8, 16 * 5 + 8)),
        (64, 48),
    );
    let row: Vec<u32> = (0..64).map(|x| ours[5 * 64 + x]).collect();
    assert_eq!(
        &row[2..=12],
        &[128, 255, 255, 255, 255, 255, 255, 255, 255, 255, 128]
    );
    assert_eq!(ours.iter().sum::<u32>(), 9 * 255 + 2 * 128);
    // Half a pixel below the centres: the intensity splits evenly over two rows.
    let (ours, _) = wu_frame(wu((16 * 2, 16 * 5 + 16), (16 * 12, 16 * 5 + 16)), (64, 48));
    assert_eq!((ours[5 * 64 + 6], ours[6 * 64 + 6]), (128, 128));
}
