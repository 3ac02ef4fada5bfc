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
//! **Interpolation bound.** Every attribute step is the exact gradient
//! rounded to half a unit of the last fraction bit. *Small triangles* (box
//! under 1024 px a side, set up in `i32`) step from one anchor per triangle
//! (triangle setup): the value at a pixel is vertex 0's plus `x` steps of
//! `gx` and `y` steps of `gy` (the anchor's offset, rounded once, then the
//! steps along the row and down the rows), so its drift is at most
//! `(W + H + 1) / 2` units for a box of `W x H` pixels: at most 1025
//! units, 0.016 LSB of colour (16 fraction bits) and 0.063 LSB of Z (14
//! fraction bits). *Large triangles* restart each span from the exact plane equation
//! (barycentric weights from the integer edge functions, rounded to 2^-30:
//! within 2^-11 LSB of exact, 2^-10 of colour and 2^-9 of Z counting the
//! weights' two roundings), and each DDA step then adds at most half a unit:
//! for the longest span (4096 pixels) that is 2^-5 LSB of colour and 2^-3
//! LSB of Z. The final rounding to the stored integer adds 0.5 LSB.
//! Hence the **tested bounds** against the f64 reference:
//!
//! | quantity | bound (LSB) | tests |
//! | --- | --- | --- |
//! | colour (RGB888) | `0.5 + 2^-5 + 2^-10` | `accuracy`, `domain` (every triangle class, every span) |
//! | Z (16-bit plane) | `0.5 + 2^-3 + 2^-9` | the same |
//! | Bresenham line Z | `0.5 + 2^-10` | `lines` |
//! | coverage | exactly the reference's pixel centres (same top-left rule) | `accuracy`, `domain`, `watertight` |
//!
//! measured at 0.4999 (colour) and 0.4990 (Z) on the 4096-pixel span, and
//! 0.5050 and 0.5027 on the largest stepped triangle (1023 px a side).
//!
//! **Domain.** Vertices and line end points anywhere in
//! `[-COORD_LIMIT, COORD_LIMIT)` (the guard band: 8192 px each way) are
//! valid, and so is every span whose channels stay in range to its last
//! pixel; anything else is an [`Error`](crate::Error), never garbage. Edge
//! functions then stay below 2^40 and every product in setup below 2^62, so
//! nothing wraps: the tests run with overflow checks on, over huge, tiny,
//! sliver, near-collinear, collinear and coincident triangles
//! (`tests/tests/domain.rs`).
//!
//! **Fewer bits.** A tile with [`Precision`] `Bits<C, Z>` rounds span starts
//! and steps to `C` / `Z` fraction bits: the drift bound becomes `k`
//! half-units of the coarser bit, `k / 2^(C+1)` LSB of colour after `k`
//! pixels. `tilerast-lab tradeoff` measures what that costs in error
//! (nothing is saved in cycles on a 32-bit core). Depth planes with
//! fraction bits ([`Depth24`](crate::fragment::Depth24),
//! [`Depth32`](crate::fragment::Depth32)) keep 8 or 14 of the DDA's 14
//! fraction bits of Z instead of rounding to the integer.
//!
//! **Saturation.** Values are clamped to the channel range when quantized, so
//! the dither "+1" and DDA drift never wrap.

use core::num::NonZeroU32;
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
/// How many fraction bits the colour and Z DDAs keep: a tile type parameter
/// ([`Tile`](crate::tile::Tile)'s last), [`FullPrecision`] by default.
///
/// The DDA registers are 32 bits wide whatever this says; fewer bits round
/// every span's start and step to nearest at `COLOR_BITS` (of at most
/// [`COLOR_FRAC`]) and `Z_BITS` (of at most [`Z_FRAC`]) fraction bits, which
/// is exactly the arithmetic of a narrower datapath. It exists to *measure*
/// what each bit buys (`tilerast-lab tradeoff`), the way the seed's designers
/// sized REjr's interpolators in their C model; the full widths cost nothing
/// extra on a 32-bit core.
///
/// ```
/// use tilerast::numeric::{Bits, FullPrecision, Precision};
/// assert_eq!((FullPrecision::COLOR_BITS, FullPrecision::Z_BITS), (16, 14));
/// assert_eq!(<Bits<8, 4> as Precision>::COLOR_BITS, 8);
/// ```
pub trait Precision: 'static {
    /// Colour fraction bits kept, `0..=16`.
    const COLOR_BITS: u32;
    /// Z fraction bits kept, `0..=14`.
    const Z_BITS: u32;
    /// Whether opaque Gouraud triangles follow the **plane contract**
    /// ([`PlaneContract`]) instead of the exact one.
    const PLANE: bool = false;
}

/// A [`Precision`] of `C` colour and `Z` depth fraction bits (values above
/// the maximum mean the maximum).
#[derive(Debug, Clone, Copy, Default)]
pub struct Bits<const C: u32, const Z: u32>;

impl<const C: u32, const Z: u32> Precision for Bits<C, Z> {
    const COLOR_BITS: u32 = C;
    const Z_BITS: u32 = Z;
}

/// Every fraction bit the DDAs have: 16 for colour, 14 for Z.
pub type FullPrecision = Bits<COLOR_FRAC, Z_FRAC>;

/// The **plane contract** for opaque Gouraud triangles: every fraction bit
/// ([`FullPrecision`]), and attribute steps from *one* reciprocal of the
/// triangle's doubled area instead of exactly rounded quotients — the
/// cheaper of the two numeric contracts (`docs/contracts.md`).
///
/// Both contracts anchor each attribute at the top-left pixel of the
/// triangle's box and evaluate `c + i gx + j gy` with wrapping 32-bit
/// arithmetic, so both are invariant under tiling and bit-identical on every
/// chip. They differ in the steps `gx`, `gy` (`n` a step's numerator,
/// `d1 k1 + d2 k2`):
///
/// - **exact** ([`FullPrecision`], [`Bits`]): `round(n / area2)`, the
///   exactly rounded rational step;
/// - **plane** (this type): `r = floor((2^46 - 1) / area2)` (three 32-bit
///   divisions a triangle), the barycentric weights' steps
///   `w = round(k r / 2^16)` with 30 fraction bits, and each attribute's
///   step `round(d1 w1 + d2 w2)`: two 32x32-bit products, no division.
///   `r` is within 2^-30 of `2^46 / area2`, so in the domain below a value
///   strays from the exact contract's by under 2^-6 of a depth unit and
///   2^-14 of a colour unit, plus the steps' rounding. A large triangle
///   (`area2 >= 2^16`) takes `r = floor((2^62 - 1) / area2)`, one 64-bit
///   division, and `w = round(k r / 2^32)`: the same weights. Measured on
///   208,538 fragments of random triangles (727 of them large): no colour
///   and 41 depths differ from the exact contract's, by one unit.
///
/// **Domain.** The plane contract takes a triangle whose barycentric
/// weights change by less than 2^8 across its box and which is either
/// small, `area2 < 2^16` (under 128 square pixels; a sliver, whose weights
/// change by 2 or more a pixel, keeps fewer fraction bits), or large with
/// a box under 512 pixels of width plus height (so the steps' rounding,
/// summed across the box, stays under 2^-4 of a depth unit) and no
/// sliver. A larger triangle that is no sliver — a side of 1024 pixels or
/// more, or a wider box: the near-clipped ground or wall beside the
/// camera — is a *far* triangle: its setup runs in 64 bits per 64-pixel
/// block, and its planes are anchored once per 256-pixel cell of the
/// screen at a pixel whose weights are exactly rounded, so a value is
/// never more than 510 steps from its anchor (error under 2^-4 of a
/// depth unit and 2^-7 of a colour unit; `tile::mesh`). Slivers beyond
/// these take the exact contract. The choice depends on the
/// triangle alone, never on the tile, and so do the cells. Translucent,
/// quadratic, textured and antialiased triangles keep the exact contract.
///
/// ```
/// use tilerast::prelude::*;
/// type Fast = Planes<Rgb565Format, Depth16, NoWid, NoDither, NoAa, PlaneContract>;
/// assert!(<PlaneContract as Precision>::PLANE);
/// assert!(!<FullPrecision as Precision>::PLANE);
/// assert_eq!(Tile::<256, Fast>::bits_per_pixel(), 32); // no plane of its own
/// ```
#[derive(Debug, Clone, Copy, Default)]
pub struct PlaneContract;

