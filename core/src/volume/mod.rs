//! Volume rendering with normal blending (seed 002): a density volume is
//! cut into view-aligned slices drawn back to front, each sample classified
//! through a lookup table, its **normal** (not its shaded colour) blended
//! into a per-pixel plane, and the frame shaded **once per pixel at the
//! end** — so shading costs the same whatever the volume's size.
//!
//! The stages, each a module:
//!
//! 1. **Slicing** (§3.1): [`VolumeView::new`] sets up `count` slices
//!    parallel to the image plane, farthest first, each cut to the volume's
//!    box and mapped affinely from screen to 3D texture coordinates
//!    (exact for view-aligned planes, in perspective too). Scan conversion
//!    solves each row's span from the box's six half-planes in integers.
//! 2. **Sampling**: trilinear in the densities ([`Volume`], 8-bit, read in
//!    place) with 8-bit weights; normals trilinear in precomputed quantised
//!    gradients ([`Normals::Quantized`], Q0.7) or central differences on the
//!    fly ([`Normals::OnTheFly`]).
//! 3. **Classification** (§3.2, §4.1): opacity and colour from the density
//!    through a [`Transfer`] table; a transparent sample stops here.
//! 4. **Normal blending** (§4.2): back to front,
//!    `N_f = N_s α_s + N_f (1 - α_s)`, likewise the colour and the
//!    accumulated opacity, in a [`VolumePlane`] of [`NormalCell`]s (normal
//!    in [`NORMAL_ONE`] units, Q1.15 opacity, Q8.8 colour: 14 bytes a
//!    pixel) — only in tiles of frames that draw a volume: a scene without
//!    one holds no plane and runs none of this code.
//! 5. **Shading** (§4.3), once per pixel: `I = Σ kd_j L_j · N_f + ka α_f`
//!    ([`VolumeLights`]; the seed's `kd L·N + ka Ia` with the ambient term
//!    weighted by the accumulated opacity, so the volume composites over
//!    whatever the tile already holds), times the composited colour, then
//!    dithered and packed over the tile's pixel like every fragment. New
//!    lights re-run only this pass.
//!
//! **Why it is equal** (§4.2): `L · N` is linear in `N`, so blending the
//! normals then shading equals shading each sample then blending the
//! intensities. The baseline, [`PerSliceShading`] (Meissner's method, the
//! seed's comparison), runs stages 1–3 with the same code and shades every
//! sample instead. Both use the linear (two-sided, unclamped) diffuse term
//! the seed's colour matrix computes; the sum is clamped at the end. With
//! one colour for all densities ([`Transfer::is_monochrome`]) they differ
//! only by rounding: each blend rounds once to half a unit of its plane
//! (`2^-15` of the normal, `2^-16` of the opacity), so over `k` blended
//! samples the difference stays below `k` such units, times the lights'
//! weight (the bound `tests/tests/volume.rs` checks). With colours from the
//! table the normal-blended image is an approximation (the mean colour
//! times the mean intensity), measured in `reports/volume.md`.
//!
//! Opaque geometry and volumes share a frame: draw the geometry into the
//! tile first (with a depth plane), then [`VolumePlane::composite`] skips
//! samples behind it and [`VolumePlane::shade`] blends over it.
//!
//! ```
//! use tilerast::prelude::*;
//! use tilerast::geometry::{Angle, Mat4};
//! use tilerast::volume::*;
//!
//! let mut density = vec![0u8; 16 * 16 * 16];
//! sphere(16, &mut density)?;
//! let vol = Volume::new(&density, [16; 3])?;
//! let tf = Transfer::from_points(&[
//!     TfPoint::new(100, 0, Rgb::new(255, 200, 150)),
//!     TfPoint::new(200, 255, Rgb::new(255, 200, 150)),
//! ])?;
//! let model = Mat4::<f32>::rotation_y(Angle::degrees(20));
//! let view = Mat4::look_at([0.0, 0.0, 2.0], [0.0; 3], [0.0, 1.0, 0.0])?;
//! let proj = Mat4::perspective(Angle::degrees(40), 1.0, 0.5, 4.0)?;
//! let screen = Rect::new(0, 0, 32, 32);
//! let scene: VolumeView<'_, 32> = VolumeView::new(vol, &tf, &model, &view, &proj, screen, 32)?;
//! let lights = VolumeLights::new(&model, &[([0.3f32, 0.5, 1.0], 0.8)], 0.2)?;
//!
//! type T = Tile<{ groups(32, 32) }, Planes<Rgb565Format, Depth16>>;
//! let (mut tile, mut plane) = (T::new(), VolumePlane::<{ groups(32, 32) }, NormalCell>::new());
//! tile.begin(screen, &Clear::default())?;
//! let stats = plane.composite(&tile, &scene, &NormalBlending);
//! plane.shade(&mut tile, &NormalBlending, &lights);
//! assert!(stats.composited > 0);
//! assert_ne!(tile.raw(16, 16), Some(0)); // the sphere's middle is lit
//! assert_eq!(tile.raw(0, 0), Some(0)); // a corner is not
//! # Ok::<(), tilerast::Error>(())
//! ```

