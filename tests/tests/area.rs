//! Area-sampling antialiasing through the α-channel (seed 001 §IV.5,
//! `tilerast::area`) against the exact area of each pixel a triangle covers.
//!
//! **The bound.** A flagged edge pixel's weight is its exact coverage
//! rounded to 1/256 (at most 0.5/256 off, 0.498 LSB of a full-contrast
//! blend); the blend drops no bit of a flat source (its colour has no
//! fraction) and rounds once (0.5 LSB). Over a flat background in RGB888
//! without dither a pixel is within `AREA_BOUND` = 0.5 · 255/256 + 0.5 +
//! 2^-10 LSB of `coverage · C + (1 - coverage) · C_bg`, coverage computed
//! here independently: the triangle clipped by the pixel square in `f64`.

use proptest::prelude::*;
use tilerast::embedded_graphics_core::pixelcolor::RgbColor;
use tilerast::prelude::*;
use tilerast_sim::{AaKind, FormatKind};
use tilerast_tests::{config, vsub};

const AREA_BOUND: f64 = 0.5 * 255.0 / 256.0 + 0.5 + 1.0 / 1024.0;
const W: u16 = 48;
const H: u16 = 40;

/// Area of convex polygon `poly` (pixels) inside the square of pixel
/// `(px, py)`: the polygon clipped by the square's four sides.
fn area_in_pixel(poly: &[(f64, f64)], px: f64, py: f64) -> f64 {
    let mut p: Vec<(f64, f64)> = poly.to_vec();
    // Each side as (axis, bound, keep >= bound?).
    for (axis, bound, above) in [
        (0, px, true),
        (0, px + 1.0, false),
        (1, py, true),
        (1, py + 1.0, false),
    ] {
        let inside = |q: (f64, f64)| {
            let v = if axis == 0 { q.0 } else { q.1 };
            if above {
                v >= bound
            } else {
                v <= bound
            }
        };
        let mut out = Vec::new();
        for i in 0..p.len() {
            let (a, b) = (p[i], p[(i + 1) % p.len()]);
            if inside(a) {
                out.push(a);
            }
            if inside(a) != inside(b) {
                let (va, vb) = if axis == 0 { (a.0, b.0) } else { (a.1, b.1) };
                let t = (bound - va) / (vb - va);
                out.push((a.0 + (b.0 - a.0) * t, a.1 + (b.1 - a.1) * t));
            }
        }
        p = out;
        if p.len() < 3 {
            return 0.0;
        }
    }
    let twice: f64 = (0..p.len())
        .map(|i| {
            let (a, b) = (p[i], p[(i + 1) % p.len()]);
            a.0 * b.1 - b.0 * a.1
        })
        .sum();
    twice.abs() / 2.0
}

fn px_of(v: &Vertex) -> (f64, f64) {
    (v.x.to_num::<f64>(), v.y.to_num::<f64>())
}

fn rgb(p: u32) -> [f64; 3] {
    [(p >> 16) & 255, (p >> 8) & 255, p & 255].map(|v| v as f64)
}

fn white(x: i64, y: i64) -> Vertex {
    vsub(x, y, 100, [255, 255, 255])
}

