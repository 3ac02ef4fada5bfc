//! Texture mapping (seed 001 §IV.3): texture planes read in place, texel
//! addressing and filtering, and the perspective modes a tile compiles.
//!
//! **Planes.** A [`Texture`] borrows its texels — a `&'static [u8]` in
//! flash or any slice in RAM — in one of four formats ([`TexFormat`]:
//! RGB565 little-endian, RGB888, Gray8, or 8-bit indices into a palette of
//! [`Rgb`]), any size up to 4096 texels a side, addressed with
//! [`Wrap::Repeat`] or [`Wrap::Clamp`] and filtered [`Filter::Nearest`] or
//! [`Filter::Bilinear`]. Nothing is copied; a frame's textures are a slice
//! of them ([`WithTextures`](crate::frame::WithTextures)) and a textured triangle names one by index.
//!
//! **Coordinates.** A [`TexVertex`] carries `u`, `v` in texels with 4
//! fraction bits (`U12.4`; texel centres at `+0.5`) and `q`, the vertex's
//! `1/w` scaled so the triangle's largest is near `u16::MAX` (any common
//! factor cancels). `s = u q`, `t = v q` and `q` are affine in screen space,
//! so the exact texture coordinate is `u = s / q` at every pixel.
//!
//! **Perspective, chosen by type** ([`TextureMode`], the tile
//! configuration's `Texturing`):
//! - [`AffineTexturing`]: `u`, `v` interpolated linearly in screen space,
//!   ignoring `q` — one addition per coordinate and pixel, and the bends
//!   the seed warns of when the triangle's depth varies;
//! - [`QuadraticTexturing`], **the RE's**: each span is cut into segments
//!   of up to 32 pixels at fixed screen columns; per segment `u` and `v` are
//!   computed exactly (`s / q`) at its first pixel and its end, its middle
//!   from those and `q` (the exact perspective point, one 32-bit division),
//!   and the quadratic through the three is stepped by second-order
//!   forward differences — two additions per coordinate and pixel, the
//!   fast-Phong unit's operation (§IV.2). A segment whose quadratic would
//!   miss by more than half a texel (fast depth change) is halved, down to
//!   2 pixels, so the error stays below half a texel at any depth ratio
//!   (measured to 64:1) and costs extra only where the depth demands it.
//!   The tolerance is the mode's parameter (`QuadraticTexturing<TOL>`,
//!   eighths of a texel): looser is cheaper, [`NEVER_SPLIT`] is the seed's
//!   plain 32-pixel segments.
//!   Segments depend on the covered row alone, whatever the tiling, so
//!   tiles cannot change the output;
//! - [`ExactTexturing`]: `s / q`, `t / q` divided at every pixel.
//!
//! `NoTexturing` (the default) compiles none of it: a textured triangle
//! is drawn with its shade alone, as grey.
//!
//! The exact samples are 32.32 fixed point (`i64`); spans step them in
//! 32 bits, `I14.18` texels, whose rounding stays below 2^-9 texel over a
//! 32-pixel segment.

use crate::error::Error;
use crate::format::Rgb;
use crate::numeric::Coord;

/// How texels are stored.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum TexFormat {
    /// Two bytes a texel, RGB565 little-endian (a frame buffer's layout).
    Rgb565,
    /// Three bytes a texel, R, G, B.
    Rgb888,
    /// One byte a texel, grey.
    Gray8,
    /// One byte a texel, an index into the texture's palette (indices past
    /// its end read its last colour).
    Indexed8,
}

impl TexFormat {
    /// Bytes a texel.
    pub const fn bytes(self) -> usize {
        match self {
            TexFormat::Rgb565 => 2,
            TexFormat::Rgb888 => 3,
            TexFormat::Gray8 | TexFormat::Indexed8 => 1,
        }
    }
}

/// What a coordinate outside the texture reads.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Wrap {
    /// The texture tiles the plane (a power-of-two side wraps by a mask,
    /// any other by a remainder).
    Repeat,
    /// The edge texels extend outwards.
    Clamp,
}

/// How a texel is read at a fractional coordinate.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Filter {
    /// The texel the coordinate falls in.
    Nearest,
    /// The four texels around it, weighted by 8-bit fractions.
    Bilinear,
}

/// Largest texture side, in texels (the `U12.4` coordinates' range).
pub const MAX_SIDE: u16 = 4096;

