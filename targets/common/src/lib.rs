//! # tilerast-fw
//!
//! The application side of tilerast firmware, shared by every board under
//! `targets/` and by the host, so that the host can compute exactly what a
//! board must output:
//!
//! - [`run_scene`]: replay an encoded scene (a [`wire`](tilerast::wire) header and its
//!   commands, typically `include_bytes!` in flash) tile by tile, draw a text
//!   label on each tile with `embedded-graphics` (the tile is a
//!   `DrawTarget`), and flush each tile to any `DrawTarget` — measuring
//!   raster and flush time with a caller-supplied clock.
//! - [`workloads`]: the fixed workloads whose cost per pixel the boards
//!   report (flat fill, Gouraud with and without Z, window ID and dither,
//!   and `embedded-graphics`' own triangle fill for comparison).
//! - [`anim`]: an animated gauge flushed by partial updates (only the
//!   tiles that changed), with the bytes it saves.
//! - [`spin`]: a mesh rotating under the on-device geometry stage, frame
//!   by frame, with the vertex stage and the raster timed apart.
//! - [`volumes`]: a density volume drawn by normal blending and by
//!   per-slice shading (seed 002), phases timed apart.
//! - [`city`]: a city walked through by a camera, drawn with occlusion
//!   culling (seed 004) in each mode, frames hashed.
//! - [`rng`]: the deterministic PRNG those workloads (and the host tests)
//!   use.
//! - [`report`]: the lines a firmware prints (scene CRCs, workload ticks),
//!   computable on the host too.
//! - [`examples`]: what the real-board examples draw each frame (the host
//!   renders the same frames against the emulated RP2040's panels).
//! - `panel` (feature): what the ST7789 board examples share.
//! - `board` (feature, with a port: `cortex-m` or `riscv`): the runtime
//!   side — instruction clock, report output, stack high-water mark.
#![no_std]
#![deny(missing_docs)]
#![cfg_attr(not(feature = "board"), forbid(unsafe_code))]

pub mod anim;
#[cfg(feature = "board")]
pub mod board;
pub mod city;
pub mod examples;
#[cfg(feature = "panel")]
pub mod panel;
pub mod report;
pub mod rng;
pub mod spin;
pub mod volumes;
pub mod workloads;

use embedded_graphics::{
    mono_font::{ascii::FONT_6X10, MonoTextStyle},
    prelude::*,
    text::{Baseline, Text},
};
use tilerast::prelude::*;
use tilerast::wire::SceneHeader;

/// A clock: each call returns the ticks elapsed since the previous call.
/// Boards wrap SysTick; the host passes `|| 0`.
pub trait Clock {
    /// Ticks since the last call.
    fn lap(&mut self) -> u32;
}

impl<F: FnMut() -> u32> Clock for F {
    fn lap(&mut self) -> u32 {
        self()
    }
}

/// What rendering one scene did and cost.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct SceneRun {
    /// Binning and replay counts.
    pub stats: FrameStats,
    /// Pixels on screen.
    pub pixels: u32,
    /// Ticks spent clearing tiles and rasterizing commands.
    pub raster_ticks: u64,
    /// Ticks spent drawing the label and flushing tiles.
    pub flush_ticks: u64,
}

/// Error of [`run_scene`]: the raster core's, or the display's.
pub type RunError<E> = FlushError<E>;

/// Renders an encoded scene into tiles of `tile` size with a tile buffer of
/// configuration `C` (checked against the scene header) and `bins`, draws `label` (if
/// any) at the top left of the screen on every tile, and flushes each tile to
/// `target`.
pub fn run_scene<const N: usize, C, T, const BC: usize, const BT: usize>(
    scene: &[u8],
    tile_buf: &mut Tile<N, C>,
    bins: &mut Bins<BC, BT>,
    tile: (u16, u16),
    label: Option<&str>,
    target: &mut T,
    clock: &mut impl Clock,
) -> Result<SceneRun, RunError<T::Error>>
where
    C: TileConfig,
    T: DrawTarget,
    T::Color: From<<C::Format as PixelFormat>::Color>,
{
    let (header, cmds) = SceneHeader::parse(scene)?;
    header.check::<C>()?;
    let frame = header.frame(tile)?;
    let white = C::Format::to_color(C::Format::pack_rgb(Rgb::new(255, 255, 255)));
    let mut run = SceneRun {
        pixels: header.width as u32 * header.height as u32,
        ..SceneRun::default()
    };
    clock.lap();
    let stats = frame.render_binned(tile_buf, bins, &cmds, |t| {
        run.raster_ticks += clock.lap() as u64;
        if let Some(text) = label {
            let style = MonoTextStyle::new(&FONT_6X10, white);
            let text = Text::with_baseline(text, Point::new(6, 4), style, Baseline::Top);
            // Only where the label is: drawn into every tile, its glyphs
            // cost the micro:bit's demo frame 1.6 M instructions (measured).
            let area: embedded_graphics::primitives::Rectangle = t.area().into();
            if !text.bounding_box().intersection(&area).is_zero_sized() {
                let _ = text.draw(t);
            }
        }
        let r = t.flush(target);
        run.flush_ticks += clock.lap() as u64;
        r
    })?;
    run.stats = stats;
    Ok(run)
}

/// Ticks of rendering an encoded scene *until* each phase ([`Phase`]), in
/// pipeline order (bin, clear, decode, setup, traverse, all): cumulative, so
/// a phase's own cost is the difference with the one before. Nothing is
/// flushed; `run_scene` measures the flush.
pub fn phase_ticks<const N: usize, C: TileConfig, const BC: usize, const BT: usize>(
    scene: &[u8],
    tile_buf: &mut Tile<N, C>,
    bins: &mut Bins<BC, BT>,
    tile: (u16, u16),
    clock: &mut impl Clock,
) -> Result<[u64; 6], Error> {
    let (header, cmds) = SceneHeader::parse(scene)?;
    header.check::<C>()?;
    let frame = header.frame(tile)?;
    let mut out = [0; 6];
    let phases = [
        Phase::Bin,
        Phase::Clear,
        Phase::Decode,
        Phase::Setup,
        Phase::Traverse,
        Phase::All,
    ];
    for (o, phase) in out.iter_mut().zip(phases) {
        clock.lap();
        frame
            .render_until(phase, tile_buf, bins, &cmds, |_| Ok::<(), ()>(()))
            .map_err(|e| match e {
                FlushError::Raster(e) => e,
                // The hook above never fails.
                _ => Error::BadSize,
            })?;
        *o = clock.lap() as u64;
    }
    Ok(out)
}
