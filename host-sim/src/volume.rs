//! Volumes in the simulator (seed 002): loading (NIfTI through the
//! `nifti` crate, raw bytes, the seed's procedural sphere), resampling, the
//! scene file's `[volume]` table, and rendering through the core's volume
//! stage ([`tilerast::volume`]) in the same frame as the scene's commands.
//!
//! ```toml
//! [volume]
//! source = "sphere"          # "sphere", a .nii / .nii.gz, or a .raw (then dims)
//! size = 64                  # sphere side, or resample the file to size^3
//! dims = [64, 64, 64]        # .raw only: sides, x fastest
//! slices = 128               # view-aligned slices (the seed: 64..256)
//! normals = "quantized"      # quantized (precomputed, 3 bytes a voxel) | on_the_fly
//! mode = "normal"            # normal blending | per_slice (Meissner's baseline)
//! view = "shaded"            # shaded | normals (the composited normals as colour, Fig. 2a)
//! transfer = [[60, 0, 255, 220, 190], [120, 40, 255, 220, 190]]  # density, alpha, r, g, b
//! eye = [0, 0, 2.2]          # camera, looking at the origin, y up
//! fov = 40                   # degrees
//! rotate = [0, 30, 0]        # the volume's rotation about x, y, z (degrees)
//! lights = [[0.4, 0.6, 1.0, 0.8]]  # direction towards the light (world) and kd
//! ambient = 0.2
//! ```

use crate::error::{Error, Readable, Result};
use crate::image::Image;
use crate::render::{copy_tile, frame_and_tile, Config, FormatKind, Rendered};
use serde::Deserialize;
use std::path::{Path, PathBuf};
use std::time::Instant;
use tilerast::geometry::{Angle, Mat4};
use tilerast::prelude::*;
use tilerast::volume::{
    Compositor, NormalBlending, NormalCell, PerSliceShading, TfPoint, Transfer, Volume,
    VolumeLights, VolumePlane, VolumeStats, VolumeView, NORMAL_ONE,
};

/// Pixel capacity (groups of 8) of a volume scene's tile: 16,384 pixels
/// (a 128 x 128 tile; its normal plane is 224 KB).
pub const VOLUME_GROUPS: usize = 2048;

/// Most slices a scene may ask for.
pub const MAX_SLICES: usize = 1024;

/// Largest side of a volume the simulator makes (sphere, resampling):
/// 256^3 is 64 MB of densities and normals, the seed's largest.
pub const MAX_MADE_SIDE: u16 = 256;

/// Fills `buf` from `r`; on an error, the bytes read before it.
fn read_all(
    r: &mut impl std::io::Read,
    buf: &mut [u8],
) -> std::result::Result<(), (std::io::Error, usize)> {
    let mut got = 0;
    while got < buf.len() {
        match r.read(&mut buf[got..]) {
            Ok(0) => return Err((std::io::ErrorKind::UnexpectedEof.into(), got)),
            Ok(k) => got += k,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(e) => return Err((e, got)),
        }
    }
    Ok(())
}

fn made_side(n: u16) -> Result<()> {
    if (2..=MAX_MADE_SIDE).contains(&n) {
        Ok(())
    } else {
        Err(Error::Unsupported(format!(
            "a made volume's side is 2..={MAX_MADE_SIDE}, not {n}"
        )))
    }
}

/// A density volume in memory, with its quantised normals.
#[derive(Debug, Clone, PartialEq)]
pub struct VolumeData {
    /// Densities, `x` fastest.
    pub density: Vec<u8>,
    /// Sides in voxels.
    pub dims: [u16; 3],
    /// Voxel spacing, Q8.8 (millimetres for the MRI).
    pub spacing: [u16; 3],
    /// [`Volume::compute_normals`] of the densities.
    pub normals: Vec<u8>,
    /// [`Volume::compute_bricks`] of the densities, bricks of
    /// `2^brick_shift` cells a side.
    pub bricks: Vec<u8>,
    /// The bricks' side, as a shift ([`BRICK_SHIFT`] unless
    /// [`VolumeData::with_brick_shift`] chose another).
    pub brick_shift: u32,
}

/// The simulator's empty-space bricks: 4 cells a side (2 bytes per 64
/// voxels; `volume-report` measures the other sides).
pub const BRICK_SHIFT: u32 = 2;

impl VolumeData {
    fn with_normals(density: Vec<u8>, dims: [u16; 3], spacing: [u16; 3]) -> Result<Self> {
        let mut normals = vec![0u8; 3 * density.len()];
        let mut bricks = vec![0u8; tilerast::volume::brick_bytes(dims, BRICK_SHIFT)];
        let v = Volume::new(&density, dims)?;
        v.compute_normals(&mut normals)?;
        v.compute_bricks(BRICK_SHIFT, &mut bricks)?;
        Ok(VolumeData {
            density,
            dims,
            spacing,
            normals,
            bricks,
            brick_shift: BRICK_SHIFT,
        })
    }

