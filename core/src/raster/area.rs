//! Area-sampling antialiasing through the α-channel (seed 001 §IV.5: "RE
//! uses area sampling, performed in the α-channel"): each pixel a
//! triangle's **flagged** edges cross gets the exact area of the pixel
//! square inside them as its blend weight, `C = α C_tri + (1 - α) C_dst`.
//!
//! **Which edges.** A [`Vertex::edge_flag`] marks the edge from that vertex
//! to the next, as OpenGL's edge flag does: an edge that borders something
//! else on screen (a silhouette, an open boundary, a lone triangle). An
//! unflagged edge keeps the aliased rule — pixel centre and top-left
//! rule — so two triangles of one surface still cover complementary pixels
//! and no background shows through a shared edge (area sampling every
//! edge would leave a seam of `c (1 - c)` background on each).
//!
//! **Coverage, exactly.** Over a pixel square an edge function `E` (value
//! `e` at the centre, changes `a` per pixel in x and `b` in y) spans
//! `e ± (|a| + |b|)/2`. With `A = max(|a|, |b|)`, `B = min(..)` the part of
//! the square where `E >= 0` is, in closed form ([`edge_coverage`]):
//! - `1/2 + e/A` while `|e| <= (A - B)/2` (the edge crosses two opposite
//!   sides),
//! - `1 - (A + B - 2e)² / (8 A B)` above, `(A + B + 2e)² / (8 A B)` below
//!   (it cuts a corner),
//!
//! rounded to 1/256: one integer division. A pixel that two or three
//! flagged edges cross (near a vertex, and across a thin sliver) is the
//! square clipped by each half-plane, its area by the shoelace formula in
//! `f64` ([`polygon_coverage`]): only `+ - * /`, so it is bit-identical on
//! every target.
//!
//! **Colour and depth** of an edge pixel are the triangle's planes at its
//! centre, exactly (`sum c_k E_k / area2`), clamped to the vertices' range
//! since the centre may lie outside; interior pixels go through the span
//! loop as for aliased triangles, so a triangle without flags draws
//! exactly what it draws without this mode.
//!
//! **Order.** An edge pixel blends over whatever the tile holds when the
//! triangle is drawn: draw what lies behind a silhouette first (back to
//! front, as for translucency). A pixel whose centre is inside writes
//! depth, one outside only tests it.

use crate::format::Rgb;
use crate::geom::Vertex;
use crate::numeric::Divisor;
use crate::raster::coverage::{AaMode, Centre1};
use crate::setup::{oriented_edges, Edge};

/// Area-sampling antialiasing (the RE's, through the α-channel): a tile
/// configuration's antialiasing choice ([`Planes`](crate::config::Planes)'
/// fifth parameter) that adds **no plane** — 0 bits a pixel — and draws
/// every triangle edge flagged by [`Vertex::edge_flag`] with its pixels'
/// exact coverage as α. Unflagged triangles draw exactly as without it.
///
/// ```
/// use tilerast::prelude::*;
/// type Smooth = Planes<Rgb565Format, Depth16, NoWid, NoDither, AreaAa>;
/// let mut tile: Box<Tile<{ groups(16, 16) }, Smooth>> = Box::default();
/// tile.begin(Rect::new(0, 0, 16, 16), &Clear::default()).unwrap();
/// let v = |x: f32, y: f32| Vertex::new(Coord::from_num(x), Coord::from_num(y), 9, Rgb::new(255, 255, 255)).with_edge_flag(true);
/// tile.draw(&Command::triangle([v(1.0, 1.0), v(15.0, 3.0), v(4.0, 14.0)])).unwrap();
/// // Edge pixels are grey: partly covered, blended over the black clear.
/// let grey = (0..16 * 16)
///     .filter(|i| !matches!(tile.raw(i % 16, i / 16), Some(0 | 0xFFFF)))
///     .count();
/// assert!(grey > 20);
/// assert_eq!(Tile::<{ groups(16, 16) }, Smooth>::bits_per_pixel(), 32);
/// ```
#[derive(Debug, Clone, Copy, Default)]
pub struct AreaAa;

