//! The scene file format (TOML). A scene sets the screen and the pipeline
//! configuration, declares windows, and lists commands in drawing order.
//!
//! ```toml
//! [screen]
//! width = 240                # pixels, 1..=4096
//! height = 160
//! format = "rgb444"          # rgb888 | rgb565 | rgb444 | gray8 | binary
//! tile = [64, 32]            # tile width, height (default 64 x 64)
//! dither = 8                 # 0 (none) | 2 | 4 | 8 | 16
//! depth = true               # 16-bit Z plane (default: true)
//! window_ids = true          # 8-bit window-ID plane (default: on when windows exist)
//! background = [16, 16, 32]  # clear colour
//! aa = "ruf8"                # coverage antialiasing: none | ruf4 | ruf8 | ruf16 |
//!                            # ss1 | ss4 | ss8 | ss16 | grid4 | grid8 (default none)
//! texturing = "quadratic"    # textured meshes' perspective: none | affine |
//!                            # quadratic (default) | exact (seed 001 §IV.3)
//!
//! [[window]]                 # claims a rectangle for a window ID, in order
//! id = 1
//! rect = [8, 8, 150, 120]    # x, y, w, h
//! background = [40, 40, 60]  # optional: filled inside the window
//!
//! [[command]]
//! kind = "triangle"          # x, y in pixels (1/16 px precision), z 0..65535, r, g, b
//! window = 1
//! v = [[10, 10, 100, 255, 0, 0], [100, 20, 100, 0, 255, 0], [50, 90, 100, 0, 0, 255]]
//! edge_aa = true             # optional: antialias its edges (seed 003 eq. 8)
//! alpha = [255, 128, 0]      # optional: opacity, one for all vertices or one each
//! blend = "alpha"            # optional: opaque | alpha | alpha_zwrite (default:
//!                            # alpha when an alpha is given; see below)
//!
//! [[command]]
//! kind = "span"              # the raster engine's span: start values and per-pixel steps
//! x = 0
//! y = 5
//! len = 100
//! rgb = [0, 0, 0]
//! drgb = [2.55, 0, 0]
//! z = 0
//! dz = 0
//!
//! [[command]]
//! kind = "fill"              # flat area fill
//! rect = [0, 0, 10, 10]
//! rgb = [255, 255, 255]
//! plane_mask = 0xF800        # optional, in the packed format's bits
//! alpha = 96                 # optional: a translucent fill (spans take it too)
//!
//! [[command]]
//! kind = "zfill"
//! rect = [0, 0, 10, 10]
//! z = 30000
//!
//! [[command]]
//! kind = "line"              # Bresenham, sub-pixel endpoints, end point excluded
//! from = [10.5, 20]
//! to = [200, 37.25]
//! rgb = [255, 255, 0]
//! z = [100, 100]             # optional depth at both ends
//! style = { pattern = 0x0F0F, scale = 2 }   # optional on/off pattern
//! aa = true                  # optional: two-point (Wu) antialiasing
//!
//! [[command]]
//! kind = "polyline"          # segments continue the style's phase
//! points = [[10, 10], [50, 30], [90, 10]]
//! rgb = [255, 255, 255]
//! closed = false
//!
//! [[command]]
//! kind = "mesh"              # an OBJ with its .mtl colours, camera and light
//! obj = "../assets/models/teapot.obj"
//! eye = [0, 1, 3]
//! rotate_y = 30
//! edge_aa = true             # optional: antialias its silhouette and open boundary
//! shading = "fast_phong"     # optional: gouraud (default) | fast_phong
//! texture = "checker.png"    # optional: a PNG for every group (default: the
//!                            # .mtl's map_Kd); textured groups are lit white
//! uv = "spherical"           # optional: obj (its vt, default) | spherical | cylindrical
//! uv_scale = [4, 2]          # optional: repeats of the texture
//! filter = "bilinear"        # optional: bilinear (default) | nearest
//! ```
//!
//! Translucent commands (seed 001 §IV.4) blend `C = α C + (1 - α) C_dst`
//! over what is drawn before them, so list them back to front after the
//! opaque ones; they test Z and write it only with `blend = "alpha_zwrite"`.
//!
//! Antialiased edges are drawn after every other command, over the finished
//! solids; `tilerast-sim render --edge-aa on|off` switches them for the
//! whole scene (every triangle's edges, every mesh's silhouette).
//!
//! Every command takes an optional `window` (default 0). Errors name the file,
//! the line and the problem.
//!
//! A `[volume]` table ([`crate::volume`] lists its keys) draws a density
//! volume over the commands, through the core's volume stage.
//!
//! A `[city]` table ([`crate::city`] lists its keys) draws a frame of the
//! occlusion-culling city instead, culled as the table says.