    /// The same data with bricks of `2^shift` cells a side
    /// ([`tilerast::volume::BRICK_SHIFTS`]).
    pub fn with_brick_shift(mut self, shift: u32) -> Result<Self> {
        let mut bricks = vec![0u8; tilerast::volume::brick_bytes(self.dims, shift)];
        Volume::new(&self.density, self.dims)?.compute_bricks(shift, &mut bricks)?;
        self.bricks = bricks;
        self.brick_shift = shift;
        Ok(self)
    }

    /// The seed's "small sphere", `n^3` ([`tilerast::volume::sphere`]);
    /// [`Error::Unsupported`] for `n` outside `2..=`[`MAX_MADE_SIDE`].
    pub fn sphere(n: u16) -> Result<Self> {
        made_side(n)?;
        let mut d = vec![0u8; (n as usize).pow(3)];
        tilerast::volume::sphere(n, &mut d)?;
        Self::with_normals(d, [n; 3], [256; 3])
    }

    /// A NIfTI-1 file (`.nii` or `.nii.gz`): 8-bit data as it is, other
    /// types rescaled from their range to `0..=255`; spacing from `pixdim`.
    /// At most the default [`Limits::max_bytes`](crate::Limits) of
    /// (decompressed) data: [`VolumeData::load_nifti_within`].
    pub fn load_nifti(path: &Path) -> Result<Self> {
        Self::load_nifti_within(path, crate::Limits::default().max_bytes)
    }

    /// [`VolumeData::load_nifti`] reading at most `max_bytes` of data.
    /// The header is read first and what it declares — dimensions, voxel
    /// type, data offset — is checked before anything else is read: a
    /// 1 MB gzip bomb that declares 1024³ voxels is refused from its
    /// header, and the decompressed stream is cut at the declared size,
    /// so no file makes the loader read or allocate more than that.
    /// Errors are sentences naming the file ("the data ends early: 40 of
    /// 512 bytes").
    pub fn load_nifti_within(path: &Path, max_bytes: u64) -> Result<Self> {
        let file = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
        Self::read_nifti(std::io::BufReader::new(file), path, max_bytes)
    }