mod data;
mod slice;
mod transfer;

use data::CellBits;
pub use data::{
    brick_bytes, sphere, visible_cell_bytes, Normals, Volume, BRICK_SHIFTS, MAX_VOLUME_SIDE,
    NORMAL_ONE,
};
pub use slice::Slice;
pub use transfer::{TfPoint, Transfer};

use crate::config::TileConfig;
use crate::error::Error;
use crate::format::{PixelFormat, Rgb};
use crate::fragment::DepthPlane;
use crate::geom::Rect;
use crate::geometry::{Mat4, Real, Vec3};
use crate::tile::Tile;

/// Directional lights most a [`VolumeLights`] holds.
pub const MAX_VOLUME_LIGHTS: usize = 4;

/// The shading of stage 5: directional lights turned into the volume's
/// voxel space, each with its diffuse weight `kd`, and the ambient term
/// `ka Ia`, all Q1.14.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct VolumeLights {
    dirs: heapless::Vec<[i32; 3], MAX_VOLUME_LIGHTS>,
    ambient: i32,
}

impl VolumeLights {
    /// Lights from world-space directions towards each light with their
    /// `kd`, and the ambient term, for a volume placed by `model` (a
    /// rotation, uniformly scaled: directions are turned by its transpose
    /// and normalised). `kd` and the ambient term lie in `[0, 2]` (the
    /// Q1.14 sums stay in `i32`). [`Error::Degenerate`] for a zero or
    /// non-finite direction or a weight out of range, [`Error::ListFull`]
    /// beyond [`MAX_VOLUME_LIGHTS`].
    ///
    /// ```
    /// use tilerast::geometry::Mat4;
    /// use tilerast::volume::VolumeLights;
    /// let l = VolumeLights::new(&Mat4::<f32>::IDENTITY, &[([0.0, 0.0, 2.0], 0.5)], 0.25)?;
    /// assert_eq!(l.directions(), &[[0, 0, 8192]]);
    /// assert_eq!(l.ambient(), 4096);
    /// # Ok::<(), tilerast::Error>(())
    /// ```
    pub fn new<S: Real>(
        model: &Mat4<S>,
        lights: &[(Vec3<S>, S)],
        ambient: S,
    ) -> Result<Self, Error> {
        let two = S::ONE + S::ONE;
        let weight = |w: S| {
            if w >= S::ZERO && w <= two {
                Ok(w)
            } else {
                Err(Error::Degenerate)
            }
        };
        let mut dirs = heapless::Vec::new();
        for &(d, kd) in lights {
            let kd = weight(kd)?;
            let m = model.transform_dir_transposed(d);
            let n = crate::geometry::normalize(m)?;
            let q = |v: S| (v * kd).to_fixed(14).ok_or(Error::NotFinite);
            dirs.push([q(n[0])?, q(n[1])?, q(n[2])?])
                .map_err(|_| Error::ListFull)?;
        }
        let ambient = weight(ambient)?.to_fixed(14).ok_or(Error::NotFinite)?;
        Ok(VolumeLights { dirs, ambient })
    }

    /// The lights' directions times `kd`, Q1.14, in voxel space.
    pub fn directions(&self) -> &[[i32; 3]] {
        &self.dirs
    }

    /// The ambient term, Q1.14.
    pub fn ambient(&self) -> i32 {
        self.ambient
    }

    /// `Σ_j kd_j L_j · n` (Q1.14 in and out), the linear diffuse term, of
    /// a normal in [`NORMAL_ONE`] units turned to Q1.14 ([`q14`]).
    #[inline(always)]
    fn diffuse(&self, n: [i32; 3]) -> i32 {
        let n = q14(n);
        let mut s = 0i32;
        for l in &self.dirs {
            s += (l[0] * n[0] + l[1] * n[1] + l[2] * n[2]) >> 14;
        }
        s
    }
}

/// A normal in [`NORMAL_ONE`] units (`127 x 2^8`) in Q1.14, rounded:
/// `x 129 / 2^8` (`127 x 129 = 16383`).
#[inline(always)]
fn q14(n: [i32; 3]) -> [i32; 3] {
    n.map(|v| (v * 129 + (1 << 7)) >> 8)
}

/// A frame's volume: the data, its transfer function and its slices set
/// up for one camera — up to `K` slices.
#[derive(Debug, Clone)]
pub struct VolumeView<'a, const K: usize> {
    volume: Volume<'a>,
    transfer: &'a Transfer,
    slices: heapless::Vec<Slice, K>,
    tops: [i32; 3],
}

