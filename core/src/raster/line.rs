//! Vector drawing (seed 001, §II and Conclusion: "vector drawing with line
//! styles"): Bresenham lines with sub-pixel endpoints, depth, window ID,
//! plane mask and a repeating on/off style; two-point (Wu) antialiased lines
//! (seed 003 eqs. 4-7) and edge antialiasing of solids (seed 003 eq. 8),
//! which walk the same way.
//!
//! **Which pixels.** Along the major axis (the larger of `|dx|`, `|dy|`),
//! every pixel whose centre `16 c + 8` lies in the half-open interval from
//! the start point to the end point gets one pixel: the one whose cell
//! contains the ideal line at that centre, `floor(minor / 16)` — exactly
//! the pixel Bresenham picks, computed with the exact quotient/remainder
//! walk of the triangle traversal, so it cannot depend on the tiling. The end
//! point is excluded, so a polyline draws each shared vertex once; a
//! zero-length line draws nothing.
//!
//! **Depth** is interpolated exactly along the major axis (floor). **Style**:
//! bit `(phase + k / scale) % 16` of `pattern` decides pixel `k` (counted
//! from the start point), so the pattern continues across tiles, and a
//! polyline continues it across segments by passing on
//! [`LineCmd::next_phase`].
//!
//! Each pixel goes through the same fragment path as spans (window ID, Z,
//! dither, pack, plane mask).
//!
//! **Two-point lines** ([`LineCmd::antialias`]) visit every column the
//! line's extent touches and blend the two pixels straddling the exact line
//! at the column centre over the tile, by distance (eq. 7); end columns are
//! weighted by the part of their cell the line covers, so a line neither
//! brightens nor dims at its ends or at tile borders.
//!
//! **Antialiased edges** ([`EdgeCmd`]) walk the same columns and blend only
//! the pixel outside the solid, by the part of it the solid covers (eq. 8).
//! A scene without them has no such command: no plane, no pass, no cost.

use crate::error::Error;
use crate::format::Rgb;
use crate::geom::Rect;
use crate::geom::Vertex;
use crate::numeric::{div_floor, Coord, SUBPIXEL, Z_FRAC};
use crate::raster::traverse::FloorWalk;

/// A repeating on/off pattern: 16 bits, each held for `scale` pixels.
///
/// ```
/// use tilerast::line::LineStyle;
/// let dashed = LineStyle { pattern: 0x00FF, scale: 1, phase: 0 };
/// assert!(dashed.on(0) && dashed.on(7) && !dashed.on(8) && dashed.on(16));
/// assert!(LineStyle::SOLID.on(12345));
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct LineStyle {
    /// Bit `i` set: pattern position `i` is drawn.
    pub pattern: u16,
    /// Pixels per pattern bit (0 is taken as 1).
    pub scale: u8,
    /// Pattern position of the first pixel, in pixels.
    pub phase: u16,
}

impl LineStyle {
    /// Every pixel drawn.
    pub const SOLID: LineStyle = LineStyle {
        pattern: 0xFFFF,
        scale: 1,
        phase: 0,
    };

    /// Whether pixel `k` (from the start point) is drawn.
    #[inline]
    pub fn on(&self, k: u32) -> bool {
        let scale = self.scale.max(1) as u32;
        let bit = ((self.phase as u32 + k) / scale) % 16;
        (self.pattern >> bit) & 1 != 0
    }
}

impl Default for LineStyle {
    fn default() -> Self {
        Self::SOLID
    }
}

/// A line from `p0` to `p1` (end point excluded), flat colour, depth
/// interpolated from `z0` to `z1`.
///
/// ```
/// use tilerast::prelude::*;
/// use tilerast::line::{LineCmd, LineStyle};
/// let p = |x: i32, y: i32| (Coord::from_num(x) + Coord::from_num(0.5), Coord::from_num(y) + Coord::from_num(0.5));
/// let l = LineCmd { p0: p(0, 0), p1: p(10, 3), z: [0, 0], color: Rgb::new(255, 255, 255), style: LineStyle::SOLID, antialias: false };
/// assert_eq!(l.steps(), 10); // columns 0..10, the end pixel excluded
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct LineCmd {
    /// Start point (sub-pixel).
    pub p0: (Coord, Coord),
    /// End point (sub-pixel), not drawn.
    pub p1: (Coord, Coord),
    /// Depth at `p0` and `p1`.
    pub z: [u16; 2],
    /// Colour.
    pub color: Rgb,
    /// On/off pattern.
    pub style: LineStyle,
    /// Two-point (Wu) antialiasing instead of Bresenham.
    pub antialias: bool,
}

