//! The numeric contract: every fixed-point format the pipeline uses, its range
//! and its rounding.
//!
//! | quantity | format | range | where |
//! | --- | --- | --- | --- |
//! | vertex x, y | [`Coord`] = `I28F4`: 4 sub-pixel bits | `[-8192, 8192)` pixels ([`COORD_LIMIT`]) | API |
//! | vertex Z | `u16` | `0..=65535`, 0 nearest | API |
//! | vertex colour | `u8` per channel | `0..=255` | API |
//! | span colour / step | [`ColorFix`] = `U16F16` / [`ColorStep`] = `I16F16`, 0..255 scale | end of span within `[0, 256)` | API |
//! | span Z / step | [`ZFix`] = `U16F16` / [`ZStep`] = `I16F16` | end of span within `[0, 65536)` | API |
//! | edge function | `i64`, units of (1/16 px)² | `|E| < 2^40` | setup, traversal |
//! | interpolated colour | `i32`, *output* channel scale with [`COLOR_FRAC`] = 16 fraction bits | `[0, 2^24)` | span DDA |
//! | interpolated Z | `i32`, 16.[`Z_FRAC`] = 16.14 | `[0, 2^30 + 2^13]` | span DDA |
//!
//! **Pixel centres** are at `+0.5`: pixel `(px, py)` is sampled at sub-pixel
//! position `(16 px + 8, 16 py + 8)`. The **top-left fill rule** decides
//! samples exactly on an edge, so meshes are watertight.
//!
//! **Interpolation bound.** Each span restarts from the exact plane equation
//! (barycentric weights from the integer edge functions, rounded to 2^-30), so
//! the start value is within 2^-11 LSB of exact. Each DDA step adds a delta
//! rounded to half a unit of the last fraction bit, so after `k` steps the
//! drift is at most `k / 2` units: for the longest span (4096 pixels) that is
//! 2^-5 LSB of colour (16 fraction bits) and 2^-3 LSB of Z (14 fraction bits).
//! The final rounding to the stored integer adds 0.5 LSB. Hence the tested
//! bounds: **colour within 1 LSB, Z within 1 LSB** of the f64 reference.
//!
//! **Saturation.** Values are clamped to the channel range when quantized, so
//! the dither "+1" and DDA drift never wrap.

use fixed::types::{I16F16, I28F4, U16F16};

/// Vertex coordinate: signed pixels with 4 sub-pixel bits (`I28F4`).
///
/// ```
/// use tilerast::numeric::Coord;
/// let x = Coord::from_num(10.25);
/// assert_eq!(x.to_bits(), 164); // 10.25 * 16
/// ```
pub type Coord = I28F4;
/// Span-command colour channel on the 0..255 scale (`U16F16`).
pub type ColorFix = U16F16;
/// Span-command per-pixel colour step on the 0..255 scale (`I16F16`).
pub type ColorStep = I16F16;
/// Span-command depth (`U16F16`, 0..65535).
pub type ZFix = U16F16;
/// Span-command per-pixel depth step (`I16F16`).
pub type ZStep = I16F16;

/// Sub-pixel bits of [`Coord`].
pub const SUBPIXEL_BITS: u32 = 4;
/// Sub-pixel units per pixel.
pub const SUBPIXEL: i64 = 1 << SUBPIXEL_BITS;
/// Vertex coordinates must lie in `[-COORD_LIMIT, COORD_LIMIT)` pixels: the
/// screen plus a guard band. Beyond it, commands are rejected with
/// [`Error::CoordOutOfRange`](crate::Error::CoordOutOfRange).
pub const COORD_LIMIT: i32 = 8192;
/// Largest screen or tile side in pixels.
pub const MAX_SIDE: u16 = 4096;
/// Fraction bits of interpolated colour in the span DDA.
pub const COLOR_FRAC: u32 = 16;
/// Fraction bits of interpolated Z in the span DDA.
pub const Z_FRAC: u32 = 14;
/// Fraction bits of barycentric weights at span start.
pub(crate) const W_FRAC: u32 = 30;

/// Floor division for `d > 0`. When both operands fit in `i32` (small and
/// medium triangles: nearly always) it divides in 32 bits — exactly the same
/// quotient, but one hardware or short library division instead of a 64-bit
/// library call (Cortex-M0 has no divide instruction at all).
#[inline]
pub(crate) fn div_floor(n: i64, d: i64) -> i64 {
    if let (Ok(n), Ok(d)) = (i32::try_from(n), i32::try_from(d)) {
        let q = n / d;
        return if (n % d) < 0 { q as i64 - 1 } else { q as i64 };
    }
    let q = n / d;
    if (n % d) < 0 {
        q - 1
    } else {
        q
    }
}

/// Division rounded to nearest (ties up) for `d > 0`.
#[inline]
pub(crate) fn div_round(n: i64, d: i64) -> i64 {
    div_floor(n + d / 2, d)
}

/// Converts a 16.14 interpolated Z to the stored 16-bit value (floor; the span
/// start carries the +0.5 rounding bias).
#[inline(always)]
pub(crate) fn z_to_u16(z: i32) -> u16 {
    // z <= 2^30 + 2^13 + drift, so z >> 14 <= 65536 only if drift exceeded its
    // bound; clamp anyway: never wrap.
    (z >> Z_FRAC).clamp(0, 0xFFFF) as u16
}

#[cfg(test)]
mod tests {
    use super::*;
    #[test]
    fn floor_and_round_division() {
        assert_eq!(div_floor(-1, 16), -1);
        assert_eq!(div_floor(-16, 16), -1);
        assert_eq!(div_floor(15, 16), 0);
        assert_eq!(div_round(7, 16), 0);
        assert_eq!(div_round(8, 16), 1);
        assert_eq!(div_round(-8, 16), 0);
        assert_eq!(div_round(-9, 16), -1);
    }
}
