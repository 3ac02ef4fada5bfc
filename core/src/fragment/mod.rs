//! Fragment tests (seed 001, §II.4–5): the window-ID test, then the Z test.
//!
//! A fragment is written only where the tile's window-ID plane holds the
//! command's ID, and only where its Z is **less than** the stored Z, which it
//! then replaces (read-modify-write, as REjr's Z channel). Either plane can be
//! absent: `NoDepth` and `NoWid` store `()`, and their tests are the constant
//! `true`, so the inner loop carries no trace of them.
//!
//! **Depth bits.** The Z DDA carries 16.14 fixed point ([`crate::numeric`]).
//! [`Depth16`] keeps the integer part (rounded): vertex depths are `u16`,
//! so surfaces closer than one unit tie, and the first drawn wins.
//! [`Depth24`] and [`Depth32`] keep 8 and 14 fraction bits of the
//! interpolated value as well, for scenes with close or intersecting
//! surfaces; they cost 1 and 2 more bytes a pixel (`tilerast-lab tradeoff`
//! measures what that buys).

pub mod dither;

use crate::format::{Cell, ColorPlane, Plane};
use core::marker::PhantomData;

/// Whether a tile has a depth plane, chosen by type.
pub trait DepthMode: 'static {
    /// Storage for `8 N` pixels.
    type Plane<const N: usize>: DepthPlane;
    /// Bits per pixel of the plane.
    const BITS: u32;
}

/// Whether a tile has a window-ID plane, chosen by type.
pub trait WidMode: 'static {
    /// Storage for `8 N` pixels.
    type Plane<const N: usize>: WidPlane;
    /// Bits per pixel of the plane.
    const BITS: u32;
}

/// A Z plane of cells `T` holding depth with `FRAC` fraction bits (16.`FRAC`),
/// less-than test: [`Depth16`], [`Depth24`], [`Depth32`].
///
/// ```
/// use tilerast::prelude::*;
/// assert_eq!(Tile::<64, Planes<Rgb565Format, Depth16>>::bits_per_pixel(), 16 + 16);
/// assert_eq!(Tile::<64, Planes<Rgb565Format, Depth24>>::bits_per_pixel(), 16 + 24);
/// assert_eq!(Tile::<64, Planes<Rgb565Format, Depth32>>::bits_per_pixel(), 16 + 32);
/// ```
#[derive(Debug, Clone, Copy, Default)]
pub struct DepthBits<T, const FRAC: u32>(PhantomData<T>);
/// 16-bit Z plane: integer depth.
pub type Depth16 = DepthBits<u16, 0>;
/// 24-bit Z plane (three bytes): depth in 16.8.
pub type Depth24 = DepthBits<[u8; 3], 8>;
/// 32-bit Z plane: depth in 16.14, every bit the DDA has.
pub type Depth32 = DepthBits<u32, 14>;
/// No depth plane: every fragment passes.
#[derive(Debug, Clone, Copy, Default)]
pub struct NoDepth;
/// 8-bit window-ID plane (256 windows).
#[derive(Debug, Clone, Copy, Default)]
pub struct Wid8;
/// No window-ID plane: every fragment passes.
#[derive(Debug, Clone, Copy, Default)]
pub struct NoWid;

/// A plane whose presence is a value: `Switchable<Depth16>` or
/// `Switchable<Wid8>` stores the plane of `M` always and stores and tests
/// through it only while switched on
/// ([`Tile::enable_depth`](crate::tile::Tile::enable_depth),
/// [`Tile::enable_wid`](crate::tile::Tile::enable_wid); on when new).
/// Switched off, a tile draws exactly what the same tile without the plane
/// draws (tested). For a host that reads its configuration from a file: one
/// compiled pipeline serves both, at the cost of the plane's RAM and a
/// branch a pixel. Firmware names its planes by type.
///
/// ```
/// use tilerast::prelude::*;
/// type Host = Planes<Rgb565Format, Switchable<Depth16>, Switchable<Wid8>>;
/// let mut tile: Tile<8, Host> = Tile::new();
/// tile.enable_depth(false);
/// tile.begin(Rect::new(0, 0, 8, 8), &Clear { depth: 7, ..Clear::default() })?;
/// assert_eq!(tile.depth(0, 0), Some(0xFFFF)); // as without a depth plane
/// tile.enable_depth(true);
/// tile.begin(Rect::new(0, 0, 8, 8), &Clear { depth: 7, ..Clear::default() })?;
/// assert_eq!(tile.depth(0, 0), Some(7));
/// # Ok::<(), Error>(())
/// ```
#[derive(Debug, Clone, Copy, Default)]
pub struct Switchable<M>(PhantomData<M>);

