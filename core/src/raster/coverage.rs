//! Coverage antialiasing (seed 000, "RUF buffer"): sample patterns,
//! coverage masks computed exactly from the integer edge functions, the RUF
//! buffer's per-pixel update (eqs. 1-3, 6, 7) and, in the same terms,
//! supersampling with one colour and one depth per sample.
//!
//! **Samples.** A pattern is `M` positions inside the pixel, in 1/16 pixel
//! from its centre — the sub-pixel grid of the vertices, so every edge
//! function at a sample is an exact integer and the top-left rule decides
//! ties exactly as for pixel centres: two triangles sharing an edge cover
//! complementary samples. The paper's figure of its 8 sparse points cannot
//! be read from the seed's text, so the sparse patterns are the standard
//! Direct3D / Vulkan ones ([`Sparse4`], [`Sparse8`], [`Sparse16`]); the
//! regular grids [`Grid4x4`] and [`Grid8x8`] serve as references, and
//! [`Centre1`] is the aliased pipeline's single sample.
//!
//! **Fragments.** A triangle gives a pixel one fragment: its coverage mask
//! `M_if`, a depth per covered sample and one colour (Gouraud at the pixel
//! centre, clamped to the vertex colours' range), as in the A-buffer.
//!
//! **RUF update** (`RufPixel::update`), for a fragment with object tag
//! `t`:
//! 1. survived mask `M_sur` = covered samples whose depth passes (eq. 1);
//! 2. colour `C_ff += C_if N(M_sur)/T - C_RUF N(M_sur & M_RUF)/T - Ĉ N(M_sur & M_ff & !M_RUF)/T`
//!    (eqs. 2, 3): add the survivor, remove what the hidden samples
//!    contributed — exactly where the RUF buffer knows it, estimated by the
//!    pixel's current mean colour `Ĉ` elsewhere (eq. 3's fourth term);
//! 3. `M_ff |= M_sur`, depths written;
//! 4. RUF write: same tag and exclusive masks, merge (eqs. 6, 7);
//!    otherwise replace.
//!
//! The background is not a fragment: `C_ff` sums only covered samples, and
//! `RufPixel::resolve` adds the clear colour for the samples no fragment
//! covered. With a full mask `Ĉ = C_ff`, which is the paper's fourth term
//! literally; with a partial one the mean is taken over covered samples
//! only, so the background never enters the estimate.
//!
//! **Accumulator.** `C_ff` is kept per channel in 8.8 fixed point (`u16`):
//! each update rounds its terms to 1/256 of a level and the result is
//! clamped to `[0, 255 N(M_ff) / T]` (the range a sum of covered samples can
//! have), so rounding and the estimate can neither wrap nor drift outside
//! the colours that were drawn. The tests bound the error after hundreds of
//! fragments in adversarial orders.

use crate::format::Rgb;
use crate::geom::cell_bounds;
use crate::geom::Rect;
use crate::geom::Vertex;
use crate::numeric::{div_round, SUBPIXEL};
use crate::setup::oriented_edges;

/// A set of sample positions in a pixel.
pub trait SamplePattern: Copy + Default + core::fmt::Debug {
    /// Samples per pixel, `T_m` in the paper (at most 64).
    const M: usize;
    /// Sample offsets from the pixel centre, in 1/16 pixel, each in `-8..8`.
    const OFFSETS: &'static [(i8, i8)];
    /// Short name, e.g. `"sparse8"`.
    const NAME: &'static str;
}