/// A triangle well inside the screen (sub-pixel coordinates), not degenerate.
fn triangle() -> impl Strategy<Value = [Vertex; 3]> {
    let c = || (2 * 16..(W as i64 - 2) * 16, 2 * 16..(H as i64 - 2) * 16);
    (c(), c(), c())
        .prop_filter("zero area", |&((ax, ay), (bx, by), (cx, cy))| {
            (bx - ax) * (cy - ay) - (by - ay) * (cx - ax) != 0
        })
        .prop_map(|((ax, ay), (bx, by), (cx, cy))| [white(ax, ay), white(bx, by), white(cx, cy)])
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(tilerast_tests::cases(200)))]

    /// Every pixel of a lone triangle (all its edges are boundaries) over a
    /// flat background is the exact blend by its exact area, within the
    /// bound, through tiles; pixels it does not touch keep the background.
    #[test]
    fn each_pixel_is_its_exact_area(v in triangle(), bg in any::<[u8; 3]>()) {
        let mut c = config(W, H, FormatKind::Rgb888);
        c.aa = AaKind::Area;
        c.tile = (16, 8);
        let fill = Command::fill(Rect::new(0, 0, W as u32, H as u32), Rgb::new(bg[0], bg[1], bg[2]));
        let ours = tilerast_sim::render(&c, &[fill, Command::triangle(v)]).unwrap();
        let poly = v.map(|v| px_of(&v));
        let mut worst = 0.0f64;
        for y in 0..H as usize {
            for x in 0..W as usize {
                let a = area_in_pixel(&poly, x as f64, y as f64);
                let got = rgb(ours.raw[y * W as usize + x]);
                for (g, b) in got.iter().zip(bg) {
                    let want = a * 255.0 + (1.0 - a) * b as f64;
                    worst = worst.max((g - want).abs());
                }
            }
        }
        prop_assert!(worst <= AREA_BOUND, "worst {}", worst);
    }

    /// A tile configured with area sampling draws triangles without edge
    /// flags exactly as a tile without it: Gouraud, depth, any winding.
    #[test]
    fn unflagged_triangles_draw_as_aliased(v in triangle(), c in any::<[[u8; 3]; 3]>(), z in any::<[u16; 3]>()) {
        let v: [Vertex; 3] = core::array::from_fn(|i| Vertex { color: Rgb::new(c[i][0], c[i][1], c[i][2]), z: z[i], ..v[i] });
        type Smooth = Planes<Rgb888Format, Depth16, NoWid, Bayer4, AreaAa>;
        type Plain = Planes<Rgb888Format, Depth16, NoWid, Bayer4, NoAa>;
        let r = Rect::new(0, 0, W as u32, H as u32);
        let mut a: Box<Tile<{ groups(48, 40) }, Smooth>> = Box::default();
        let mut b: Box<Tile<{ groups(48, 40) }, Plain>> = Box::default();
        a.begin(r, &Clear::default()).unwrap();
        b.begin(r, &Clear::default()).unwrap();
        a.draw(&Command::triangle(v)).unwrap();
        b.draw(&Command::triangle(v)).unwrap();
        for y in 0..H as i32 {
            for x in 0..W as i32 {
                prop_assert_eq!(a.raw(x, y), b.raw(x, y));
                prop_assert_eq!(a.depth(x, y), b.depth(x, y));
            }
        }
    }

    /// The tiling cannot change an area-sampled picture.
    #[test]
    fn tiling_changes_nothing(v in triangle(), w in 1u16..20, h in 1u16..20) {
        let mut c = config(W, H, FormatKind::Rgb565);
        c.aa = AaKind::Area;
        c.depth = true;
        c.dither = 4;
        let one = tilerast_sim::render(&c, &[Command::triangle(v)]).unwrap();
        c.tile = (w, h);
        let tiled = tilerast_sim::render(&c, &[Command::triangle(v)]).unwrap();
        prop_assert_eq!(one.raw, tiled.raw);
        prop_assert_eq!(one.depth, tiled.depth);
    }
}

/// A convex polygon cut into a fan of triangles around an inner point: its
/// inner edges are not flagged, so no background shows through them — every
/// pixel whose square lies inside the polygon is exactly the colour — and
/// every pixel its outline crosses, away from the outline's corners, is the
/// polygon's exact area.
#[test]
fn a_fan_is_seamless_and_its_outline_exact() {
    let outline: Vec<(i64, i64)> = [
        (4.3, 6.1),
        (30.7, 3.2),
        (44.1, 20.6),
        (29.9, 36.3),
        (8.2, 30.8),
    ]
    .iter()
    .map(|&(x, y)| ((x * 16.0) as i64, (y * 16.0) as i64))
    .collect();
    let centre = white(22 * 16 + 5, 19 * 16 + 3);
    let n = outline.len();
    let mut cmds: Vec<Command> = (0..n)
        .map(|i| {
            let (a, b) = (outline[i], outline[(i + 1) % n]);
            Command::triangle([centre, white(a.0, a.1), white(b.0, b.1)])
        })
        .collect();
    let mut c = config(W, H, FormatKind::Rgb888);
    c.aa = AaKind::Area;
    c.tile = (16, 16);
    let ours = tilerast_sim::render(&c, &cmds).unwrap();
    // The simulator flags exactly the outline.
    tilerast_sim::mesh::flag_silhouettes(&mut cmds);
    let flags: Vec<[bool; 3]> = cmds
        .iter()
        .map(|c| match c {
            Command::Triangle { v, .. } => v.map(|v| v.edge_flag),
            _ => unreachable!(),
        })
        .collect();
    assert!(
        flags.iter().all(|f| *f == [false, true, false]),
        "{flags:?}"
    );
    let poly: Vec<(f64, f64)> = outline
        .iter()
        .map(|&(x, y)| (x as f64 / 16.0, y as f64 / 16.0))
        .collect();
    let (mut inner, mut edge, mut worst) = (0, 0, 0.0f64);
    for y in 0..H as i64 {
        for x in 0..W as i64 {
            let a = area_in_pixel(&poly, x as f64, y as f64);
            let got = rgb(ours.raw[(y * W as i64 + x) as usize]);
            let corner = poly
                .iter()
                .any(|&(cx, cy)| (cx - x as f64).abs() < 1.5 && (cy - y as f64).abs() < 1.5);
            if a == 1.0 {
                inner += 1;
                assert_eq!(got, [255.0; 3], "seam at ({x}, {y})");
            } else if !corner {
                edge += 1;
                for g in got {
                    worst = worst.max((g - a * 255.0).abs());
                }
            }
        }
    }
    assert!(inner > 600 && edge > 100, "{inner} {edge}");
    assert!(worst <= AREA_BOUND, "worst {worst}");
}

