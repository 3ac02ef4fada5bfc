//! The geometry stage's two numeric back ends, chosen by type: [`f32`] for
//! parts with an FPU (Cortex-M4F, M7) and [`Fx`] (`I16F16` from the `fixed`
//! crate, saturating) for parts without one (Cortex-M0/M0+).
//!
//! Both are **bit-exact across targets**:
//!
//! - `Fx` is integer arithmetic: the same bits on every machine.
//! - `f32` uses only `+ - * /` and conversions, which IEEE 754 rounds
//!   correctly on x86-64 (SSE), the Cortex-M4F's FPU and the M0's soft
//!   float alike. No fused multiply-add is ever formed (Rust does not
//!   contract `a * b + c`), no `libm` transcendental is called (their last
//!   bit differs between libraries), and the M4F runs with flush-to-zero and
//!   default-NaN off (the reset state `cortex-m-rt` keeps). Sine and cosine
//!   come from integers ([`Angle::sin_cos`]); the inverse square root is
//!   `micromath`'s bit-level estimate refined by Newton steps made of the
//!   same four operations. The firmware CRC tests check this claim on both
//!   chips.
//!
//! Overflow: `f32` overflows to infinity; `Fx` saturates and treats its two
//! extreme values as "not finite", so one check ([`Real::is_finite`])
//! catches both, and the geometry stage turns it into an error naming the
//! vertex.

use core::fmt::Debug;
use core::ops::{Add, Mul, Neg, Sub};
use fixed::types::I16F16;

mod sealed {
    pub trait Sealed {}
    impl Sealed for f32 {}
    impl Sealed for super::Fx {}
}