impl<M: DepthMode> DepthMode for Switchable<M> {
    type Plane<const N: usize> = Switch<M::Plane<N>>;
    const BITS: u32 = M::BITS;
}
impl<M: WidMode> WidMode for Switchable<M> {
    type Plane<const N: usize> = Switch<M::Plane<N>>;
    const BITS: u32 = M::BITS;
}

impl<T: Cell + 'static, const FRAC: u32> DepthMode for DepthBits<T, FRAC> {
    type Plane<const N: usize> = ZPlane<T, FRAC, N>;
    const BITS: u32 = 8 * core::mem::size_of::<T>() as u32;
}
impl DepthMode for NoDepth {
    type Plane<const N: usize> = ();
    const BITS: u32 = 0;
}
impl WidMode for Wid8 {
    type Plane<const N: usize> = Plane<u8, N>;
    const BITS: u32 = 8;
}
impl WidMode for NoWid {
    type Plane<const N: usize> = ();
    const BITS: u32 = 0;
}

/// Whether a tile's loops can alpha-blend ([`crate::command::Blend`]),
/// chosen by type like a plane: a configuration without it compiles no
/// blending code at all (what a Cortex-M0's flash needs), and draws
/// translucent commands opaque.
///
/// ```
/// use tilerast::prelude::*;
/// type Glass = Planes<Rgb565Format, Depth16, NoWid, Bayer4, NoAa, FullPrecision, AlphaBlending>;
/// assert!(<Glass as TileConfig>::Blending::ALPHA);
/// assert!(!<St7789Config as TileConfig>::Blending::ALPHA);
/// // Blending needs no plane: the destination colour is the colour plane.
/// assert_eq!(Tile::<8, Glass>::bits_per_pixel(), Tile::<8, St7789Config>::bits_per_pixel());
/// ```
pub trait BlendMode: 'static {
    /// Whether translucent commands blend.
    const ALPHA: bool;
}
/// No blending: translucent commands are drawn opaque (the default).
#[derive(Debug, Clone, Copy, Default)]
pub struct NoBlending;
/// Alpha blending compiled in: translucent commands blend.
#[derive(Debug, Clone, Copy, Default)]
pub struct AlphaBlending;
impl BlendMode for NoBlending {
    const ALPHA: bool = false;
}
impl BlendMode for AlphaBlending {
    const ALPHA: bool = true;
}

/// Whether a tile's triangle loops step quadratic colours
/// ([`crate::command::Command::Quadratic`], the RE's fast Phong), chosen by
/// type like [`BlendMode`]: a configuration without it compiles no
/// quadratic setup or stepping and draws those triangles Gouraud-shaded
/// from their vertex colours.
///
/// ```
/// use tilerast::prelude::*;
/// type Lit = Planes<Rgb565Format, Depth16, NoWid, Bayer4, NoAa, FullPrecision, NoBlending, QuadraticShading>;
/// assert!(<Lit as TileConfig>::Shading::QUADRATIC);
/// assert!(!<St7789Config as TileConfig>::Shading::QUADRATIC);
/// assert_eq!(Tile::<8, Lit>::bits_per_pixel(), Tile::<8, St7789Config>::bits_per_pixel());
/// ```
pub trait ShadingMode: 'static {
    /// Whether quadratic triangles are stepped quadratically.
    const QUADRATIC: bool;
}
/// Gouraud only: quadratic triangles take their vertex colours (the default).
#[derive(Debug, Clone, Copy, Default)]
pub struct GouraudShading;
/// Quadratic (fast Phong) triangles compiled in.
#[derive(Debug, Clone, Copy, Default)]
pub struct QuadraticShading;
impl ShadingMode for GouraudShading {
    const QUADRATIC: bool = false;
}
impl ShadingMode for QuadraticShading {
    const QUADRATIC: bool = true;
}

