//! The geometric base every stage shares: integer rectangles in screen
//! pixels, triangle vertices in sub-pixel coordinates, and the pixel boxes
//! of a triangle.

use crate::error::Error;
use crate::format::Rgb;
use crate::numeric::{Coord, COORD_LIMIT, SUBPIXEL, SUBPIXEL_BITS};

/// An axis-aligned rectangle of whole pixels: `x..x+w`, `y..y+h`.
///
/// ```
/// use tilerast::geom::Rect;
/// let a = Rect::new(0, 0, 10, 10);
/// assert_eq!(a.intersect(&Rect::new(5, -5, 10, 10)), Some(Rect::new(5, 0, 5, 5)));
/// assert_eq!(a.intersect(&Rect::new(10, 0, 1, 1)), None);
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Rect {
    /// Left column.
    pub x: i32,
    /// Top row.
    pub y: i32,
    /// Width in pixels.
    pub w: u32,
    /// Height in pixels.
    pub h: u32,
}

impl Rect {
    /// A rectangle from its top-left corner and size.
    pub const fn new(x: i32, y: i32, w: u32, h: u32) -> Self {
        Rect { x, y, w, h }
    }

    /// One past the right column (computed in `i64`: never overflows).
    pub fn x1(&self) -> i64 {
        self.x as i64 + self.w as i64
    }

    /// One past the bottom row.
    pub fn y1(&self) -> i64 {
        self.y as i64 + self.h as i64
    }

    /// The overlap of two rectangles, `None` when empty.
    ///
    /// ```
    /// use tilerast::prelude::*;
    /// let a = Rect::new(-4, -4, 8, 8);
    /// assert_eq!(a.intersect(&Rect::new(2, 0, u32::MAX, 2)), Some(Rect::new(2, 0, 2, 2)));
    /// assert_eq!(a.intersect(&Rect::new(i32::MIN, 0, 10, 2)), None);
    /// ```
    // Inlined on a host: out of line it was 8% of the host's small
    // triangles (3.7 px each: 21.2 -> 19.4 ns/px, measured); the
    // microcontrollers keep the compiler's choice (the M0's flash).
    #[cfg_attr(not(target_arch = "arm"), inline)]
    pub fn intersect(&self, o: &Rect) -> Option<Rect> {
        // 32-bit: from the larger start, what is left of each extent (a
        // tile clips every triangle it draws: 87 instructions in `i64` on
        // the Cortex-M0, measured), branch-free until the end (a branch
        // per axis lost to the Cortex-M4's branch-free `i64` compares).
        let axis = |a: i32, wa: u32, b: i32, wb: u32| {
            let x0 = a.max(b);
            let la = wa.saturating_sub(x0.wrapping_sub(a) as u32);
            let lb = wb.saturating_sub(x0.wrapping_sub(b) as u32);
            (x0, la.min(lb))
        };
        let (x, w) = axis(self.x, self.w, o.x, o.w);
        let (y, h) = axis(self.y, self.h, o.y, o.h);
        (w > 0 && h > 0).then_some(Rect::new(x, y, w, h))
    }

    /// Number of pixels.
    pub fn area(&self) -> u64 {
        self.w as u64 * self.h as u64
    }
}

/// Rectangles convert to and from `embedded-graphics`' `Rectangle`.
///
/// ```
/// use tilerast::prelude::*;
/// use embedded_graphics_core::{geometry::{Point, Size}, primitives::Rectangle};
/// let r = Rectangle::new(Point::new(-2, 3), Size::new(10, 4));
/// assert_eq!(Rect::from(r), Rect::new(-2, 3, 10, 4));
/// assert_eq!(Rectangle::from(Rect::new(-2, 3, 10, 4)), r);
/// ```
impl From<embedded_graphics_core::primitives::Rectangle> for Rect {
    fn from(r: embedded_graphics_core::primitives::Rectangle) -> Self {
        Rect::new(r.top_left.x, r.top_left.y, r.size.width, r.size.height)
    }
}

impl From<Rect> for embedded_graphics_core::primitives::Rectangle {
    fn from(r: Rect) -> Self {
        use embedded_graphics_core::geometry::{Point, Size};
        embedded_graphics_core::primitives::Rectangle::new(
            Point::new(r.x, r.y),
            Size::new(r.w, r.h),
        )
    }
}

