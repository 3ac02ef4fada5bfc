//! Classification (seed 002 §3.2, §4.1): a density's opacity and colour
//! through one lookup table, the transfer function.

use crate::error::Error;
use crate::format::Rgb;

/// One point of a piecewise-linear transfer function.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TfPoint {
    /// The density it sits at.
    pub density: u8,
    /// Opacity there (0 transparent, 255 opaque).
    pub alpha: u8,
    /// Colour there.
    pub color: Rgb,
}

impl TfPoint {
    /// A point.
    pub const fn new(density: u8, alpha: u8, color: Rgb) -> Self {
        TfPoint {
            density,
            alpha,
            color,
        }
    }
}

/// The lookup table (seed 002 §3.2): for every density, an opacity, its
/// blend weight and a colour — 1.25 KB, built once from points and read
/// once per sample.
///
/// ```
/// use tilerast::volume::{Transfer, TfPoint};
/// use tilerast::prelude::Rgb;
/// let w = Rgb::new(255, 255, 255);
/// let tf = Transfer::from_points(&[TfPoint::new(50, 0, w), TfPoint::new(150, 200, w)])?;
/// assert_eq!((tf.alpha(0), tf.alpha(50), tf.alpha(100), tf.alpha(255)), (0, 0, 100, 200));
/// assert!(Transfer::from_points(&[TfPoint::new(9, 1, w), TfPoint::new(3, 1, w)]).is_err());
/// # Ok::<(), tilerast::Error>(())
/// ```
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Transfer {
    alpha: [u8; 256],
    /// `round(alpha * 2^15 / 255)`: the compositing weight, Q1.15.
    weight: [u16; 256],
    color: [Rgb; 256],
    /// How many densities from each one on have zero weight (at most 255):
    /// [`Transfer::transparent`]'s range test.
    clear: [u8; 256],
}

impl Transfer {
    /// The table of a piecewise-linear function through `points` (sorted
    /// by strictly increasing density; held constant before the first and
    /// after the last), each entry rounded to nearest.
    /// [`Error::Malformed`] when `points` is empty or unsorted.
    pub fn from_points(points: &[TfPoint]) -> Result<Self, Error> {
        if points.is_empty() || points.windows(2).any(|w| w[0].density >= w[1].density) {
            return Err(Error::Malformed);
        }
        let mut t = Transfer {
            alpha: [0; 256],
            weight: [0; 256],
            color: [Rgb::new(0, 0, 0); 256],
            clear: [0; 256],
        };
        for d in 0..256usize {
            let next = points.iter().position(|p| p.density as usize >= d);
            let (a, b) = match next {
                None => (points[points.len() - 1], points[points.len() - 1]),
                Some(0) => (points[0], points[0]),
                Some(i) => (points[i - 1], points[i]),
            };
            let (d0, d1) = (a.density as i32, b.density as i32);
            let lerp = |x: u8, y: u8| -> u8 {
                if d1 == d0 {
                    return y;
                }
                let (x, y) = (x as i32, y as i32);
                let num = x * (d1 - d0) + (y - x) * (d as i32 - d0);
                ((2 * num + (d1 - d0)) / (2 * (d1 - d0))) as u8
            };
            t.alpha[d] = lerp(a.alpha, b.alpha);
            t.color[d] = Rgb::new(
                lerp(a.color.r, b.color.r),
                lerp(a.color.g, b.color.g),
                lerp(a.color.b, b.color.b),
            );
            t.weight[d] = ((t.alpha[d] as u32 * (1 << 16) + 255) / 510) as u16;
        }
        let mut run = 0u32;
        for d in (0..256).rev() {
            run = if t.weight[d] == 0 { run + 1 } else { 0 };
            t.clear[d] = run.min(255) as u8;
        }
        Ok(t)
    }

    /// Whether every density in `lo..=hi` has zero opacity weight: a
    /// brick of that range holds no visible sample.
    ///
    /// ```
    /// use tilerast::prelude::Rgb;
    /// use tilerast::volume::{TfPoint, Transfer};
    /// let tf = Transfer::from_points(&[
    ///     TfPoint::new(100, 0, Rgb::new(255, 255, 255)),
    ///     TfPoint::new(200, 255, Rgb::new(255, 255, 255)),
    /// ])?;
    /// assert!(tf.transparent(0, 100));
    /// assert!(!tf.transparent(90, 110));
    /// # Ok::<(), tilerast::Error>(())
    /// ```
    #[inline(always)]
    pub fn transparent(&self, lo: u8, hi: u8) -> bool {
        hi.wrapping_sub(lo) < self.clear[lo as usize]
    }

    /// The opacity of density `d`.
    pub fn alpha(&self, d: u8) -> u8 {
        self.alpha[d as usize]
    }

    /// The colour of density `d`.
    pub fn color(&self, d: u8) -> Rgb {
        self.color[d as usize]
    }

    /// The compositing weight of density `d`: `round(α 2^15 / 255)`, Q1.15.
    #[inline(always)]
    pub fn weight(&self, d: u8) -> u16 {
        self.weight[d as usize]
    }

    /// Whether every density maps to one colour: then normal blending
    /// equals per-slice shading exactly (up to rounding; seed 002 §4.2).
    pub fn is_monochrome(&self) -> bool {
        self.color.iter().all(|c| *c == self.color[0])
    }
}
