//! tilerast on real hardware: a Raspberry Pi Pico 2 (RP2350, Cortex-M33
//! with FPU, 150 MHz) drives a 240x240 ST7789 over SPI. The same program as
//! the RP2040's (`targets/rp-pico-st7789`, whose frame loop this includes:
//! `src/tiles.rs`), with the geometry stage in `f32` on the M33's FPU:
//! `mipidsi` initialises the panel, then each frame is rendered in 60x40
//! tiles (9.6 KB) and sent by **DMA while the next tile renders**, two
//! 4.8 KB byte buffers in ping-pong. No 115 KB frame buffer anywhere.
//!
//! Wiring (SPI0): GP18 SCK, GP19 MOSI, GP17 CS, GP16 DC, GP20 RST.
//! Flash and watch the log with a probe (`cargo run --release`: probe-rs
//! prints the `defmt` messages sent over RTT); a panic (`panic-probe`)
//! prints its message the same way.
#![no_std]
#![no_main]

#[path = "../../rp-pico-st7789/src/tiles.rs"]
mod tiles;

use hal::dma::DMAExt;
use hal::{clocks::Clock, fugit::RateExtU32, gpio, pac, spi, Timer};
use rp235x_hal as hal;
use tilerast_fw::panel::init_st7789;
use {defmt_rtt as _, panic_probe as _};

/// The boot ROM's image definition: a secure Arm executable.
#[link_section = ".start_block"]
#[used]
pub static IMAGE_DEF: hal::block::ImageDef = hal::block::ImageDef::secure_exe();

/// The Pico 2's crystal.
const XTAL_FREQ_HZ: u32 = 12_000_000;

#[hal::entry]
fn main() -> ! {
    let mut pac = pac::Peripherals::take().unwrap();
    let mut watchdog = hal::Watchdog::new(pac.WATCHDOG);
    let clocks = hal::clocks::init_clocks_and_plls(
        XTAL_FREQ_HZ,
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
    let pins = gpio::Pins::new(
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
    let mut timer = Timer::new_timer0(pac.TIMER0, &mut pac.RESETS, &clocks);
    // Initialised, the bus comes back for DMA (chip select held low).
    let (bus, _cs, dc) = init_st7789(bus, cs, dc, rst, &mut timer).unwrap();
    let dma = pac.DMA.split(&mut pac.RESETS);
    // `f32`: the Cortex-M33 has an FPU.
    tiles::run::<f32, _, _>(dma.ch0, bus, dc, || timer.get_counter().ticks())
}
