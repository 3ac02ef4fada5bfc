//! The volume a frame reads in place: 8-bit densities, their gradient
//! normals (precomputed and quantised, or computed on the fly), and the
//! trilinear 3D-texture sampler both read through.

use crate::error::Error;
use crate::geometry::isqrt;

use super::Transfer;

/// Largest volume side, in voxels: coordinates are 16.16 fixed point and
/// `1024 << 16` leaves room below `i32::MAX` for a step.
pub const MAX_VOLUME_SIDE: u16 = 1024;

/// Unit of the sampled and composited normals: `127 x 2^8` (the quantised
/// normals' Q0.7 scale with 8 more bits, so a trilinear sum of them is one
/// shift from it; a component lies in `[-NORMAL_ONE, NORMAL_ONE]`). Phase
/// II turns a pixel's normal to Q1.14 once, not every sample.
pub const NORMAL_ONE: i32 = 127 << 8;

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
    /// The largest index of a cell's lowest corner whose 8 corners lie in
    /// the volume by index arithmetic: `len - (w h + w + 2)` (never
    /// negative: every side is at least 2).
    last_cell: usize,
    spacing: [u16; 3],
    normals: Normals<'a>,
    bricks: Option<Bricks<'a>>,
    /// One bit a cell, set where the cell may hold a visible sample
    /// ([`Volume::compute_visible_cells`]).
    visible: Option<&'a [u8]>,
}

/// Per-brick density ranges for empty-space skipping (seed 002 taken
/// further): a brick is `2^shift` cells a side, and its range covers every
/// voxel a sample in it reads (its cells' corners, so one voxel past its
/// upper faces). Trilinear interpolation stays inside the range of the
/// corners it reads, so a sample in a brick whose whole range has zero
/// opacity ([`Transfer::transparent`](super::Transfer::transparent)) is
/// transparent: it is skipped without a fetch, and the image is the same.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Bricks<'a> {
    /// `(min, max)` byte pairs, brick `x` fastest.
    range: &'a [u8],
    shift: u32,
    /// Bricks per row and per layer.
    stride: [usize; 2],
}

/// Smallest and largest brick side a [`Volume`] takes, as shifts: 2 to 32
/// cells.
pub const BRICK_SHIFTS: core::ops::RangeInclusive<u32> = 1..=5;

/// Bytes [`Volume::compute_bricks`] writes for a volume of `dims` in
/// bricks of `2^shift` cells a side: two per brick (`ceil(d / 2^shift)`
/// bricks an axis).
///
/// ```
/// use tilerast::volume::brick_bytes;
/// assert_eq!(brick_bytes([32, 32, 32], 2), 2 * 8 * 8 * 8);
/// assert_eq!(brick_bytes([33, 32, 32], 2), 2 * 9 * 8 * 8);
/// ```
pub const fn brick_bytes(dims: [u16; 3], shift: u32) -> usize {
    2 * bricks_along(dims[0], shift) * bricks_along(dims[1], shift) * bricks_along(dims[2], shift)
}

/// Bytes [`Volume::compute_visible_cells`] writes for a volume of `dims`:
/// one bit a voxel (the cell it is the lowest corner of), `x` fastest,
/// bit `i & 7` of byte `i >> 3`; then the box of the set bits, 12 bytes
/// (lowest and highest voxel an axis, `u16` little-endian; the lowest
/// above the highest when none is set).
///
/// ```
/// use tilerast::volume::visible_cell_bytes;
/// assert_eq!(visible_cell_bytes([32, 32, 32]), 4096 + 12);
/// assert_eq!(visible_cell_bytes([3, 3, 3]), 4 + 12);
/// ```
pub const fn visible_cell_bytes(dims: [u16; 3]) -> usize {
    cell_bit_bytes(dims) + CELL_BOX_BYTES
}

/// The bitmap's part of [`visible_cell_bytes`].
const fn cell_bit_bytes(dims: [u16; 3]) -> usize {
    (dims[0] as usize * dims[1] as usize * dims[2] as usize).div_ceil(8)
}

/// The box's part of [`visible_cell_bytes`].
const CELL_BOX_BYTES: usize = 12;

