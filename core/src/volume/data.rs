//! The volume a frame reads in place: 8-bit densities, their gradient
//! normals (precomputed and quantised, or computed on the fly), and the
//! trilinear 3D-texture sampler both read through.

use crate::error::Error;
use crate::geometry::isqrt;

/// Largest volume side, in voxels: coordinates are 16.16 fixed point and
/// `1024 << 16` leaves room below `i32::MAX` for a step.
pub const MAX_VOLUME_SIDE: u16 = 1024;

/// Unit of the composited normals: `2^14` (Q1.14, the blended normal lies
/// in `[-1, 1]` per component).
pub const NORMAL_ONE: i32 = 1 << 14;

/// Where a volume's normals come from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Normals<'a> {
    /// Central differences of the densities at every sample (8 corners of
    /// 6 reads, one integer square root): no memory, more cycles.
    OnTheFly,
    /// Three bytes a voxel (`x, y, z` as `i8`, Q0.7: `round(127 n)`), made
    /// by [`Volume::compute_normals`]: three more reads a corner.
    Quantized(&'a [u8]),
}

/// An 8-bit density volume borrowed in place (flash or RAM), `x` fastest
/// (NIfTI's order): voxel `(x, y, z)` is byte `x + w (y + h z)`.
///
/// ```
/// use tilerast::volume::{Volume, Normals};
/// let mut d = [0u8; 4 * 4 * 4];
/// d[1 + 4 * (1 + 4 * 1)] = 200;
/// let v = Volume::new(&d, [4, 4, 4])?.with_spacing([256, 256, 512])?;
/// assert_eq!(v.density(1, 1, 1), 200);
/// // The gradient points into the dense voxel, the normal out of it.
/// assert_eq!(v.voxel_normal(0, 1, 1), [-127, 0, 0]);
/// assert_eq!(v.normals(), Normals::OnTheFly);
/// assert!(Volume::new(&d, [4, 4, 3]).is_err());
/// # Ok::<(), tilerast::Error>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Volume<'a> {
    density: &'a [u8],
    dims: [u16; 3],
    spacing: [u16; 3],
    normals: Normals<'a>,
}

impl<'a> Volume<'a> {
    /// A `dims[0] x dims[1] x dims[2]` volume over `density`, unit spacing,
    /// normals on the fly. [`Error::BadSize`] if a side is below 2 or above
    /// [`MAX_VOLUME_SIDE`], or the slice's length is not the product.
    pub fn new(density: &'a [u8], dims: [u16; 3]) -> Result<Self, Error> {
        let ok = dims.iter().all(|&d| (2..=MAX_VOLUME_SIDE).contains(&d))
            && density.len() == dims.iter().map(|&d| d as usize).product::<usize>();
        if !ok {
            return Err(Error::BadSize);
        }
        Ok(Volume {
            density,
            dims,
            spacing: [256; 3],
            normals: Normals::OnTheFly,
        })
    }

    /// Voxel spacing per axis in 1/256 of a unit (Q8.8, e.g. millimetres:
    /// `[256, 256, 512]` for 1 x 1 x 2 mm). [`Error::BadSize`] for 0.
    pub fn with_spacing(mut self, spacing: [u16; 3]) -> Result<Self, Error> {
        if spacing.contains(&0) {
            return Err(Error::BadSize);
        }
        self.spacing = spacing;
        Ok(self)
    }

    /// Reads normals from `normals` ([`Normals::Quantized`], 3 bytes a
    /// voxel, as [`Volume::compute_normals`] writes them).
    /// [`Error::BadSize`] for another length.
    pub fn with_normals(mut self, normals: &'a [u8]) -> Result<Self, Error> {
        if normals.len() != 3 * self.density.len() {
            return Err(Error::BadSize);
        }
        self.normals = Normals::Quantized(normals);
        Ok(self)
    }

    /// Sides in voxels.
    pub fn dims(&self) -> [u16; 3] {
        self.dims
    }

    /// Spacing (Q8.8).
    pub fn spacing(&self) -> [u16; 3] {
        self.spacing
    }