use crate::error::{Error, Location, Result};
use crate::mesh::{self, MeshSpec, MeshStats};
use crate::obj::Limits;
use crate::render::{Config, FormatKind};
use serde::Deserialize;
use std::path::Path;
use tilerast::numeric::{ColorFix, ColorStep, ZFix, ZStep, MAX_SIDE};
use tilerast::prelude::*;

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneFile {
    screen: toml::Spanned<ScreenSpec>,
    #[serde(default)]
    window: Vec<toml::Spanned<WindowSpec>>,
    #[serde(default)]
    command: Vec<toml::Spanned<CommandSpec>>,
    volume: Option<toml::Spanned<crate::volume::VolumeSpec>>,
    city: Option<toml::Spanned<crate::city::CitySpec>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct ScreenSpec {
    width: u16,
    height: u16,
    format: FormatKind,
    #[serde(default = "default_tile")]
    tile: [u16; 2],
    #[serde(default)]
    dither: u8,
    #[serde(default = "yes")]
    depth: bool,
    window_ids: Option<bool>,
    #[serde(default)]
    background: [u8; 3],
    #[serde(default)]
    aa: crate::render::AaKind,
    #[serde(default = "quadratic")]
    texturing: crate::render::TexKind,
    /// `"back"` or `"front"`: the frame drops the triangles facing that
    /// way on screen while binning (`Frame::cull`); default `"none"`.
    #[serde(default)]
    cull: CullKind,
}

/// A scene's `cull` ([`Cull`]).
#[derive(Debug, Clone, Copy, Default, Deserialize)]
#[serde(rename_all = "lowercase")]
enum CullKind {
    #[default]
    None,
    Back,
    Front,
}

impl From<CullKind> for Cull {
    fn from(k: CullKind) -> Cull {
        match k {
            CullKind::None => Cull::None,
            CullKind::Back => Cull::Back,
            CullKind::Front => Cull::Front,
        }
    }
}

fn quadratic() -> crate::render::TexKind {
    crate::render::TexKind::Quadratic
}

fn default_tile() -> [u16; 2] {
    [64, 64]
}
fn yes() -> bool {
    true
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct WindowSpec {
    id: u8,
    rect: [i32; 4],
    background: Option<[u8; 3]>,
}

#[derive(Debug, Deserialize)]
#[serde(tag = "kind", rename_all = "lowercase", deny_unknown_fields)]
enum CommandSpec {
    Triangle {
        v: [[f64; 6]; 3],
        #[serde(default)]
        edge_aa: bool,
        #[serde(default)]
        window: u8,
        plane_mask: Option<u32>,
        alpha: Option<AlphaSpec>,
        blend: Option<BlendKind>,
    },
    Span {
        x: i32,
        y: i32,
        len: u16,
        rgb: [f64; 3],
        #[serde(default)]
        drgb: [f64; 3],
        #[serde(default)]
        z: f64,
        #[serde(default)]
        dz: f64,
        #[serde(default)]
        window: u8,
        plane_mask: Option<u32>,
        alpha: Option<u8>,
        blend: Option<BlendKind>,
    },
    Fill {
        rect: [i32; 4],
        rgb: [u8; 3],
        #[serde(default)]
        window: u8,
        plane_mask: Option<u32>,
        alpha: Option<u8>,
        blend: Option<BlendKind>,
    },
    Zfill {
        rect: [i32; 4],
        z: u16,
        #[serde(default)]
        window: u8,
    },
    Line {
        from: [f64; 2],
        to: [f64; 2],
        rgb: [u8; 3],
        #[serde(default)]
        z: [u16; 2],
        style: Option<StyleSpec>,
        #[serde(default)]
        aa: bool,
        #[serde(default)]
        window: u8,
        plane_mask: Option<u32>,
    },
    Polyline {
        points: Vec<[f64; 2]>,
        rgb: [u8; 3],
        #[serde(default)]
        z: u16,
        #[serde(default)]
        closed: bool,
        style: Option<StyleSpec>,
        #[serde(default)]
        aa: bool,
        #[serde(default)]
        window: u8,
        plane_mask: Option<u32>,
    },
    Mesh(MeshSpec),
}

/// A triangle's opacity: one for all vertices or one each.
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(untagged)]
enum AlphaSpec {
    All(u8),
    Each([u8; 3]),
}

impl AlphaSpec {
    fn each(self) -> [u8; 3] {
        match self {
            AlphaSpec::All(a) => [a; 3],
            AlphaSpec::Each(a) => a,
        }
    }
}

/// How a command blends (`blend = "opaque" | "alpha" | "alpha_zwrite"`).
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(rename_all = "snake_case")]
pub(crate) enum BlendKind {
    Opaque,
    Alpha,
    AlphaZwrite,
}

