//! Ordered dither computed from the pixel address bits (seed 001, §II.3,
//! eqs. 1–2). The threshold of an `n x n` Bayer matrix (`n = 2^L`) is a bit
//! permutation of the low `L` bits of the screen address ([`threshold`]);
//! the span loops read the same numbers from a 16 x 16 table it fills at
//! compile time ([`Dither::threshold`]), a byte load where the seed's
//! hardware wires the permutation.
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

/// An ordered-dither choice: [`Bayer<L>`](Bayer), fixed at compile time
/// (a zero-sized value whose level folds into the loops: an unused dither
/// costs no instruction), or [`RuntimeDither`], whose level is a value (a
/// host that reads its configuration from a file compiles one pipeline for
/// every level). A tile holds its dither as a value
/// ([`Tile::set_dither`](crate::tile::Tile::set_dither)).
pub trait Dither: Copy + 'static {
    /// The value a new tile starts with.
    const NEW: Self;

    /// Whether the level is a value that varies at run time
    /// ([`RuntimeDither`]): the span loop then takes `NoDither`'s path at
    /// level 0. `false` for a dither fixed by type.
    const VARIES: bool = false;

    /// `log2` of the matrix side: 0 (none), 1 (2x2), 2 (4x4), 3 (8x8), 4 (16x16).
    fn log2(self) -> u32;

    /// The value of this type with matrix side `2^log2`, if it has one
    /// (a `Bayer<L>` only for `L`).
    ///
    /// ```
    /// use tilerast::dither::{Bayer4, Dither, RuntimeDither};
    /// assert!(Bayer4::with_log2(2).is_some());
    /// assert!(Bayer4::with_log2(3).is_none());
    /// assert_eq!(RuntimeDither::with_log2(3).map(Dither::log2), Some(3));
    /// ```
    #[inline]
    fn with_log2(log2: u32) -> Option<Self> {
        (Self::NEW.log2() == log2).then_some(Self::NEW)
    }

    /// The threshold at screen address `(x, y)`: [`threshold`]`(log2, x, y)`.
    ///
    /// ```
    /// use tilerast::dither::{threshold, Bayer8, Dither};
    /// assert_eq!(Bayer8::NEW.threshold(13, 6), threshold(3, 13, 6));
    /// ```
    #[inline(always)]
    fn threshold(self, x: u32, y: u32) -> u32 {
        ((1 << (2 * self.log2())) - 1) - self.complement(x, y)
    }

    /// What quantization adds to a lane at `(x, y)`: the threshold's
    /// complement `4^L - 1 - t` at the position of the compared fraction
    /// bits. Read from a 16 x 16 table of complements that [`threshold`]
    /// fills at compile time (256 bytes of flash, only for the matrix a
    /// build uses): in a span loop the row is loop-invariant, so a pixel's
    /// dither costs a mask, a byte load and one saturating add per lane
    /// instead of the bit permutation's nine instructions and a compare
    /// and increment per lane on the Cortex-M4 (measured: see
    /// `reports/targets.md`).
    ///
    /// ```
    /// use tilerast::dither::{threshold, Bayer8, Dither};
    /// assert_eq!(Bayer8::NEW.carry(13, 6), ((63 - threshold(3, 13, 6)) << 10) as i32);
    /// ```
    #[inline(always)]
    fn carry(self, x: u32, y: u32) -> i32 {
        (self.complement(x, y) << (crate::numeric::COLOR_FRAC - 2 * self.log2())) as i32
    }

    /// The largest [`Self::carry`], `(4^L - 1) 2^(16 - 2L)` (0 without
    /// dither): a lane below `2^16 (max + 1) - carry_max` quantizes
    /// without reaching its clamp at any address.
    ///
    /// ```
    /// use tilerast::dither::{Bayer8, Dither, NoDither};
    /// assert_eq!(Bayer8::NEW.carry_max(), 63 << 10);
    /// assert_eq!(NoDither::NEW.carry_max(), 0);
    /// ```
    #[inline(always)]
    fn carry_max(self) -> i32 {
        let bits = 2 * self.log2();
        (((1u32 << bits) - 1) << (crate::numeric::COLOR_FRAC - bits)) as i32
    }

    /// The bias added once at span start so that truncation in the
    /// quantizer rounds to nearest: half a unit of the last fraction bit
    /// it looks at.
    ///
    /// ```
    /// use tilerast::dither::{Bayer4, Dither, NoDither};
    /// assert_eq!(NoDither::NEW.round_bias(), 1 << 15);
    /// assert_eq!(Bayer4::NEW.round_bias(), 1 << 11);
    /// ```
    #[inline(always)]
    fn round_bias(self) -> i32 {
        1 << (crate::numeric::COLOR_FRAC - 2 * self.log2() - 1)
    }

    /// The dither row from screen `(x, y)` rightwards, packed into one
    /// word for a 2x2 or 4x4 matrix fixed by type ([`Self::packed`]): the
    /// pixel's [`Self::carry`] is [`packed_carry`] of it, and each
    /// rotation right by 4 ([`packed_step`]) moves one pixel right. A
    /// pixel's carry is then a mask, where a table read costs an index, a
    /// load and a shift and holds two more registers in the span loop (the
    /// Cortex-M4 city walk 1.221 -> 1.187 M instructions a frame). 0 when
    /// not packed.
    #[doc(hidden)]
    #[inline(always)]
    fn packed_row(self, x: u32, y: u32) -> u32 {
        if self.packed() {
            PACKED[self.log2() as usize - 1][(y & 15) as usize].rotate_right(4 * (x & 7))
        } else {
            0
        }
    }

    /// Whether [`Self::packed_row`] packs the row: a 2x2 or 4x4 matrix fixed
    /// by type (each carry then fits the nibble [`NIBBLE`]), on a core
    /// with the registers to hold it ([`MANY_REGS`]: the Cortex-M0's
    /// span loops spill the word, and read the table instead — the
    /// micro:bit's SSD1306 frame 0.4% and its demo 0.6% cheaper that way,
    /// measured).
    #[doc(hidden)]
    #[inline(always)]
    fn packed(self) -> bool {
        MANY_REGS && !Self::VARIES && (self.log2() == 1 || self.log2() == 2)
    }

    /// `4^L - 1 - threshold(x, y)`, from the table.
    #[doc(hidden)]
    #[inline(always)]
    fn complement(self, x: u32, y: u32) -> u32 {
        let table = match self.log2() {
            0 => return 0,
            1 => &BAYER_2,
            2 => &BAYER_4,
            3 => &BAYER_8,
            _ => &BAYER_16,
        };
        table[(y & 15) as usize][(x & 15) as usize] as u32
    }
}