/// A scalar the geometry stage computes in: [`f32`] or [`Fx`].
///
/// Sealed: the stage's exactness claims are made for these two only.
///
/// ```
/// use tilerast::geometry::{Fx, Real};
/// fn half<S: Real>(v: S) -> S { v * S::HALF }
/// assert_eq!(half(3.0f32), 1.5);
/// assert_eq!(half(Fx::from_i32(3)).to_fixed(1), Some(3)); // 1.5 = 3 halves
/// ```
pub trait Real:
    Copy
    + Debug
    + Default
    + PartialOrd
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Neg<Output = Self>
    + sealed::Sealed
{
    /// 0.
    const ZERO: Self;
    /// 1.
    const ONE: Self;
    /// 0.5.
    const HALF: Self;
    /// The back end's name, for reports.
    const NAME: &'static str;
    /// An integer (saturating for `Fx` beyond ±32767).
    fn from_i32(v: i32) -> Self;
    /// `bits / 2^frac`, rounded to the nearest representable value (ties
    /// away from zero for `Fx`, to even for `f32`), `frac <= 62`.
    fn from_q(bits: i64, frac: u32) -> Self;
    /// `self / d`; division by zero gives a non-finite value.
    fn div(self, d: Self) -> Self;
    /// `1 / sqrt(self)` for `self > 0`; non-finite otherwise.
    fn inv_sqrt(self) -> Self;
    /// `false` for NaN and infinities (`f32`), and for the saturated
    /// extremes (`Fx`).
    fn is_finite(self) -> bool;
    /// `round(self * 2^frac)` (halves rounded up), `None` when not finite or
    /// beyond `i32`.
    fn to_fixed(self, frac: u32) -> Option<i32>;
    /// `self * 2^frac` rounded to an integer when it lies below 2^22 in
    /// magnitude (a projected vertex: sub-pixels inside the guard band, a
    /// 16-bit depth), else `None`: `f32` rounds halves to even with one
    /// addition (exact there: adding `1.5 · 2^23` puts the sum where the
    /// spacing of `f32` values is 1, and its exponent says whether it
    /// did), a third of [`Self::to_fixed`]'s instructions on the
    /// Cortex-M4F; `Fx` is [`Self::to_fixed`].
    ///
    /// ```
    /// use tilerast::geometry::{Fx, Real};
    /// assert_eq!(2.3f32.round_small(4), Some(37)); // 36.8
    /// assert_eq!((-2.3f32).round_small(4), Some(-37));
    /// assert_eq!(2.5f32.round_small(0), Some(2)); // a half, to even
    /// assert_eq!(1e7f32.round_small(0), None);
    /// assert_eq!(f32::NAN.round_small(0), None);
    /// assert_eq!(Fx::from_q(23, 1).round_small(0), Some(12)); // 11.5, half up
    /// ```
    fn round_small(self, frac: u32) -> Option<i32> {
        self.to_fixed(frac)
    }
    /// `row · (q, 1)` for a Q15 position `q` (`q / 2^15` in model units, or
    /// `q` itself with [`Self::FOLD_Q15`]): one coordinate of a vertex's
    /// clip-space position, as [`Mat4::transform`](super::Mat4) computes
    /// it. `bounded` says the caller checked that no partial result can
    /// overflow or saturate (the row's absolute sum is small); `Fx` then
    /// multiplies the position's 16 bits in plain 32-bit integer
    /// arithmetic, the same numbers without `fixed`'s saturating products
    /// (on the Cortex-M0, three quarters of the transform's cost).
    #[inline]
    fn affine_q15(row: &[Self; 4], q: [i16; 3], bounded: bool) -> Self {
        let _ = bounded;
        let c = Self::from_q15;
        row[0] * c(q[0]) + row[1] * c(q[1]) + row[2] * c(q[2]) + row[3]
    }
    /// A Q15 position component as [`Self::affine_q15`] feeds it to a
    /// matrix row: the integer itself when the back end folds the scale
    /// into the matrix ([`Self::FOLD_Q15`]), else the fraction `v / 2^15`.
    ///
    /// ```
    /// use tilerast::geometry::{Fx, Real};
    /// assert_eq!(f32::from_q15(-3), -3.0);
    /// assert_eq!(Fx::from_q15(1 << 14), Fx::HALF);
    /// ```
    #[inline(always)]
    fn from_q15(v: i16) -> Self {
        if Self::FOLD_Q15 {
            Self::from_i32(v as i32)
        } else {
            Self::from_q(v as i64, 15)
        }
    }
    /// Whether a mesh's positions enter [`Mat4::transform`](super::Mat4)
    /// as integers, the `2^-15` of their Q15 scale folded into the matrix
    /// ([`super::Scene::draw`]): for `f32`, whose scaling by a power of two
    /// is exact, it saves three multiplications a vertex; `Fx` would lose
    /// the matrix's low bits, so it keeps the scale per position.
    const FOLD_Q15: bool = false;
    /// The larger of two values.
    fn max(self, o: Self) -> Self {
        if o > self {
            o
        } else {
            self
        }
    }
    /// The smaller of two values.
    fn min(self, o: Self) -> Self {
        if o < self {
            o
        } else {
            self
        }
    }
}

impl Real for f32 {
    const ZERO: Self = 0.0;
    const ONE: Self = 1.0;
    const HALF: Self = 0.5;
    const NAME: &'static str = "f32";
    fn from_i32(v: i32) -> Self {
        v as f32
    }
    fn from_q(bits: i64, frac: u32) -> Self {
        // One rounding (the integer to float conversion), then an exact
        // scaling by a power of two.
        bits as f32 * pow2_neg(frac)
    }
    fn div(self, d: Self) -> Self {
        self / d
    }
    fn inv_sqrt(self) -> Self {
        if !above(self, 0.0) || !Real::is_finite(self) {
            return f32::NAN;
        }
        // micromath's estimate (within ~5%), then three Newton steps
        // y <- y (1.5 - x/2 y^2): the error squares each step (5% -> 4e-3
        // -> 2e-5 -> f32 rounding).
        let mut y = micromath::F32Ext::invsqrt(self);
        let h = self * 0.5;
        for _ in 0..3 {
            y = y * (1.5 - h * y * y);
        }
        y
    }
    fn is_finite(self) -> bool {
        self.is_finite()
    }
    const FOLD_Q15: bool = true;
    #[inline]
    fn round_small(self, frac: u32) -> Option<i32> {
        const MAGIC: f32 = 12_582_912.0; // 1.5 · 2^23
        let t = (self * (1u64 << frac) as f32 + MAGIC).to_bits();
        // In [2^23, 2^24): exponent 127 + 23, sign clear.
        (t >> 23 == 150).then(|| (t as i32).wrapping_sub(MAGIC.to_bits() as i32))
    }
    fn to_fixed(self, frac: u32) -> Option<i32> {
        let t = self * (1u64 << frac) as f32 + 0.5;
        // `as` truncates towards zero (and saturates); floor by hand.
        if !(t > -2_147_483_648.0 && t < 2_147_483_648.0) {
            return None;
        }
        let i = t as i32;
        Some(if (i as f32) > t { i - 1 } else { i })
    }
}

