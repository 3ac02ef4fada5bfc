//! The seed's dithering claim, measured: a smooth gradient rendered to 12-bit
//! RGB444 with ordered dither, seen through an 8x8 box blur (an eye at a
//! distance), is closer to the 24-bit render than the undithered 12-bit one.

use tilerast::prelude::*;
use tilerast_sim::{metrics, render, FormatKind};
use tilerast_tests::{config, tri, vsub};

const W: u16 = 160;
const H: u16 = 96;

fn gradient() -> Vec<Command> {
    // Two triangles covering the screen, each corner a different dark-ish
    // colour: slow ramps, the case where 4-bit banding shows.
    let (w, h) = (W as i64 * 16, H as i64 * 16);
    let c = [[10, 40, 90], [120, 60, 20], [30, 150, 60], [200, 180, 40]];
    vec![
        tri(
            [
                vsub(0, 0, 0, c[0]),
                vsub(w, 0, 0, c[1]),
                vsub(0, h, 0, c[2]),
            ],
            0,
        ),
        tri(
            [
                vsub(w, 0, 0, c[1]),
                vsub(w, h, 0, c[3]),
                vsub(0, h, 0, c[2]),
            ],
            0,
        ),
    ]
}

fn blurred(format: FormatKind, dither: u8) -> Vec<[f64; 3]> {
    let mut c = config(W, H, format);
    c.dither = dither;
    c.tile = (32, 32);
    metrics::box_blur(&render(&c, &gradient()).unwrap().image, 8)
}

#[test]
fn dithered_12_bit_is_closer_to_24_bit_after_blur() {
    let truth = blurred(FormatKind::Rgb888, 0);
    let plain = metrics::rms(&blurred(FormatKind::Rgb444, 0), &truth);
    let mut report = format!("RGB444 vs RGB888 after 8x8 box blur, RMS (0..255): none {plain:.3}");
    for n in [2u8, 4, 8] {
        let d = metrics::rms(&blurred(FormatKind::Rgb444, n), &truth);
        report += &format!(", {n}x{n} {d:.3}");
        assert!(
            d < plain,
            "{n}x{n} dither: {d} is not closer than undithered {plain}"
        );
    }
    // Measured: RMS falls from about 3.1 to about 0.5; demand at least 4x.
    let d8 = metrics::rms(&blurred(FormatKind::Rgb444, 8), &truth);
    assert!(d8 < plain / 4.0, "{report}");
    println!("{report}");
}

#[test]
fn saturated_colours_do_not_wrap_under_dither() {
    // Full white and full black in every format and dither: +1 saturates.
    for format in [
        FormatKind::Rgb888,
        FormatKind::Rgb565,
        FormatKind::Rgb444,
        FormatKind::Gray8,
        FormatKind::Binary,
    ] {
        for dither in [0u8, 2, 4, 8, 16] {
            let (w, h) = (W as i64 * 16, H as i64 * 16);
            let mut c = config(W, H, format);
            c.dither = dither;
            for (col, expect) in [([255u8; 3], [255u8; 3]), ([0; 3], [0; 3])] {
                let cmds = vec![tri(
                    [
                        vsub(-16, -16, 0, col),
                        vsub(w + 64, -16, 0, col),
                        vsub(-16, h * 3, 0, col),
                    ],
                    0,
                )];
                let mut c2 = c;
                c2.clear.color = Rgb::new(77, 77, 77);
                let img = render(&c2, &cmds).unwrap().image;
                for y in 0..H as u32 {
                    for x in 0..(W as u32 / 2) {
                        assert_eq!(
                            img.get(x, y),
                            expect,
                            "{format:?} dither {dither} at ({x}, {y})"
                        );
                    }
                }
            }
        }
    }
}