    /// [`VolumeData::load_nifti_within`] from `input` (a `.nii` or a
    /// gzipped one, told apart by its first bytes), errors naming `path`.
    ///
    /// ```
    /// use std::path::Path;
    /// use tilerast_sim::volume::VolumeData;
    /// let e = VolumeData::read_nifti(&b"short"[..], Path::new("x.nii"), 1 << 20).unwrap_err();
    /// assert_eq!(e.to_string(), "x.nii: the file ends early: 5 of 352 bytes");
    /// ```
    pub fn read_nifti(
        mut input: impl std::io::BufRead,
        path: &Path,
        max_bytes: u64,
    ) -> Result<Self> {
        use nifti::{InMemNiftiObject, NiftiHeader, NiftiObject, RandomAccessNiftiVolume};
        use std::io::Read;
        let bad = |m: String| Error::Unsupported(format!("{}: {m}", path.display()));
        let gz = {
            let head = input.fill_buf().map_err(|e| Error::io(path, e))?;
            head.starts_with(&[0x1f, 0x8b])
        };
        let mut src: Box<dyn Read + '_> = if gz {
            Box::new(flate2::bufread::GzDecoder::new(input))
        } else {
            Box::new(input)
        };
        let what = if gz { "the gzip stream" } else { "the file" };
        let read_err = |e: std::io::Error, got: usize, want: u64| -> Error {
            match e.kind() {
                std::io::ErrorKind::UnexpectedEof => {
                    bad(format!("{what} ends early: {got} of {want} bytes"))
                }
                std::io::ErrorKind::InvalidInput | std::io::ErrorKind::InvalidData => {
                    bad(format!("{what} is corrupt after {got} bytes: {e}"))
                }
                _ => Error::io(path, e),
            }
        };
        // The header: 348 bytes, then 4 of extension flags.
        let mut head = vec![0u8; 352];
        read_all(&mut src, &mut head).map_err(|(e, got)| read_err(e, got, 352))?;
        let h = NiftiHeader::from_reader(&head[..])
            .map_err(|e| bad(format!("not a NIfTI-1 header: {e}")))?;
        if h.dim[0] < 3 || h.dim[0] > 7 {
            return Err(bad(format!(
                "{} dimensions: a volume has 3 (dim[0] = {})",
                h.dim[0], h.dim[0]
            )));
        }
        let side = 2..=tilerast::volume::MAX_VOLUME_SIDE;
        if let Some((axis, &d)) = h.dim[1..4]
            .iter()
            .enumerate()
            .find(|(_, d)| !side.contains(*d))
        {
            return Err(bad(format!(
                "side {axis} is {} voxels: each side must be 2..={}",
                d as i16,
                tilerast::volume::MAX_VOLUME_SIDE
            )));
        }
        if let Some(&extra) = h.dim[4..=h.dim[0] as usize].iter().find(|&&d| d != 1) {
            return Err(bad(format!(
                "a 4D series ({} volumes): one 3D volume is read",
                extra as i16
            )));
        }
        let dims = [h.dim[1], h.dim[2], h.dim[3]];
        let n = dims.iter().map(|&d| d as u64).product::<u64>();
        let bytes_per = match h.bitpix {
            8 | 16 | 32 | 64 => h.bitpix as u64 / 8,
            b => return Err(bad(format!("{b} bits a voxel: 8, 16, 32 or 64 are read"))),
        };
        let off = h.vox_offset;
        if !off.is_finite() || !(352.0..=16.0 * 1024.0 * 1024.0).contains(&off) {
            return Err(bad(format!(
                "the data offset (vox_offset) is {}: it must be 352..=16 MiB",
                Readable(off as f64)
            )));
        }
        let total = off as u64 + n * bytes_per;
        if total > max_bytes {
            return Err(bad(format!(
                "{}x{}x{} voxels of {bytes_per} bytes ({} bytes) exceed the limit of {max_bytes} bytes",
                dims[0], dims[1], dims[2], total
            )));
        }
        let mut all = head;
        all.resize(total as usize, 0);
        read_all(&mut src, &mut all[352..]).map_err(|(e, got)| read_err(e, 352 + got, total))?;
        for (name, v) in [("scl_slope", h.scl_slope), ("scl_inter", h.scl_inter)] {
            if !v.is_finite() {
                return Err(bad(format!("{name} is {v}: it must be finite")));
            }
        }
        let obj = InMemNiftiObject::from_reader(&all[..]).map_err(|e| bad(e.to_string()))?;
        let n = n as usize;
        let vol = obj.into_volume();
        let plain =
            h.datatype == 2 && (h.scl_slope == 0.0 || h.scl_slope == 1.0) && h.scl_inter == 0.0;
        let density = if plain {
            let mut raw = vol.into_raw_data();
            raw.truncate(n);
            raw
        } else {
            let mut v = Vec::with_capacity(n);
            for z in 0..dims[2] {
                for y in 0..dims[1] {
                    for x in 0..dims[0] {
                        v.push(vol.get_f64(&[x, y, z]).map_err(|e| bad(e.to_string()))?);
                    }
                }
            }
            let bad_voxels = v.iter().filter(|x| !x.is_finite()).count();
            if bad_voxels > 0 {
                return Err(bad(format!(
                    "{bad_voxels} of {n} voxels are NaN or infinite"
                )));
            }
            let (lo, hi) = v
                .iter()
                .fold((f64::MAX, f64::MIN), |(a, b), &x| (a.min(x), b.max(x)));
            let span = (hi - lo).max(1e-12);
            v.iter()
                .map(|&x| ((x - lo) / span * 255.0).round() as u8)
                .collect()
        };
        if density.len() != n {
            return Err(bad(format!(
                "{} voxels where its dimensions declare {n}",
                density.len()
            )));
        }
        let spacing = [1, 2, 3].map(|i| {
            let s = h.pixdim[i].abs() as f64;
            let s = if s.is_finite() && s > 0.0 { s } else { 1.0 };
            (s * 256.0).round().clamp(1.0, 65535.0) as u16
        });
        Self::with_normals(density, dims, spacing)
    }

    /// Raw 8-bit densities of `dims`, `x` fastest, unit spacing. Reads
    /// exactly the `w h d` bytes the dimensions declare (a longer file's
    /// rest is ignored; `/dev/zero` gives a black volume), at most the
    /// default [`Limits::max_bytes`](crate::Limits): see
    /// [`VolumeData::load_raw_within`].
    pub fn load_raw(path: &Path, dims: [u16; 3]) -> Result<Self> {
        Self::load_raw_within(path, dims, crate::Limits::default().max_bytes)
    }

    /// [`VolumeData::load_raw`] of at most `max_bytes`, checked before the
    /// file is read.
    pub fn load_raw_within(path: &Path, dims: [u16; 3], max_bytes: u64) -> Result<Self> {
        let file = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
        Self::read_raw(std::io::BufReader::new(file), path, dims, max_bytes)
    }

    /// [`VolumeData::load_raw_within`] from `src`, named `path` in
    /// messages: `dims` are checked against `max_bytes` before a byte is
    /// read, then exactly the bytes they declare are read.
    pub fn read_raw(
        mut src: impl std::io::Read,
        path: &Path,
        dims: [u16; 3],
        max_bytes: u64,
    ) -> Result<Self> {
        let bad = |m: String| Error::Unsupported(format!("{}: {m}", path.display()));
        let side = 2..=tilerast::volume::MAX_VOLUME_SIDE;
        if let Some(d) = dims.iter().find(|d| !side.contains(*d)) {
            return Err(bad(format!(
                "dims side {d}: each side must be 2..={}",
                tilerast::volume::MAX_VOLUME_SIDE
            )));
        }
        let n = dims.iter().map(|&d| d as u64).product::<u64>();
        if n > max_bytes {
            return Err(bad(format!(
                "dims {}x{}x{} declare {n} bytes, over the limit of {max_bytes}",
                dims[0], dims[1], dims[2]
            )));
        }
        let mut d = vec![0u8; n as usize];
        read_all(&mut src, &mut d).map_err(|(e, got)| {
            if e.kind() == std::io::ErrorKind::UnexpectedEof {
                bad(format!(
                    "the file ends early: {got} of the {n} bytes dims declare"
                ))
            } else {
                Error::io(path, e)
            }
        })?;
        Volume::new(&d, dims)?;
        Self::with_normals(d, dims, [256; 3])
    }

    /// Resampled trilinearly to `n^3` voxels covering the same box (the
    /// spacing grows or shrinks per axis to keep the physical shape).
    /// [`Error::Unsupported`] for `n` outside `2..=`[`MAX_MADE_SIDE`].
    pub fn resample(&self, n: u16) -> Result<Self> {
        made_side(n)?;
        let [w, h, d] = self.dims.map(|v| v as usize);
        let at = |x: usize, y: usize, z: usize| self.density[x + w * (y + h * z)] as f64;
        let scale = |a: usize| (self.dims[a] as f64 - 1.0) / (n as f64 - 1.0);
        let (sx, sy, sz) = (scale(0), scale(1), scale(2));
        let mut out = Vec::with_capacity((n as usize).pow(3));
        for k in 0..n as usize {
            for j in 0..n as usize {
                for i in 0..n as usize {
                    let p = [i as f64 * sx, j as f64 * sy, k as f64 * sz];
                    let i0 = [p[0] as usize, p[1] as usize, p[2] as usize];
                    let i0 = [i0[0].min(w - 2), i0[1].min(h - 2), i0[2].min(d - 2)];
                    let f = [
                        p[0] - i0[0] as f64,
                        p[1] - i0[1] as f64,
                        p[2] - i0[2] as f64,
                    ];
                    let mut v = 0.0;
                    for c in 0..8 {
                        let (dx, dy, dz) = (c & 1, c >> 1 & 1, c >> 2 & 1);
                        let wgt = (if dx == 1 { f[0] } else { 1.0 - f[0] })
                            * (if dy == 1 { f[1] } else { 1.0 - f[1] })
                            * (if dz == 1 { f[2] } else { 1.0 - f[2] });
                        v += wgt * at(i0[0] + dx, i0[1] + dy, i0[2] + dz);
                    }
                    out.push(v.round().clamp(0.0, 255.0) as u8);
                }
            }
        }
        let spacing = [0, 1, 2].map(|a| {
            (self.spacing[a] as f64 * scale(a))
                .round()
                .clamp(1.0, 65535.0) as u16
        });
        Self::with_normals(out, [n; 3], spacing)
    }

    /// The core's view of it, normals precomputed or on the fly, skipping
    /// transparent bricks or not (the same image either way).
    pub fn volume(&self, quantized: bool, skip: bool) -> Result<Volume<'_>> {
        let mut v = Volume::new(&self.density, self.dims)?.with_spacing(self.spacing)?;
        if quantized {
            v = v.with_normals(&self.normals)?;
        }
        if skip {
            v = v.with_bricks(&self.bricks, self.brick_shift)?;
        }
        Ok(v)
    }
}

