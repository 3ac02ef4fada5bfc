//! The span DDA (pipeline stage 4, seed 001 §II.1 and §III.1): from the
//! start values and per-pixel deltas of R, G, B and Z, every pixel of a span
//! is produced with one add per channel — the REjr channels in software.
//! Triangles (one span per covered row, restarted from the plane equation)
//! and span commands both end here: **one span loop**.
//!
//! The span loop itself (window-ID test, Z test and write, then the one
//! fragment store: dither, pack, plane mask, store) runs over the tile's
//! planes in [`crate::tile`]; this module holds the DDA values it steps.

use crate::format::Lanes;
use crate::numeric::{Precision, COLOR_FRAC, Z_FRAC};

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
        SpanStart {
            c: quantize_color::<P, L>(self.c),
            dc: quantize_color::<P, L>(self.dc),
            z: quantize_z::<P>(self.z),
            dz: quantize_z::<P>(self.dz),
        }
    }
}

/// Rounds `v` to nearest at `2^drop` (modulo 2^32, so a wrapped plane value
/// rounds like the value it stands for).
#[inline(always)]
fn round_at(v: i32, drop: u32) -> i32 {
    if drop == 0 {
        v
    } else {
        v.wrapping_add(1 << (drop - 1)) & !((1 << drop) - 1)
    }
}

/// Colour lanes (16 fraction bits) rounded to the `P::COLOR_BITS` the DDA
/// keeps.
#[inline(always)]
pub(crate) fn quantize_color<P: Precision, L: Lanes>(c: L) -> L {
    c.map(|v| round_at(v, COLOR_FRAC.saturating_sub(P::COLOR_BITS)))
}

/// Z (16.14) rounded to the `P::Z_BITS` the DDA keeps.
#[inline(always)]
pub(crate) fn quantize_z<P: Precision>(z: i32) -> i32 {
    round_at(z, Z_FRAC.saturating_sub(P::Z_BITS))
}
