//! The speed-against-accuracy sweep (`tilerast-lab tradeoff`): every knob
//! of the pipeline turned on a fixed set of scenes, each setting measured
//! on both axes.
//!
//! **Knobs** (a *family* each):
//! - colour fraction bits of the span DDA ([`tilerast::numeric::Bits`]),
//!   RGB888, and RGB565 with 8x8 dither (the dither reads fraction bits);
//! - the depth plane: 16, 24 or 32 bits ([`tilerast::fragment::DepthBits`]),
//!   and Z fraction bits of the DDA, on scenes with close surfaces;
//! - sub-pixel bits of the vertices (0 to the 4 [`tilerast::numeric::Coord`]
//!   has), modelled by snapping the scene's vertices to the coarser grid —
//!   which is what a pipeline with fewer bits receives;
//! - the dither matrix (none, 2x2, 4x4, 8x8) per display format;
//! - antialiasing of solids: none, edge AA (seed 003 eq. 8), RUF-4/8/16
//!   (seed 000), sparse supersampling 4/8/16, a 4x4 grid;
//! - lines: Bresenham or two-point (Wu), RGB888 and RGB565;
//! - the geometry stage's back end (f64, f32, fixed `I16F16`);
//! - shading between the vertices (seed 001 §IV.2): Gouraud, fast Phong
//!   (ours) and Bishop & Weimer's Taylor colours, on a specular sphere and
//!   the teapot, against exact Phong ([`crate::phong`]);
//! - perspective texturing (seed 001 §IV.3): affine, the RE's quadratic
//!   interpolation at three tolerances and exact division, on a rectangle
//!   seen at depth ratios 4 and 16, against the exact mapping
//!   ([`crate::texture`]);
//! - alpha blending (seed 001 §IV.4): translucent panels drawn opaque or
//!   blended over the gradient scene.
//!
//! Area-sampling antialiasing through α (seed 001 §IV.5) is a setting of
//! the antialiasing family, beside edge AA, RUF and supersampling.
//!
//! The core has no approximate arithmetic to trade (setup is exact integer
//! math and one reciprocal, 2^-11 LSB; the host's mesh projection is f64),
//! so there is no "fast math" family: nothing to buy there.
//!
//! **Error** of each setting, against the f64 reference of the exact scene
//! ([`reference`](mod@reference)): against the 16x16 supersampled ideal and against the
//! pixel-centre reference, seed 000 eq. 8 per pixel, PSNR and max error;
//! after an 8x8 box blur, the RMS difference (what an eye at a distance sees
//! of banding, which dither trades for noise); and *visible artifacts*,
//! where they mean something: pixels more than 8/255 off the pixel-centre
//! reference in any channel or, for the depth knob, more than 1 off its
//! depth (a wrong surface in front, a band, a shifted edge), in families
//! whose coverage is the reference's.
//! The shading, texturing and alpha families change colours inside
//! surfaces, not coverage: shading and texturing measure against their own
//! f64 reference at pixel centres (exact Phong; the exact perspective
//! mapping, whose ramp texture turns colour error into texel error, 16 LSB
//! a texel), which also stands in for the ideal; alpha blending against the
//! blended scene's ordinary references.
//!
//! **Cost**: host time per pixel (median of repeated whole frames, the
//! pipeline alone, every setting timed once per turn so that a slow spell
//! of the machine falls on all of them alike), tile RAM per pixel (`size_of` of the planes), memory
//! traffic per frame (bytes read and written, counted by replaying the
//! scene's fragments through the pixel kinds, [`crate::ruf::traffic_with`]),
//! and instructions per pixel on the emulated Cortex-M4 and Cortex-M0 for
//! the settings the firmware measures (`reports/targets.md`, its own
//! workloads).
//!
//! Output: a Markdown table, a CSV and a chart of error against cost per
//! family with each scene's Pareto front marked.

use crate::aa::{line_scene, with_line_aa, IDEAL_SAMPLES};
use crate::ruf::{model_scene, traffic_with, Sizes};
use embedded_graphics_core::pixelcolor::Rgb888;
use std::path::PathBuf;
use tilerast::coverage::*;
use tilerast::line::EdgeCmd;
use tilerast::prelude::*;
use tilerast_sim::image::Image;
use tilerast_sim::mesh::GeometryKind;
use tilerast_sim::metrics::{box_blur, compare, rms, Diff};
use tilerast_sim::reference::{self, RefFrame};
use tilerast_sim::render::{
    render_as, render_textured, render_timed, AaKind, Config, FormatKind, Rendered, TexKind,
    SIM_GROUPS,
};
use tilerast_sim::texscene::{ramp, ramp_texels, texel_error, tilted_quad};

/// Pixels more than this far off the pixel-centre reference, in any
/// channel, are visible artifacts.
pub const ARTIFACT_LSB: u8 = 8;

/// With the depth knob, pixels whose depth is more than this far off the
/// reference's are artifacts too (another surface won the depth test): the
/// contract's Z bound is below 0.63.
pub const ARTIFACT_Z: f64 = 1.0;

/// Side of the box blur for the banding error.
pub const BLUR: u32 = 8;

/// How the sweep runs.
#[derive(Debug, Clone)]
pub struct Options {
    /// Folder of the seeds' OBJ models (`teapot.obj`, `dolphins.obj`); the
    /// model scenes are skipped when `None`.
    pub models: Option<PathBuf>,
    /// Timed renders per setting (the median is kept).
    pub runs: usize,
    /// Samples per pixel side of the ideal (16 for the report).
    pub ideal_samples: u32,
    /// Show progress on stderr.
    pub progress: bool,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            models: Some(PathBuf::from("assets/models")),
            runs: 15,
            ideal_samples: IDEAL_SAMPLES,
            progress: true,
        }
    }
}

/// A knob, with the axes its chart uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Family {
    /// Colour fraction bits of the span DDA.
    ColourBits,
    /// Depth plane bits and Z fraction bits.
    Depth,
    /// Sub-pixel bits of the vertices.
    Subpixel,
    /// Dither matrix per display format.
    Dither,
    /// Antialiasing of solids.
    Aa,
    /// Line drawing mode.
    Lines,
    /// The geometry stage's numeric back end (f32, fixed point, f64).
    Geometry,
    /// Shading between the vertices: Gouraud, fast Phong, Taylor.
    Shading,
    /// Perspective texturing: affine, quadratic, exact.
    Texturing,
    /// Translucent commands drawn opaque or alpha-blended.
    Alpha,
}

impl Family {
    /// Every family, in report order.
    pub const ALL: [Family; 10] = [
        Family::ColourBits,
        Family::Depth,
        Family::Subpixel,
        Family::Dither,
        Family::Aa,
        Family::Lines,
        Family::Geometry,
        Family::Shading,
        Family::Texturing,
        Family::Alpha,
    ];
    /// Its title.
    pub fn title(self) -> &'static str {
        match self {
            Family::ColourBits => "colour fraction bits",
            Family::Depth => "depth plane and Z fraction bits",
            Family::Subpixel => "sub-pixel bits",
            Family::Dither => "dither matrix per format",
            Family::Aa => "antialiasing of solids",
            Family::Lines => "lines",
            Family::Geometry => "geometry back end",
            Family::Shading => "shading between the vertices",
            Family::Texturing => "perspective texturing",
            Family::Alpha => "alpha blending",
        }
    }
    /// The cost and error its chart and Pareto front use, by name.
    pub fn axes(self) -> (Axis, Axis) {
        match self {
            Family::ColourBits => (Axis::Knob, Axis::CentreMse),
            Family::Depth => (Axis::BytesPx, Axis::Artifacts),
            Family::Subpixel => (Axis::Knob, Axis::IdealMse),
            Family::Dither => (Axis::NsPx, Axis::BlurRms),
            Family::Aa | Family::Lines | Family::Alpha => (Axis::NsPx, Axis::IdealMse),
            Family::Geometry => (Axis::NsVertex, Axis::CentreMse),
            Family::Shading => (Axis::NsPx, Axis::CentreMse),
            Family::Texturing => (Axis::NsPx, Axis::Texels),
        }
    }
}