/// The blend mode: as named, else alpha blending when an `alpha` is given.
fn blend_of(kind: Option<BlendKind>, has_alpha: bool) -> Blend {
    match kind {
        Some(BlendKind::Opaque) => Blend::Opaque,
        Some(BlendKind::Alpha) => Blend::Alpha,
        Some(BlendKind::AlphaZwrite) => Blend::AlphaZWrite,
        None if has_alpha => Blend::Alpha,
        None => Blend::Opaque,
    }
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct StyleSpec {
    pattern: u16,
    #[serde(default = "one")]
    scale: u8,
}

fn one() -> u8 {
    1
}

fn line_style(s: &Option<StyleSpec>, phase: u16) -> LineStyle {
    s.as_ref().map_or(
        LineStyle {
            phase,
            ..LineStyle::SOLID
        },
        |s| LineStyle {
            pattern: s.pattern,
            scale: s.scale,
            phase,
        },
    )
}

fn fixes<T: tilerast::fixed::traits::Fixed>(v: &[f64; 3], what: &str) -> Result<[T; 3], String> {
    Ok([fix(v[0], what)?, fix(v[1], what)?, fix(v[2], what)?])
}

fn point(p: [f64; 2]) -> Result<(Coord, Coord), String> {
    Ok((fix::<Coord>(p[0], "x")?, fix::<Coord>(p[1], "y")?))
}

/// A loaded scene: its configuration and display list.
#[derive(Debug, Clone)]
pub struct Scene {
    /// The file's stem (`"scene"` when parsed from text).
    pub name: String,
    /// Pipeline configuration.
    pub config: Config,
    /// Commands in drawing order (windows first).
    pub commands: Vec<Command>,
    /// One line per mesh loaded (saying whether its silhouette is
    /// antialiased as the scene now stands), then one per warning.
    pub notes: Vec<String>,
    /// Mesh statistics, summed.
    pub mesh: MeshStats,
    /// Exact Phong's shading of the lit mesh triangles, by command index
    /// ([`Scene::exact_phong`]).
    pub phong: std::collections::HashMap<usize, mesh::PhongTri>,
    /// Textures of the textured meshes; a textured command's `tex`
    /// indexes them.
    pub textures: Vec<crate::meshtex::TexImage>,
    /// How textured triangles are drawn (`[screen] texturing`, default
    /// quadratic; `none` draws their shade).
    pub texturing: crate::render::TexKind,
    /// The `[volume]`, drawn over the commands (seed 002).
    pub volume: Option<crate::volume::VolumeScene>,
    /// The `[city]`, drawn instead of the commands (seed 004).
    pub city: Option<crate::city::CitySpec>,
    /// Commands before the antialiased edges.
    solid_commands: usize,
    /// Every edge that edge antialiasing can draw (triangles' edges, meshes'
    /// silhouettes), and whether it is on.
    edges: Vec<(bool, Command)>,
    /// Per mesh: its summary and its silhouette edges in `edges`.
    meshes: Vec<(String, std::ops::Range<usize>)>,
    /// What loading skipped or could not find.
    warnings: Vec<String>,
}

/// Line numbers of byte offsets, in `O(log lines)` each (finding them by
/// counting newlines from the start made parsing quadratic).
struct Lines<'a> {
    src: &'a str,
    /// Offset of every line start.
    starts: Vec<usize>,
}

impl<'a> Lines<'a> {
    fn new(src: &'a str) -> Self {
        let starts = std::iter::once(0)
            .chain(src.match_indices('\n').map(|(i, _)| i + 1))
            .collect();
        Lines { src, starts }
    }

    /// 1-based line of a byte offset.
    fn of(&self, offset: usize) -> usize {
        self.starts.partition_point(|&s| s <= offset)
    }

    /// The line of `key = ...` in the table whose header is at `span`
    /// (up to the next table header), or the header's line when the key
    /// is not written (a default).
    fn key(&self, span: &std::ops::Range<usize>, key: &str) -> usize {
        let first = self.of(span.start);
        (first..=self.starts.len())
            .map(|n| {
                let start = self.starts[n - 1];
                let end = self.starts.get(n).copied().unwrap_or(self.src.len());
                (n, self.src[start..end].trim_start())
            })
            .take_while(|(n, line)| *n == first || !line.starts_with('['))
            .find(|(_, line)| {
                line.strip_prefix(key)
                    .is_some_and(|r| r.trim_start().starts_with('='))
            })
            .map_or(first, |(n, _)| n)
    }
}

fn rect(r: [i32; 4]) -> Result<Rect, String> {
    if r[2] < 0 || r[3] < 0 {
        return Err(format!("rectangle {r:?} has a negative size"));
    }
    Ok(Rect::new(r[0], r[1], r[2] as u32, r[3] as u32))
}

/// A coordinate as the core's `f32` entry point takes it: finite values
/// beyond `f32`'s range stay finite (and out of the coordinate range), so
/// `1e308` is reported as out of range, not as "infinite".
pub(crate) fn coord_f32(v: f64) -> f32 {
    if v.is_finite() {
        v.clamp(-1e30, 1e30) as f32
    } else {
        v as f32
    }
}

