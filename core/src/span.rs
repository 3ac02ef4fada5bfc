//! The span DDA (pipeline stage 4, seed 001 §II.1 and §III.1): from the
//! start values and per-pixel deltas of R, G, B and Z, every pixel of a span
//! is produced with one add per channel — the REjr channels in software.
//! Triangles (one span per covered row, restarted from the plane equation)
//! and span commands both end here: **one span loop**.
//!
//! Per pixel, in order: window-ID test, Z test and write
//! ([`crate::fragment`]), dither and pack ([`crate::dither`],
//! [`crate::format`]), plane mask, store. The loop advances the
//! accumulators only between pixels, never after the last one, so no
//! unobserved value can overflow.

use crate::command::{SpanCmd, State};
use crate::config::TileConfig;
use crate::coverage::AaMode;
use crate::dither::{quantize, round_bias, Dither};
use crate::format::{ColorPlane, Lanes, PixelFormat};
use crate::fragment::{DepthMode, DepthPlane, WidMode, WidPlane};
use crate::numeric::{Precision, COLOR_FRAC, Z_FRAC};
use crate::tile::Tile;

/// Start values and per-pixel steps of one span, in the DDA formats: colour
/// lanes in the output scale with 16 fraction bits, Z in 16.14, both without
/// the rounding bias (the span loop adds it).
#[derive(Debug, Clone, Copy)]
pub(crate) struct SpanStart<L> {
    pub c: L,
    pub dc: L,
    pub z: i32,
    pub dz: i32,
}

impl<L: Lanes> SpanStart<L> {
    /// The values `k` DDA steps further, computed at once: exactly what `k`
    /// additions give. The products may wrap in `i32`, but the result is a
    /// value of a pixel inside the primitive, which fits, and two's
    /// complement arithmetic is exact modulo 2^32 — so no 64-bit multiply.
    #[inline]
    pub fn advanced(self, k: i64) -> Self {
        let k = k as i32;
        SpanStart {
            c: self
                .c
                .zip(self.dc, |v, d| v.wrapping_add(k.wrapping_mul(d))),
            z: self.z.wrapping_add(k.wrapping_mul(self.dz)),
            ..self
        }
    }

    /// Start and steps rounded to nearest at the fraction bits `P` keeps
    /// (the DDA of a narrower datapath; seed 001 tuned these widths). With
    /// [`FullPrecision`](crate::numeric::FullPrecision) nothing is dropped
    /// and this compiles to nothing. Called at the tile-independent restart
    /// point, before [`Self::advanced`], so tiling cannot change the result.
    #[inline(always)]
    pub fn quantized<P: Precision>(self) -> Self {
        let (cd, zd) = (
            COLOR_FRAC.saturating_sub(P::COLOR_BITS),
            Z_FRAC.saturating_sub(P::Z_BITS),
        );
        let q = |v: i32, drop: u32| {
            if drop == 0 {
                v
            } else {
                v.wrapping_add(1 << (drop - 1)) & !((1 << drop) - 1)
            }
        };
        SpanStart {
            c: self.c.map(|v| q(v, cd)),
            dc: self.dc.map(|v| q(v, cd)),
            z: q(self.z, zd),
            dz: q(self.dz, zd),
        }
    }
}

impl<const N: usize, C, F, Z, W, D, A, P> Tile<N, C>
where
    C: TileConfig<Format = F, Depth = Z, Wid = W, Dither = D, Aa = A, Precision = P>,
    F: PixelFormat,
    Z: DepthMode,
    W: WidMode,
    D: Dither,
    A: AaMode,
    P: Precision,
{
    /// Draws `n >= 1` pixels from screen `(x, y)`, which the caller has
    /// clipped to this tile.
    #[inline]
    pub(crate) fn span(&mut self, x: i64, y: i64, n: i64, s: SpanStart<F::Lanes>, st: &State) {
        let a = self.area;
        let idx = ((y - a.y as i64) * a.w as i64 + (x - a.x as i64)) as usize;
        let bias = round_bias::<D>();
        let s = SpanStart {
            c: s.c.map(|v| v + bias),
            z: s.z + (1 << (Z_FRAC - 1)),
            ..s
        };
        let mask = st.plane_mask & F::MASK_ALL;
        // Screen addresses are non-negative inside a tile; only their low
        // bits reach the dither.
        let (xs, ys) = (x as u32, y as u32);
        if mask == F::MASK_ALL {
            self.span_loop::<false>(idx, xs, ys, n as usize, s, st.wid, mask);
        } else {
            self.span_loop::<true>(idx, xs, ys, n as usize, s, st.wid, mask);
        }
    }

    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    fn span_loop<const MASKED: bool>(
        &mut self,
        mut idx: usize,
        mut x: u32,
        y: u32,
        n: usize,
        s: SpanStart<F::Lanes>,
        wid: u8,
        mask: u32,
    ) {
        let (mut c, mut z) = (s.c, s.z);
        let end = idx + n;
        loop {
            if self.wid.pass(idx, wid) && self.depth.test_and_set(idx, z) {
                let t = D::threshold(x, y);
                let mut raw = F::pack(c.zip(F::MAX, |v, max| quantize::<D>(v, max, t)));
                if MASKED {
                    raw = (self.color.get(idx) & !mask) | (raw & mask);
                }
                self.color.set(idx, raw);
            }
            idx += 1;
            if idx == end {
                break;
            }
            x = x.wrapping_add(1);
            c = c.zip(s.dc, |v, d| v + d);
            z += s.dz;
        }
    }

    /// The span command: clipped to the tile. Its values are converted to
    /// the DDA formats at a restart point that does not depend on the tiling
    /// (its first pixel at or right of `min(tile.x, 0)`, exactly, from the
    /// command's own 16.16 values) and advanced from there to the tile, so a
    /// span drawn across tiles equals the span drawn whole.
    pub(crate) fn span_cmd(&mut self, s: &SpanCmd, st: &State) {
        let a = self.area;
        if (s.y as i64) < a.y as i64 || s.y as i64 >= a.y1() {
            return;
        }
        let x0 = (s.x as i64).max(a.x as i64);
        let x1 = (s.x as i64 + s.len as i64).min(a.x1());
        if x0 >= x1 {
            return;
        }
        let xr = (s.x as i64).max((a.x as i64).min(0));
        let k = xr - s.x as i64;
        let at = |start: i64, step: i64| start + k * step;
        let rgb = |f: &dyn Fn(usize) -> i64| [f(0), f(1), f(2)];
        // 16.16 inputs to the DDA formats (colour: output scale x.16; Z: 16.14).
        let c = F::lanes_from_rgb(rgb(&|i| {
            at(s.color[i].to_bits() as i64, s.dcolor[i].to_bits() as i64)
        }));
        let dc = F::lanes_from_rgb(rgb(&|i| s.dcolor[i].to_bits() as i64));
        let zshift = 16 - Z_FRAC;
        let z = (at(s.z.to_bits() as i64, s.dz.to_bits() as i64) >> zshift) as i32;
        let dz = crate::numeric::div_round(s.dz.to_bits() as i64, 1 << zshift) as i32;
        let start = SpanStart { c, dc, z, dz }
            .quantized::<P>()
            .advanced(x0 - xr);
        self.span(x0, s.y as i64, x1 - x0, start, st);
    }
}