impl LineCmd {
    /// A solid, aliased (Bresenham) line from `p0` to `p1` at depth 0.
    ///
    /// ```
    /// use tilerast::prelude::*;
    /// let p = |x: i32, y: i32| (Coord::from_num(x), Coord::from_num(y));
    /// let l = LineCmd::new(p(0, 0), p(10, 3), Rgb::new(255, 255, 0)).antialiased().depth([5, 9]);
    /// assert!(l.antialias && l.z == [5, 9] && l.validate().is_ok());
    /// ```
    pub const fn new(p0: (Coord, Coord), p1: (Coord, Coord), color: Rgb) -> Self {
        LineCmd {
            p0,
            p1,
            z: [0, 0],
            color,
            style: LineStyle::SOLID,
            antialias: false,
        }
    }

    /// The same line with two-point (Wu) antialiasing.
    pub const fn antialiased(self) -> Self {
        LineCmd {
            antialias: true,
            ..self
        }
    }

    /// The same line with depth `z[0]` at `p0` and `z[1]` at `p1`.
    pub const fn depth(self, z: [u16; 2]) -> Self {
        LineCmd { z, ..self }
    }

    /// The same line with an on/off pattern.
    pub const fn styled(self, style: LineStyle) -> Self {
        LineCmd { style, ..self }
    }
}

/// A line in major/minor axes, ready to walk.
#[derive(Debug, Clone, Copy)]
pub(crate) struct LineSetup {
    /// True when y is the major axis.
    pub y_major: bool,
    /// Start and end along the major axis (sub-pixel), and whether the line
    /// runs towards smaller major coordinates.
    a: i64,
    b: i64,
    reversed: bool,
    /// Minor coordinate at `a` and its change over `b - a`.
    m0: i64,
    dm: i64,
    /// Depth at `a` and its change over `b - a`.
    z0: i64,
    dz: i64,
    /// First and last pixel index along the major axis (inclusive), if any.
    pub first: i64,
    pub last: i64,
}

fn sub(c: (Coord, Coord)) -> (i64, i64) {
    (c.0.to_bits() as i64, c.1.to_bits() as i64)
}

impl LineCmd {
    /// Checks the coordinate domain.
    pub fn validate(&self) -> Result<(), Error> {
        let p = |(x, y)| Vertex::new(x, y, 0, Rgb::default());
        p(self.p0).validate()?;
        p(self.p1).validate()
    }

    pub(crate) fn setup(&self) -> Option<LineSetup> {
        LineSetup::new(self.p0, self.p1, self.z)
    }

    /// Pixels the line steps through (drawn or not by the style): what a
    /// polyline adds to the phase of its next segment.
    pub fn steps(&self) -> u32 {
        self.setup().map_or(0, |s| {
            let (first, last) = s.columns(self.antialias);
            (last - first + 1).max(0) as u32
        })
    }

    /// The style phase for a segment that continues this one.
    pub fn next_phase(&self) -> u16 {
        let period = 16 * self.style.scale.max(1) as u32;
        ((self.style.phase as u32 + self.steps()) % period) as u16
    }

    /// The screen pixels the line can touch.
    pub fn bounds(&self) -> Option<Rect> {
        self.setup()?.bounds(self.antialias)
    }
}

/// Which side of an edge the solid lies on, walking from its first vertex
/// to its second on the y-down screen: `Right` when
/// `cross(p1 - p0, q - p0) > 0` for a point `q` inside.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Side {
    /// The solid is on the left (counter-clockwise side on screen).
    Left,
    /// The solid is on the right (clockwise side on screen).
    Right,
}

