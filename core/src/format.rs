//! Display formats (pipeline stage *pack*): how the interpolated channels of a
//! fragment are quantized and packed into the tile's colour plane, and how a
//! packed pixel leaves the tile as an `embedded-graphics` colour.
//!
//! Colour is interpolated directly in the **output channel scale** (seed 001,
//! §II.3: the top bits of a 10-bit channel are the displayed value, the low
//! bits are the dither fraction). A vertex colour `c` (0..255) becomes
//! `c * MAX / 255` with 16 fraction bits at setup, so the per-pixel path is
//! only adds, one compare per channel and a pack. Grey formats interpolate a
//! single luma channel, `(77 R + 150 G + 29 B) / 256` (the same weights as
//! `embedded-graphics`), computed per vertex: one lane instead of three.

use crate::numeric::{div255, div_round, COLOR_FRAC};
use embedded_graphics_core::pixelcolor::{
    raw::RawU16, BinaryColor, Gray8, GrayColor, PixelColor, Rgb565, Rgb888, RgbColor,
};

/// A 24-bit input colour, 0..255 per channel.
///
/// ```
/// use tilerast::format::Rgb;
/// let c = Rgb::new(255, 128, 0);
/// assert_eq!((c.r, c.g, c.b), (255, 128, 0));
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Rgb {
    /// Red.
    pub r: u8,
    /// Green.
    pub g: u8,
    /// Blue.
    pub b: u8,
}

impl Rgb {
    /// A colour from its channels.
    pub const fn new(r: u8, g: u8, b: u8) -> Self {
        Rgb { r, g, b }
    }
}

/// Colours convert to and from `embedded-graphics`' `Rgb888`.
///
/// ```
/// use tilerast::prelude::*;
/// use embedded_graphics_core::pixelcolor::{Rgb888, RgbColor};
/// assert_eq!(Rgb::from(Rgb888::CYAN), Rgb::new(0, 255, 255));
/// assert_eq!(Rgb888::from(Rgb::new(1, 2, 3)), Rgb888::new(1, 2, 3));
/// ```
impl From<Rgb888> for Rgb {
    fn from(c: Rgb888) -> Self {
        Rgb::new(c.r(), c.g(), c.b())
    }
}

impl From<Rgb> for Rgb888 {
    fn from(c: Rgb) -> Self {
        Rgb888::new(c.r, c.g, c.b)
    }
}