/// Depth- and window-ID-plane storage: the tile's internals.
/// Public only with the `unstable` feature (the research crate and the
/// tests use them); no stability promise.
mod planes {
    #![allow(unused_imports)]
    use super::*;

    /// Depth-plane storage.
    pub trait DepthPlane: Sized {
        /// A new plane (contents are set by the tile's clear).
        const NEW: Self;
        /// Whether the plane stores and tests (a constant unless the
        /// plane is [`Switchable`]).
        #[inline(always)]
        fn present(&self) -> bool {
            true
        }
        /// Switches a [`Switchable`] plane on or off; others ignore it.
        #[inline(always)]
        fn set_present(&mut self, _on: bool) {}
        /// Sets pixel `i` to the integer depth `z` (clears, Z fills, resolved
        /// coverage).
        fn put(&mut self, i: usize, z: u16);
        /// Sets every pixel of `r` to `z` (the tile's clear): a slice fill
        /// where the plane is stored.
        #[inline(always)]
        fn put_range(&mut self, r: core::ops::Range<usize>, z: u16) {
            for i in r {
                self.put(i, z);
            }
        }
        /// Reads pixel `i`'s integer depth, rounded down (65535 when there is
        /// no plane).
        fn read(&self, i: usize) -> u16;
        /// The Z test of an interpolated depth `z` (16.14, rounding bias of
        /// half a unit included): passes when `z` is less than the stored
        /// value at the plane's precision (`z` clamped to its range), and
        /// stores it.
        fn test_and_set(&mut self, i: usize, z: i32) -> bool;
        /// [`Self::test_and_set`] of a depth `z` in `0..2^30`, whose clamp
        /// cannot act (a span the loop has checked whole): a shift.
        #[inline(always)]
        fn test_and_set_in_range(&mut self, i: usize, z: i32) -> bool {
            self.test_and_set(i, z)
        }
        /// The Z test without the write (partial-coverage fragments).
        fn test(&self, i: usize, z: i32) -> bool;
        /// Pixels of `r` whose integer depth is above `z` (the occlusion
        /// box test's count), the scan stopping once `limit` are found.
        fn farther(&self, r: core::ops::Range<usize>, z: u16, limit: u32) -> u32;
        /// [`Self::farther`], and the nearest and farthest integer depth of
        /// `r`, in one pass (the occlusion summary's refresh).
        fn farther_min_max(&self, r: core::ops::Range<usize>, z: u16) -> (u32, u16, u16);
    }

    /// Window-ID plane storage.
    pub trait WidPlane: Sized {
        /// A new plane.
        const NEW: Self;
        /// Whether the plane stores and tests (a constant unless the
        /// plane is [`Switchable`]).
        #[inline(always)]
        fn present(&self) -> bool {
            true
        }
        /// Switches a [`Switchable`] plane on or off; others ignore it.
        #[inline(always)]
        fn set_present(&mut self, _on: bool) {}
        /// Sets pixel `i` to `id`.
        fn put(&mut self, i: usize, id: u8);
        /// Sets every pixel of `r` to `id` (a window's rows): a slice fill
        /// where the plane is stored. A pixel at a time, the demo frame's
        /// window claims cost 0.27 M instructions more on the Cortex-M4 and
        /// 0.31 M on the M0 (measured).
        #[inline(always)]
        fn put_range(&mut self, r: core::ops::Range<usize>, id: u8) {
            for i in r {
                self.put(i, id);
            }
        }
        /// Reads pixel `i` (0 when there is no plane).
        fn read(&self, i: usize) -> u8;
        /// The window-ID test.
        fn pass(&self, i: usize, id: u8) -> bool;
    }