/// A texture plane borrowed in place.
///
/// ```
/// use tilerast::prelude::*;
/// // 2x2 RGB888, clamped, bilinear.
/// static TEXELS: [u8; 12] = [255, 0, 0, 0, 255, 0, 0, 0, 255, 255, 255, 255];
/// let t = Texture::new(&TEXELS, 2, 2, TexFormat::Rgb888)?.wrap(Wrap::Clamp).filter(Filter::Bilinear);
/// assert_eq!(t.texel(1, 0), Rgb::new(0, 255, 0));
/// // Texel centres are at +0.5 (coordinates are 32.32 texels).
/// let at = |u: f64, v: f64| t.sample((u * 2f64.powi(32)) as i64, (v * 2f64.powi(32)) as i64);
/// assert_eq!(at(0.5, 0.5), Rgb::new(255, 0, 0));
/// assert_eq!(at(1.0, 0.5), Rgb::new(128, 128, 0));
/// assert_eq!(Texture::new(&TEXELS, 3, 2, TexFormat::Rgb888), Err(Error::BadSize));
/// # Ok::<(), Error>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Texture<'a> {
    data: &'a [u8],
    palette: &'a [Rgb],
    w: u16,
    h: u16,
    format: TexFormat,
    wrap: Wrap,
    filter: Filter,
}

impl<'a> Texture<'a> {
    /// A `w x h` texture of `format` over `data` (row-major, no padding),
    /// repeating and nearest-filtered. [`Error::BadSize`] if a side is 0 or
    /// over [`MAX_SIDE`] or `data` is too short; use [`Texture::indexed`]
    /// for [`TexFormat::Indexed8`].
    pub const fn new(data: &'a [u8], w: u16, h: u16, format: TexFormat) -> Result<Self, Error> {
        Self::checked(data, &[], w, h, format)
    }

    /// A `w x h` paletted texture: one index a texel into `palette`
    /// (non-empty).
    ///
    /// ```
    /// use tilerast::prelude::*;
    /// static PAL: [Rgb; 2] = [Rgb::new(0, 0, 0), Rgb::new(250, 200, 0)];
    /// let t = Texture::indexed(&[0, 1, 1, 7], &PAL, 2, 2)?;
    /// assert_eq!((t.texel(1, 0), t.texel(1, 1)), (PAL[1], PAL[1]));
    /// # Ok::<(), Error>(())
    /// ```
    pub const fn indexed(
        data: &'a [u8],
        palette: &'a [Rgb],
        w: u16,
        h: u16,
    ) -> Result<Self, Error> {
        if palette.is_empty() {
            return Err(Error::BadSize);
        }
        Self::checked(data, palette, w, h, TexFormat::Indexed8)
    }

    const fn checked(
        data: &'a [u8],
        palette: &'a [Rgb],
        w: u16,
        h: u16,
        format: TexFormat,
    ) -> Result<Self, Error> {
        let need = w as usize * h as usize * format.bytes();
        let indexed = matches!(format, TexFormat::Indexed8);
        if w == 0 || h == 0 || w > MAX_SIDE || h > MAX_SIDE || data.len() < need {
            return Err(Error::BadSize);
        }
        if indexed == palette.is_empty() {
            return Err(Error::BadSize);
        }
        Ok(Texture {
            data,
            palette,
            w,
            h,
            format,
            wrap: Wrap::Repeat,
            filter: Filter::Nearest,
        })
    }

    /// The same texture addressed with `wrap` on both axes.
    pub const fn wrap(mut self, wrap: Wrap) -> Self {
        self.wrap = wrap;
        self
    }

    /// The same texture read with `filter`.
    pub const fn filter(mut self, filter: Filter) -> Self {
        self.filter = filter;
        self
    }

    /// Width and height in texels.
    pub const fn size(&self) -> (u16, u16) {
        (self.w, self.h)
    }

    /// How it is addressed and filtered.
    ///
    /// ```
    /// use tilerast::prelude::*;
    /// let t = Texture::new(&[0; 4], 2, 2, TexFormat::Gray8)?.filter(Filter::Bilinear);
    /// assert_eq!(t.modes(), (Wrap::Repeat, Filter::Bilinear));
    /// # Ok::<(), Error>(())
    /// ```
    pub const fn modes(&self) -> (Wrap, Filter) {
        (self.wrap, self.filter)
    }