macro_rules! pattern {
    ($(#[$doc:meta])* $name:ident, $label:literal, [$(($x:expr, $y:expr)),* $(,)?]) => {
        $(#[$doc])*
        #[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
        pub struct $name;
        impl SamplePattern for $name {
            const OFFSETS: &'static [(i8, i8)] = &[$(($x, $y)),*];
            const M: usize = Self::OFFSETS.len();
            const NAME: &'static str = $label;
        }
    };
}

pattern!(
    /// One sample at the pixel centre: the aliased pipeline.
    Centre1, "1 sample", [(0, 0)]
);
pattern!(
    /// Direct3D / Vulkan standard 4-sample pattern.
    Sparse4, "4 sparse", [(-2, -6), (6, -2), (-6, 2), (2, 6)]
);
pattern!(
    /// Direct3D / Vulkan standard 8-sample pattern (stands in for the
    /// paper's 8 sparse points).
    Sparse8, "8 sparse", [(1, -3), (-1, 3), (5, 1), (-3, -5), (-5, 5), (-7, -1), (3, 7), (7, -7)]
);
pattern!(
    /// Direct3D / Vulkan standard 16-sample pattern.
    Sparse16, "16 sparse", [
        (1, 1), (-1, -3), (-3, 2), (4, -1), (-5, -2), (2, 5), (5, 3), (3, -5),
        (-2, 6), (0, -7), (-4, -6), (-6, 4), (-8, 0), (7, -4), (6, 7), (-7, -8),
    ]
);
pattern!(
    /// A regular 4x4 grid at `(i + 1/2) / 4`.
    Grid4x4, "4x4 grid", [
        (-6, -6), (-2, -6), (2, -6), (6, -6), (-6, -2), (-2, -2), (2, -2), (6, -2),
        (-6, 2), (-2, 2), (2, 2), (6, 2), (-6, 6), (-2, 6), (2, 6), (6, 6),
    ]
);
pattern!(
    /// A regular 8x8 grid at `(i + 1/2) / 8`: the paper's reference.
    Grid8x8, "8x8 grid", [
        (-7, -7), (-5, -7), (-3, -7), (-1, -7), (1, -7), (3, -7), (5, -7), (7, -7),
        (-7, -5), (-5, -5), (-3, -5), (-1, -5), (1, -5), (3, -5), (5, -5), (7, -5),
        (-7, -3), (-5, -3), (-3, -3), (-1, -3), (1, -3), (3, -3), (5, -3), (7, -3),
        (-7, -1), (-5, -1), (-3, -1), (-1, -1), (1, -1), (3, -1), (5, -1), (7, -1),
        (-7, 1), (-5, 1), (-3, 1), (-1, 1), (1, 1), (3, 1), (5, 1), (7, 1),
        (-7, 3), (-5, 3), (-3, 3), (-1, 3), (1, 3), (3, 3), (5, 3), (7, 3),
        (-7, 5), (-5, 5), (-3, 5), (-1, 5), (1, 5), (3, 5), (5, 5), (7, 5),
        (-7, 7), (-5, 7), (-3, 7), (-1, 7), (1, 7), (3, 7), (5, 7), (7, 7),
    ]
);

/// A coverage mask: bit `i` is sample `i` of the pattern.
pub type Mask = u64;

/// How a pixel stores a mask: the smallest unsigned integer with `M` bits.
pub trait MaskBits: Copy + Default + PartialEq + Eq + core::fmt::Debug {
    /// Widens to a [`Mask`].
    fn get(self) -> Mask;
    /// Narrows a mask that fits.
    fn put(m: Mask) -> Self;
    /// No sample.
    const DEFAULT_ZERO: Self;
}

macro_rules! mask_bits {
    ($($t:ty),*) => {$(
        impl MaskBits for $t {
            #[inline(always)]
            fn get(self) -> Mask {
                self as Mask
            }
            #[inline(always)]
            fn put(m: Mask) -> Self {
                m as $t
            }
            const DEFAULT_ZERO: Self = 0;
        }
    )*};
}
mask_bits!(u8, u16, u32, u64);

/// `N(m)`: covered samples.
#[inline]
pub fn count(m: Mask) -> u32 {
    m.count_ones()
}

/// The mask of all `M` samples.
#[inline]
pub const fn full<P: SamplePattern>() -> Mask {
    full_m(P::M)
}

const fn full_m(m: usize) -> Mask {
    if m >= 64 {
        u64::MAX
    } else {
        (1u64 << m) - 1
    }
}

/// Coverage of one pixel by the half-planes `e_i(p) - bias_i >= 0`, given
/// each edge's value at the pixel centre and its change per sub-pixel step
/// in x and y (`e(centre + o) = e + dx o.x + dy o.y`, exact integers).
///
/// ```
/// use tilerast::coverage::{mask, Sparse4, SamplePattern};
/// // The half-plane x >= centre: E = 16 x' with x' the offset in 1/16 px.
/// let m = mask::<Sparse4>(&[(0, 1, 0, 0)]);
/// // Sparse4's samples with x >= 0: (6, -2) and (2, 6); bit 1 and bit 3.
/// assert_eq!(m, 0b1010);
/// ```
pub fn mask<P: SamplePattern>(edges: &[(i64, i64, i64, i64)]) -> Mask {
    let mut m = 0;
    for (k, &(ox, oy)) in P::OFFSETS.iter().enumerate() {
        let inside = edges
            .iter()
            .all(|&(e, dx, dy, bias)| e + dx * ox as i64 + dy * oy as i64 - bias >= 0);
        m |= (inside as Mask) << k;
    }
    m
}

/// The samples of pixel `(px, py)` inside triangle `v`, with the pipeline's
/// fill rule; 0 for a zero-area triangle.
///
/// ```
/// use tilerast::coverage::{triangle_mask, full, Sparse8};
/// use tilerast::prelude::*;
/// let v = |x: i32, y: i32| Vertex::new(Coord::from_num(x), Coord::from_num(y), 0, Rgb::default());
/// // Two triangles sharing the diagonal of pixel (0, 0): complementary samples.
/// let (a, b) = ([v(0, 0), v(1, 0), v(1, 1)], [v(0, 0), v(1, 1), v(0, 1)]);
/// let (ma, mb) = (triangle_mask::<Sparse8>(&a, 0, 0), triangle_mask::<Sparse8>(&b, 0, 0));
/// assert_eq!((ma & mb, ma | mb), (0, full::<Sparse8>()));
/// ```
pub fn triangle_mask<P: SamplePattern>(v: &[Vertex; 3], px: i64, py: i64) -> Mask {
    let Some((e, _, _)) = oriented_edges(v) else {
        return 0;
    };
    // e(centre + o) = e(centre) + (a / 16) o.x + (step / 16) o.y, exactly.
    let s = SUBPIXEL;
    mask::<P>(&e.map(|e| (e.a * px + e.row(py), e.a / s, e.step / s, e.bias)))
}

/// Colour channels of an 8.8 accumulator.
fn lanes(c: Rgb) -> [i32; 3] {
    [c.r as i32, c.g as i32, c.b as i32]
}

/// `v * n / d` rounded to nearest, for non-negative operands.
#[inline]
fn scale(v: i32, n: u32, d: u32) -> i32 {
    ((v as i64 * n as i64 * 2 + d as i64) / (2 * d as i64)) as i32
}

/// Seed 000 Table 3: bits per pixel of the RUF scheme, `2 (m + C) + m Z + tag`.
///
/// ```
/// use tilerast::coverage::{ruf_bits, ss_bits};
/// // The paper's C = Z = 32, tag = 16: 8 samples, 64 vs 44 bytes.
/// assert_eq!((ss_bits(8, 32, 32) / 8, ruf_bits(8, 32, 32, 16) / 8), (64, 44));
/// ```
pub const fn ruf_bits(m: u32, c: u32, z: u32, tag: u32) -> u32 {
    2 * (m + c) + m * z + tag
}

/// Seed 000 Table 3: bits per pixel of supersampling, `m (C + Z)`.
pub const fn ss_bits(m: u32, c: u32, z: u32) -> u32 {
    m * (c + z)
}

/// The coverage state of a tile's pixels ([`crate::tile::Tile`]'s sixth
/// type parameter): none, the RUF buffer, supersampling, or area sampling
/// through the α-channel ([`crate::area::AreaAa`], no plane).
pub trait AaMode: 'static {
    /// Samples per pixel; 0 without coverage antialiasing.
    const SAMPLES: usize;
    /// Whether triangles' flagged edges are area-sampled
    /// ([`crate::area`]); compiled out where `false`.
    const AREA: bool = false;
    /// The sample positions.
    type Pattern: SamplePattern;
    /// Storage for `8 N` pixels (`()` for none).
    type Plane<const N: usize>: AaPlane;
    /// Name, e.g. `"RUF-8"`.
    const NAME: &'static str;
}

/// No coverage antialiasing: no plane, no cost.
#[derive(Debug, Clone, Copy, Default)]
pub struct NoAa;

impl AaMode for NoAa {
    const SAMPLES: usize = 0;
    type Pattern = Centre1;
    type Plane<const N: usize> = ();
    const NAME: &'static str = "none";
}

/// The RUF buffer with `M` samples at pattern `P`, masks stored as `B`.
#[derive(Debug, Clone, Copy, Default)]
pub struct Ruf<const M: usize, P, B = u64>(core::marker::PhantomData<(P, B)>);

/// Supersampling with `M` samples at pattern `P`: colour and depth each.
#[derive(Debug, Clone, Copy, Default)]
pub struct Ss<const M: usize, P>(core::marker::PhantomData<P>);

/// RUF buffer, 4 sparse samples.
pub type Ruf4 = Ruf<4, Sparse4, u8>;
/// RUF buffer, 8 sparse samples (the paper's configuration).
pub type Ruf8 = Ruf<8, Sparse8, u8>;
/// RUF buffer, 16 sparse samples.
pub type Ruf16 = Ruf<16, Sparse16, u16>;
/// Supersampling at the pixel centre only (the aliased result, through the
/// coverage path).
pub type Ss1 = Ss<1, Centre1>;
/// Supersampling, 4 sparse samples.
pub type Ss4 = Ss<4, Sparse4>;
/// Supersampling, 8 sparse samples (the paper's "8ss").
pub type Ss8 = Ss<8, Sparse8>;
/// Supersampling, 16 sparse samples.
pub type Ss16 = Ss<16, Sparse16>;
/// Supersampling on a regular 4x4 grid.
pub type SsGrid4 = Ss<16, Grid4x4>;
/// Supersampling on a regular 8x8 grid (the paper's reference).
pub type SsGrid8 = Ss<64, Grid8x8>;

impl<const M: usize, P: SamplePattern + 'static, B: MaskBits + 'static> AaMode for Ruf<M, P, B> {
    const SAMPLES: usize = {
        assert!(M == P::M && M <= 8 * core::mem::size_of::<B>());
        M
    };
    type Pattern = P;
    type Plane<const N: usize> = Cells<RufPixel<M, B>, N>;
    const NAME: &'static str = P::NAME;
}

impl<const M: usize, P: SamplePattern + 'static> AaMode for Ss<M, P> {
    const SAMPLES: usize = {
        assert!(M == P::M);
        M
    };
    type Pattern = P;
    type Plane<const N: usize> = Cells<SsPixel<M>, N>;
    const NAME: &'static str = P::NAME;
}