    /// [`DepthPlane::farther_min_max`] of `cells` holding depth with
    /// `FRAC` fraction bits, a cell at a time: what a microcontroller runs
    /// (eight at a time cost the Cortex-M4 city's S&W and CHC walks 6% and
    /// 3% more instructions, the single pass 0.2% less: measured).
    pub(crate) fn farther_min_max_each<T: Cell, const FRAC: u32>(
        cells: &[T],
        z: u16,
    ) -> (u32, u16, u16) {
        cells.iter().fold((0, u16::MAX, 0), |(n, lo, hi), c| {
            let d = (c.to_u32() >> FRAC) as u16;
            (n + (z < d) as u32, lo.min(d), hi.max(d))
        })
    }

    /// [`farther_min_max_each`] eight cells at a time, what a host runs:
    /// each depth biased to `i16` (`d ^ 0x8000`, the same order), so the
    /// compares, minima and maxima of eight are independent lanes that
    /// x86-64's baseline SIMD takes whole (SSE2 has signed 16-bit minima,
    /// not unsigned ones). The single pass on the host's culling city, two
    /// 60-frame walks: 519 -> 500 M instructions (large triangles),
    /// 797 -> 780 M (small), callgrind.
    pub(crate) fn farther_min_max_lanes<T: Cell, const FRAC: u32>(
        cells: &[T],
        z: u16,
    ) -> (u32, u16, u16) {
        let bias = |d: u16| (d ^ 0x8000) as i16;
        let at = |c: &T| bias((c.to_u32() >> FRAC) as u16);
        let zb = bias(z);
        let mut chunks = cells.chunks_exact(8);
        let (mut n, mut lo, mut hi) = (0u32, i16::MAX, i16::MIN);
        for ch in &mut chunks {
            let v: [i16; 8] = core::array::from_fn(|k| at(&ch[k]));
            n += v.iter().map(|&d| (zb < d) as u32).sum::<u32>();
            lo = v.iter().fold(lo, |m, &d| m.min(d));
            hi = v.iter().fold(hi, |m, &d| m.max(d));
        }
        for c in chunks.remainder() {
            let d = at(c);
            (n, lo, hi) = (n + (zb < d) as u32, lo.min(d), hi.max(d));
        }
        let unbias = |d: i16| d as u16 ^ 0x8000;
        (n, unbias(lo), unbias(hi))
    }

    /// Storage of a [`DepthBits`] plane: depth in 16.`FRAC` in cells `T`.
    pub struct ZPlane<T, const FRAC: u32, const N: usize>(Plane<T, N>);

    impl<T: Cell, const FRAC: u32, const N: usize> ZPlane<T, FRAC, N> {
        /// Largest stored value: 65535 with every fraction bit set.
        const MAX: u32 = (0x1_0000 << FRAC) - 1;

        /// An interpolated 16.14 depth at the plane's precision. The DDA keeps
        /// `z <= 2^30 + 2^13` plus its drift; clamp anyway: never wrap.
        #[inline(always)]
        fn stored(z: i32) -> u32 {
            (z >> (crate::numeric::Z_FRAC - FRAC)).clamp(0, Self::MAX as i32) as u32
        }

        /// `stored(z) < cell` for the test without the write, compared in
        /// 16.14 with the cell shifted up: `max(z, 0) < cell 2^(14 - FRAC)`
        /// (a floor does not change a compare with a multiple of the
        /// step, and a cell is at most `MAX`). On the Cortex-M4 a clamp
        /// and one compare with a shifted operand instead of a shift, a
        /// clamp and a compare: the translucent workload 5,186 -> 5,096
        /// ticks (measured). The test that writes keeps `stored(z)`
        /// first: it stores it, and comparing `z` there cost the fast-Phong
        /// loop a spilled register (5,057 -> 5,216 ticks, measured).
        #[inline(always)]
        fn nearer(z: i32, cell: u32) -> bool {
            z.max(0) < (cell << (crate::numeric::Z_FRAC - FRAC)) as i32
        }

