//! `[city]` scenes: the occlusion-culling city of seed 004
//! ([`tilerast_fw::city`], the same the firmware walks), one frame of its
//! camera path, drawn through the core's [`tilerast::occlusion`] walk with
//! the culling mode the scene names. Culling is the scene's switch:
//! `cull = "none"` draws every object front to back without a test.
//!
//! Keys (all optional): `side` (blocks a side, 1..=15, default 8), `sub`
//! (face subdivisions, 1..=8: 1 is large triangles), `seed`, `frames`
//! (path length, default 200) and `frame` (which one, default 0), `cull`
//! (`none`, `stop-and-wait`, `chc`, `single-pass`; default
//! `single-pass`), `threshold` (0..=128, default 0: exact).

use crate::error::{Error, Result};
use crate::image::Image;
use crate::render::{copy_tile, frame_and_tile, Config, FormatKind, Rendered};
use serde::Deserialize;
use std::time::Instant;
use tilerast::geometry::{Mat4, Mesh, Scene, VertexSlot};
use tilerast::occlusion::{Aabb, CullMode, CullStats, Culler, HiZ, KdTree};
use tilerast::prelude::*;
use tilerast_fw::city::{self, City, MESH_BYTES};

/// How a `[city]` scene culls.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum CullKind {
    /// No culling.
    None,
    /// Stop-and-wait occlusion queries.
    StopAndWait,
    /// Coherent hierarchical culling.
    Chc,
    /// The seed's single pass.
    #[default]
    SinglePass,
}

impl From<CullKind> for CullMode {
    fn from(k: CullKind) -> CullMode {
        match k {
            CullKind::None => CullMode::Off,
            CullKind::StopAndWait => CullMode::StopAndWait,
            CullKind::Chc => CullMode::Chc,
            CullKind::SinglePass => CullMode::SinglePass,
        }
    }
}

/// The `[city]` table.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CitySpec {
    /// Blocks a side.
    #[serde(default = "default_side")]
    pub side: u32,
    /// Face subdivisions.
    #[serde(default = "default_sub")]
    pub sub: usize,
    /// Seed of the buildings.
    #[serde(default)]
    pub seed: u32,
    /// Frames of the camera path.
    #[serde(default = "default_frames")]
    pub frames: u32,
    /// The frame drawn.
    #[serde(default)]
    pub frame: u32,
    /// Culling mode.
    #[serde(default)]
    pub cull: CullKind,
    /// Minimum visible fragments.
    #[serde(default)]
    pub threshold: u8,
}

fn default_side() -> u32 {
    8
}
fn default_sub() -> usize {
    1
}
fn default_frames() -> u32 {
    200
}

/// Tile capacity of city scenes: 64 x 64 pixels.
const CITY_GROUPS: usize = 512;
/// Tree nodes: 15 x 15 buildings and the ground.
const NODES: usize = 2 * 226 - 1;

impl CitySpec {
    /// Checks the keys' ranges.
    pub fn check(&self) -> std::result::Result<(), String> {
        if !(1..=15).contains(&self.side) {
            return Err(format!("side {} (1..=15)", self.side));
        }
        if !(1..=city::MAX_SUB).contains(&self.sub) {
            return Err(format!("sub {} (1..={})", self.sub, city::MAX_SUB));
        }
        if self.frames == 0 || self.frame >= self.frames {
            return Err(format!(
                "frame {} of {} (frame < frames)",
                self.frame, self.frames
            ));
        }
        if self.threshold > 128 {
            return Err(format!("threshold {} (0..=128)", self.threshold));
        }
        Ok(())
    }

    /// The city.
    pub fn city(&self) -> City {
        City {
            side: self.side,
            sub: self.sub,
            seed: self.seed,
        }
    }
}