    /// Where the normals come from.
    pub fn normals(&self) -> Normals<'a> {
        self.normals
    }

    /// Voxels.
    pub fn len(&self) -> usize {
        self.density.len()
    }

    /// Never: a volume has at least 8 voxels.
    pub fn is_empty(&self) -> bool {
        self.density.is_empty()
    }

    #[inline(always)]
    fn index(&self, x: usize, y: usize, z: usize) -> usize {
        x + self.dims[0] as usize * (y + self.dims[1] as usize * z)
    }

    /// The density of voxel `(x, y, z)` (coordinates clamped to the volume).
    pub fn density(&self, x: usize, y: usize, z: usize) -> u8 {
        let c = |v: usize, d: u16| v.min(d as usize - 1);
        self.density[self.index(c(x, self.dims[0]), c(y, self.dims[1]), c(z, self.dims[2]))]
    }

    /// The density gradient at voxel `(x, y, z)` by central differences
    /// (`d(x+1) - d(x-1)`; one-sided, with the edge voxel repeated, at the
    /// borders): each component in `-255..=255`.
    #[inline]
    pub fn gradient(&self, x: usize, y: usize, z: usize) -> [i32; 3] {
        let d = |x: usize, y: usize, z: usize| self.density(x, y, z) as i32;
        let m = |v: usize| v.saturating_sub(1);
        [
            d(x + 1, y, z) - d(m(x), y, z),
            d(x, y + 1, z) - d(x, m(y), z),
            d(x, y, z + 1) - d(x, y, m(z)),
        ]
    }

    /// The quantised normal of voxel `(x, y, z)`: `-gradient / |gradient|`
    /// (pointing from dense to empty, out of a surface) in Q0.7, each
    /// component `round(127 n)` by integer arithmetic (the same bits on
    /// every target); `[0, 0, 0]` where the density is flat.
    pub fn voxel_normal(&self, x: usize, y: usize, z: usize) -> [i8; 3] {
        let g = self.gradient(x, y, z).map(|v| v as i64);
        // The length with 12 fraction bits (the floor of the root would
        // otherwise be off by up to 2% for small gradients).
        let len = isqrt(((g[0] * g[0] + g[1] * g[1] + g[2] * g[2]) as u64) << 24) as i64;
        if len == 0 {
            return [0; 3];
        }
        // The root is rounded down: |127 g / len| can exceed 127 by a
        // hair; clamp.
        g.map(|v| div_round(-127 * (v << 12), len).clamp(-127, 127) as i8)
    }

    /// Writes every voxel's [`Volume::voxel_normal`] into `out` (3 bytes a
    /// voxel), for [`Volume::with_normals`]. [`Error::BufferTooSmall`] when
    /// `out` is shorter than `3 len`.
    pub fn compute_normals(&self, out: &mut [u8]) -> Result<(), Error> {
        if out.len() < 3 * self.len() {
            return Err(Error::BufferTooSmall);
        }
        let [w, h, d] = self.dims.map(|v| v as usize);
        let mut i = 0;
        for z in 0..d {
            for y in 0..h {
                for x in 0..w {
                    let n = self.voxel_normal(x, y, z);
                    out[i..i + 3].copy_from_slice(&n.map(|v| v as u8));
                    i += 3;
                }
            }
        }
        Ok(())
    }

    /// The 8 voxels around 16.16 voxel coordinate `t` (inside
    /// `[0, dims - 1]`) as indices, and the 8-bit fractions.
    #[inline(always)]
    fn cell(&self, t: [i32; 3]) -> ([usize; 8], [i32; 3]) {
        let i = [0, 1, 2].map(|a| (t[a] >> 16) as usize);
        let f = t.map(|v| (v >> 8) & 255);
        let up = [0, 1, 2].map(|a| (i[a] + 1).min(self.dims[a] as usize - 1) - i[a]);
        let (sx, sy) = (
            self.dims[0] as usize,
            self.dims[0] as usize * self.dims[1] as usize,
        );
        let b = self.index(i[0], i[1], i[2]);
        let (dx, dy, dz) = (up[0], up[1] * sx, up[2] * sy);
        (
            [
                b,
                b + dx,
                b + dy,
                b + dx + dy,
                b + dz,
                b + dx + dz,
                b + dy + dz,
                b + dx + dy + dz,
            ],
            f,
        )
    }

    /// The density at 16.16 voxel coordinate `t` (each inside
    /// `[0, (dims - 1) << 16]`), trilinear with 8-bit weights, rounded.
    #[inline(always)]
    pub(crate) fn sample(&self, t: [i32; 3]) -> (u8, [usize; 8], [i32; 3]) {
        let (c, f) = self.cell(t);
        let v = c.map(|i| self.density[i] as i32);
        // Up to 255 x 2^24: exact in `u32` (the `i32` products wrap).
        let d = ((trilinear(v, f) as u32).wrapping_add(1 << 23) >> 24) as u8;
        (d, c, f)
    }

    /// The normal at the cell [`Self::sample`] found, Q1.14
    /// ([`NORMAL_ONE`]): trilinear in the quantised normals, or the
    /// trilinear gradient normalised once (on the fly).
    #[inline(always)]
    pub(crate) fn normal_at(&self, c: &[usize; 8], f: [i32; 3]) -> [i32; 3] {
        match self.normals {
            Normals::Quantized(n) => core::array::from_fn(|a| {
                let v = c.map(|i| n[3 * i + a] as i8 as i32);
                // Q0.7 (scale 127) times 2^24 to Q1.14: x 129 / 2^24
                // (127 x 129 = 16383).
                (((trilinear(v, f) + 512) >> 10) * 129 + (1 << 13)) >> 14
            }),
            Normals::OnTheFly => {
                let [w, h, _] = self.dims.map(|v| v as usize);
                let g = c.map(|i| {
                    let (x, r) = (i % w, i / w);
                    self.gradient(x, r % h, r / h)
                });
                // 2^24 times the gradient, kept to 12 fraction bits so the
                // squares fit.
                let gi: [i64; 3] = core::array::from_fn(|a| trilinear64(g.map(|g| g[a]), f) >> 12);
                let len = isqrt((gi[0] * gi[0] + gi[1] * gi[1] + gi[2] * gi[2]) as u64) as i64;
                if len == 0 {
                    return [0; 3];
                }
                gi.map(|v| div_round(-(NORMAL_ONE as i64) * v, len) as i32)
            }
        }
    }
}