/// A triangle vertex: sub-pixel position, 16-bit depth, 24-bit colour and
/// an 8-bit opacity (used only by translucent commands, [`crate::command::Blend`])
/// and an edge flag (used only by area-sampling antialiasing,
/// [`crate::area`]); both live in the struct's padding, so a vertex stays
/// 16 bytes.
///
/// ```
/// use tilerast::prelude::*;
/// let v = Vertex::new(Coord::from_num(10.5), Coord::from_num(3), 1000, Rgb::new(255, 0, 0));
/// assert!(v.validate().is_ok());
/// let far = Vertex::new(Coord::from_num(9000), Coord::from_num(0), 0, Rgb::default());
/// assert_eq!(far.validate(), Err(Error::CoordOutOfRange));
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Vertex {
    /// Column in pixels (4 sub-pixel bits); pixel centres are at `+0.5`.
    pub x: Coord,
    /// Row in pixels (4 sub-pixel bits), growing downwards.
    pub y: Coord,
    /// Depth, 0 nearest.
    pub z: u16,
    /// Colour at the vertex.
    pub color: Rgb,
    /// Opacity at the vertex, `0` transparent to `255` opaque: interpolated
    /// like a colour channel (the RE's α-channel) when the command blends,
    /// ignored otherwise.
    pub alpha: u8,
    /// The edge from this vertex to the next one of its triangle borders
    /// something else on screen (a silhouette, an open boundary): tiles
    /// configured with [`AreaAa`](crate::area::AreaAa) antialias it by
    /// exact area coverage (OpenGL's edge flag). Ignored elsewhere and by
    /// every other tile; `false` by default.
    pub edge_flag: bool,
}

impl Default for Vertex {
    /// The origin, depth 0, black, opaque.
    fn default() -> Self {
        Vertex::new(Coord::ZERO, Coord::ZERO, 0, Rgb::new(0, 0, 0))
    }
}

impl Vertex {
    /// An opaque vertex from fixed-point coordinates.
    pub const fn new(x: Coord, y: Coord, z: u16, color: Rgb) -> Self {
        Vertex {
            x,
            y,
            z,
            color,
            alpha: 255,
            edge_flag: false,
        }
    }

    /// The same vertex with its edge to the next vertex flagged for
    /// area-sampling antialiasing ([`Vertex::edge_flag`]).
    ///
    /// ```
    /// use tilerast::prelude::*;
    /// let v = Vertex::new(Coord::from_num(1), Coord::from_num(2), 3, Rgb::new(4, 5, 6));
    /// assert!(v.with_edge_flag(true).edge_flag && !v.edge_flag);
    /// ```
    pub const fn with_edge_flag(mut self, flag: bool) -> Self {
        self.edge_flag = flag;
        self
    }

    /// The same vertex with opacity `alpha` (`0..=255`).
    ///
    /// ```
    /// use tilerast::prelude::*;
    /// let v = Vertex::new(Coord::from_num(1), Coord::from_num(2), 3, Rgb::new(4, 5, 6)).with_alpha(128);
    /// assert_eq!((v.alpha, Vertex::default().alpha), (128, 255));
    /// assert_eq!(core::mem::size_of::<Vertex>(), 16);
    /// ```
    pub const fn with_alpha(mut self, alpha: u8) -> Self {
        self.alpha = alpha;
        self
    }

    /// An opaque vertex at whole pixel `(x, y)` (the pixel's top-left
    /// corner; add 8 sub-pixels, half a pixel, for its centre): integer
    /// only, no soft float on a chip without an FPU.
    ///
    /// ```
    /// use tilerast::prelude::*;
    /// let v = Vertex::px(10, -3, 500, Rgb::new(255, 0, 0));
    /// assert_eq!((v.x, v.y), (Coord::from_num(10), Coord::from_num(-3)));
    /// assert_eq!(Vertex::subpx(168, 8, 0, Rgb::default()).x, Coord::from_num(10.5));
    /// ```
    pub const fn px(x: i16, y: i16, z: u16, color: Rgb) -> Self {
        Vertex::subpx(
            x as i32 * SUBPIXEL as i32,
            y as i32 * SUBPIXEL as i32,
            z,
            color,
        )
    }

    /// An opaque vertex at `(x, y)` in sixteenths of a pixel (the
    /// coordinates' 4 sub-pixel bits), integer only. A vertex outside the
    /// documented range is refused when its command is drawn
    /// ([`Vertex::validate`]).
    pub const fn subpx(x: i32, y: i32, z: u16, color: Rgb) -> Self {
        Vertex::new(Coord::from_bits(x), Coord::from_bits(y), z, color)
    }

    /// A vertex at an `embedded-graphics` point (whole pixels: the corner
    /// of pixel `p`; add half a pixel for its centre).
    ///
    /// ```
    /// use tilerast::prelude::*;
    /// use embedded_graphics_core::geometry::Point;
    /// let v = Vertex::at(Point::new(3, -2), 7, Rgb::new(1, 2, 3));
    /// assert_eq!((v.x, v.y), (Coord::from_num(3), Coord::from_num(-2)));
    /// ```
    pub const fn at(p: embedded_graphics_core::geometry::Point, z: u16, color: Rgb) -> Self {
        let s = SUBPIXEL as i32;
        Vertex::new(
            Coord::from_bits(p.x.saturating_mul(s)),
            Coord::from_bits(p.y.saturating_mul(s)),
            z,
            color,
        )
    }