/// Where normals come from, by name.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum NormalsKind {
    /// Precomputed, 3 bytes a voxel.
    #[default]
    Quantized,
    /// Central differences at every sample.
    OnTheFly,
}

/// How samples are composited, by name.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ModeKind {
    /// Normal blending, one shading pass (seed 002).
    #[default]
    Normal,
    /// Every sample shaded, intensities blended (the baseline).
    PerSlice,
}

/// What the frame shows.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ViewKind {
    /// The shaded volume.
    #[default]
    Shaded,
    /// The composited normals as colour (`rgb = 128 + 127 N / α`; Fig. 2a).
    Normals,
}

/// The scene file's `[volume]` table.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct VolumeSpec {
    /// `"sphere"` or a file relative to the scene.
    pub source: String,
    /// Sphere side, or the side to resample a file to.
    pub size: Option<u16>,
    /// Sides of a `.raw` file.
    pub dims: Option<[u16; 3]>,
    /// Slices.
    #[serde(default = "default_slices")]
    pub slices: u16,
    /// Normals.
    #[serde(default)]
    pub normals: NormalsKind,
    /// Compositing.
    #[serde(default)]
    pub mode: ModeKind,
    /// Skip the samples of cells the transfer function makes transparent
    /// (empty-space skipping: the same image, fewer fetches).
    #[serde(default = "default_true")]
    pub skip_empty: bool,
    /// Output.
    #[serde(default)]
    pub view: ViewKind,
    /// Transfer function points: density, alpha, r, g, b.
    pub transfer: Vec<[f64; 5]>,
    /// Camera position (looking at the origin, y up).
    #[serde(default = "default_eye")]
    pub eye: [f64; 3],
    /// Vertical field of view, degrees.
    #[serde(default = "default_fov")]
    pub fov: f64,
    /// The volume's rotation about x, then y, then z, degrees.
    #[serde(default)]
    pub rotate: [f64; 3],
    /// Lights: direction towards the light (world) and kd.
    #[serde(default = "default_lights")]
    pub lights: Vec<[f64; 4]>,
    /// Ambient term.
    #[serde(default = "default_ambient")]
    pub ambient: f64,
}