/// The complements `4^L - 1 - `[`threshold`] for `L` over one 16 x 16
/// period of the screen (every matrix up to 16 x 16 tiles it).
const fn bayer_table(l: u32) -> [[u8; 16]; 16] {
    let mut t = [[0; 16]; 16];
    let mut y = 0;
    while y < 16 {
        let mut x = 0;
        while x < 16 {
            t[y][x] = ((1 << (2 * l)) - 1 - threshold(l, x as u32, y as u32)) as u8;
            x += 1;
        }
        y += 1;
    }
    t
}

use crate::numeric::MANY_REGS;

/// Where a packed cursor's current carry sits: bits 12..16, the carries of
/// a 2x2 or 4x4 matrix (`(4^L - 1) 2^(16 - 2L)` at most).
const NIBBLE: u32 = 0xf << (crate::numeric::COLOR_FRAC - 4);
const _: () = assert!(
    crate::numeric::COLOR_FRAC == 16,
    "the packed cursor's nibble is the fourth"
);

/// The carry of the pixel a packed row ([`Dither::packed_row`]) is at.
#[doc(hidden)]
#[inline(always)]
pub fn packed_carry(word: u32) -> i32 {
    (word & NIBBLE) as i32
}

/// A packed row ([`Dither::packed_row`]) one pixel right.
#[doc(hidden)]
#[inline(always)]
pub fn packed_step(word: u32) -> u32 {
    word.rotate_right(4)
}