/// Coverage pixels (the RUF buffer and supersampling), their storage and the fragments of a triangle: the coverage plane's internals.
/// Public only with the `unstable` feature (the research crate and the
/// tests use them); no stability promise.
mod pixel {
    #![allow(unused_imports)]
    use super::*;

    /// The depth of a fragment at each sample, from the triangle's plane
    /// equation: `z = sum z_k E_k / area2` with the edge functions `E_k` exact
    /// at the sample (one `i64` division per sample).
    #[derive(Debug, Clone, Copy)]
    pub struct SampleDepth {
        /// Per edge: value at the pixel centre, change per 1/16 px in x and y.
        e: [(i64, i64, i64); 3],
        z: [i64; 3],
        area2: i64,
        offsets: &'static [(i8, i8)],
    }

    impl SampleDepth {
        /// Depth at sample `k`, rounded, clamped to 16 bits.
        pub fn at(&self, k: usize) -> u16 {
            let (ox, oy) = self.offsets[k];
            let n: i64 = (0..3)
                .map(|i| {
                    let (e, dx, dy) = self.e[i];
                    self.z[i] * (e + dx * ox as i64 + dy * oy as i64)
                })
                .sum();
            div_round(n, self.area2).clamp(0, 0xFFFF) as u16
        }
    }