/// An antialiased edge of a solid (seed 003 eq. 8), drawn **after** the
/// solids: along the edge, the pixel outside the solid that the edge crosses
/// is blended toward the solid's colour by the part of it the solid covers,
/// `I = d I_o + (1 - d) I_b`. The pixel inside (drawn by the solid) is left
/// alone, as in the seed.
///
/// `I_o` is interpolated from the vertex colours along the edge (so the
/// result does not depend on which tile holds the solid's pixels); `I_b` is
/// whatever the tile holds. The blend is Z-tested against the edge's depth
/// without writing Z, so a nearer object next to the edge is not touched.
///
/// Emit edges only where the solid borders something else — a mesh's
/// silhouette and open boundary — not between two triangles of one surface.
///
/// ```
/// use tilerast::prelude::*;
/// use tilerast::line::{EdgeCmd, Side};
/// let v = |x: f32, y: f32| Vertex::new(Coord::from_num(x), Coord::from_num(y), 0, Rgb::new(255, 255, 255));
/// let tri = [v(1.0, 1.0), v(30.0, 9.0), v(5.0, 20.0)];
/// let e = EdgeCmd::of_triangle(&tri, 0); // from tri[0] to tri[1], tri[2] inside
/// assert_eq!(e.interior, Side::Right);
/// assert_eq!(EdgeCmd::of_triangle(&[tri[0], tri[2], tri[1]], 0).interior, Side::Left);
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct EdgeCmd {
    /// The edge's end points, with the solid's depth and colour there.
    pub v: [Vertex; 2],
    /// The solid's side.
    pub interior: Side,
}

impl EdgeCmd {
    /// Edge `i` of a triangle, from `v[i]` to `v[(i + 1) % 3]`, with the
    /// third vertex inside (a degenerate triangle gives `Side::Left`).
    pub const fn of_triangle(v: &[Vertex; 3], i: usize) -> EdgeCmd {
        let (a, b, q) = (v[i % 3], v[(i + 1) % 3], v[(i + 2) % 3]);
        let (ax, ay) = (a.x.to_bits() as i64, a.y.to_bits() as i64);
        let (dx, dy) = (b.x.to_bits() as i64 - ax, b.y.to_bits() as i64 - ay);
        let cross = dx * (q.y.to_bits() as i64 - ay) - dy * (q.x.to_bits() as i64 - ax);
        EdgeCmd {
            v: [a, b],
            interior: if cross > 0 { Side::Right } else { Side::Left },
        }
    }

    /// Checks the coordinate domain.
    pub fn validate(&self) -> Result<(), Error> {
        self.v.iter().try_for_each(Vertex::validate)
    }

    pub(crate) fn setup(&self) -> Option<LineSetup> {
        let [p, q] = self.v.map(|v| (v.x, v.y));
        LineSetup::new(p, q, self.v.map(|v| v.z))
    }

    /// Whether the solid lies towards larger minor coordinates of `s`.
    pub(crate) fn interior_up(&self, s: &LineSetup) -> bool {
        let d = |f: fn(&Vertex) -> Coord| f(&self.v[1]).to_bits() - f(&self.v[0]).to_bits();
        // Moving q along +y changes cross(p1 - p0, q - p0) by dx, along +x by -dy.
        let right_is_up = if s.y_major {
            d(|v| v.y) < 0
        } else {
            d(|v| v.x) > 0
        };
        right_is_up == (self.interior == Side::Right)
    }

    /// The screen pixels the edge can touch.
    pub fn bounds(&self) -> Option<Rect> {
        self.setup()?.bounds(true)
    }
}

/// Weights of the two-point antialiased pixels are in 1/256.
pub(crate) const WU_ONE: i32 = 256;