impl<'a, const K: usize> VolumeView<'a, K> {
    /// Slices `volume` (placed by `model`: its box centred on the origin,
    /// the longest physical side 1 long) for the camera `view`, `proj` on
    /// `viewport`: `count` slices from the farthest box corner to the
    /// nearest ([`slice`](self) docs). Errors as the slicer's:
    /// [`Error::Degenerate`] for singular matrices or a projection whose
    /// `w` depends on screen position, [`Error::ListFull`] when more than
    /// `K` slices are visible.
    pub fn new<S: Real>(
        volume: Volume<'a>,
        transfer: &'a Transfer,
        model: &Mat4<S>,
        view: &Mat4<S>,
        proj: &Mat4<S>,
        viewport: Rect,
        count: u16,
    ) -> Result<Self, Error> {
        let mut slices = heapless::Vec::new();
        slice::slice(&volume, model, view, proj, viewport, count, &mut slices)?;
        let tops = volume.dims().map(|d| (d as i32 - 1) << 16);
        Ok(VolumeView {
            volume,
            transfer,
            slices,
            tops,
        })
    }

    /// The slices, farthest first.
    pub fn slices(&self) -> &[Slice] {
        &self.slices
    }

    /// The volume.
    pub fn volume(&self) -> &Volume<'a> {
        &self.volume
    }
}

/// What compositing a tile did.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct VolumeStats {
    /// Slices that touched the tile.
    pub slices: u32,
    /// Samples taken (pixels of slices, in front of the depth plane).
    pub samples: u32,
    /// Samples with non-zero opacity, blended.
    pub composited: u32,
    /// Samples in bricks or cells the transfer function makes transparent,
    /// skipped without a fetch ([`Volume::with_bricks`],
    /// [`Volume::with_visible_cells`]); part of `samples`.
    pub skipped: u32,
}

impl core::ops::AddAssign for VolumeStats {
    fn add_assign(&mut self, o: Self) {
        self.slices += o.slices;
        self.samples += o.samples;
        self.composited += o.composited;
        self.skipped += o.skipped;
    }
}

/// One pixel of a [`VolumePlane`].
pub trait Cell: Copy {
    /// Nothing composited.
    const EMPTY: Self;
    /// The accumulated opacity, Q1.15 (`32768` opaque).
    fn alpha(&self) -> i32;
}

/// A pixel of normal blending: the blended normal ([`NORMAL_ONE`] units),
/// opacity (Q1.15)
/// and colour (Q8.8), all premultiplied — 14 bytes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct NormalCell {
    /// `N_f`.
    pub n: [i16; 3],
    /// `α_f`.
    pub a: u16,
    /// `C_f`.
    pub c: [u16; 3],
}

impl Cell for NormalCell {
    const EMPTY: Self = NormalCell {
        n: [0; 3],
        a: 0,
        c: [0; 3],
    };
    fn alpha(&self) -> i32 {
        self.a as i32
    }
}

/// A pixel of per-slice shading: the blended shaded colour (Q8.14, signed:
/// the linear diffuse term can be negative) and opacity (Q1.15).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct ShadedCell {
    /// Premultiplied shaded colour.
    pub c: [i32; 3],
    /// `α_f`.
    pub a: u16,
}

impl Cell for ShadedCell {
    const EMPTY: Self = ShadedCell { c: [0; 3], a: 0 };
    fn alpha(&self) -> i32 {
        self.a as i32
    }
}

/// Pixels phase I walks in one run ([`VolumePlane::composite`]).
const RUN: usize = 32;

/// Phase I's empty-space test, chosen by type: none, the bricks' ranges,
/// the cells' bits.
const SKIP_NONE: u8 = 0;
/// See [`SKIP_NONE`].
const SKIP_BRICKS: u8 = 1;
/// See [`SKIP_NONE`].
const SKIP_CELLS: u8 = 2;

/// `f + (s - f) a` with `a` in Q1.15, rounded: back-to-front "over" of a
/// sample `s` onto a premultiplied accumulator `f` (`|s - f| <= 2
/// NORMAL_ONE < 2^16`: the product stays in `i32`).
#[inline(always)]
fn lerp(f: i32, s: i32, a: i32) -> i32 {
    f + (((s - f) * a + (1 << 14)) >> 15)
}

/// How samples are blended into a plane and the plane turned into colour.
pub trait Compositor {
    /// The plane's pixel.
    type Cell: Cell;
    /// Blends a classified sample (normal in [`NORMAL_ONE`] units, weight
    /// Q1.15, colour).
    fn blend(&self, cell: &mut Self::Cell, n: [i32; 3], a: i32, c: Rgb);
    /// The premultiplied colour a pixel shows (0..255 with 16 fraction
    /// bits, clamped at 0), for its accumulated opacity.
    fn resolve(&self, cell: &Self::Cell, lights: &VolumeLights) -> [i64; 3];
}