impl Precision for PlaneContract {
    const COLOR_BITS: u32 = COLOR_FRAC;
    const Z_BITS: u32 = Z_FRAC;
    const PLANE: bool = true;
}

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

/// `floor(n / d)` for `d < 2^24` by schoolbook division in 32-bit steps:
/// the high word, then four 8-bit digits, each a 32-by-32-bit division
/// whose dividend (remainder times 256 plus a digit) stays below 2^32. On
/// a chip with a hardware divider (Cortex-M3 and up) that is five `udiv`s,
/// against a 64-bit library division (about 170 instructions on the
/// Cortex-M4 for a 24-bit divisor, measured) or a reciprocal.
#[inline(always)]
pub(crate) fn div_floor_u24(n: u64, d: u32) -> u64 {
    div_floor_u24_with(n, d, |x| x / d)
}

/// [`div_floor_u24`] with each 32-bit quotient `x / d` from `div`.
#[inline(always)]
fn div_floor_u24_with(n: u64, d: u32, div: impl Fn(u32) -> u32) -> u64 {
    debug_assert!(d > 0 && d < 1 << 24);
    let hi = (n >> 32) as u32;
    let q_hi = div(hi);
    let mut r = hi - q_hi * d;
    let mut q_lo = 0u32;
    let lo = n as u32;
    let mut k = 4;
    while k > 0 {
        k -= 1;
        let cur = (r << 8) | ((lo >> (8 * k)) & 0xff);
        let q = div(cur);
        r = cur - q * d;
        q_lo = (q_lo << 8) | q;
    }
    ((q_hi as u64) << 32) | q_lo as u64
}

/// Whether this is a 32-bit microcontroller (Arm M-profile, RV32), whose
/// arithmetic routes [`HW_DIV32`], [`LONG_MUL`] and [`HW_CLZ`] choose; a
/// 64-bit host has every instruction they ask about.
pub(crate) const MCU32: bool = cfg!(any(target_arch = "arm", target_arch = "riscv32"));

/// Whether most instructions reach more than eight registers: not on
/// ARMv6-M (the Cortex-M0), whose 16-bit Thumb encodings address r0-r7,
/// so that a span loop that holds one more value spills it. A route that
/// trades a table read for a register held across a loop checks it.
pub(crate) const MANY_REGS: bool = !cfg!(all(target_arch = "arm", not(target_has_atomic = "32")));

/// Whether this chip divides 32-bit integers in hardware: every Arm
/// M-profile core with 32-bit atomics (ARMv7-M, ARMv8-M Mainline) has
/// `udiv`, every RISC-V core with the `M` extension (rv32imc, rv32imac:
/// ESP32-C3 and C6, the RP2350's Hazard3) has `divu`; the Cortex-M0
/// (ARMv6-M) and rv32i have neither. Elsewhere (the host) a 64-bit division
/// is one instruction. Both routes are bit-identical and the tests run both
/// on the host (`docs/contracts.md`, "Routes by chip").
pub(crate) const HW_DIV32: bool = cfg!(any(
    all(target_arch = "arm", target_has_atomic = "32"),
    all(target_arch = "riscv32", target_feature = "m")
));

/// `floor(n / d)` for `d > 0`: the traversal's edge walks ([`FloorWalk`],
/// six per triangle and tile). One `sdiv` where the core has it; on the
/// Cortex-M0, whose division is a library call of about 100 instructions
/// (38,580 of them in the micro:bit's demo frame), quotients below 8 —
/// nearly every one: edge crossings inside a small triangle's box, steep
/// edges' slopes — by repeated subtraction (1.4 M instructions fewer in
/// that frame: measured).
///
/// [`FloorWalk`]: crate::raster::traverse
#[inline(always)]
pub(crate) fn div_floor_i32(n: i32, d: i32) -> i32 {
    div_floor_i32_by::<LONG_MUL>(n, d)
}

/// [`div_floor_i32`] by the division instruction (`HW`) or by the M0's
/// route (the tests run both on the host).
#[inline(always)]
fn div_floor_i32_by<const HW: bool>(n: i32, d: i32) -> i32 {
    debug_assert!(d > 0);
    if HW {
        let q = n / d;
        return if n % d < 0 { q - 1 } else { q };
    }
    // floor(n / d) = -1 - floor(!n / d) for n < 0 (!n = -n - 1 >= 0).
    let neg = n < 0;
    let m = (if neg { !n } else { n }) as u32;
    let q = small_quotient(m, d as u32) as i32;
    if neg {
        -1 - q
    } else {
        q
    }
}

/// `m / d` (`d > 0`): by repeated subtraction when the quotient is below
/// 8 (in the demo frame nearly all are 0 or 1: measured), else the
/// library's division.
#[cfg_attr(all(target_arch = "arm", not(target_has_atomic = "32")), inline(never))]
fn small_quotient(m: u32, d: u32) -> u32 {
    if d >= 1 << 28 || m >= d << 3 {
        return m / d;
    }
    let (mut q, mut r) = (0, m);
    while r >= d {
        r -= d;
        q += 1;
    }
    q
}

/// `(a / d, b / d)` rounded to nearest, ties up ([`div_round`]'s results),
/// for `|a|, |b| < 2^62` and `d > 0`: two quotients by one divisor, each
/// by the fastest exact route the chip has. A 64-bit host divides; a chip
/// that divides 32-bit integers in hardware (ARMv7-M and up) takes
/// [`div_floor_u24`] when `d < 2^24` and both are non-negative; the
/// Cortex-M0, whose every division is a library call, takes
/// [`div_floor_bytes`] for a divisor in `256..2^24` and quotients below
/// 2^40 (a perspective sample's `q` and its texel coordinates), otherwise
/// one reciprocal ([`Divisor`]) serves both.
#[inline(always)]
pub(crate) fn div_round_pair(a: i64, b: i64, d: i64) -> (i64, i64) {
    div_round_pair_by::<{ cfg!(target_pointer_width = "64") }, HW_DIV32>(a, b, d)
}

/// [`div_round_pair`] by the host's division (`WIDE`), the division
/// instruction's route (`DIV32`) or the Cortex-M0's (neither): the tests
/// run every route on the host.
#[inline(always)]
fn div_round_pair_by<const WIDE: bool, const DIV32: bool>(a: i64, b: i64, d: i64) -> (i64, i64) {
    if WIDE {
        return (div_round(a, d), div_round(b, d));
    }
    let small = d < 1 << 24 && a >= 0 && b >= 0;
    if DIV32 && small {
        let q = |n: i64| div_floor_u24((n + d / 2) as u64, d as u32) as i64;
        return (q(a), q(b));
    }
    if !DIV32 && small && d >= 1 << 8 {
        // Both quotients inline (a closure called twice was a function of
        // its own at the micro:bit's `opt-level = "s"`).
        let (d32, half) = (d as u32, d / 2);
        let rho = recip9(d32);
        let qa = div_floor_bytes((a + half) as u64, d32, rho);
        let qb = div_floor_bytes((b + half) as u64, d32, rho);
        if let (Some(qa), Some(qb)) = (qa, qb) {
            return (qa as i64, qb as i64);
        }
    }
    let r = Divisor::new(d);
    (r.round(a), r.round(b))
}