impl LineSetup {
    /// The walk of the segment `p0` to `p1` with depths `z`; `None` when
    /// it has no extent along its major axis.
    pub(crate) fn new(p0: (Coord, Coord), p1: (Coord, Coord), z: [u16; 2]) -> Option<LineSetup> {
        let (p, q) = (sub(p0), sub(p1));
        let y_major = (q.1 - p.1).abs() > (q.0 - p.0).abs();
        let (mut pa, mut pb) = if y_major {
            ((p.1, p.0), (q.1, q.0))
        } else {
            (p, q)
        };
        let (mut z0, mut z1) = (z[0] as i64, z[1] as i64);
        let reversed = pb.0 < pa.0;
        if reversed {
            core::mem::swap(&mut pa, &mut pb);
            core::mem::swap(&mut z0, &mut z1);
        }
        let (a, b) = (pa.0, pb.0);
        if a == b {
            return None;
        }
        let half = SUBPIXEL / 2;
        // Centres 16c + 8 in [a, b) (forward) or (a, b] (reversed: the end
        // point p1 is then at a).
        let (first, last) = if reversed {
            (
                div_floor(a - half, SUBPIXEL) + 1,
                div_floor(b - half, SUBPIXEL),
            )
        } else {
            (
                -div_floor(-(a - half), SUBPIXEL),
                div_floor(b - half - 1, SUBPIXEL),
            )
        };
        // `first > last` (no centre on the line) still leaves Wu's coverage.
        Some(LineSetup {
            y_major,
            a,
            b,
            reversed,
            m0: pa.1,
            dm: pb.1 - pa.1,
            z0,
            dz: z1 - z0,
            first,
            last,
        })
    }

    /// The screen pixels the walk can touch: the columns it steps through
    /// and, across them, the pixels containing the line (and for the
    /// two-point walk, one more on each side).
    pub(crate) fn bounds(&self, antialias: bool) -> Option<Rect> {
        let (first, last) = self.columns(antialias);
        if first > last {
            return None;
        }
        let (m0, m1) = (self.m0, self.m0 + self.dm);
        let lo = div_floor(m0.min(m1), SUBPIXEL) - antialias as i64;
        let hi = div_floor(m0.max(m1), SUBPIXEL) + antialias as i64;
        let (w, h) = ((last - first + 1) as u32, (hi - lo + 1) as u32);
        Some(if self.y_major {
            Rect::new(lo as i32, first as i32, h, w)
        } else {
            Rect::new(first as i32, lo as i32, w, h)
        })
    }

    /// First and last pixel along the major axis: those whose centre lies
    /// in the line (Bresenham), or whose cell it touches (Wu, which weights
    /// the end cells by their coverage).
    pub(crate) fn columns(&self, antialias: bool) -> (i64, i64) {
        if antialias {
            (div_floor(self.a, SUBPIXEL), div_floor(self.b - 1, SUBPIXEL))
        } else {
            (self.first, self.last)
        }
    }

    /// `[at p0, at p1]` reordered to `[at a, at b]`, the walk's direction.
    pub(crate) fn ends<T>(&self, [p, q]: [T; 2]) -> [T; 2] {
        if self.reversed {
            [q, p]
        } else {
            [p, q]
        }
    }

    /// Length along the major axis (sub-pixels, positive) and the offset of
    /// the first two-point column's centre from `a`.
    pub(crate) fn extent(&self) -> (i64, i64) {
        (self.b - self.a, self.centre(self.columns(true).0))
    }

    /// Offset of column `c`'s centre from `a`, in sub-pixels.
    fn centre(&self, c: i64) -> i64 {
        SUBPIXEL * c + SUBPIXEL / 2 - self.a
    }

    /// Z at column centres from `c0` on, in 16.14 (the span path adds the
    /// rounding half): floor((z0 len + t dz) 2^14 / len), below 2^50.
    // Inlined: once the draw code grew, the compiler left it out of line,
    // where its floor divisions made twice the 64-bit library calls
    // (Bresenham: 133 instead of 110 instructions a step on the
    // Cortex-M4, measured).
    #[inline(always)]
    fn z_walk(&self, c0: i64) -> FloorWalk<i64> {
        let (len, zs) = (self.b - self.a, 1i64 << Z_FRAC);
        FloorWalk::new(
            (self.z0 * len + self.centre(c0) * self.dz) * zs,
            len,
            SUBPIXEL * self.dz * zs,
        )
    }

