//! Vector drawing (seed 001, §II and Conclusion: "vector drawing with line
//! styles"): Bresenham lines with sub-pixel endpoints, depth, window ID,
//! plane mask and a repeating on/off style.
//!
//! **Which pixels.** Along the major axis (the larger of `|dx|`, `|dy|`),
//! every pixel whose centre `16 c + 8` lies in the half-open interval from
//! the start point to the end point gets one pixel: the one whose cell
//! contains the ideal line at that centre, `floor(minor / 16)` — exactly
//! the pixel Bresenham picks, computed with the exact quotient/remainder
//! walk of [`crate::traverse`], so it cannot depend on the tiling. The end
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

use crate::error::Error;
use crate::format::Rgb;
use crate::geom::Rect;
use crate::numeric::{div_floor, Coord, COORD_LIMIT, SUBPIXEL, Z_FRAC};
use crate::traverse::FloorWalk;

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
        let lim = COORD_LIMIT as i64 * SUBPIXEL;
        let ok = |c: (Coord, Coord)| {
            let (x, y) = sub(c);
            (-lim..lim).contains(&x) && (-lim..lim).contains(&y)
        };
        if ok(self.p0) && ok(self.p1) {
            Ok(())
        } else {
            Err(Error::CoordOutOfRange)
        }
    }

    pub(crate) fn setup(&self) -> Option<LineSetup> {
        let (p, q) = (sub(self.p0), sub(self.p1));
        let y_major = (q.1 - p.1).abs() > (q.0 - p.0).abs();
        let (mut pa, mut pb) = if y_major {
            ((p.1, p.0), (q.1, q.0))
        } else {
            (p, q)
        };
        let (mut z0, mut z1) = (self.z[0] as i64, self.z[1] as i64);
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
        let s = self.setup()?;
        let (first, last) = s.columns(self.antialias);
        if first > last {
            return None;
        }
        // Wu also touches the pixel after the one containing the line.
        let lo = div_floor(s.m0.min(s.m0 + s.dm), SUBPIXEL) - self.antialias as i64;
        let hi = div_floor(s.m0.max(s.m0 + s.dm), SUBPIXEL) + self.antialias as i64;
        let (w, h) = ((last - first + 1) as u32, (hi - lo + 1) as u32);
        Some(if s.y_major {
            Rect::new(lo as i32, first as i32, h, w)
        } else {
            Rect::new(first as i32, lo as i32, w, h)
        })
    }
}

/// Weights of the two-point antialiased pixels are in 1/256.
pub(crate) const WU_ONE: i32 = 256;

impl LineSetup {
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

    /// Offset of column `c`'s centre from `a`, in sub-pixels.
    fn centre(&self, c: i64) -> i64 {
        SUBPIXEL * c + SUBPIXEL / 2 - self.a
    }

    /// Z at column centres from `c0` on, in 16.14 (the span path adds the
    /// rounding half): floor((z0 len + t dz) 2^14 / len), below 2^50.
    fn z_walk(&self, c0: i64) -> FloorWalk {
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
            let d = (u.q & 255) as i32;
            let w1 = (d * cover) >> 8;
            f(k as u32, c, u.q >> 8, cover - w1, w1, z.q as i32);
            u.next();
            z.next();
        }
    }
}