/// The packed rows of 2x2 and 4x4 for `x = 0` (mod 8), per `y & 15`:
/// pixel `j`'s carry, shifted down to a nibble, in nibble `(3 + j) % 8`,
/// so that rotating right by `4 (x & 7)` brings pixel `x`'s into
/// [`NIBBLE`] and each further rotation by 4 the next pixel's.
static PACKED: [[u32; 16]; 2] = {
    let mut t = [[0; 16]; 2];
    let mut l = 1;
    while l <= 2 {
        let c = bayer_table(l);
        let mut y = 0;
        while y < 16 {
            let mut w = 0u32;
            let mut j = 0;
            while j < 8 {
                let nibble = (c[y][j] as u32) << (4 - 2 * l);
                w |= nibble << (4 * ((3 + j) % 8));
                j += 1;
            }
            t[l as usize - 1][y] = w;
            y += 1;
        }
        l += 1;
    }
    t
};

/// The tables of [`Dither::carry`] for `L = 1..=4`, each its own
/// `static`, so a build links only the one it reads.
static BAYER_2: [[u8; 16]; 16] = bayer_table(1);
static BAYER_4: [[u8; 16]; 16] = bayer_table(2);
static BAYER_8: [[u8; 16]; 16] = bayer_table(3);
static BAYER_16: [[u8; 16]; 16] = bayer_table(4);

/// Bayer ordered dither of side `2^L`, fixed by type. `Bayer<0>` is no
/// dither (round to nearest).
///
/// ```
/// use tilerast::dither::{threshold, Bayer8};
/// // Seed eq. 1, D(2) = [[0, 2], [3, 1]] (row = y, column = x):
/// assert_eq!([threshold(1, 0, 0), threshold(1, 1, 0), threshold(1, 0, 1), threshold(1, 1, 1)], [0, 2, 3, 1]);
/// ```
#[derive(Debug, Clone, Copy, Default)]
pub struct Bayer<const L: u32>;

impl<const L: u32> Bayer<L> {
    /// `log2` of the matrix side.
    pub const LOG2: u32 = {
        assert!(L <= 4, "dither matrices up to 16x16");
        L
    };
}

impl<const L: u32> Dither for Bayer<L> {
    const NEW: Self = Bayer;
    #[inline(always)]
    fn log2(self) -> u32 {
        Self::LOG2
    }
}

/// No dither: round to nearest.
pub type NoDither = Bayer<0>;
/// 2x2 ordered dither.
pub type Bayer2 = Bayer<1>;
/// 4x4 ordered dither.
pub type Bayer4 = Bayer<2>;
/// 8x8 ordered dither (the seed's REjr).
pub type Bayer8 = Bayer<3>;

/// An ordered dither whose matrix side is a value, `2^log2` (0 to 4; 0 is
/// none): what the host simulator uses, so that one compiled pipeline
/// serves every level a scene file may ask for. Its pixels equal
/// [`Bayer<L>`](Bayer)'s at the same level (tested); it costs a table
/// pointer and a shift by a register where `Bayer` folds constants.
/// Firmware names its dither by type.
///
/// ```
/// use tilerast::dither::{Bayer8, Dither, RuntimeDither};
/// let d = RuntimeDither::new(3)?;
/// assert_eq!(d.carry(13, 6), Bayer8::NEW.carry(13, 6));
/// assert!(RuntimeDither::new(5).is_err());
/// # Ok::<(), tilerast::Error>(())
/// ```
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct RuntimeDither {
    log2: u8,
}

impl RuntimeDither {
    /// The dither of side `2^log2`; [`Error::BadSize`](crate::Error::BadSize)
    /// above 4 (16 x 16).
    pub const fn new(log2: u32) -> Result<Self, crate::Error> {
        if log2 > 4 {
            return Err(crate::Error::BadSize);
        }
        Ok(RuntimeDither { log2: log2 as u8 })
    }
}