    /// The fragments of triangle `v` on the pixels of `clip`: for every pixel
    /// whose cell the triangle's box meets and whose mask is not empty, calls
    /// `f(px, py, mask, colour, depth)` with the Gouraud colour at the pixel
    /// centre (clamped to the vertex colours' range, since the centre of an
    /// edge pixel can lie outside) and the depth at each sample.
    ///
    /// ```
    /// use tilerast::coverage::{fragments, Sparse4};
    /// use tilerast::prelude::*;
    /// let v = |x: i32, y: i32| Vertex::new(Coord::from_num(x), Coord::from_num(y), 100, Rgb::new(9, 9, 9));
    /// let mut n = 0;
    /// fragments::<Sparse4>(&[v(0, 0), v(4, 0), v(0, 4)], &Rect::new(0, 0, 8, 8), |_, _, m, c, z| {
    ///     n += 1;
    ///     assert!(m != 0 && c == Rgb::new(9, 9, 9) && z.at(0) == 100);
    /// });
    /// assert_eq!(n, 10); // 4 + 3 + 2 + 1 pixels touch the triangle
    /// ```
    pub fn fragments<P: SamplePattern>(
        v: &[Vertex; 3],
        clip: &Rect,
        mut f: impl FnMut(i64, i64, Mask, Rgb, &SampleDepth),
    ) {
        let Some((e, area2, swapped)) = oriented_edges(v) else {
            return;
        };
        let vv = if swapped { [v[0], v[2], v[1]] } else { *v };
        let Some(r) = cell_bounds(v).intersect(clip) else {
            return;
        };
        let (x0, x1, y0, y1) = (r.x as i64, r.x1() - 1, r.y as i64, r.y1() - 1);
        let s = SUBPIXEL;
        let cs = vv.map(|v| [v.color.r, v.color.g, v.color.b].map(|c| c as i64));
        let range = |ch: usize| {
            cs.iter()
                .fold((255, 0), |(l, h), c| (c[ch].min(l), c[ch].max(h)))
        };
        let ranges = [range(0), range(1), range(2)];
        for py in y0..=y1 {
            for px in x0..=x1 {
                let ec = e.map(|e| e.a * px + e.row(py));
                let m =
                    mask::<P>(&[0, 1, 2].map(|k| (ec[k], e[k].a / s, e[k].step / s, e[k].bias)));
                if m == 0 {
                    continue;
                }
                let ch = |k: usize| {
                    let n: i64 = (0..3).map(|i| cs[i][k] * ec[i]).sum();
                    div_round(n, area2).clamp(ranges[k].0, ranges[k].1) as u8
                };
                let depth = SampleDepth {
                    e: [0, 1, 2].map(|k| (ec[k], e[k].a / s, e[k].step / s)),
                    z: vv.map(|v| v.z as i64),
                    area2,
                    offsets: P::OFFSETS,
                };
                f(px, py, m, Rgb::new(ch(0), ch(1), ch(2)), &depth);
            }
        }
    }