impl VolumeSpec {
    /// The procedural sphere with `transfer` and every other key at its
    /// default: 128 slices, quantised normals, normal blending, shaded,
    /// eye at `[0, 0, 2.2]`, 40°, no rotation, one light, ambient 0.2.
    pub fn new(transfer: Vec<[f64; 5]>) -> Self {
        VolumeSpec {
            source: "sphere".into(),
            size: None,
            dims: None,
            slices: default_slices(),
            normals: NormalsKind::Quantized,
            mode: ModeKind::Normal,
            skip_empty: true,
            view: ViewKind::Shaded,
            transfer,
            eye: default_eye(),
            fov: default_fov(),
            rotate: [0.0; 3],
            lights: default_lights(),
            ambient: default_ambient(),
        }
    }
}

fn default_true() -> bool {
    true
}

fn default_slices() -> u16 {
    128
}
fn default_eye() -> [f64; 3] {
    [0.0, 0.0, 2.2]
}
fn default_fov() -> f64 {
    40.0
}
fn default_lights() -> Vec<[f64; 4]> {
    vec![[0.4, 0.6, 1.0, 0.8]]
}
fn default_ambient() -> f64 {
    0.2
}

/// A scene's volume, loaded and ready to render.
#[derive(Debug, Clone)]
pub struct VolumeScene {
    /// The data.
    pub data: VolumeData,
    /// The table.
    pub transfer: Transfer,
    /// The spec it came from.
    pub spec: VolumeSpec,
    /// [`Volume::compute_visible_cells`] of the data for the table (one
    /// bit a voxel), what `skip_empty` skips by; empty: it skips by the
    /// data's bricks instead.
    pub cells: Vec<u8>,
}

impl VolumeScene {
    /// A scene of `data` through `transfer`, its cells classified once
    /// when the spec skips empty space (else no bits are held).
    pub fn new(data: VolumeData, transfer: Transfer, spec: VolumeSpec) -> Result<Self> {
        let mut cells = Vec::new();
        if spec.skip_empty {
            cells = vec![0u8; tilerast::volume::visible_cell_bytes(data.dims)];
            Volume::new(&data.density, data.dims)?.compute_visible_cells(&transfer, &mut cells)?;
        }
        Ok(VolumeScene {
            data,
            transfer,
            spec,
            cells,
        })
    }