/// Trilinear interpolation of 8 corner values (`|v| <= 127` signed or
/// `<= 255` unsigned read as such) with 8-bit fractions: the result times
/// `2^24`. Fits `i32` for `|v| <= 127`; unsigned densities go through
/// `u32` arithmetic in the wrapping sense and are read back as `u32`.
#[inline(always)]
fn trilinear(v: [i32; 8], f: [i32; 3]) -> i32 {
    let l = |a: i32, b: i32, f: i32| a.wrapping_mul(256 - f).wrapping_add(b.wrapping_mul(f));
    let x = [
        l(v[0], v[1], f[0]),
        l(v[2], v[3], f[0]),
        l(v[4], v[5], f[0]),
        l(v[6], v[7], f[0]),
    ];
    let y = [l(x[0], x[1], f[1]), l(x[2], x[3], f[1])];
    l(y[0], y[1], f[2])
}

/// [`trilinear`] in `i64` (gradients up to 255 in magnitude).
#[inline(always)]
fn trilinear64(v: [i32; 8], f: [i32; 3]) -> i64 {
    let l = |a: i64, b: i64, f: i32| a * (256 - f) as i64 + b * f as i64;
    let v = v.map(|v| v as i64);
    let x = [
        l(v[0], v[1], f[0]),
        l(v[2], v[3], f[0]),
        l(v[4], v[5], f[0]),
        l(v[6], v[7], f[0]),
    ];
    l(l(x[0], x[1], f[1]), l(x[2], x[3], f[1]), f[2])
}