    /// One fragment: a triangle's part of a pixel.
    #[derive(Debug, Clone, Copy)]
    pub struct Fragment<const M: usize> {
        /// `M_if`: the samples the triangle covers.
        pub mask: Mask,
        /// Depth at each sample (only covered ones are read).
        pub z: [u16; M],
        /// The fragment's one colour.
        pub color: Rgb,
        /// Object tag: fragments of one object (an OBJ group) share it.
        pub tag: u16,
    }

    /// The frame-buffer pixel and the RUF buffer entry of one pixel
    /// (seed 000 Fig. 2) for `M` samples, masks stored as `B`.
    ///
    /// Fields are ordered largest first so that `size_of` adds no padding
    /// beyond rounding the whole to 2 bytes.
    #[derive(Debug, Clone, Copy, PartialEq, Eq)]
    pub struct RufPixel<const M: usize, B: MaskBits = u64> {
        /// Depth per sample.
        pub z: [u16; M],
        /// `C_ff`: sum over covered samples of their colour / `T`, 8.8 fixed point.
        pub c_ff: [u16; 3],
        /// The RUF fragment's object tag.
        pub tag: u16,
        /// `M_ff`: samples some fragment covers.
        pub m_ff: B,
        /// `M_RUF`: the samples of the most recently used fragment.
        pub m_ruf: B,
        /// `C_RUF`: its colour.
        pub c_ruf: Rgb,
    }

    impl<const M: usize, B: MaskBits> RufPixel<M, B> {
        /// A cleared pixel: nothing covered, every depth `z`.
        pub const fn new(z: u16) -> Self {
            RufPixel {
                z: [z; M],
                c_ff: [0; 3],
                tag: 0,
                m_ff: B::DEFAULT_ZERO,
                m_ruf: B::DEFAULT_ZERO,
                c_ruf: Rgb::new(0, 0, 0),
            }
        }