/// A display format: channel count and depth, packing, plane storage and the
/// `embedded-graphics` colour it flushes as.
pub trait PixelFormat: 'static {
    /// The colour type a packed pixel converts to when flushed.
    type Color: PixelColor;
    /// Colour-plane storage for `8 N` pixels.
    type Plane<const N: usize>: ColorPlane;
    /// Interpolated channels.
    type Lanes: Lanes;
    /// Largest value of each channel (e.g. `[31, 63, 31]` for RGB565).
    const MAX: Self::Lanes;
    /// Plane mask that writes every bit.
    const MASK_ALL: u32;
    /// A short name for reports.
    const NAME: &'static str;

    /// Maps a colour on the 0..255 scale with 16 fraction bits (`[r, g, b]`,
    /// signed so that it also serves per-pixel steps) to lanes in the output
    /// scale with [`COLOR_FRAC`] fraction bits, rounded to nearest.
    fn lanes_from_rgb(rgb: [i64; 3]) -> Self::Lanes;
    /// The lanes of an 8-bit colour: [`Self::lanes_from_rgb`] of
    /// `rgb · 2^16`, exactly. RGB formats override it with two 32-bit
    /// products a channel and no division (a vertex's colour, three per
    /// triangle and tile: about 150 instructions each on the Cortex-M0
    /// through the general path, measured).
    ///
    /// ```
    /// use tilerast::format::{PixelFormat, Rgb565Format};
    /// let exact = Rgb565Format::lanes_from_rgb([200 << 16, 100 << 16, 7 << 16]);
    /// assert_eq!(Rgb565Format::lanes_from_rgb8([200, 100, 7]), exact);
    /// ```
    #[inline(always)]
    fn lanes_from_rgb8(rgb: [u8; 3]) -> Self::Lanes {
        Self::lanes_from_rgb(rgb.map(|c| (c as i64) << COLOR_FRAC))
    }
    /// The lanes of a texel `rgb` (0..=255) modulated by `shade` (0.16, at
    /// most `2^16 + 2^8`): `rgb shade / 2^16` mapped like
    /// [`Self::lanes_from_rgb`]. RGB formats override it with 32-bit
    /// arithmetic and no division (a texel a pixel: three library
    /// divisions and six 64-bit multiplications on the Cortex-M0), within
    /// 2^-7 of an output unit of it.
    #[inline(always)]
    fn lanes_modulated(rgb: [u8; 3], shade: u32) -> Self::Lanes {
        Self::lanes_from_rgb(rgb.map(|c| c as i64 * shade as i64))
    }
    /// Packs quantized channel values (each within `0..=MAX`).
    fn pack(q: Self::Lanes) -> u32;
    /// Converts a packed pixel to its `embedded-graphics` colour.
    fn to_color(raw: u32) -> Self::Color;
    /// Packs an `embedded-graphics` colour (what a tile stores when used as
    /// a `DrawTarget`).
    fn from_color(c: Self::Color) -> u32;
    /// Splits a packed pixel into its channel values (each `0..=MAX`): what
    /// blending reads back.
    fn unpack(raw: u32) -> Self::Lanes;
    /// The channel values a write through `mask` (within [`Self::MASK_ALL`])
    /// reads back when it blends: [`Self::unpack`], except for formats
    /// that keep several images in one cell ([`Rgb444PairFormat`]).
    #[inline(always)]
    fn unpack_masked(raw: u32, mask: u32) -> Self::Lanes {
        let _ = mask;
        Self::unpack(raw)
    }

    /// A flat colour, rounded to nearest, packed: what fills write (the seed's
    /// fill bypasses the interpolating channels and the dither).
    ///
    /// ```
    /// use tilerast::format::{PixelFormat, Rgb, Rgb565Format};
    /// assert_eq!(Rgb565Format::pack_rgb(Rgb::new(255, 255, 255)), 0xFFFF);
    /// assert_eq!(Rgb565Format::pack_rgb(Rgb::new(255, 0, 0)), 0xF800);
    /// ```
    fn pack_rgb(c: Rgb) -> u32 {
        let l = Self::lanes_from_rgb8([c.r, c.g, c.b]);
        let half = 1 << (COLOR_FRAC - 1);
        Self::pack(l.zip(Self::MAX, |v, m| ((v + half) >> COLOR_FRAC).clamp(0, m)))
    }
}

// `lanes_from_rgb` keeps its input's 16 fraction bits: the DDA format must match.
const _: () = assert!(
    COLOR_FRAC == 16,
    "colour lanes carry the 16 fraction bits of the API's U16F16"
);

/// Scales one 0..255 channel (8.16) to `0..=max` (x.16), rounded. Colours
/// (as opposed to signed steps) take a `u32` path — `v * max + 127` stays
/// below 2^32 for `v < 2^24`, `max <= 255` — with the same result as the
/// `i64` one and no 64-bit division (a long library call on Cortex-M0).
#[inline(always)]
fn scale(v: i64, max: i32) -> i32 {
    match u32::try_from(v) {
        Ok(u) if u < 1 << 24 => div255(u * max as u32 + 127) as i32,
        _ => div_round(v * max as i64, 255) as i32,
    }
}

/// [`scale`] of an integer channel `c << 16` (`max <= 255`): with
/// `t = c max <= 65,025` and `2^16 = 255 · 257 + 1`,
/// `(t 2^16 + 127) / 255 = 257 t + (t + 127) / 255`, whose floor's second
/// term is `(t + 128) 257 / 2^16` ([`div255`]'s identity below 2^16).
/// Every `c` and `max` is checked against [`scale`] in the tests.
#[inline(always)]
const fn scale8(c: u8, max: i32) -> i32 {
    let t = c as u32 * max as u32;
    (t * 257 + (((t + 128) * 257) >> 16)) as i32
}