/// `2^-frac` as an `f32` (exact for `frac <= 126`).
fn pow2_neg(frac: u32) -> f32 {
    f32::from_bits((127 - frac.min(126)) << 23)
}

/// The fixed-point back end: `I16F16` (16 integer bits with sign, 16
/// fraction bits: range `[-32768, 32768)`, step `2^-16`), with saturating
/// arithmetic. Its extreme values stand for overflow ("not finite").
///
/// Domain of the geometry stage in `Fx`: every clip-space coordinate below
/// 32768 in magnitude, so keep the far plane within a few hundred units and
/// models near the unit cube (the mesh's own scale is folded into the
/// transform, and positions enter as exact `Q15` fractions).
///
/// ```
/// use tilerast::geometry::{Fx, Real};
/// let big = Fx::from_i32(30000);
/// assert!(!(big + big).is_finite()); // saturated: overflow, not a wrap
/// assert_eq!(Fx::from_i32(3).div(Fx::from_i32(4)).to_fixed(2), Some(3));
/// ```
#[derive(Debug, Clone, Copy, Default, PartialEq, PartialOrd)]
pub struct Fx(pub I16F16);

impl Add for Fx {
    type Output = Fx;
    fn add(self, o: Fx) -> Fx {
        Fx(self.0.saturating_add(o.0))
    }
}
impl Sub for Fx {
    type Output = Fx;
    fn sub(self, o: Fx) -> Fx {
        Fx(self.0.saturating_sub(o.0))
    }
}
impl Mul for Fx {
    type Output = Fx;
    #[inline]
    fn mul(self, o: Fx) -> Fx {
        if crate::numeric::LONG_MUL {
            Fx(self.0.saturating_mul(o.0))
        } else {
            Fx(I16F16::from_bits(mul_q16(self.0.to_bits(), o.0.to_bits())))
        }
    }
}

/// `I16F16::saturating_div` on the bits for a dividend in `[0, 1]` and a
/// positive divisor — the projection's `1 / w` — by one 32-bit division
/// instead of `fixed`'s 64-bit one (a library call on every chip here; on
/// the Cortex-M0 about 300 instructions a vertex, measured); `None`
/// elsewhere. `(a 2^16) / b` truncated: for `a < 2^16` the dividend fits
/// 32 bits; for `a = 2^16`, `2^32 / b` is `(2^32 - 1) / b`, one more when
/// `b` divides `2^32`.
#[inline]
fn div_q16_positive(a: i32, b: i32) -> Option<i32> {
    if b <= 0 || !(0..=1 << 16).contains(&a) {
        return None;
    }
    let b = b as u32;
    let q = if a < 1 << 16 {
        ((a as u32) << 16) / b
    } else {
        let q = u32::MAX / b;
        q.saturating_add((u32::MAX - q * b == b - 1) as u32)
    };
    Some(q.min(i32::MAX as u32) as i32)
}