/// A quantity a chart can plot.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Axis {
    /// The knob's own width in bits (fraction or sub-pixel bits).
    Knob,
    /// Tile RAM per pixel.
    BytesPx,
    /// Host nanoseconds per pixel.
    NsPx,
    /// Eq. 8 per pixel against the pixel-centre reference.
    CentreMse,
    /// Eq. 8 per pixel against the 16x16 ideal.
    IdealMse,
    /// RMS after the box blur.
    BlurRms,
    /// Visible artifact pixels.
    Artifacts,
    /// Host nanoseconds per vertex of the geometry stage.
    NsVertex,
    /// The largest texel error over the covered pixels.
    Texels,
}

impl Axis {
    /// Its label.
    pub fn label(self) -> &'static str {
        match self {
            Axis::Knob => "bits",
            Axis::BytesPx => "tile bytes/px",
            Axis::NsPx => "host ns/px",
            Axis::CentreMse => "eq.8/px vs pixel-centre f64",
            Axis::IdealMse => "eq.8/px vs 16x16 ideal",
            Axis::BlurRms => "RMS after 8x8 blur",
            Axis::Artifacts => "artifact pixels",
            Axis::NsVertex => "host ns/vertex",
            Axis::Texels => "worst texel error",
        }
    }
    /// Its value at a point.
    pub fn of(self, p: &Point) -> f64 {
        match self {
            Axis::Knob => p.knob_bits.unwrap_or(0) as f64,
            Axis::BytesPx => p.bytes_px,
            Axis::NsPx => p.ns_px,
            Axis::CentreMse => p.centre.mse_per_pixel,
            Axis::IdealMse => p.ideal.mse_per_pixel,
            Axis::BlurRms => p.blur_rms,
            Axis::Artifacts => p.artifacts.unwrap_or(0) as f64,
            Axis::NsVertex => p.ns_vertex.unwrap_or(f64::NAN),
            Axis::Texels => p.texels.unwrap_or(f64::NAN),
        }
    }
}

/// [`Point`] where `embedded-graphics` has its own.
type Pt = Point;

/// One measured setting.
#[derive(Debug, Clone)]
pub struct Point {
    /// The knob.
    pub family: Family,
    /// The scene (and the fixed part of the configuration).
    pub scene: String,
    /// The setting.
    pub setting: String,
    /// The setting, short, for the chart.
    pub short: String,
    /// The knob's width in bits, for bit-width knobs.
    pub knob_bits: Option<u32>,
    /// Against the 16x16 supersampled ideal.
    pub ideal: Diff,
    /// Against the pixel-centre f64 reference.
    pub centre: Diff,
    /// RMS difference from the pixel-centre reference after an 8x8 blur.
    pub blur_rms: f64,
    /// Visible artifact pixels, where meaningful.
    pub artifacts: Option<u64>,
    /// Host nanoseconds per pixel (median).
    pub ns_px: f64,
    /// Host nanoseconds per vertex of the geometry stage (geometry knob).
    pub ns_vertex: Option<f64>,
    /// Tile RAM per pixel, bytes.
    pub bytes_px: f64,
    /// Bytes read and written per frame.
    pub traffic: Option<u64>,
    /// Instructions per pixel (per step for lines) on the emulated
    /// Cortex-M4, from the firmware's workload of this setting.
    pub m4: Option<f64>,
    /// The same on the emulated Cortex-M0 (micro:bit).
    pub m0: Option<f64>,
    /// The largest texel error over the covered pixels (texturing).
    pub texels: Option<f64>,
    /// Pareto-optimal within its family and scene on the family's axes.
    pub pareto: bool,
}

/// A scene with its references, computed once.
struct Subject {
    name: String,
    cfg: Config,
    cmds: Vec<Command>,
    /// The commands with edge antialiasing on (models only).
    edges: Vec<Command>,
    ideal: Image,
    centre_img: Image,
    centre: RefFrame,
    centre_blur: Vec<[f64; 3]>,
    /// Settings that draw their own commands (geometry back ends, shading
    /// methods), with host ns/vertex where the setting has it.
    variants: Vec<(Setting, Vec<Command>, Option<f64>)>,
}

impl Subject {
    fn new(name: &str, cfg: Config, cmds: Vec<Command>, samples: u32) -> Subject {
        // The ideal needs no edge-antialiasing commands and ignores them.
        let ideal = reference::supersample(&cfg, &cmds, samples).to_image();
        let centre = reference::render(&cfg, &cmds);
        Subject {
            ideal,
            ..Subject::with_reference(name, cfg, cmds, centre)
        }
    }
    /// A subject measured against `centre` alone (also its ideal): exact
    /// Phong, the exact texture mapping.
    fn with_reference(name: &str, cfg: Config, cmds: Vec<Command>, centre: RefFrame) -> Subject {
        let centre_img = centre.to_image();
        Subject {
            name: name.into(),
            cfg,
            cmds,
            edges: Vec::new(),
            ideal: centre_img.clone(),
            centre_blur: box_blur(&centre_img, BLUR),
            centre_img,
            centre,
            variants: Vec::new(),
        }
    }
    /// The commands `set` draws: its own variant's, or the scene's.
    fn cmds_of(&self, set: Setting) -> &[Command] {
        self.variants
            .iter()
            .find(|v| v.0 == set)
            .map(|v| v.1.as_slice())
            .unwrap_or(&self.cmds)
    }
}

fn cfg(w: u16, h: u16, depth: bool) -> Config {
    Config {
        width: w,
        height: h,
        format: FormatKind::Rgb888,
        tile: (64, 32),
        dither: 0,
        depth,
        wid: false,
        clear: Clear {
            color: Rgb::new(16, 16, 24),
            ..Clear::default()
        },
        aa: AaKind::None,
        cull: tilerast::command::Cull::None,
    }
}

fn vtx(x: f64, y: f64, z: u16, c: [u8; 3]) -> Vertex {
    Vertex::new(
        Coord::from_num(x),
        Coord::from_num(y),
        z,
        Rgb::new(c[0], c[1], c[2]),
    )
}

fn tri(v: [Vertex; 3]) -> Command {
    Command::Triangle {
        v,
        state: State::default(),
    }
}