impl AaMode for AreaAa {
    const SAMPLES: usize = 0;
    const AREA: bool = true;
    type Pattern = Centre1;
    type Plane<const N: usize> = ();
    const NAME: &'static str = "area";
}

/// Coverage of a pixel square by the half-plane `E >= 0`, in 1/256
/// (`0..=256`), for `E`'s value `e` at the centre and its changes `a`, `b`
/// per pixel in x and y (any units, the same for all three). Exact but for
/// the final rounding to nearest.
///
/// ```
/// use tilerast::area::edge_coverage;
/// assert_eq!(edge_coverage(0, 16, 0), 128); // a vertical edge through the centre
/// assert_eq!(edge_coverage(4, 16, 0), 192); // a quarter pixel to the right
/// assert_eq!(edge_coverage(0, 16, 16), 128); // a diagonal through the centre
/// assert_eq!(edge_coverage(-16, 16, 16), 0); // through a corner, outside
/// assert_eq!(edge_coverage(8, 16, 16), 224); // cuts an eighth off a corner
/// ```
pub fn edge_coverage(e: i64, a: i64, b: i64) -> u16 {
    Band::new(a, b).coverage(e)
}

/// One edge's band of partly covered pixels: `|e| < h / 2`, with the two
/// divisors of [`edge_coverage`]'s closed form set up once per edge (each
/// quotient is then a high product, [`Divisor`]).
#[derive(Debug, Clone, Copy)]
struct Band {
    /// `|a| + |b|`: the change of `E` across the pixel square.
    h: i64,
    /// `max(|a|, |b|) - min(|a|, |b|)`.
    diff: i64,
    big: i64,
    by_big: Divisor,
    /// `/ (big small)`, for a corner cut off.
    by_corner: Divisor,
}

impl Band {
    /// For `(a, b) != (0, 0)` and `|a|, |b| < 2^23`.
    fn new(a: i64, b: i64) -> Band {
        let (a, b) = (a.unsigned_abs() as i64, b.unsigned_abs() as i64);
        let (big, small) = (a.max(b), a.min(b));
        Band {
            h: big + small,
            diff: big - small,
            big,
            by_big: Divisor::new(big.max(1)),
            by_corner: Divisor::new((big * small).max(1)),
        }
    }

    fn coverage(&self, e: i64) -> u16 {
        let e2 = 2 * e;
        if e2 >= self.h {
            256
        } else if e2 <= -self.h {
            0
        } else if e2.abs() <= self.diff {
            // Both sides crossed: linear in e.
            self.by_big.round(128 * self.big + 256 * e) as u16
        } else {
            // A corner cut off: the triangle's area t²/(8AB).
            let t = self.h - e2.abs();
            let corner = self.by_corner.round(32 * t * t);
            if e > 0 {
                (256 - corner) as u16
            } else {
                corner as u16
            }
        }
    }
}