/// Bricks of `2^shift` cells along an axis of `d` voxels.
const fn bricks_along(d: u16, shift: u32) -> usize {
    (d as usize + (1 << shift) - 1) >> shift
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
        let (w, wh) = (dims[0] as usize, dims[0] as usize * dims[1] as usize);
        Ok(Volume {
            density,
            dims,
            last_cell: density.len() - (wh + w + 2),
            spacing: [256; 3],
            normals: Normals::OnTheFly,
            bricks: None,
            visible: None,
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

    /// Writes the density range of every brick of `2^shift` cells a side
    /// into `out` ([`brick_bytes`] of them), for [`Volume::with_bricks`]:
    /// 1 KB for a 32^3 volume in 4-cell bricks. [`Error::BadSize`] for a
    /// shift outside [`BRICK_SHIFTS`], [`Error::BufferTooSmall`] when `out`
    /// is shorter.
    ///
    /// ```
    /// use tilerast::volume::{brick_bytes, sphere, Volume};
    /// let mut d = vec![0u8; 16 * 16 * 16];
    /// sphere(16, &mut d)?;
    /// let mut bricks = vec![0u8; brick_bytes([16; 3], 1)];
    /// let vol = Volume::new(&d, [16; 3])?;
    /// vol.compute_bricks(1, &mut bricks)?;
    /// assert_eq!(&bricks[..2], &[0, 0]); // a corner of the cube is empty
    /// let vol = vol.with_bricks(&bricks, 1)?;
    /// # let _ = vol;
    /// # Ok::<(), tilerast::Error>(())
    /// ```
    pub fn compute_bricks(&self, shift: u32, out: &mut [u8]) -> Result<(), Error> {
        if !BRICK_SHIFTS.contains(&shift) {
            return Err(Error::BadSize);
        }
        if out.len() < brick_bytes(self.dims, shift) {
            return Err(Error::BufferTooSmall);
        }
        let d = self.dims.map(|v| v as usize);
        let n = self.dims.map(|v| bricks_along(v, shift));
        // Brick b's voxels along an axis: b 2^shift ..= b 2^shift + 2^shift
        // (the last cell's upper corner), cut to the volume.
        let span = |b: usize, a: usize| (b << shift)..=((b + 1) << shift).min(d[a] - 1);
        let mut i = 0;
        for bz in 0..n[2] {
            for by in 0..n[1] {
                for bx in 0..n[0] {
                    let (mut lo, mut hi) = (u8::MAX, u8::MIN);
                    for z in span(bz, 2) {
                        for y in span(by, 1) {
                            let row = self.index(0, y, z);
                            for &v in &self.density[row + (bx << shift)..=row + *span(bx, 0).end()]
                            {
                                lo = lo.min(v);
                                hi = hi.max(v);
                            }
                        }
                    }
                    out[i] = lo;
                    out[i + 1] = hi;
                    i += 2;
                }
            }
        }
        Ok(())
    }

    /// Skips samples in bricks the transfer function makes transparent,
    /// reading the ranges [`Volume::compute_bricks`] wrote into `bricks`
    /// for `2^shift`-cell bricks. [`Error::BadSize`] for another length or
    /// a shift outside [`BRICK_SHIFTS`].
    pub fn with_bricks(mut self, bricks: &'a [u8], shift: u32) -> Result<Self, Error> {
        if !BRICK_SHIFTS.contains(&shift) || bricks.len() != brick_bytes(self.dims, shift) {
            return Err(Error::BadSize);
        }
        let n = self.dims.map(|v| bricks_along(v, shift));
        self.bricks = Some(Bricks {
            range: bricks,
            shift,
            stride: [n[0], n[0] * n[1]],
        });
        Ok(self)
    }

    /// Classifies every cell through `tf` once (seed 002's classification
    /// folded into a bitmap): bit `x + w (y + h z)` of `out` is set when
    /// the range of the 8 corner densities of the cell a sample at voxel
    /// `(x, y, z)` reads (from `(x, y, z)` to `(x + 1, y + 1, z + 1)`, each
    /// coordinate first cut to `dims - 2`: on the top faces the cell below)
    /// holds a density of non-zero opacity. Trilinear interpolation stays
    /// inside its corners' range, so a sample in a clear cell is
    /// transparent and [`Volume::with_visible_cells`] skips it before the
    /// fetch: the same image, one bit a voxel (4 KB for 32^3), found from
    /// the integer part of a sample's coordinates alone. Unlike
    /// [`Volume::compute_bricks`]'s ranges the bits depend on the transfer
    /// function: make them again when it changes. [`Error::BufferTooSmall`]
    /// when `out` is shorter than [`visible_cell_bytes`].
    ///
    /// ```
    /// use tilerast::prelude::Rgb;
    /// use tilerast::volume::{sphere, visible_cell_bytes, TfPoint, Transfer, Volume};
    /// let mut d = vec![0u8; 16 * 16 * 16];
    /// sphere(16, &mut d)?;
    /// let w = Rgb::new(255, 255, 255);
    /// let tf = Transfer::from_points(&[TfPoint::new(100, 0, w), TfPoint::new(200, 255, w)])?;
    /// let mut bits = vec![0u8; visible_cell_bytes([16; 3])];
    /// let vol = Volume::new(&d, [16; 3])?;
    /// vol.compute_visible_cells(&tf, &mut bits)?;
    /// assert_eq!(bits[0] & 1, 0); // a corner of the cube is clear
    /// let vol = vol.with_visible_cells(&bits)?;
    /// # let _ = vol;
    /// # Ok::<(), tilerast::Error>(())
    /// ```
    pub fn compute_visible_cells(&self, tf: &Transfer, out: &mut [u8]) -> Result<(), Error> {
        let out = out
            .get_mut(..visible_cell_bytes(self.dims))
            .ok_or(Error::BufferTooSmall)?;
        out.fill(0);
        let [w, h, d] = self.dims.map(|v| v as usize);
        // The box of the set bits: lowest and highest an axis.
        let (mut lo, mut hi) = (self.dims, [0u16; 3]);
        // Each row of cells: the corners' range along x from two voxel
        // rows of each of two layers, folded pairwise.
        for z in 0..d {
            for y in 0..h {
                let (cy, cz) = (y.min(h - 2), z.min(d - 2));
                let rows = [
                    self.index(0, cy, cz),
                    self.index(0, cy + 1, cz),
                    self.index(0, cy, cz + 1),
                    self.index(0, cy + 1, cz + 1),
                ];
                let range = |x: usize| {
                    rows.iter().fold((u8::MAX, u8::MIN), |(lo, hi), &r| {
                        let v = self.density[r + x];
                        (lo.min(v), hi.max(v))
                    })
                };
                let mut prev = range(0);
                let mut visible = false;
                for x in 0..w {
                    // The last voxel repeats the last cell's bit.
                    if x + 1 < w {
                        let next = range(x + 1);
                        let (lo, hi) = (prev.0.min(next.0), prev.1.max(next.1));
                        visible = !tf.transparent(lo, hi);
                        prev = next;
                    }
                    if visible {
                        let i = self.index(x, y, z);
                        out[i >> 3] |= 1 << (i & 7);
                        for (a, v) in [x, y, z].into_iter().enumerate() {
                            (lo[a], hi[a]) = (lo[a].min(v as u16), hi[a].max(v as u16));
                        }
                    }
                }
            }
        }
        let n = cell_bit_bytes(self.dims);
        for (k, v) in lo.into_iter().chain(hi).enumerate() {
            out[n + 2 * k..n + 2 * k + 2].copy_from_slice(&v.to_le_bytes());
        }
        Ok(())
    }

    /// The 16.16 box `[bot, top]` that holds every sample whose cell bit
    /// ([`Volume::compute_visible_cells`]) is set — the whole volume
    /// without bits. A sample outside it is clear: phase I's rows are
    /// solved against it, and the samples around a volume's visible part
    /// are never walked. Empty (`bot > top` on an axis) when no bit is
    /// set.
    pub(crate) fn visible_box(&self) -> [[i32; 3]; 2] {
        let top = self.dims.map(|d| (d as i32 - 1) << 16);
        let Some(b) = self
            .visible
            .and_then(|v| v.get(cell_bit_bytes(self.dims)..))
            .and_then(|b| b.first_chunk::<CELL_BOX_BYTES>())
        else {
            return [[0; 3], top];
        };
        let at = |k: usize| u16::from_le_bytes([b[2 * k], b[2 * k + 1]]) as i32;
        // A sample reads cell floor(t) (its bit repeats on the top face):
        // lo <= floor(t) <= hi, with `lo` at most `dims` (then empty).
        [
            core::array::from_fn(|a| at(a).min(self.dims[a] as i32) << 16),
            core::array::from_fn(|a| {
                (at(3 + a).min(self.dims[a] as i32) << 16 | 0xffff).min(top[a])
            }),
        ]
    }

    /// Skips samples in cells [`Volume::compute_visible_cells`] found
    /// clear, reading its bits, and walks none outside their box.
    /// [`Error::BadSize`] for another length.
    pub fn with_visible_cells(mut self, bits: &'a [u8]) -> Result<Self, Error> {
        if bits.len() != visible_cell_bytes(self.dims) {
            return Err(Error::BadSize);
        }
        self.visible = Some(bits);
        Ok(self)
    }

    /// Whether the volume skips clear cells by a bitmap.
    pub fn has_visible_cells(&self) -> bool {
        self.visible.is_some()
    }

    /// The side of the bricks skipped, as a shift (cells `2^shift`), if
    /// any.
    pub fn brick_shift(&self) -> Option<u32> {
        self.bricks.map(|b| b.shift)
    }

    /// The density range of the brick holding the cell of 16.16 voxel
    /// coordinate `t` (inside `[0, dims - 1]`), when the volume has bricks.
    #[inline(always)]
    pub(crate) fn brick_range(&self, t: [i32; 3]) -> Option<(u8, u8)> {
        let b = self.bricks.as_ref()?;
        let s = 16 + b.shift;
        let i = (t[0] >> s) as usize
            + (t[1] >> s) as usize * b.stride[0]
            + (t[2] >> s) as usize * b.stride[1];
        Some((b.range[2 * i], b.range[2 * i + 1]))
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

    /// The cell around 16.16 voxel coordinate `t` (each inside
    /// `[0, (dims - 1) << 16]`): its lowest corner and the 8-bit fractions
    /// of its trilinear weights. On a top face (`t = (dims - 1) << 16`,
    /// fraction 0) the cell is the one below with fraction `256`: the same
    /// value (the weight-0 corner drops out exactly), and every corner is
    /// `+1`, `+w`, `+w h` away, so a corner pair along `x` is two
    /// adjacent bytes read by one bounds check. Outside the range the
    /// corner is still clamped into the volume (the fractions are then
    /// meaningless, never the reads).
    #[inline(always)]
    pub(crate) fn cell(&self, t: [i32; 3]) -> Probe {
        // i = min(t >> 16, dims - 2), f = (t - i 2^16) >> 8 = (t >> 8) -
        // i 2^8: branch-free. (The second form is not linear in `t`, so
        // the walk keeps one running coordinate an axis, not several.)
        let axis = |a: usize| {
            let i = ((t[a] >> 16) as u32).min(self.dims[a] as u32 - 2);
            (i, ((t[a] >> 8) as u32).wrapping_sub(i << 8) & 0x1ff)
        };
        let ((x, fx), (y, fy), (z, fz)) = (axis(0), axis(1), axis(2));
        Probe {
            base: self.index(x as usize, y as usize, z as usize) as u32,
            f: fx | fy << 9 | fz << 18,
        }
    }

    /// The cells' visibility bits ([`Volume::with_visible_cells`]) with
    /// what indexes them, for phase I's walk.
    #[inline(always)]
    pub(crate) fn cell_bits(&self) -> CellBits<'a> {
        CellBits {
            bits: self.visible.unwrap_or_default(),
            w: self.dims[0] as usize,
            wh: self.dims[0] as usize * self.dims[1] as usize,
        }
    }

    /// The density at 16.16 voxel coordinate `t` (each inside
    /// `[0, (dims - 1) << 16]`), trilinear with 8-bit weights, rounded;
    /// and the cell, for [`Self::normal_at`].
    #[cfg(test)]
    pub(crate) fn sample(&self, t: [i32; 3]) -> (u8, Probe) {
        let p = self.cell(t);
        (self.density_at(p), p)
    }

    /// The density in cell `p` at its fractions, trilinear with 8-bit
    /// weights, rounded.
    #[allow(unsafe_code)]
    #[inline(always)]
    pub(crate) fn density_at(&self, p: Probe) -> u8 {
        let w = p.weights();
        let Some(rows) = self.rows(p) else {
            return 0;
        };
        // Up to 255 x 2^24: exact in `u32`.
        let mut s = 0u32;
        for (r, &row) in rows.iter().enumerate() {
            // SAFETY: `rows` checked `row + 2 <= len`.
            let v = unsafe { chunk::<2>(self.density, row) };
            s = s
                .wrapping_add(w[2 * r] * v[0] as u32)
                .wrapping_add(w[2 * r + 1] * v[1] as u32);
        }
        (s.wrapping_add(1 << 23) >> 24) as u8
    }

    /// The first voxel of each of cell `p`'s four rows of two (`y`, `z` =
    /// 0/1 in that order), `None` unless every row's pair lies inside the
    /// volume (one test for the eight reads: always inside for a cell
    /// [`Self::cell`] found). Row `r`'s pair is then bytes `r..r + 2` of
    /// the densities and bytes `3 r..3 r + 6` of quantised normals.
    #[inline(always)]
    fn rows(&self, p: Probe) -> Option<[usize; 4]> {
        let (w, wh) = (
            self.dims[0] as usize,
            self.dims[0] as usize * self.dims[1] as usize,
        );
        let base = p.base as usize;
        // base <= len - (wh + w + 2): the last row ends by `len`.
        (base <= self.last_cell).then_some([base, base + w, base + wh, base + wh + w])
    }

    /// The normal in cell `p` ([`Self::cell`]), in [`NORMAL_ONE`] units:
    /// trilinear in the quantised normals, or the trilinear gradient
    /// normalised once (on the fly).
    #[allow(unsafe_code)]
    #[inline(always)]
    pub(crate) fn normal_at(&self, p: &Probe) -> [i32; 3] {
        match self.normals {
            Normals::Quantized(n) => {
                // Q0.7 (scale 127) times 2^24, below 2^31 in magnitude.
                let w = p.weights();
                let mut s = [0i32; 3];
                let Some(rows) = self.rows(*p) else {
                    return [0; 3];
                };
                for (r, &row) in rows.iter().enumerate() {
                    // SAFETY: `rows` checked `row + 2 <= len`, and the
                    // normals are `3 len` long (`with_normals`).
                    let v = unsafe { chunk::<6>(n, 3 * row) };
                    let (w0, w1) = (w[2 * r] as i32, w[2 * r + 1] as i32);
                    for (a, s) in s.iter_mut().enumerate() {
                        *s += w0 * (v[a] as i8 as i32) + w1 * (v[3 + a] as i8 as i32);
                    }
                }
                // 127 x 2^24 is one: 2^16 to `NORMAL_ONE`, one shift (was
                // a rounded rescale to Q1.14, 5 instructions a component
                // on the Cortex-M4, every blended sample).
                s.map(|s| s >> 16)
            }
            Normals::OnTheFly => {
                let (w, h) = (self.dims[0] as usize, self.dims[1] as usize);
                let b = p.base as usize;
                let [x, y, z] = [b % w, b / w % h, b / (w * h)];
                let g: [[i32; 3]; 8] = core::array::from_fn(|k| {
                    self.gradient(x + (k & 1), y + (k >> 1 & 1), z + (k >> 2))
                });
                // 2^24 times the gradient, kept to 12 fraction bits so the
                // squares fit.
                let f = p.fractions().map(|f| f as i32);
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

/// The `N` bytes of `s` from `i`, for `i + N <= s.len()`, unchecked: the
/// sampler's 4 density and 4 normal reads a sample are bounded by one test
/// ([`Volume::rows`]) instead of two each (M4 volume phase I: *measured
/// below*). `chunk_checked` is its safe twin, compared in the tests.
///
/// # Safety
/// `i + N <= s.len()`.
#[allow(unsafe_code)]
#[inline(always)]
unsafe fn chunk<const N: usize>(s: &[u8], i: usize) -> [u8; N] {
    debug_assert!(i + N <= s.len());
    // SAFETY: `[u8; N]` has alignment 1 and the caller keeps the `N`
    // bytes from `i` inside `s`.
    unsafe { s.as_ptr().add(i).cast::<[u8; N]>().read() }
}

/// [`chunk`]'s safe twin: the same bytes, zeros out of range.
#[cfg(test)]
fn chunk_checked<const N: usize>(s: &[u8], i: usize) -> [u8; N] {
    *s.get(i..)
        .and_then(|s| s.first_chunk::<N>())
        .unwrap_or(&[0; N])
}

/// A volume's cells' visibility bits, one a voxel ([`Volume::cell_bits`];
/// empty without them: every cell visible).
#[derive(Debug, Clone, Copy)]
pub(crate) struct CellBits<'a> {
    bits: &'a [u8],
    w: usize,
    wh: usize,
}

impl CellBits<'_> {
    /// Whether the cell a sample at 16.16 voxel coordinate `t` (each
    /// inside `[0, (dims - 1) << 16]`) reads may hold a visible sample: its
    /// bit, indexed by the integer parts alone (the top faces' bits repeat
    /// the cells below); `true` without bits.
    #[inline(always)]
    pub(crate) fn visible(&self, t: [i32; 3]) -> bool {
        let i = (t[0] >> 16) as usize
            + self.w * (t[1] >> 16) as usize
            + self.wh * (t[2] >> 16) as usize;
        self.bits.get(i >> 3).is_none_or(|b| b >> (i & 7) & 1 != 0)
    }
}

/// A sample's cell ([`Volume::cell`]): its lowest corner's voxel index
/// and the three 8-bit fractions, 9 bits each (`256` on a top face),
/// packed in a word so phase I's first pass can list it cheaply.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub(crate) struct Probe {
    base: u32,
    f: u32,
}

impl Probe {
    /// The fractions along `x`, `y`, `z`.
    #[inline(always)]
    fn fractions(&self) -> [u32; 3] {
        [self.f & 0x1ff, self.f >> 9 & 0x1ff, self.f >> 18]
    }

    /// The 8 corners' trilinear weights, corner `k = x + 2 y + 4 z`: each a
    /// product of three 8-bit factors (at most 2^24), summing to 2^24.
    #[inline(always)]
    fn weights(&self) -> [u32; 8] {
        let [fx, fy, fz] = self.fractions();
        let yz = [
            (256 - fy) * (256 - fz),
            fy * (256 - fz),
            (256 - fy) * fz,
            fy * fz,
        ];
        core::array::from_fn(|k| if k & 1 == 0 { 256 - fx } else { fx } * yz[k >> 1])
    }
}

/// Trilinear interpolation of 8 corner values (`|v| <= 127` signed or
/// `<= 255` unsigned read as such) with 8-bit fractions, lerp by lerp:
/// the result times `2^24`. Fits `i32` for `|v| <= 127`; unsigned
/// densities go through `u32` arithmetic in the wrapping sense and are
/// read back as `u32`. The tests' reference for [`Volume::sample`]'s
/// weights.
#[cfg(test)]
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
    extern crate std;
    use super::*;

    /// A 16.16 point inside a volume of `dims`: on the low face, the top
    /// face or random, by axis, as `k` runs.
    fn point(dims: [u16; 3], k: usize, next: &mut impl FnMut() -> u64) -> [i32; 3] {
        core::array::from_fn(|a| {
            let top = ((dims[a] as i64 - 1) << 16) as u64;
            match (k + a) % 5 {
                0 => 0,
                1 => top as i32,
                _ => (next() % (top + 1)) as i32,
            }
        })
    }

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
            let (s, _) = vol.sample(t);
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
            let (_, c) = q.sample(t16);
            let (_, c0) = vol.sample(t16);
            let (a, b) = (q.normal_at(&c), vol.normal_at(&c0));
            for k in 0..3 {
                // Q0.7 quantisation: within 1/127 plus rounding.
                assert!((a[k] - b[k]).abs() <= 280, "{t:?}: {a:?} vs {b:?}");
            }
        }
    }

    /// The lerp-by-lerp trilinear interpolation of the clamped cell (the
    /// upper neighbour repeated on a top face), as the sampler was first
    /// written: density and both normals'.
    fn reference(vol: &Volume<'_>, n: &[u8], t: [i32; 3]) -> (u8, [i32; 3], [i32; 3]) {
        let d = vol.dims().map(|v| v as usize);
        let i = [0, 1, 2].map(|a| (t[a] >> 16) as usize);
        let f = t.map(|v| (v >> 8) & 255);
        let c: [[usize; 3]; 8] =
            core::array::from_fn(|k| [0, 1, 2].map(|a| (i[a] + (k >> a & 1)).min(d[a] - 1)));
        let at = |p: [usize; 3]| p[0] + d[0] * (p[1] + d[1] * p[2]);
        let v = c.map(|p| vol.density[at(p)] as i32);
        let dens = ((trilinear(v, f) as u32).wrapping_add(1 << 23) >> 24) as u8;
        let q = core::array::from_fn(|a| {
            let v = c.map(|p| n[3 * at(p) + a] as i8 as i32);
            trilinear(v, f) >> 16
        });
        let g = c.map(|p| vol.gradient(p[0], p[1], p[2]));
        let gi: [i64; 3] = core::array::from_fn(|a| trilinear64(g.map(|g| g[a]), f) >> 12);
        let len = isqrt((gi[0] * gi[0] + gi[1] * gi[1] + gi[2] * gi[2]) as u64) as i64;
        let fly = if len == 0 {
            [0; 3]
        } else {
            gi.map(|v| div_round(-(NORMAL_ONE as i64) * v, len) as i32)
        };
        (dens, q, fly)
    }

    /// The sampler (weights once, corner pairs, the top-face cell moved
    /// down) equals the lerp-by-lerp reference bit for bit: density,
    /// quantised and on-the-fly normals, at random points and on every
    /// face, on random volumes of several shapes.
    #[test]
    fn sampler_equals_the_lerp_reference() {
        let mut next = crate::numeric::xorshift(11);
        for dims in [[2u16, 2, 2], [3, 5, 4], [9, 7, 11], [16, 2, 3]] {
            let len = dims.iter().map(|&d| d as usize).product::<usize>();
            let dens: std::vec::Vec<u8> = (0..len).map(|_| next() as u8).collect();
            let plain = Volume::new(&dens, dims).unwrap();
            let mut n = std::vec![0u8; 3 * len];
            plain.compute_normals(&mut n).unwrap();
            let q = plain.with_normals(&n).unwrap();
            for k in 0..4000 {
                let t = point(dims, k, &mut next);
                let (want, wq, wf) = reference(&plain, &n, t);
                let (got, probe) = q.sample(t);
                assert_eq!(got, want, "{dims:?} {t:?}");
                assert_eq!(q.normal_at(&probe), wq, "{dims:?} {t:?}");
                let (_, probe) = plain.sample(t);
                assert_eq!(plain.normal_at(&probe), wf, "{dims:?} {t:?}");
            }
        }
    }

    /// The unchecked reads equal their safe twin at every in-range index
    /// of a row; a cell past the last one reads nothing (`rows` refuses
    /// it), and a top-face probe from `cell` is always accepted.
    #[test]
    #[allow(unsafe_code)]
    fn unchecked_reads_equal_the_checked_ones() {
        let mut next = crate::numeric::xorshift(5);
        let bytes: std::vec::Vec<u8> = (0..97).map(|_| next() as u8).collect();
        for i in 0..=bytes.len() - 6 {
            // SAFETY: `i + 6 <= len` (and `i + 2`).
            unsafe {
                assert_eq!(chunk::<6>(&bytes, i), chunk_checked::<6>(&bytes, i));
                assert_eq!(chunk::<2>(&bytes, i), chunk_checked::<2>(&bytes, i));
            }
        }
        assert_eq!(chunk_checked::<2>(&bytes, 96), [0, 0]);
        for dims in [[2u16, 2, 2], [3, 5, 4], [9, 7, 11]] {
            let len = dims.iter().map(|&d| d as usize).product::<usize>();
            let d = std::vec![7u8; len];
            let vol = Volume::new(&d, dims).unwrap();
            let top = dims.map(|d| (d as i32 - 1) << 16);
            let p = vol.cell(top);
            let rows = vol.rows(p).expect("the top corner's cell");
            assert!(rows[3] + 2 <= len);
            assert_eq!(vol.density_at(p), 7);
            let past = Probe {
                base: vol.last_cell as u32 + 1,
                f: 0,
            };
            assert!(vol.rows(past).is_none());
            assert_eq!(vol.density_at(past), 0);
        }
    }

    /// A sample whose cell bit is clear is transparent: at random points
    /// and on every face of random blob volumes, `visible(t)` is false only
    /// where the sampled density has zero weight; and the bits clear
    /// something. The bits' box is exactly the set bits' and every sample
    /// outside it is clear; with no bit set it is empty.
    #[test]
    fn clear_cells_hold_only_transparent_samples() {
        use crate::format::Rgb;
        let mut next = crate::numeric::xorshift(23);
        let tf = Transfer::from_points(&[
            super::super::TfPoint::new(120, 0, Rgb::new(255, 255, 255)),
            super::super::TfPoint::new(200, 255, Rgb::new(255, 255, 255)),
        ])
        .unwrap();
        let mut clear = 0;
        for dims in [[2u16, 2, 2], [3, 5, 4], [9, 7, 11], [16, 2, 3]] {
            let len = dims.iter().map(|&d| d as usize).product::<usize>();
            let dens: std::vec::Vec<u8> = (0..len)
                .map(|i| {
                    if (i / 5) % 3 == 0 {
                        next() as u8
                    } else {
                        next() as u8 / 3
                    }
                })
                .collect();
            let plain = Volume::new(&dens, dims).unwrap();
            let mut bits = std::vec![0u8; visible_cell_bytes(dims)];
            plain.compute_visible_cells(&tf, &mut bits).unwrap();
            let vol = plain.with_visible_cells(&bits).unwrap();
            let [bot, top] = vol.visible_box();
            for k in 0..4000 {
                let t = point(dims, k, &mut next);
                if !vol.cell_bits().visible(t) {
                    clear += 1;
                    let (d, _) = vol.sample(t);
                    assert_eq!(tf.weight(d), 0, "{dims:?} {t:?}");
                }
                // Outside the box: clear.
                if (0..3).any(|a| t[a] < bot[a] || t[a] > top[a]) {
                    assert!(!vol.cell_bits().visible(t), "{dims:?} {t:?}");
                }
            }
            // The box is the set bits' box, by a direct scan.
            let (mut lo, mut hi) = ([i32::MAX; 3], [i32::MIN; 3]);
            let [w, h, _] = dims.map(|d| d as usize);
            for i in 0..len {
                if bits[i >> 3] >> (i & 7) & 1 != 0 {
                    let p = [i % w, i / w % h, i / (w * h)].map(|v| v as i32);
                    lo = core::array::from_fn(|a| lo[a].min(p[a]));
                    hi = core::array::from_fn(|a| hi[a].max(p[a]));
                }
            }
            if lo[0] <= hi[0] {
                assert_eq!(bot, lo.map(|v| v << 16), "{dims:?}");
                let want = core::array::from_fn(|a| {
                    (hi[a] << 16 | 0xffff).min((dims[a] as i32 - 1) << 16)
                });
                assert_eq!(top, want, "{dims:?}");
            }
        }
        assert!(clear > 1000, "{clear}");
        // Nothing visible: an empty box.
        let d = [0u8; 27];
        let plain = Volume::new(&d, [3; 3]).unwrap();
        let mut bits = [0xffu8; visible_cell_bytes([3; 3])];
        plain.compute_visible_cells(&tf, &mut bits).unwrap();
        let [bot, top] = plain.with_visible_cells(&bits).unwrap().visible_box();
        assert!((0..3).all(|a| bot[a] > top[a]), "{bot:?} {top:?}");
    }
}