/// `floor(2^32 / (t + 1))` for the nine top bits `t` of a divisor
/// (`256..512`): [`recip9`]'s table, 1 KB of flash where it is used.
const RECIP9: [u32; 256] = {
    let mut t = [0u32; 256];
    let mut i = 0;
    while i < 256 {
        t[i] = ((1u64 << 32) / (i as u64 + 257)) as u32;
        i += 1;
    }
    t
};

/// A lower bound of `2^32 / d` within a factor `256/257`, for `d` in
/// `256..2^24`, from its nine top bits `t` (`d = t 2^s + low`, `low <
/// 2^s`): `floor(2^32 / (t + 1)) >> s`, below `2^32 / d` because
/// `d < (t + 1) 2^s`. No division: the Cortex-M0 has none (a library call
/// of about 165 instructions for the exact reciprocal).
#[inline(always)]
const fn recip9(d: u32) -> u32 {
    debug_assert!(d >= 1 << 8 && d < 1 << 24);
    // The shift that leaves nine bits, by compares (no `clz` on the M0).
    let mut s = 0;
    if d >= 1 << 16 {
        s += 8;
    }
    if d >> s >= 1 << 12 {
        s += 4;
    }
    if d >> s >= 1 << 10 {
        s += 2;
    }
    if d >> s >= 1 << 9 {
        s += 1;
    }
    RECIP9[(d >> s) as usize - 256] >> s
}

/// `floor(n / d)` for `d` in `256..2^24` and `n / d < 2^40` (`None`
/// otherwise: `n >> 40` reaches `d`), with `rho` from [`recip9`]: five
/// 8-bit digits, each estimated from the remainder `r < d` alone as `r rho
/// 2^-24` — one 32-bit product, below 2^32 since `rho < 2^32 / d` — which
/// is at most 3 below the digit (the bound's 1/257, the floors, the
/// incoming byte; 2 at most over 300,000 random digits, worst remainders
/// included), then corrected up while the remainder, exact in 32
/// bits, reaches `d`. Exact for every input: the estimate never exceeds
/// the digit, and each correction keeps `remainder = dividend - digit d`.
/// On the Cortex-M0 about 20 instructions a digit, against 35 for the
/// reciprocal's 32x32-bit high product ([`Divisor`]'s digits).
#[inline(always)]
fn div_floor_bytes(n: u64, d: u32, rho: u32) -> Option<u64> {
    let (hi, lo) = ((n >> 32) as u32, n as u32);
    let r = hi >> 8;
    if r >= d {
        return None;
    }
    let (top, r) = byte_digit(r, hi & 0xff, d, rho);
    let (g3, r) = byte_digit(r, lo >> 24, d, rho);
    let (g2, r) = byte_digit(r, (lo >> 16) & 0xff, d, rho);
    let (g1, r) = byte_digit(r, (lo >> 8) & 0xff, d, rho);
    let (g0, _) = byte_digit(r, lo & 0xff, d, rho);
    let low = (g3 << 24) | (g2 << 16) | (g1 << 8) | g0;
    Some(((top as u64) << 32) | low as u64)
}

/// One digit of [`div_floor_bytes`]: `floor((r 2^8 + byte) / d)` and the
/// remainder, for `r < d`, `byte < 2^8`, `rho` from [`recip9`].
#[inline(always)]
const fn byte_digit(r: u32, byte: u32, d: u32, rho: u32) -> (u32, u32) {
    let x = (r << 8) | byte;
    let mut g = r.wrapping_mul(rho) >> 24;
    let mut rem = x.wrapping_sub(g.wrapping_mul(d));
    while rem >= d {
        rem -= d;
        g += 1;
    }
    (g, rem)
}

/// `floor((2^32 - 1) / d)` for `0 < d < 2^24`: the 32-bit reciprocal of
/// [`Divisor`]'s route for chips without a divider, once per triangle and
/// tile. For `d >= 256` four byte digits ([`byte_digit`]) of `2^32 - 1`
/// (about 100 instructions on the Cortex-M0) instead of the library
/// division (about 280 there; the micro:bit's demo frame 0.4 M
/// instructions faster, measured); below, the division.
#[inline(always)]
const fn reciprocal32(d: u32) -> u32 {
    debug_assert!(d > 0 && d < 1 << 24);
    if d < 1 << 8 {
        return u32::MAX / d;
    }
    let rho = recip9(d);
    let (mut q, mut r, mut k) = (0, 0, 0);
    while k < 4 {
        let (g, rem) = byte_digit(r, 0xff, d, rho);
        (q, r, k) = ((q << 8) | g, rem, k + 1);
    }
    q
}

/// `floor(num 2^16 / den)` for `num < den < 2^16`: a weight with 16
/// fraction bits (a quadratic segment's perspective middle). One division
/// where the chip has one (and on a host); on the Cortex-M0 two byte
/// digits ([`div_floor_bytes`]) for `den >= 256` instead of the library
/// division (about 165 instructions).
#[inline(always)]
pub(crate) fn div_shl16(num: u32, den: u32) -> u32 {
    div_shl16_by::<{ HW_DIV32 || !MCU32 }>(num, den)
}

#[inline(always)]
fn div_shl16_by<const DIV32: bool>(num: u32, den: u32) -> u32 {
    debug_assert!(num < den && den < 1 << 16);
    if DIV32 || den < 1 << 8 {
        return (num << 16) / den;
    }
    let rho = recip9(den);
    let (g1, r) = byte_digit(num, 0, den, rho);
    let (g0, _) = byte_digit(r, 0, den, rho);
    (g1 << 8) | g0
}

/// Whether the core multiplies two 32-bit integers into 64 bits in one
/// instruction (`umull`/`smull`: ARMv7-M and up; `mulhu` beside `mul`:
/// RISC-V with `M`; every host); ARMv6-M (the Cortex-M0) has only the low
/// half ([`wide_mul`]), rv32i no multiply at all.
pub(crate) const LONG_MUL: bool = !MCU32 || HW_DIV32;

/// Whether the core counts leading zeros in one instruction (`clz`: every
/// Arm core but ARMv6-M, whose `leading_zeros` is a library call; RISC-V
/// only with `Zbb`, which rv32imac and the ESP32-C3 lack: there LLVM
/// expands it into a dozen or more instructions).
pub(crate) const HW_CLZ: bool = !MCU32
    || cfg!(any(
        all(target_arch = "arm", target_has_atomic = "32"),
        target_feature = "zbb"
    ));

/// Whether the opaque span loop drops its clamps on spans whose values
/// provably stay in range ([`steps_bounded`], [`ends_in`]): where a clamp
/// costs instructions at every pixel — ARMv6-M, the Cortex-M0, has no
/// `usat` and no conditional execution (six or seven instructions a lane,
/// measured), nor has RISC-V, nor a host (x86-64: a compare and a
/// conditional move per bound, four values a pixel) — and in the unit
/// tests, which run both loops. On ARMv7-M and up one saturating
/// instruction clamps a lane, less than the per-span test would cost.
///
/// On the host, measured with callgrind on two of the culling city's
/// 60-frame walks (single pass): 714 -> 519 M instructions with large triangles,
/// 978 -> 797 M with small ones (wall time a frame 490 -> 386 us and
/// 796 -> 704 us); the small-triangle teapot scene, whose spans are a few
/// pixels, 8.6 -> 9.3 M in its triangles (+0.5% of the whole render).
pub(crate) const CLAMP_FREE_SPANS: bool =
    !MCU32 || !cfg!(all(target_arch = "arm", target_has_atomic = "32")) || cfg!(test);