    /// Loads the data a spec names (files relative to `base`, each at most
    /// `limits.max_bytes` of data) and checks the rest.
    pub fn load(
        spec: VolumeSpec,
        base: &Path,
        limits: &crate::Limits,
    ) -> std::result::Result<Self, String> {
        let e = |e: Error| e.to_string();
        if spec.slices == 0 || spec.slices as usize > MAX_SLICES {
            return Err(format!("slices = {} must be 1..={MAX_SLICES}", spec.slices));
        }
        let data = if spec.source == "sphere" {
            VolumeData::sphere(spec.size.unwrap_or(64)).map_err(e)?
        } else {
            let path: PathBuf = base.join(&spec.source);
            let name = spec.source.to_ascii_lowercase();
            let d = if name.ends_with(".raw") {
                let dims = spec.dims.ok_or("a .raw volume needs dims = [w, h, d]")?;
                VolumeData::load_raw_within(&path, dims, limits.max_bytes).map_err(e)?
            } else if name.ends_with(".nii") || name.ends_with(".nii.gz") {
                VolumeData::load_nifti_within(&path, limits.max_bytes).map_err(e)?
            } else {
                return Err(format!(
                    "source {:?}: expected \"sphere\", .nii, .nii.gz or .raw",
                    spec.source
                ));
            };
            match spec.size {
                Some(n) => d.resample(n).map_err(e)?,
                None => d,
            }
        };
        let transfer = transfer(&spec.transfer)?;
        if !spec.fov.is_finite() || !(1.0..=170.0).contains(&spec.fov) {
            return Err(format!(
                "fov = {} must be 1..=170 degrees",
                Readable(spec.fov)
            ));
        }
        // The camera and the lights are checked here, where the scene
        // file's name and line are known, not when the frame is drawn.
        let finite = |name: &str, v: &[f64]| match v.iter().find(|x| !x.is_finite()) {
            Some(x) => Err(format!("{name} has {x}: every number must be finite")),
            None => Ok(()),
        };
        finite("eye", &spec.eye)?;
        finite("rotate", &spec.rotate)?;
        finite("ambient", &[spec.ambient])?;
        for l in &spec.lights {
            finite("a light", l)?;
        }
        let scene = VolumeScene::new(data, transfer, spec).map_err(e)?;
        let s = &scene.spec;
        let eye = s.eye.map(Readable);
        let cam = scene.camera(64, 64).map_err(|e| {
            format!("eye = [{}, {}, {}]: {e} (it must be away from the origin and not straight above it)", eye[0], eye[1], eye[2])
        })?;
        scene
            .lights(&cam[0], &s.lights)
            .map_err(|e| format!("lights: {e} (each needs a direction that is not zero)"))?;
        Ok(scene)
    }

    /// Model, view and projection for a `w x h` screen.
    pub fn camera(&self, w: u16, h: u16) -> Result<[Mat4<f32>; 3]> {
        let s = &self.spec;
        let r = |d: f64| Angle::from_degrees_f32(d as f32);
        let model = Mat4::rotation_z(r(s.rotate[2]))
            .mul(&Mat4::rotation_y(r(s.rotate[1])))
            .mul(&Mat4::rotation_x(r(s.rotate[0])));
        let eye = s.eye.map(|v| v as f32);
        let view = Mat4::look_at(eye, [0.0; 3], [0.0, 1.0, 0.0])?;
        let dist = (eye[0] * eye[0] + eye[1] * eye[1] + eye[2] * eye[2]).sqrt();
        let near = (dist - 1.0).max(0.05);
        let proj = Mat4::perspective(r(s.fov), w as f32 / h as f32, near, dist + 1.0)?;
        Ok([model, view, proj])
    }

    /// The volume sliced for a camera on a `w x h` screen.
    pub fn view(
        &self,
        run: VolumeRun,
        [model, view, proj]: [Mat4<f32>; 3],
        w: u16,
        h: u16,
    ) -> Result<Box<VolumeView<'_, MAX_SLICES>>> {
        let quantized = run.normals == NormalsKind::Quantized;
        let vol = if run.skip_empty && !self.cells.is_empty() {
            self.data
                .volume(quantized, false)?
                .with_visible_cells(&self.cells)?
        } else {
            self.data.volume(quantized, run.skip_empty)?
        };
        let screen = Rect::new(0, 0, w as u32, h as u32);
        Ok(Box::new(VolumeView::new(
            vol,
            &self.transfer,
            &model,
            &view,
            &proj,
            screen,
            run.slices,
        )?))
    }

    /// The lights for the volume's model matrix.
    pub fn lights(&self, model: &Mat4<f32>, lights: &[[f64; 4]]) -> Result<VolumeLights> {
        let l: Vec<([f32; 3], f32)> = lights
            .iter()
            .map(|l| ([l[0] as f32, l[1] as f32, l[2] as f32], l[3] as f32))
            .collect();
        Ok(VolumeLights::new(model, &l, self.spec.ambient as f32)?)
    }
}

/// A transfer table from `[density, alpha, r, g, b]` points.
pub fn transfer(points: &[[f64; 5]]) -> std::result::Result<Transfer, String> {
    let pts = points
        .iter()
        .map(|p| {
            if p.iter().any(|v| !(0.0..=255.0).contains(v)) {
                return Err(format!("transfer point {p:?}: values must be 0..=255"));
            }
            let b = |v: f64| v.round() as u8;
            Ok(TfPoint::new(
                b(p[0]),
                b(p[1]),
                Rgb::new(b(p[2]), b(p[3]), b(p[4])),
            ))
        })
        .collect::<std::result::Result<Vec<_>, _>>()?;
    Transfer::from_points(&pts)
        .map_err(|_| "transfer needs points with strictly increasing densities".to_string())
}

/// Host time of the volume stage, summed over tiles, in nanoseconds.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct VolumeTiming {
    /// Slicing (set-up, once a frame).
    pub setup_ns: f64,
    /// Phase I: slice, classify, composite.
    pub phase1_ns: f64,
    /// Phase II: shade.
    pub phase2_ns: f64,
    /// What compositing did.
    pub stats: VolumeStats,
}

