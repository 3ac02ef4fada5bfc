//! Image error metrics: the RUF seed's colour error (seed 000, eq. 8: the sum
//! over pixels and R, G, B of squared differences), PSNR and max abs error.

use crate::image::Image;

/// The difference between a test image and a reference.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Diff {
    /// Seed 000 eq. 8: `sum over i, j, c of (r_ijc - t_ijc)^2`.
    pub sse: u64,
    /// Mean of eq. 8 per pixel.
    pub mse_per_pixel: f64,
    /// Peak signal-to-noise ratio in dB over all channels (infinite when equal).
    pub psnr: f64,
    /// Largest absolute channel difference.
    pub max_abs: u8,
    /// Pixels that differ at all.
    pub differing: u64,
}

impl std::fmt::Display for Diff {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "color error (eq. 8, sum of squared RGB differences) = {}\nmean per pixel = {:.4}\nPSNR = {:.2} dB\nmax abs error = {}\ndiffering pixels = {}",
            self.sse, self.mse_per_pixel, self.psnr, self.max_abs, self.differing
        )
    }
}

/// Compares two images of the same size.
pub fn compare(a: &Image, b: &Image) -> crate::Result<Diff> {
    if (a.width, a.height) != (b.width, b.height) {
        return Err(crate::Error::SizeMismatch {
            a: (a.width, a.height),
            b: (b.width, b.height),
        });
    }
    let (mut sse, mut max_abs, mut differing) = (0u64, 0u8, 0u64);
    for (p, q) in a.pixels.iter().zip(&b.pixels) {
        let mut diff = false;
        for c in 0..3 {
            let d = p[c].abs_diff(q[c]);
            sse += d as u64 * d as u64;
            max_abs = max_abs.max(d);
            diff |= d != 0;
        }
        differing += diff as u64;
    }
    let n = a.pixels.len().max(1) as f64;
    let mse = sse as f64 / (3.0 * n);
    let psnr = if sse == 0 {
        f64::INFINITY
    } else {
        10.0 * (255.0f64 * 255.0 / mse).log10()
    };
    Ok(Diff {
        sse,
        mse_per_pixel: sse as f64 / n,
        psnr,
        max_abs,
        differing,
    })
}

/// A `k x k` box blur with clamped borders (to look at dithered images the
/// way an eye at a distance does).
pub fn box_blur(img: &Image, k: u32) -> Vec<[f64; 3]> {
    let (w, h) = (img.width as i64, img.height as i64);
    let r0 = -(k as i64 - 1) / 2;
    let mut out = vec![[0.0; 3]; img.pixels.len()];
    for y in 0..h {
        for x in 0..w {
            let mut s = [0.0; 3];
            for dy in 0..k as i64 {
                for dx in 0..k as i64 {
                    let xx = (x + r0 + dx).clamp(0, w - 1);
                    let yy = (y + r0 + dy).clamp(0, h - 1);
                    let p = img.pixels[(yy * w + xx) as usize];
                    for c in 0..3 {
                        s[c] += p[c] as f64;
                    }
                }
            }
            out[(y * w + x) as usize] = s.map(|v| v / (k * k) as f64);
        }
    }
    out
}

/// Root-mean-square difference of two f64 images.
pub fn rms(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    let s: f64 = a
        .iter()
        .zip(b)
        .flat_map(|(p, q)| (0..3).map(move |c| (p[c] - q[c]).powi(2)))
        .sum();
    (s / (3 * a.len().max(1)) as f64).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;
    #[test]
    fn metric_counts_squares() {
        let a = Image {
            width: 2,
            height: 1,
            pixels: vec![[0, 0, 0], [10, 0, 0]],
        };
        let b = Image {
            width: 2,
            height: 1,
            pixels: vec![[0, 3, 0], [10, 0, 4]],
        };
        let d = compare(&a, &b).unwrap();
        assert_eq!((d.sse, d.max_abs, d.differing), (25, 4, 2));
        assert!(compare(&a, &a).unwrap().psnr.is_infinite());
    }
}
