//! Tile configurations: one type names every plane of a tile — colour
//! format, depth, window ID, dither, coverage antialiasing, precision, blending
//! and shading —
//! so a program writes `Tile<N, St7789Config>` instead of eight parameters, and
//! the frame, the overlay and the firmware helpers carry one name.
//!
//! Every plane the configuration leaves out is a zero-sized type: it costs
//! no byte of RAM and its per-pixel test compiles to nothing. A display
//! format alone is a configuration too (colour only), and [`Planes`] spells
//! out any other combination.
//!
//! ```
//! use tilerast::prelude::*;
//! // The presets...
//! assert_eq!(Tile::<300, St7789Config>::bits_per_pixel(), 16 + 16);
//! assert_eq!(Tile::<128, Ssd1306Config>::bits_per_pixel(), 1);
//! // ...a bare format (colour only)...
//! assert_eq!(Tile::<8, Rgb888Format>::bits_per_pixel(), 24);
//! // ...and the full generic form.
//! type Mine = Planes<Rgb444Format, Depth24, Wid8, Bayer8>;
//! assert_eq!(Tile::<8, Mine>::bits_per_pixel(), 16 + 24 + 8);
//! ```
//!
//! Tiles are sized in groups of 8 pixels; [`groups`] names pixels instead
//! and [`Tile::frame`](crate::tile::Tile::frame) checks a frame's tile size
//! against the type at compile time.

use crate::format::{
    BinaryFormat, Gray8Format, PixelFormat, Rgb444Format, Rgb444PairFormat, Rgb565Format,
    Rgb888Format,
};
use crate::fragment::dither::{Bayer4, Dither, NoDither};
use crate::fragment::{
    BlendMode, Depth16, DepthMode, GouraudShading, NoBlending, NoDepth, NoWid, ShadingMode, WidMode,
};
use crate::numeric::{FullPrecision, Precision};
use crate::raster::coverage::{AaMode, NoAa};
use crate::texture::{NoTexturing, TextureMode};
use core::marker::PhantomData;

/// What a tile holds and how it writes: one type for the nine choices.
pub trait TileConfig {
    /// Display format of the colour plane.
    type Format: PixelFormat;
    /// Depth plane ([`NoDepth`], [`Depth16`], `Depth24`, `Depth32`).
    type Depth: DepthMode;
    /// Window-ID plane ([`NoWid`] or `Wid8`).
    type Wid: WidMode;
    /// Ordered dither ([`NoDither`], `Bayer2` .. `Bayer16`).
    type Dither: Dither;
    /// Coverage antialiasing plane ([`NoAa`], RUF or supersampling).
    type Aa: AaMode;
    /// Fraction bits of the span DDAs ([`FullPrecision`] or `Bits<C, Z>`).
    type Precision: Precision;
    /// Whether translucent commands blend ([`NoBlending`] or
    /// `AlphaBlending`): code, not a plane.
    type Blending: BlendMode;
    /// Whether quadratic (fast Phong) triangles are stepped quadratically
    /// ([`GouraudShading`] or `QuadraticShading`): code, not a plane.
    type Shading: ShadingMode;
    /// How textured triangles map their textures
    /// ([`crate::texture::NoTexturing`], `AffineTexturing`,
    /// `QuadraticTexturing`, `ExactTexturing`): code, not a plane.
    type Texturing: TextureMode;
}

/// Any combination of planes: the full generic form of a [`TileConfig`].
/// Unnamed planes default to absent, precision to full, blending to none,
/// shading to Gouraud, texturing to none.
#[allow(clippy::type_complexity)]
pub struct Planes<
    F,
    Z = NoDepth,
    W = NoWid,
    D = NoDither,
    A = NoAa,
    P = FullPrecision,
    B = NoBlending,
    S = GouraudShading,
    X = NoTexturing,
>(PhantomData<(F, Z, W, D, A, P, B, S, X)>);

impl<F, Z, W, D, A, P, B, S, X> TileConfig for Planes<F, Z, W, D, A, P, B, S, X>
where
    F: PixelFormat,
    Z: DepthMode,
    W: WidMode,
    D: Dither,
    A: AaMode,
    P: Precision,
    B: BlendMode,
    S: ShadingMode,
    X: TextureMode,
{
    type Format = F;
    type Depth = Z;
    type Wid = W;
    type Dither = D;
    type Aa = A;
    type Precision = P;
    type Blending = B;
    type Shading = S;
    type Texturing = X;
}

/// A display format alone is a configuration: colour plane only, no
/// dither.
macro_rules! format_configs {
    ($($f:ty),*) => {$(
        impl TileConfig for $f {
            type Format = $f;
            type Depth = NoDepth;
            type Wid = NoWid;
            type Dither = NoDither;
            type Aa = NoAa;
            type Precision = FullPrecision;
            type Blending = NoBlending;
            type Shading = GouraudShading;
            type Texturing = NoTexturing;
        }
    )*};
}
format_configs!(
    Rgb888Format,
    Rgb565Format,
    Rgb444Format,
    Rgb444PairFormat,
    Gray8Format,
    BinaryFormat
);

/// Preset for colour TFTs (ST7789, ILI9341, GC9A01): RGB565, 16-bit Z,
/// 4x4 ordered dither — 4 bytes a pixel.
pub type St7789Config = Planes<Rgb565Format, Depth16, NoWid, Bayer4>;

/// Preset for one-bit OLEDs (SSD1306, SH1106): 1 bit a pixel with a 4x4
/// ordered dither, no depth (draw back to front).
pub type Ssd1306Config = Planes<BinaryFormat, NoDepth, NoWid, Bayer4>;

/// Groups of 8 pixels a `w x h` tile needs: the `N` of
/// [`Tile<N, C>`](crate::tile::Tile), named in pixels.
///
/// ```
/// use tilerast::prelude::*;
/// type PanelTile = Tile<{ groups(60, 40) }, St7789Config>; // 2400 pixels
/// assert_eq!(PanelTile::CAPACITY, 2400);
/// assert_eq!(groups(3, 3), 2); // rounded up
/// ```
pub const fn groups(w: u16, h: u16) -> usize {
    (w as usize * h as usize).div_ceil(8)
}
