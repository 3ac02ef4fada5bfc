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

use crate::command::Command;
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

/// Which command kinds a tile draws: code, not a plane ([`AllCommands`] or
/// [`Triangles`]). A kind a set leaves out is not compiled into the tile's
/// draw code; a command of that kind reaching the tile draws nothing and
/// is reported as [`Error::ConfigMismatch`](crate::Error::ConfigMismatch)
/// (by [`Tile::draw`](crate::tile::Tile::draw) and by the frame).
///
/// ```
/// use tilerast::prelude::*;
/// // A 1-bit OLED drawing meshes only: no line, span, edge or fast-Phong
/// // code (`MeshPlanes` spells the same).
/// type Oled = Planes<BinaryFormat, Depth16, NoWid, Bayer4,
///                    NoAa, FullPrecision, NoBlending, GouraudShading, NoTexturing, Triangles>;
/// let mut tile: Tile<8, Oled> = Tile::new();
/// tile.begin(Rect::new(0, 0, 8, 8), &Clear::default())?;
/// tile.draw(&Command::fill(Rect::new(0, 0, 8, 8), Rgb::new(255, 255, 255)))?;
/// use tilerast::line::{LineCmd, LineStyle};
/// let p = |v: i32| (Coord::from_num(v), Coord::from_num(v));
/// let line = LineCmd { p0: p(0), p1: p(7), z: [0, 0], color: Rgb::new(0, 0, 0),
///                      style: LineStyle::SOLID, antialias: false };
/// assert_eq!(tile.draw(&Command::line(line)), Err(Error::ConfigMismatch));
/// # Ok::<(), Error>(())
/// ```
pub trait CommandSet {
    /// Whether lines, spans, antialiased edges and quadratic (fast-Phong)
    /// triangles are drawn; triangles (flat, Gouraud, textured) and fills
    /// always are.
    const ALL: bool;

    /// Whether a tile with this set draws `cmd`.
    #[inline(always)]
    fn draws(cmd: &Command) -> bool {
        Self::ALL
            || matches!(
                cmd,
                Command::Triangle { .. }
                    | Command::Textured { .. }
                    | Command::Fill { .. }
                    | Command::ZFill { .. }
                    | Command::WidFill { .. }
            )
    }
}

/// Every command kind: the default.
pub struct AllCommands;
impl CommandSet for AllCommands {
    const ALL: bool = true;
}

/// Triangles (flat, Gouraud, textured) and fills only: what a mesh scene
/// needs. On the Cortex-M4 the SSD1306 scene's firmware is 20 KB smaller
/// with it (`reports/targets.md`, "Flash and RAM").
pub struct Triangles;
impl CommandSet for Triangles {
    const ALL: bool = false;
}

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
    /// Which command kinds are drawn ([`AllCommands`] or [`Triangles`]):
    /// code, not a plane.
    type Commands: CommandSet;
}

/// Any combination of planes: the full generic form of a [`TileConfig`].
/// Unnamed planes default to absent, precision to full, blending to none,
/// shading to Gouraud, texturing to none, commands to all.
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
    K = AllCommands,
>(PhantomData<(F, Z, W, D, A, P, B, S, X, K)>);

impl<F, Z, W, D, A, P, B, S, X, K> TileConfig for Planes<F, Z, W, D, A, P, B, S, X, K>
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
    K: CommandSet,
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
    type Commands = K;
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
            type Commands = AllCommands;
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

/// A configuration that draws meshes only ([`Triangles`]): colour format
/// `F`, depth `Z`, window ID `W` and dither `D` as in [`Planes`], every
/// other parameter its default — no line, span, edge or fast-Phong code.
///
/// ```
/// use tilerast::prelude::*;
/// type Oled = MeshPlanes<BinaryFormat, Depth16, NoWid, Bayer4>;
/// assert_eq!(Tile::<128, Oled>::bits_per_pixel(), 1 + 16);
/// ```
pub type MeshPlanes<F, Z = NoDepth, W = NoWid, D = NoDither> =
    Planes<F, Z, W, D, NoAa, FullPrecision, NoBlending, GouraudShading, NoTexturing, Triangles>;

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

#[cfg(test)]
mod tests {
    extern crate std;
    use crate::prelude::*;
    use crate::raster::line::{LineCmd, LineStyle};
    use std::{vec, vec::Vec};

    type Full = Planes<Rgb565Format, Depth16, NoWid, Bayer4>;
    type Meshes = MeshPlanes<Rgb565Format, Depth16, NoWid, Bayer4>;

    fn scene(with_line: bool) -> DisplayList<4> {
        let v = |x: i32, y: i32, c: u8| {
            Vertex::new(
                Coord::from_num(x),
                Coord::from_num(y),
                100,
                Rgb::new(c, 90, 200 - c),
            )
        };
        let mut l = DisplayList::new();
        l.push(Command::fill(Rect::new(0, 0, 24, 16), Rgb::new(5, 6, 7)))
            .unwrap();
        l.push(Command::triangle([
            v(1, 1, 0),
            v(23, 4, 120),
            v(6, 15, 200),
        ]))
        .unwrap();
        if with_line {
            let p = |x: i32, y: i32| (Coord::from_num(x), Coord::from_num(y));
            l.push(Command::line(LineCmd {
                p0: p(0, 15),
                p1: p(23, 0),
                z: [0, 0],
                color: Rgb::new(255, 255, 255),
                style: LineStyle::SOLID,
                antialias: false,
            }))
            .unwrap();
        }
        l
    }

    /// Every pixel of `list` rendered in 8x8 tiles of configuration `C`.
    fn pixels<C: TileConfig>(list: &DisplayList<4>) -> Result<Vec<u32>, Error> {
        let mut tile: Tile<8, C> = Tile::new();
        let frame = Tile::<8, C>::frame::<8, 8>(24, 16)?;
        let mut out = vec![];
        frame
            .render_with(&mut tile, list, |t| {
                let a = t.area();
                for y in a.y..a.y + a.h as i32 {
                    for x in a.x..a.x + a.w as i32 {
                        out.push(t.raw(x, y).unwrap());
                    }
                }
                Ok::<(), ()>(())
            })
            .map_err(|e| match e {
                FlushError::Raster(e) => e,
                _ => Error::Malformed,
            })?;
        Ok(out)
    }

    #[test]
    fn triangles_only_draws_meshes_as_every_command_does() {
        let list = scene(false);
        assert_eq!(pixels::<Meshes>(&list), pixels::<Full>(&list));
    }

    #[test]
    fn a_command_kind_left_out_is_an_error_not_a_blank() {
        let list = scene(true);
        assert!(pixels::<Full>(&list).is_ok());
        assert_eq!(pixels::<Meshes>(&list), Err(Error::ConfigMismatch));
        let mut tile: Tile<8, Meshes> = Tile::new();
        tile.begin(Rect::new(0, 0, 8, 8), &Clear::default())
            .unwrap();
        assert_eq!(tile.draw(&list[2]), Err(Error::ConfigMismatch));
        // The refusal does not stick to the next command.
        assert_eq!(tile.draw(&list[0]), Ok(()));
    }
}