/// [`RuntimeDither`]'s carries by level, already shifted into place
/// (`4^L - 1 - t` at bit `16 - 2L`; level 0 all zero): a pixel's carry is
/// one load, where the complement tables would cost a shift by a register
/// too (5 KB, linked only by a program that uses `RuntimeDither`).
static RUNTIME_CARRIES: [[[i32; 16]; 16]; 5] = {
    let mut t = [[[0; 16]; 16]; 5];
    let mut l = 1;
    while l < 5 {
        let c = bayer_table(l as u32);
        let mut y = 0;
        while y < 16 {
            let mut x = 0;
            while x < 16 {
                t[l][y][x] = (c[y][x] as i32) << (crate::numeric::COLOR_FRAC - 2 * l as u32);
                x += 1;
            }
            y += 1;
        }
        l += 1;
    }
    t
};

impl Dither for RuntimeDither {
    const NEW: Self = RuntimeDither { log2: 0 };
    const VARIES: bool = true;
    #[inline]
    fn with_log2(log2: u32) -> Option<Self> {
        Self::new(log2).ok()
    }
    #[inline(always)]
    fn log2(self) -> u32 {
        self.log2 as u32
    }
    #[inline(always)]
    fn carry(self, x: u32, y: u32) -> i32 {
        RUNTIME_CARRIES[(self.log2 as usize).min(4)][(y & 15) as usize][(x & 15) as usize]
    }
}

