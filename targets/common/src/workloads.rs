//! The workloads whose cost the boards report, identical on every target
//! (the commands come from a fixed-seed [`Rng`], at compile time: they live
//! in flash and cost no RAM). Each renders into one [`SIDE`] x [`SIDE`] tile.
//!
//! Pixel counts are a property of the workload, not of the chip: the host
//! computes them once ([`covered_pixels`]) and divides the boards' counts.

use crate::rng::Rng;
use crate::Clock;
use embedded_graphics::{
    prelude::*,
    primitives::{PrimitiveStyle, Triangle},
};
use tilerast::prelude::*;

/// Tile side of every workload (1024 pixels: fits the Cortex-M0's 16 KB).
pub const SIDE: u32 = 32;
/// Triangles per workload.
pub const TRIANGLES: usize = 64;
/// Full-tile fills per workload.
pub const FILLS: usize = 8;
/// Large triangles per workload: pairs that each cover the whole tile.
pub const LARGE_TRIANGLES: usize = 8;
/// Lines per workload.
pub const LINES: usize = 48;

/// Small Gouraud triangles (about 12 px across) with random depth and
/// colours, scattered over the tile.
pub static TRIANGLE_CMDS: [Command; TRIANGLES] = TRIANGLE_CMDS_CONST;
/// The same triangles followed by all their edges, antialiased (seed 003
/// eq. 8): what edge antialiasing adds, at its most (every edge).
pub static EDGE_AA_CMDS: [Command; 4 * TRIANGLES] = with_edges();
/// The same triangles with every edge flagged for area sampling (seed 001
/// §IV.5, [`AreaAaBench`]): what the RE's antialiasing through the
/// α-channel adds, at its most.
pub static AREA_AA_CMDS: [Command; TRIANGLES] = with_edge_flags();
/// Large Gouraud triangles: [`LARGE_TRIANGLES`] / 2 pairs, each pair
/// splitting the whole tile along a diagonal, random colours, each pair
/// nearer than the last (every pixel passes the Z test and is stored: the
/// per-pixel cost of a span, with few rows and setups to share it).
pub static LARGE_TRIANGLE_CMDS: [Command; LARGE_TRIANGLES] = large_triangles(false, false);
/// The same triangles translucent ([`Blend::Alpha`], random opacity per
/// vertex): every pixel passes the Z test and is blended over the last
/// pair — the per-pixel cost of alpha blending beside the opaque one.
pub static LARGE_BLEND_CMDS: [Command; LARGE_TRIANGLES] = large_triangles(true, false);
/// The same triangles quadratically shaded (fast Phong, seed 001 §IV.2:
/// [`Command::Quadratic`] with random edge-midpoint colours), opaque: the
/// per-pixel cost of fast Phong beside Gouraud's.
pub static LARGE_QUAD_CMDS: [Command; LARGE_TRIANGLES] = large_triangles(false, true);
/// The same pairs textured (seed 001 §IV.3): each pair a wall seen at
/// an angle, `q` (`1/w`) falling 4:1 from its left edge to its right,
/// [`TEXTURES`]' 16 x 16 texels across — the per-pixel cost of each
/// perspective mode ([`TexBench`]) beside Gouraud's.
pub static LARGE_TEX_CMDS: [Command; LARGE_TRIANGLES] = large_textured();
/// The workloads' texture: 16 x 16 RGB565 texels in flash, repeating,
/// nearest-filtered.
pub static TEXTURES: [Texture<'static>; 1] =
    [match Texture::new(&TEXELS, 16, 16, TexFormat::Rgb565) {
        Ok(t) => t,
        Err(_) => panic!("16 x 16 RGB565"),
    }];
static TEXELS: [u8; 512] = texels();
/// Full-tile flat fills.
pub static FILL_CMDS: [Command; FILLS] = fills();
/// Lines across the tile in every direction, Bresenham.
pub static LINE_CMDS: [Command; LINES] = lines(false);
/// The same lines, two-point (Wu) antialiased.
pub static WU_LINE_CMDS: [Command; LINES] = lines(true);

/// What the `const` command arrays start as before each slot is written.
const PLACEHOLDER: Command = Command::WidFill {
    rect: Rect::new(0, 0, 0, 0),
    wid: 0,
};

const fn lines(antialias: bool) -> [Command; LINES] {
    let mut rng = Rng::new(0x6c69_6e65_7377_7521);
    let side = SIDE as i64 * 16;
    let mut out = [PLACEHOLDER; LINES];
    let mut i = 0;
    while i < LINES {
        let p = rng.vertex((8, side - 8), (8, side - 8));
        let q = rng.vertex((8, side - 8), (8, side - 8));
        let line = LineCmd {
            p0: (p.x, p.y),
            p1: (q.x, q.y),
            z: [0, 0],
            color: p.color,
            style: LineStyle::SOLID,
            antialias,
        };
        out[i] = Command::Line {
            line,
            state: State::new(0),
        };
        i += 1;
    }
    out
}

/// Line steps (pixels along the major axis) of line commands: what line
/// costs are divided by.
pub fn line_steps(cmds: &[Command]) -> u64 {
    cmds.iter()
        .map(|c| {
            if let Command::Line { line, .. } = c {
                line.steps() as u64
            } else {
                0
            }
        })
        .sum()
}

const fn triangles() -> [Command; TRIANGLES] {
    let mut rng = Rng::new(0x7173_7261_7374_6c69);
    let side = SIDE as i64 * 16;
    let mut out = [PLACEHOLDER; TRIANGLES];
    let mut i = 0;
    while i < TRIANGLES {
        let cx = rng.range(0, side);
        let cy = rng.range(0, side);
        let v = rng.triangle((cx - 100, cx + 100), (cy - 100, cy + 100));
        out[i] = Command::Triangle {
            v,
            state: State::new(0),
        };
        i += 1;
    }
    out
}

const fn corner(x: i32, y: i32, z: u16, rng: &mut Rng) -> Vertex {
    Vertex::new(Coord::from_bits(x), Coord::from_bits(y), z, rng.rgb())
}

/// `[a, b, c]` as a Gouraud triangle, or quadratic with midpoint colours
/// from `rng`.
const fn tri(v: [Vertex; 3], state: State, quad: bool, rng: &mut Rng) -> Command {
    if quad {
        Command::Quadratic {
            alpha: 255,
            v: [
                QuadVertex::new(v[0], rng.rgb()),
                QuadVertex::new(v[1], rng.rgb()),
                QuadVertex::new(v[2], rng.rgb()),
            ],
            state,
        }
    } else {
        Command::Triangle { v, state }
    }
}

const fn large_triangles(blend: bool, quad: bool) -> [Command; LARGE_TRIANGLES] {
    let mut rng = Rng::new(0x6c61_7267_6574_7269);
    let side = SIDE as i32 * 16;
    let mut out = [PLACEHOLDER; LARGE_TRIANGLES];
    let mut i = 0;
    while i < LARGE_TRIANGLES {
        let z = 60000 - 7000 * (i / 2) as u16;
        let (mut a, mut c) = (corner(0, 0, z, &mut rng), corner(side, side, z, &mut rng));
        let (mut b, mut d) = (corner(side, 0, z, &mut rng), corner(0, side, z, &mut rng));
        let mut state = State::new(0);
        if blend {
            state.blend = Blend::Alpha;
            a.alpha = rng.rgb().r;
            b.alpha = rng.rgb().r;
            c.alpha = rng.rgb().r;
            d.alpha = rng.rgb().r;
        }
        out[i] = tri([a, b, c], state, quad, &mut rng);
        out[i + 1] = tri([a, c, d], state, quad, &mut rng);
        i += 2;
    }
    out
}

const fn texels() -> [u8; 512] {
    let mut rng = Rng::new(0x7465_7874_7572_6573);
    let mut out = [0u8; 512];
    let mut i = 0;
    while i < 512 {
        out[i] = rng.byte();
        i += 1;
    }
    out
}

/// A vertex of a [`LARGE_TEX_CMDS`] wall: `q` 4:1 from left to right.
const fn tv(x: i32, y: i32, z: u16, u: u16, v: u16) -> TexVertex {
    TexVertex {
        x: Coord::from_bits(x),
        y: Coord::from_bits(y),
        z,
        u,
        v,
        q: if x == 0 { 65535 } else { 16384 },
    }
}

const fn large_textured() -> [Command; LARGE_TRIANGLES] {
    let side = SIDE as i32 * 16;
    let mut out = [PLACEHOLDER; LARGE_TRIANGLES];
    let mut i = 0;
    while i < LARGE_TRIANGLES {
        let z = 60000 - 7000 * (i / 2) as u16;
        let k = 16 * i as u16;
        let (a, b) = (tv(0, 0, z, k, 0), tv(side, 0, z, k + 256, 0));
        let (c, d) = (tv(side, side, z, k + 256, 256), tv(0, side, z, k, 256));
        out[i] = Command::textured(0, [a, b, c], [255, 200, 160]);
        out[i + 1] = Command::textured(0, [a, c, d], [255, 160, 200]);
        i += 2;
    }
    out
}

const fn with_edges() -> [Command; 4 * TRIANGLES] {
    let mut out = [PLACEHOLDER; 4 * TRIANGLES];
    let mut i = 0;
    while i < TRIANGLES {
        out[i] = TRIANGLE_CMDS_CONST[i];
        if let Command::Triangle { v, state } = TRIANGLE_CMDS_CONST[i] {
            let mut k = 0;
            while k < 3 {
                out[TRIANGLES + 3 * i + k] = Command::Edge {
                    edge: tilerast::line::EdgeCmd::of_triangle(&v, k),
                    state,
                };
                k += 1;
            }
        }
        i += 1;
    }
    out
}

const TRIANGLE_CMDS_CONST: [Command; TRIANGLES] = triangles();

const fn with_edge_flags() -> [Command; TRIANGLES] {
    let mut out = TRIANGLE_CMDS_CONST;
    let mut i = 0;
    while i < TRIANGLES {
        if let Command::Triangle { v, state } = TRIANGLE_CMDS_CONST[i] {
            out[i] = Command::Triangle {
                v: [
                    v[0].with_edge_flag(true),
                    v[1].with_edge_flag(true),
                    v[2].with_edge_flag(true),
                ],
                state,
            };
        }
        i += 1;
    }
    out
}

/// The tile configuration of the area-sampling workload ([`AREA_AA_CMDS`]):
/// the Gouraud + Z workload's with area sampling compiled in.
pub type AreaAaBench = Planes<Rgb565Format, Depth16, NoWid, NoDither, AreaAa>;

const fn fills() -> [Command; FILLS] {
    let mut out = [PLACEHOLDER; FILLS];
    let mut i = 0;
    while i < FILLS {
        let k = i as u8;
        let color = Rgb::new(k * 30, 90, 200 - k * 20);
        out[i] = Command::fill(Rect::new(0, 0, SIDE, SIDE), color);
        i += 1;
    }
    out
}

/// Ticks to clear the tile and draw `cmds` into it, textured triangles
/// with `textures`.
pub fn draw<const N: usize, C: TileConfig>(
    tile: &mut Tile<N, C>,
    cmds: &[Command],
    textures: &[Texture<'_>],
    clock: &mut impl Clock,
) -> Result<u64, Error> {
    tile.begin(Rect::new(0, 0, SIDE, SIDE), &Clear::default())?;
    clock.lap();
    for c in cmds {
        tile.draw_textured(c, textures)?;
    }
    Ok(clock.lap() as u64)
}

/// The tile configuration of the textured workload ([`LARGE_TEX_CMDS`]):
/// RGB565 + Z16, perspective mode `X`.
pub type TexBench<X> = Planes<
    Rgb565Format,
    Depth16,
    NoWid,
    NoDither,
    NoAa,
    FullPrecision,
    NoBlending,
    GouraudShading,
    X,
>;

/// The Gouraud + Z workloads under the plane contract
/// ([`PlaneContract`]): the cost axis of the numeric contracts' trade-off.
pub type PlaneZBench = Planes<Rgb565Format, Depth16, NoWid, NoDither, NoAa, PlaneContract>;

/// The same with window ID and 8x8 dither.
pub type PlaneZWidDitherBench = Planes<Rgb565Format, Depth16, Wid8, Bayer8, NoAa, PlaneContract>;

/// The tile configuration of the translucent workload ([`LARGE_BLEND_CMDS`]):
/// RGB565 + Z16 with blending compiled in.
pub type BlendBench =
    Planes<Rgb565Format, Depth16, NoWid, NoDither, NoAa, FullPrecision, AlphaBlending>;

/// The tile configuration of the fast-Phong workload ([`LARGE_QUAD_CMDS`]):
/// RGB565 + Z16 with quadratic shading compiled in.
pub type QuadBench = Planes<
    Rgb565Format,
    Depth16,
    NoWid,
    NoDither,
    NoAa,
    FullPrecision,
    NoBlending,
    QuadraticShading,
>;

/// Exact Phong's per-pixel arithmetic alone, in back end `S` — no
/// traversal, no Z, so a lower bound of what an exact-Phong span would
/// cost: per pixel the normal is stepped (3 additions), normalised
/// (`inv_sqrt`), lit (ambient + Lambert) and packed to RGB565 into `buf`,
/// over the tile as many times as the large workloads cover it. Returns
/// the ticks and a CRC of `buf`.
pub fn exact_phong<S: tilerast::geometry::Real>(
    buf: &mut [u16],
    clock: &mut impl Clock,
) -> (u64, u32) {
    use tilerast::geometry::dot;
    let q = |v: i64| S::from_q(v, 16);
    let light = [q(26_000), q(36_000), q(40_000)];
    let (ambient, kd) = (q(9_830), [q(204 << 16), q(90 << 16), q(51 << 16)]);
    let (nx, ny) = ([q(700), q(-150), q(90)], [q(-120), q(650), q(40)]);
    clock.lap();
    for pass in 0..(LARGE_TRIANGLES / 2) as i64 {
        let mut row = [q(-11_000 + 300 * pass), q(-10_000), q(60_000)];
        for y in 0..SIDE as usize {
            let mut n = row;
            for x in 0..SIDE as usize {
                let k = dot(n, n).inv_sqrt();
                let d = (dot(n, light) * k).max(S::ZERO);
                let lit = ambient + d;
                let ch = |c: S, bits: u32| {
                    let v = (c * lit).to_fixed(0).unwrap_or(255).clamp(0, 255) as u16;
                    v >> (8 - bits)
                };
                buf[y * SIDE as usize + x] = ch(kd[0], 5) << 11 | ch(kd[1], 6) << 5 | ch(kd[2], 5);
                n = [n[0] + nx[0], n[1] + nx[1], n[2] + nx[2]];
            }
            row = [row[0] + ny[0], row[1] + ny[1], row[2] + ny[2]];
        }
    }
    let t = clock.lap() as u64;
    let crc = buf
        .iter()
        .fold(0u32, |h, &p| h.rotate_left(5) ^ p as u32)
        .wrapping_mul(0x9e37_79b9);
    (t, crc)
}

/// CRC32 of a tile's packed pixels (row-major, each as 4 little-endian
/// bytes): what the boards print after each workload, so the host can check
/// that a workload draws the same bytes there.
pub fn tile_crc<const N: usize, C: TileConfig>(tile: &Tile<N, C>) -> u32 {
    let mut crc = tilerast::hash::Crc32::default();
    for y in 0..SIDE as i32 {
        for x in 0..SIDE as i32 {
            crc.update(&tile.raw(x, y).unwrap_or(0).to_le_bytes());
        }
    }
    crc.finish()
}

/// Ticks to draw the same commands with `embedded-graphics`' own
/// primitives onto the tile as a `DrawTarget`: each triangle as a flat
/// `Triangle` fill (first vertex's colour), each line as a 1-pixel `Line`;
/// vertices rounded to whole pixels.
pub fn eg_primitives<const N: usize, C: TileConfig>(
    tile: &mut Tile<N, C>,
    cmds: &[Command],
    clock: &mut impl Clock,
) -> Result<u64, Error> {
    use embedded_graphics::primitives::Line;
    tile.begin(Rect::new(0, 0, SIDE, SIDE), &Clear::default())?;
    let px =
        |(x, y): (Coord, Coord)| Point::new(x.round().to_num::<i32>(), y.round().to_num::<i32>());
    let color = |c: Rgb| C::Format::to_color(C::Format::pack_rgb(c));
    clock.lap();
    for c in cmds {
        let _ = match c {
            Command::Triangle { v, .. } => {
                let [a, b, d] = v.map(|v| px((v.x, v.y)));
                Triangle::new(a, b, d)
                    .into_styled(PrimitiveStyle::with_fill(color(v[0].color)))
                    .draw(tile)
            }
            Command::Line { line: l, .. } => Line::new(px(l.p0), px(l.p1))
                .into_styled(PrimitiveStyle::with_stroke(color(l.color), 1))
                .draw(tile),
            _ => Ok(()),
        };
    }
    Ok(clock.lap() as u64)
}

/// Pixels the commands cover inside the `side` x `side` square at the
/// origin (at most 64), summed over commands (overdraw included): each is
/// drawn alone, white on black, into an RGB888 tile and counted.
pub fn covered_pixels(cmds: &[Command], side: u32) -> Result<u64, Error> {
    let mut tile: Tile<512, Rgb888Format> = Tile::new();
    let area = Rect::new(0, 0, side, side);
    let mut n = 0;
    for c in cmds {
        let white = match *c {
            Command::Triangle { v, state } => Command::Triangle {
                v: v.map(|v| Vertex {
                    color: Rgb::new(255, 255, 255),
                    ..v
                }),
                state,
            },
            Command::Fill {
                rect, state, alpha, ..
            } => Command::Fill {
                rect,
                color: Rgb::new(255, 255, 255),
                alpha,
                state,
            },
            other => other,
        };
        tile.begin(area, &Clear::default())?;
        tile.draw(&white)?;
        let s = side as i32;
        n += (0..s * s)
            .filter(|i| tile.raw(i % s, i / s) != Some(0))
            .count() as u64;
    }
    Ok(n)
}

/// Counts the pixels drawn into it (within [`SIDE`] x [`SIDE`]).
struct Counter(u64);

impl OriginDimensions for Counter {
    fn size(&self) -> Size {
        Size::new(SIDE, SIDE)
    }
}

impl DrawTarget for Counter {
    type Color = embedded_graphics::pixelcolor::Rgb565;
    type Error = core::convert::Infallible;
    fn draw_iter<I: IntoIterator<Item = Pixel<Self::Color>>>(
        &mut self,
        pixels: I,
    ) -> Result<(), Self::Error> {
        let b = self.bounding_box();
        self.0 += pixels.into_iter().filter(|p| b.contains(p.0)).count() as u64;
        Ok(())
    }
}

/// Pixels `embedded-graphics` fills for the triangles in [`eg_primitives`].
pub fn eg_covered_pixels(cmds: &[Command]) -> u64 {
    let mut c = Counter(0);
    let px = |c: Coord| c.round().to_num::<i32>();
    for cmd in cmds {
        if let Command::Triangle { v, .. } = cmd {
            let [a, b, d] = v.map(|v| Point::new(px(v.x), px(v.y)));
            let style = PrimitiveStyle::with_fill(embedded_graphics::pixelcolor::Rgb565::WHITE);
            let _ = Triangle::new(a, b, d).into_styled(style).draw(&mut c);
        }
    }
    c.0
}
