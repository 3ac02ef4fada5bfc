//! tilerast on real hardware: a Raspberry Pi Pico (RP2040, Cortex-M0+, no
//! FPU) drives a 128x64 one-bit SSD1306 OLED over I2C through the
//! `ssd1306` crate. The whole screen is one tile of the SSD1306 preset —
//! 1 bit a pixel, 4x4 ordered dither, 1 KB — so Gouraud shading becomes
//! dither patterns; text goes over it with `embedded-graphics`.
//!
//! Wiring (I2C0, 400 kHz): GP4 SDA, GP5 SCL, address 0x3C.
//! Flash and watch the log with a probe (`cargo run --release`: probe-rs
//! prints the `defmt` messages sent over RTT).
#![no_std]
#![no_main]

use rp_pico::entry;
use rp_pico::hal::{self, fugit::RateExtU32, gpio, pac, Timer};
use ssd1306::{prelude::*, I2CDisplayInterface, Ssd1306};
use tilerast::prelude::*;
use tilerast_fw::examples::oled::{self, label, scene, Oled};
use {defmt_rtt as _, panic_probe as _};

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
    let sda: gpio::Pin<_, gpio::FunctionI2C, gpio::PullUp> = pins.gpio4.reconfigure();
    let scl: gpio::Pin<_, gpio::FunctionI2C, gpio::PullUp> = pins.gpio5.reconfigure();
    let i2c = hal::I2C::i2c0(
        pac.I2C0,
        sda,
        scl,
        400.kHz(),
        &mut pac.RESETS,
        &clocks.system_clock,
    );
    let timer = Timer::new(pac.TIMER, &mut pac.RESETS, &clocks);
    let mut display = Ssd1306::new(
        I2CDisplayInterface::new(i2c),
        DisplaySize128x64,
        DisplayRotation::Rotate0,
    )
    .into_buffered_graphics_mode();
    display.init().unwrap();
    defmt::info!("SSD1306 ready; {} bytes of renderer", Oled::BYTES);

    // One tile covers the screen.
    let mut renderer = oled::renderer().unwrap();
    let mut list: DisplayList<3> = DisplayList::new();
    let mut angle = 0.0f32;
    let mut frames = 0u32;
    let mut since = timer.get_counter();
    loop {
        // Errors are reported, never discarded into a blank screen.
        match scene(&mut list, angle) {
            Ok(()) => {
                let drawn = renderer.render(&list, |t| {
                    // The tile's own errors are `Infallible`.
                    let Ok(()) = label(t);
                    t.flush(&mut display)
                });
                match drawn {
                    Ok(_) => match display.flush() {
                        Ok(()) => frames += 1,
                        Err(e) => defmt::error!("i2c: {}", defmt::Debug2Format(&e)),
                    },
                    Err(FlushError::Raster(e)) => defmt::error!("raster: {}", e),
                    Err(e) => defmt::error!("display: {}", defmt::Debug2Format(&e)),
                }
            }
            Err(e) => defmt::error!("scene: {}", e),
        }
        let now = timer.get_counter();
        let us = (now - since).to_micros();
        if us >= 1_000_000 {
            defmt::info!("{} frames/s", frames as u64 * 1_000_000 / us);
            (frames, since) = (0, now);
        }
        angle += oled::STEP;
    }
}
