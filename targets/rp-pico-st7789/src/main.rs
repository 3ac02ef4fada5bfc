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

use embedded_hal::digital::OutputPin;
use embedded_hal::spi::SpiBus;
use hal::dma::{single_buffer, Channel, DMAExt, CH0};
use mipidsi::{interface::SpiInterface, models::ST7789, options::ColorInversion, Builder};
use rp_pico::entry;
use rp_pico::hal::{self, clocks::Clock, fugit::RateExtU32, gpio, pac, spi, Timer};
use tilerast::geometry::{
    Angle, DrawOptions, Fx, Lighting, Mat4, Mesh, Real, Scene, VertexSlot, CUBE_BYTES,
};
use tilerast::prelude::*;
use {defmt_rtt as _, panic_probe as _};

/// 60x40-pixel tiles, ST7789 preset (RGB565 + 16-bit Z + 4x4 dither).
type PanelTile = Tile<{ groups(60, 40) }, St7789Config>;

/// Bytes of one tile as the panel takes it.
const TILE_BYTES: usize = 60 * 40 * 2;
/// One ping-pong buffer.
type Buf = &'static mut [u8; TILE_BYTES];

/// Sends an ST7789 command byte (DC low) and its parameters (DC high),
/// blocking: a few bytes before each tile's DMA transfer.
fn command<B: SpiBus, D: OutputPin>(bus: &mut B, dc: &mut D, cmd: u8, data: &[u8]) {
    let _ = dc.set_low();
    let _ = bus.write(&[cmd]);
    let _ = bus.flush();
    let _ = dc.set_high();
    let _ = bus.write(data);
    let _ = bus.flush();
}

/// Opens the panel window of `a` for a RAM write (CASET, RASET, RAMWR).
fn window<B: SpiBus, D: OutputPin>(bus: &mut B, dc: &mut D, a: Rect) {
    let be = |lo: i32, len: u32| {
        let (s, e) = (lo as u16, (lo + len as i32 - 1) as u16);
        [(s >> 8) as u8, s as u8, (e >> 8) as u8, e as u8]
    };
    command(bus, dc, 0x2A, &be(a.x, a.w));
    command(bus, dc, 0x2B, &be(a.y, a.h));
    command(bus, dc, 0x2C, &[]);
}

/// The SPI bus and chip select as the `SpiDevice` `mipidsi` initialises the
/// panel through, given back afterwards for DMA (`embedded-hal-bus`'s
/// `ExclusiveDevice` keeps its bus).
struct Device<B, C> {
    bus: B,
    cs: C,
}

impl<B: embedded_hal::spi::ErrorType, C> embedded_hal::spi::ErrorType for Device<B, C> {
    type Error = B::Error;
}

impl<B: SpiBus, C: OutputPin> embedded_hal::spi::SpiDevice for Device<B, C> {
    fn transaction(
        &mut self,
        ops: &mut [embedded_hal::spi::Operation<'_, u8>],
    ) -> Result<(), B::Error> {
        use embedded_hal::spi::Operation;
        let _ = self.cs.set_low();
        let r = ops.iter_mut().try_for_each(|op| match op {
            Operation::Read(b) => self.bus.read(b),
            Operation::Write(b) => self.bus.write(b),
            Operation::Transfer(r, w) => self.bus.transfer(r, w),
            Operation::TransferInPlace(b) => self.bus.transfer_in_place(b),
            Operation::DelayNs(_) => Ok(()),
        });
        let f = self.bus.flush();
        let _ = self.cs.set_high();
        r.and(f)
    }
}

/// The DMA link to the panel: idle, or sending a buffer.
enum Link<S: hal::dma::WriteTarget<TransmittedWord = u8>> {
    Idle(Channel<CH0>, S),
    Busy(single_buffer::Transfer<Channel<CH0>, Buf, S>),
}

/// The camera 3 units away, 40° field of view, and one white light from
/// the upper left: set once.
fn camera(scene: &mut Scene<'_, Fx>) -> Result<(), Error> {
    let q = |v: i32| Fx::from_q(v as i64, 8); // 1/256 units
    scene.set_camera(
        Mat4::look_at([q(0), q(0), q(3 * 256)], [q(0); 3], [q(0), q(256), q(0)])?,
        Mat4::perspective(Angle::degrees(40), Fx::ONE, q(256), q(5 * 256))?,
    );
    scene.set_viewport(Rect::new(0, 0, 240, 240))?;
    scene.set_lighting(Lighting::white([q(-102), q(154), q(256)], q(51))?);
    Ok(())
}

/// This frame's draw: the cube turned by `t` about y and half that about x.
fn turn<'a>(scene: &mut Scene<'a, Fx>, cube: &Mesh<'a>, t: Angle) -> Result<(), Error> {
    scene.clear();
    let half = Angle::from_turn_q16(t.turn_q16() / 2);
    let model = Mat4::rotation_x(half).mul(&Mat4::rotation_y(t));
    scene.draw(cube, &model, &DrawOptions::default())?;
    Ok(())
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
    let spi = Device { bus, cs };
    let mut buffer = [0u8; 512];
    let di = SpiInterface::new(spi, dc, &mut buffer);
    let display = Builder::new(ST7789, di)
        .display_size(240, 240)
        .invert_colors(ColorInversion::Inverted)
        .reset_pin(rst)
        .init(&mut timer)
        .unwrap();
    // Initialised: take the bus back for DMA, chip select held low.
    let (di, _model, _rst) = display.release();
    let (spi, mut dc) = di.release();
    let Device { bus, mut cs } = spi;
    let _ = cs.set_low();
    let dma = pac.DMA.split(&mut pac.RESETS);
    let mut link = Some(Link::Idle(dma.ch0, bus));
    let mut next: Option<Buf> = cortex_m::singleton!(: [u8; TILE_BYTES] = [0; TILE_BYTES]);
    let mut spare: Option<Buf> = cortex_m::singleton!(: [u8; TILE_BYTES] = [0; TILE_BYTES]);
    defmt::info!("ST7789 ready; {} bytes per tile", PanelTile::plane_bytes());

    // 60x40 tiles: checked against `PanelTile` when compiling.
    let mut frame = PanelTile::frame::<60, 40>(240, 240).unwrap();
    frame.clear = Clear {
        color: Rgb::new(8, 8, 16),
        ..Clear::default()
    };
    let mut tile = PanelTile::new();
    let mut bins: Bins<256, 36> = Bins::new();
    let mut mesh_buf = [0u8; CUBE_BYTES];
    let cube = Mesh::cube(&mut mesh_buf).unwrap();
    let mut slots = [VertexSlot::EMPTY; 24];
    let mut scene: Scene<'_, Fx> = Scene::new(&mut slots);
    if let Err(e) = camera(&mut scene) {
        defmt::error!("camera: {}", e);
    }
    let mut angle = Angle::default();
    let mut frames = 0u32;
    let mut since = timer.get_counter();
    loop {
        // Errors are reported, never discarded into a black screen.
        let drawn = turn(&mut scene, &cube, angle)
            .map_err(FlushError::Raster)
            .and_then(|()| {
                frame.render_binned(&mut tile, &mut bins, &scene, |t| {
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
                    window(&mut bus, &mut dc, t.area());
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
        let now = timer.get_counter();
        let us = (now - since).to_micros();
        if us >= 1_000_000 {
            defmt::info!("{} frames/s", frames as u64 * 1_000_000 / us);
            (frames, since) = (0, now);
        }
        angle = angle.add(Angle::degrees(3));
    }
}
