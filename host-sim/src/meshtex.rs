//! Textured meshes: where a mesh's
//! texture comes from (the scene's `texture = "…png"` or the `.mtl`'s
//! `map_Kd`), its texture coordinates (the OBJ's `vt`, or a spherical or
//! cylindrical projection for models that have none), and how a lit
//! triangle of the geometry stage becomes a [`Command::Textured`].
//!
//! **Decided here.** A textured group is lit white, so the geometry
//! stage's Gouraud colour is the *shade* the texel is modulated by
//! (`texel · shade / 255`, the core's rule); its fast-Phong shading, if
//! asked, is not used (a textured triangle interpolates its shade
//! linearly). `q` at a vertex is `65535 · near / z_eye` (the vertex's
//! `1/w` scaled into `u16`, exact in f64). Pieces of triangles that the
//! geometry stage clipped carry no texture coordinates and draw their
//! shade untextured; they are counted ([`crate::mesh::MeshStats::untextured`]).
//! Texture coordinates are shifted per triangle by whole repeats of the
//! texture so they start in `0..side` — the same picture with `Repeat` —
//! and the seam of a generated projection is unwrapped per triangle.

use crate::image::Image;
use std::path::{Path, PathBuf};
use tilerast::prelude::*;

/// Where a mesh's texture coordinates come from (`uv = "…"`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum UvKind {
    /// The OBJ's `vt` (groups without them draw untextured, with a warning).
    #[default]
    Obj,
    /// Longitude and latitude around the model's centre.
    Spherical,
    /// Longitude around the model's y axis and height along it.
    Cylindrical,
}

/// Texel filter of a mesh's texture (`filter = "…"`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum FilterKind {
    /// Bilinear between the four nearest texels.
    #[default]
    Bilinear,
    /// The nearest texel.
    Nearest,
}

/// A texture the simulator owns: RGB888 texels read from a PNG.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct TexImage {
    /// The PNG it was read from.
    pub path: PathBuf,
    /// `width * height * 3` bytes, row-major, top row first.
    pub texels: Vec<u8>,
    /// Width in texels (`1..=MAX_SIDE`).
    pub width: u16,
    /// Height in texels (`1..=MAX_SIDE`).
    pub height: u16,
    /// How it is filtered.
    pub filter: FilterKind,
}

impl TexImage {
    /// Reads a PNG (8-bit RGB, RGBA, grey or grey-alpha; alpha dropped) of
    /// at most [`tilerast::texture::MAX_SIDE`] texels a side.
    pub fn load(path: &Path, filter: FilterKind) -> crate::Result<TexImage> {
        let img = Image::load_png(path)?;
        let side = |v: u32| {
            u16::try_from(v)
                .ok()
                .filter(|&s| (1..=tilerast::texture::MAX_SIDE).contains(&s))
        };
        let (Some(width), Some(height)) = (side(img.width), side(img.height)) else {
            return Err(crate::Error::Unsupported(format!(
                "{}: a texture is 1..={} texels a side, not {}x{}",
                path.display(),
                tilerast::texture::MAX_SIDE,
                img.width,
                img.height
            )));
        };
        Ok(TexImage {
            path: path.to_path_buf(),
            texels: img.pixels.as_flattened().to_vec(),
            width,
            height,
            filter,
        })
    }

    /// The core's view of it: repeating, filtered as asked.
    pub fn texture(&self) -> Texture<'_> {
        let filter = match self.filter {
            FilterKind::Bilinear => Filter::Bilinear,
            FilterKind::Nearest => Filter::Nearest,
        };
        Texture::new(&self.texels, self.width, self.height, TexFormat::Rgb888)
            .expect("sides checked by load")
            .wrap(Wrap::Repeat)
            .filter(filter)
    }
}

/// Texture coordinates of fitted positions (the unit cube around the
/// origin) by a projection, in repeats of the texture (`0..1` once round).
pub fn projected_uv(kind: UvKind, pos: &[[f64; 3]]) -> Vec<[f64; 2]> {
    use std::f64::consts::PI;
    pos.iter()
        .map(|p| {
            let u = 0.5 + p[0].atan2(p[2]) / (2.0 * PI);
            let v = match kind {
                UvKind::Spherical => {
                    let r = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
                    0.5 + (p[1] / r.max(f64::MIN_POSITIVE)).clamp(-1.0, 1.0).asin() / PI
                }
                _ => (p[1] + 1.0) / 2.0,
            };
            [u, v]
        })
        .collect()
}

/// A group's texturing: which scene texture, and per OBJ vertex its
/// texture coordinates (repeats, `v` up as in OBJ) and `q`.
#[derive(Debug, Clone)]
pub struct TexturedMesh {
    /// Index of the texture in the mesh's list.
    pub tex: u8,
    /// Texture size in texels.
    pub size: (u16, u16),
    /// Per OBJ vertex: `(u, v)`, `0..1` across the texture once (before
    /// `scale`).
    pub uv: Vec<[f64; 2]>,
    /// Repeats of the texture across `0..1` of `u` and `v`.
    pub scale: [f64; 2],
    /// Per OBJ vertex: `65535 · near / z_eye` (`None` in front of the
    /// near plane).
    pub q: Vec<Option<f64>>,
    /// Whether the seam of a projection is unwrapped per triangle.
    pub seam: bool,
}

impl TexturedMesh {
    /// The textured command of a whole triangle: the geometry stage's
    /// positions and shade (red of its colour; the group is lit white),
    /// with the texture coordinates of OBJ vertices `corners`.
    pub fn command(&self, v: [Vertex; 3], corners: [u32; 3], state: State) -> Option<Command> {
        let q = corners.map(|i| self.q[i as usize]);
        let [Some(q0), Some(q1), Some(q2)] = q else {
            return None;
        };
        let qmax = q0.max(q1).max(q2);
        let (w, h) = (self.size.0 as f64, self.size.1 as f64);
        let mut uv = corners.map(|i| self.uv[i as usize]);
        if self.seam {
            // A triangle across the projection's seam: bring its low side
            // round to the high one.
            let (lo, hi) = uv
                .iter()
                .fold((f64::MAX, f64::MIN), |(l, h), t| (l.min(t[0]), h.max(t[0])));
            if hi - lo > 0.5 {
                for t in &mut uv {
                    if t[0] < 0.5 {
                        t[0] += 1.0;
                    }
                }
            }
        }
        // Texels, `v` down; shifted by whole repeats to start in 0..side.
        let [su, sv] = self.scale;
        let tx = uv.map(|[u, v]| [u * su * w, (1.0 - v) * sv * h]);
        let shift = |k: usize, side: f64| {
            let lo = tx.iter().map(|t| t[k]).fold(f64::MAX, f64::min);
            (lo / side).floor() * side
        };
        let (su, sv) = (shift(0, w), shift(1, h));
        let qs = [q0, q1, q2];
        let tv = |k: usize| {
            // `q` scaled so the nearest vertex has 65535: only ratios matter.
            let q = (qs[k] / qmax * 65535.0).round().clamp(1.0, 65535.0) as u16;
            TexVertex::new(
                v[k].x,
                v[k].y,
                v[k].z,
                ((tx[k][0] - su) as f32, (tx[k][1] - sv) as f32),
                q,
            )
        };
        let shade = v.map(|x| x.color.r);
        Some(Command::Textured {
            tex: self.tex,
            v: [tv(0), tv(1), tv(2)],
            shade,
            alpha: 255,
            state,
        })
    }
}