/// Options of one volume render.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct VolumeRun {
    /// Compositing.
    pub mode: ModeKind,
    /// Normals.
    pub normals: NormalsKind,
    /// Output.
    pub view: ViewKind,
    /// Slices.
    pub slices: u16,
    /// Empty-space skipping.
    pub skip_empty: bool,
}

impl VolumeScene {
    /// The run the scene file asks for.
    pub fn run(&self) -> VolumeRun {
        VolumeRun {
            mode: self.spec.mode,
            normals: self.spec.normals,
            view: self.spec.view,
            slices: self.spec.slices,
            skip_empty: self.spec.skip_empty,
        }
    }
}

/// Renders `cmds` then the volume over them, in tiles as the firmware
/// would (RGB888, or RGB565 with the 4x4 dither: 16-bit Z either way).
pub fn render(
    cfg: &Config,
    cmds: &[Command],
    vs: &VolumeScene,
    run: VolumeRun,
    lights: &[[f64; 4]],
) -> Result<(Rendered, VolumeTiming)> {
    if !cfg.depth || cfg.wid || cfg.aa != crate::AaKind::None {
        return Err(Error::Unsupported(
            "volume scenes are rendered with a depth plane, no window IDs and no coverage AA"
                .into(),
        ));
    }
    match (cfg.format, cfg.dither) {
        (FormatKind::Rgb888, 0 | 1) => render_in::<Planes<Rgb888Format, Depth16>>(cfg, cmds, vs, run, lights),
        (FormatKind::Rgb565, 4) => render_in::<St7789Config>(cfg, cmds, vs, run, lights),
        (f, d) => Err(Error::Unsupported(format!(
            "volume scenes are rgb888 without dither or rgb565 with dither 4 (this scene: {}, dither {d})",
            f.name()
        ))),
    }
}

fn render_in<C: TileConfig>(
    cfg: &Config,
    cmds: &[Command],
    vs: &VolumeScene,
    run: VolumeRun,
    lights: &[[f64; 4]],
) -> Result<(Rendered, VolumeTiming)>
where
    embedded_graphics_core::pixelcolor::Rgb888: From<<C::Format as PixelFormat>::Color>,
{
    let (frame, mut tile) = frame_and_tile::<C, VOLUME_GROUPS>(cfg)?;
    let (w, h) = (cfg.width, cfg.height);
    let [model, view, proj] = vs.camera(w, h)?;
    let vl = vs.lights(&model, lights)?;
    let t0 = Instant::now();
    let scene = vs.view(run, [model, view, proj], w, h)?;
    let mut timing = VolumeTiming {
        setup_ns: t0.elapsed().as_nanos() as f64,
        ..Default::default()
    };
    let n = w as usize * h as usize;
    let mut image = Image::new(w as u32, h as u32);
    let (mut raw, mut depth) = (vec![0u32; n], vec![u16::MAX; n]);
    fn pass<C: TileConfig, M: Compositor, const G: usize>(
        t: &mut Tile<G, C>,
        plane: &mut VolumePlane<G, M::Cell>,
        scene: &VolumeView<'_, MAX_SLICES>,
        comp: &M,
        lights: &VolumeLights,
        view: ViewKind,
        timing: &mut VolumeTiming,
    ) {
        let t0 = Instant::now();
        timing.stats += plane.composite(t, scene, comp);
        let t1 = Instant::now();
        if view == ViewKind::Shaded {
            plane.shade(t, comp, lights);
        }
        timing.phase1_ns += (t1 - t0).as_nanos() as f64;
        timing.phase2_ns += t1.elapsed().as_nanos() as f64;
    }
    let stats = match run.mode {
        ModeKind::Normal => {
            let mut plane: Box<VolumePlane<VOLUME_GROUPS, NormalCell>> = Box::default();
            frame.render_with(&mut tile, cmds, |t| {
                pass(
                    t,
                    &mut plane,
                    &scene,
                    &NormalBlending,
                    &vl,
                    run.view,
                    &mut timing,
                );
                copy_tile(t, &mut image, &mut raw, &mut depth);
                if run.view == ViewKind::Normals {
                    paint_normals(t.area(), &plane, &mut image);
                }
                Ok::<(), core::convert::Infallible>(())
            })
        }
        ModeKind::PerSlice => {
            let mut plane: Box<VolumePlane<VOLUME_GROUPS, tilerast::volume::ShadedCell>> =
                Box::default();
            let comp = PerSliceShading(&vl);
            frame.render_with(&mut tile, cmds, |t| {
                pass(
                    t,
                    &mut plane,
                    &scene,
                    &comp,
                    &vl,
                    ViewKind::Shaded,
                    &mut timing,
                );
                copy_tile(t, &mut image, &mut raw, &mut depth);
                Ok::<(), core::convert::Infallible>(())
            })
        }
    }
    .map_err(tilerast::Error::from)?;
    Ok((
        Rendered {
            image,
            raw,
            depth,
            bits_per_pixel: Tile::<VOLUME_GROUPS, C>::bits_per_pixel(),
            stats,
            ns_per_pixel: None,
        },
        timing,
    ))
}

