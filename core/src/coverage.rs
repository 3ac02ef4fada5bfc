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
//! **RUF update** ([`RufPixel::update`]), for a fragment with object tag
//! `t`:
//! 1. survived mask `M_sur` = covered samples whose depth passes (eq. 1);
//! 2. colour `C_ff += C_if N(M_sur)/T - C_RUF N(M_sur & M_RUF)/T - Ĉ N(M_sur & M_ff & !M_RUF)/T`
//!    (eqs. 2, 3): add the survivor, remove what the hidden samples
//!    contributed — exactly where the RUF buffer knows it, estimated by the
//!    pixel's current mean colour `Ĉ` elsewhere (eq. 3's fourth term);
//! 3. `M_ff |= M_sur`, depths written;
//! 4. RUF write: same tag, merge (eqs. 6, 7); otherwise replace.
//!
//! The background is not a fragment: `C_ff` sums only covered samples, and
//! [`RufPixel::resolve`] adds the clear colour for the samples no fragment
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

use crate::command::Vertex;
use crate::format::Rgb;
use crate::numeric::SUBPIXEL;
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

/// `N(m)`: covered samples.
#[inline]
pub fn count(m: Mask) -> u32 {
    m.count_ones()
}

/// The mask of all `M` samples.
#[inline]
pub const fn full<P: SamplePattern>() -> Mask {
    if P::M >= 64 {
        u64::MAX
    } else {
        (1u64 << P::M) - 1
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

/// Colour channels of an 8.8 accumulator.
fn lanes(c: Rgb) -> [i32; 3] {
    [c.r as i32, c.g as i32, c.b as i32]
}

/// `v * n / d` rounded to nearest, for non-negative operands.
#[inline]
fn scale(v: i32, n: u32, d: u32) -> i32 {
    ((v as i64 * n as i64 * 2 + d as i64) / (2 * d as i64)) as i32
}

/// The frame-buffer pixel and the RUF buffer entry of one pixel
/// (seed 000 Fig. 2) for `M` samples.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RufPixel<const M: usize> {
    /// `C_ff`: sum over covered samples of their colour / `T`, 8.8 fixed point.
    pub c_ff: [u16; 3],
    /// `M_ff`: samples some fragment covers.
    pub m_ff: Mask,
    /// Depth per sample.
    pub z: [u16; M],
    /// The RUF fragment's object tag.
    pub tag: u16,
    /// `M_RUF`: the samples of the most recently used fragment.
    pub m_ruf: Mask,
    /// `C_RUF`: its colour.
    pub c_ruf: Rgb,
}

impl<const M: usize> RufPixel<M> {
    /// A cleared pixel: nothing covered, every depth `z`.
    pub const fn new(z: u16) -> Self {
        RufPixel {
            c_ff: [0; 3],
            m_ff: 0,
            z: [z; M],
            tag: 0,
            m_ruf: 0,
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
        // Eq. 1: survived samples.
        let mut sur: Mask = 0;
        for i in 0..M {
            if f.mask >> i & 1 != 0 && f.z[i] < self.z[i] {
                sur |= 1 << i;
            }
        }
        if sur == 0 {
            return 0;
        }
        let t = M as u32;
        let (n_sur, n_ruf) = (count(sur), count(sur & self.m_ruf));
        let n_est = count(sur & self.m_ff & !self.m_ruf);
        let n_ff = count(self.m_ff);
        let m_new = self.m_ff | sur;
        let hi = scale(255 << 8, count(m_new), t);
        let (cif, cruf) = (lanes(f.color), lanes(self.c_ruf));
        // Eqs. 2 and 3, per channel, in 8.8.
        for ch in 0..3 {
            let cff = self.c_ff[ch] as i32;
            let mut v = cff + scale(cif[ch] << 8, n_sur, t) - scale(cruf[ch] << 8, n_ruf, t);
            if n_est > 0 {
                // The mean colour of the covered samples, Ĉ = C_ff T / N(M_ff),
                // times N / T: C_ff N / N(M_ff).
                v -= scale(cff, n_est, n_ff);
            }
            self.c_ff[ch] = v.clamp(0, hi) as u16;
        }
        self.m_ff = m_new;
        for i in 0..M {
            if sur >> i & 1 != 0 {
                self.z[i] = f.z[i];
            }
        }
        // Eqs. 6 and 7: merge fragments of one object, else replace. The
        // RUF samples the survivor covers again take its colour, so the
        // weights are the old samples that stay and the survivor's.
        if f.tag == self.tag && self.m_ruf != 0 {
            let keep = count(self.m_ruf & !sur);
            let merged = self.m_ruf | sur;
            let n = count(merged);
            let mix = |old: u8, new: u8| {
                ((old as u32 * keep + new as u32 * n_sur + n / 2) / n) as u8
            };
            self.c_ruf = Rgb::new(
                mix(self.c_ruf.r, f.color.r),
                mix(self.c_ruf.g, f.color.g),
                mix(self.c_ruf.b, f.color.b),
            );
            self.m_ruf = merged;
        } else {
            self.tag = f.tag;
            self.m_ruf = sur;
            self.c_ruf = f.color;
        }
        sur
    }

    /// The pixel's colour: the covered samples' sum plus the background on
    /// the samples no fragment covered, rounded to 8 bits.
    pub fn resolve(&self, background: Rgb) -> Rgb {
        let free = M as u32 - count(self.m_ff);
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
        let mut sur = 0;
        for i in 0..M {
            if f.mask >> i & 1 != 0 && f.z[i] < self.z[i] {
                sur |= 1 << i;
                self.z[i] = f.z[i];
                self.c[i] = f.color;
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