/// Depth: an edge pixel whose centre is inside writes the triangle's depth,
/// one whose centre is outside only tests it; a nearer surface is not
/// blended over.
#[test]
fn depth_is_written_where_the_centre_is_inside() {
    type Smooth = Planes<Rgb888Format, Depth16, NoWid, NoDither, AreaAa>;
    let r = Rect::new(0, 0, 32, 32);
    let mut t: Box<Tile<{ groups(32, 32) }, Smooth>> = Box::default();
    t.begin(r, &Clear::default()).unwrap();
    let v = |x: f64, y: f64| {
        Vertex::new(
            Coord::from_num(x),
            Coord::from_num(y),
            5000,
            Rgb::new(255, 255, 255),
        )
        .with_edge_flag(true)
    };
    // A vertical edge at x = 10.25: column 9's centre (9.5) is outside, column 10's inside.
    let tri = [v(10.25, 0.0), v(10.25, 32.0), v(40.0, 16.0)];
    t.draw(&Command::triangle(tri)).unwrap();
    assert_eq!(t.depth(9, 16), Some(u16::MAX));
    assert_eq!(t.depth(10, 16), Some(5000));
    // Column 10 is three quarters covered, column 9 none of it.
    assert_eq!(t.pixel(10, 16).map(|p| p.r()), Some(191));
    assert_eq!(t.pixel(9, 16).map(|p| p.r()), Some(0));
    // A nearer surface over column 10 keeps its colour.
    let near = Command::Fill {
        rect: Rect::new(0, 0, 32, 32),
        color: Rgb::new(0, 0, 255),
        alpha: 255,
        state: State::default(),
    };
    t.draw(&near).unwrap();
    t.draw(&Command::zfill(Rect::new(0, 0, 32, 32), 100))
        .unwrap();
    t.draw(&Command::triangle(tri)).unwrap();
    assert_eq!(t.pixel(10, 16).map(|p| (p.r(), p.b())), Some((0, 255)));
}

/// Edge flags survive the wire format (tags 15/16), and a triangle without
/// flags keeps its old encoding.
#[test]
fn edge_flags_round_trip_the_wire() {
    let t = |x: i64, f: bool| vsub(x, x / 3, 7, [1, 2, 3]).with_edge_flag(f);
    for (far, flags) in [
        (16, [true, false, true]),
        (40_000, [false, true, false]),
        (16, [false; 3]),
    ] {
        let v = [
            t(far, flags[0]),
            t(2 * far, flags[1]),
            t(far / 2 + 5, flags[2]),
        ];
        let cmd = Command::triangle([
            v[0],
            v[1],
            Vertex {
                y: v[2].y + Coord::from_num(9),
                ..v[2]
            },
        ]);
        let mut buf = [0u8; tilerast::wire::MAX_ENCODED];
        let n = tilerast::wire::encode(&cmd, &mut buf).unwrap();
        assert_eq!(tilerast::wire::decode(&buf[..n]).unwrap(), (cmd, n));
        let plain = if far == 16 { 2 } else { 1 };
        assert_eq!(
            buf[0] & 0x1f,
            if flags.iter().any(|&f| f) {
                plain + 14
            } else {
                plain
            }
        );
    }
}