/// [`scale8`] of every channel value for a channel of `MAX`: 1 KB of
/// flash per channel size a program converts 8-bit colours to (only the
/// sizes its formats use are linked). The mesh path converts nine
/// channels a (tile, triangle) pair: two instructions each from here
/// instead of seven (the Cortex-M4 teapot: about 50 a pair, measured).
struct Scale8<const MAX: i32>;

impl<const MAX: i32> Scale8<MAX> {
    const TABLE: [i32; 256] = {
        let mut t = [0; 256];
        let mut c = 0;
        while c < 256 {
            t[c] = scale8(c as u8, MAX);
            c += 1;
        }
        t
    };

    #[inline(always)]
    fn of(c: u8) -> i32 {
        Self::TABLE[c as usize]
    }
}

/// `c shade / 2^16` (`c` on the 0..255 scale, `shade` 0.16) in the output
/// scale `0..=max` with 16 fraction bits: `c max / 255` to 8 fraction bits
/// (`x 257 / 2^16` for `/ 255`, within 2^-8), then times the shade, all
/// below 2^32 (`255 · 255 · 257 < 2^24`, `65,280 · 65,792 < 2^32`).
#[inline(always)]
fn modulate(c: u8, max: u32, shade: u32) -> i32 {
    let t = (c as u32 * max * 257) >> 8;
    ((t * shade.min(65_792)) >> 8) as i32
}

/// Scales RGB (8.16) to a luma lane `0..=max` (x.16), rounded.
#[inline]
fn scale_luma(rgb: [i64; 3], max: i32) -> i32 {
    let y = 77 * rgb[0] + 150 * rgb[1] + 29 * rgb[2];
    div_round(y * max as i64, 255 * 256) as i32
}

macro_rules! rgb_format {
    ($name:ident, $color:ty, $cell:ty, [$r:expr, $g:expr, $b:expr], $mask:expr, $label:expr, $doc:expr) => {
        #[doc = $doc]
        #[derive(Debug, Clone, Copy, Default)]
        pub struct $name;
        impl PixelFormat for $name {
            type Color = $color;
            type Plane<const N: usize> = Plane<$cell, N>;
            type Lanes = [i32; 3];
            const MAX: [i32; 3] = [$r, $g, $b];
            const MASK_ALL: u32 = $mask;
            const NAME: &'static str = $label;
            #[inline(always)]
            fn lanes_from_rgb(rgb: [i64; 3]) -> [i32; 3] {
                [scale(rgb[0], $r), scale(rgb[1], $g), scale(rgb[2], $b)]
            }
            #[inline(always)]
            fn lanes_from_rgb8(rgb: [u8; 3]) -> [i32; 3] {
                [
                    Scale8::<{ $r }>::of(rgb[0]),
                    Scale8::<{ $g }>::of(rgb[1]),
                    Scale8::<{ $b }>::of(rgb[2]),
                ]
            }
            #[inline(always)]
            fn lanes_modulated(rgb: [u8; 3], shade: u32) -> [i32; 3] {
                [
                    modulate(rgb[0], $r, shade),
                    modulate(rgb[1], $g, shade),
                    modulate(rgb[2], $b, shade),
                ]
            }
            #[inline(always)]
            fn pack(q: [i32; 3]) -> u32 {
                const GB: u32 = ($g as u32 + 1).trailing_zeros();
                const BB: u32 = ($b as u32 + 1).trailing_zeros();
                (q[0] as u32) << (GB + BB) | (q[1] as u32) << BB | q[2] as u32
            }
            #[inline]
            fn to_color(raw: u32) -> $color {
                const GB: u32 = ($g as u32 + 1).trailing_zeros();
                const BB: u32 = ($b as u32 + 1).trailing_zeros();
                <$color>::new(
                    (raw >> (GB + BB)) as u8 & $r,
                    (raw >> BB) as u8 & $g,
                    raw as u8 & $b,
                )
            }
            #[inline]
            fn from_color(c: $color) -> u32 {
                Self::pack([c.r() as i32, c.g() as i32, c.b() as i32])
            }
            #[inline]
            fn unpack(raw: u32) -> [i32; 3] {
                const GB: u32 = ($g as u32 + 1).trailing_zeros();
                const BB: u32 = ($b as u32 + 1).trailing_zeros();
                [
                    (raw >> (GB + BB)) as i32 & $r,
                    (raw >> BB) as i32 & $g,
                    raw as i32 & $b,
                ]
            }
        }
    };
}

