//! Ordered dither computed from the pixel address bits (seed 001, §II.3,
//! eqs. 1–2). No table: the threshold of an `n x n` Bayer matrix (`n = 2^L`)
//! is a bit permutation of the low `L` bits of the screen address.
//!
//! Seed eq. 2 for 8x8 (`L = 3`), `D[0]` the least significant bit:
//! `D[0]=Y[2], D[1]=X[2]^Y[2], D[2]=Y[1], D[3]=X[1]^Y[1], D[4]=Y[0], D[5]=X[0]^Y[0]`.
//! The general rule, for `k = 0..L`: bit `2k` is `Y[L-1-k]`, bit `2k+1` is
//! `(X^Y)[L-1-k]`. This equals the recursive definition of eq. 1 (tested).
//!
//! Quantization (seed Fig. 2): the integer part of the interpolated channel
//! is the true value; the top `2L` fraction bits are compared with the
//! threshold, and when they are greater the value is incremented. The
//! increment **saturates** at the channel maximum.

/// An ordered-dither choice, fixed at compile time: an unused dither costs
/// no instruction.
pub trait Dither: 'static {
    /// `log2` of the matrix side: 0 (none), 1 (2x2), 2 (4x4), 3 (8x8), 4 (16x16).
    const LOG2: u32;
    /// The threshold at screen address `(x, y)`: [`threshold`]`(LOG2, x, y)`.
    #[inline(always)]
    fn threshold(x: u32, y: u32) -> u32 {
        threshold(Self::LOG2, x, y)
    }
}

/// Bayer ordered dither of side `2^L`. `Bayer<0>` is no dither (round to
/// nearest).
///
/// ```
/// use tilerast::dither::{threshold, Bayer8};
/// // Seed eq. 1, D(2) = [[0, 2], [3, 1]] (row = y, column = x):
/// assert_eq!([threshold(1, 0, 0), threshold(1, 1, 0), threshold(1, 0, 1), threshold(1, 1, 1)], [0, 2, 3, 1]);
/// ```
#[derive(Debug, Clone, Copy, Default)]
pub struct Bayer<const L: u32>;

impl<const L: u32> Dither for Bayer<L> {
    const LOG2: u32 = {
        assert!(L <= 4, "dither matrices up to 16x16");
        L
    };
}

/// No dither: round to nearest.
pub type NoDither = Bayer<0>;
/// 2x2 ordered dither.
pub type Bayer2 = Bayer<1>;
/// 4x4 ordered dither.
pub type Bayer4 = Bayer<2>;
/// 8x8 ordered dither (the seed's REjr).
pub type Bayer8 = Bayer<3>;