/// Normal blending (seed 002 §4.2): the plane keeps normals; lights come
/// at [`VolumePlane::shade`].
#[derive(Debug, Clone, Copy, Default)]
pub struct NormalBlending;

impl Compositor for NormalBlending {
    type Cell = NormalCell;
    #[inline(always)]
    fn blend(&self, cell: &mut NormalCell, n: [i32; 3], a: i32, c: Rgb) {
        for (f, s) in cell.n.iter_mut().zip(n) {
            *f = lerp(*f as i32, s, a) as i16;
        }
        cell.a = lerp(cell.a as i32, 1 << 15, a) as u16;
        for (f, s) in cell.c.iter_mut().zip([c.r, c.g, c.b]) {
            *f = lerp(*f as i32, (s as i32) << 8, a) as u16;
        }
    }

    fn resolve(&self, cell: &NormalCell, lights: &VolumeLights) -> [i64; 3] {
        let a = cell.a as i64;
        if a == 0 {
            return [0; 3];
        }
        let n = cell.n.map(|v| v as i32);
        // I_f = Σ kd L · N_f + ka α_f (Q1.14, premultiplied by α_f).
        let i = (lights.diffuse(n) as i64 + ((lights.ambient as i64 * a) >> 15)).max(0);
        // Colour = I_f C_f / α_f: C_f (Q8.8) I (Q1.14) 2^15 / a, to 16
        // fraction bits: C I 2^9 / a, by one reciprocal.
        let r = reciprocal40(a as u32) as i64;
        cell.c.map(|c| (((c as i64 * i) >> 8) * r) >> 23)
    }
}

/// `floor((2^40 + a / 2) / a)` for `0 < a <= 2^15`, phase II's reciprocal
/// of a pixel's opacity, by two 32-bit divisions (16-bit digits of long
/// division: `2^24 / a`, then the remainder with the low digit `a / 2`)
/// instead of a 64-bit one (a library call on every chip here).
#[inline(always)]
fn reciprocal40(a: u32) -> u64 {
    debug_assert!(a > 0 && a <= 1 << 15);
    let hi = (1 << 24) / a;
    let lo = ((((1 << 24) - hi * a) << 16) | (a / 2)) / a;
    (hi as u64) << 16 | lo as u64
}

/// Per-slice shading, the seed's baseline (Meissner et al.): every sample
/// is shaded with `lights` as it is classified, and the intensities are
/// blended.
#[derive(Debug, Clone, Copy)]
pub struct PerSliceShading<'l>(pub &'l VolumeLights);

impl Compositor for PerSliceShading<'_> {
    type Cell = ShadedCell;
    #[inline(always)]
    fn blend(&self, cell: &mut ShadedCell, n: [i32; 3], a: i32, c: Rgb) {
        let l = self.0;
        let i = l.diffuse(n) + l.ambient;
        for (f, c) in cell.c.iter_mut().zip([c.r, c.g, c.b]) {
            let s = c as i64 * i as i64;
            let v = *f as i64;
            *f = (v + (((s - v) * a as i64 + (1 << 14)) >> 15)) as i32;
        }
        cell.a = lerp(cell.a as i32, 1 << 15, a) as u16;
    }

    fn resolve(&self, cell: &ShadedCell, _: &VolumeLights) -> [i64; 3] {
        cell.c.map(|c| (c.max(0) as i64) << 2)
    }
}

/// The per-pixel plane a tile composites a volume into: `8 N` cells,
/// chosen by type ([`NormalCell`] for normal blending, [`ShadedCell`] for
/// the per-slice baseline). Only frames that draw a volume hold one.
///
/// ```
/// use tilerast::prelude::*;
/// use tilerast::volume::{VolumePlane, NormalCell};
/// assert_eq!(VolumePlane::<{ groups(32, 32) }, NormalCell>::bytes(), 14 * 1024);
/// ```
pub struct VolumePlane<const N: usize, K: Cell> {
    cells: [[K; 8]; N],
    area: Rect,
}

impl<const N: usize, K: Cell> Default for VolumePlane<N, K> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize, K: Cell> VolumePlane<N, K> {
    /// An empty plane; `const`, so it can be a `static`.
    pub const fn new() -> Self {
        VolumePlane {
            cells: [[K::EMPTY; 8]; N],
            area: Rect::new(0, 0, 0, 0),
        }
    }

    /// Bytes of the plane's cells.
    pub const fn bytes() -> usize {
        core::mem::size_of::<[[K; 8]; N]>()
    }