/// `d ^ (d >> 31)`: `|d|` for `d >= 0`, `|d| - 1` below — a bound on a
/// step's size without a negation, OR-ed over a span's channels for
/// [`steps_bounded`].
#[inline(always)]
pub(crate) fn ones_abs(d: i32) -> u32 {
    (d ^ (d >> 31)) as u32
}

/// Whether `n - 1` steps of at most `m + 1` each (`m` from [`ones_abs`])
/// cannot reach `2^31 + 2^24` in all: `n <= 2^12` and
/// `(m >> 12) n < 2^19`, one 32-bit product (`(m + 1)(n - 1) <
/// (2^12 (m >> 12) + 2^12) n < 2^31 + 2^24`).
#[inline(always)]
pub(crate) fn steps_bounded(m: u32, n: u32) -> bool {
    n <= 1 << 12 && (m >> 12) * n < 1 << 19
}

/// Whether every value `v + k d` (`k < n`) of a DDA stepped in wrapping
/// `i32` lies in `0..lim` and equals its exact integer, given
/// [`steps_bounded`] for `|d|` and `n`, `1 <= n` and `lim <= 2^30`: both
/// ends do. The exact last value `T = v + (n - 1) d` lies within
/// `2^31 + 2^24` of `v`, inside `(-2^31 - 2^24, 2^31 + 2^30 + 2^24)`, a
/// range narrower than `2^32` that meets no other copy of `0..lim` modulo
/// 2^32: the wrapped last value is in `0..lim` exactly when `T` is. The
/// values between are then in range too (they lie between the ends), so
/// none wrapped.
#[inline(always)]
pub(crate) fn ends_in(v: i32, d: i32, n: u32, lim: u32) -> bool {
    let last = v.wrapping_add(d.wrapping_mul((n as i32).wrapping_sub(1)));
    (v as u32) < lim && (last as u32) < lim
}

/// `a b`, all 64 bits: one `umull` where the core has it ([`LONG_MUL`]);
/// on the Cortex-M0 four 16x16-bit products ([`wide_mul_pieces`]) instead
/// of the general 64x64-bit library multiply (`__aeabi_lmul`, ~40
/// instructions a call, 55 calls per triangle and tile in the setup:
/// measured).
#[inline(always)]
pub(crate) fn wide_mul(a: u32, b: u32) -> u64 {
    wide_mul_by::<LONG_MUL>(a, b)
}

/// [`wide_mul`] by the long multiply (`LONG`) or by 16-bit pieces (the
/// tests run both routes on the host).
#[inline(always)]
fn wide_mul_by<const LONG: bool>(a: u32, b: u32) -> u64 {
    if LONG {
        a as u64 * b as u64
    } else {
        wide_mul_pieces(a, b)
    }
}

/// [`wide_mul`] from four 16x16-bit products. Out of line on the Cortex-M0:
/// inlined at every product of the setup it overflowed the micro:bit's
/// 256 KB of flash (the workloads' build); a call still costs far less than
/// `__aeabi_lmul`'s.
#[cfg_attr(all(target_arch = "arm", not(target_has_atomic = "32")), inline(never))]
fn wide_mul_pieces(a: u32, b: u32) -> u64 {
    wide_mul_pieces_inline(a, b)
}

/// [`wide_mul_pieces`] where it is made: the one copy in the Cortex-M0's
/// 32-bit reciprocal quotient ([`Divisor`], eight per triangle and tile)
/// saves the call.
#[inline(always)]
fn wide_mul_pieces_inline(a: u32, b: u32) -> u64 {
    let (a0, a1, b0, b1) = (a & 0xffff, a >> 16, b & 0xffff, b >> 16);
    // Each partial product is below 2^32; `mid` below 2^33 (its carry).
    let (mid, carry) = (a1 * b0).overflowing_add(a0 * b1);
    let (lo, c) = (a0 * b0).overflowing_add(mid << 16);
    let hi = a1 * b1 + (mid >> 16) + ((carry as u32) << 16) + c as u32;
    (hi as u64) << 32 | lo as u64
}

/// `x k` modulo 2^64 for a small factor `k < 2^16` (a segment's length, a
/// pixel offset): where the core has no long multiply ([`LONG_MUL`]) two
/// 32x16-bit products and a 32-bit one, about a dozen instructions,
/// instead of `__aeabi_lmul`'s ~37 (measured: 3,300 calls in the quadratic
/// texturing workload).
#[inline(always)]
pub(crate) fn mul_small(x: i64, k: u32) -> i64 {
    mul_small_by::<LONG_MUL>(x, k)
}

#[inline(always)]
fn mul_small_by<const LONG: bool>(x: i64, k: u32) -> i64 {
    debug_assert!(k < 1 << 16);
    if LONG {
        return x.wrapping_mul(k as i64);
    }
    let lo = x as u32;
    // `lo k = (lo mod 2^16) k + (lo >> 16) k 2^16`, each product below 2^32.
    let low = ((lo & 0xffff) * k) as u64 + ((((lo >> 16) * k) as u64) << 16);
    let hi = ((x >> 32) as i32).wrapping_mul(k as i32);
    (low as i64).wrapping_add((hi as i64) << 32)
}

/// `a b` for signed 32-bit factors, exactly ([`wide_mul`]).
#[inline(always)]
pub(crate) fn wide_mul_i(a: i32, b: i32) -> i64 {
    wide_mul_i_by::<LONG_MUL>(a, b)
}

#[inline(always)]
fn wide_mul_i_by<const LONG: bool>(a: i32, b: i32) -> i64 {
    if LONG {
        return a as i64 * b as i64;
    }
    let p = wide_mul_by::<false>(a.unsigned_abs(), b.unsigned_abs()) as i64;
    negated_if(p, (a ^ b) < 0)
}

/// `-p` (modulo 2^64) when `negative`, else `p`: the sign of a product
/// built from magnitudes.
#[inline(always)]
fn negated_if(p: i64, negative: bool) -> i64 {
    if negative {
        p.wrapping_neg()
    } else {
        p
    }
}

/// `g o` modulo 2^64 (`g.wrapping_mul(o)`) for a 32-bit `o`: on the
/// Cortex-M0, no library multiply — for `|o| < 2^15` (a plane's anchor
/// offset, twice per plane and tile: within a small triangle's box) two
/// 32-bit products of `g`'s low word's halves ([`mul_i16`]), otherwise one
/// [`wide_mul`].
#[inline(always)]
pub(crate) fn wrapping_mul_i32(g: i64, o: i32) -> i64 {
    wrapping_mul_i32_by::<LONG_MUL>(g, o)
}

#[inline(always)]
fn wrapping_mul_i32_by<const LONG: bool>(g: i64, o: i32) -> i64 {
    if LONG {
        return g.wrapping_mul(o as i64);
    }
    let hi = ((g >> 32) as i32).wrapping_mul(o);
    if is_i16(o) {
        // g o = hi(g) o 2^32 + lo(g) o, modulo 2^64.
        return ((hi as i64) << 32).wrapping_add(mul_i16((g as u32) >> 16, g as u16, o));
    }
    // g |o| = lo(g) |o| + hi(g) |o| 2^32, modulo 2^64.
    let m = o.unsigned_abs();
    let hi = ((g >> 32) as u32).wrapping_mul(m);
    let p = wide_mul_by::<false>(g as u32, m).wrapping_add((hi as u64) << 32) as i64;
    negated_if(p, o < 0)
}

/// Whether `k` lies in `(-2^15, 2^15)`: one add and one unsigned compare.
#[inline(always)]
fn is_i16(k: i32) -> bool {
    (k as u32).wrapping_add(0x7fff) < 0xffff
}