fn fix<T: tilerast::fixed::traits::Fixed>(v: f64, what: &str) -> Result<T, String> {
    if !v.is_finite() {
        return Err(format!("{what} is not finite"));
    }
    T::checked_from_num(v).ok_or_else(|| {
        format!(
            "{what} = {} is out of range ({} to {})",
            crate::error::Readable(v),
            T::MIN,
            T::MAX
        )
    })
}

fn state(window: u8, mask: Option<u32>) -> State {
    State {
        wid: window,
        plane_mask: mask.unwrap_or(u32::MAX),
        ..State::default()
    }
}

impl Scene {
    /// Reads and checks a scene file; meshes are loaded relative to it.
    /// Files and lines are bounded by the default [`Limits`].
    pub fn load(path: impl AsRef<Path>) -> Result<Scene> {
        Scene::load_with(path, &Limits::default())
    }

    /// [`Scene::load`] with explicit limits on file size and line length
    /// (the scene file and every OBJ and MTL it loads).
    pub fn load_with(path: impl AsRef<Path>, limits: &Limits) -> Result<Scene> {
        Scene::load_shaded(path, limits, None)
    }

    /// [`Scene::load_with`], every mesh shaded as `shading` says when it is
    /// given (the CLI's `--shading`), whatever its scene file says.
    pub fn load_shaded(
        path: impl AsRef<Path>,
        limits: &Limits,
        shading: Option<mesh::ShadingKind>,
    ) -> Result<Scene> {
        let path = path.as_ref();
        let bytes = crate::obj::read_bounded(path, limits)?;
        let src = String::from_utf8(bytes).map_err(|e| {
            let bad = e.utf8_error().valid_up_to();
            let line = e.as_bytes()[..bad].iter().filter(|&&b| b == b'\n').count() + 1;
            Error::Invalid {
                at: Location::at(path, line, None),
                message: format!("not UTF-8 text: {}", e.utf8_error()),
            }
        })?;
        if let Some(n) = src.lines().position(|l| l.len() > limits.max_line) {
            return Err(Error::LongLine {
                at: Location::at(path, n + 1, None),
                limit: limits.max_line,
            });
        }
        let mut scene = Scene::parse_inner(
            &src,
            path.parent().unwrap_or(Path::new(".")),
            limits,
            shading,
        )
        .map_err(|e| e.in_file(path))?;
        if let Some(stem) = path.file_stem() {
            scene.name = stem.to_string_lossy().into_owned();
        }
        Ok(scene)
    }

    /// Parses scene text; errors are located by line ([`Error::Invalid`]).
    pub fn parse(src: &str, base: &Path) -> Result<Scene> {
        Scene::parse_with(src, base, &Limits::default())
    }

    /// [`Scene::parse`] with explicit limits for the files it loads.
    pub fn parse_with(src: &str, base: &Path, limits: &Limits) -> Result<Scene> {
        Scene::parse_inner(src, base, limits, None)
    }