rgb_format!(
    Rgb888Format,
    Rgb888,
    [u8; 3],
    [255, 255, 255],
    0xFF_FFFF,
    "rgb888",
    "24-bit true colour, 3 bytes per pixel."
);
rgb_format!(
    Rgb565Format,
    Rgb565,
    u16,
    [31, 63, 31],
    0xFFFF,
    "rgb565",
    "16-bit colour (ST7789, ILI9341), 2 bytes per pixel."
);
rgb_format!(
    Rgb444Format,
    Rgb444,
    u16,
    [15, 15, 15],
    0x0FFF,
    "rgb444",
    "12-bit colour, the seed's double-buffered half-plane mode (`0x0RGB` in 2 bytes)."
);

/// 8-bit grey, 1 byte per pixel.
#[derive(Debug, Clone, Copy, Default)]
pub struct Gray8Format;
impl PixelFormat for Gray8Format {
    type Color = Gray8;
    type Plane<const N: usize> = Plane<u8, N>;
    type Lanes = [i32; 1];
    const MAX: [i32; 1] = [255];
    const MASK_ALL: u32 = 0xFF;
    const NAME: &'static str = "gray8";
    #[inline]
    fn lanes_from_rgb(rgb: [i64; 3]) -> [i32; 1] {
        [scale_luma(rgb, 255)]
    }
    #[inline(always)]
    fn pack(q: [i32; 1]) -> u32 {
        q[0] as u32
    }
    fn to_color(raw: u32) -> Gray8 {
        Gray8::new(raw as u8)
    }
    fn from_color(c: Gray8) -> u32 {
        c.luma() as u32
    }
    fn unpack(raw: u32) -> [i32; 1] {
        [raw as i32 & 255]
    }
}

/// 1 bit per pixel (SSD1306 class), 8 pixels per byte. Shading shows only
/// through dithering.
#[derive(Debug, Clone, Copy, Default)]
pub struct BinaryFormat;
impl PixelFormat for BinaryFormat {
    type Color = BinaryColor;
    type Plane<const N: usize> = BitPlane<N>;
    type Lanes = [i32; 1];
    const MAX: [i32; 1] = [1];
    const MASK_ALL: u32 = 1;
    const NAME: &'static str = "binary";
    #[inline]
    fn lanes_from_rgb(rgb: [i64; 3]) -> [i32; 1] {
        [scale_luma(rgb, 1)]
    }
    #[inline(always)]
    fn pack(q: [i32; 1]) -> u32 {
        q[0] as u32
    }
    fn to_color(raw: u32) -> BinaryColor {
        BinaryColor::from(raw & 1 != 0)
    }
    fn from_color(c: BinaryColor) -> u32 {
        c.is_on() as u32
    }
    fn unpack(raw: u32) -> [i32; 1] {
        [raw as i32 & 1]
    }
}

/// One 12-bit half of an [`Rgb444PairFormat`] cell: the front or back
/// buffer of the seed's double buffering.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Half {
    /// Bits 0..12.
    Low,
    /// Bits 12..24.
    High,
}

impl Half {
    /// The plane mask that writes this half only (a command's
    /// [`State::plane_mask`](crate::command::State::plane_mask)).
    pub const fn mask(self) -> u32 {
        0xFFF << self.shift()
    }
    /// The other half: the back buffer becomes the front after a frame.
    pub const fn other(self) -> Half {
        match self {
            Half::Low => Half::High,
            Half::High => Half::Low,
        }
    }
    const fn shift(self) -> u32 {
        match self {
            Half::Low => 0,
            Half::High => 12,
        }
    }
}

