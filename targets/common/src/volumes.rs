//! The volume workload (seed 002): the seed's "small sphere", 32^3, made
//! and its normals quantised on the device, sliced into 32 view-aligned
//! slices and drawn by normal blending into a 64 x 64 RGB565 frame in
//! 32 x 32 tiles, then by per-slice shading (the baseline), then by normal
//! blending again skipping the bricks the transfer function makes
//! transparent (4-cell bricks, 1 KB of ranges made on the device; the
//! same frame), then skipping the cells it makes transparent (one bit a
//! cell, 4 KB made on the device; the same frame) — each phase timed, the
//! frames hashed so the host can check every bit.

use crate::Clock;
use tilerast::geometry::{Angle, Mat4};
use tilerast::prelude::*;
use tilerast::volume::{
    brick_bytes, sphere, visible_cell_bytes, Compositor, NormalBlending, PerSliceShading, TfPoint,
    Transfer, Volume, VolumeLights, VolumePlane, VolumeStats, VolumeView,
};

/// Volume side, voxels.
pub const VOL_SIDE: u16 = 32;
/// Voxels.
pub const VOXELS: usize = (VOL_SIDE as usize).pow(3);
/// Screen side, pixels.
pub const VOL_SCREEN: u16 = 64;
/// Slices.
pub const VOL_SLICES: u16 = 32;
/// Brick side of the empty-space skipping run, as a shift: 4 cells.
pub const BRICK_SHIFT: u32 = 2;
/// Bytes of brick ranges.
pub const BRICK_BYTES: usize = brick_bytes([VOL_SIDE; 3], BRICK_SHIFT);
/// Bytes of cell bits.
pub const CELL_BYTES: usize = visible_cell_bytes([VOL_SIDE; 3]);
/// The runs [`run`] returns, in order: normal blending, per-slice shading,
/// normal blending skipping transparent bricks, then transparent cells.
pub const MODES: [&str; 4] = [
    "normal_blending",
    "per_slice",
    "normal_bricks",
    "normal_cells",
];
/// Tile side.
const TILE: u16 = 32;
/// Tile capacity, groups of 8 pixels.
const G: usize = (TILE as usize * TILE as usize) / 8;

/// The frame's tile configuration (the ST7789 preset: RGB565, 16-bit Z,
/// 4x4 dither).
pub type VolumeConfig = St7789Config;

/// What one volume frame cost and drew.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct VolumeRun {
    /// Ticks: making the sphere and quantising its normals (once; and
    /// its brick ranges or cell bits, for the runs that skip).
    pub prepare: u32,
    /// Ticks: slicing (once a frame).
    pub setup: u32,
    /// Ticks: phase I (slice, classify, composite), summed over tiles.
    pub phase1: u32,
    /// Ticks: phase II (shade), summed over tiles.
    pub phase2: u32,
    /// Samples and blends.
    pub stats: VolumeStats,
    /// CRC32 of the frame's packed pixels, tile by tile.
    pub crc: u32,
}

/// The transfer function: the sphere's shell, warm colours.
pub fn transfer() -> Result<Transfer, Error> {
    Transfer::from_points(&[
        TfPoint::new(100, 0, Rgb::new(255, 120, 60)),
        TfPoint::new(170, 60, Rgb::new(250, 230, 120)),
        TfPoint::new(230, 200, Rgb::new(255, 255, 255)),
    ])
}