    fn parse_inner(
        src: &str,
        base: &Path,
        limits: &Limits,
        shading: Option<mesh::ShadingKind>,
    ) -> Result<Scene> {
        let lines = Lines::new(src);
        let invalid = |line: usize, message: String| Error::Invalid {
            at: Location::line(line),
            message,
        };
        let file: SceneFile = toml::from_str(src).map_err(|e| {
            let line = e.span().map(|s| lines.of(s.start)).unwrap_or(0);
            invalid(line, e.message().trim().to_string())
        })?;
        let screen_span = file.screen.span();
        let at_screen =
            |key: &str, e: String| invalid(lines.key(&screen_span, key), format!("[screen] {e}"));
        let s = file.screen.get_ref();
        let side_ok = |v: u16| (1..=MAX_SIDE).contains(&v);
        for (key, v) in [("width", s.width), ("height", s.height)] {
            if !side_ok(v) {
                return Err(at_screen(
                    key,
                    format!(
                        "size {}x{} must be 1..={MAX_SIDE} per side",
                        s.width, s.height
                    ),
                ));
            }
        }
        if !side_ok(s.tile[0]) || !side_ok(s.tile[1]) {
            return Err(at_screen(
                "tile",
                format!("tile {:?} must be 1..={MAX_SIDE} per side", s.tile),
            ));
        }
        let tile_px = s.tile[0].min(s.width) as usize * s.tile[1].min(s.height) as usize;
        if tile_px > crate::render::SIM_GROUPS * 8 {
            return Err(at_screen(
                "tile",
                format!(
                    "tile {:?} exceeds the simulator's {} pixels",
                    s.tile,
                    crate::render::SIM_GROUPS * 8
                ),
            ));
        }
        if ![0, 2, 4, 8, 16].contains(&s.dither) {
            return Err(at_screen(
                "dither",
                format!("dither = {} must be 0, 2, 4, 8 or 16", s.dither),
            ));
        }
        if s.aa != crate::render::AaKind::None && ![0, 4, 8].contains(&s.dither) {
            return Err(at_screen(
                "aa",
                format!(
                    "coverage antialiasing (aa = \"{}\") is built into the simulator with dither 0, 4 or 8, not {}",
                    s.aa.name(),
                    s.dither
                ),
            ));
        }
        let [r, g, b] = s.background;
        let config = Config {
            width: s.width,
            height: s.height,
            format: s.format,
            tile: (s.tile[0].min(s.width), s.tile[1].min(s.height)),
            dither: s.dither,
            depth: s.depth,
            wid: s.window_ids.unwrap_or(!file.window.is_empty()),
            clear: Clear {
                color: Rgb::new(r, g, b),
                ..Clear::default()
            },
            aa: s.aa,
            cull: s.cull.into(),
        };
        let mut commands = Vec::new();
        let mut meshes = Vec::new();
        let mut mesh_stats = MeshStats::default();
        let mut phong = std::collections::HashMap::new();
        let mut textures: Vec<crate::meshtex::TexImage> = Vec::new();
        let mut warnings = Vec::new();
        let mut edges = Vec::new();
        // Object tags for coverage antialiasing: one per triangle of the
        // file and per OBJ group, from 1.
        let mut tags = 0u16;
        for w in &file.window {
            let line = lines.key(&w.span(), "rect");
            let w = w.get_ref();
            let r = rect(w.rect).map_err(|e| invalid(line, e))?;
            commands.push(Command::WidFill { rect: r, wid: w.id });
            if let Some([r0, g0, b0]) = w.background {
                commands.push(Command::fill(r, Rgb::new(r0, g0, b0)).window(w.id));
            }
        }
        for c in &file.command {
            let span = c.span();
            // An error names the line of the key it is about.
            let key = |k: &'static str| {
                let line = lines.key(&span, k);
                move |e: String| invalid(line, e)
            };
            let cmd = match c.get_ref() {
                CommandSpec::Triangle {
                    v,
                    edge_aa,
                    window,
                    plane_mask,
                    alpha,
                    blend,
                } => {
                    let mut vs = [Vertex::default(); 3];
                    for (k, p) in v.iter().enumerate() {
                        let ch = |i: usize, name: &str| -> Result<u8, String> {
                            let x = p[i];
                            if x.is_finite() && (0.0..=255.0).contains(&x) && x.fract() == 0.0 {
                                Ok(x as u8)
                            } else {
                                Err(format!(
                                    "vertex {k}: {name} = {x} must be an integer 0..=255"
                                ))
                            }
                        };
                        let at = key("v");
                        let z = p[2];
                        if !(z.is_finite() && (0.0..=65535.0).contains(&z)) {
                            return Err(at(format!("vertex {k}: z = {z} must be 0..=65535")));
                        }
                        let color = Rgb::new(
                            ch(3, "r").map_err(at)?,
                            ch(4, "g").map_err(at)?,
                            ch(5, "b").map_err(at)?,
                        );
                        vs[k] = Vertex::try_from_f32(
                            coord_f32(p[0]),
                            coord_f32(p[1]),
                            z.round() as u16,
                            color,
                        )
                        .map_err(|e| at(format!("vertex {k}: {e}")))?;
                    }
                    for (v, a) in vs.iter_mut().zip(alpha.map_or([255; 3], AlphaSpec::each)) {
                        v.alpha = a;
                    }
                    // Each triangle of the file is an object of its own.
                    let st = State {
                        tag: mesh::next_tag(&mut tags),
                        blend: blend_of(*blend, alpha.is_some()),
                        ..state(*window, *plane_mask)
                    };
                    for i in 0..3 {
                        let edge = tilerast::line::EdgeCmd::of_triangle(&vs, i);
                        edges.push((*edge_aa, Command::Edge { edge, state: st }));
                    }
                    Command::Triangle { v: vs, state: st }
                }
                CommandSpec::Span {
                    x,
                    y,
                    len,
                    rgb,
                    drgb,
                    z,
                    dz,
                    window,
                    plane_mask,
                    alpha,
                    blend,
                } => {
                    let span = SpanCmd {
                        x: *x,
                        y: *y,
                        len: *len,
                        color: fixes::<ColorFix>(rgb, "rgb").map_err(key("rgb"))?,
                        dcolor: fixes::<ColorStep>(drgb, "drgb").map_err(key("drgb"))?,
                        z: fix::<ZFix>(*z, "z").map_err(key("z"))?,
                        dz: fix::<ZStep>(*dz, "dz").map_err(key("dz"))?,
                        alpha: alpha.unwrap_or(255),
                    };
                    span.validate().map_err(|e| key("len")(e.to_string()))?;
                    Command::Span {
                        span,
                        state: State {
                            blend: blend_of(*blend, alpha.is_some()),
                            ..state(*window, *plane_mask)
                        },
                    }
                }
                CommandSpec::Fill {
                    rect: r,
                    rgb,
                    window,
                    plane_mask,
                    alpha,
                    blend,
                } => Command::Fill {
                    rect: rect(*r).map_err(key("rect"))?,
                    color: Rgb::new(rgb[0], rgb[1], rgb[2]),
                    alpha: alpha.unwrap_or(255),
                    state: State {
                        blend: blend_of(*blend, alpha.is_some()),
                        ..state(*window, *plane_mask)
                    },
                },
                CommandSpec::Zfill { rect: r, z, window } => Command::ZFill {
                    rect: rect(*r).map_err(key("rect"))?,
                    z: *z,
                    state: state(*window, None),
                },
                CommandSpec::Line {
                    from,
                    to,
                    rgb,
                    z,
                    style,
                    aa,
                    window,
                    plane_mask,
                } => {
                    let line = LineCmd {
                        p0: point(*from).map_err(key("from"))?,
                        p1: point(*to).map_err(key("to"))?,
                        z: *z,
                        color: Rgb::new(rgb[0], rgb[1], rgb[2]),
                        style: line_style(style, 0),
                        antialias: *aa,
                    };
                    line.validate().map_err(|e| key("to")(e.to_string()))?;
                    Command::Line {
                        line,
                        state: state(*window, *plane_mask),
                    }
                }
                CommandSpec::Polyline {
                    points,
                    rgb,
                    z,
                    closed,
                    style,
                    aa,
                    window,
                    plane_mask,
                } => {
                    let mut pts = points
                        .iter()
                        .map(|p| point(*p))
                        .collect::<Result<Vec<_>, _>>()
                        .map_err(key("points"))?;
                    if *closed && pts.len() > 2 {
                        pts.push(pts[0]);
                    }
                    let mut phase = 0;
                    for seg in pts.windows(2) {
                        let line = LineCmd {
                            p0: seg[0],
                            p1: seg[1],
                            z: [*z; 2],
                            color: Rgb::new(rgb[0], rgb[1], rgb[2]),
                            style: line_style(style, phase),
                            antialias: *aa,
                        };
                        line.validate().map_err(|e| key("points")(e.to_string()))?;
                        phase = line.next_phase();
                        commands.push(Command::Line {
                            line,
                            state: state(*window, *plane_mask),
                        });
                    }
                    continue;
                }
                CommandSpec::Mesh(spec) => {
                    let mut found = Vec::new();
                    let first_command = commands.len();
                    let mesh_spec = mesh::MeshSpec {
                        edge_aa: true,
                        shading: shading.unwrap_or(spec.shading),
                        ..spec.clone()
                    };
                    let st = mesh::load(
                        &mesh_spec,
                        base,
                        (config.width, config.height),
                        &mut commands,
                        &mut found,
                        &mut tags,
                        limits,
                    )
                    .map_err(|e| key("obj")(e.to_string()))?;
                    let first_edge = edges.len();
                    edges.extend(found.into_iter().map(|e| (spec.edge_aa, e)));
                    let mut note = format!(
                        "mesh {}: {} vertices, {} triangles, {} groups, {} dropped, {} clipped (near/far plane, guard band), {} culled, {} wireframe lines, {} silhouette edges",
                        spec.obj, st.vertices, st.triangles, st.groups, st.dropped, st.clipped, st.culled, st.lines, st.edges,
                    );
                    if st.obj_lines > 0 {
                        note += &format!(", {} OBJ lines", st.obj_lines);
                    }
                    if st.textured + st.untextured > 0 {
                        note += &format!(
                            ", {} textured triangles ({} clipped pieces untextured)",
                            st.textured, st.untextured
                        );
                    }
                    // Its textures join the scene's: renumber its commands'.
                    for c in &mut commands[first_command..] {
                        if let Command::Textured { tex, .. } = c {
                            let k = textures.len() + *tex as usize;
                            *tex = u8::try_from(k).map_err(|_| {
                                key("texture")("a scene holds at most 256 textures".into())
                            })?;
                        }
                    }
                    textures.extend(st.textures);
                    meshes.push((note, first_edge..edges.len()));
                    warnings.extend(st.warnings.iter().map(|w| format!("warning: {w}")));
                    mesh_stats.vertices += st.vertices;
                    mesh_stats.triangles += st.triangles;
                    mesh_stats.groups += st.groups;
                    mesh_stats.dropped += st.dropped;
                    phong.extend(st.phong);
                    continue;
                }
            };
            commands.push(cmd);
        }
        let volume = match &file.volume {
            None => None,
            Some(v) => {
                let span = v.span();
                let spec = v.get_ref().clone();
                Some(
                    crate::volume::VolumeScene::load(spec, base, limits)
                        .map_err(|e| invalid(lines.of(span.start), format!("[volume] {e}")))?,
                )
            }
        };
        let city = match &file.city {
            None => None,
            Some(c) => {
                let spec = c.get_ref().clone();
                spec.check()
                    .map_err(|e| invalid(lines.of(c.span().start), format!("[city] {e}")))?;
                Some(spec)
            }
        };
        let mut scene = Scene {
            volume,
            city,
            name: "scene".into(),
            config,
            solid_commands: commands.len(),
            commands,
            notes: Vec::new(),
            mesh: mesh_stats,
            phong,
            textures,
            texturing: s.texturing,
            edges,
            meshes,
            warnings,
        };
        scene.rebuild_edges();
        Ok(scene)
    }
}