/// The seed's double buffer (seed 001 §II.2, "image plane split in two"):
/// one 24-bit plane (3 bytes a pixel) holding **two RGB444 images**, a front
/// buffer being shown while the back one is drawn. Each half is 12-bit
/// colour; an ordered dither ([`Bayer8`](crate::fragment::dither::Bayer8))
/// makes it look close to 24-bit, as REjr does. Use it for a frame buffer
/// in RAM that a display controller scans out (one half at a time), when
/// two RGB565 buffers do not fit: 3 bytes a pixel instead of 4.
///
/// A frame draws into the back half by giving every command that half's
/// plane mask ([`Half::mask`]: clear it with a masked `Fill` and `ZFill`,
/// not [`Tile::begin`](crate::tile::Tile::begin), which clears both). An
/// unmasked write fills both halves. Blending (edge and Wu antialiasing)
/// reads the half it writes. [`PixelFormat::to_color`] reads the low half;
/// [`Rgb444PairFormat::half`] either one.
///
/// ```
/// use tilerast::prelude::*;
/// use tilerast::format::{Half, Rgb444, Rgb444PairFormat};
/// let mut tile: Tile<2, Rgb444PairFormat> = Tile::new(); // 16 pixels
/// tile.begin(Rect::new(0, 0, 4, 4), &Clear::default())?;
/// let mut back = State::new(0);
/// back.plane_mask = Half::High.mask();
/// tile.draw(&Command::Fill { rect: Rect::new(0, 0, 4, 4), color: Rgb::new(255, 0, 0), state: back, alpha: 255 })?;
/// let raw = tile.raw(1, 1).unwrap();
/// assert_eq!(Rgb444PairFormat::half(raw, Half::High), Rgb444::new(15, 0, 0)); // drawn
/// assert_eq!(Rgb444PairFormat::half(raw, Half::Low), Rgb444::new(0, 0, 0)); // untouched
/// # Ok::<(), Error>(())
/// ```
#[derive(Debug, Clone, Copy, Default)]
pub struct Rgb444PairFormat;

impl Rgb444PairFormat {
    /// The colour one half of a packed cell holds.
    pub const fn half(raw: u32, h: Half) -> Rgb444 {
        Rgb444((raw >> h.shift()) as u16 & 0xFFF)
    }
}

impl PixelFormat for Rgb444PairFormat {
    type Color = Rgb444;
    type Plane<const N: usize> = Plane<[u8; 3], N>;
    type Lanes = [i32; 3];
    const MAX: [i32; 3] = [15, 15, 15];
    const MASK_ALL: u32 = 0xFF_FFFF;
    const NAME: &'static str = "rgb444x2";
    #[inline(always)]
    fn lanes_from_rgb(rgb: [i64; 3]) -> [i32; 3] {
        Rgb444Format::lanes_from_rgb(rgb)
    }
    #[inline(always)]
    fn pack(q: [i32; 3]) -> u32 {
        let c = Rgb444Format::pack(q);
        c | c << 12
    }
    #[inline]
    fn to_color(raw: u32) -> Rgb444 {
        Self::half(raw, Half::Low)
    }
    #[inline]
    fn from_color(c: Rgb444) -> u32 {
        let c = c.0 as u32;
        c | c << 12
    }
    #[inline]
    fn unpack(raw: u32) -> [i32; 3] {
        Rgb444Format::unpack(raw & 0xFFF)
    }
    #[inline(always)]
    fn unpack_masked(raw: u32, mask: u32) -> [i32; 3] {
        let h = if mask & 0xFFF == 0 { 12 } else { 0 };
        Rgb444Format::unpack((raw >> h) & 0xFFF)
    }
}

/// 12-bit RGB colour (4 bits per channel), which `embedded-graphics` lacks.
///
/// ```
/// use tilerast::format::Rgb444;
/// use embedded_graphics_core::pixelcolor::{Rgb888, RgbColor};
/// assert_eq!(Rgb888::from(Rgb444::new(15, 8, 0)), Rgb888::new(255, 136, 0));
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Rgb444(u16);

impl Rgb444 {
    /// A colour from 4-bit channels (higher bits are ignored).
    pub const fn new(r: u8, g: u8, b: u8) -> Self {
        Rgb444(((r as u16 & 15) << 8) | ((g as u16 & 15) << 4) | (b as u16 & 15))
    }
}

impl PixelColor for Rgb444 {
    type Raw = RawU16;
}

impl From<Rgb444> for RawU16 {
    fn from(c: Rgb444) -> Self {
        RawU16::new(c.0)
    }
}