/// The threshold `D(x, y)` in `0..4^L` of the `2^L x 2^L` Bayer matrix at screen
/// address `(x, y)`, from the address bits alone (seed eq. 2 generalised).
#[inline(always)]
pub fn threshold(l: u32, x: u32, y: u32) -> u32 {
    let xy = x ^ y;
    let mut d = 0;
    let mut k = 0;
    while k < l {
        let bit = l - 1 - k;
        d |= ((y >> bit) & 1) << (2 * k) | ((xy >> bit) & 1) << (2 * k + 1);
        k += 1;
    }
    d
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Seed eq. 1, recursively: D(n) = [[4D(n/2) + D2_00, 4D(n/2) + D2_01], ...].
    fn recursive(n: u32, x: u32, y: u32) -> u32 {
        const D2: [[u32; 2]; 2] = [[0, 2], [3, 1]];
        if n == 1 {
            return 0;
        }
        let h = n / 2;
        4 * recursive(h, x % h, y % h) + D2[(y / h) as usize][(x / h) as usize]
    }

    fn check<const L: u32>() {
        let n = 1 << L;
        let mut seen = [false; 256];
        for y in 0..n {
            for x in 0..n {
                let t = threshold(L, x, y);
                assert_eq!(t, recursive(n, x, y), "L={L} x={x} y={y}");
                seen[t as usize] = true;
                // Address bits beyond L do not matter: the matrix tiles the screen.
                assert_eq!(threshold(L, x + 7 * n, y + 3 * n), t);
            }
        }
        assert!(seen[..(n * n) as usize].iter().all(|&s| s), "a permutation");
    }

    #[test]
    fn address_bits_equal_recursive_bayer() {
        check::<1>();
        check::<2>();
        check::<3>();
        check::<4>();
    }

    #[test]
    fn seed_equation_2_bits() {
        for y in 0..8u32 {
            for x in 0..8u32 {
                let b = |v: u32, i: u32| (v >> i) & 1;
                let d = b(y, 2)
                    | (b(x, 2) ^ b(y, 2)) << 1
                    | b(y, 1) << 2
                    | (b(x, 1) ^ b(y, 1)) << 3
                    | b(y, 0) << 4
                    | (b(x, 0) ^ b(y, 0)) << 5;
                assert_eq!(threshold(3, x, y), d);
            }
        }
    }

    #[test]
    fn increment_saturates_at_max() {
        // 15 + fraction 63/64 at any threshold must stay 15 (4-bit channel).
        let v = (15 << 16) | (63 << 10);
        for t in 0..64 {
            assert_eq!(quantize::<Bayer8>(v, 15, t), 15);
        }
        // Just below max: value 14 + 63/64 becomes 15 for all but the top threshold.
        let v = (14 << 16) | (63 << 10);
        assert_eq!(
            (0..64)
                .filter(|&t| quantize::<Bayer8>(v, 15, t) == 15)
                .count(),
            63
        );
        // Negative drift clamps to zero.
        assert_eq!(quantize::<Bayer8>(-5, 15, 0), 0);
        assert_eq!(quantize::<NoDither>(-5, 15, 0), 0);
    }

    #[test]
    fn dither_average_equals_value() {
        // Over one matrix period, the mean output equals the fraction (6 bits).
        for f in 0..64i32 {
            let v = (3 << 16) | (f << 10);
            let sum: i32 = (0..8)
                .flat_map(|y| (0..8).map(move |x| (x, y)))
                .map(|(x, y)| quantize::<Bayer8>(v, 15, threshold(3, x, y)))
                .sum();
            assert_eq!(sum, 3 * 64 + f);
        }
    }
}

/// The quantizer every fragment store uses.
/// Public only with the `unstable` feature (the research crate and the
/// tests use them); no stability promise.
mod quant {
    #![allow(unused_imports)]
    use super::*;

    /// Quantizes one lane (output scale, [`COLOR_FRAC`](crate::numeric::COLOR_FRAC)
    /// fraction bits, already carrying the `+0.5` bias of [`round_bias`]) to an
    /// integer in `0..=max`, dithered with threshold `t`.
    #[inline(always)]
    pub fn quantize<D: Dither>(v: i32, max: i32, t: u32) -> i32 {
        use crate::numeric::COLOR_FRAC;
        let int = v >> COLOR_FRAC;
        if D::LOG2 == 0 {
            int.clamp(0, max)
        } else {
            let bits = 2 * D::LOG2;
            let frac = ((v >> (COLOR_FRAC - bits)) as u32) & ((1 << bits) - 1);
            (int + (frac > t) as i32).clamp(0, max)
        }
    }

    /// The bias added once at span start so that truncation in [`quantize`]
    /// rounds to nearest: half a unit of the last fraction bit it looks at.
    pub const fn round_bias<D: Dither>() -> i32 {
        1 << (crate::numeric::COLOR_FRAC - 2 * D::LOG2 - 1)
    }
}

#[cfg(feature = "unstable")]
pub use quant::{quantize, round_bias};
#[cfg(not(feature = "unstable"))]
pub(crate) use quant::{quantize, round_bias};