        /// Applies one fragment (eqs. 1-3, 6, 7); returns the survived mask.
        ///
        /// ```
        /// use tilerast::coverage::{Fragment, RufPixel};
        /// use tilerast::format::Rgb;
        /// let mut p = RufPixel::<8>::new(u16::MAX);
        /// let red = Fragment { mask: 0b0000_0011, z: [10; 8], color: Rgb::new(255, 0, 0), tag: 1 };
        /// assert_eq!(p.update(&red), 0b11);
        /// // Two of eight samples red over a black background: a quarter red.
        /// assert_eq!(p.resolve(Rgb::new(0, 0, 0)), Rgb::new(64, 0, 0));
        /// ```
        pub fn update(&mut self, f: &Fragment<M>) -> Mask {
            self.update_with(f.mask, |i| f.z[i], true, f.color, f.tag)
        }

        /// [`Self::update`] with the fragment's depth at sample `i` given by
        /// `z(i)` (called for covered samples only); without `depth_test`
        /// every covered sample survives (a tile without a depth plane draws
        /// in painter's order).
        pub fn update_with(
            &mut self,
            mask: Mask,
            mut z: impl FnMut(usize) -> u16,
            depth_test: bool,
            color: Rgb,
            tag: u16,
        ) -> Mask {
            // Eq. 1: survived samples.
            let mut sur: Mask = 0;
            let mut zs = [0u16; M];
            for (i, zi) in zs.iter_mut().enumerate() {
                if mask >> i & 1 != 0 {
                    *zi = z(i);
                    if !depth_test || *zi < self.z[i] {
                        sur |= 1 << i;
                    }
                }
            }
            if sur == 0 {
                return 0;
            }
            let (m_ff, m_ruf) = (self.m_ff.get(), self.m_ruf.get());
            let t = M as u32;
            let (n_sur, n_ruf) = (count(sur), count(sur & m_ruf));
            let n_est = count(sur & m_ff & !m_ruf);
            // Covered samples the RUF entry does not explain: where the
            // estimated ones come from.
            let n_other = count(m_ff & !m_ruf);
            let n_in_ruf = count(m_ruf);
            let m_new = m_ff | sur;
            let hi = scale(255 << 8, count(m_new), t);
            let (cif, cruf) = (lanes(color), lanes(self.c_ruf));
            // Eqs. 2 and 3, per channel, in 8.8.
            for ch in 0..3 {
                let cff = self.c_ff[ch] as i32;
                let mut v = cff + scale(cif[ch] << 8, n_sur, t) - scale(cruf[ch] << 8, n_ruf, t);
                if n_est > 0 {
                    // Eq. 3's fourth term. Ĉ is the mean colour of the covered
                    // samples outside the RUF entry — the sum C_ff minus the RUF
                    // entry's share, over their count — times N(est) / T.
                    let others = (cff - scale(cruf[ch] << 8, n_in_ruf, t)).max(0);
                    v -= scale(others, n_est, n_other);
                }
                self.c_ff[ch] = v.clamp(0, hi) as u16;
            }
            self.m_ff = B::put(m_new);
            for (i, zi) in zs.iter().enumerate() {
                if sur >> i & 1 != 0 {
                    self.z[i] = *zi;
                }
            }
            // Eqs. 6 and 7: merge fragments of one object, else replace. The
            // paper merges because neighbouring polygons of one object give
            // exclusive fragments; a fragment of the same object that hides part
            // of the RUF fragment (a fold, a back face) is not that case and
            // replaces it, so the RUF colour stays one surface's.
            if tag == self.tag && m_ruf != 0 && sur & m_ruf == 0 {
                let keep = count(m_ruf);
                let merged = m_ruf | sur;
                let n = count(merged);
                let mix =
                    |old: u8, new: u8| ((old as u32 * keep + new as u32 * n_sur + n / 2) / n) as u8;
                self.c_ruf = Rgb::new(
                    mix(self.c_ruf.r, color.r),
                    mix(self.c_ruf.g, color.g),
                    mix(self.c_ruf.b, color.b),
                );
                self.m_ruf = B::put(merged);
            } else {
                self.tag = tag;
                self.m_ruf = B::put(sur);
                self.c_ruf = color;
            }
            sur
        }