    /// The cell of screen pixel `(x, y)` of the last composited tile.
    pub fn cell(&self, x: i32, y: i32) -> Option<&K> {
        let a = self.area;
        let (dx, dy) = (x - a.x, y - a.y);
        if dx < 0 || dy < 0 || dx >= a.w as i32 || dy >= a.h as i32 {
            return None;
        }
        Some(&self.cells.as_flattened()[(dy * a.w as i32 + dx) as usize])
    }

    /// Composites `view` into the plane over `tile`'s area (stages 1–4),
    /// back to front, each sample only where it is nearer than the tile's
    /// depth plane. The plane starts empty; the tile is only read.
    pub fn composite<const TN: usize, C: TileConfig, M: Compositor<Cell = K>, const S: usize>(
        &mut self,
        tile: &Tile<TN, C>,
        view: &VolumeView<'_, S>,
        comp: &M,
    ) -> VolumeStats {
        let area = tile.area;
        self.area = area;
        let cells = self.cells.as_flattened_mut();
        let n = (area.w * area.h) as usize;
        let mut stats = VolumeStats::default();
        if n > cells.len() {
            // A tile larger than the plane: nothing composited or shaded.
            self.area = Rect::new(0, 0, 0, 0);
            return stats;
        }
        cells[..n].fill(K::EMPTY);
        // Chosen once: a volume without bricks or cell bits runs a loop
        // without the test; the cell bits, finer, win over the bricks.
        let cells = &mut cells[..n];
        if view.volume.has_visible_cells() {
            Self::slices::<TN, C, M, S, SKIP_CELLS>(cells, area, tile, view, comp, &mut stats);
        } else if view.volume.brick_shift().is_some() {
            Self::slices::<TN, C, M, S, SKIP_BRICKS>(cells, area, tile, view, comp, &mut stats);
        } else {
            Self::slices::<TN, C, M, S, SKIP_NONE>(cells, area, tile, view, comp, &mut stats);
        }
        stats
    }

    /// Phase I over the slices into `cells` (the tile's area), testing
    /// each sample's brick (`SKIP_BRICKS`) or cell bit (`SKIP_CELLS`).
    fn slices<
        const TN: usize,
        C: TileConfig,
        M: Compositor<Cell = K>,
        const S: usize,
        const SKIP: u8,
    >(
        cells: &mut [K],
        area: Rect,
        tile: &Tile<TN, C>,
        view: &VolumeView<'_, S>,
        comp: &M,
        stats: &mut VolumeStats,
    ) {
        let (vol, tf) = (&view.volume, view.transfer);
        // Counted in locals (registers), added once.
        let (mut samples, mut skipped, mut composited) = (0, 0, 0);
        // A row is walked in runs of up to `RUN` pixels, in two passes:
        // the first tests depth (and bricks or cells) with few values live
        // and lists the samples to fetch; the second fetches, classifies
        // and blends only those. One pass carrying both kept
        // the fetch's values spilled on every pixel. Each sample lands in
        // its own cell of the plane, so the order of blends is unchanged.
        let mut keep = [0u8; RUN];
        // Taken out of the volume once: the first pass sees a plain slice.
        let bits = vol.cell_bits();
        // The samples walked: the volume's, or the box of its visible
        // cells (the same image: every sample outside it is clear).
        let walked = match SKIP {
            SKIP_CELLS => vol.visible_box(),
            _ => [[0; 3], view.tops],
        };
        // Every slice nearer than the tile's nearest depth (nothing drawn
        // in front, or no depth plane): the first pass runs without the
        // depth test, the same samples (a volume alone, the M4 sphere's
        // phase I: 132.3 -> 123.5 instructions a sample).
        let farthest = view.slices.iter().map(|s| s.z).max().unwrap_or(0);
        let (_, nearest, _) = tile
            .depth
            .farther_min_max(0..(area.w * area.h) as usize, farthest);
        let open = farthest < nearest;
        for s in view.slices.iter() {
            let Some(r) = s.bounds.intersect(&area) else {
                continue;
            };
            stats.slices += 1;
            let (z, tx) = (s.z, s.tx);
            for py in r.y..r.y + r.h as i32 {
                let (x0, x1, mut t) = s.row(py, r.x, r.x + r.w as i32, walked);
                let row = (py - area.y) * area.w as i32 - area.x;
                let mut cx = x0;
                while cx < x1 {
                    let n = (x1 - cx).min(RUN as i32) as usize;
                    let first = (row + cx) as usize;
                    let (m, passed, empty) = if open {
                        Self::walk_run::<TN, C, SKIP, false>(
                            tile, first, n, z, t, tx, vol, bits, tf, &mut keep,
                        )
                    } else {
                        Self::walk_run::<TN, C, SKIP, true>(
                            tile, first, n, z, t, tx, vol, bits, tf, &mut keep,
                        )
                    };
                    samples += passed;
                    skipped += empty;
                    if let Some(cells) = cells.get_mut(first..) {
                        let keep = keep.get(..m).unwrap_or_default();
                        composited += Self::fetch_run(cells, vol, tf, comp, t, tx, keep);
                    }
                    for (t, d) in t.iter_mut().zip(tx) {
                        *t += d * n as i32;
                    }
                    cx += n as i32;
                }
            }
        }
        stats.samples += samples;
        stats.skipped += skipped;
        stats.composited += composited;
    }