/// `I16F16::saturating_mul` on the bits, `floor(a b / 2^16)` clamped to
/// `i32`, from four 16x16-bit products: where the core has no 32x32 to
/// 64-bit multiply (ARMv6-M, the Cortex-M0), `fixed`'s 64-bit product is a
/// library call and its overflow test more (the geometry stage's
/// dominant cost there: the teapot's vertex stage 6,800 instructions a
/// vertex, measured). Equal to it for every input: `a b = ah bh 2^32 +
/// (ah bl + al bh) 2^16 + al bl` with `al`, `bl` the unsigned low halves,
/// each partial product within 32 bits, the sum within 64.
#[inline]
fn mul_q16(a: i32, b: i32) -> i32 {
    let (ah, al) = (a >> 16, a & 0xffff);
    let (bh, bl) = (b >> 16, b & 0xffff);
    let lo = (al as u32 * bl as u32) >> 16;
    if ((ah + 128) as u32 | (bh + 128) as u32) < 256 {
        // Both below 128 in magnitude (the geometry stage's usual values):
        // every term and the sum within 2^31, no 64-bit arithmetic.
        return ((ah * bh) << 16) + ah * bl + al * bh + lo as i32;
    }
    let hh = (ah * bh) as i64;
    let mid = (ah * bl) as i64 + (al * bh) as i64;
    ((hh << 16) + mid + lo as i64).clamp(i32::MIN as i64, i32::MAX as i64) as i32
}
impl Neg for Fx {
    type Output = Fx;
    fn neg(self) -> Fx {
        Fx(self.0.saturating_neg())
    }
}

impl Real for Fx {
    const ZERO: Self = Fx(I16F16::ZERO);
    const ONE: Self = Fx(I16F16::ONE);
    const HALF: Self = Fx(I16F16::from_bits(1 << 15));
    const NAME: &'static str = "fixed I16F16";
    fn from_i32(v: i32) -> Self {
        Fx(I16F16::saturating_from_num(v))
    }
    fn from_q(bits: i64, frac: u32) -> Self {
        let v: i64 = if frac >= 16 {
            let s = frac - 16;
            if s == 0 {
                bits
            } else {
                // Round half away from zero.
                let h = 1i64 << (s - 1);
                if bits >= 0 {
                    (bits + h) >> s
                } else {
                    -((-bits + h) >> s)
                }
            }
        } else {
            bits.saturating_mul(1 << (16 - frac))
        };
        Fx(I16F16::from_bits(
            v.clamp(i32::MIN as i64, i32::MAX as i64) as i32
        ))
    }
    #[inline]
    fn div(self, d: Self) -> Self {
        if let Some(q) = div_q16_positive(self.0.to_bits(), d.0.to_bits()) {
            return Fx(I16F16::from_bits(q));
        }
        if d.0 == I16F16::ZERO {
            return if self.0 < 0 {
                Fx(I16F16::MIN)
            } else {
                Fx(I16F16::MAX)
            };
        }
        Fx(self.0.saturating_div(d.0))
    }
    fn inv_sqrt(self) -> Self {
        if self.0 <= 0 || !self.is_finite() {
            return Fx(I16F16::MAX);
        }
        // sqrt(bits * 2^32) has 24 fraction bits; then 2^40 / s, rounded,
        // has 16: integers only, exact to about half a step.
        let s = isqrt((self.0.to_bits() as u64) << 32).max(1);
        let inv = ((1u64 << 40) + s / 2) / s;
        Fx(I16F16::from_bits(inv.min(i32::MAX as u64 - 1) as i32))
    }
    fn is_finite(self) -> bool {
        self.0 != I16F16::MAX && self.0 != I16F16::MIN
    }
    #[inline]
    fn affine_q15(row: &[Self; 4], q: [i16; 3], bounded: bool) -> Self {
        if !bounded {
            let c = Fx::from_q15;
            return row[0] * c(q[0]) + row[1] * c(q[1]) + row[2] * c(q[2]) + row[3];
        }
        // `fixed`'s product of `m` and the position `2 q` (its bits) is
        // `floor(m q / 2^15)`; with `m = mh 2^16 + ml`, that is
        // `2 mh q + floor(ml q / 2^15)`, both products within 32 bits. No
        // sum saturates (`bounded`), so none needs a test.
        let term = |m: Fx, q: i16| {
            let (m, q) = (m.0.to_bits(), q as i32);
            ((m >> 16) * q * 2).wrapping_add(((m & 0xffff) * q) >> 15)
        };
        let v = term(row[0], q[0])
            .wrapping_add(term(row[1], q[1]))
            .wrapping_add(term(row[2], q[2]))
            .wrapping_add(row[3].0.to_bits());
        Fx(I16F16::from_bits(v))
    }
    fn to_fixed(self, frac: u32) -> Option<i32> {
        if !self.is_finite() {
            return None;
        }
        let b = self.0.to_bits() as i64;
        let v = if frac >= 16 {
            b << (frac - 16)
        } else {
            (b + (1 << (15 - frac))) >> (16 - frac)
        };
        i32::try_from(v).ok()
    }
}