    /// A vertex from float pixel coordinates, rounded to the nearest 1/16
    /// pixel. NaN and infinities give [`Error::NotFinite`], coordinates
    /// outside `[-COORD_LIMIT, COORD_LIMIT)` give [`Error::CoordOutOfRange`].
    ///
    /// ```
    /// use tilerast::prelude::*;
    /// assert!(Vertex::try_from_f32(1.03, 2.0, 0, Rgb::default()).is_ok());
    /// assert_eq!(Vertex::try_from_f32(f32::NAN, 2.0, 0, Rgb::default()), Err(Error::NotFinite));
    /// assert_eq!(Vertex::try_from_f32(1e9, 2.0, 0, Rgb::default()), Err(Error::CoordOutOfRange));
    /// ```
    pub fn try_from_f32(x: f32, y: f32, z: u16, color: Rgb) -> Result<Self, Error> {
        let c = |v: f32| -> Result<Coord, Error> {
            if !v.is_finite() {
                return Err(Error::NotFinite);
            }
            Coord::checked_from_num(v).ok_or(Error::CoordOutOfRange)
        };
        let v = Vertex::new(c(x)?, c(y)?, z, color);
        v.validate()?;
        Ok(v)
    }

    /// Checks the documented coordinate domain.
    pub fn validate(&self) -> Result<(), Error> {
        let lim = COORD_LIMIT as i64 * SUBPIXEL;
        let ok = |c: Coord| (-lim..lim).contains(&(c.to_bits() as i64));
        if ok(self.x) && ok(self.y) {
            Ok(())
        } else {
            Err(Error::CoordOutOfRange)
        }
    }
}

/// A vertex of a quadratically shaded triangle ([`crate::command::Command::Quadratic`],
/// the RE's fast Phong, seed 001 §IV.2): a [`Vertex`] without opacity plus
/// the colour at the midpoint of the edge to the next vertex. Three vertex
/// and three midpoint colours fix a quadratic per channel over the
/// triangle; 16 bytes, like [`Vertex`].
///
/// ```
/// use tilerast::prelude::*;
/// let v = Vertex::new(Coord::from_num(1), Coord::from_num(2), 3, Rgb::new(4, 5, 6));
/// let q = QuadVertex::new(v, Rgb::new(7, 8, 9));
/// assert_eq!((q.vertex(), q.mid), (v, Rgb::new(7, 8, 9)));
/// assert_eq!(core::mem::size_of::<QuadVertex>(), 16);
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct QuadVertex {
    /// Column in pixels (4 sub-pixel bits).
    pub x: Coord,
    /// Row in pixels (4 sub-pixel bits), growing downwards.
    pub y: Coord,
    /// Depth, 0 nearest.
    pub z: u16,
    /// Colour at the vertex.
    pub color: Rgb,
    /// Colour at the midpoint of the edge from this vertex to the next
    /// (vertex 2's edge goes back to vertex 0).
    pub mid: Rgb,
}

impl QuadVertex {
    /// A vertex's position, depth and colour, and the colour at the
    /// midpoint of its edge to the next vertex.
    pub const fn new(v: Vertex, mid: Rgb) -> Self {
        QuadVertex {
            x: v.x,
            y: v.y,
            z: v.z,
            color: v.color,
            mid,
        }
    }

    /// The vertex without its midpoint colour (opaque).
    pub const fn vertex(&self) -> Vertex {
        Vertex::new(self.x, self.y, self.z, self.color)
    }
}

/// The pixels whose centres can lie inside the triangle, or `None`.
///
/// Validated coordinates are below 2^18 sub-pixels, so this is `i32` math,
/// and the divisions by 16 are arithmetic shifts (floor): it runs for every
/// command in every tile, so it must be cheap on a Cortex-M0.
pub(crate) fn pixel_bounds(v: &[Vertex; 3]) -> Option<Rect> {
    SubBox::of(v).pixels()
}

/// A vertex as the fused mesh path reads it, in place ([`crate::tile`]'s
/// plane-contract path; the geometry stage's vertex cache is made of
/// them): sub-pixel position (1/16 px, within the validated domain),
/// 16-bit depth (smaller is nearer), 8-bit RGB, and a byte and 16 bits
/// the producer keeps its own flags in (the raster ignores them: the
/// geometry stage's outcodes, and its front-triangle bits). 16 bytes.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub(crate) struct MeshVertex {
    pub x: i32,
    pub y: i32,
    pub z: u16,
    pub rgb: [u8; 3],
    pub code: u8,
    pub spare: u16,
}