    /// The texel at column `i < w`, row `j < h`.
    #[inline]
    pub fn texel(&self, i: u32, j: u32) -> Rgb {
        let k = j as usize * self.w as usize + i as usize;
        let d = self.data;
        match self.format {
            TexFormat::Rgb565 => {
                let p = u16::from_le_bytes([d[2 * k], d[2 * k + 1]]) as u32;
                let (r, g, b) = (p >> 11, (p >> 5) & 63, p & 31);
                Rgb::new(
                    ((r << 3) | (r >> 2)) as u8,
                    ((g << 2) | (g >> 4)) as u8,
                    ((b << 3) | (b >> 2)) as u8,
                )
            }
            TexFormat::Rgb888 => Rgb::new(d[3 * k], d[3 * k + 1], d[3 * k + 2]),
            TexFormat::Gray8 => Rgb::new(d[k], d[k], d[k]),
            TexFormat::Indexed8 => {
                let last = self.palette.len() - 1;
                self.palette[(d[k] as usize).min(last)]
            }
        }
    }

    /// The texel index a whole-texel coordinate `i` addresses on an axis of
    /// `n` texels.
    #[inline(always)]
    fn wrapped(&self, i: i64, n: u16) -> u32 {
        match self.wrap {
            Wrap::Clamp => i.clamp(0, n as i64 - 1) as u32,
            Wrap::Repeat if n.is_power_of_two() => (i as u32) & (n as u32 - 1),
            Wrap::Repeat => i.rem_euclid(n as i64) as u32,
        }
    }

    /// The filtered colour at `(u, v)`, texels in 32.32 fixed point
    /// (texel `(i, j)` covers `[i, i + 1) x [j, j + 1)`).
    #[inline]
    pub fn sample(&self, u: i64, v: i64) -> Rgb {
        match self.filter {
            Filter::Nearest => {
                self.texel(self.wrapped(u >> 32, self.w), self.wrapped(v >> 32, self.h))
            }
            Filter::Bilinear => {
                let (u, v) = (u - (1 << 31), v - (1 << 31));
                let (fu, fv) = (((u >> 24) & 255) as u32, ((v >> 24) & 255) as u32);
                let (i0, j0) = (u >> 32, v >> 32);
                let (i0, i1) = (self.wrapped(i0, self.w), self.wrapped(i0 + 1, self.w));
                let (j0, j1) = (self.wrapped(j0, self.h), self.wrapped(j0 + 1, self.h));
                let [a, b, c, d] =
                    [(i0, j0), (i1, j0), (i0, j1), (i1, j1)].map(|(i, j)| self.texel(i, j));
                let mix = |a: u8, b: u8, c: u8, d: u8| {
                    let top = a as u32 * (256 - fu) + b as u32 * fu;
                    let bot = c as u32 * (256 - fu) + d as u32 * fu;
                    ((top * (256 - fv) + bot * fv + (1 << 15)) >> 16) as u8
                };
                Rgb::new(
                    mix(a.r, b.r, c.r, d.r),
                    mix(a.g, b.g, c.g, d.g),
                    mix(a.b, b.b, c.b, d.b),
                )
            }
        }
    }
}

/// A vertex of a textured triangle
/// ([`Command::Textured`](crate::command::Command::Textured)): position,
/// depth and texture coordinates, 16 bytes.
///
/// ```
/// use tilerast::prelude::*;
/// let t = TexVertex::new(Coord::from_num(3), Coord::from_num(4), 100, (2.5, 7.0), 65535);
/// assert_eq!((t.u, t.v), (40, 112)); // 1/16 texel
/// assert_eq!(core::mem::size_of::<TexVertex>(), 16);
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct TexVertex {
    /// Column in pixels (4 sub-pixel bits).
    pub x: Coord,
    /// Row in pixels (4 sub-pixel bits), growing downwards.
    pub y: Coord,
    /// Depth, 0 nearest.
    pub z: u16,
    /// Texture column in 1/16 texel (`U12.4`).
    pub u: u16,
    /// Texture row in 1/16 texel (`U12.4`).
    pub v: u16,
    /// `1/w` at the vertex, scaled by any factor common to the triangle;
    /// must be non-zero. Equal `q`s make the mapping affine.
    pub q: u16,
}

impl TexVertex {
    /// A vertex from its position, depth, texture coordinates in texels
    /// (rounded to 1/16, clamped to `0..4096`) and `q`.
    pub fn new(x: Coord, y: Coord, z: u16, (u, v): (f32, f32), q: u16) -> Self {
        let fix = |t: f32| (t * 16.0 + 0.5).clamp(0.0, 65535.0) as u16;
        TexVertex {
            x,
            y,
            z,
            u: fix(u),
            v: fix(v),
            q,
        }
    }