/// 240x160 of long Gouraud spans: a dark, gentle two-way ramp behind
/// everything (where banding shows), a saturated RGB triangle (channels at
/// 0 and 255) and a grey wedge in front.
pub fn gradient_scene() -> (Config, Vec<Command>) {
    let (w, h) = (240.0, 160.0);
    let bg = [
        vtx(0.0, 0.0, 60000, [10, 20, 40]),
        vtx(w, 0.0, 60000, [40, 60, 110]),
        vtx(w, h, 60000, [70, 50, 90]),
        vtx(0.0, h, 60000, [20, 40, 60]),
    ];
    let cmds = vec![
        tri([bg[0], bg[1], bg[2]]),
        tri([bg[0], bg[2], bg[3]]),
        tri([
            vtx(20.3, 12.7, 20000, [255, 0, 0]),
            vtx(226.9, 40.2, 30000, [0, 255, 0]),
            vtx(70.6, 150.1, 25000, [0, 0, 255]),
        ]),
        tri([
            vtx(130.2, 70.4, 10000, [255, 255, 255]),
            vtx(238.5, 150.8, 12000, [0, 0, 0]),
            vtx(110.7, 158.3, 11000, [128, 128, 128]),
        ]),
    ];
    (cfg(240, 160, true), cmds)
}

/// 192x128 of two flat surfaces crossing at a shallow depth angle, their
/// depths within 12 units of each other everywhere: a red pair of
/// triangles drawn first, then a green pair. The visible one changes at
/// `x = 96`; a 16-bit plane ties near there and the first drawn wins.
pub fn crossing_scene() -> (Config, Vec<Command>) {
    let (w, h) = (192.0, 128.0);
    let mut cmds = Vec::new();
    // Depth 30000 + 12 x / w against 30012 - 12 x / w (per screen width).
    for (za, zb, c) in [
        (30000u16, 30012u16, [220, 40, 40]),
        (30012, 30000, [40, 200, 60]),
    ] {
        let q = [
            vtx(0.0, 0.0, za, c),
            vtx(w, 0.0, zb, c),
            vtx(w, h, zb, c),
            vtx(0.0, h, za, c),
        ];
        cmds.push(tri([q[0], q[1], q[2]]));
        cmds.push(tri([q[0], q[2], q[3]]));
    }
    (cfg(192, 128, true), cmds)
}

/// The gradient scene with translucent panels in front ([`Blend::Alpha`],
/// Z tested, not written): a bluish rectangle at α 128 and a triangle whose
/// α runs from 40 to 230 across it, overlapping each other and every
/// surface behind, drawn back to front.
pub fn glass_scene() -> (Config, Vec<Command>) {
    let (c, mut cmds) = gradient_scene();
    let a = |x, y, z, c, alpha| vtx(x, y, z, c).with_alpha(alpha);
    let panel = [
        a(30.5, 20.25, 8000, [120, 180, 255], 128),
        a(150.75, 20.25, 8000, [120, 180, 255], 128),
        a(150.75, 120.5, 8000, [160, 200, 255], 128),
        a(30.5, 120.5, 8000, [160, 200, 255], 128),
    ];
    for t in [
        [panel[0], panel[1], panel[2]],
        [panel[0], panel[2], panel[3]],
        [
            a(90.2, 60.6, 6000, [255, 220, 60], 40),
            a(232.1, 90.3, 6000, [255, 120, 40], 230),
            a(120.4, 155.9, 6000, [255, 60, 160], 140),
        ],
    ] {
        cmds.push(tri(t).blend(Blend::Alpha));
    }
    (c, cmds)
}

/// A model's scene with its depths squeezed into `units` of the 16-bit
/// range: a small object far away in a deep view volume.
fn squeezed(cmds: &[Command], units: u32) -> Vec<Command> {
    let zs = cmds.iter().flat_map(|c| match c {
        Command::Triangle { v, .. } => v.map(|v| v.z).to_vec(),
        _ => vec![],
    });
    let (lo, hi) = zs.fold((u16::MAX, 0), |(a, b), z| (a.min(z), b.max(z)));
    let span = (hi.saturating_sub(lo)).max(1) as u32;
    cmds.iter()
        .map(|c| match *c {
            Command::Triangle { v, state } => Command::Triangle {
                v: v.map(|v| Vertex {
                    z: (40000 + (v.z.saturating_sub(lo) as u32 * units + span / 2) / span) as u16,
                    ..v
                }),
                state,
            },
            other => other,
        })
        .collect()
}

/// The commands with every vertex snapped (to nearest) to a grid of
/// `2^-bits` pixels.
pub fn snapped(cmds: &[Command], bits: u32) -> Vec<Command> {
    let drop = tilerast::numeric::SUBPIXEL_BITS.saturating_sub(bits);
    let snap = |c: Coord| {
        if drop == 0 {
            c
        } else {
            Coord::from_bits(((c.to_bits() + (1 << (drop - 1))) >> drop) << drop)
        }
    };
    cmds.iter()
        .map(|c| match *c {
            Command::Triangle { v, state } => Command::Triangle {
                v: v.map(|v| Vertex {
                    x: snap(v.x),
                    y: snap(v.y),
                    ..v
                }),
                state,
            },
            other => other,
        })
        .collect()
}

/// The firmware's per-pixel (per-step for lines) instruction counts on the
/// M4 and the M0, by workload name, from `reports/targets.md`.
fn fw_counts(targets: &str) -> Vec<(String, f64, Option<f64>)> {
    targets
        .lines()
        .filter_map(|l| {
            let cells: Vec<&str> = l.split('|').map(str::trim).collect();
            (cells.len() >= 4)
                .then(|| {
                    Some((
                        cells[1].to_string(),
                        cells[2].parse().ok()?,
                        cells[3].parse().ok(),
                    ))
                })
                .flatten()
        })
        .collect()
}

/// A setting to measure.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Setting {
    /// Colour fraction bits, in RGB888 without dither or RGB565 with 8x8.
    Colour(u32, bool),
    /// Depth plane bits and Z fraction bits.
    Depth(u32, u32),
    Subpixel(u32),
    Dither(FormatKind, u8),
    /// Coverage mode, or `None` with edge AA.
    Aa(AaKind, bool),
    /// Format, two-point antialiasing.
    Line(FormatKind, bool),
    /// The geometry stage's back end.
    Geometry(GeometryKind),
    /// Index into [`crate::phong::METHODS`].
    Shading(usize),
    /// Perspective mode of the textured rectangle.
    Texture(TexKind),
    /// Translucent commands blended (or drawn opaque).
    Alpha(bool),
}