/// `(h 2^16 + l) k` exactly, for `|h| <= 2^16`, `l < 2^16` and
/// `|k| < 2^15`: two 32-bit products (each below 2^31 in magnitude) and a
/// 64-bit shift and add — on the Cortex-M0 about a third of a call of
/// [`wide_mul_pieces`]' four products.
#[inline(always)]
fn mul_i16(h: u32, l: u16, k: i32) -> i64 {
    (((h as i32).wrapping_mul(k) as i64) << 16) + (l as i32 * k) as i64
}

/// `a k + b l`, exactly. On the Cortex-M0, for `|k|, |l| < 2^15` (a small
/// triangle's edge steps over 16, its gradients' numerators) four 32-bit
/// products ([`mul_i16`]) instead of two 64-bit ones of four 16-bit pieces
/// each.
#[inline(always)]
pub(crate) fn dot2_i16(a: i32, k: i32, b: i32, l: i32) -> i64 {
    dot2_i16_by::<LONG_MUL>(a, k, b, l)
}

#[inline(always)]
fn dot2_i16_by<const LONG: bool>(a: i32, k: i32, b: i32, l: i32) -> i64 {
    if !LONG && is_i16(k) && is_i16(l) {
        // The high halves' products summed in 32 bits (each below 2^30),
        // shifted once; the low halves' each below 2^31.
        let hi = (a >> 16) * k + (b >> 16) * l;
        let lo = |a: i32, k: i32| (a as u16 as i32 * k) as i64;
        return ((hi as i64) << 16) + lo(a, k) + lo(b, l);
    }
    wide_mul_i_by::<LONG>(a, k) + wide_mul_i_by::<LONG>(b, l)
}

/// `a k + b l`, exactly, for `|a|, |b| < 2^30` (a plane's attribute
/// differences: colour lanes below 2^24, depth below 2^30) and any `k`,
/// `l` (its weights' steps). On the Cortex-M0 eight 32-bit products of
/// 16-bit halves, summed before they are widened — one call for both
/// products instead of two [`wide_mul_i`]s, each with its signs' fix-ups
/// (the plane contract's set-up: eight a (tile, triangle) pair).
#[inline(always)]
pub(crate) fn dot2_wide(a: i32, k: i32, b: i32, l: i32) -> i64 {
    dot2_wide_by::<LONG_MUL>(a, k, b, l)
}

#[inline(always)]
fn dot2_wide_by<const LONG: bool>(a: i32, k: i32, b: i32, l: i32) -> i64 {
    debug_assert!(a.unsigned_abs() < 1 << 30 && b.unsigned_abs() < 1 << 30);
    if LONG {
        return a as i64 * k as i64 + b as i64 * l as i64;
    }
    dot2_wide_pieces(a, k, b, l)
}

/// [`dot2_wide`] by 16-bit halves: `x = xh 2^16 + xl` with `xh` signed
/// (`x >> 16`) and `xl` unsigned. With `|ah|, |bh| <= 2^14`: the high
/// halves' products sum below 2^30, `ah kl + bh ll` below 2^31 in
/// magnitude; `al kh` and `bl lh` each fit `i32` but not their sum; the
/// low products each fit `u32`. Out of line on the Cortex-M0 (flash).
#[cfg_attr(all(target_arch = "arm", not(target_has_atomic = "32")), inline(never))]
fn dot2_wide_pieces(a: i32, k: i32, b: i32, l: i32) -> i64 {
    let (ah, al, bh, bl) = (a >> 16, a & 0xffff, b >> 16, b & 0xffff);
    let (kh, kl, lh, ll) = (k >> 16, k & 0xffff, l >> 16, l & 0xffff);
    let hh = ah * kh + bh * lh;
    let m1 = ah * kl + bh * ll;
    let m2 = (al * kh) as i64 + (bl * lh) as i64;
    let lo = (al as u32 * kl as u32) as u64 + (bl as u32 * ll as u32) as u64;
    ((hh as i64) << 32) + ((m1 as i64 + m2) << 16) + lo as i64
}

/// `floor(x / 255)` for any `u32`, without a division: the colour scale's
/// `/ 255` is a library call of ~90 instructions on the Cortex-M0 (nine
/// per triangle and tile, measured); hosts and ARMv7-M keep the compiler's
/// multiply by the reciprocal. With `q0 = floor(x / 256)`,
/// `q = q0 + floor(q0 / 2^8) + floor(q0 / 2^16) + floor(q0 / 2^24)`
/// stays below the series `x / 255 = Σ x / 256^k` and loses less than 5 to
/// its floors and tail, so `r = x - 255 q < 1275`, and `floor(r / 255) =
/// (r + 1) 257 / 2^16` for every `r < 2^16` (both checked in the tests).
#[inline(always)]
pub(crate) const fn div255(x: u32) -> u32 {
    div255_by::<LONG_MUL>(x)
}

#[inline(always)]
const fn div255_by<const LONG: bool>(x: u32) -> u32 {
    if LONG {
        return x / 255;
    }
    let q0 = x >> 8;
    let q = q0 + (q0 >> 8) + (q0 >> 16) + (q0 >> 24);
    let r = x - 255 * q;
    q + (((r + 1) * 257) >> 16)
}

/// The high 64 bits of `a b`, from four 32x32-bit products ([`wide_mul`]):
/// the same code as a `u128` product on the Cortex-M4 (four `umull`s;
/// measured equal); on the Cortex-M0, where `u128` becomes a general
/// 128-bit multiply, four inline 16-bit-piece products.
#[inline(always)]
fn mul_high(a: u64, b: u64) -> u64 {
    let (a0, a1) = (a as u32, (a >> 32) as u32);
    let (b0, b1) = (b as u32, (b >> 32) as u32);
    let (p01, p10) = (wide_mul(a0, b1), wide_mul(a1, b0));
    let mid = (wide_mul(a0, b0) >> 32) + (p01 & 0xffff_ffff) + (p10 & 0xffff_ffff);
    wide_mul(a1, b1) + (p01 >> 32) + (p10 >> 32) + (mid >> 32)
}

/// Many divisions by one positive divisor `d` (a triangle's doubled area):
/// exactly [`div_round`]'s result without a 64-bit division per quotient (a
/// long library call on the Cortex-M4 and M0).
///
/// For `d < 2^24` (every triangle under 2^15 square pixels) the quotients
/// go through 32-bit divisions (`narrow`): a dividend below 2^32 takes one,
/// a larger one [`div_floor_u24`]'s five. On a chip that divides in
/// hardware ([`HW_DIV32`]) each is a `udiv`, and a dividend that fits `i32`
/// — most of a small triangle's attribute steps — goes straight to it: no
/// reciprocal is made (its 64-bit division cost about 75 instructions per
/// triangle on the Cortex-M4, each reciprocal quotient about 35:
/// measured). On the Cortex-M0, whose 32-bit division is a library call of
/// about 100 instructions and 64-bit one several hundred, each is the
/// 32-bit reciprocal `floor((2^32 - 1) / d)`'s estimate and at most one
/// correction: one library division per triangle. Otherwise the 64-bit
/// reciprocal `floor((2^64 - 1) / d)` is computed once, and each quotient
/// is a 64x64-bit high product plus at most one correction.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Divisor {
    d: u64,
    /// The 64-bit reciprocal; when `narrow`, the 32-bit one on the
    /// reciprocal route, 0 on the division instruction's.
    r: u64,
    /// Quotients by 32-bit divisions (`d < 2^24`).
    narrow: bool,
    /// `d` when `narrow`: a divisor the compiler knows is not zero (no
    /// check before each `udiv`).
    d32: NonZeroU32,
}