/// The threshold `D(x, y)` in `0..4^L` of the `2^L x 2^L` Bayer matrix at screen
/// address `(x, y)`, from the address bits alone (seed eq. 2 generalised).
#[inline(always)]
pub const fn threshold(l: u32, x: u32, y: u32) -> u32 {
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

    /// A packed row walks the same carries as [`Dither::carry`] at every
    /// level it packs, from every start, for 40 pixels.
    #[test]
    fn packed_rows_walk_the_carries() {
        fn walk<D: Dither>(d: D) {
            if !d.packed() {
                return;
            }
            for y in 0..16 {
                for x0 in 0..16 {
                    let mut w = d.packed_row(x0, y);
                    for i in 0..40 {
                        let (l, want) = (d.log2(), d.carry(x0 + i, y));
                        assert_eq!(packed_carry(w), want, "{l} {x0} {y} {i}");
                        w = packed_step(w);
                    }
                }
            }
        }
        assert!(Bayer2::NEW.packed() && Bayer4::NEW.packed());
        assert!(!Bayer8::NEW.packed() && !RuntimeDither::new(2).unwrap().packed());
        walk(NoDither::NEW);
        walk(Bayer2::NEW);
        walk(Bayer4::NEW);
        walk(Bayer8::NEW);
        walk(Bayer::<4>::NEW);
        for l in 0..5 {
            walk(RuntimeDither::new(l).unwrap());
        }
    }

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

    /// The span loops' table lookup is the address-bit threshold
    /// everywhere on the screen, for every matrix.
    #[test]
    fn table_thresholds_equal_address_bits() {
        fn check<const L: u32>() {
            for y in (0..40).chain(u32::MAX - 40..=u32::MAX) {
                for x in (0..40).chain(u32::MAX - 40..=u32::MAX) {
                    let t = threshold(L, x, y);
                    assert_eq!(Bayer::<L>::NEW.threshold(x, y), t, "L={L} {x} {y}");
                    let c = ((1 << (2 * L)) - 1 - t) << (16 - 2 * L);
                    assert_eq!(Bayer::<L>::NEW.carry(x, y), c as i32, "L={L} {x} {y}");
                    let r = RuntimeDither::new(L).unwrap();
                    assert_eq!(r.threshold(x, y), t, "L={L} {x} {y}");
                    assert_eq!(r.carry(x, y), c as i32, "L={L} {x} {y}");
                    assert_eq!(r.carry_max(), Bayer::<L>::NEW.carry_max());
                    assert_eq!(r.round_bias(), Bayer::<L>::NEW.round_bias());
                }
            }
        }
        check::<0>();
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

    /// The carry form of [`quantize`] is the seed's compare-and-increment
    /// for every value (the extremes included) and threshold.
    #[test]
    fn quantize_equals_compare_and_increment() {
        fn check<D: Dither>() {
            let bits = 2 * D::NEW.log2();
            let values = (-70_000..70_000)
                .step_by(7)
                .chain((0..1 << 13).map(|k| (15 << 16) - 40 + k * 127))
                .chain([
                    i32::MIN,
                    i32::MIN + 1,
                    -1,
                    0,
                    1,
                    i32::MAX - 70_000,
                    i32::MAX - 1,
                    i32::MAX,
                ]);
            for v in values {
                for t in (0..(1u32 << bits) + 2)
                    .step_by(1 + bits as usize / 8 * 4)
                    .chain([u32::MAX])
                {
                    let int = v >> 16;
                    let frac = ((v >> (16 - bits)) as u32) & ((1 << bits) - 1);
                    let inc = if bits == 0 { 0 } else { (frac > t) as i32 };
                    for max in [15, 31, 255] {
                        assert_eq!(
                            quantize(D::NEW, v, max, t),
                            (int + inc).clamp(0, max),
                            "{v} {t} {max}"
                        );
                    }
                }
            }
        }
        check::<NoDither>();
        check::<Bayer2>();
        check::<Bayer8>();
        check::<Bayer<4>>();
    }

    #[test]
    fn increment_saturates_at_max() {
        // 15 + fraction 63/64 at any threshold must stay 15 (4-bit channel).
        let v = (15 << 16) | (63 << 10);
        for t in 0..64 {
            assert_eq!(quantize(Bayer8::NEW, v, 15, t), 15);
        }
        // Just below max: value 14 + 63/64 becomes 15 for all but the top threshold.
        let v = (14 << 16) | (63 << 10);
        assert_eq!(
            (0..64)
                .filter(|&t| quantize(Bayer8::NEW, v, 15, t) == 15)
                .count(),
            63
        );
        // Negative drift clamps to zero.
        assert_eq!(quantize(Bayer8::NEW, -5, 15, 0), 0);
        assert_eq!(quantize(NoDither::NEW, -5, 15, 0), 0);
    }

    #[test]
    fn dither_average_equals_value() {
        // Over one matrix period, the mean output equals the fraction (6 bits).
        for f in 0..64i32 {
            let v = (3 << 16) | (f << 10);
            let sum: i32 = (0..8)
                .flat_map(|y| (0..8).map(move |x| (x, y)))
                .map(|(x, y)| quantize(Bayer8::NEW, v, 15, threshold(3, x, y)))
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
    /// fraction bits, already carrying the `+0.5` bias of [`Dither::round_bias`]) to an
    /// integer in `0..=max`, dithered with threshold `t`: the integer part,
    /// plus one when the top `2 LOG2` fraction bits exceed `t` (seed
    /// Fig. 2), clamped.
    ///
    /// Computed as `(v + (4^L - 1 - t) 2^(16 - 2L)) >> 16`: the complement
    /// of the threshold added at the position of the compared bits carries
    /// into the integer exactly when they exceed it (the bits below cannot
    /// carry: they are under one unit of that position). The addition
    /// saturates, so the result equals the compare-and-increment for every
    /// `v`; per lane on the Cortex-M4 a `QADD` and a `USAT` with a shifted
    /// operand instead of seven instructions (measured: see
    /// `reports/targets.md`). A threshold at or above `4^L - 1` never
    /// increments.
    #[cfg_attr(not(feature = "unstable"), allow(dead_code))]
    #[inline(always)]
    pub fn quantize<D: Dither>(d: D, v: i32, max: i32, t: u32) -> i32 {
        let bits = 2 * d.log2();
        let complement = ((1u32 << bits) - 1).saturating_sub(t);
        quantize_carry(
            v,
            max,
            (complement << (crate::numeric::COLOR_FRAC - bits)) as i32,
        )
    }

    /// [`quantize`] with the threshold's [`Dither::carry`].
    #[inline(always)]
    pub fn quantize_carry(v: i32, max: i32, carry: i32) -> i32 {
        (v.saturating_add(carry) >> crate::numeric::COLOR_FRAC).clamp(0, max)
    }
}

#[cfg(all(test, not(feature = "unstable")))]
use quant::quantize;
#[cfg(not(feature = "unstable"))]
pub(crate) use quant::quantize_carry;
#[cfg(feature = "unstable")]
pub use quant::{quantize, quantize_carry};