/// `a > b`, and `false` when either is NaN: `!above(a, b)` rejects NaN
/// where `a <= b` would let it through.
#[inline]
pub(crate) fn above<T: PartialOrd>(a: T, b: T) -> bool {
    a > b
}

/// Floor of the square root of `v` (bit by bit: exact, no division).
pub(crate) fn isqrt(v: u64) -> u64 {
    let (mut rem, mut root) = (v, 0u64);
    let mut bit = 1u64 << 62;
    while bit > rem {
        bit >>= 2;
    }
    while bit != 0 {
        if rem >= root + bit {
            rem -= root + bit;
            root = (root >> 1) + bit;
        } else {
            root >>= 1;
        }
        bit >>= 2;
    }
    root
}

/// An angle as a binary fraction of a turn (`65536` = 360°, step
/// 0.0055°): range reduction is exact and needs no float, so a rotation is
/// the same on every chip and back end.
///
/// ```
/// use tilerast::geometry::Angle;
/// assert_eq!(Angle::degrees(90), Angle::from_turn_q16(16384));
/// // 30° is not a whole step (5461.33 of 65536): within half a step, 5e-5 rad.
/// let (s, c) = Angle::degrees(30).sin_cos::<f32>();
/// assert!((s - 0.5).abs() < 5e-5 && (c - 0.866_025_4).abs() < 5e-5);
/// let (s, c) = Angle::degrees(90).sin_cos::<f32>();
/// assert_eq!((s, c), (1.0, 0.0));
/// ```
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Angle(u16);

impl Angle {
    /// An angle of `q / 65536` of a turn.
    pub const fn from_turn_q16(q: u16) -> Self {
        Angle(q)
    }
    /// Whole degrees (any integer; reduced modulo 360).
    pub const fn degrees(d: i32) -> Self {
        let d = d.rem_euclid(360) as u32;
        Angle(((d * 65536 + 180) / 360) as u16)
    }
    /// Degrees as a float, rounded to the nearest step and reduced modulo a
    /// turn; NaN and infinities give 0°, and so do angles of more than 32,767
    /// turns, whose step exceeds a degree in `f32` anyway.
    ///
    /// ```
    /// use tilerast::geometry::Angle;
    /// assert_eq!(Angle::from_degrees_f32(-90.0), Angle::degrees(270));
    /// assert_eq!(Angle::from_degrees_f32(720.0 + 45.0), Angle::degrees(45));
    /// assert_eq!(Angle::from_degrees_f32(f32::NAN), Angle::degrees(0));
    /// ```
    pub fn from_degrees_f32(d: f32) -> Self {
        // Q16 of a turn as an i32 (exact wrap modulo 2^16 below).
        let q = (d / 360.0 * 65536.0).to_fixed(0).unwrap_or(0);
        Angle(q as u16)
    }
    /// The angle in units of `1 / 65536` turn.
    pub const fn turn_q16(self) -> u16 {
        self.0
    }
    /// The sum of two angles (wrapping around the turn).
    pub const fn add(self, o: Angle) -> Angle {
        Angle(self.0.wrapping_add(o.0))
    }
    /// `(sin, cos)`, computed in `Q30` integers (error below `3e-9`) and
    /// rounded once to the back end.
    pub fn sin_cos<S: Real>(self) -> (S, S) {
        let (s, c) = sin_cos_q30(self.0);
        (S::from_q(s as i64, 30), S::from_q(c as i64, 30))
    }
}

