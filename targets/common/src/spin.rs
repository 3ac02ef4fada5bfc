//! A rotating, lit mesh drawn on the device: the geometry stage
//! ([`tilerast::geometry`]) transforms, clips, culls and lights a mesh read
//! in place from flash every frame, and the frame pipeline bins and
//! rasterizes it in small tiles. The same code runs on the host, so the
//! host computes the CRC each board must print for each frame.
//!
//! Two subjects:
//! - the teapot (6,320 triangles, exported by the simulator as a
//!   model-space mesh) on the Cortex-M4F in `f32`, RGB565 + Z16 at 240x240
//!   in 64x32 tiles (8 KB);
//! - a cube built here ([`cube`]) on the Cortex-M0 in fixed point.

use crate::Clock;
use embedded_graphics::prelude::{DrawTarget, Size};
use tilerast::frame::CommandSource;
use tilerast::geometry::{
    Angle, DrawOptions, DrawStats, Lighting, Mat4, Mesh, Real, Scene, VertexSlot,
};
use tilerast::hash::CrcTarget;
use tilerast::prelude::*;

/// Screen side, pixels.
pub const SIDE: u16 = 240;
/// The tile's planes: RGB565 + 16-bit Z, as on an ST7789.
pub type SpinConfig = Planes<Rgb565Format, Depth16, NoWid, NoDither, NoAa, PlaneContract>;
/// Background.
pub const BACKGROUND: Rgb = Rgb::new(16, 24, 48);

/// What one frame cost and did.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct SpinFrame {
    /// CRC32 of the frame's pixel stream.
    pub crc: u32,
    /// Ticks of the vertex stage (transform, cull, light).
    pub vertex_ticks: u64,
    /// Ticks of binning and rasterizing.
    pub raster_ticks: u64,
    /// Ticks of handing the finished tiles to the target (the CRC
    /// "flush" on the boards), counted apart as the peers' figures have
    /// none.
    pub flush_ticks: u64,
    /// What the geometry stage did.
    pub geometry: DrawStats,
    /// What the frame pipeline did.
    pub frame: FrameStats,
}

/// The model rotation of frame `k` of `frames`: a full turn about `y`
/// over the animation, tilted 20° towards the viewer.
pub fn rotation<S: Real>(k: u32, frames: u32) -> Mat4<S> {
    let turn = ((k as u64 * 65536) / frames.max(1) as u64) as u16;
    Mat4::rotation_x(Angle::degrees(20)).mul(&Mat4::rotation_y(Angle::from_turn_q16(turn)))
}

/// The animation's scene over `slots`: the camera 3 units away on `z`,
/// 40° field of view, one white light from the upper right, ambient 0.2.
fn stage<S: Real>(slots: &mut [VertexSlot]) -> Result<Scene<'_, S, 1>, Error> {
    let q = |v: i32| S::from_q(v as i64, 8); // 1/256 units
    let mut scene = Scene::new(slots);
    scene.set_camera(
        Mat4::look_at([q(0), q(0), q(3 * 256)], [q(0); 3], [q(0), q(256), q(0)])?,
        Mat4::perspective(Angle::degrees(40), S::ONE, q(256), q(5 * 256))?,
    );
    scene.set_viewport(Rect::new(0, 0, SIDE as u32, SIDE as u32))?;
    scene.set_lighting(Lighting::white([q(102), q(154), q(256)], q(51))?);
    Ok(scene)
}

/// Renders frame `k` of `frames` of `mesh` with back end `S` in tiles of
/// `tile` (at most `8 N` pixels), bins of `BC` entries, and flushes each
/// tile to `target` (a CRC on the boards, a panel, or a PNG on the host).
#[allow(clippy::too_many_arguments)]
pub fn frame_into<S, const N: usize, const BC: usize, const BT: usize, T>(
    mesh: &Mesh<'_>,
    slots: &mut [VertexSlot],
    tile_buf: &mut Tile<N, SpinConfig>,
    bins: &mut Bins<BC, BT>,
    tile: (u16, u16),
    (k, frames): (u32, u32),
    target: &mut T,
    clock: &mut impl Clock,
) -> Result<SpinFrame, FlushError<T::Error>>
where
    S: Real,
    T: DrawTarget<Color = <Rgb565Format as PixelFormat>::Color>,
{
    let mut out = SpinFrame::default();
    clock.lap();
    let mut scene = stage::<S>(slots)?;
    out.geometry = scene
        .draw(mesh, &rotation(k, frames), &DrawOptions::default())
        .map_err(Error::from)?;
    out.vertex_ticks = clock.lap() as u64;
    let mut frame = Frame::new(SIDE, SIDE, tile.0, tile.1)?;
    frame.clear.color = BACKGROUND;
    let (mut raster, mut flush) = (0, 0);
    out.frame = frame.render_binned(tile_buf, bins, &scene, |t| {
        raster += clock.lap() as u64;
        let r = t.flush(target);
        flush += clock.lap() as u64;
        r
    })?;
    out.raster_ticks = raster + clock.lap() as u64;
    out.flush_ticks = flush;
    Ok(out)
}