    /// Position and depth as a plain [`crate::geom::Vertex`] of colour
    /// `shade` (grey).
    pub const fn vertex(&self, shade: u8) -> crate::geom::Vertex {
        crate::geom::Vertex::new(self.x, self.y, self.z, Rgb::new(shade, shade, shade))
    }
}

/// How a tile maps textures, chosen by type: the configuration's
/// `Texturing` ([`crate::config::TileConfig`]). Code, not a plane.
pub trait TextureMode: 'static {
    /// [`PERSPECTIVE_NONE`] compiles no texturing at all; otherwise one of
    /// [`PERSPECTIVE_AFFINE`], [`PERSPECTIVE_QUADRATIC`],
    /// [`PERSPECTIVE_EXACT`].
    const MODE: u8;
    /// The quadratic mode's tolerance in eighths of a texel: a segment
    /// whose quadratic the estimate says may miss by more is halved
    /// ([`QuadraticTexturing`]'s parameter; the other modes ignore it).
    const TOLERANCE: u32 = QUADRATIC_TOLERANCE;
}

/// [`QuadraticTexturing`]'s default tolerance, eighths of a texel: half a
/// texel, the seed's accuracy target.
pub const QUADRATIC_TOLERANCE: u32 = 4;
/// A tolerance no segment exceeds: the quadratic mode never splits (one
/// segment per 32 screen columns, the seed's own scheme).
pub const NEVER_SPLIT: u32 = u16::MAX as u32;

/// No texturing compiled: a textured triangle draws its shade, grey.
pub const PERSPECTIVE_NONE: u8 = 0;
/// Linear `u`, `v` in screen space.
pub const PERSPECTIVE_AFFINE: u8 = 1;
/// The RE's quadratic along each span.
pub const PERSPECTIVE_QUADRATIC: u8 = 2;
/// A division at every pixel.
pub const PERSPECTIVE_EXACT: u8 = 3;

/// No texture mapping (the default): no code.
#[derive(Debug, Clone, Copy, Default)]
pub struct NoTexturing;
/// Affine texture mapping ([module docs](self)).
#[derive(Debug, Clone, Copy, Default)]
pub struct AffineTexturing;
/// Perspective by quadratic interpolation along each span, the RE's
/// ([module docs](self)), within `TOL` eighths of a texel (default half a
/// texel): the speed-against-accuracy knob of the mode. A larger `TOL`
/// splits fewer segments; [`NEVER_SPLIT`] keeps every
/// 32-pixel segment whole. Measured on both axes in `reports/texture.md`
/// and `reports/targets.md`.
///
/// ```
/// use tilerast::prelude::*;
/// use tilerast::texture::NEVER_SPLIT;
/// // Within two texels: cheaper where the depth changes fast.
/// type Loose = Planes<Rgb565Format, Depth16, NoWid, NoDither, NoAa, FullPrecision,
///     NoBlending, GouraudShading, QuadraticTexturing<16>>;
/// type Seed = QuadraticTexturing<NEVER_SPLIT>;
/// # let _ = (core::marker::PhantomData::<Loose>, core::marker::PhantomData::<Seed>);
/// ```
#[derive(Debug, Clone, Copy, Default)]
pub struct QuadraticTexturing<const TOL: u32 = QUADRATIC_TOLERANCE>;
/// Perspective by a division at every pixel ([module docs](self)).
#[derive(Debug, Clone, Copy, Default)]
pub struct ExactTexturing;

impl TextureMode for NoTexturing {
    const MODE: u8 = PERSPECTIVE_NONE;
}
impl TextureMode for AffineTexturing {
    const MODE: u8 = PERSPECTIVE_AFFINE;
}
impl<const TOL: u32> TextureMode for QuadraticTexturing<TOL> {
    const MODE: u8 = PERSPECTIVE_QUADRATIC;
    const TOLERANCE: u32 = {
        assert!(
            TOL >= 1 && TOL <= NEVER_SPLIT,
            "TOL: 1..=NEVER_SPLIT eighths"
        );
        TOL
    };
}
impl TextureMode for ExactTexturing {
    const MODE: u8 = PERSPECTIVE_EXACT;
}