    /// Calls `f(k, major, minor, z_16_14)` for each Bresenham pixel whose
    /// major index lies in `lo..hi`, with `k` its index from the start point.
    pub(crate) fn walk(&self, lo: i64, hi: i64, mut f: impl FnMut(u32, i64, i64, i32)) {
        let (c0, c1) = (self.first.max(lo), (self.last + 1).min(hi));
        if c0 >= c1 {
            return;
        }
        let len = self.b - self.a;
        // minor(c) = m0 + (centre - a) dm / len: pixel floor(minor / 16)
        //          = floor((m0 len + (centre - a) dm) / (16 len)).
        let mut minor = FloorWalk::new(
            self.m0 * len + self.centre(c0) * self.dm,
            SUBPIXEL * len,
            SUBPIXEL * self.dm,
        );
        let mut z = self.z_walk(c0);
        for c in c0..c1 {
            let k = if self.reversed {
                self.last - c
            } else {
                c - self.first
            };
            f(k as u32, c, minor.q, z.q as i32);
            minor.next();
            z.next();
        }
    }

    /// The cells of the two-point walk: for each column in `lo..hi` the
    /// line's extent touches, calls `f(k, major, u, cover, z)` with `k` the
    /// column's index from the start point, `u` the exact line position at
    /// the column centre in pixel-centre units of 1/256 (floor), `cover` the
    /// part of the column's cell inside the extent (in 1/256) and `z` the
    /// depth in 16.14.
    fn walk_cells(&self, lo: i64, hi: i64, mut f: impl FnMut(u32, i64, i64, i32, i32)) {
        let (first, last) = self.columns(true);
        let (c0, c1) = (first.max(lo), (last + 1).min(hi));
        if c0 >= c1 {
            return;
        }
        let len = self.b - self.a;
        // Minor position in pixel-centre coordinates, in 1/256 pixel:
        // u = (minor - 8) / 16 * 256 = 16 (minor - 8), with minor exact.
        let mut u = FloorWalk::new(
            16 * ((self.m0 - SUBPIXEL / 2) * len + self.centre(c0) * self.dm),
            len,
            256 * self.dm,
        );
        let mut z = self.z_walk(c0);
        for c in c0..c1 {
            let k = if self.reversed { last - c } else { c - first };
            let cell =
                (self.b.min(SUBPIXEL * c + SUBPIXEL) - self.a.max(SUBPIXEL * c)).clamp(0, SUBPIXEL);
            let cover = cell as i32 * WU_ONE / SUBPIXEL as i32;
            f(k as u32, c, u.q, cover, z.q as i32);
            u.next();
            z.next();
        }
    }

    /// Two-point antialiasing (seed 003, eqs. 4 and 7): for each column in
    /// `lo..hi` the line touches, calls `f(k, major, minor, w0, w1, z)` for
    /// the pixels `minor` and `minor + 1` straddling the line at the column
    /// centre, with weights `w0 + w1` equal to the column's coverage along
    /// the major axis ([`WU_ONE`] inside, less at the end cells), split by
    /// the distance `D` to pixel `minor`'s centre: `w1 = D cov`, `w0 = cov - w1`.
    pub(crate) fn walk_wu(
        &self,
        lo: i64,
        hi: i64,
        mut f: impl FnMut(u32, i64, i64, i32, i32, i32),
    ) {
        self.walk_cells(lo, hi, |k, c, u, cover, z| {
            let w1 = ((u & 255) as i32 * cover) >> 8;
            f(k, c, u >> 8, cover - w1, w1, z);
        });
    }

    /// Edge antialiasing (seed 003 eq. 8): for each column in `lo..hi` the
    /// edge touches, calls `f(major, minor, w, k, z)` for the one pixel outside
    /// the solid whose cell the edge crosses, if any. `w` (in 1/256) is the
    /// part of that pixel on the solid's side: with `D` the two-point
    /// distance, `1/2 - D` when the solid lies towards larger minor
    /// coordinates (`up`), else `D - 1/2`, times the column's coverage; `k`
    /// is the column's index from the first column of the walk.
    pub(crate) fn walk_edge(
        &self,
        up: bool,
        lo: i64,
        hi: i64,
        mut f: impl FnMut(i64, i64, i32, i64, i32),
    ) {
        let half = WU_ONE / 2;
        let first = self.columns(true).0;
        self.walk_cells(lo, hi, |_, c, u, cover, z| {
            let d = (u & 255) as i32;
            let (m, part) = if up {
                (u >> 8, half - d)
            } else {
                (1 + (u >> 8), d - half)
            };
            if part > 0 {
                f(c, m, (part * cover) >> 8, c - first, z);
            }
        });
    }
}