impl Setting {
    fn family(self) -> Family {
        match self {
            Setting::Colour(..) => Family::ColourBits,
            Setting::Depth(..) => Family::Depth,
            Setting::Subpixel(_) => Family::Subpixel,
            Setting::Dither(..) => Family::Dither,
            Setting::Aa(..) => Family::Aa,
            Setting::Line(..) => Family::Lines,
            Setting::Geometry(_) => Family::Geometry,
            Setting::Shading(_) => Family::Shading,
            Setting::Texture(_) => Family::Texturing,
            Setting::Alpha(_) => Family::Alpha,
        }
    }
    fn label(self) -> String {
        match self {
            Setting::Colour(c, _) => format!("{c} colour bits"),
            Setting::Depth(b @ (16 | 24), _) => format!("Z{b}"),
            Setting::Depth(b, z) => format!("Z{b}, {z} Z bits"),
            Setting::Subpixel(s) => format!("{s} sub-pixel bits"),
            Setting::Dither(_, 0) => "no dither".into(),
            Setting::Dither(_, d) => format!("{d}x{d}"),
            Setting::Aa(AaKind::None, true) => "edge AA".into(),
            Setting::Aa(AaKind::Area, _) => "area (α)".into(),
            Setting::Aa(k, _) => k.name().into(),
            Setting::Line(_, wu) => if wu { "Wu" } else { "Bresenham" }.into(),
            Setting::Geometry(GeometryKind::F32) => "f32 (core)".into(),
            Setting::Geometry(GeometryKind::Fixed) => "fixed I16F16 (core)".into(),
            Setting::Geometry(GeometryKind::Reference) => "f64 (reference)".into(),
            Setting::Shading(m) => crate::phong::METHODS[m].into(),
            Setting::Texture(TexKind::Quadratic) => "quadratic within ½ texel".into(),
            Setting::Texture(TexKind::Quadratic2) => "quadratic within 2 texels".into(),
            Setting::Texture(TexKind::QuadraticNoSplit) => "quadratic, 32-px segments".into(),
            Setting::Texture(TexKind::Exact) => "exact division".into(),
            Setting::Texture(k) => k.name().into(),
            Setting::Alpha(false) => "opaque (α ignored)".into(),
            Setting::Alpha(true) => "α-blended".into(),
        }
    }
    /// The label on the chart.
    fn short(self) -> String {
        match self {
            Setting::Colour(b, _) | Setting::Subpixel(b) => b.to_string(),
            Setting::Depth(b @ (16 | 24), _) => format!("Z{b}"),
            Setting::Depth(b, z) => format!("Z{b}/{z}"),
            Setting::Dither(_, 0) => "none".into(),
            Setting::Line(_, false) => "Bres.".into(),
            Setting::Shading(0) => "Gouraud".into(),
            Setting::Shading(1) => "fast Phong".into(),
            Setting::Shading(_) => "Taylor".into(),
            Setting::Texture(TexKind::Quadratic) => "quad ½".into(),
            Setting::Texture(TexKind::Quadratic2) => "quad 2".into(),
            Setting::Texture(TexKind::QuadraticNoSplit) => "quad 32".into(),
            Setting::Texture(k) => k.name().into(),
            Setting::Alpha(false) => "opaque".into(),
            Setting::Alpha(true) => "blended".into(),
            _ => self.label(),
        }
    }
    /// What the scene's series holds fixed besides the scene.
    fn series(self) -> Option<String> {
        match self {
            Setting::Colour(_, false) => Some("rgb888".into()),
            Setting::Colour(_, true) => Some("rgb565, 8x8 dither".into()),
            Setting::Dither(f, _) | Setting::Line(f, _) => Some(f.name().into()),
            _ => None,
        }
    }
    fn knob_bits(self) -> Option<u32> {
        match self {
            Setting::Colour(c, _) => Some(c),
            Setting::Subpixel(s) => Some(s),
            Setting::Depth(b, _) => Some(b),
            _ => None,
        }
    }
    /// The firmware workload measuring this setting.
    fn workload(self) -> Option<&'static str> {
        match self {
            Setting::Aa(AaKind::None, false) => Some("Gouraud + Z"),
            Setting::Aa(AaKind::None, true) => Some("Gouraud + Z + edge AA (eq. 8) on every edge"),
            Setting::Aa(AaKind::Area, _) => {
                Some("Gouraud + Z + area sampling (α, seed 001 §IV.5) on every edge")
            }
            Setting::Line(FormatKind::Rgb565, false) => Some("Bresenham, RGB565"),
            Setting::Line(FormatKind::Rgb565, true) => Some("two-point (Wu) antialiased, RGB565"),
            Setting::Dither(FormatKind::Rgb565, 0) => Some("Gouraud + Z + window ID"),
            Setting::Dither(FormatKind::Rgb565, 8) => Some("Gouraud + Z + window ID + 8x8 dither"),
            Setting::Shading(0) | Setting::Alpha(false) => Some("large triangles: Gouraud + Z"),
            // Taylor's colours are drawn by the same quadratic command.
            Setting::Shading(_) => Some("large triangles: fast Phong (quadratic, seed 001 §IV.2) + Z"),
            Setting::Alpha(true) => {
                Some("large triangles: Gouraud + Z, alpha-blended (per-vertex α)")
            }
            Setting::Texture(TexKind::Affine) => {
                Some("large triangles: textured (16x16 RGB565, nearest, q 4:1) + Z, affine")
            }
            Setting::Texture(TexKind::Quadratic) => Some(
                "the same, perspective by quadratic interpolation along the span (seed 001 §IV.3)",
            ),
            Setting::Texture(TexKind::Exact) => {
                Some("the same, perspective by division at every pixel")
            }
            Setting::Texture(TexKind::Quadratic2) => {
                Some("the same, quadratic within two texels (`QuadraticTexturing<16>`)")
            }
            Setting::Texture(TexKind::QuadraticNoSplit) => Some("the same, quadratic never split (`QuadraticTexturing<NEVER_SPLIT>`, the seed's 32-px segments)"),
            _ => None,
        }
    }
}

type R = Result<Rendered, Error>;

fn colour_bits<F: PixelFormat, D: Dither>(c: u32, cfg: &Config, cmds: &[Command], runs: usize) -> R
where
    Rgb888: From<F::Color>,
{
    fn at<F: PixelFormat, D: Dither, P: Precision>(cfg: &Config, cmds: &[Command], runs: usize) -> R
    where
        Rgb888: From<F::Color>,
    {
        render_as::<F, Depth16, NoWid, D, NoAa, P, SIM_GROUPS>(cfg, cmds, runs)
    }
    match c {
        2 => at::<F, D, Bits<2, 14>>(cfg, cmds, runs),
        4 => at::<F, D, Bits<4, 14>>(cfg, cmds, runs),
        6 => at::<F, D, Bits<6, 14>>(cfg, cmds, runs),
        8 => at::<F, D, Bits<8, 14>>(cfg, cmds, runs),
        10 => at::<F, D, Bits<10, 14>>(cfg, cmds, runs),
        12 => at::<F, D, Bits<12, 14>>(cfg, cmds, runs),
        _ => at::<F, D, FullPrecision>(cfg, cmds, runs),
    }
}

fn depth_bits(b: u32, z: u32, cfg: &Config, cmds: &[Command], runs: usize) -> R {
    fn at<Z: DepthMode, P: Precision>(cfg: &Config, cmds: &[Command], runs: usize) -> R {
        render_as::<Rgb888Format, Z, NoWid, NoDither, NoAa, P, SIM_GROUPS>(cfg, cmds, runs)
    }
    match (b, z) {
        (16, _) => at::<Depth16, FullPrecision>(cfg, cmds, runs),
        (24, _) => at::<Depth24, FullPrecision>(cfg, cmds, runs),
        (32, 0) => at::<Depth32, Bits<16, 0>>(cfg, cmds, runs),
        (32, 4) => at::<Depth32, Bits<16, 4>>(cfg, cmds, runs),
        (32, 8) => at::<Depth32, Bits<16, 8>>(cfg, cmds, runs),
        _ => at::<Depth32, FullPrecision>(cfg, cmds, runs),
    }
}

fn format_bytes(f: FormatKind) -> u64 {
    match f {
        FormatKind::Rgb888 => 3,
        FormatKind::Rgb565 | FormatKind::Rgb444 => 2,
        // Gray8, and the 1-bit format's read-modify-write of a byte.
        _ => 1,
    }
}