        /// The test that writes, of a depth `z` already at the plane's
        /// precision.
        #[inline(always)]
        fn test_and_store(&mut self, i: usize, z: u32) -> bool {
            let cell = &mut self.0 .0.as_flattened_mut()[i];
            if z < cell.to_u32() {
                *cell = T::from_u32(z);
                true
            } else {
                false
            }
        }
    }

    impl<T: Cell, const FRAC: u32, const N: usize> DepthPlane for ZPlane<T, FRAC, N> {
        const NEW: Self = ZPlane(<Plane<T, N> as ColorPlane>::NEW);
        #[inline(always)]
        fn put(&mut self, i: usize, z: u16) {
            self.0 .0.as_flattened_mut()[i] = T::from_u32((z as u32) << FRAC);
        }
        #[inline(always)]
        fn put_range(&mut self, r: core::ops::Range<usize>, z: u16) {
            ColorPlane::fill(&mut self.0, r, (z as u32) << FRAC);
        }
        #[inline(always)]
        fn read(&self, i: usize) -> u16 {
            (self.0 .0.as_flattened()[i].to_u32() >> FRAC) as u16
        }
        #[inline(always)]
        fn test(&self, i: usize, z: i32) -> bool {
            Self::nearer(z, self.0 .0.as_flattened()[i].to_u32())
        }
        fn farther(&self, r: core::ops::Range<usize>, z: u16, limit: u32) -> u32 {
            let cells = &self.0 .0.as_flattened()[r];
            if limit as usize >= cells.len() {
                // No early stop possible: a branch-free count.
                return cells
                    .iter()
                    .map(|c| (z < (c.to_u32() >> FRAC) as u16) as u32)
                    .sum();
            }
            let mut n = 0;
            for c in cells {
                n += (z < (c.to_u32() >> FRAC) as u16) as u32;
                if n >= limit {
                    break;
                }
            }
            n
        }
        fn farther_min_max(&self, r: core::ops::Range<usize>, z: u16) -> (u32, u16, u16) {
            let cells = &self.0 .0.as_flattened()[r];
            if crate::numeric::MCU32 {
                farther_min_max_each::<T, FRAC>(cells, z)
            } else {
                farther_min_max_lanes::<T, FRAC>(cells, z)
            }
        }
        #[inline(always)]
        fn test_and_set(&mut self, i: usize, z: i32) -> bool {
            self.test_and_store(i, Self::stored(z))
        }
        #[inline(always)]
        fn test_and_set_in_range(&mut self, i: usize, z: i32) -> bool {
            debug_assert!((0..1 << 30).contains(&z));
            // `stored(z)`, whose clamp cannot act below 2^30.
            self.test_and_store(i, z as u32 >> (crate::numeric::Z_FRAC - FRAC))
        }
    }

    impl DepthPlane for () {
        const NEW: Self = ();
        #[inline(always)]
        fn present(&self) -> bool {
            false
        }
        #[inline(always)]
        fn put(&mut self, _: usize, _: u16) {}
        #[inline(always)]
        fn read(&self, _: usize) -> u16 {
            u16::MAX
        }
        #[inline(always)]
        fn test_and_set(&mut self, _: usize, _: i32) -> bool {
            true
        }
        #[inline(always)]
        fn test(&self, _: usize, _: i32) -> bool {
            true
        }
        fn farther(&self, r: core::ops::Range<usize>, z: u16, limit: u32) -> u32 {
            if z < u16::MAX {
                (r.len() as u32).min(limit)
            } else {
                0
            }
        }
        fn farther_min_max(&self, r: core::ops::Range<usize>, z: u16) -> (u32, u16, u16) {
            (self.farther(r, z, u32::MAX), u16::MAX, u16::MAX)
        }
    }