/// `round(n / d)` for `d > 0`, halves away from zero.
#[inline]
fn div_round(n: i64, d: i64) -> i64 {
    if n >= 0 {
        (2 * n + d) / (2 * d)
    } else {
        -((-2 * n + d) / (2 * d))
    }
}

/// Fills `out` (`n^3` bytes, `x` fastest) with the seed's "small sphere":
/// a ball of radius `0.4 n` centred in the cube whose density falls off
/// linearly from 255 at the centre to 0 at the radius, a denser shell
/// (`160..=230`) near its surface so a transfer function can pick it out.
/// Integer arithmetic: the same bytes everywhere. [`Error::BadSize`] when
/// `out.len() != n^3` or `n < 2`.
///
/// ```
/// let mut d = vec![0u8; 16 * 16 * 16];
/// tilerast::volume::sphere(16, &mut d)?;
/// assert!(d[8 + 16 * (8 + 16 * 8)] > 200); // centre
/// assert_eq!(d[0], 0); // corner
/// # Ok::<(), tilerast::Error>(())
/// ```
pub fn sphere(n: u16, out: &mut [u8]) -> Result<(), Error> {
    let n = n as i64;
    if n < 2 || out.len() as i64 != n * n * n {
        return Err(Error::BadSize);
    }
    // Distances in 1/16 voxel, centre at (n - 1) / 2.
    let c = 8 * (n - 1);
    let r = 16 * 2 * n / 5;
    let mut i = 0;
    for z in 0..n {
        for y in 0..n {
            for x in 0..n {
                let d = |v: i64| 16 * v - c;
                let dist = isqrt((d(x) * d(x) + d(y) * d(y) + d(z) * d(z)) as u64) as i64;
                out[i] = if dist >= r {
                    0
                } else if 8 * dist >= 7 * r {
                    // The shell: the outer eighth.
                    (230 - 70 * (8 * dist - 7 * r) / r) as u8
                } else {
                    (255 - 155 * dist / r) as u8
                };
                i += 1;
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn isqrt_is_exact() {
        for v in (0..5000u64).chain([u32::MAX as u64, u64::MAX >> 2, 1 << 40]) {
            let r = isqrt(v);
            assert!(r * r <= v && (r + 1) * (r + 1) > v, "{v}");
        }
    }

    #[test]
    fn trilinear_reproduces_corners_and_planes() {
        let mut d = [0u8; 27];
        for (i, v) in d.iter_mut().enumerate() {
            // A linear ramp in x + 2y + 4z.
            *v = ((i % 3) * 10 + (i / 3 % 3) * 20 + (i / 9) * 40) as u8;
        }
        let vol = Volume::new(&d, [3, 3, 3]).unwrap();
        for t in [
            [0, 0, 0],
            [1 << 16, 1 << 15, 3 << 15],
            [2 << 16, 2 << 16, 2 << 16],
        ] {
            let (s, _, _) = vol.sample(t);
            let exact = (t[0] as f64 * 10.0 + t[1] as f64 * 20.0 + t[2] as f64 * 40.0) / 65536.0;
            assert!((s as f64 - exact).abs() <= 0.5, "{t:?}: {s} vs {exact}");
        }
    }

    #[test]
    fn quantized_and_on_the_fly_normals_agree_at_voxels() {
        let mut d = [0u8; 16 * 16 * 16];
        sphere(16, &mut d).unwrap();
        let mut n = [0u8; 3 * 16 * 16 * 16];
        let vol = Volume::new(&d, [16; 3]).unwrap();
        vol.compute_normals(&mut n).unwrap();
        let q = vol.with_normals(&n).unwrap();
        for t in [[3, 8, 8], [8, 12, 5], [13, 13, 13]] {
            let t16 = t.map(|v| v << 16);
            let (_, c, f) = q.sample(t16);
            let (a, b) = (q.normal_at(&c, f), vol.normal_at(&c, f));
            for k in 0..3 {
                // Q0.7 quantisation: within 1/127 plus rounding.
                assert!((a[k] - b[k]).abs() <= 140, "{t:?}: {a:?} vs {b:?}");
            }
        }
    }
}