impl Scene {
    /// The core's view of [`Scene::textures`], in order.
    pub fn core_textures(&self) -> Vec<tilerast::texture::Texture<'_>> {
        self.textures.iter().map(|t| t.texture()).collect()
    }

    /// Renders the scene with the core, its textures in its perspective
    /// mode ([`crate::render::render_textured`]; without textured
    /// commands, [`crate::render::render`]).
    pub fn render(&self) -> Result<crate::render::Rendered> {
        if let Some(c) = &self.city {
            return Ok(crate::city::render(&self.config, c)?.0);
        }
        if let Some(v) = &self.volume {
            let run = v.run();
            return Ok(crate::volume::render(
                &self.config,
                &self.commands,
                v,
                run,
                &v.spec.lights,
            )?
            .0);
        }
        let textured = self
            .commands
            .iter()
            .any(|c| matches!(c, Command::Textured { .. }));
        if !textured {
            return Ok(crate::render::render(&self.config, &self.commands)?);
        }
        let c = &self.config;
        if self.texturing != crate::render::TexKind::None
            && (!c.depth
                || c.wid
                || c.aa != crate::render::AaKind::None
                || ![0, 1, 4].contains(&c.dither))
        {
            return Err(Error::Unsupported(format!(
                "textured meshes are rendered with a depth plane, no window IDs, no coverage AA and dither 0 or 4 (this scene: depth {}, window IDs {}, aa {}, dither {})",
                c.depth,
                c.wid,
                c.aa.name(),
                c.dither
            )));
        }
        Ok(crate::render::render_textured(
            c,
            &self.commands,
            &self.core_textures(),
            self.texturing,
            0,
        )?)
    }

    /// The scene in the f64 reference renderer, textured triangles exact
    /// (perspective-correct, f64 filtering).
    pub fn reference(&self) -> crate::reference::RefFrame {
        crate::reference::render_textured(&self.config, &self.commands, &self.core_textures())
    }

    /// The scene in the f64 reference renderer with every lit mesh
    /// triangle exact-Phong shaded: the normal interpolated across it
    /// (screen-space weights) and normalised at every pixel, then lit as
    /// the geometry stage lights a vertex ([`mesh::PhongTri`]). What fast
    /// Phong approximates; there is no firmware path for it.
    pub fn exact_phong(&self) -> crate::reference::RefFrame {
        crate::reference::render_shaded(&self.config, &self.commands, &|k, w| {
            self.phong.get(&k).map(|t| t.exact(w))
        })
    }

    /// Turns edge antialiasing (seed 003 eq. 8) on or off for every
    /// triangle and mesh of the scene.
    pub fn set_edge_aa(&mut self, on: bool) {
        for e in &mut self.edges {
            e.0 = on;
        }
        self.rebuild_edges();
    }

    /// Appends the edges that are on after every other command: edge
    /// antialiasing blends over the finished solids.
    fn rebuild_edges(&mut self) {
        self.commands.truncate(self.solid_commands);
        let on = self.edges.iter().filter(|e| e.0).map(|e| e.1);
        self.commands.extend(on);
        let edges = &self.edges;
        self.notes = self
            .meshes
            .iter()
            .map(|(note, r)| {
                let aa = !r.is_empty() && edges[r.clone()].iter().all(|e| e.0);
                format!("{note}{}", if aa { " (antialiased)" } else { "" })
            })
            .chain(self.warnings.iter().cloned())
            .collect();
    }

    /// Overrides every line's mode: two-point (Wu) antialiased or Bresenham.
    pub fn set_line_aa(&mut self, antialias: bool) {
        for c in &mut self.commands {
            if let Command::Line { line, .. } = c {
                line.antialias = antialias;
            }
        }
    }

    /// The wire-format header of this scene (`tilerast::wire`).
    pub fn header(&self) -> tilerast::wire::SceneHeader {
        let c = &self.config;
        let mut format = [0u8; 8];
        format[..c.format.name().len()].copy_from_slice(c.format.name().as_bytes());
        tilerast::wire::SceneHeader {
            width: c.width,
            height: c.height,
            tile: c.tile,
            format,
            dither_log2: c.dither.max(1).trailing_zeros() as u8,
            depth_bits: if c.depth { 16 } else { 0 },
            wid_bits: if c.wid { 8 } else { 0 },
            clear: c.clear,
            cull: c.cull,
        }
    }

    /// The scene as firmware stores it in flash: header, then commands,
    /// with runs of triangles that share a state (an OBJ group) packed as
    /// indexed meshes. Decoding yields exactly [`Scene::commands`].
    pub fn encode(&self) -> Result<Vec<u8>, Error> {
        use tilerast::wire::{self, HEADER_LEN, MAX_ENCODED};
        let mut out = vec![0u8; HEADER_LEN];
        self.header().encode(&mut out)?;
        let small = |v: &[Vertex; 3]| {
            v.iter().all(|v| {
                i16::try_from(v.x.to_bits()).is_ok() && i16::try_from(v.y.to_bits()).is_ok()
            })
        };
        let cmds = &self.commands;
        let mut i = 0;
        while i < cmds.len() {
            if let Command::Triangle { v, state } = &cmds[i] {
                if small(v) {
                    let mut verts: Vec<Vertex> = Vec::new();
                    let mut index = std::collections::HashMap::new();
                    let mut tris = Vec::new();
                    while let Some(Command::Triangle { v, state: s }) = cmds.get(i) {
                        // A record holds up to 65535 vertices and triangles:
                        // a larger group continues in the next record.
                        if s != state
                            || !small(v)
                            || verts.len() + 3 > u16::MAX as usize
                            || tris.len() >= u16::MAX as usize
                        {
                            break;
                        }
                        tris.push(v.map(|v| {
                            *index.entry(v).or_insert_with(|| {
                                verts.push(v);
                                (verts.len() - 1) as u16
                            })
                        }));
                        i += 1;
                    }
                    let mut buf = vec![0u8; 16 + verts.len() * 9 + tris.len() * 6];
                    let n = wire::encode_mesh(&verts, &tris, state, &mut buf)?;
                    out.extend_from_slice(&buf[..n]);
                    continue;
                }
            }
            let mut buf = [0u8; MAX_ENCODED];
            let n = wire::encode(&cmds[i], &mut buf)?;
            out.extend_from_slice(&buf[..n]);
            i += 1;
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    const HEAD: &str = "[screen]\nwidth = 32\nheight = 16\nformat = \"rgb565\"\n";

    fn err(body: &str) -> String {
        Scene::parse(&format!("{HEAD}{body}"), Path::new("."))
            .unwrap_err()
            .to_string()
    }

    #[test]
    fn errors_name_the_line() {
        // Errors name the line of the key they are about.
        let e = err("\n[[command]]\nkind = \"fill\"\nrect = [0, 0, 4, -4]\nrgb = [1, 2, 3]\n");
        assert!(e.starts_with("8: ") && e.contains("negative"), "{e}");
        let e = err("\n[[command]]\nkind = \"triangle\"\nv = [[0, 0, 0, 0, 0, 0], [1e9, 0, 0, 0, 0, 0], [0, 1, 0, 0, 0, 0]]\n");
        assert!(
            e.starts_with("8: ") && e.contains("outside the documented range"),
            "{e}"
        );
        let e = err("\n[[command]]\nkind = \"circle\"\n");
        assert!(e.starts_with("6: ") || e.starts_with("7: "), "{e}");
        let e = Scene::parse("[screen]\nwidth = 99999\n", Path::new("."))
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("2: "), "{e}");
        let e = err("\n[[command]]\nkind = \"span\"\nx = 0\ny = 0\nlen = 300\nrgb = [0, 0, 0]\ndrgb = [1, 0, 0]\n");
        assert!(e.starts_with("10: ") && e.contains("span"), "{e}");
    }

    #[test]
    fn line_aa_override_switches_every_line() {
        let src = format!("{HEAD}[[command]]\nkind = \"polyline\"\npoints = [[1, 1], [9, 3], [2, 7]]\nrgb = [9, 9, 9]\n");
        let mut s = Scene::parse(&src, Path::new(".")).unwrap();
        let aa = |s: &Scene| {
            s.commands
                .iter()
                .map(|c| matches!(c, Command::Line { line, .. } if line.antialias))
                .collect::<Vec<_>>()
        };
        assert_eq!(aa(&s), [false, false]);
        s.set_line_aa(true);
        assert_eq!(aa(&s), [true, true]);
    }

    #[test]
    fn absurd_sizes_are_refused() {
        let e = Scene::parse(
            "[screen]\nwidth = 5000\nheight = 5\nformat = \"binary\"\n",
            Path::new("."),
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("must be 1..=4096"), "{e}");
        let e = Scene::parse(
            "[screen]\nwidth = 0\nheight = 5\nformat = \"binary\"\n",
            Path::new("."),
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("must be 1..=4096"), "{e}");
    }

    #[test]
    fn windows_come_first_and_enable_the_plane() {
        let s = Scene::parse(
            &format!("{HEAD}[[window]]\nid = 2\nrect = [0, 0, 8, 8]\nbackground = [1, 1, 1]\n"),
            Path::new("."),
        )
        .unwrap();
        assert!(s.config.wid);
        assert_eq!(s.commands.len(), 2);
    }
}