/// Frame `k` of `frames` as [`frame_into`] renders it, each finished tile
/// discarded: the pipeline alone, vertex stage included (the host times
/// the firmware's frame with it: `tilerast-lab frames`). `each`, when
/// given, receives every command the frame draws (the f64 reference draws
/// the same triangles).
pub fn frame_discard<S: Real, const N: usize, const BC: usize, const BT: usize>(
    mesh: &Mesh<'_>,
    slots: &mut [VertexSlot],
    tile_buf: &mut Tile<N, SpinConfig>,
    bins: &mut Bins<BC, BT>,
    tile: (u16, u16),
    (k, frames): (u32, u32),
    each: Option<&mut dyn FnMut(&Command)>,
) -> Result<FrameStats, Error> {
    let mut scene = stage::<S>(slots)?;
    scene.draw(mesh, &rotation(k, frames), &DrawOptions::default())?;
    if let Some(f) = each {
        scene.each(|c| f(c))?;
    }
    let mut frame = Frame::new(SIDE, SIDE, tile.0, tile.1)?;
    frame.clear.color = BACKGROUND;
    frame
        .render_binned(tile_buf, bins, &scene, |_| Ok::<(), ()>(()))
        .map_err(|e| match e {
            FlushError::Raster(e) => e,
            // The discarding target never fails.
            _ => Error::BadSize,
        })
}

/// The vertex stage alone for frame `k` of `frames`, nothing hashed or
/// drawn (the host's timing of it).
pub fn vertex_only<S: Real>(
    mesh: &Mesh<'_>,
    slots: &mut [VertexSlot],
    (k, frames): (u32, u32),
) -> Result<DrawStats, Error> {
    let mut scene = stage::<S>(slots)?;
    Ok(scene.draw(mesh, &rotation(k, frames), &DrawOptions::default())?)
}

/// The vertex stage alone for frame `k` of `frames`: what it did, its
/// ticks, and an FNV-1a hash of every triangle it emits (positions, depths,
/// colours) — the geometry stage's output, checked bit for bit against the
/// host without rasterizing.
pub fn vertex_stage<S: Real>(
    mesh: &Mesh<'_>,
    slots: &mut [VertexSlot],
    (k, frames): (u32, u32),
    clock: &mut impl Clock,
) -> Result<(DrawStats, u64, u32), Error> {
    clock.lap();
    let mut scene = stage::<S>(slots)?;
    let st = scene.draw(mesh, &rotation(k, frames), &DrawOptions::default())?;
    let ticks = clock.lap() as u64;
    let mut h: u32 = 0x811c_9dc5;
    let mut eat = |v: u32| {
        for b in v.to_le_bytes() {
            h = (h ^ b as u32).wrapping_mul(0x0100_0193);
        }
    };
    scene.each_keyed(|key, c| {
        eat(key);
        if let Command::Triangle { v, .. } = c {
            for v in v {
                eat(v.x.to_bits() as u32);
                eat(v.y.to_bits() as u32);
                eat(v.z as u32 | (v.color.r as u32) << 16 | (v.color.g as u32) << 24);
                eat(v.color.b as u32);
            }
        }
    })?;
    Ok((st, ticks, h))
}

/// [`frame_into`] a CRC of the pixel stream ([`SpinFrame::crc`]).
#[allow(clippy::too_many_arguments)]
pub fn frame<S: Real, const N: usize, const BC: usize, const BT: usize>(
    mesh: &Mesh<'_>,
    slots: &mut [VertexSlot],
    tile_buf: &mut Tile<N, SpinConfig>,
    bins: &mut Bins<BC, BT>,
    tile: (u16, u16),
    k: u32,
    frames: u32,
    clock: &mut impl Clock,
) -> Result<SpinFrame, Error> {
    let mut target =
        CrcTarget::<<Rgb565Format as PixelFormat>::Color>::new(Size::new(SIDE as u32, SIDE as u32));
    let mut out = frame_into::<S, N, BC, BT, _>(
        mesh,
        slots,
        tile_buf,
        bins,
        tile,
        (k, frames),
        &mut target,
        clock,
    )
    .map_err(|e| match e {
        FlushError::Raster(e) => e,
        _ => Error::BadSize,
    })?;
    out.crc = target.crc();
    Ok(out)
}

/// Bytes of the [`cube`] mesh.
pub const CUBE_BYTES: usize = tilerast::geometry::CUBE_BYTES;

/// The cube the M0 turns: [`Mesh::cube`].
pub fn cube(buf: &mut [u8; CUBE_BYTES]) -> Result<Mesh<'_>, Error> {
    Mesh::cube(buf)
}

/// Renders `frames` frames of `mesh` with back end `S` and calls `report`
/// with each; the first error ends the run.
pub fn run<S: Real, const N: usize, const BC: usize, const BT: usize>(
    mesh: &Mesh<'_>,
    slots: &mut [VertexSlot],
    tile: (u16, u16),
    frames: u32,
    clock: &mut impl Clock,
    mut report: impl FnMut(u32, &SpinFrame),
) -> Result<(), Error> {
    let mut tile_buf: Tile<N, SpinConfig> = Tile::new();
    let mut bins: Bins<BC, BT> = Bins::new();
    for k in 0..frames {
        let f = frame::<S, N, BC, BT>(
            mesh,
            slots,
            &mut tile_buf,
            &mut bins,
            tile,
            k,
            frames,
            clock,
        )?;
        report(k, &f);
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_cube_turns_and_both_back_ends_draw_it() {
        let mut buf = [0u8; CUBE_BYTES];
        let mesh = cube(&mut buf).unwrap();
        let mut slots = [VertexSlot::EMPTY; 24];
        let mut crcs = [0u32; 2];
        run::<f32, { 32 * 32 / 8 }, 256, 64>(&mesh, &mut slots, (32, 32), 2, &mut || 0, |k, f| {
            assert!(f.geometry.front >= 2 && f.geometry.front <= 6, "{f:?}");
            crcs[k as usize] = f.crc;
        })
        .unwrap();
        assert_ne!(crcs[0], crcs[1], "the cube moves");
        run::<tilerast::geometry::Fx, { 32 * 32 / 8 }, 256, 64>(
            &mesh,
            &mut slots,
            (32, 32),
            1,
            &mut || 0,
            |_, f| assert!(f.geometry.front >= 2, "{f:?}"),
        )
        .unwrap();
    }
}