/// Bytes per frame of the aliased pipeline (pixel-centre fragments), plus
/// edge antialiasing's blends (Z and colour read, colour written) along
/// each edge's major axis.
fn aliased_traffic(cmds: &[Command], cfg: &Config, format: FormatKind, zbytes: u64) -> u64 {
    let sizes = Sizes {
        c: format_bytes(format),
        z: zbytes,
        tag: 0,
        mask: 0,
    };
    let (w, h) = (cfg.width, cfg.height);
    let (t, _) = traffic_with::<Centre1, 1>(cmds, w, h, sizes, zbytes > 0);
    let screen = Rect::new(0, 0, w as u32, h as u32);
    let blends: u64 = cmds
        .iter()
        .filter_map(|c| match c {
            Command::Edge { edge, .. } => EdgeCmd::bounds(edge)?.intersect(&screen),
            _ => None,
        })
        .map(|r| r.w.max(r.h) as u64)
        .sum();
    t.total() + blends * (zbytes + 2 * sizes.c)
}

fn coverage_traffic(s: &Subject, k: AaKind) -> u64 {
    let (cmds, w, h) = (&s.cmds, s.cfg.width, s.cfg.height);
    let sz = |m: u64| Sizes {
        c: 3,
        z: 2,
        tag: 2,
        mask: m.div_ceil(8),
    };
    let (ss, ruf) = match k {
        AaKind::Ruf4 | AaKind::Ss4 => traffic_with::<Sparse4, 4>(cmds, w, h, sz(4), true),
        AaKind::Ruf8 | AaKind::Ss8 => traffic_with::<Sparse8, 8>(cmds, w, h, sz(8), true),
        AaKind::Ruf16 | AaKind::Ss16 => traffic_with::<Sparse16, 16>(cmds, w, h, sz(16), true),
        AaKind::Grid4 => traffic_with::<Grid4x4, 16>(cmds, w, h, sz(16), true),
        AaKind::Grid8 => traffic_with::<Grid8x8, 64>(cmds, w, h, sz(64), true),
        AaKind::None | AaKind::Area => traffic_with::<Centre1, 1>(cmds, w, h, sz(1), true),
    };
    match k {
        AaKind::Ruf4 | AaKind::Ruf8 | AaKind::Ruf16 => ruf.total(),
        _ => ss.total(),
    }
}

/// Measures one setting on one subject.
/// Draws one setting on one subject, timing `runs` renders first.
fn draw(s: &Subject, set: Setting, runs: usize) -> Result<Rendered, String> {
    let base = s.cfg;
    let err = |e: Error| format!("{} / {}: {e:?}", s.name, set.label());
    let r = match set {
        Setting::Colour(c, false) => colour_bits::<Rgb888Format, NoDither>(c, &base, &s.cmds, runs),
        Setting::Colour(c, true) => colour_bits::<Rgb565Format, Bayer8>(c, &base, &s.cmds, runs),
        Setting::Depth(b, z) => depth_bits(b, z, &base, &s.cmds, runs),
        Setting::Subpixel(bits) => render_timed(&base, &snapped(&s.cmds, bits), runs),
        Setting::Dither(f, d) => {
            let cfg = Config {
                format: f,
                dither: d,
                ..base
            };
            render_timed(&cfg, &s.cmds, runs)
        }
        Setting::Aa(k, edge) => {
            let cfg = Config { aa: k, ..base };
            render_timed(&cfg, if edge { &s.edges } else { &s.cmds }, runs)
        }
        Setting::Line(f, wu) => {
            let cfg = Config { format: f, ..base };
            render_timed(&cfg, &with_line_aa(&s.cmds, wu), runs)
        }
        Setting::Geometry(_) | Setting::Shading(_) => render_timed(&base, s.cmds_of(set), runs),
        Setting::Texture(kind) => {
            let ramp_texels = ramp_texels();
            render_textured(&base, &s.cmds, &[ramp(&ramp_texels)], kind, runs)
        }
        Setting::Alpha(true) => render_timed(&base, &s.cmds, runs),
        Setting::Alpha(false) => {
            let opaque: Vec<Command> = s
                .cmds
                .iter()
                .map(|c| {
                    let mut c = *c;
                    if let Some(st) = c.state_mut() {
                        st.blend = Blend::Opaque;
                    }
                    c
                })
                .collect();
            render_timed(&base, &opaque, runs)
        }
    };
    r.map_err(err)
}

/// Bytes read and written per frame by one setting on one subject, where
/// the replay models it.
fn traffic(s: &Subject, set: Setting) -> Option<u64> {
    let rgb888 = |cmds: &[Command]| aliased_traffic(cmds, &s.cfg, FormatKind::Rgb888, 2);
    match set {
        Setting::Colour(_, dither) => Some(aliased_traffic(
            &s.cmds,
            &s.cfg,
            if dither {
                FormatKind::Rgb565
            } else {
                FormatKind::Rgb888
            },
            2,
        )),
        Setting::Depth(b, _) => Some(aliased_traffic(
            &s.cmds,
            &s.cfg,
            FormatKind::Rgb888,
            b as u64 / 8,
        )),
        Setting::Subpixel(_) => Some(rgb888(&s.cmds)),
        Setting::Dither(f, _) => Some(aliased_traffic(&s.cmds, &s.cfg, f, 2)),
        // Area sampling reads and writes the same silhouette pixels as
        // edge AA: its traffic model is the edges'.
        Setting::Aa(AaKind::None, true) | Setting::Aa(AaKind::Area, _) => Some(rgb888(&s.edges)),
        Setting::Aa(AaKind::None, false) => Some(rgb888(&s.cmds)),
        Setting::Aa(k, _) => Some(coverage_traffic(s, k)),
        Setting::Geometry(_) => Some(rgb888(s.cmds_of(set))),
        // The replay counts triangles: the quadratic commands of the
        // shading methods cover the Gouraud list's fragments.
        Setting::Shading(_) => Some(rgb888(&s.cmds)),
        // Not modelled: the replay has no texel reads, and does not blend
        // (a blend reads the colour and writes no Z).
        Setting::Line(..) | Setting::Texture(_) | Setting::Alpha(_) => None,
    }
}

/// Measures one setting on one subject, all but its host time
/// ([`run`] times the settings in turns).
fn measure(s: &Subject, set: Setting, fw: &[(String, f64, Option<f64>)]) -> Result<Point, String> {
    let r = draw(s, set, 0)?;
    // In families whose coverage is the reference's.
    let artifacts_meaningful = !matches!(
        set,
        Setting::Colour(_, true) | Setting::Dither(..) | Setting::Aa(..) | Setting::Line(..)
    );
    let texels = matches!(set, Setting::Texture(_)).then(|| texel_error(&r, &s.centre).max);
    let centre = compare(&r.image, &s.centre_img).map_err(|e| e.to_string())?;
    let artifacts = artifacts_meaningful.then(|| {
        (0..r.raw.len())
            .filter(|&i| {
                let (a, b) = (r.image.pixels[i], s.centre_img.pixels[i]);
                let wrong_colour = (0..3).any(|c| a[c].abs_diff(b[c]) > ARTIFACT_LSB);
                let (z, zr) = (r.depth[i] as f64, s.centre.depth[i]);
                // Depth counts where depth is the knob: elsewhere a moved
                // vertex shifts depth invisibly.
                let wrong_depth = matches!(set, Setting::Depth(..))
                    && zr.is_finite()
                    && (z - zr).abs() > ARTIFACT_Z;
                wrong_colour || wrong_depth
            })
            .count() as u64
    });
    let fw_row = set
        .workload()
        .and_then(|w| fw.iter().find(|(n, ..)| n == w));
    Ok(Point {
        family: set.family(),
        scene: match set.series() {
            Some(x) => format!("{}, {x}", s.name),
            None => s.name.clone(),
        },
        setting: set.label(),
        short: set.short(),
        knob_bits: set.knob_bits(),
        ideal: compare(&r.image, &s.ideal).map_err(|e| e.to_string())?,
        centre,
        blur_rms: rms(&box_blur(&r.image, BLUR), &s.centre_blur),
        artifacts,
        ns_px: f64::NAN,
        ns_vertex: s.variants.iter().find(|v| v.0 == set).and_then(|v| v.2),
        bytes_px: r.bits_per_pixel as f64 / 8.0,
        traffic: traffic(s, set),
        m4: fw_row.map(|r| r.1),
        m0: fw_row.and_then(|r| r.2),
        texels,
        pareto: false,
    })
}