        /// Forgets every fragment: an area fill paints the pixel's background
        /// (kept by the caller, e.g. the tile's colour plane), which no later
        /// fragment needs to subtract — it is what uncovered samples show.
        /// Depths stay (fills do not write Z).
        pub fn uncover(&mut self) {
            self.c_ff = [0; 3];
            self.m_ff = B::DEFAULT_ZERO;
            self.m_ruf = B::DEFAULT_ZERO;
            self.tag = 0;
        }

        /// The covered samples' sum (8.8 per channel, already divided by `T`)
        /// and the number of samples no fragment covers.
        pub fn parts(&self) -> ([u16; 3], u32) {
            (self.c_ff, M as u32 - count(self.m_ff.get()))
        }

        /// The nearest depth of any sample.
        pub fn nearest(&self) -> u16 {
            self.z.iter().copied().min().unwrap_or(u16::MAX)
        }

        /// The pixel's colour: the covered samples' sum plus the background on
        /// the samples no fragment covered, rounded to 8 bits.
        pub fn resolve(&self, background: Rgb) -> Rgb {
            let free = M as u32 - count(self.m_ff.get());
            let bg = lanes(background);
            let ch = |i: usize| {
                let v = self.c_ff[i] as i32 + scale(bg[i] << 8, free, M as u32);
                ((v + 128) >> 8).clamp(0, 255) as u8
            };
            Rgb::new(ch(0), ch(1), ch(2))
        }
    }

    /// A supersampled pixel: colour and depth per sample (`M (C + Z)` bits).
    #[derive(Debug, Clone, Copy, PartialEq, Eq)]
    pub struct SsPixel<const M: usize> {
        /// Colour per sample.
        pub c: [Rgb; M],
        /// Depth per sample.
        pub z: [u16; M],
    }

    impl<const M: usize> SsPixel<M> {
        /// Every sample `color` at depth `z`.
        pub const fn new(color: Rgb, z: u16) -> Self {
            SsPixel {
                c: [color; M],
                z: [z; M],
            }
        }

        /// Z-tests each covered sample and writes the survivors; returns them.
        pub fn update(&mut self, f: &Fragment<M>) -> Mask {
            self.update_with(f.mask, |i| f.z[i], true, f.color)
        }

        /// [`Self::update`] with the depth at sample `i` given by `z(i)`, and
        /// the depth test switched by `depth_test`.
        pub fn update_with(
            &mut self,
            mask: Mask,
            mut z: impl FnMut(usize) -> u16,
            depth_test: bool,
            color: Rgb,
        ) -> Mask {
            let mut sur = 0;
            for i in 0..M {
                if mask >> i & 1 != 0 {
                    let zi = z(i);
                    if !depth_test || zi < self.z[i] {
                        sur |= 1 << i;
                        self.z[i] = zi;
                        self.c[i] = color;
                    }
                }
            }
            sur
        }

        /// The box-filtered colour (rounded mean of the samples).
        pub fn resolve(&self) -> Rgb {
            let mut s = [0u32; 3];
            for c in &self.c {
                s[0] += c.r as u32;
                s[1] += c.g as u32;
                s[2] += c.b as u32;
            }
            let m = M as u32;
            let ch = |v: u32| ((v + m / 2) / m) as u8;
            Rgb::new(ch(s[0]), ch(s[1]), ch(s[2]))
        }
    }

    /// Storage of per-pixel values for `8 N` pixels.
    #[derive(Debug, Clone)]
    pub struct Cells<T, const N: usize>(pub [[T; 8]; N]);

    /// Per-pixel coverage state.
    pub trait AaPlane: Sized {
        /// A plane (contents undefined until cleared).
        const NEW: Self;
        /// Clears pixel `i`: nothing covered, depth `z`, background `bg`.
        fn clear(&mut self, i: usize, z: u16, bg: Rgb);
        /// Applies a fragment to pixel `i`: covered samples, depth per sample
        /// (tested when `test`), colour and object tag.
        fn fragment(
            &mut self,
            i: usize,
            mask: Mask,
            z: impl FnMut(usize) -> u16,
            test: bool,
            c: Rgb,
            tag: u16,
        );
        /// Fills pixel `i` with a colour, no depth test.
        fn fill(&mut self, i: usize, c: Rgb);
        /// Sets every sample's depth.
        fn zfill(&mut self, i: usize, z: u16);
        /// The pixel's covered samples' colour sum divided by the sample count
        /// (8.8 per channel), and the fraction of samples that show the
        /// background, in 1/256 (the caller holds the background colour).
        fn resolve(&self, i: usize) -> ([u16; 3], u32);
        /// The nearest sample depth.
        fn nearest(&self, i: usize) -> u16;
    }

