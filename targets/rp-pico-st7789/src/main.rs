//! tilerast on real hardware: a Raspberry Pi Pico (RP2040, Cortex-M0+, no
//! FPU) drives a 240x240 ST7789 over SPI. Each frame the on-device geometry
//! stage (`tilerast::geometry`, fixed point: no float anywhere) turns a lit
//! cube — transform, back-face culling, lighting — and the frame pipeline
//! renders it. `mipidsi` initialises the panel;
//! then each frame is rendered in 60x40 tiles — 2400 pixels of RGB565 +
//! 16-bit Z, 9.6 KB — and sent by **DMA while the next tile renders**: the
//! panel's memory is the front buffer, and two 4.8 KB byte buffers
//! ping-pong — tile k+1 is rendered and packed (`Tile::panel_bytes`:
//! big-endian RGB565) while tile k streams out. No 115 KB frame buffer
//! anywhere.
//!
//! Wiring (SPI0): GP18 SCK, GP19 MOSI, GP17 CS, GP16 DC, GP20 RST.
//! Flash and watch the log with a probe (`cargo run --release`: probe-rs
//! prints the `defmt` messages sent over RTT); a panic (`panic-probe`)
//! prints its message the same way.
#![no_std]
#![no_main]

mod tiles;

use hal::dma::DMAExt;
use rp_pico::entry;
use rp_pico::hal::{self, clocks::Clock, fugit::RateExtU32, gpio, pac, spi, Timer};
use tilerast::geometry::Fx;
use tilerast_fw::panel::init_st7789;
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
    // Initialised, the bus comes back for DMA (chip select held low).
    let (bus, _cs, dc) = init_st7789(bus, cs, dc, rst, &mut timer).unwrap();
    let dma = pac.DMA.split(&mut pac.RESETS);
    // Fixed point: the Cortex-M0+ has no FPU.
    tiles::run::<Fx, _, _>(dma.ch0, bus, dc, || timer.get_counter().ticks())
}