/// Coverage of a pixel square by the intersection of half-planes
/// `e + a x + b y >= 0` (`x, y` in pixels from the centre), in 1/256: the
/// square clipped by each (Sutherland–Hodgman), its area by the shoelace
/// formula, in `f32` with `+ - * /` only (correctly rounded by IEEE 754:
/// the same bits on every target, and the Cortex-M4F's FPU computes them).
///
/// ```
/// use tilerast::area::polygon_coverage;
/// // x >= 0 and y >= 0: the quarter of the pixel right of and below the centre.
/// assert_eq!(polygon_coverage(&[(0, 16, 0), (0, 0, 16)]), 64);
/// assert_eq!(polygon_coverage(&[(0, 16, 0)]), 128);
/// ```
pub fn polygon_coverage(planes: &[(i64, i64, i64)]) -> u16 {
    // At most 4 + one vertex per half-plane, clipped back and forth
    // between two buffers.
    let mut buf = [[(0f32, 0f32); 7]; 2];
    buf[0][..4].copy_from_slice(&[(-0.5, -0.5), (0.5, -0.5), (0.5, 0.5), (-0.5, 0.5)]);
    let mut n = 4;
    for (pass, &(e, a, b)) in planes.iter().enumerate() {
        // Scaled so that the larger coefficient is 1. A half-plane that
        // crosses the pixel has |e| < |a| + |b| < 2^24: exact in `f32`.
        let s = a.abs().max(b.abs()).max(1) as f32;
        let c = |v: i64| v.clamp(-(1 << 24), 1 << 24) as i32 as f32 / s;
        let (e, a, b) = (c(e), c(a), c(b));
        let [b0, b1] = &mut buf;
        let (poly, next) = if pass % 2 == 0 {
            (&*b0, b1)
        } else {
            (&*b1, b0)
        };
        let f = |p: (f32, f32)| e + a * p.0 + b * p.1;
        let (mut m, mut fp) = (0, f(poly[0]));
        for i in 0..n {
            let j = if i + 1 == n { 0 } else { i + 1 };
            let (p, q, fq) = (poly[i], poly[j], f(poly[j]));
            if fp >= 0.0 && m < 7 {
                next[m] = p;
                m += 1;
            }
            if (fp >= 0.0) != (fq >= 0.0) && m < 7 {
                let t = fp / (fp - fq);
                next[m] = (p.0 + (q.0 - p.0) * t, p.1 + (q.1 - p.1) * t);
                m += 1;
            }
            fp = fq;
        }
        n = m;
        if n < 3 {
            return 0;
        }
    }
    let poly = &buf[planes.len() % 2];
    let mut twice = 0f32;
    for i in 0..n {
        let (p, q) = (poly[i], poly[if i + 1 == n { 0 } else { i + 1 }]);
        twice += p.0 * q.1 - q.0 * p.1;
    }
    let v = twice.abs() * 128.0 + 0.5;
    (v as i32).clamp(0, 256) as u16
}

/// One edge pixel of an area-sampled triangle.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct EdgePixel {
    /// Coverage by the flagged edges, 1/256 (`1..=256`).
    pub w: u16,
    /// Whether the centre is inside every edge (the aliased rule): it
    /// writes depth.
    pub inside: bool,
    /// Colour at the centre, clamped to the vertices' range.
    pub color: Rgb,
    /// Depth at the centre, clamped likewise.
    pub z: u16,
    /// Opacity at the centre, clamped likewise.
    pub alpha: u8,
}

/// A pixel of an area-sampled triangle's row: its edge values at the
/// centre.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Cursor {
    ec: [i64; 3],
}

/// Where a pixel stands against an area-sampled triangle.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Cover {
    /// Outside: an unflagged edge's centre test fails, or no flagged area.
    Out,
    /// Crossed by a flagged edge.
    Edge,
    /// Inside the unflagged edges' centre test and entirely inside the
    /// flagged ones.
    Full,
}

/// An area-sampled triangle: its oriented edges, which are flagged (with
/// their bands), and the planes of its attributes over one reciprocal of
/// its doubled area.
#[derive(Debug, Clone)]
pub(crate) struct AreaSetup {
    e: [Edge; 3],
    flagged: [bool; 3],
    band: [Band; 3],
    by_area: Divisor,
    /// Per vertex (in edge order): r, g, b, z, α.
    attr: [[i64; 5]; 3],
    lo: [i64; 5],
    hi: [i64; 5],
}

impl AreaSetup {
    /// `None` for a zero-area triangle.
    pub fn new(v: &[Vertex; 3]) -> Option<Self> {
        let (e, area2, swapped) = oriented_edges(v)?;
        // Edge k lies opposite vertex k of the (swapped) order; vertex i's
        // flag names the edge from v[i] to v[i + 1].
        let vv = if swapped { [v[0], v[2], v[1]] } else { *v };
        let order = if swapped { [0, 2, 1] } else { [0, 1, 2] };
        let flagged = order.map(|o| v[(o + 1) % 3].edge_flag);
        let attr = vv.map(|v| {
            let c = v.color;
            [
                c.r as i64,
                c.g as i64,
                c.b as i64,
                v.z as i64,
                v.alpha as i64,
            ]
        });
        let lo = core::array::from_fn(|k| attr.iter().map(|a| a[k]).min().unwrap_or(0));
        let hi = core::array::from_fn(|k| attr.iter().map(|a| a[k]).max().unwrap_or(0));
        let band = core::array::from_fn(|k| {
            if flagged[k] {
                Band::new(e[k].a, e[k].step)
            } else {
                Band::new(1, 0)
            }
        });
        Some(AreaSetup {
            e,
            flagged,
            band,
            by_area: Divisor::new(area2),
            attr,
            lo,
            hi,
        })
    }