/// Renders the workload four times ([`MODES`]) into `density`, `normals`,
/// `bricks` and `cells` (the volume's RAM: 32 KB, 96 KB, 1 KB and 4 KB).
pub fn run(
    density: &mut [u8; VOXELS],
    normals: &mut [u8; 3 * VOXELS],
    bricks: &mut [u8; BRICK_BYTES],
    cells: &mut [u8; CELL_BYTES],
    clock: &mut impl Clock,
) -> Result<[VolumeRun; 4], Error> {
    clock.lap();
    sphere(VOL_SIDE, density)?;
    Volume::new(density, [VOL_SIDE; 3])?.compute_normals(normals)?;
    let prepare = clock.lap();
    Volume::new(density, [VOL_SIDE; 3])?.compute_bricks(BRICK_SHIFT, bricks)?;
    let prepare_bricks = prepare + clock.lap();
    let tf = transfer()?;
    Volume::new(density, [VOL_SIDE; 3])?.compute_visible_cells(&tf, cells)?;
    let prepare_cells = prepare + clock.lap();
    let vol = Volume::new(density, [VOL_SIDE; 3])?.with_normals(normals)?;
    let model =
        Mat4::<f32>::rotation_y(Angle::degrees(25)).mul(&Mat4::rotation_x(Angle::degrees(-20)));
    let view = Mat4::look_at([0.0, 0.0, 2.0], [0.0; 3], [0.0, 1.0, 0.0])?;
    let proj = Mat4::perspective(Angle::degrees(40), 1.0, 1.0, 3.0)?;
    let lights = VolumeLights::new(&model, &[([0.4f32, 0.6, 1.0], 0.8)], 0.2)?;
    let screen = Rect::new(0, 0, VOL_SCREEN as u32, VOL_SCREEN as u32);
    clock.lap();
    let scene: VolumeView<'_, { VOL_SLICES as usize }> =
        VolumeView::new(vol, &tf, &model, &view, &proj, screen, VOL_SLICES)?;
    let setup = clock.lap();
    let sliced = |v| -> Result<VolumeView<'_, { VOL_SLICES as usize }>, Error> {
        VolumeView::new(v, &tf, &model, &view, &proj, screen, VOL_SLICES)
    };
    let skipping = sliced(vol.with_bricks(bricks, BRICK_SHIFT)?)?;
    let culling = sliced(vol.with_visible_cells(cells)?)?;
    let mut tile: Tile<G, VolumeConfig> = Tile::new();
    let normal = frame(&mut tile, &scene, &NormalBlending, &lights, clock)?;
    let per_slice = frame(&mut tile, &scene, &PerSliceShading(&lights), &lights, clock)?;
    let bricked = frame(&mut tile, &skipping, &NormalBlending, &lights, clock)?;
    let celled = frame(&mut tile, &culling, &NormalBlending, &lights, clock)?;
    let with = |r: VolumeRun, prepare| VolumeRun {
        prepare,
        setup,
        ..r
    };
    Ok([
        with(normal, prepare),
        with(per_slice, prepare),
        with(bricked, prepare_bricks),
        with(celled, prepare_cells),
    ])
}

#[inline(never)]
fn frame<M: Compositor>(
    tile: &mut Tile<G, VolumeConfig>,
    scene: &VolumeView<'_, { VOL_SLICES as usize }>,
    comp: &M,
    lights: &VolumeLights,
    clock: &mut impl Clock,
) -> Result<VolumeRun, Error> {
    let frame = Tile::<G, VolumeConfig>::frame::<TILE, TILE>(VOL_SCREEN, VOL_SCREEN)?;
    let mut plane: VolumePlane<G, M::Cell> = VolumePlane::new();
    let mut run = VolumeRun::default();
    let mut crc = tilerast::hash::Crc32::default();
    frame
        .render_with(tile, &[][..], |t| {
            clock.lap();
            run.stats += plane.composite(t, scene, comp);
            run.phase1 += clock.lap();
            plane.shade(t, comp, lights);
            run.phase2 += clock.lap();
            let a = t.area();
            for y in a.y..a.y + a.h as i32 {
                for x in a.x..a.x + a.w as i32 {
                    crc.update(&t.raw(x, y).unwrap_or(0).to_le_bytes());
                }
            }
            Ok::<(), Error>(())
        })
        .map_err(|e| match e {
            FlushError::Raster(e) | FlushError::Target(e) => e,
            _ => Error::Malformed,
        })?;
    run.crc = crc.finish();
    Ok(run)
}