/// `(sin, cos)` of `a / 65536` turn in `Q30`.
fn sin_cos_q30(a: u16) -> (i32, i32) {
    const ONE: i64 = 1 << 30;
    // pi * 2^40, for x = r * (pi/2) / 2^14 in Q30 = r * pi * 2^15.
    const PI_Q40: i64 = 3_454_217_652_358;
    // Sine and cosine of r / 2^14 of a right angle, r in 0..=8192 (45°):
    // Taylor series to x^9 / x^10 (next terms below 2e-9 at 45°), Horner
    // in Q30.
    let poly = |r: i64| -> (i64, i64) {
        let x = (r * PI_Q40 + (1 << 24)) >> 25;
        let x2 = (x * x + (1 << 29)) >> 30;
        let mut s = ONE;
        for k in [72, 42, 20, 6] {
            s = ONE - (x2 * s / ONE) / k;
        }
        let s = (x * s + (1 << 29)) >> 30;
        let mut c = ONE;
        for k in [90, 56, 30, 12, 2] {
            c = ONE - (x2 * c / ONE) / k;
        }
        (s, c)
    };
    let quadrant = a >> 14;
    let r = (a & 0x3FFF) as i64;
    let (s, c) = if r <= 8192 {
        poly(r)
    } else {
        let (s, c) = poly(16384 - r);
        (c, s)
    };
    let (s, c) = (s.clamp(-ONE, ONE) as i32, c.clamp(-ONE, ONE) as i32);
    match quadrant {
        0 => (s, c),
        1 => (c, -s),
        2 => (-s, -c),
        _ => (-c, s),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The 32-bit division equals `fixed`'s saturating one wherever it
    /// answers: every divisor below 2^20 and random ones, dividends at
    /// 1, 0 and between.
    #[test]
    fn div_q16_positive_is_fixed_saturating_div() {
        let mut next = crate::numeric::xorshift(0x1234_5678_9abc_def1);
        let random: [i32; 100_000] = core::array::from_fn(|_| (next() as u32 >> 1) as i32);
        for (k, b) in (1..1 << 20).chain(random).enumerate() {
            let a = match k % 4 {
                0 | 1 => 1 << 16,
                2 => (next() % (1 << 16)) as i32,
                _ => 0,
            };
            let want = I16F16::from_bits(a).saturating_div(I16F16::from_bits(b));
            assert_eq!(div_q16_positive(a, b), Some(want.to_bits()), "{a} / {b}");
        }
        assert_eq!(div_q16_positive(-1, 5), None);
        assert_eq!(div_q16_positive(1 << 16, 0), None);
        assert_eq!(div_q16_positive((1 << 16) + 1, 5), None);
    }

    /// `Fx`'s integer transform of a Q15 position equals the saturating
    /// one wherever the row's absolute sum is below 2^14 (what
    /// `Scene::draw` checks), extreme positions included.
    #[test]
    fn fx_affine_q15_bounded_is_the_saturating_sum() {
        let mut next = crate::numeric::xorshift(0x9e37_79b9_7f4a_7c15);
        for n in 0..200_000u32 {
            let big = 1u64 << (16 + n % 15); // rows of every size below 2^30
            let row: [Fx; 4] = core::array::from_fn(|_| {
                Fx(I16F16::from_bits(
                    ((next() % (2 * big)) as i64 - big as i64) as i32 / 4,
                ))
            });
            let q: [i16; 3] = core::array::from_fn(|k| match (n + k as u32) % 7 {
                0 => i16::MIN,
                1 => i16::MAX,
                _ => next() as i16,
            });
            let want = Fx::affine_q15(&row, q, false);
            assert_eq!(Fx::affine_q15(&row, q, true), want, "{row:?} {q:?}");
        }
    }

    /// The Cortex-M0's multiply equals `fixed`'s saturating one: extremes,
    /// halves' boundaries and random bits.
    #[test]
    fn mul_q16_is_fixed_saturating_mul() {
        let edge = [
            0,
            1,
            -1,
            0xffff,
            0x1_0000,
            -0x1_0000,
            0x7fff_ffff,
            i32::MIN,
            i32::MIN + 1,
            0x8000,
            -0x8000,
            0x7fff_0000,
            -0x7fff_0000,
        ];
        let mut next = crate::numeric::xorshift(0x2545_f491_4f6c_dd1d);
        let random = (0..200_000).map(|_| {
            let v = next() as i32;
            v >> (next() % 32)
        });
        extern crate std;
        let vals: std::vec::Vec<i32> = edge.into_iter().chain(random).collect();
        for (k, &a) in vals.iter().enumerate() {
            for &b in vals.iter().skip(k % 97).step_by(4001).chain(edge.iter()) {
                let want = I16F16::from_bits(a).saturating_mul(I16F16::from_bits(b));
                assert_eq!(mul_q16(a, b), want.to_bits(), "{a} * {b}");
            }
        }
    }

    #[test]
    fn sin_cos_matches_f64_everywhere() {
        let mut worst = 0f64;
        for q in 0..=u16::MAX {
            let (s, c) = sin_cos_q30(q);
            let a = q as f64 / 65536.0 * core::f64::consts::TAU;
            let es = (s as f64 / (1u64 << 30) as f64 - libm_sin(a)).abs();
            let ec = (c as f64 / (1u64 << 30) as f64 - libm_cos(a)).abs();
            worst = worst.max(es).max(ec);
        }
        assert!(worst < 3e-9, "worst {worst}");
    }

    // f64 sine and cosine without std: Taylor series after reduction to
    // [-pi, pi], far more digits than the Q30 code under test.
    fn libm_sin(a: f64) -> f64 {
        let pi = core::f64::consts::PI;
        let mut x = a % (2.0 * pi);
        if x > pi {
            x -= 2.0 * pi;
        }
        let (mut term, mut sum) = (x, x);
        for n in 1..30 {
            term *= -x * x / ((2 * n) as f64 * (2 * n + 1) as f64);
            sum += term;
        }
        sum
    }
    fn libm_cos(a: f64) -> f64 {
        libm_sin(a + core::f64::consts::FRAC_PI_2)
    }

    #[test]
    fn inverse_square_roots() {
        for v in [1e-4f32, 0.01, 0.5, 1.0, 2.0, 3.0, 1000.0, 1e6] {
            let got = v.inv_sqrt() as f64;
            let want = 1.0 / (v as f64).powf(0.5);
            assert!((got / want - 1.0).abs() < 3e-7, "{v}: {got} vs {want}");
        }
        for v in [0.01f64, 0.5, 1.0, 2.0, 3.0, 1000.0] {
            let x = Fx::from_q((v * 65536.0) as i64, 16);
            let got = x.inv_sqrt().0.to_num::<f64>();
            // Against the quantised input; the result's own step is 2^-16.
            let want = 1.0 / x.0.to_num::<f64>().powf(0.5);
            assert!((got - want).abs() < 1e-4, "{v}: {got} vs {want}");
        }
        assert!(!(-1.0f32).inv_sqrt().is_finite());
        assert!(!Real::is_finite(Fx::ZERO.inv_sqrt()));
    }

    #[test]
    fn rounding_to_fixed() {
        assert_eq!(2.5f32.to_fixed(0), Some(3));
        assert_eq!((-2.5f32).to_fixed(0), Some(-2));
        assert_eq!((-2.51f32).to_fixed(0), Some(-3));
        assert_eq!(1.03f32.to_fixed(4), Some(16));
        assert_eq!(f32::NAN.to_fixed(4), None);
        assert_eq!(3e9f32.to_fixed(0), None);
        let h = Fx::from_q(-5, 1); // -2.5
        assert_eq!(h.to_fixed(0), Some(-2));
        assert_eq!(Fx::from_q(5, 1).to_fixed(0), Some(3));
        assert_eq!(isqrt(99), 9);
        assert_eq!(isqrt(1 << 62), 1 << 31);
    }
}