    /// Phase I's first pass over a run of `n <= RUN` pixels from tile
    /// index `first`, the first at voxel coordinate `t`: lists in `keep`
    /// the samples nearer than the depth plane and not in clear bricks or
    /// cells. Returns how many it listed, how many passed the depth test,
    /// how many of those it skipped. `DEPTH` false: the caller found every
    /// sample nearer than the depth plane, and the test is left out. Not
    /// inlined: the walk's state stays
    /// out of its registers.
    #[allow(clippy::too_many_arguments)]
    #[inline(never)]
    fn walk_run<const TN: usize, C: TileConfig, const SKIP: u8, const DEPTH: bool>(
        tile: &Tile<TN, C>,
        first: usize,
        n: usize,
        z: u16,
        mut t: [i32; 3],
        tx: [i32; 3],
        vol: &Volume<'_>,
        bits: CellBits<'_>,
        tf: &Transfer,
        keep: &mut [u8; RUN],
    ) -> (usize, u32, u32) {
        let n = n.min(RUN);
        // Depth failures are counted (rare where nothing is drawn in
        // front), not passes: one add fewer a sample.
        let (mut m, mut hidden) = (0, 0);
        for k in 0..n {
            if DEPTH && z >= tile.depth.read(first + k) {
                hidden += 1;
            } else {
                let empty = match SKIP {
                    SKIP_BRICKS => vol
                        .brick_range(t)
                        .is_some_and(|(lo, hi)| tf.transparent(lo, hi)),
                    SKIP_CELLS => !bits.visible(t),
                    _ => false,
                };
                if !empty {
                    // `m <= k < RUN`.
                    keep[m % RUN] = k as u8;
                    m += 1;
                }
            }
            for (t, d) in t.iter_mut().zip(tx) {
                *t += d;
            }
        }
        let passed = n as u32 - hidden;
        (m, passed, passed - m as u32)
    }

    /// Phase I's second pass over a run: samples `t + k tx` for each
    /// listed `k`, classifies it and blends the visible ones into
    /// `cells[k]`; returns how many it blended. Not inlined: its own
    /// registers, not the walk's.
    #[inline(never)]
    fn fetch_run<M: Compositor<Cell = K>>(
        cells: &mut [K],
        vol: &Volume<'_>,
        tf: &Transfer,
        comp: &M,
        t: [i32; 3],
        tx: [i32; 3],
        keep: &[u8],
    ) -> u32 {
        let mut composited = 0;
        for &k in keep {
            let p = vol.cell(core::array::from_fn(|a| t[a] + tx[a] * k as i32));
            let d = vol.density_at(p);
            let a = tf.weight(d) as i32;
            if a != 0 {
                composited += 1;
                let nrm = vol.normal_at(&p);
                if let Some(cell) = cells.get_mut(k as usize) {
                    comp.blend(cell, nrm, a, tf.color(d));
                }
            }
        }
        composited
    }