    /// A cursor at pixel `(px, py)`: the edge values at its centre, exact;
    /// [`Self::step`] moves it along the row.
    pub fn cursor(&self, px: i64, py: i64) -> Cursor {
        Cursor {
            ec: self.e.each_ref().map(|e| e.a * px + e.row(py)),
        }
    }

    /// Moves the cursor one pixel right (`RIGHT`) or left: additions.
    #[inline(always)]
    pub fn step<const RIGHT: bool>(&self, c: &mut Cursor) {
        for k in 0..3 {
            c.ec[k] = if RIGHT {
                c.ec[k] + self.e[k].a
            } else {
                c.ec[k] - self.e[k].a
            };
        }
    }

    /// How the cursor's pixel stands.
    #[inline(always)]
    pub fn cover(&self, c: &Cursor) -> Cover {
        let mut full = true;
        for k in 0..3 {
            let ec = c.ec[k];
            if self.flagged[k] {
                let h = self.band[k].h;
                if 2 * ec <= -h {
                    return Cover::Out;
                }
                full &= 2 * ec >= h;
            } else if ec < self.e[k].bias {
                return Cover::Out;
            }
        }
        if full {
            Cover::Full
        } else {
            Cover::Edge
        }
    }

    /// The cursor's pixel, which [`Self::cover`] found crossed; `None`
    /// where its coverage rounds to 0. With `alpha` its opacity is
    /// interpolated too (else 255).
    pub fn pixel(&self, c: &Cursor, alpha: bool) -> Option<EdgePixel> {
        let ec = &c.ec;
        let mut crossing = [(0i64, 0i64, 0i64); 3];
        let (mut n, mut first) = (0, 0);
        for (k, &e) in ec.iter().enumerate() {
            if self.flagged[k] && 2 * e < self.band[k].h {
                if n == 0 {
                    first = k;
                }
                crossing[n] = (e, self.e[k].a, self.e[k].step);
                n += 1;
            }
        }
        let w = match n {
            0 => 256,
            1 => self.band[first].coverage(ec[first]),
            _ => polygon_coverage(&crossing[..n]),
        };
        if w == 0 {
            return None;
        }
        let inside = (0..3).all(|k| ec[k] >= self.e[k].bias);
        let ch = |k: usize| {
            let n = self.attr[0][k] * ec[0] + self.attr[1][k] * ec[1] + self.attr[2][k] * ec[2];
            self.by_area.round(n).clamp(self.lo[k], self.hi[k])
        };
        Some(EdgePixel {
            w,
            inside,
            color: Rgb::new(ch(0) as u8, ch(1) as u8, ch(2) as u8),
            z: ch(3) as u16,
            alpha: if alpha { ch(4) as u8 } else { 255 },
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The closed form against the clipped polygon, over every kind of
    /// crossing (sides, corners, axis-aligned, steep and shallow).
    #[test]
    fn closed_form_equals_the_polygon() {
        let mut worst = 0i32;
        for a in [-48i64, -17, -16, -3, 0, 1, 5, 16, 31, 160] {
            for b in [-40i64, -16, -7, 0, 2, 16, 33, 255] {
                if a == 0 && b == 0 {
                    continue;
                }
                let h = a.abs() + b.abs();
                for e in -h..=h {
                    let c = edge_coverage(e, a, b) as i32;
                    let p = polygon_coverage(&[(e, a, b)]) as i32;
                    worst = worst.max((c - p).abs());
                }
            }
        }
        // Each rounds the same exact area to nearest; a tie may go either way.
        assert!(worst <= 1, "worst {worst}");
    }

    #[test]
    fn complementary_half_planes_sum_to_one() {
        for (e, a, b) in [(3i64, 16i64, 5i64), (-7, 9, 16), (0, 1, 1), (12, 16, 16)] {
            let s = edge_coverage(e, a, b) + edge_coverage(-e, -a, -b);
            assert!((255..=257).contains(&s), "{s}");
        }
    }
}
