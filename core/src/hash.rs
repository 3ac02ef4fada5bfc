//! Output checking: a CRC32 of the pixel stream a display would receive.
//! Firmware renders into a [`CrcTarget`] and reports the CRC; the host
//! renders the same scene the same way and must get the same number — the
//! proof that x86-64, Cortex-M0 and Cortex-M4 produce the same bytes.

use embedded_graphics_core::{
    draw_target::DrawTarget,
    geometry::{OriginDimensions, Size},
    pixelcolor::{raw::RawData, IntoStorage, PixelColor},
    primitives::Rectangle,
    Pixel,
};

/// CRC-32 (IEEE 802.3, reflected, as zlib), a byte at a time through a
/// 256-entry table (1 KB of flash; the 16-entry table it replaced took
/// two lookups a byte: 24 instructions a pixel of the micro:bit's
/// flush, measured).
///
/// ```
/// use tilerast::hash::Crc32;
/// let mut c = Crc32::new();
/// c.update(b"123456789");
/// assert_eq!(c.finish(), 0xCBF4_3926);
/// ```
#[derive(Debug, Clone, Copy)]
pub struct Crc32(u32);

const TABLE: [u32; 256] = {
    let mut t = [0u32; 256];
    let mut i = 0;
    while i < 256 {
        let mut c = i as u32;
        let mut k = 0;
        while k < 8 {
            c = if c & 1 != 0 {
                (c >> 1) ^ 0xEDB8_8320
            } else {
                c >> 1
            };
            k += 1;
        }
        t[i] = c;
        i += 1;
    }
    t
};

impl Default for Crc32 {
    fn default() -> Self {
        Self::new()
    }
}

impl Crc32 {
    /// A fresh CRC.
    pub const fn new() -> Self {
        Crc32(!0)
    }
    /// Adds bytes.
    pub fn update(&mut self, bytes: &[u8]) {
        for &b in bytes {
            let c = self.0;
            self.0 = (c >> 8) ^ TABLE[((c ^ b as u32) & 0xff) as usize];
        }
    }
    /// The CRC of everything added so far.
    pub const fn finish(&self) -> u32 {
        !self.0
    }
}

/// A 32-bit hash a word at a time, for change detection (not
/// cryptographic, not a checksum: equal inputs give equal hashes on every
/// chip; different ones collide with odds about 2^-32). It is a
/// [`core::hash::Hasher`], so any `Hash` value can be added, e.g. a
/// [`Command`](crate::command::Command).
///
/// ```
/// use core::hash::{Hash, Hasher};
/// use tilerast::hash::WordHash;
/// use tilerast::prelude::*;
/// let hash = |c: &Command| {
///     let mut h = WordHash::new();
///     c.hash(&mut h);
///     h.value()
/// };
/// let a = Command::fill(Rect::new(0, 0, 4, 4), Rgb::new(1, 2, 3));
/// let b = Command::fill(Rect::new(0, 0, 4, 4), Rgb::new(1, 2, 4));
/// assert_eq!(hash(&a), hash(&a));
/// assert_ne!(hash(&a), hash(&b));
/// ```
#[derive(Debug, Clone, Copy)]
pub struct WordHash(u32);

impl Default for WordHash {
    fn default() -> Self {
        Self::new()
    }
}

impl WordHash {
    /// A fresh hash (FNV's offset basis).
    pub const fn new() -> Self {
        WordHash(0x811C_9DC5)
    }

    /// Adds one word: xor, multiply by the golden ratio's 2^32 multiple,
    /// rotate.
    #[inline(always)]
    pub fn add(&mut self, v: u32) {
        self.0 = (self.0 ^ v).wrapping_mul(0x9E37_79B1).rotate_left(13);
    }

    /// The hash of everything added so far.
    pub const fn value(&self) -> u32 {
        self.0
    }
}

impl core::hash::Hasher for WordHash {
    fn finish(&self) -> u64 {
        self.0 as u64
    }
    fn write(&mut self, bytes: &[u8]) {
        bytes.iter().for_each(|&b| self.add(b as u32));
    }
    fn write_u8(&mut self, v: u8) {
        self.add(v as u32)
    }
    fn write_u16(&mut self, v: u16) {
        self.add(v as u32)
    }
    fn write_u32(&mut self, v: u32) {
        self.add(v)
    }
    fn write_u64(&mut self, v: u64) {
        self.add(v as u32);
        self.add((v >> 32) as u32);
    }
    fn write_usize(&mut self, v: usize) {
        self.write_u64(v as u64)
    }
    fn write_i8(&mut self, v: i8) {
        self.add(v as u32)
    }
    fn write_i16(&mut self, v: i16) {
        self.add(v as u32)
    }
    fn write_i32(&mut self, v: i32) {
        self.add(v as u32)
    }
    fn write_isize(&mut self, v: isize) {
        self.write_u64(v as u64)
    }
}

/// A `DrawTarget` of a given size that stores nothing and hashes every
/// colour it receives, in order, as its raw storage value in little-endian
/// bytes (`ceil(bits / 8)` bytes per pixel).
///
/// ```
/// use tilerast::hash::CrcTarget;
/// use embedded_graphics_core::{pixelcolor::Rgb565, prelude::*, primitives::Rectangle};
/// let mut t = CrcTarget::<Rgb565>::new(Size::new(2, 1));
/// t.fill_contiguous(&Rectangle::new(Point::zero(), Size::new(2, 1)), [Rgb565::RED, Rgb565::BLUE])?;
/// assert_eq!(t.pixels(), 2);
/// # Ok::<(), core::convert::Infallible>(())
/// ```
#[derive(Debug, Clone)]
pub struct CrcTarget<C> {
    crc: Crc32,
    size: Size,
    pixels: u32,
    _color: core::marker::PhantomData<C>,
}

impl<C> CrcTarget<C> {
    /// A target of `size` pixels.
    pub fn new(size: Size) -> Self {
        CrcTarget {
            crc: Crc32::new(),
            size,
            pixels: 0,
            _color: core::marker::PhantomData,
        }
    }
    /// The CRC of the stream so far.
    pub fn crc(&self) -> u32 {
        self.crc.finish()
    }
    /// Pixels received.
    pub fn pixels(&self) -> u32 {
        self.pixels
    }
}

impl<C> CrcTarget<C>
where
    C: PixelColor + IntoStorage,
    C::Storage: Into<u32>,
{
    fn add(&mut self, c: C) {
        let bytes = C::Raw::BITS_PER_PIXEL.div_ceil(8);
        let v: u32 = c.into_storage().into();
        self.crc.update(&v.to_le_bytes()[..bytes]);
        self.pixels += 1;
    }
}

impl<C> OriginDimensions for CrcTarget<C> {
    fn size(&self) -> Size {
        self.size
    }
}

impl<C> DrawTarget for CrcTarget<C>
where
    C: PixelColor + IntoStorage,
    C::Storage: Into<u32>,
{
    type Color = C;
    type Error = core::convert::Infallible;

    fn draw_iter<I: IntoIterator<Item = Pixel<C>>>(
        &mut self,
        pixels: I,
    ) -> Result<(), Self::Error> {
        pixels.into_iter().for_each(|Pixel(_, c)| self.add(c));
        Ok(())
    }

    fn fill_contiguous<I: IntoIterator<Item = C>>(
        &mut self,
        _: &Rectangle,
        colors: I,
    ) -> Result<(), Self::Error> {
        colors.into_iter().for_each(|c| self.add(c));
        Ok(())
    }
}
