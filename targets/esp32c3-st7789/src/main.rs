//! tilerast on real hardware: an ESP32-C3 (RV32IMC, 160 MHz, no FPU: the
//! geometry stage in fixed point) drives a 240x240 ST7789 over SPI, with
//! `esp-hal` on stable Rust. The same program as the Raspberry Pi ones
//! (`targets/rp-pico-st7789`): `mipidsi` initialises the panel, then each
//! frame the lit cube turns and is rendered in 60x40 tiles (9.6 KB) and
//! sent by **DMA while the next tile renders**, two 4.8 KB DMA buffers in
//! ping-pong. Errors and frames per second are printed on the USB serial
//! console (`esp-println`); a panic prints its message and a backtrace
//! (`esp-backtrace`).
//!
//! Wiring (SPI2): GPIO6 SCK, GPIO7 MOSI, GPIO10 CS, GPIO2 DC, GPIO3 RST.
//! Flash and watch with `cargo run --release` (`espflash`).
#![no_std]
#![no_main]

use esp_backtrace as _;
use esp_hal::delay::Delay;
use esp_hal::dma::DmaTxBuf;
use esp_hal::gpio::{Level, Output, OutputConfig};
use esp_hal::spi::master::{Config, Spi, SpiDma};
use esp_hal::spi::Mode;
use esp_hal::time::{Instant, Rate};
use esp_hal::{dma_tx_buffer, Blocking};
use esp_println::println;
use tilerast::geometry::{Angle, Fx, Mesh, Scene, VertexSlot, CUBE_BYTES};
use tilerast::prelude::*;
use tilerast_fw::examples::cube::{self, camera, turn, Panel, TILE_BYTES};
use tilerast_fw::panel::{init_st7789, window};

esp_bootloader_esp_idf::esp_app_desc!();

/// The SPI link to the panel: idle, or sending a buffer by DMA.
enum Link<'d> {
    Idle(SpiDma<'d, Blocking>),
    Busy(esp_hal::spi::master::SpiDmaTransfer<'d, Blocking, DmaTxBuf>),
}

#[esp_hal::main]
fn main() -> ! {
    let p = esp_hal::init(esp_hal::Config::default());
    let out = || OutputConfig::default();
    let cs = Output::new(p.GPIO10, Level::High, out());
    let dc = Output::new(p.GPIO2, Level::Low, out());
    let rst = Output::new(p.GPIO3, Level::High, out());
    let config = Config::default()
        .with_frequency(Rate::from_mhz(40))
        .with_mode(Mode::_0);
    let bus = Spi::new(p.SPI2, config)
        .expect("SPI configuration")
        .with_sck(p.GPIO6)
        .with_mosi(p.GPIO7);
    // Initialised, the bus comes back for DMA (chip select held low).
    let (bus, _cs, mut dc) =
        init_st7789(bus, cs, dc, rst, &mut Delay::new()).expect("ST7789 initialisation");
    let mut link = Some(Link::Idle(bus.with_dma(p.DMA_CH0)));
    let mut next = Some(dma_tx_buffer!(TILE_BYTES).expect("DMA buffer"));
    let mut spare = Some(dma_tx_buffer!(TILE_BYTES).expect("DMA buffer"));
    println!("ST7789 ready; {} bytes of renderer", Panel::BYTES);

    // 60x40 tiles (a window the panel takes per DMA transfer).
    let mut renderer = cube::renderer().expect("renderer");
    let mut mesh_buf = [0u8; CUBE_BYTES];
    let cube = Mesh::cube(&mut mesh_buf).expect("cube");
    let mut slots = [VertexSlot::EMPTY; 24];
    let mut scene: Scene<'_, Fx> = Scene::new(&mut slots);
    if let Err(e) = camera(&mut scene) {
        println!("camera: {e}");
    }
    let mut angle = Angle::default();
    let mut frames = 0u32;
    let mut since = Instant::now();
    loop {
        // Errors are reported, never discarded into a black screen.
        let drawn = turn(&mut scene, &cube, angle)
            .map_err(FlushError::Raster)
            .and_then(|()| {
                renderer.render(&scene, |t| {
                    // Pack tile k+1 while tile k is still streaming out...
                    let mut buf = next
                        .take()
                        .or_else(|| spare.take())
                        .ok_or("no free buffer")?;
                    let n = t
                        .panel_bytes(buf.as_mut_slice())
                        .map_err(|_| "tile larger than a buffer")?;
                    buf.set_length(n);
                    // ... then wait for it, and send this one.
                    let mut spi = match link.take().ok_or("DMA link lost")? {
                        Link::Idle(spi) => spi,
                        Link::Busy(tr) => {
                            let (spi, done) = tr.wait();
                            next = Some(done);
                            spi
                        }
                    };
                    window(&mut spi, &mut dc, t.area()).map_err(|_| "SPI error")?;
                    match spi.write_buffer(n, buf) {
                        Ok(tr) => link = Some(Link::Busy(tr)),
                        Err((_, spi, buf)) => {
                            (link, next) = (Some(Link::Idle(spi)), Some(buf));
                            return Err("DMA transfer refused");
                        }
                    }
                    Ok::<(), &'static str>(())
                })
            });
        match drawn {
            Ok(_) => frames += 1,
            Err(FlushError::Raster(e)) => println!("raster: {e}"),
            Err(FlushError::Target(e)) => println!("display: {e}"),
            Err(e) => println!("display: {e:?}"),
        }
        let us = since.elapsed().as_micros();
        if us >= 1_000_000 {
            println!("{} frames/s", frames as u64 * 1_000_000 / us);
            (frames, since) = (0, Instant::now());
        }
        angle = angle.add(cube::STEP);
    }
}