/// Marks, within each family and scene, the points no other point beats
/// on both of the family's axes (lower or equal cost and error, one of
/// them strictly).
pub fn mark_pareto(points: &mut [Point]) {
    let flags: Vec<bool> = points
        .iter()
        .map(|p| {
            let (cx, ex) = p.family.axes();
            let (c, e) = (cx.of(p), ex.of(p));
            !points.iter().any(|q| {
                q.family == p.family
                    && q.scene == p.scene
                    && cx.of(q) <= c
                    && ex.of(q) <= e
                    && (cx.of(q) < c || ex.of(q) < e)
            })
        })
        .collect();
    for (p, f) in points.iter_mut().zip(flags) {
        p.pareto = f;
    }
}

/// Runs the whole sweep.
pub fn run(opt: &Options) -> Result<Vec<Point>, String> {
    let mut plan: Vec<(usize, Setting)> = Vec::new();
    let mut subjects: Vec<Subject> = Vec::new();
    let n = opt.ideal_samples;
    let fw = std::fs::read_to_string("reports/targets.md")
        .map(|t| fw_counts(&t))
        .unwrap_or_default();

    let (c, cmds) = gradient_scene();
    subjects.push(Subject::new("gradient 240x160", c, cmds, n));
    let (mut c, cmds) = gradient_scene();
    c.format = FormatKind::Gray8;
    subjects.push(Subject::new("gradient 240x160 (luma)", c, cmds, n));
    let (c, cmds) = crossing_scene();
    subjects.push(Subject::new("crossing planes 192x128", c, cmds, n));
    let (c, cmds) = line_scene();
    subjects.push(Subject::new("40 lines 128x96", c, cmds, n));
    let mut models = Vec::new();
    if let Some(dir) = &opt.models {
        for name in ["teapot", "dolphins"] {
            let mut sc = model_scene(&dir.join(format!("{name}.obj")))?;
            let mut cfg = sc.config;
            cfg.depth = true;
            let mut sub = Subject::new(&format!("{name} 256x192"), cfg, sc.commands.clone(), n);
            sc.set_edge_aa(true);
            sub.edges = sc.commands.clone();
            sc.set_edge_aa(false);
            subjects.push(sub);
            models.push(subjects.len() - 1);
            if name == "teapot" {
                subjects.push(Subject::new(
                    "teapot, depth in 16 units",
                    cfg,
                    squeezed(&sc.commands, 16),
                    n,
                ));
            }
        }
    }
    // The geometry knob: each back end's commands against the references
    // of the f64 geometry's (so the error is the back end's alone).
    let mut geometry_subjects = Vec::new();
    if let Some(dir) = &opt.models {
        for name in ["teapot", "dolphins"] {
            let path = dir.join(format!("{name}.obj"));
            let reference = crate::ruf::model_scene_with(&path, "reference")?;
            let mut cfg = reference.config;
            cfg.depth = true;
            let mut sub = Subject::new(
                &format!("{name} 256x192, f64 geometry as reference"),
                cfg,
                reference.commands.clone(),
                n,
            );
            let obj = tilerast_sim::obj::load(&path, &tilerast_sim::Limits::default())
                .map_err(|e| e.to_string())?;
            let mut spec = tilerast_sim::mesh::MeshSpec::new("x.obj");
            (spec.eye, spec.fov, spec.cull_back) = ([0.3, 0.4, 3.2], 40.0, true);
            for (k, word) in [
                (GeometryKind::F32, "f32"),
                (GeometryKind::Fixed, "fixed"),
                (GeometryKind::Reference, "reference"),
            ] {
                let sc = crate::ruf::model_scene_with(&path, word)?;
                let ns =
                    tilerast_sim::mesh::vertex_stage_ns(&obj, &spec, crate::ruf::SIZE, k, opt.runs);
                sub.variants
                    .push((Setting::Geometry(k), sc.commands, Some(ns)));
            }
            subjects.push(sub);
            geometry_subjects.push(subjects.len() - 1);
        }
    }
    // Shading: each method's commands against exact Phong.
    let mut lit = Vec::new();
    let mut shaded = vec![(
        "sphere, 12 slices, specular".to_string(),
        crate::phong::sphere_scene(12, true)?,
    )];
    if let Some(dir) = &opt.models {
        shaded.push((
            "teapot 240x240, specular".into(),
            crate::phong::teapot_scene(dir, true)?,
        ));
    }
    for (name, (obj, spec)) in shaded {
        let b = crate::phong::build(&obj, &spec);
        let mut sub =
            Subject::with_reference(&name, crate::phong::config(), b.lists[0].clone(), b.exact());
        for (m, list) in b.lists.into_iter().enumerate() {
            sub.variants.push((Setting::Shading(m), list, None));
        }
        subjects.push(sub);
        lit.push(subjects.len() - 1);
    }
    // Texturing: the tilted rectangle against the exact mapping.
    let mut tilted = Vec::new();
    for ratio in [4.0, 16.0] {
        let cfg = crate::texture::config();
        let cmds = tilted_quad(cfg.width, cfg.height, ratio);
        let exact = reference::render_textured(&cfg, &cmds, &[ramp(&ramp_texels())]);
        subjects.push(Subject::with_reference(
            &format!("rectangle at depth ratio {ratio}"),
            cfg,
            cmds.to_vec(),
            exact,
        ));
        tilted.push(subjects.len() - 1);
    }
    let (c, cmds) = glass_scene();
    subjects.push(Subject::new("translucent panels 240x160", c, cmds, n));
    let glass = subjects.len() - 1;
    let (gradient, luma, crossing, lines) = (0, 1, 2, 3);
    let teapot = models.first().copied();

    for c in [2, 4, 6, 8, 10, 12, 16] {
        plan.push((gradient, Setting::Colour(c, false)));
        plan.push((gradient, Setting::Colour(c, true)));
        if let Some(t) = teapot {
            plan.push((t, Setting::Colour(c, false)));
        }
    }
    let close: Vec<usize> = std::iter::once(crossing)
        .chain(teapot.map(|t| t + 1))
        .collect();
    for &s in &close {
        for (b, z) in [(16, 14), (24, 14), (32, 0), (32, 4), (32, 8), (32, 14)] {
            plan.push((s, Setting::Depth(b, z)));
        }
    }
    for &m in &models {
        for b in 0..=4 {
            plan.push((m, Setting::Subpixel(b)));
        }
    }
    for f in [
        FormatKind::Rgb565,
        FormatKind::Rgb444,
        FormatKind::Gray8,
        FormatKind::Binary,
    ] {
        let s = if f.is_gray() { luma } else { gradient };
        for d in [0, 2, 4, 8] {
            plan.push((s, Setting::Dither(f, d)));
        }
    }
    for &m in &models {
        for (k, e) in [
            (AaKind::None, false),
            (AaKind::None, true),
            (AaKind::Area, false),
            (AaKind::Ruf4, false),
            (AaKind::Ruf8, false),
            (AaKind::Ruf16, false),
            (AaKind::Ss4, false),
            (AaKind::Ss8, false),
            (AaKind::Ss16, false),
            (AaKind::Grid4, false),
        ] {
            plan.push((m, Setting::Aa(k, e)));
        }
    }
    for f in [FormatKind::Rgb888, FormatKind::Rgb565] {
        for wu in [false, true] {
            plan.push((lines, Setting::Line(f, wu)));
        }
    }
    for &g in &geometry_subjects {
        for k in [
            GeometryKind::Reference,
            GeometryKind::F32,
            GeometryKind::Fixed,
        ] {
            plan.push((g, Setting::Geometry(k)));
        }
    }

    for &t in &lit {
        for m in 0..crate::phong::METHODS.len() {
            plan.push((t, Setting::Shading(m)));
        }
    }
    for &t in &tilted {
        for k in [
            TexKind::Affine,
            TexKind::QuadraticNoSplit,
            TexKind::Quadratic2,
            TexKind::Quadratic,
            TexKind::Exact,
        ] {
            plan.push((t, Setting::Texture(k)));
        }
    }
    plan.push((glass, Setting::Alpha(false)));
    plan.push((glass, Setting::Alpha(true)));

    let mut out = Vec::with_capacity(plan.len());
    // A progress bar on a terminal; nothing when piped (CI logs) or off.
    let bar = if opt.progress {
        indicatif::ProgressBar::new((plan.len() * (1 + opt.runs)) as u64)
    } else {
        indicatif::ProgressBar::hidden()
    };
    bar.set_style(
        indicatif::ProgressStyle::with_template("[{bar:30}] {pos}/{len} {elapsed} {msg}")
            .map_err(|e| e.to_string())?
            .progress_chars("#> "),
    );
    for (s, set) in &plan {
        bar.set_message(format!("{}: {}", subjects[*s].name, set.label()));
        out.push(measure(&subjects[*s], *set, &fw)?);
        bar.inc(1);
    }
    // Host time: one timed render of every setting per turn, `runs` turns,
    // the median kept, so that the machine's slow spells (seconds long on
    // a shared host) fall on every setting alike instead of on whichever
    // settings were timed during them.
    let mut times = vec![Vec::with_capacity(opt.runs); plan.len()];
    for turn in 0..opt.runs {
        bar.set_message(format!("timing, turn {} of {}", turn + 1, opt.runs));
        for ((s, set), t) in plan.iter().zip(&mut times) {
            let ns = draw(&subjects[*s], *set, 1)?.ns_per_pixel;
            t.push(ns.unwrap_or(f64::NAN));
            bar.inc(1);
        }
    }
    for (p, mut t) in out.iter_mut().zip(times) {
        t.sort_by(f64::total_cmp);
        if !t.is_empty() {
            p.ns_px = t[t.len() / 2];
        }
    }
    bar.finish_and_clear();
    mark_pareto(&mut out);
    Ok(out)
}