impl RgbColor for Rgb444 {
    fn r(&self) -> u8 {
        (self.0 >> 8) as u8 & 15
    }
    fn g(&self) -> u8 {
        (self.0 >> 4) as u8 & 15
    }
    fn b(&self) -> u8 {
        self.0 as u8 & 15
    }
    const MAX_R: u8 = 15;
    const MAX_G: u8 = 15;
    const MAX_B: u8 = 15;
    const BLACK: Self = Rgb444::new(0, 0, 0);
    const RED: Self = Rgb444::new(15, 0, 0);
    const GREEN: Self = Rgb444::new(0, 15, 0);
    const BLUE: Self = Rgb444::new(0, 0, 15);
    const YELLOW: Self = Rgb444::new(15, 15, 0);
    const MAGENTA: Self = Rgb444::new(15, 0, 15);
    const CYAN: Self = Rgb444::new(0, 15, 15);
    const WHITE: Self = Rgb444::new(15, 15, 15);
}

/// Expands a 4-bit channel exactly (`v * 17`).
const fn x17(v: u8) -> u8 {
    v * 17
}

impl From<Rgb444> for Rgb888 {
    fn from(c: Rgb444) -> Self {
        Rgb888::new(x17(c.r()), x17(c.g()), x17(c.b()))
    }
}

impl From<Rgb444> for Rgb565 {
    fn from(c: Rgb444) -> Self {
        Rgb565::from(Rgb888::from(c))
    }
}

impl From<Rgb444> for Gray8 {
    fn from(c: Rgb444) -> Self {
        Gray8::from(Rgb888::from(c))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    #[test]
    fn extremes_map_to_channel_limits() {
        assert_eq!(Rgb444Format::pack_rgb(Rgb::new(255, 255, 255)), 0xFFF);
        assert_eq!(Rgb888Format::pack_rgb(Rgb::new(1, 2, 3)), 0x010203);
        assert_eq!(Gray8Format::pack_rgb(Rgb::new(255, 255, 255)), 255);
        assert_eq!(BinaryFormat::pack_rgb(Rgb::new(255, 255, 255)), 1);
        assert_eq!(BinaryFormat::pack_rgb(Rgb::new(0, 0, 0)), 0);
        let c = Rgb565Format::to_color(0xF800);
        assert_eq!(Rgb888::from(c), Rgb888::new(255, 0, 0));
    }

    #[test]
    fn eight_bit_channels_scale_exactly() {
        for max in 1..=255 {
            for c in 0..=255u8 {
                assert_eq!(scale8(c, max), scale((c as i64) << 16, max), "{c} {max}");
            }
        }
        fn same<F: PixelFormat<Lanes = L>, L: PartialEq + core::fmt::Debug>(c: [u8; 3]) {
            let wide = c.map(|v| (v as i64) << 16);
            assert_eq!(
                F::lanes_from_rgb8(c),
                F::lanes_from_rgb(wide),
                "{}",
                F::NAME
            );
        }
        for c in [[0, 0, 0], [255, 255, 255], [1, 128, 254], [17, 34, 51]] {
            same::<Rgb565Format, _>(c);
            same::<Rgb444Format, _>(c);
            same::<Rgb888Format, _>(c);
            same::<Gray8Format, _>(c);
        }
    }
}

/// Colour-plane storage and the lanes of a fragment: the tile's internals.
/// Public only with the `unstable` feature (the research crate and the
/// tests use them); no stability promise.
mod planes {
    #![allow(unused_imports)]
    use super::*;

    /// The interpolated channels of one fragment: `[i32; 3]` for RGB formats,
    /// `[i32; 1]` for grey and binary. Each lane is a fixed-point value in the
    /// output channel scale with [`COLOR_FRAC`] fraction bits.
    pub trait Lanes: Copy + core::fmt::Debug {
        /// Number of lanes.
        const LEN: usize;
        /// Builds lanes from a function of the lane index.
        fn from_fn(f: impl FnMut(usize) -> i32) -> Self;
        /// Lane `i`.
        fn lane(&self, i: usize) -> i32;
        /// Lane-wise map.
        #[inline(always)]
        fn map(self, mut f: impl FnMut(i32) -> i32) -> Self {
            Self::from_fn(|i| f(self.lane(i)))
        }
        /// Lane-wise combination.
        #[inline(always)]
        fn zip(self, o: Self, mut f: impl FnMut(i32, i32) -> i32) -> Self {
            Self::from_fn(|i| f(self.lane(i), o.lane(i)))
        }
    }

