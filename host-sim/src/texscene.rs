//! The perspective-texturing workload, shared by the
//! tests, the trade-off report and the firmware: a textured rectangle seen
//! at an angle, so that its far edge is `ratio` times as deep as its near
//! one, mapped with a *ramp* texture whose texels encode their own
//! coordinates — so the texel error of a rendering is read off its pixels.
//!
//! The ramp is 16 x 16 RGB888 texels, texel `(i, j)` = `(16 i, 16 j, 0)`,
//! clamped and bilinear: at a point `(u, v)` inside it red is
//! `16 (u - 1/2)` and green `16 (v - 1/2)`, so one 8-bit step of red or
//! green is 1/16 texel, and `|red - red_exact| / 16` is the `u` error.
//!
//! The rectangle is a trapezoid on screen: its near (left) edge spans 90% of
//! the screen's height, its far (right) edge `1 / ratio` of that, and `q`
//! (`1/w`) is `65535` at the near edge and `65535 / ratio` at the far one —
//! the exact projection of a planar rectangle, `q` affine in screen space.
//! `u` runs 0..16 from left to right, `v` 0..16 from top to bottom, in two
//! triangles split along a diagonal.

use crate::reference::RefFrame;
use crate::render::Rendered;
use tilerast::prelude::*;

/// Side of the ramp texture, in texels.
pub const RAMP_SIDE: u16 = 16;

/// The ramp's texels: `(16 i, 16 j, 0)` at column `i`, row `j`.
pub fn ramp_texels() -> Vec<u8> {
    let n = RAMP_SIDE as usize;
    (0..n * n)
        .flat_map(|k| [(16 * (k % n)) as u8, (16 * (k / n)) as u8, 0])
        .collect()
}

/// The ramp texture over `texels` ([`ramp_texels`]): clamped, bilinear.
pub fn ramp(texels: &[u8]) -> Texture<'_> {
    Texture::new(texels, RAMP_SIDE, RAMP_SIDE, TexFormat::Rgb888)
        .expect("16 x 16 RGB888")
        .wrap(Wrap::Clamp)
        .filter(Filter::Bilinear)
}

/// The rectangle at depth ratio `ratio >= 1` on a `w x h` screen, texture
/// 0, shade 255 (the texel itself): two [`Command::Textured`].
pub fn tilted_quad(w: u16, h: u16, ratio: f64) -> [Command; 2] {
    let (w, h) = (w as f64, h as f64);
    let (xl, xr, cy) = (0.05 * w, 0.95 * w, h / 2.0);
    let (hl, hr) = (0.45 * h, 0.45 * h / ratio);
    let q = |far: bool| {
        if far {
            (65535.0 / ratio).round().max(1.0) as u16
        } else {
            65535
        }
    };
    let z = |far: bool| if far { 40000 } else { 10000 };
    let s = RAMP_SIDE as f32;
    let tv = |x: f64, y: f64, far: bool, u: f32, v: f32| {
        TexVertex::new(
            Coord::from_num(x),
            Coord::from_num(y),
            z(far),
            (u, v),
            q(far),
        )
    };
    let tl = tv(xl, cy - hl, false, 0.0, 0.0);
    let bl = tv(xl, cy + hl, false, 0.0, s);
    let tr = tv(xr, cy - hr, true, s, 0.0);
    let br = tv(xr, cy + hr, true, s, s);
    [
        Command::textured(0, [tl, tr, br], [255; 3]),
        Command::textured(0, [tl, br, bl], [255; 3]),
    ]
}

/// Texel error of a ramp rendering against the f64 reference.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct TexelError {
    /// Largest error over the covered pixels, texels (`u` or `v`).
    pub max: f64,
    /// Mean of the per-pixel largest error.
    pub mean: f64,
    /// Covered pixels.
    pub pixels: usize,
}

/// The texel error of `ours` (an RGB888 rendering of a ramp scene) against
/// `exact`, over the pixels the reference covers.
pub fn texel_error(ours: &Rendered, exact: &RefFrame) -> TexelError {
    let mut e = TexelError::default();
    let mut sum = 0.0;
    for (i, p) in ours.raw.iter().enumerate() {
        if exact.depth[i] >= 65535.0 {
            continue;
        }
        let (r, g) = (((p >> 16) & 255) as f64, ((p >> 8) & 255) as f64);
        let c = exact.color[i];
        let err = (r - c[0]).abs().max((g - c[1]).abs()) / 16.0;
        e.max = e.max.max(err);
        sum += err;
        e.pixels += 1;
    }
    e.mean = sum / e.pixels.max(1) as f64;
    e
}