    impl<const N: usize> WidPlane for Plane<u8, N> {
        const NEW: Self = <Self as ColorPlane>::NEW;
        #[inline(always)]
        fn put(&mut self, i: usize, id: u8) {
            self.0.as_flattened_mut()[i] = id;
        }
        #[inline(always)]
        fn put_range(&mut self, r: core::ops::Range<usize>, id: u8) {
            ColorPlane::fill(self, r, id as u32);
        }
        #[inline(always)]
        fn read(&self, i: usize) -> u8 {
            self.0.as_flattened()[i].to_u32() as u8
        }
        #[inline(always)]
        fn pass(&self, i: usize, id: u8) -> bool {
            self.0.as_flattened()[i] == id
        }
    }

    impl WidPlane for () {
        const NEW: Self = ();
        #[inline(always)]
        fn present(&self) -> bool {
            false
        }
        #[inline(always)]
        fn put(&mut self, _: usize, _: u8) {}
        #[inline(always)]
        fn read(&self, _: usize) -> u8 {
            0
        }
        #[inline(always)]
        fn pass(&self, _: usize, _: u8) -> bool {
            true
        }
    }

    /// The switch of a [`Switch`] plane, the same for both plane traits.
    macro_rules! switch_flag {
        ($plane:ident) => {
            const NEW: Self = Switch {
                off: false,
                plane: <P as $plane>::NEW,
            };
            #[inline(always)]
            fn present(&self) -> bool {
                !self.off
            }
            #[inline(always)]
            fn set_present(&mut self, on: bool) {
                self.off = !on;
            }
        };
    }

    /// Storage of a [`Switchable`] plane: plane `P` and whether it is
    /// off; off, every method answers as the absent plane `()` does. (The
    /// flag says *off* so that a new plane is all zero bits: a boxed tile
    /// is then zeroed in place, not built on the stack and copied.)
    pub struct Switch<P> {
        off: bool,
        plane: P,
    }

    impl<P: DepthPlane> DepthPlane for Switch<P> {
        switch_flag!(DepthPlane);
        #[inline(always)]
        fn put(&mut self, i: usize, z: u16) {
            if !self.off {
                DepthPlane::put(&mut self.plane, i, z);
            }
        }
        #[inline(always)]
        fn put_range(&mut self, r: core::ops::Range<usize>, z: u16) {
            if !self.off {
                DepthPlane::put_range(&mut self.plane, r, z);
            }
        }
        #[inline(always)]
        fn read(&self, i: usize) -> u16 {
            if !self.off {
                DepthPlane::read(&self.plane, i)
            } else {
                DepthPlane::read(&(), i)
            }
        }
        #[inline(always)]
        fn test_and_set(&mut self, i: usize, z: i32) -> bool {
            self.off || self.plane.test_and_set(i, z)
        }
        #[inline(always)]
        fn test_and_set_in_range(&mut self, i: usize, z: i32) -> bool {
            self.off || self.plane.test_and_set_in_range(i, z)
        }
        #[inline(always)]
        fn test(&self, i: usize, z: i32) -> bool {
            self.off || self.plane.test(i, z)
        }
        fn farther(&self, r: core::ops::Range<usize>, z: u16, limit: u32) -> u32 {
            if !self.off {
                self.plane.farther(r, z, limit)
            } else {
                ().farther(r, z, limit)
            }
        }
        fn farther_min_max(&self, r: core::ops::Range<usize>, z: u16) -> (u32, u16, u16) {
            if !self.off {
                self.plane.farther_min_max(r, z)
            } else {
                ().farther_min_max(r, z)
            }
        }
    }

    impl<P: WidPlane> WidPlane for Switch<P> {
        switch_flag!(WidPlane);
        #[inline(always)]
        fn put(&mut self, i: usize, id: u8) {
            if !self.off {
                WidPlane::put(&mut self.plane, i, id);
            }
        }
        #[inline(always)]
        fn put_range(&mut self, r: core::ops::Range<usize>, id: u8) {
            if !self.off {
                self.plane.put_range(r, id);
            }
        }
        #[inline(always)]
        fn read(&self, i: usize) -> u8 {
            if !self.off {
                WidPlane::read(&self.plane, i)
            } else {
                WidPlane::read(&(), i)
            }
        }
        #[inline(always)]
        fn pass(&self, i: usize, id: u8) -> bool {
            self.off || self.plane.pass(i, id)
        }
    }
}