    /// Shades the plane into `tile` (stage 5): every pixel with opacity
    /// gets its resolved colour blended over the tile's, dithered and
    /// packed. Call again with other lights for another image of the same
    /// composite.
    pub fn shade<const TN: usize, C: TileConfig, M: Compositor<Cell = K>>(
        &self,
        tile: &mut Tile<TN, C>,
        comp: &M,
        lights: &VolumeLights,
    ) {
        let area = tile.area;
        if area != self.area {
            return;
        }
        let cells = self.cells.as_flattened();
        for y in 0..area.h as i32 {
            for x in 0..area.w as i32 {
                let idx = (y * area.w as i32 + x) as usize;
                let cell = &cells[idx];
                let a = cell.alpha();
                if a == 0 {
                    continue;
                }
                let premult = comp.resolve(cell, lights);
                let lanes = <C::Format as PixelFormat>::lanes_from_rgb(premult);
                tile.over(
                    idx,
                    (area.x + x) as u32,
                    (area.y + y) as u32,
                    lanes,
                    (1 << 15) - a,
                );
            }
        }
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use crate::geometry::{Angle, Mat4};
    use crate::prelude::*;
    use std::vec;

    /// The procedural sphere, `side` voxels a side.
    fn sphere_of(side: u16) -> std::vec::Vec<u8> {
        let mut d = vec![0u8; (side as usize).pow(3)];
        sphere(side, &mut d).unwrap();
        d
    }

    /// Skipping bricks or cells the transfer function makes transparent
    /// changes no cell: the same plane with and without bricks, for every
    /// brick side, and with the cells' bits,
    /// on the sphere and on noise (whose ranges are wide), from several
    /// angles; and it skips something where there is empty space.
    #[test]
    fn brick_skipping_changes_nothing() {
        const SIDE: u16 = 20;
        let n = SIDE as usize;
        let sphere_d = sphere_of(SIDE);
        let mut next = crate::numeric::xorshift(7);
        // Noise in blobs: mostly clear, some dense clusters.
        let noise: std::vec::Vec<u8> = (0..n * n * n)
            .map(|i| {
                let r = next() as u8;
                if (i / 97) % 5 == 0 {
                    r
                } else {
                    r / 3
                }
            })
            .collect();
        let tf = Transfer::from_points(&[
            TfPoint::new(90, 0, Rgb::new(255, 120, 60)),
            TfPoint::new(170, 60, Rgb::new(250, 230, 120)),
            TfPoint::new(230, 200, Rgb::new(255, 255, 255)),
        ])
        .unwrap();
        let view = Mat4::look_at([0.0f32, 0.0, 2.0], [0.0; 3], [0.0, 1.0, 0.0]).unwrap();
        let proj = Mat4::perspective(Angle::degrees(40), 1.0, 0.5, 4.0).unwrap();
        let screen = Rect::new(0, 0, 32, 32);
        type T = Tile<{ groups(32, 32) }, Planes<Rgb565Format, Depth16>>;
        type P = VolumePlane<{ groups(32, 32) }, NormalCell>;
        let mut tile = T::new();
        tile.begin(screen, &Clear::default()).unwrap();
        let (mut skipped, mut boxed) = (0, 0);
        for density in [&sphere_d, &noise] {
            let plain = Volume::new(density, [SIDE; 3]).unwrap();
            for deg in [0, 33, 90, 161, 270] {
                let model = Mat4::<f32>::rotation_y(Angle::degrees(deg))
                    .mul(&Mat4::rotation_x(Angle::degrees(deg / 3)));
                let cells = |vol: Volume<'_>| {
                    let scene: VolumeView<'_, 24> =
                        VolumeView::new(vol, &tf, &model, &view, &proj, screen, 24).unwrap();
                    let mut plane = P::new();
                    let stats = plane.composite(&tile, &scene, &NormalBlending);
                    (plane.cells, stats)
                };
                let (want, base) = cells(plain);
                assert!(base.composited > 0 && base.skipped == 0);
                let mut most = 0;
                for shift in BRICK_SHIFTS {
                    let mut bricks = vec![0u8; brick_bytes([SIDE; 3], shift)];
                    plain.compute_bricks(shift, &mut bricks).unwrap();
                    let vol = plain.with_bricks(&bricks, shift).unwrap();
                    let (got, stats) = cells(vol);
                    assert!(got == want, "shift {shift}, {deg} degrees");
                    assert_eq!(stats.samples, base.samples);
                    assert_eq!(stats.composited, base.composited);
                    skipped += stats.skipped;
                    most = most.max(stats.skipped);
                }
                // The cells' bits: the same plane, at least as much
                // skipped as the finest bricks (and over them, too); the
                // samples outside their box are not even walked.
                let mut bits = vec![0u8; visible_cell_bytes([SIDE; 3])];
                plain.compute_visible_cells(&tf, &mut bits).unwrap();
                let vol = plain.with_visible_cells(&bits).unwrap();
                let (got, stats) = cells(vol);
                assert!(got == want, "cells, {deg} degrees");
                assert!(stats.samples <= base.samples);
                assert_eq!(stats.composited, base.composited);
                let unwalked = base.samples - stats.samples;
                assert!(
                    stats.skipped + unwalked >= most,
                    "{} < {most}",
                    stats.skipped
                );
                boxed += unwalked;
                let mut bricks = vec![0u8; brick_bytes([SIDE; 3], 1)];
                plain.compute_bricks(1, &mut bricks).unwrap();
                let both = vol.with_bricks(&bricks, 1).unwrap();
                assert!(cells(both) == (got, stats), "cells and bricks");
            }
        }
        assert!(skipped > 1000, "{skipped}");
        // The sphere's box leaves samples out.
        assert!(boxed > 1000, "{boxed}");
    }