    impl AaPlane for () {
        const NEW: Self = ();
        fn clear(&mut self, _: usize, _: u16, _: Rgb) {}
        fn fragment(
            &mut self,
            _: usize,
            _: Mask,
            _: impl FnMut(usize) -> u16,
            _: bool,
            _: Rgb,
            _: u16,
        ) {
        }
        fn fill(&mut self, _: usize, _: Rgb) {}
        fn zfill(&mut self, _: usize, _: u16) {}
        fn resolve(&self, _: usize) -> ([u16; 3], u32) {
            ([0; 3], 256)
        }
        fn nearest(&self, _: usize) -> u16 {
            u16::MAX
        }
    }

    impl<const M: usize, B: MaskBits, const N: usize> AaPlane for Cells<RufPixel<M, B>, N> {
        const NEW: Self = Cells([[RufPixel::new(u16::MAX); 8]; N]);
        #[inline]
        fn clear(&mut self, i: usize, z: u16, _: Rgb) {
            self.0.as_flattened_mut()[i] = RufPixel::new(z);
        }
        #[inline]
        fn fragment(
            &mut self,
            i: usize,
            mask: Mask,
            z: impl FnMut(usize) -> u16,
            test: bool,
            c: Rgb,
            tag: u16,
        ) {
            self.0.as_flattened_mut()[i].update_with(mask, z, test, c, tag);
        }
        fn fill(&mut self, i: usize, _: Rgb) {
            self.0.as_flattened_mut()[i].uncover();
        }
        fn zfill(&mut self, i: usize, z: u16) {
            self.0.as_flattened_mut()[i].z = [z; M];
        }
        fn resolve(&self, i: usize) -> ([u16; 3], u32) {
            let (sum, free) = self.0.as_flattened()[i].parts();
            (sum, (free * 256 + M as u32 / 2) / M as u32)
        }
        fn nearest(&self, i: usize) -> u16 {
            self.0.as_flattened()[i].nearest()
        }
    }

    impl<const M: usize, const N: usize> AaPlane for Cells<SsPixel<M>, N> {
        const NEW: Self = Cells([[SsPixel::new(Rgb::new(0, 0, 0), u16::MAX); 8]; N]);
        #[inline]
        fn clear(&mut self, i: usize, z: u16, bg: Rgb) {
            self.0.as_flattened_mut()[i] = SsPixel::new(bg, z);
        }
        #[inline]
        fn fragment(
            &mut self,
            i: usize,
            mask: Mask,
            z: impl FnMut(usize) -> u16,
            test: bool,
            c: Rgb,
            _: u16,
        ) {
            self.0.as_flattened_mut()[i].update_with(mask, z, test, c);
        }
        fn fill(&mut self, i: usize, c: Rgb) {
            self.0.as_flattened_mut()[i].c = [c; M];
        }
        fn zfill(&mut self, i: usize, z: u16) {
            self.0.as_flattened_mut()[i].z = [z; M];
        }
        fn resolve(&self, i: usize) -> ([u16; 3], u32) {
            let c = self.0.as_flattened()[i].resolve();
            ([c.r, c.g, c.b].map(|v| (v as u16) << 8), 0)
        }
        fn nearest(&self, i: usize) -> u16 {
            self.0.as_flattened()[i]
                .z
                .iter()
                .copied()
                .min()
                .unwrap_or(u16::MAX)
        }
    }
}

#[cfg(feature = "unstable")]
pub use pixel::{fragments, AaPlane, Cells, Fragment, RufPixel, SampleDepth, SsPixel};
#[cfg(not(feature = "unstable"))]
pub(crate) use pixel::{fragments, AaPlane, Cells, RufPixel, SsPixel};