#[cfg(feature = "unstable")]
pub use planes::{DepthPlane, Switch, WidPlane, ZPlane};
#[cfg(not(feature = "unstable"))]
pub(crate) use planes::{DepthPlane, Switch, WidPlane, ZPlane};

#[cfg(test)]
mod tests {
    use super::planes::{DepthPlane, ZPlane};

    /// Both Z tests compare the depth clamped to the plane's range and
    /// rounded down to its precision with the cell (the test without the
    /// write in 16.14, the cell shifted up), ties failing; what passes is
    /// stored clamped. Every plane precision, the extremes included.
    #[test]
    fn z_tests_compare_the_clamped_depth_and_store_it() {
        fn check<P: DepthPlane>(frac: u32) {
            let sh = 14 - frac;
            let max = (0x1_0000u32 << frac) - 1;
            for cell in [0u32, 1, 2, 0x7fff << frac, max - 1, max] {
                let zs = [
                    i32::MIN,
                    -(1 << 14),
                    -1,
                    0,
                    (cell << sh) as i32 - 1,
                    (cell << sh) as i32,
                    (cell << sh) as i32 + 1,
                    1 << 30,
                    i32::MAX,
                ];
                for z in zs {
                    let mut p = P::NEW;
                    // Cell 0 holds `cell` (its integer part for `put`).
                    p.put(0, (cell >> frac) as u16);
                    let stored = (cell >> frac) << frac;
                    let pass = ((z >> sh).clamp(0, max as i32) as u32) < stored;
                    assert_eq!(p.test(0, z), pass, "{frac} {cell} {z}");
                    assert_eq!(p.test_and_set(0, z), pass, "{frac} {cell} {z}");
                    let kept = if pass {
                        (z >> sh).clamp(0, max as i32) as u32 >> frac
                    } else {
                        cell >> frac
                    };
                    assert_eq!(p.read(0) as u32, kept, "{frac} {cell} {z}");
                }
            }
        }
        check::<ZPlane<u16, 0, 1>>(0);
        check::<ZPlane<[u8; 3], 8, 1>>(8);
        check::<ZPlane<u32, 14, 1>>(14);
    }

    /// The refresh's two forms (a cell at a time on a microcontroller,
    /// eight at a time on a host) agree on random runs of every length up
    /// to 40 and every depth at a run's extremes, 0 and 65535 included.
    #[test]
    fn refresh_scans_agree() {
        use super::planes::{farther_min_max_each, farther_min_max_lanes};
        use crate::numeric::xorshift;
        let mut next = xorshift(0x2545_f491);
        for len in 0..=40usize {
            for round in 0..50 {
                let cells: [u16; 40] = core::array::from_fn(|_| match round % 3 {
                    // Every value, the extremes, a narrow band.
                    0 => next() as u16,
                    1 => [0, 1, 0x7fff, 0x8000, 0xfffe, 0xffff][next() as usize % 6],
                    _ => 0x8000 + (next() % 5) as u16 - 2,
                });
                let cells = &cells[..len];
                let zs = [0, 1, 0x7fff, 0x8000, 0xffff, next() as u16];
                for z in zs.into_iter().chain(cells.iter().copied()) {
                    assert_eq!(
                        farther_min_max_lanes::<u16, 0>(cells, z),
                        farther_min_max_each::<u16, 0>(cells, z),
                        "{cells:?} {z}"
                    );
                }
                let wide: [u32; 40] = core::array::from_fn(|_| (next() as u32) >> 2);
                let z = next() as u16;
                assert_eq!(
                    farther_min_max_lanes::<u32, 14>(&wide[..len], z),
                    farther_min_max_each::<u32, 14>(&wide[..len], z)
                );
            }
        }
    }
}