impl MeshVertex {
    /// The compact form of a command's vertex.
    #[inline(always)]
    pub(crate) fn of(v: &Vertex) -> Self {
        MeshVertex {
            x: v.x.to_bits(),
            y: v.y.to_bits(),
            z: v.z,
            rgb: [v.color.r, v.color.g, v.color.b],
            spare: 0,
            code: 0,
        }
    }

    /// The command vertex it stands for.
    #[inline(always)]
    pub(crate) fn vertex(&self) -> Vertex {
        Vertex::new(
            crate::numeric::Coord::from_bits(self.x),
            crate::numeric::Coord::from_bits(self.y),
            self.z,
            crate::format::Rgb::new(self.rgb[0], self.rgb[1], self.rgb[2]),
        )
    }
}

/// A triangle's box in sub-pixels, inclusive: made once per triangle and
/// tile for both the choice of integer ([`crate::setup`]'s `fits_box`) and
/// the pixel bounds (the two took 46 instructions a triangle apart on the
/// Cortex-M4).
#[derive(Debug, Clone, Copy)]
pub(crate) struct SubBox {
    /// Smallest x and y.
    pub lo: (i32, i32),
    /// Largest x and y.
    pub hi: (i32, i32),
}

impl SubBox {
    /// The box of three vertices.
    #[inline(always)]
    pub(crate) fn of(v: &[Vertex; 3]) -> Self {
        Self::of_points(v.map(|v| (v.x.to_bits(), v.y.to_bits())))
    }

    /// The box of three points.
    #[inline(always)]
    pub(crate) fn of_points([a, b, c]: [(i32, i32); 3]) -> Self {
        SubBox {
            lo: (a.0.min(b.0).min(c.0), a.1.min(b.1).min(c.1)),
            hi: (a.0.max(b.0).max(c.0), a.1.max(b.1).max(c.1)),
        }
    }

    /// The pixels whose centres can lie inside: pixel px has its centre at
    /// 16 px + 8, so px in `[ceil((min - 8) / 16), floor((max - 8) / 16)]`.
    #[inline(always)]
    pub(crate) fn pixels(&self) -> Option<Rect> {
        let (x0, x1) = pixel_span(self.lo.0, self.hi.0);
        let (y0, y1) = pixel_span(self.lo.1, self.hi.1);
        (x0 <= x1 && y0 <= y1)
            .then(|| Rect::new(x0, y0, (x1 - x0 + 1) as u32, (y1 - y0 + 1) as u32))
    }
}

/// The pixels (inclusive, empty when the first exceeds the second) whose
/// centres `16 p + 8` lie in the sub-pixel interval `[lo, hi]`:
/// `[ceil((lo - 8) / 16), floor((hi - 8) / 16)]`.
#[inline(always)]
pub(crate) fn pixel_span(lo: i32, hi: i32) -> (i32, i32) {
    let half = (SUBPIXEL / 2) as i32;
    (
        (lo - half + (SUBPIXEL as i32 - 1)) >> SUBPIXEL_BITS,
        (hi - half) >> SUBPIXEL_BITS,
    )
}

/// The pixels (inclusive) whose cells `[16 p, 16 p + 16)` meet the
/// sub-pixel interval `[lo, hi]`, `lo <= hi`.
#[inline(always)]
pub(crate) fn cell_span(lo: i32, hi: i32) -> (i32, i32) {
    (lo >> SUBPIXEL_BITS, hi >> SUBPIXEL_BITS)
}

/// The pixels whose cells `[16 p, 16 p + 16)` the triangle's box meets:
/// every pixel any sample of which can be inside (coverage antialiasing).
pub(crate) fn cell_bounds(v: &[Vertex; 3]) -> Rect {
    cell_bounds_of(v.map(|v| (v.x.to_bits(), v.y.to_bits())))
}

/// [`cell_bounds`] from the vertices' positions alone (sub-pixels).
#[inline(always)]
pub(crate) fn cell_bounds_of([a, b, c]: [(i32, i32); 3]) -> Rect {
    let (x0, x1) = (a.0.min(b.0).min(c.0), a.0.max(b.0).max(c.0));
    let (y0, y1) = (a.1.min(b.1).min(c.1), a.1.max(b.1).max(c.1));
    let cells = |lo: i32, hi: i32| {
        let (lo, hi) = cell_span(lo, hi);
        (lo, (hi - lo + 1) as u32)
    };
    let ((x, w), (y, h)) = (cells(x0, x1), cells(y0, y1));
    Rect::new(x, y, w, h)
}
