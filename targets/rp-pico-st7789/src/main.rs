//! tilerast on real hardware: a Raspberry Pi Pico (RP2040, Cortex-M0+, no
//! FPU) drives a 240x240 ST7789 over SPI through `mipidsi`. Each frame is
//! rendered in 60x40 tiles — 2400 pixels of RGB565 + 16-bit Z, 9.6 KB — and
//! every tile goes straight to the panel with one `fill_contiguous`: no
//! 115 KB frame buffer anywhere.
//!
//! Wiring (SPI0): GP18 SCK, GP19 MOSI, GP17 CS, GP16 DC, GP20 RST.
//! Flash and watch the log with a probe (`cargo run --release`: probe-rs
//! prints the `defmt` messages sent over RTT); a panic (`panic-probe`)
//! prints its message the same way.
#![no_std]
#![no_main]

use embedded_hal_bus::spi::ExclusiveDevice;
use micromath::F32Ext;
use mipidsi::{interface::SpiInterface, models::ST7789, options::ColorInversion, Builder};
use rp_pico::entry;
use rp_pico::hal::{self, clocks::Clock, fugit::RateExtU32, gpio, pac, spi, Timer};
use tilerast::prelude::*;
use {defmt_rtt as _, panic_probe as _};

/// 60x40-pixel tiles, ST7789 preset (RGB565 + 16-bit Z + 4x4 dither).
type PanelTile = Tile<{ groups(60, 40) }, St7789Config>;

/// A floor of two Gouraud triangles and a spinning triangle that pierces it.
fn scene(list: &mut DisplayList<4>, angle: f32) -> Result<(), Error> {
    list.clear();
    let v = |x: f32, y: f32, z: u16, c: (u8, u8, u8)| {
        Vertex::try_from_f32(x, y, z, Rgb::new(c.0, c.1, c.2))
    };
    let floor = [(20, 40, 90), (120, 40, 150), (20, 120, 60), (200, 160, 40)];
    list.push(Command::Triangle {
        v: [
            v(0.0, 120.0, 30000, floor[0])?,
            v(240.0, 120.0, 30000, floor[1])?,
            v(0.0, 240.0, 10000, floor[2])?,
        ],
        state: State::default(),
    })?;
    list.push(Command::Triangle {
        v: [
            v(240.0, 120.0, 30000, floor[1])?,
            v(240.0, 240.0, 10000, floor[3])?,
            v(0.0, 240.0, 10000, floor[2])?,
        ],
        state: State::default(),
    })?;
    // Setup-time float math (soft-float on the M0+), never per pixel.
    let corner = |k: f32| {
        let a = angle + k * 2.094_395;
        (
            120.0 + 100.0 * a.cos(),
            130.0 + 100.0 * a.sin(),
            (20000.0 + 15000.0 * a.sin()) as u16,
        )
    };
    let [(x0, y0, z0), (x1, y1, z1), (x2, y2, z2)] = [corner(0.0), corner(1.0), corner(2.0)];
    list.push(Command::Triangle {
        v: [
            v(x0, y0, z0, (255, 40, 40))?,
            v(x1, y1, z1, (40, 255, 40))?,
            v(x2, y2, z2, (40, 40, 255))?,
        ],
        state: State::default(),
    })
}

#[entry]
fn main() -> ! {
    let mut pac = pac::Peripherals::take().unwrap();
    let mut watchdog = hal::Watchdog::new(pac.WATCHDOG);
    let clocks = hal::clocks::init_clocks_and_plls(
        rp_pico::XOSC_CRYSTAL_FREQ,
        pac.XOSC,
        pac.CLOCKS,
        pac.PLL_SYS,
        pac.PLL_USB,
        &mut pac.RESETS,
        &mut watchdog,
    )
    .ok()
    .unwrap();
    let sio = hal::Sio::new(pac.SIO);
    let pins = rp_pico::Pins::new(
        pac.IO_BANK0,
        pac.PADS_BANK0,
        sio.gpio_bank0,
        &mut pac.RESETS,
    );

    let sclk: gpio::Pin<_, gpio::FunctionSpi, gpio::PullNone> = pins.gpio18.reconfigure();
    let mosi: gpio::Pin<_, gpio::FunctionSpi, gpio::PullNone> = pins.gpio19.reconfigure();
    let cs = pins.gpio17.into_push_pull_output();
    let dc = pins.gpio16.into_push_pull_output();
    let rst = pins.gpio20.into_push_pull_output();
    let bus = spi::Spi::<_, _, _, 8>::new(pac.SPI0, (mosi, sclk)).init(
        &mut pac.RESETS,
        clocks.peripheral_clock.freq(),
        62_500_000u32.Hz(),
        embedded_hal::spi::MODE_0,
    );
    let mut timer = Timer::new(pac.TIMER, &mut pac.RESETS, &clocks);
    let spi = ExclusiveDevice::new_no_delay(bus, cs).unwrap();
    let mut buffer = [0u8; 512];
    let di = SpiInterface::new(spi, dc, &mut buffer);
    let mut display = Builder::new(ST7789, di)
        .display_size(240, 240)
        .invert_colors(ColorInversion::Inverted)
        .reset_pin(rst)
        .init(&mut timer)
        .unwrap();
    defmt::info!("ST7789 ready; {} bytes per tile", PanelTile::plane_bytes());

    // 60x40 tiles: checked against `PanelTile` when compiling.
    let mut frame = PanelTile::frame::<60, 40>(240, 240).unwrap();
    frame.clear = Clear {
        color: Rgb::new(8, 8, 16),
        ..Clear::default()
    };
    let mut tile = PanelTile::new();
    let mut list: DisplayList<4> = DisplayList::new();
    let mut angle = 0.0f32;
    let mut frames = 0u32;
    let mut since = timer.get_counter();
    loop {
        // Errors are reported, never discarded into a black screen.
        match scene(&mut list, angle) {
            // The panel's `DrawTarget<Color = Rgb565>` receives each tile.
            Ok(()) => match frame.render(&mut tile, &list, &mut display) {
                Ok(_) => frames += 1,
                Err(FlushError::Raster(e)) => defmt::error!("raster: {}", e),
                Err(e) => defmt::error!("display: {}", defmt::Debug2Format(&e)),
            },
            Err(e) => defmt::error!("scene: {}", e),
        }
        let now = timer.get_counter();
        let us = (now - since).to_micros();
        if us >= 1_000_000 {
            defmt::info!("{} frames/s", frames as u64 * 1_000_000 / us);
            (frames, since) = (0, now);
        }
        angle += 0.05;
    }
}