/// Renders the scene's frame (with the commands of the scene file drawn
/// nowhere: a city scene is the city). Walks the path from frame 0 so the
/// culler has the history it would have at `frame`; only `frame` is kept.
pub fn render(cfg: &Config, spec: &CitySpec) -> Result<(Rendered, CullStats)> {
    if !cfg.depth || cfg.wid || cfg.aa != crate::AaKind::None {
        return Err(Error::Unsupported(
            "city scenes are rendered with a depth plane, no window IDs and no coverage AA".into(),
        ));
    }
    match (cfg.format, cfg.dither) {
        (FormatKind::Rgb888, 0 | 1) => render_in::<Planes<Rgb888Format, Depth16>>(cfg, spec),
        (FormatKind::Rgb565, 4) => render_in::<St7789Config>(cfg, spec),
        (f, d) => Err(Error::Unsupported(format!(
            "city scenes are rgb888 without dither or rgb565 with dither 4 (this scene: {}, dither {d})",
            f.name()
        ))),
    }
}

/// Calls `f(x, y, packed pixel, depth)` for every pixel of a tile.
pub fn each_pixel<const G: usize, C: TileConfig>(
    t: &Tile<G, C>,
    mut f: impl FnMut(i32, i32, u32, u16),
) {
    let a = t.area();
    for y in a.y..a.y + a.h as i32 {
        for x in a.x..a.x + a.w as i32 {
            f(
                x,
                y,
                t.raw(x, y).unwrap_or(0),
                t.depth(x, y).unwrap_or(u16::MAX),
            );
        }
    }
}

/// One frame of a [`walk`]: its culling counts, the vertices the geometry
/// stage transformed, and its time (geometry, culling, raster; the
/// callback's own time excluded), ns.
#[derive(Debug, Clone, Copy, Default)]
pub struct WalkFrame {
    /// Culling counts.
    pub stats: CullStats,
    /// Vertices transformed.
    pub vertices: u32,
    /// Host time, ns.
    pub ns: f64,
}