fn opt<T>(v: Option<T>, f: impl Fn(T) -> String) -> String {
    v.map(f).unwrap_or_default()
}

/// The points as CSV, one row each.
pub fn csv(points: &[Point]) -> String {
    let mut s = String::from(
        "family,scene,setting,knob_bits,ideal_eq8_per_px,ideal_psnr_db,ideal_max,centre_eq8_per_px,centre_psnr_db,centre_max,blur_rms,artifact_px,host_ns_per_px,m4_instr_per_px,tile_bytes_per_px,traffic_bytes_per_frame,m0_instr_per_px,worst_texel_error,pareto\n",
    );
    for p in points {
        s += &format!(
            "{},{},{},{},{:.3},{:.2},{},{:.3},{:.2},{},{:.3},{},{:.2},{},{},{},{},{},{}\n",
            p.family.title(),
            p.scene.replace(',', ";"),
            p.setting.replace(',', ";"),
            opt(p.knob_bits, |b| b.to_string()),
            p.ideal.mse_per_pixel,
            p.ideal.psnr,
            p.ideal.max_abs,
            p.centre.mse_per_pixel,
            p.centre.psnr,
            p.centre.max_abs,
            p.blur_rms,
            opt(p.artifacts, |a| a.to_string()),
            p.ns_px,
            opt(p.m4, |m| format!("{m:.1}")),
            p.bytes_px,
            opt(p.traffic, |t| t.to_string()),
            opt(p.m0, |m| format!("{m:.1}")),
            opt(p.texels, |t| format!("{t:.3}")),
            p.pareto
        );
    }
    s
}

/// The points as Markdown: one table per family.
pub fn markdown(points: &[Point]) -> String {
    let mut s = String::new();
    for f in Family::ALL {
        let rows: Vec<&Point> = points.iter().filter(|p| p.family == f).collect();
        if rows.is_empty() {
            continue;
        }
        let (cx, ex) = f.axes();
        s += &format!(
            "### {}\n\nPareto front (**bold**): {} against {}.\n\n\
             | scene | setting | eq.8/px vs ideal | PSNR vs ideal | max | eq.8/px vs centre | PSNR vs centre | blur RMS | artifacts | host ns/px | M4 instr/px | M0 instr/px | tile B/px | traffic B/frame |\n\
             | --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |\n",
            f.title(),
            ex.label(),
            cx.label()
        );
        for p in rows {
            let mut set = if p.pareto {
                format!("**{}**", p.setting)
            } else {
                p.setting.clone()
            };
            if let Some(ns) = p.ns_vertex {
                set += &format!(", {ns:.1} host ns/vertex");
            }
            if let Some(t) = p.texels {
                set += &format!(", worst {t:.2} texel");
            }
            s += &format!(
                "| {} | {} | {:.1} | {:.2} | {} | {:.2} | {:.2} | {:.3} | {} | {:.2} | {} | {} | {} | {} |\n",
                p.scene,
                set,
                p.ideal.mse_per_pixel,
                p.ideal.psnr,
                p.ideal.max_abs,
                p.centre.mse_per_pixel,
                p.centre.psnr,
                p.blur_rms,
                opt(p.artifacts, |a| a.to_string()),
                p.ns_px,
                opt(p.m4, |m| format!("{m:.1}")),
                opt(p.m0, |m| format!("{m:.1}")),
                p.bytes_px,
                opt(p.traffic, |t| t.to_string()),
            );
        }
        s += "\n";
    }
    s
}