impl Divisor {
    /// Whether the division instruction's route is compiled: where the
    /// chip has one, and in the tests (which run every route on the host).
    const DIV32: bool = HW_DIV32 || cfg!(test);
    /// Whether the 32-bit reciprocal's route is compiled: the Cortex-M0
    /// (no divider), and the tests.
    const RECIP32: bool = (MCU32 && !HW_DIV32) || cfg!(test);

    /// For `d > 0`.
    #[inline]
    pub(crate) const fn new(d: i64) -> Self {
        Self::new_by(d, HW_DIV32 || Self::RECIP32, !HW_DIV32)
    }

    /// [`Self::new`] with the 32-bit routes for `d < 2^24` (`narrow`), by
    /// the reciprocal (`recip32`) or the division instruction: the tests
    /// run every route on the host.
    #[inline]
    const fn new_by(d: i64, narrow: bool, recip32: bool) -> Self {
        let d = d as u64;
        let narrow = narrow && d < 1 << 24;
        Divisor {
            d,
            r: match (narrow, recip32) {
                (false, _) => u64::MAX / d,
                (true, true) => reciprocal32(d as u32) as u64,
                (true, false) => 0,
            },
            narrow,
            d32: match NonZeroU32::new(d as u32) {
                Some(d) if narrow => d,
                _ => NonZeroU32::MIN,
            },
        }
    }

    /// `x / d` for `x < 2^32` when `narrow`: the instruction, or the
    /// reciprocal's estimate `floor(x r / 2^32)`, which with
    /// `r >= (2^32 - d) / d` is above `x / d - 1` (so at most one
    /// correction; the remainder is below `2 d < 2^25`).
    #[inline(always)]
    fn quot32(&self, x: u32) -> u32 {
        if Self::DIV32 && (!Self::RECIP32 || self.r == 0) {
            return x / self.d32;
        }
        let d = self.d as u32;
        let q = (wide_mul_pieces_inline(x, self.r as u32) >> 32) as u32;
        if x.wrapping_sub(q.wrapping_mul(d)) >= d {
            q + 1
        } else {
            q
        }
    }

    /// `floor(n / d)` when `narrow`: a dividend below 2^32 in one 32-bit
    /// quotient on the reciprocal's route, else five ([`div_floor_u24`]).
    /// One copy on the Cortex-M0: inlined at every use (every attribute
    /// plane, area sampling, texturing) it took 6.5 KB more and filled the
    /// workloads' build to the last byte of its 256 KB (measured with
    /// `llvm-size`); a call costs little beside a quotient there.
    #[cfg_attr(all(target_arch = "arm", not(target_has_atomic = "32")), inline(never))]
    #[cfg_attr(
        not(all(target_arch = "arm", not(target_has_atomic = "32"))),
        inline(always)
    )]
    fn floor_narrow(&self, n: u64) -> u64 {
        if Self::RECIP32 {
            if let Ok(x) = u32::try_from(n) {
                return self.quot32(x) as u64;
            }
        }
        div_floor_u24_with(n, self.d as u32, |x| self.quot32(x))
    }

    /// `floor(n / d)` for `n < 2^63`: with `r >= (2^64 - d) / d` the high
    /// product is at least `n / d - n / 2^64 > n / d - 1/2`, so one
    /// correction step suffices.
    #[inline(always)]
    fn floor_u(&self, n: u64) -> u64 {
        if (Self::DIV32 || Self::RECIP32) && self.narrow {
            return self.floor_narrow(n);
        }
        let q = mul_high(n, self.r);
        // The remainder `n - q d` lies in `[0, 2d)`: for `d < 2^31` (every
        // small triangle) it is exact in 32-bit arithmetic, one multiply.
        let carry = if self.d < 1 << 31 {
            (n as u32).wrapping_sub((q as u32).wrapping_mul(self.d as u32)) >= self.d as u32
        } else {
            n - q * self.d >= self.d
        };
        if carry {
            q + 1
        } else {
            q
        }
    }

    /// [`Self::round`] for `|n| < 2^30` and `d < 2^24`, in 32 bits: one
    /// division instruction (or the Cortex-M0's reciprocal quotient) and
    /// no 64-bit arithmetic. The same integer as [`Self::round`].
    #[inline(always)]
    pub(crate) fn round_small(&self, n: i32) -> i32 {
        debug_assert!(n.unsigned_abs() < 1 << 30 && self.d < 1 << 24);
        let num = n + (self.d as i32 >> 1);
        // floor(m / d) = !floor(!m / d) for m < 0 (!m = -m - 1 >= 0).
        let s = num >> 31;
        let x = (num ^ s) as u32;
        let q = if Self::DIV32 || Self::RECIP32 {
            // `d < 2^24`: the divisor is narrow on these routes.
            self.quot32(x)
        } else {
            x / self.d as u32
        };
        q as i32 ^ s
    }

    /// `n / d` rounded to nearest, ties up: [`div_round`]`(n, d)` for
    /// `|n| < 2^62`.
    #[inline(always)]
    pub(crate) fn round(&self, n: i64) -> i64 {
        let num = n + (self.d / 2) as i64;
        let by_div = Self::DIV32 && (!Self::RECIP32 || self.r == 0);
        if by_div && self.narrow && num as i32 as i64 == num {
            // floor(m / d) = !floor(!m / d) for m < 0 (!m = -m - 1 >= 0):
            // one unsigned division between two sign flips.
            let m = num as i32;
            let s = m >> 31;
            return (((m ^ s) as u32 / self.d32) as i32 ^ s) as i64;
        }
        if num >= 0 {
            self.floor_u(num as u64) as i64
        } else {
            -(self.floor_u(num.unsigned_abs() + self.d - 1) as i64)
        }
    }
}

/// `k (k - 1) / 2` modulo 2^32 — what `k` second-order forward-difference
/// steps add of the second difference — in one 32-bit product: the even
/// factor halved first, `k >> 1` times `k - 1` (`k` even) or `k` (`k` odd),
/// which is `(k - 1) | 1` either way. The 64-bit product and halving it
/// replaces took twelve instructions on the M4 (once per fast-Phong row and
/// per textured segment entry); the M0 has no 64-bit multiply.
#[inline(always)]
pub(crate) fn pairs(k: i32) -> i32 {
    (k >> 1).wrapping_mul(k.wrapping_sub(1) | 1)
}