/// Walks `c` (its camera path of `frames` frames) with `mode` and
/// `threshold` for frames `0..=last`, through tiles of `frame`, handing
/// every finished tile to `each(k, tile)`: the host's city driver (the
/// simulator's `[city]` scenes, the lab's report, the tests).
#[allow(clippy::too_many_arguments)]
pub fn walk<C: TileConfig, const G: usize, const B: usize, const SH: u32>(
    c: &City,
    frame: &Frame,
    frames: u32,
    last: u32,
    mode: CullMode,
    threshold: u8,
    each: impl FnMut(u32, &mut Tile<G, C>) -> Result<()>,
) -> Result<Vec<WalkFrame>> {
    let mut bytes = vec![0u8; MESH_BYTES];
    let mut gbytes = vec![0u8; MESH_BYTES];
    let (building, ground) = city::meshes(c.sub, &mut bytes, &mut gbytes)?;
    let items: Vec<(Mesh<'_>, Mat4<f32>)> = (0..c.objects())
        .map(|i| c.item(i, building, ground))
        .collect();
    let path = |k| c.view(k, frames).map_err(Error::from);
    walk_scene::<C, G, B, SH>(&items, path, frame, last, mode, threshold, each)
}

/// Walks any objects (meshes placed by model matrices, at most 225) along
/// a camera path (`path(k)` for frame `k`), for frames `0..=last`: the
/// driver under [`walk`], and under the lab's room of teapots.
#[allow(clippy::too_many_arguments)]
pub fn walk_scene<C: TileConfig, const G: usize, const B: usize, const SH: u32>(
    items: &[(Mesh<'_>, Mat4<f32>)],
    path: impl Fn(u32) -> Result<city::Camera>,
    frame: &Frame,
    last: u32,
    mode: CullMode,
    threshold: u8,
    mut each: impl FnMut(u32, &mut Tile<G, C>) -> Result<()>,
) -> Result<Vec<WalkFrame>> {
    let boxes: Vec<Aabb<f32>> = items.iter().map(|(m, t)| Aabb::of_mesh(m, t)).collect();
    let mut culler: Box<Culler<f32, NODES>> = Box::new(Culler::new(KdTree::build(&boxes)?));
    culler.set_threshold(threshold)?;
    let verts = items.iter().map(|(m, _)| m.vertices() as usize).sum();
    let mut slots = vec![VertexSlot::EMPTY; verts];
    let mut scene: Box<Scene<'_, f32, 226>> = Box::new(Scene::new(&mut slots));
    let s = frame.screen();
    scene.set_viewport(Rect::new(0, 0, s.w, s.h))?;
    scene.set_lighting(city::lighting()?);
    let mut tile: Box<Tile<G, C>> = Box::default();
    let mut hiz: Box<HiZ<B, SH>> = Box::default();
    let mut out = vec![];
    for k in 0..=last {
        let mut spent = 0.0;
        let cam = path(k)?;
        let t0 = Instant::now();
        let (stats, vertices) = city::walk_frame(
            cam,
            items,
            &mut culler,
            &mut scene,
            (frame, &mut *tile, &mut *hiz),
            mode,
            |t| {
                let t1 = Instant::now();
                let r = each(k, t);
                spent += t1.elapsed().as_secs_f64();
                r
            },
        )
        .map_err(|e| match e {
            FlushError::Target(e) => e,
            FlushError::Raster(e) => e.into(),
            e => Error::Unsupported(format!("{e:?}")),
        })?;
        out.push(WalkFrame {
            stats,
            vertices,
            ns: (t0.elapsed().as_secs_f64() - spent) * 1e9,
        });
    }
    Ok(out)
}

/// Every frame of a walk of `frames` frames: packed pixels (row-major,
/// the frame's screen), the frames' counts and times, and the pixels with
/// depth written, summed.
pub fn walk_pixels<C: TileConfig, const G: usize, const B: usize, const SH: u32>(
    c: &City,
    frame: &Frame,
    frames: u32,
    mode: CullMode,
    threshold: u8,
) -> Result<(Vec<Vec<u32>>, Vec<WalkFrame>, u64)> {
    collect_pixels(frame, frames, |each| {
        walk::<C, G, B, SH>(c, frame, frames, frames.max(1) - 1, mode, threshold, each)
    })
}

/// What [`collect_pixels`] hands a walker: the callback that keeps a tile.
pub type Keep<'k, C, const G: usize> = &'k mut dyn FnMut(u32, &mut Tile<G, C>) -> Result<()>;

/// Runs `walker` (a [`walk`] or [`walk_scene`] of `frames` frames) with a
/// callback that keeps every frame's packed pixels and counts the pixels
/// with depth written.
pub fn collect_pixels<C: TileConfig, const G: usize>(
    frame: &Frame,
    frames: u32,
    walker: impl FnOnce(Keep<'_, C, G>) -> Result<Vec<WalkFrame>>,
) -> Result<(Vec<Vec<u32>>, Vec<WalkFrame>, u64)> {
    let side = frame.screen().w as usize;
    let n = side * frame.screen().h as usize;
    let mut px = vec![vec![0u32; n]; frames as usize];
    let mut visible = 0;
    let walked = walker(&mut |k, t| {
        let out = &mut px[k as usize];
        each_pixel(t, |x, y, raw, z| {
            out[y as usize * side + x as usize] = raw;
            visible += (z != u16::MAX) as u64;
        });
        Ok(())
    })?;
    Ok((px, walked, visible))
}

fn render_in<C: TileConfig>(cfg: &Config, spec: &CitySpec) -> Result<(Rendered, CullStats)>
where
    embedded_graphics_core::pixelcolor::Rgb888: From<<C::Format as PixelFormat>::Color>,
{
    spec.check().map_err(Error::Unsupported)?;
    let (frame, _) = frame_and_tile::<C, CITY_GROUPS>(cfg)?;
    let (w, h) = (cfg.width, cfg.height);
    let px = w as usize * h as usize;
    let mut image = Image::new(w as u32, h as u32);
    let (mut raw, mut depth) = (vec![0u32; px], vec![u16::MAX; px]);
    let frames = walk::<C, CITY_GROUPS, 256, 3>(
        &spec.city(),
        &frame,
        spec.frames,
        spec.frame,
        spec.cull.into(),
        spec.threshold,
        |k, t| {
            if k == spec.frame {
                copy_tile(t, &mut image, &mut raw, &mut depth);
            }
            Ok(())
        },
    )?;
    let last = frames.last().map(|f| f.stats).unwrap_or_default();
    Ok((
        Rendered {
            image,
            raw,
            depth,
            bits_per_pixel: Tile::<CITY_GROUPS, C>::bits_per_pixel(),
            stats: FrameStats {
                tiles: last.tiles,
                replayed: last.commands,
                ..Default::default()
            },
            ns_per_pixel: None,
        },
        last,
    ))
}