    impl<const C: usize> Lanes for [i32; C] {
        const LEN: usize = C;
        #[inline(always)]
        fn from_fn(mut f: impl FnMut(usize) -> i32) -> Self {
            // Unrolled by hand for one and three lanes: `core::array::from_fn`
            // stayed an out-of-line call on thumbv7em (1.2 M instructions a
            // teapot frame), and at `opt-level = "s"` (the micro:bit) a loop
            // is not unrolled, so the lanes lived in stack arrays walked
            // per pixel (measured).
            let mut out = [0; C];
            if C == 3 {
                out[0] = f(0);
                out[1] = f(1);
                out[2] = f(2);
            } else if C == 1 {
                out[0] = f(0);
            } else {
                for (i, o) in out.iter_mut().enumerate() {
                    *o = f(i);
                }
            }
            out
        }
        #[inline(always)]
        fn lane(&self, i: usize) -> i32 {
            self[i]
        }
    }

    /// Storage of one plane for `8 N` pixels; values travel as `u32`.
    pub trait ColorPlane: Sized {
        /// A plane of zeros (a constant, so tiles can be built in `const`
        /// context and live in a `static`).
        const NEW: Self;
        /// The value at pixel index `i` (`i < 8 N`).
        fn get(&self, i: usize) -> u32;
        /// Stores `v` (already within the plane's bit width) at pixel index `i`.
        fn set(&mut self, i: usize, v: u32);
        /// Stores `v` at every pixel index of `r` (`r.end <= 8 N`): a flat
        /// span or a row of a rectangle. Cell planes override it with a
        /// slice fill, which the compiler turns into wide stores.
        #[inline(always)]
        fn fill(&mut self, r: core::ops::Range<usize>, v: u32) {
            for i in r {
                self.set(i, v);
            }
        }
    }

    /// One element of a [`Plane`].
    pub trait Cell: Copy + Default {
        /// Zero.
        const ZERO: Self;
        /// Widens to `u32`.
        fn to_u32(self) -> u32;
        /// Narrows from `u32` (the value fits by construction).
        fn from_u32(v: u32) -> Self;
    }

    /// The unsigned integer cells.
    macro_rules! int_cells {
        ($($t:ty),*) => {$(
            impl Cell for $t {
                const ZERO: Self = 0;
                #[inline(always)]
                #[allow(clippy::unnecessary_cast)]
                fn to_u32(self) -> u32 {
                    self as u32
                }
                #[inline(always)]
                #[allow(clippy::unnecessary_cast)]
                fn from_u32(v: u32) -> Self {
                    v as $t
                }
            }
        )*};
    }
    int_cells!(u8, u16, u32);

    impl Cell for [u8; 3] {
        const ZERO: Self = [0; 3];
        #[inline(always)]
        fn to_u32(self) -> u32 {
            (self[0] as u32) << 16 | (self[1] as u32) << 8 | self[2] as u32
        }
        #[inline(always)]
        fn from_u32(v: u32) -> Self {
            [(v >> 16) as u8, (v >> 8) as u8, v as u8]
        }
    }

    /// A plane of `8 N` cells of type `T`, stored as `N` groups of 8 so that the
    /// 1-bit format can pack a group into one byte with the same `N`.
    ///
    /// ```
    /// use tilerast::format::{ColorPlane, Plane};
    /// let mut p: Plane<u16, 2> = Plane::NEW;
    /// p.set(15, 0xBEEF);
    /// assert_eq!(p.get(15), 0xBEEF);
    /// assert_eq!(core::mem::size_of::<Plane<u16, 2>>(), 32);
    /// ```
    #[derive(Clone)]
    pub struct Plane<T, const N: usize>(pub [[T; 8]; N]);