    /// Phase I leaves the depth test out only when every slice is nearer
    /// than the whole tile: a far depth at a pixel the volume misses (the
    /// tested walk) changes nothing against the cleared tile (the open
    /// walk), and a near depth at a pixel it covers hides exactly that
    /// pixel — with and without the cells' bits.
    #[test]
    fn depth_test_left_out_only_where_nothing_is_nearer() {
        const SIDE: u16 = 20;
        let d = sphere_of(SIDE);
        let tf = Transfer::from_points(&[
            TfPoint::new(90, 0, Rgb::new(255, 120, 60)),
            TfPoint::new(230, 200, Rgb::new(255, 255, 255)),
        ])
        .unwrap();
        let mut bits = vec![0u8; visible_cell_bytes([SIDE; 3])];
        let plain = Volume::new(&d, [SIDE; 3]).unwrap();
        plain.compute_visible_cells(&tf, &mut bits).unwrap();
        let model = Mat4::<f32>::rotation_y(Angle::degrees(30));
        let view = Mat4::look_at([0.0f32, 0.0, 3.0], [0.0; 3], [0.0, 1.0, 0.0]).unwrap();
        let proj = Mat4::perspective(Angle::degrees(40), 1.0, 0.5, 6.0).unwrap();
        let screen = Rect::new(0, 0, 32, 32);
        type T = Tile<{ groups(32, 32) }, Planes<Rgb565Format, Depth16>>;
        type P = VolumePlane<{ groups(32, 32) }, NormalCell>;
        for vol in [plain, plain.with_visible_cells(&bits).unwrap()] {
            let scene: VolumeView<'_, 16> =
                VolumeView::new(vol, &tf, &model, &view, &proj, screen, 16).unwrap();
            let farthest = scene.slices().iter().map(|s| s.z).max().unwrap();
            let run = |set: Option<(usize, u16)>| {
                let mut tile = T::new();
                tile.begin(screen, &Clear::default()).unwrap();
                if let Some((i, z)) = set {
                    tile.depth.put(i, z);
                }
                let mut plane = P::new();
                let stats = plane.composite(&tile, &scene, &NormalBlending);
                (plane.cells, stats)
            };
            let (want, base) = run(None);
            let flat = want.as_flattened();
            let missed = flat.iter().position(|c| c.a == 0).unwrap();
            let covered = flat.iter().position(|c| c.a != 0).unwrap();
            assert!(run(Some((missed, farthest))) == (want, base));
            let (got, stats) = run(Some((covered, 0)));
            assert!(stats.samples < base.samples);
            for (i, (g, w)) in got.as_flattened().iter().zip(flat).enumerate() {
                assert_eq!(*g, if i == covered { NormalCell::EMPTY } else { *w });
            }
        }
    }

    /// Each brick's range is exactly its voxels' (one past its upper
    /// faces, cut to the volume), against a direct scan; bad shifts and
    /// lengths are refused.
    #[test]
    fn brick_ranges_are_their_voxels() {
        let dims = [7u16, 5, 9];
        let mut next = crate::numeric::xorshift(3);
        let d: std::vec::Vec<u8> = (0..7 * 5 * 9).map(|_| next() as u8).collect();
        let vol = Volume::new(&d, dims).unwrap();
        for shift in BRICK_SHIFTS {
            let mut b = vec![0u8; brick_bytes(dims, shift)];
            vol.compute_bricks(shift, &mut b).unwrap();
            let mut i = 0;
            let side = 1usize << shift;
            for bz in 0..9usize.div_ceil(side) {
                for by in 0..5usize.div_ceil(side) {
                    for bx in 0..7usize.div_ceil(side) {
                        let (mut lo, mut hi) = (255u8, 0u8);
                        for z in bz * side..=((bz + 1) * side).min(8) {
                            for y in by * side..=((by + 1) * side).min(4) {
                                for x in bx * side..=((bx + 1) * side).min(6) {
                                    lo = lo.min(vol.density(x, y, z));
                                    hi = hi.max(vol.density(x, y, z));
                                }
                            }
                        }
                        assert_eq!(
                            (b[i], b[i + 1]),
                            (lo, hi),
                            "shift {shift} brick {bx},{by},{bz}"
                        );
                        i += 2;
                    }
                }
            }
            assert!(vol.with_bricks(&b[1..], shift).is_err());
        }
        assert!(vol.compute_bricks(0, &mut [0; 4096]).is_err());
        assert!(vol.compute_bricks(6, &mut [0; 4096]).is_err());
        assert!(vol.compute_bricks(2, &mut [0; 8]).is_err());
    }

    /// Phase II's two 32-bit divisions equal the 64-bit one for every
    /// opacity.
    #[test]
    fn reciprocal40_is_the_64_bit_quotient() {
        for a in 1..=1u32 << 15 {
            let want = ((1u64 << 40) + a as u64 / 2) / a as u64;
            assert_eq!(reciprocal40(a), want, "{a}");
        }
    }
}
