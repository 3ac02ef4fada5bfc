//! An animated scene for partial updates: a gauge — a static dial of
//! Gouraud triangles with a needle sweeping over it — rendered frame after
//! frame into 64x32 tiles, each tile flushed only when it changed
//! ([`Damage`]): found after drawing, from the tile's pixels
//! ([`Changes::Output`]), or before, from its commands, so that unchanged
//! tiles are not drawn either ([`Changes::Input`],
//! [`Frame::render_changed`]). The report compares the bytes sent to the
//! panel and the instructions with and without ([`run`]); the host test
//! checks the panel ends each frame equal to a full refresh.

use crate::Clock;
use tilerast::prelude::*;

/// Screen side.
pub const SIDE: u16 = 240;
/// Tile size.
pub const TILE: (u16, u16) = (64, 32);
/// Frames of the animation.
pub const FRAMES: u32 = 24;
/// The tile type: RGB565, 16-bit Z, as on an ST7789.
pub type AnimTile = Tile<{ groups(64, 32) }, Planes<Rgb565Format, Depth16>>;
/// Tiles per frame.
pub const TILES: usize = 4 * 8;

/// `sin` and `cos` of `k / 64` turns, in 1/4096 (Bhaskara's approximation,
/// integer only: the same on every chip).
pub const fn sin_cos(k: u32) -> (i32, i32) {
    const fn sin(k: u32) -> i32 {
        // Bhaskara I: sin(x) ~ 16x(pi - x) / (5 pi^2 - 4x(pi - x)), x in [0, pi].
        let k = k % 64;
        let (k, sign) = if k >= 32 { (k - 32, -1) } else { (k, 1) };
        let p = (k * (32 - k)) as i32; // x (pi - x) in (pi/32)^2 units
        sign * 4096 * 16 * p / (5 * 32 * 32 - 4 * p)
    }
    (sin(k), sin(k + 16))
}

fn vtx(x: i32, y: i32, z: u16, c: [u8; 3]) -> Vertex {
    Vertex::new(
        Coord::from_bits(x),
        Coord::from_bits(y),
        z,
        Rgb::new(c[0], c[1], c[2]),
    )
}

/// Frame `k`'s commands: the dial (12 Gouraud wedges, depth 40000) and
/// the needle at angle `k` (depth 1000).
pub fn frame_commands(k: u32) -> [Command; 13] {
    let c = 16 * 120; // centre, sub-pixels
    let mut out = [Command::fill(Rect::new(0, 0, 0, 0), Rgb::default()); 13];
    for (i, o) in out.iter_mut().take(12).enumerate() {
        let (s0, c0) = sin_cos(16 * i as u32 / 3);
        let (s1, c1) = sin_cos(16 * (i as u32 + 1) / 3);
        let r = 100 * 16;
        let tint = (i * 20) as u8;
        *o = Command::triangle([
            vtx(c, c, 40000, [30, 30, 40]),
            vtx(c + r * c0 / 4096, c + r * s0 / 4096, 40000, [200, tint, 60]),
            vtx(c + r * c1 / 4096, c + r * s1 / 4096, 40000, [60, tint, 200]),
        ]);
    }
    let (s, co) = sin_cos(k);
    let (len, half) = (90 * 16, 5 * 16);
    out[12] = Command::triangle([
        vtx(
            c + len * co / 4096,
            c + len * s / 4096,
            1000,
            [255, 255, 255],
        ),
        vtx(
            c - half * s / 4096,
            c + half * co / 4096,
            1000,
            [255, 40, 0],
        ),
        vtx(
            c + half * s / 4096,
            c - half * co / 4096,
            1000,
            [255, 40, 0],
        ),
    ]);
    out
}

/// How a frame finds the tiles to send.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Changes {
    /// Every tile is drawn; a tile is sent when its pixels' hash differs
    /// from the last one sent ([`Damage::changed`]).
    Output,
    /// A tile is drawn only when its commands' hash differs from the last
    /// frame's ([`Frame::render_changed`]), and a drawn tile is sent only
    /// when its pixels changed too (a second [`Damage`]: a command can
    /// enter a tile's bins without covering a pixel of it).
    Input,
}

/// What the animation sent and cost.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct AnimRun {
    /// Tiles of all frames (drawn or not).
    pub tiles: u32,
    /// Tiles drawn over all frames.
    pub drawn: u32,
    /// Tiles sent (changed) over all frames.
    pub sent_tiles: u32,
    /// Bytes a full refresh of every frame sends.
    pub bytes_full: u64,
    /// Bytes the partial updates sent.
    pub bytes_sent: u64,
    /// Ticks rendering (including the change test).
    pub ticks: u64,
}

/// Renders [`FRAMES`] frames, calling `send(tile)` for each tile that
/// changed since it was last sent, found as `changes` says.
pub fn run(
    tile: &mut AnimTile,
    clock: &mut impl Clock,
    changes: Changes,
    mut send: impl FnMut(&AnimTile),
) -> Result<AnimRun, Error> {
    let frame = AnimTile::frame::<64, 32>(SIDE, SIDE)?;
    let mut bins: Bins<256, TILES> = Bins::new();
    let (mut damage, mut sent): (Damage<TILES>, Damage<TILES>) = (Damage::new(), Damage::new());
    let mut run = AnimRun::default();
    // A full refresh of one frame: its tiles and their panel bytes.
    let (count, full) = frame.tiles().fold((0, 0), |(n, b), a| {
        (n + 1, b + AnimTile::panel_len(a.w, a.h) as u64)
    });
    for k in 0..FRAMES {
        let cmds = frame_commands(k);
        clock.lap();
        let mut done = |t: &mut AnimTile, sent: bool| {
            run.drawn += 1;
            if sent {
                run.sent_tiles += 1;
                run.bytes_sent += AnimTile::panel_len(t.area().w, t.area().h) as u64;
                send(t);
            }
            Ok::<(), ()>(())
        };
        match changes {
            Changes::Output => frame.render_binned(tile, &mut bins, &cmds[..], |t| {
                let sent = damage.changed(&frame, t);
                done(t, sent)
            }),
            Changes::Input => frame.render_changed(tile, &mut bins, &cmds[..], &mut damage, |t| {
                let changed = sent.changed(&frame, t);
                done(t, changed)
            }),
        }
        .map_err(|e| match e {
            FlushError::Raster(e) => e,
            _ => Error::BadSize,
        })?;
        run.ticks += clock.lap() as u64;
        run.tiles += count;
        run.bytes_full += full;
    }
    Ok(run)
}