/// Fig. 2a: the composited normals as colour over the tile's area.
fn paint_normals(area: Rect, plane: &VolumePlane<VOLUME_GROUPS, NormalCell>, image: &mut Image) {
    for y in area.y..area.y + area.h as i32 {
        for x in area.x..area.x + area.w as i32 {
            let Some(c) = plane.cell(x, y) else { continue };
            let i = (y as u32 * image.width + x as u32) as usize;
            let a = c.a as f64 / 32768.0;
            let rgb = if a > 0.0 {
                c.n.map(|v| {
                    (128.0 + 127.0 * (v as f64 / NORMAL_ONE as f64 / a).clamp(-1.0, 1.0)).round()
                        as u8
                })
            } else {
                [0; 3]
            };
            image.pixels[i] = rgb;
        }
    }
}

/// Fig. 3: one composite of the volume alone (the scene's commands are not
/// drawn), shaded once per light set — the composite is not redone.
/// RGB888, no dither. One image per set.
pub fn render_lights(cfg: &Config, vs: &VolumeScene, sets: &[Vec<[f64; 4]>]) -> Result<Vec<Image>> {
    type C = Planes<Rgb888Format, Depth16>;
    let (frame, mut tile) = frame_and_tile::<C, VOLUME_GROUPS>(cfg)?;
    let (w, h) = (cfg.width, cfg.height);
    let [model, view, proj] = vs.camera(w, h)?;
    let lights = sets
        .iter()
        .map(|l| vs.lights(&model, l))
        .collect::<Result<Vec<_>>>()?;
    let scene = vs.view(vs.run(), [model, view, proj], w, h)?;
    let mut plane: Box<VolumePlane<VOLUME_GROUPS, NormalCell>> = Box::default();
    let n = w as usize * h as usize;
    let mut out: Vec<(Image, Vec<u32>, Vec<u16>)> = sets
        .iter()
        .map(|_| (Image::new(w as u32, h as u32), vec![0; n], vec![0; n]))
        .collect();
    frame
        .render_with(&mut tile, &[][..], |t| {
            plane.composite(t, &scene, &NormalBlending);
            let area = t.area();
            for (l, (img, raw, depth)) in lights.iter().zip(out.iter_mut()) {
                t.begin(area, &cfg.clear)?;
                plane.shade(t, &NormalBlending, l);
                copy_tile(t, img, raw, depth);
            }
            Ok::<(), tilerast::Error>(())
        })
        .map_err(|e| match e {
            FlushError::Raster(e) | FlushError::Target(e) => Error::from(e),
            _ => Error::Unsupported("unknown flush error".into()),
        })?;
    Ok(out.into_iter().map(|o| o.0).collect())
}

/// The largest difference, in 8-bit output levels, that rounding allows
/// between normal blending and per-slice shading of a one-colour volume
/// after `k` blended samples at a pixel (seed 002 §4.2: equal in exact
/// arithmetic). Each blend rounds once: half a unit of the normal (Q1.14),
/// the opacity (Q1.15) and the colour (Q8.8) or shaded colour (Q8.14)
/// planes; each light's dot product rounds once; both images round to 8
/// bits at the end. The colour/opacity ratio of normal blending turns
/// those into the terms below (`α_f >= 2^-8` once a sample with `α >= 1`
/// is blended).
pub fn equality_bound(lights: &[[f64; 4]], ambient: f64, k: u32) -> f64 {
    let k = k as f64;
    let nl = lights.len() as f64;
    // Σ_j kd_j |L_j|_1 of the unit directions.
    let l1: f64 = lights
        .iter()
        .map(|l| {
            let n = (l[0] * l[0] + l[1] * l[1] + l[2] * l[2]).sqrt();
            l[3] * (l[0].abs() + l[1].abs() + l[2].abs()) / n
        })
        .sum();
    let e_c = k / 2.0 / 256.0; // colour plane, levels
    let e_a = k / 2.0 / 32768.0; // opacity
    let e_i = l1 * k / 2.0 / 16384.0 + ambient * e_a + (nl + 1.0) / 16384.0; // intensity
    let normal = (l1 + ambient) * (e_c + 255.0 * e_a) + 255.0 * e_i + e_c * e_i * 256.0;
    let per_slice = 255.0 * nl / 16384.0 + k / 2.0 / 16384.0;
    normal + per_slice + 1.0
}