/// The whole report: how it was measured, then [`markdown`].
pub fn report(
    points: &[Point],
    opt: &Options,
    chart: &std::path::Path,
    csv: &std::path::Path,
) -> String {
    format!(
        "# Speed against accuracy\n\n\
         Generated by `tilerast-lab tradeoff` (`cargo xtask bench` runs it): {} settings, \
         chart `{}`, every figure also in `{}`.\n\n\
         **Error**, against the f64 reference of the exact scene: *ideal* is the {n}x{n} \
         supersampled reference, *centre* the pixel-centre one (so the knob's own error shows \
         without the aliasing every pixel-centre renderer has); eq. 8 per pixel is seed 000's \
         sum over R, G, B of squared differences, averaged over pixels; PSNR and max are over \
         channels; *blur RMS* compares both after an {BLUR}x{BLUR} box blur (banding, which \
         dither trades for noise); *artifacts* counts pixels more than {ARTIFACT_LSB}/255 off \
         the pixel-centre reference in any channel or, for the depth knob, more than {ARTIFACT_Z} \
         off its depth, in families whose coverage is the reference's (a wrong surface in front, a band, a moved \
         edge). Shading and texturing change colours inside surfaces, not coverage: they are measured \
         against their own f64 reference at pixel centres, which stands in for the ideal too (exact Phong: \
         the normal interpolated and normalised at every pixel; the exact perspective mapping, whose ramp \
         texture turns colour error into texel error, 16 LSB a texel, so artifacts there are pixels more \
         than half a texel off); alpha blending is measured against the blended scene's references.\n\n\
         **Cost**: host ns/px is the median of {} whole frames, pipeline only, on this machine, \
         timed in turns (every setting once a turn, so a slow spell of the machine falls on all \
         alike; still noisy across runs: compare within a table); M4 and M0 instr/px are the firmware's own workload of that \
         setting under QEMU (`reports/targets.md`, RGB565; per step for lines; the shading, texturing \
         and alpha rows quote its large-triangle workloads, the texturing ones a 16x16 texture with \
         nearest sampling at depth ratio 4, Taylor the fast Phong command that draws its colours, \
         opaque the same triangles in planes without blending); tile B/px is \
         `size_of` of the planes; traffic is bytes read and written per frame, counted by \
         replaying the scene's fragments through the pixel kinds (edge AA's blends estimated \
         as one per major-axis step).\n\n\
         Each table marks its Pareto front per scene: no other setting of the family has \
         lower or equal cost and error with one strictly lower, on the axes named.\n\n{}",
        points.len(),
        chart.display(),
        csv.display(),
        opt.runs,
        markdown(points),
        n = opt.ideal_samples,
    )
}

/// Error against cost, one panel per family (error on a log scale), one
/// colour per scene, Pareto-optimal points filled and joined (`plotters`).
pub fn chart(points: &[Pt]) -> Result<Image, String> {
    use crate::chart::{err, plot, SANS};
    use plotters::prelude::*;
    const PW: u32 = 440;
    const PH: u32 = 360;
    let palette = [
        RGBColor(200, 60, 40),
        RGBColor(40, 110, 210),
        RGBColor(40, 160, 80),
        RGBColor(160, 80, 190),
        RGBColor(210, 150, 30),
        RGBColor(90, 90, 90),
    ];
    let fams: Vec<Family> = Family::ALL
        .into_iter()
        .filter(|f| points.iter().any(|p| p.family == *f))
        .collect();
    let rows = fams.len().div_ceil(2);
    plot(2 * PW, rows as u32 * PH, |area| {
        let panels = area.split_evenly((rows, 2));
        for (f, panel) in fams.iter().zip(&panels) {
            let pts: Vec<&Pt> = points.iter().filter(|p| p.family == *f).collect();
            let (cx, ex) = f.axes();
            let ey = |p: &Pt| ex.of(p) + 1e-3;
            let (x0, x1) = pts.iter().fold((f64::MAX, f64::MIN), |(a, b), p| {
                (a.min(cx.of(p)), b.max(cx.of(p)))
            });
            let (y0, y1) = pts.iter().fold((f64::MAX, f64::MIN), |(a, b), p| {
                (a.min(ey(p)), b.max(ey(p)))
            });
            let pad = ((x1 - x0) * 0.08).max(0.5);
            let (y0, y1) = (
                10f64.powf(y0.log10().floor()),
                10f64.powf(y1.log10().ceil().max(y0.log10().floor() + 1.0)),
            );
            let mut ch = ChartBuilder::on(panel)
                .caption(f.title(), (SANS, 15))
                .margin(10)
                .x_label_area_size(36)
                .y_label_area_size(56)
                .build_cartesian_2d(x0 - pad..x1 + pad, (y0..y1).log_scale())
                .map_err(err)?;
            ch.configure_mesh()
                .x_desc(cx.label())
                .y_desc(format!("{} (log)", ex.label()))
                .y_label_formatter(&|v| format!("{v:.0e}"))
                .label_style((SANS, 11))
                .draw()
                .map_err(err)?;
            let mut scenes: Vec<&str> = Vec::new();
            for p in &pts {
                if !scenes.contains(&p.scene.as_str()) {
                    scenes.push(&p.scene);
                }
            }
            for (j, sc) in scenes.iter().enumerate() {
                let col = palette[j % palette.len()];
                let mut front: Vec<&&Pt> =
                    pts.iter().filter(|p| p.scene == *sc && p.pareto).collect();
                front.sort_by(|a, b| cx.of(a).total_cmp(&cx.of(b)));
                ch.draw_series(LineSeries::new(
                    front.iter().map(|p| (cx.of(p), ey(p))),
                    col.stroke_width(1),
                ))
                .map_err(err)?
                .label(*sc)
                .legend(move |(x, y)| Circle::new((x + 5, y), 4, col.filled()));
                let mine: Vec<&&Pt> = pts.iter().filter(|p| p.scene == *sc).collect();
                ch.draw_series(mine.iter().map(|p| {
                    let style = if p.pareto {
                        col.filled()
                    } else {
                        col.stroke_width(1)
                    };
                    EmptyElement::at((cx.of(p), ey(p)))
                        + Circle::new((0, 0), 4, style)
                        + Text::new(
                            p.short.clone(),
                            (5, -12),
                            (SANS, 10).into_font().color(&col),
                        )
                }))
                .map_err(err)?;
            }
            ch.configure_series_labels()
                .background_style(WHITE.mix(0.85))
                .border_style(RGBColor(180, 180, 180))
                .label_font((SANS, 10))
                .position(SeriesLabelPosition::UpperRight)
                .draw()
                .map_err(err)?;
        }
        Ok(())
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn m4_table_rows_parse() {
        let t = "| workload | a | b |\n| --- | ---: | ---: |\n| Gouraud + Z | 341.7 | 1421.0 |\n";
        assert_eq!(
            fw_counts(t),
            vec![("Gouraud + Z".to_string(), 341.7, Some(1421.0))]
        );
    }

    #[test]
    fn snapping_rounds_to_the_coarser_grid() {
        let v = |x: i32| Vertex::new(Coord::from_bits(x), Coord::from_bits(-x), 0, Rgb::default());
        let c = [tri([v(13), v(7), v(-9)])];
        let Command::Triangle { v: s, .. } = snapped(&c, 2)[0] else {
            unreachable!()
        };
        // Grid of 4 sub-pixels: 13 -> 12, 7 -> 8, -9 -> -8 (ties up).
        assert_eq!(s.map(|v| v.x.to_bits()), [12, 8, -8]);
        assert_eq!(snapped(&c, 4)[0], c[0]);
    }
}
