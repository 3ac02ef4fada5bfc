//! The frame loop of the Raspberry Pi ST7789 examples, one source for both
//! chips: `rp2040-hal` and `rp235x-hal` have the same DMA and SPI API, so
//! `targets/rp-pico2-st7789` includes this file with its own `hal`.
//!
//! Each frame the geometry stage turns the lit cube and the frame pipeline
//! renders it in 60x40 tiles (RGB565 + 16-bit Z + 4x4 dither, 9.6 KB),
//! each sent by **DMA while the next tile renders**: two 4.8 KB byte
//! buffers ping-pong — tile k+1 is rendered and packed
//! (`Tile::panel_bytes`: big-endian RGB565) while tile k streams out — and
//! the panel's memory is the front buffer. Errors are logged over
//! `defmt`, never discarded into a black screen; frames per second too.

use super::hal;
use embedded_hal::digital::OutputPin;
use embedded_hal::spi::SpiBus;
use hal::dma::{single_buffer, Channel, CH0};
use tilerast::geometry::{Angle, Mesh, Real, Scene, VertexSlot, CUBE_BYTES};
use tilerast::prelude::*;
use tilerast_fw::examples::cube::{self, camera, turn, Panel, TILE_BYTES};
use tilerast_fw::panel::window;
/// One ping-pong buffer.
type Buf = &'static mut [u8; TILE_BYTES];

/// The DMA link to the panel: idle, or sending a buffer.
enum Link<S: hal::dma::WriteTarget<TransmittedWord = u8>> {
    Idle(Channel<CH0>, S),
    Busy(single_buffer::Transfer<Channel<CH0>, Buf, S>),
}

/// Runs the cube forever: `ch` and `bus` are the DMA channel and the SPI
/// bus the panel was initialised on (chip select held low), `dc` its
/// data/command pin, `micros` a microsecond clock; `R` the geometry back
/// end (`Fx` without an FPU, `f32` with one).
pub fn run<R: Real, B, D>(ch: Channel<CH0>, bus: B, mut dc: D, mut micros: impl FnMut() -> u64) -> !
where
    B: hal::dma::WriteTarget<TransmittedWord = u8> + SpiBus,
    D: OutputPin,
{
    let mut link = Some(Link::Idle(ch, bus));
    let mut next: Option<Buf> = cortex_m::singleton!(: [u8; TILE_BYTES] = [0; TILE_BYTES]);
    let mut spare: Option<Buf> = cortex_m::singleton!(: [u8; TILE_BYTES] = [0; TILE_BYTES]);
    defmt::info!("ST7789 ready; {} bytes of renderer", Panel::BYTES);

    // 60x40 tiles (a window the panel takes per DMA transfer).
    let mut renderer = cube::renderer().unwrap();
    let mut mesh_buf = [0u8; CUBE_BYTES];
    let cube = Mesh::cube(&mut mesh_buf).unwrap();
    let mut slots = [VertexSlot::EMPTY; 24];
    let mut scene: Scene<'_, R> = Scene::new(&mut slots);
    if let Err(e) = camera(&mut scene) {
        defmt::error!("camera: {}", e);
    }
    let mut angle = Angle::default();
    let mut frames = 0u32;
    let mut since = micros();
    loop {
        // Errors are reported, never discarded into a black screen.
        let drawn = turn(&mut scene, &cube, angle)
            .map_err(FlushError::Raster)
            .and_then(|()| {
                renderer.render(&scene, |t| {
                    // Pack tile k+1 while tile k is still streaming out...
                    let buf = next
                        .take()
                        .or_else(|| spare.take())
                        .ok_or("no free buffer")?;
                    t.panel_bytes(&mut buf[..])
                        .map_err(|_| "tile larger than a buffer")?;
                    // ... then wait for it, and send this one.
                    let (ch, mut bus) = match link.take().ok_or("DMA link lost")? {
                        Link::Idle(ch, bus) => (ch, bus),
                        Link::Busy(tr) => {
                            let (ch, done, bus) = tr.wait();
                            next = Some(done);
                            (ch, bus)
                        }
                    };
                    window(&mut bus, &mut dc, t.area()).map_err(|_| "SPI error")?;
                    link = Some(Link::Busy(single_buffer::Config::new(ch, buf, bus).start()));
                    Ok::<(), &'static str>(())
                })
            });
        match drawn {
            Ok(_) => frames += 1,
            Err(FlushError::Raster(e)) => defmt::error!("raster: {}", e),
            Err(FlushError::Target(e)) => defmt::error!("display: {}", e),
            Err(e) => defmt::error!("display: {}", defmt::Debug2Format(&e)),
        }
        let now = micros();
        let us = now.wrapping_sub(since);
        if us >= 1_000_000 {
            defmt::info!("{} frames/s", frames as u64 * 1_000_000 / us);
            (frames, since) = (0, now);
        }
        angle = angle.add(cube::STEP);
    }
}
