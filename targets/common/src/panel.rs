//! What the ST7789 board examples share (feature `panel`): the panel's
//! set-up through `mipidsi` over any `embedded-hal` SPI bus, giving the bus
//! back for DMA; and its window commands. What the examples draw is
//! [`crate::examples::cube`].
//!
//! A board example is then its HAL's set-up, its DMA ping-pong and its
//! log: `targets/rp-pico-st7789` (RP2040), `targets/rp-pico2-st7789`
//! (RP2350), `targets/esp32c3-st7789` (ESP32-C3).

use embedded_hal::delay::DelayNs;
use embedded_hal::digital::OutputPin;
use embedded_hal::spi::{ErrorType, Operation, SpiBus, SpiDevice};
use mipidsi::{interface::SpiInterface, models::ST7789, options::ColorInversion, Builder};
use tilerast::prelude::Rect;

/// Sends an ST7789 command byte (DC low) and its parameters (DC high),
/// blocking: a few bytes before each tile's transfer. The first bus error
/// is returned; DC errors are the pin's, which on these chips cannot fail.
///
/// The bus is flushed before DC moves: a DMA transfer counts as done once
/// its last byte is in the SPI FIFO, not on the wire, and a DC flipped
/// then turns the tile's last bytes into commands (up to 8 on the RP2040:
/// the emulated board found it, `tests/tests/rp2040.rs`).
pub fn command<B: SpiBus, D: OutputPin>(
    bus: &mut B,
    dc: &mut D,
    cmd: u8,
    data: &[u8],
) -> Result<(), B::Error> {
    bus.flush()?;
    let _ = dc.set_low();
    bus.write(&[cmd])?;
    bus.flush()?;
    let _ = dc.set_high();
    bus.write(data)?;
    bus.flush()
}

/// Opens the panel window of `a` for a RAM write (CASET, RASET, RAMWR): the
/// tile's pixels follow as data.
pub fn window<B: SpiBus, D: OutputPin>(bus: &mut B, dc: &mut D, a: Rect) -> Result<(), B::Error> {
    let be = |lo: i32, len: u32| {
        let (s, e) = (lo as u16, (lo + len as i32 - 1) as u16);
        [(s >> 8) as u8, s as u8, (e >> 8) as u8, e as u8]
    };
    command(bus, dc, 0x2A, &be(a.x, a.w))?;
    command(bus, dc, 0x2B, &be(a.y, a.h))?;
    command(bus, dc, 0x2C, &[])
}

/// Initialises a 240x240 ST7789 (colours inverted, as the common IPS
/// modules want) through `mipidsi` on `bus` with chip select `cs`,
/// data/command `dc` and reset `rst`, then gives back the bus, the chip
/// select (held low: the panel stays selected) and DC, for DMA transfers.
pub fn init_st7789<B, CS, DC, RST>(
    bus: B,
    cs: CS,
    dc: DC,
    rst: RST,
    delay: &mut impl DelayNs,
) -> Result<(B, CS, DC), &'static str>
where
    B: SpiBus,
    CS: OutputPin,
    DC: OutputPin,
    RST: OutputPin,
{
    let mut buffer = [0u8; 512];
    let di = SpiInterface::new(Device { bus, cs }, dc, &mut buffer);
    let display = Builder::new(ST7789, di)
        .display_size(240, 240)
        .invert_colors(ColorInversion::Inverted)
        .reset_pin(rst)
        .init(delay)
        .map_err(|_| "ST7789 initialisation failed")?;
    let (di, _model, _rst) = display.release();
    let (device, dc) = di.release();
    let Device { bus, mut cs } = device;
    cs.set_low().map_err(|_| "chip select")?;
    Ok((bus, cs, dc))
}

/// An SPI bus and its chip select as the `SpiDevice` a panel driver
/// (`mipidsi`) initialises the panel through; afterwards the example takes
/// the bus back for DMA (`embedded-hal-bus`'s `ExclusiveDevice` keeps it).
pub struct Device<B, C> {
    /// The bus.
    pub bus: B,
    /// Chip select, low while a transaction runs.
    pub cs: C,
}

impl<B: ErrorType, C> ErrorType for Device<B, C> {
    type Error = B::Error;
}

impl<B: SpiBus, C: OutputPin> SpiDevice for Device<B, C> {
    fn transaction(&mut self, ops: &mut [Operation<'_, u8>]) -> Result<(), B::Error> {
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