/// A xorshift64 generator from `seed` (non-zero): the unit tests'
/// pseudo-random inputs, the same on every run.
#[cfg(test)]
pub(crate) fn xorshift(mut seed: u64) -> impl FnMut() -> u64 {
    move || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        seed
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Whenever [`steps_bounded`] and [`ends_in`] pass, every value of the
    /// wrapping DDA is the exact one and in range (checked in `i64`), at
    /// the extremes of every argument; and they pass often enough to be
    /// worth their test.
    #[test]
    fn in_range_spans_never_leave_their_range() {
        let mut next = xorshift(0x005e_ed0f_5a75);
        let lims = [
            1u32,
            2,
            1 << 16,
            (32 << 16) - (63 << 10),
            1 << 21,
            1 << 24,
            1 << 30,
        ];
        let mut passed = 0;
        for k in 0..200_000u32 {
            let lim = lims[k as usize % lims.len()];
            let n = match next() % 4 {
                0 => 1 + (next() % 4) as u32,
                1 => 1 + (next() % 64) as u32,
                2 => (1 << 12) - (next() % 2) as u32,
                _ => 1 + (next() % (1 << 13)) as u32,
            };
            let v = match next() % 4 {
                0 => (next() % lim as u64) as i32,
                1 => lim as i32 - 1 - (next() % 3) as i32,
                2 => (next() % 3) as i32 - 1,
                _ => next() as i32,
            };
            let d = match next() % 5 {
                0 => (next() % 64) as i32 - 32,
                1 => (next() as i32) >> (next() % 32),
                2 => ((lim as i64 - 1 - 2 * v as i64) / n.max(2) as i64 - 1) as i32,
                3 => i32::MIN + (next() % 2) as i32,
                _ => (next() as i32) >> 8,
            };
            if !(steps_bounded(ones_abs(d), n) && ends_in(v, d, n, lim)) {
                continue;
            }
            passed += 1;
            let mut w = v;
            for j in 0..n as i64 {
                let exact = v as i64 + j * d as i64;
                assert!(
                    (0..lim as i64).contains(&exact),
                    "{v} {d} {n} {lim}: {exact}"
                );
                assert_eq!(w as i64, exact);
                w = w.wrapping_add(d);
            }
        }
        assert!(passed > 20_000, "{passed}");
    }

    #[test]
    fn mul_small_is_the_product_modulo_2_64_on_both_routes() {
        let xs = [
            0,
            1,
            -1,
            0xffff,
            0x1_0000,
            0xffff_ffff,
            0x1_0000_0000,
            -0x1_0000_0000,
            0x7fff_ffff_ffff,
            i64::MAX,
            i64::MIN,
            i64::MIN + 1,
            0x1234_5678_9abc_def0,
            -0x0fed_cba9_8765_4321,
        ];
        for x in xs {
            for k in [0, 1, 2, 31, 32, 0x7fff, 0xffff] {
                let exact = x.wrapping_mul(k as i64);
                assert_eq!(mul_small_by::<false>(x, k), exact, "{x} {k}");
                assert_eq!(mul_small_by::<true>(x, k), exact, "{x} {k}");
            }
        }
    }

    #[test]
    fn pairs_is_the_halved_product_modulo_2_32() {
        let edges = [
            i32::MIN,
            i32::MIN + 1,
            i32::MIN + 2,
            -65_537,
            65_536,
            92_682,
            i32::MAX,
        ];
        for k in (-70_000..70_000).chain(edges) {
            let exact = (k as i64 * (k as i64 - 1) / 2) as i32;
            assert_eq!(pairs(k), exact, "{k}");
        }
    }
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

    #[test]
    fn narrow_division_is_exact() {
        let mut x = 0x9e37_79b9_7f4a_7c15u64;
        for i in 0..200_000u64 {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            let d = match i % 4 {
                0 => (x >> 40) as u32 | 1,
                1 => (1 << 24) - 1 - (i as u32 & 0xff),
                2 => 1 + (i as u32 & 0xff),
                _ => ((x >> 8) as u32 & 0xff_ffff).max(1),
            };
            let n = x >> (x & 15);
            assert_eq!(div_floor_u24(n, d), n / d as u64, "{n} / {d}");
            let (n, d) = ((n >> 2) as i64, d as i64);
            let q = div_floor_u24((n + d / 2) as u64, d as u32) as i64;
            assert_eq!(q, div_round(n, d));
            assert_eq!(div_round_pair(n, -n, d), (q, div_round(-n, d)));
            for (a, b) in [(n, -n), (n, n >> 20), (n >> 30, n >> 10)] {
                let want = (div_round(a, d), div_round(b, d));
                assert_eq!(
                    div_round_pair_by::<false, false>(a, b, d),
                    want,
                    "{a} {b} / {d}"
                );
                assert_eq!(
                    div_round_pair_by::<false, true>(a, b, d),
                    want,
                    "{a} {b} / {d}"
                );
            }
            assert_eq!(Divisor::new(d).round(n), q);
            for recip32 in [false, true] {
                let by = Divisor::new_by(d, true, recip32);
                assert_eq!(by.round(n), q, "{n} / {d} {by:?}");
                assert_eq!(by.round(-n), div_round(-n, d), "{} / {d} {by:?}", -n);
                let small = n >> 30;
                assert_eq!(by.round(small), div_round(small, d), "{small} / {d} {by:?}");
            }
        }
        assert_eq!(div_floor_u24(u64::MAX, 1), u64::MAX);
        assert_eq!(
            div_floor_u24(u64::MAX, (1 << 24) - 1),
            u64::MAX / ((1 << 24) - 1)
        );
    }

    /// The Cortex-M0's byte digits: every divisor width's bound from
    /// [`recip9`] and every quotient size up to its limit, with the worst
    /// remainders (`d - 1`) and the edges.
    #[test]
    fn byte_digits_are_exact() {
        let mut x = xorshift(0x5eed_b17e_d161_7a1b);
        for i in 0..300_000u32 {
            let r = x();
            let d = match i % 3 {
                0 => (256 + (r as u32 % ((1 << 24) - 256))).max(256),
                1 => (1 << (8 + i % 16)) + (r >> 40) as u32 % (1 << (8 + i % 16)),
                _ => ((1 << 24) - 1 - (r as u32 & 0xfff)).max(256),
            }
            .min((1 << 24) - 1);
            let rho = recip9(d);
            assert!((rho as u64) * d as u64 <= 1 << 32, "{d} {rho}");
            assert!((rho as u64 + 1) * 257 * d as u64 >= 256 << 32, "{d} {rho}");
            let q = x() >> (24 + i % 40);
            let n = q * d as u64 + [0, d as u64 - 1, x() % d as u64][i as usize % 3];
            if n >> 40 >= d as u64 {
                assert_eq!(div_floor_bytes(n, d, rho), None);
            } else {
                assert_eq!(div_floor_bytes(n, d, rho), Some(n / d as u64), "{n} / {d}");
            }
        }
        for d in (1..1 << 12).chain((0..100_000).map(|_| 1 + (x() % ((1 << 24) - 1)) as u32)) {
            assert_eq!(reciprocal32(d), u32::MAX / d, "{d}");
        }
        for d in [256u32, 257, 511, 512, 65535, 65536, (1 << 24) - 1] {
            assert_eq!(reciprocal32(d), u32::MAX / d, "{d}");
            let top = ((d as u64) << 40) - 1;
            assert_eq!(div_floor_bytes(top, d, recip9(d)), Some(top / d as u64));
            assert_eq!(div_floor_bytes(top + 1, d, recip9(d)), None);
            assert_eq!(div_floor_bytes(0, d, recip9(d)), Some(0));
        }
    }

    #[test]
    fn the_weight_division_is_exact_on_both_routes() {
        let mut x = xorshift(0x3c6e_f372_fe94_f82b);
        for i in 0..300_000u32 {
            let r = x();
            let den = match i % 3 {
                0 => 1 + (r as u32 % 0xffff),
                1 => 0xffff - (r as u32 & 0xff),
                _ => (1 << (i % 16)) + (r as u32 % (1 << (i % 16))),
            }
            .clamp(1, 0xffff);
            let num = [0, den - 1, (r >> 32) as u32 % den][i as usize % 3];
            let want = ((num as u64) << 16) / den as u64;
            assert_eq!(
                div_shl16_by::<false>(num, den) as u64,
                want,
                "{num} / {den}"
            );
            assert_eq!(div_shl16_by::<true>(num, den) as u64, want, "{num} / {den}");
        }
    }

    #[test]
    fn the_m0_routes_are_exact() {
        let mut x = 0x2545_f491_4f6c_dd1du64;
        let edges = [
            0,
            1,
            2,
            0xffff,
            0x1_0000,
            0x7fff_ffff,
            0x8000_0000,
            u32::MAX,
        ];
        for &a in &edges {
            for &b in &edges {
                assert_eq!(wide_mul_by::<false>(a, b), a as u64 * b as u64);
                let (a, b) = (a as i32, b as i32);
                assert_eq!(wide_mul_i_by::<false>(a, b), a as i64 * b as i64);
            }
        }
        let floor = |n: i32, d: i32| (n as f64 / d as f64).floor() as i32;
        for n in [
            0,
            1,
            -1,
            7,
            8,
            -8,
            -9,
            63,
            64,
            -64,
            -65,
            i32::MAX,
            i32::MIN,
            1 << 30,
            -(1 << 30),
        ] {
            for d in [1, 2, 3, 7, 8, 64, 1 << 24, (1 << 28) - 1, 1 << 28, i32::MAX] {
                assert_eq!(div_floor_i32_by::<false>(n, d), floor(n, d), "{n} / {d}");
                assert_eq!(div_floor_i32_by::<true>(n, d), floor(n, d), "{n} / {d}");
            }
        }
        for _ in 0..1_000_000 {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            // Quotients of every size, small ones most often.
            let d = ((x >> 40) as i32 & 0x7fff_ffff) >> ((x >> 32) as u32 % 31);
            let n = (x as i32) >> ((x >> 8) as u32 % 32);
            let d = d.max(1);
            assert_eq!(div_floor_i32_by::<false>(n, d), floor(n, d), "{n} / {d}");
            let (a, b) = (x as u32, (x >> 32) as u32);
            assert_eq!(wide_mul_by::<false>(a, b), a as u64 * b as u64);
            let (a, b) = (a as i32, b as i32);
            assert_eq!(wide_mul_i_by::<false>(a, b), a as i64 * b as i64);
        }
        for _ in 0..1_000_000 {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            let o = (x.rotate_left(17) as i32) >> (x % 31);
            let g = x as i64 >> (x >> 58);
            assert_eq!(wrapping_mul_i32_by::<false>(g, o), g.wrapping_mul(o as i64));
        }
        for &g in &[0, 1, -1, i64::MAX, i64::MIN, 1 << 32, -(1 << 32)] {
            for &o in &[0, 1, -1, i32::MAX, i32::MIN] {
                assert_eq!(wrapping_mul_i32_by::<false>(g, o), g.wrapping_mul(o as i64));
            }
        }
        // The remainder's bound and the small division, exhaustively.
        for r in 0..1u32 << 16 {
            assert_eq!(((r + 1) * 257) >> 16, r / 255, "{r}");
        }
        let tail = u32::MAX - 100_000..=u32::MAX;
        for x in (0..1u32 << 24)
            .chain((0..=u32::MAX).step_by(251))
            .chain(tail)
        {
            let q0 = x >> 8;
            let q = q0 + (q0 >> 8) + (q0 >> 16) + (q0 >> 24);
            assert!(x - 255 * q < 1275, "{x}");
            assert_eq!(div255_by::<false>(x), x / 255, "{x}");
        }
    }

    #[test]
    fn mul_high_is_the_high_half() {
        let mut x = 0x2545_f491_4f6c_dd1du64;
        for _ in 0..100_000 {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            let y = x.rotate_left(29) ^ 0x9e37_79b9_7f4a_7c15;
            assert_eq!(mul_high(x, y), ((x as u128 * y as u128) >> 64) as u64);
        }
        assert_eq!(mul_high(u64::MAX, u64::MAX), u64::MAX - 1);
    }

    #[test]
    fn sixteen_bit_products_are_exact() {
        let mut x = 0x2545_f491_4f6c_dd1du64;
        let edges = [
            0,
            1,
            -1,
            0x7fff,
            -0x7fff,
            0x8000,
            -0x8000,
            i32::MAX,
            i32::MIN,
        ];
        for i in 0..200_000u64 {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            let pick = |s: u32| {
                if i % 5 == 0 {
                    edges[(x >> s) as usize % edges.len()]
                } else {
                    (x >> s) as i32 >> ((x >> (s + 27)) as u32 & 31)
                }
            };
            let (a, k, b, l) = (pick(0), pick(8), pick(16), pick(24));
            let exact = a as i128 * k as i128 + b as i128 * l as i128;
            if let Ok(exact) = i64::try_from(exact) {
                assert_eq!(dot2_i16_by::<false>(a, k, b, l), exact, "{a} {k} {b} {l}");
                assert_eq!(dot2_i16_by::<true>(a, k, b, l), exact, "{a} {k} {b} {l}");
            }
            let m30 = |a: i32| (a >> 1).clamp(1 - (1 << 30), (1 << 30) - 1);
            let (a30, b30) = (m30(a), m30(b));
            let exact = a30 as i64 * k as i64 + b30 as i64 * l as i64;
            assert_eq!(
                dot2_wide_by::<false>(a30, k, b30, l),
                exact,
                "{a30} {k} {b30} {l}"
            );
            assert_eq!(
                dot2_wide_by::<true>(a30, k, b30, l),
                exact,
                "{a30} {k} {b30} {l}"
            );
            let g = (x as i64).rotate_left(k as u32 & 63) >> (b as u32 & 63);
            assert_eq!(
                wrapping_mul_i32_by::<false>(g, k),
                g.wrapping_mul(k as i64),
                "{g} {k}"
            );
            assert_eq!(
                wrapping_mul_i32_by::<true>(g, k),
                g.wrapping_mul(k as i64),
                "{g} {k}"
            );
        }
    }

    #[test]
    fn round_small_is_round_on_every_narrow_route() {
        let mut next = xorshift(0x2545_f491_4f6c_dd1d);
        let check = |d: i64, n: i32| {
            let want = div_round(n as i64, d);
            assert_eq!(Divisor::new(d).round_small(n) as i64, want, "{n} / {d}");
            for recip32 in [false, true] {
                let by = Divisor::new_by(d, true, recip32);
                assert_eq!(by.round_small(n) as i64, want, "{n} / {d} {by:?}");
            }
        };
        for _ in 0..100_000 {
            let d = (next() >> (40 + next() % 24)).max(1) as i64;
            let n = (next() >> (34 + next() % 30)) as i32;
            check(d, if next() & 1 == 0 { n } else { -n });
        }
        for d in [1i64, 2, 3, 31, 32, 961, (1 << 24) - 1] {
            for n in [
                0,
                1,
                -1,
                (1 << 30) - 1,
                -(1 << 30) + 1,
                d as i32 / 2,
                -(d as i32 / 2),
            ] {
                check(d, n);
            }
        }
    }

    #[test]
    fn divisor_rounds_like_div_round() {
        let mut next = xorshift(0x9e37_79b9_7f4a_7c15);
        for _ in 0..200_000 {
            let d = (next() >> (1 + next() % 63)).max(1) as i64;
            let n = (next() >> (2 + next() % 62)) as i64 * if next() & 1 == 0 { 1 } else { -1 };
            assert_eq!(Divisor::new(d).round(n), div_round(n, d), "{n} / {d}");
            for (narrow, recip32) in [(true, false), (true, true), (false, false)] {
                let by = Divisor::new_by(d, narrow, recip32);
                assert_eq!(by.round(n), div_round(n, d), "{n} / {d} {by:?}");
            }
        }
        for d in [1i64, 2, 3, 7, 255, 1 << 29, (1 << 41) - 1] {
            for n in [
                0i64,
                1,
                -1,
                d / 2,
                -(d / 2),
                d,
                -d,
                (1 << 62) - 1 - d,
                -(1 << 62) + d,
            ] {
                assert_eq!(Divisor::new(d).round(n), div_round(n, d), "{n} / {d}");
                for (narrow, recip32) in [(true, false), (true, true), (false, false)] {
                    let by = Divisor::new_by(d, narrow, recip32);
                    assert_eq!(by.round(n), div_round(n, d), "{n} / {d} {by:?}");
                }
            }
        }
    }
}