    impl<T: Cell, const N: usize> ColorPlane for Plane<T, N> {
        const NEW: Self = Plane([[T::ZERO; 8]; N]);
        #[inline(always)]
        fn get(&self, i: usize) -> u32 {
            self.0.as_flattened()[i].to_u32()
        }
        #[inline(always)]
        fn set(&mut self, i: usize, v: u32) {
            self.0.as_flattened_mut()[i] = T::from_u32(v);
        }
        #[inline(always)]
        fn fill(&mut self, r: core::ops::Range<usize>, v: u32) {
            if let Some(cells) = self.0.as_flattened_mut().get_mut(r) {
                fill_cells(cells, T::from_u32(v));
            }
        }
    }

    /// `cells.fill(v)`. On a host, spans of a few dozen pixels (a triangle's
    /// rows) are stored in blocks of 8 cells, the last block overlapping
    /// the one before it and a short span by two overlapping halves, so
    /// there is no element-by-element tail whose end a branch predictor
    /// misses once a row (host, 1,077-px flat triangles: 0.36 ns/px
    /// against 0.92 with the slice's fill, measured). A microcontroller
    /// has no branch predictor to miss: there the library's fill.
    #[inline(always)]
    fn fill_cells<T: Copy>(cells: &mut [T], v: T) {
        if crate::numeric::MCU32 {
            // Four cells a step (whole tiles cleared: the Cortex-M4's
            // RGB565 + Z16 clear 1.8 -> 0.8 instructions a cell with
            // the library's fill, measured). ARMv7-M merges the block's
            // copy into word stores; the Cortex-M0 build (opt-level "s")
            // makes it a `memcpy` call, so there four plain stores
            // (the micro:bit cube's raster 64.6 -> 55.8 K ticks a frame).
            let mut blocks = cells.chunks_exact_mut(4);
            for b in &mut blocks {
                if crate::numeric::LONG_MUL {
                    b.copy_from_slice(&[v; 4]);
                } else {
                    (b[0], b[1], b[2], b[3]) = (v, v, v, v);
                }
            }
            return blocks.into_remainder().fill(v);
        }
        let n = cells.len();
        if n >= 8 {
            let block = [v; 8];
            let mut i = 0;
            while i + 8 < n {
                cells[i..i + 8].copy_from_slice(&block);
                i += 8;
            }
            cells[n - 8..].copy_from_slice(&block);
        } else if n >= 4 {
            let half = [v; 4];
            cells[..4].copy_from_slice(&half);
            cells[n - 4..].copy_from_slice(&half);
        } else if n >= 2 {
            let half = [v; 2];
            cells[..2].copy_from_slice(&half);
            cells[n - 2..].copy_from_slice(&half);
        } else if n == 1 {
            cells[0] = v;
        }
    }

    /// A 1-bit plane: 8 pixels per byte, bit `i % 8` of byte `i / 8`.
    ///
    /// ```
    /// use tilerast::format::{BitPlane, ColorPlane};
    /// let mut p: BitPlane<4> = BitPlane::NEW; // 32 pixels in 4 bytes
    /// p.set(9, 1);
    /// assert_eq!((p.get(8), p.get(9)), (0, 1));
    /// assert_eq!(core::mem::size_of::<BitPlane<4>>(), 4);
    /// ```
    #[derive(Clone)]
    pub struct BitPlane<const N: usize>(pub [u8; N]);

    impl<const N: usize> ColorPlane for BitPlane<N> {
        const NEW: Self = BitPlane([0; N]);
        #[inline(always)]
        fn get(&self, i: usize) -> u32 {
            (self.0[i >> 3] >> (i & 7)) as u32 & 1
        }
        #[inline(always)]
        fn set(&mut self, i: usize, v: u32) {
            let b = &mut self.0[i >> 3];
            *b = (*b & !(1 << (i & 7))) | (((v & 1) as u8) << (i & 7));
        }
    }
}

#[cfg(feature = "unstable")]
pub use planes::{BitPlane, Cell, ColorPlane, Lanes, Plane};
#[cfg(not(feature = "unstable"))]
pub(crate) use planes::{BitPlane, Cell, ColorPlane, Lanes, Plane};
