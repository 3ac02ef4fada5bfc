//! Renders a display list with the `no_std` core, in the tiles a scene
//! file asks for. A firmware names its tile's planes by type; the
//! simulator reads them from a file, so it compiles one pipeline per colour
//! format, coverage mode and depth plane, and sets the window-ID plane and
//! the dither as values (`Switchable<Wid8>`, `RuntimeDither`): the same
//! pixels, a handful of pipelines instead of hundreds.

use embedded_graphics_core::pixelcolor::Rgb888;
use tilerast::coverage::AaMode;
use tilerast::prelude::*;

/// Pixel capacity of the simulator's tile, in groups of 8: 98,304 pixels
/// (a whole 320x300 screen as one tile).
pub const SIM_GROUPS: usize = 12288;

/// The display formats by name.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Deserialize, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum FormatKind {
    /// 24-bit RGB.
    Rgb888,
    /// 16-bit RGB (5-6-5).
    Rgb565,
    /// 12-bit RGB (4-4-4), the seed's double-buffer half.
    Rgb444,
    /// 8-bit grey.
    Gray8,
    /// 1 bit per pixel.
    Binary,
}

impl FormatKind {
    /// Whether the format stores a single luma channel.
    pub fn is_gray(self) -> bool {
        matches!(self, FormatKind::Gray8 | FormatKind::Binary)
    }
    /// The name used in scene files.
    pub fn name(self) -> &'static str {
        match self {
            FormatKind::Rgb888 => Rgb888Format::NAME,
            FormatKind::Rgb565 => Rgb565Format::NAME,
            FormatKind::Rgb444 => Rgb444Format::NAME,
            FormatKind::Gray8 => Gray8Format::NAME,
            FormatKind::Binary => BinaryFormat::NAME,
        }
    }
}

/// What a frame needs: screen, format, tiles, dither and planes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Config {
    /// Screen width.
    pub width: u16,
    /// Screen height.
    pub height: u16,
    /// Display format.
    pub format: FormatKind,
    /// Tile width and height.
    pub tile: (u16, u16),
    /// Dither matrix side: 0 (none), 2, 4, 8 or 16.
    pub dither: u8,
    /// 16-bit Z plane.
    pub depth: bool,
    /// 8-bit window-ID plane.
    pub wid: bool,
    /// Tile clear values.
    pub clear: Clear,
    /// Coverage antialiasing.
    pub aa: AaKind,
    /// Back-face culling of the whole frame ([`Frame::cull`]).
    pub cull: Cull,
}

impl Config {
    /// The configuration an encoded scene's header asks for
    /// ([`tilerast::wire::SceneHeader`]), rendered in its own tiles.
    pub fn from_header(h: &tilerast::wire::SceneHeader) -> crate::Result<Config> {
        use crate::Error::Unsupported;
        let name = h.format.split(|&b| b == 0).next().unwrap_or_default();
        let format = [
            FormatKind::Rgb888,
            FormatKind::Rgb565,
            FormatKind::Rgb444,
            FormatKind::Gray8,
            FormatKind::Binary,
        ]
        .into_iter()
        .find(|f| f.name().as_bytes() == name)
        .ok_or_else(|| {
            Unsupported(format!(
                "unknown format {:?}",
                String::from_utf8_lossy(name)
            ))
        })?;
        let side = |v: u16| (1..=tilerast::numeric::MAX_SIDE).contains(&v);
        if !(side(h.width) && side(h.height) && side(h.tile.0) && side(h.tile.1)) {
            return Err(Unsupported(format!(
                "bad screen {}x{} or tile {:?}",
                h.width, h.height, h.tile
            )));
        }
        let tile = (h.tile.0.min(h.width), h.tile.1.min(h.height));
        if tile.0 as usize * tile.1 as usize > SIM_GROUPS * 8 {
            return Err(Unsupported(format!(
                "tile {tile:?} exceeds the simulator's tile"
            )));
        }
        let dither = match h.dither_log2 {
            0 => 0,
            k @ 1..=4 => 1 << k,
            k => return Err(Unsupported(format!("dither 2^{k} is not built"))),
        };
        let plane = |bits: u8, on: u8, what: &str| match bits {
            0 => Ok(false),
            b if b == on => Ok(true),
            b => Err(Unsupported(format!("{b}-bit {what} plane is not built"))),
        };
        Ok(Config {
            width: h.width,
            height: h.height,
            format,
            tile,
            dither,
            depth: plane(h.depth_bits, 16, "depth")?,
            wid: plane(h.wid_bits, 8, "window-ID")?,
            clear: h.clear,
            aa: AaKind::None,
            cull: h.cull,
        })
    }
}

/// Coverage antialiasing modes by name ([`tilerast::coverage`]).
#[derive(
    Debug,
    Clone,
    Copy,
    PartialEq,
    Eq,
    Default,
    serde::Deserialize,
    serde::Serialize,
    clap::ValueEnum,
)]
#[serde(rename_all = "lowercase")]
pub enum AaKind {
    /// None: one sample at the pixel centre, no coverage plane.
    #[default]
    None,
    /// RUF buffer, 4 sparse samples.
    Ruf4,
    /// RUF buffer, 8 sparse samples (the paper's).
    Ruf8,
    /// RUF buffer, 16 sparse samples.
    Ruf16,
    /// Supersampling, 4 sparse samples.
    Ss4,
    /// Supersampling, 8 sparse samples (the paper's "8ss").
    Ss8,
    /// Supersampling, 16 sparse samples.
    Ss16,
    /// Supersampling, regular 4x4 grid.
    Grid4,
    /// Supersampling, regular 8x8 grid (the paper's reference).
    Grid8,
    /// Area sampling through the α-channel (the RE's, [`tilerast::area`]):
    /// silhouette and boundary edges ([`crate::silhouette::flag_silhouettes`])
    /// blended by exact pixel coverage; no plane.
    Area,
}

impl AaKind {
    /// Every mode.
    pub const ALL: [AaKind; 10] = [
        AaKind::None,
        AaKind::Ruf4,
        AaKind::Ruf8,
        AaKind::Ruf16,
        AaKind::Ss4,
        AaKind::Ss8,
        AaKind::Ss16,
        AaKind::Grid4,
        AaKind::Grid8,
        AaKind::Area,
    ];
    /// The name in scene files and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            AaKind::None => "none",
            AaKind::Ruf4 => "ruf4",
            AaKind::Ruf8 => "ruf8",
            AaKind::Ruf16 => "ruf16",
            AaKind::Ss4 => "ss4",
            AaKind::Ss8 => "ss8",
            AaKind::Ss16 => "ss16",
            AaKind::Grid4 => "grid4",
            AaKind::Grid8 => "grid8",
            AaKind::Area => "area",
        }
    }
    /// Samples per pixel (1 for none).
    pub fn samples(self) -> u32 {
        match self {
            AaKind::None | AaKind::Area => 1,
            AaKind::Ruf4 | AaKind::Ss4 => 4,
            AaKind::Ruf8 | AaKind::Ss8 => 8,
            AaKind::Ruf16 | AaKind::Ss16 | AaKind::Grid4 => 16,
            AaKind::Grid8 => 64,
        }
    }
}

/// Pixel capacity of the simulator's tile with a coverage plane, in groups
/// of 8: 2,048 pixels (an 8x8 grid costs 320 bytes a pixel).
pub const AA_GROUPS: usize = 256;

/// A rendered frame.
#[derive(Debug, Clone)]
pub struct Rendered {
    /// The frame as the display shows it, expanded to RGB888.
    pub image: Image,
    /// The packed pixels as stored in the tile planes, row-major.
    pub raw: Vec<u32>,
    /// Depth plane contents (65535 where there is no plane).
    pub depth: Vec<u16>,
    /// Exact tile RAM per pixel, in bits.
    pub bits_per_pixel: u32,
    /// Binning and replay counts.
    pub stats: FrameStats,
    /// Host time of the pipeline alone, in nanoseconds per screen pixel:
    /// the median of the timed runs, when any were asked for
    /// ([`render_timed`], [`render_as`]).
    pub ns_per_pixel: Option<f64>,
}

use crate::image::Image;

impl Rendered {
    /// RAM for one tile of the configured size, in bytes.
    pub fn tile_bytes(&self, cfg: &Config) -> u64 {
        (cfg.tile.0 as u64 * cfg.tile.1 as u64 * self.bits_per_pixel as u64).div_ceil(8)
    }
}

/// Renders `cmds` in tiles as the firmware would.
pub fn render(cfg: &Config, cmds: &[Command]) -> Result<Rendered, Error> {
    render_timed(cfg, cmds, 0)
}

/// [`render`], after timing `runs` renders ([`Rendered::ns_per_pixel`]).
pub fn render_timed(cfg: &Config, cmds: &[Command], runs: usize) -> Result<Rendered, Error> {
    use tilerast::coverage::*;
    match cfg.aa {
        // Area sampling has no plane, and a triangle without edge flags
        // draws exactly as without it (tested): the simulator builds one
        // set of plane-less tiles for both, and flags the silhouettes only
        // in area mode.
        AaKind::None if cmds.iter().any(Command::edge_flagged) => {
            let mut plain = cmds.to_vec();
            for c in &mut plain {
                if let Command::Triangle { v, .. } = c {
                    v.iter_mut().for_each(|v| v.edge_flag = false);
                }
            }
            without_coverage(cfg, &plain, runs)
        }
        AaKind::None => without_coverage(cfg, cmds, runs),
        AaKind::Area => {
            let mut flagged = cmds.to_vec();
            crate::silhouette::flag_silhouettes(&mut flagged);
            without_coverage(cfg, &flagged, runs)
        }
        AaKind::Ruf4 => aa_format::<Ruf4>(cfg, cmds, runs),
        AaKind::Ruf8 => aa_format::<Ruf8>(cfg, cmds, runs),
        AaKind::Ruf16 => aa_format::<Ruf16>(cfg, cmds, runs),
        AaKind::Ss4 => aa_format::<Ss4>(cfg, cmds, runs),
        AaKind::Ss8 => aa_format::<Ss8>(cfg, cmds, runs),
        AaKind::Ss16 => aa_format::<Ss16>(cfg, cmds, runs),
        AaKind::Grid4 => aa_format::<SsGrid4>(cfg, cmds, runs),
        AaKind::Grid8 => aa_format::<SsGrid8>(cfg, cmds, runs),
    }
}

/// The window-ID plane of the simulator's tiles: present or not as the
/// scene says, one compiled pipeline for both (pixels equal a tile without
/// the plane when it is off: `tests/tests/runtime_planes.rs`).
pub type HostWid = Switchable<Wid8>;

/// [`by_format`] without a coverage plane (`AreaAa`: area sampling has no
/// plane, and a triangle without edge flags draws exactly as without it).
/// The depth plane stays a type here: as a value it cost every pixel a
/// test of the switch and the loops' registers, about 12% of a frame
/// (criterion, the teapot), for 5 pipelines more.
fn without_coverage(cfg: &Config, cmds: &[Command], runs: usize) -> Result<Rendered, Error> {
    use tilerast::area::AreaAa;
    if cfg.depth {
        by_format::<AreaAa, Depth16, RuntimeDither, SIM_GROUPS>(cfg, cmds, runs)
    } else {
        by_format::<AreaAa, NoDepth, RuntimeDither, SIM_GROUPS>(cfg, cmds, runs)
    }
}

/// `log2` of a dither matrix side as a scene names it (0 or 1: none, 2,
/// 4, 8, 16); `None` for any other.
pub fn dither_log2(side: u8) -> Option<u32> {
    match side {
        0 | 1 => Some(0),
        2 | 4 | 8 | 16 => Some(side.trailing_zeros()),
        _ => None,
    }
}

/// The simulator's pipelines: one per colour format, coverage mode and
/// depth plane — window ID and dither are values ([`HostWid`],
/// [`RuntimeDither`]), not types, so the build compiles a handful of
/// pipelines rather than one per combination (a cold release build went
/// from 11.6 min and 9.5 GB of memory to 2.6 min and 2.3 GB: the README's
/// build figures). With coverage antialiasing the depth test is always on
/// (a depth per sample; the depth plane then holds each pixel's nearest
/// sample for the lines drawn over the resolved image).
fn by_format<A: AaMode, Z: DepthMode, D: Dither, const G: usize>(
    cfg: &Config,
    cmds: &[Command],
    runs: usize,
) -> Result<Rendered, Error> {
    if dither_log2(cfg.dither).is_none() {
        return Err(Error::BadSize);
    }
    type P<F, Z, D, A> =
        Planes<F, Z, HostWid, D, A, FullPrecision, AlphaBlending, QuadraticShading>;
    match cfg.format {
        FormatKind::Rgb888 => render_source::<P<Rgb888Format, Z, D, A>, _, G>(cfg, cmds, runs),
        FormatKind::Rgb565 => render_source::<P<Rgb565Format, Z, D, A>, _, G>(cfg, cmds, runs),
        FormatKind::Rgb444 => render_source::<P<Rgb444Format, Z, D, A>, _, G>(cfg, cmds, runs),
        FormatKind::Gray8 => render_source::<P<Gray8Format, Z, D, A>, _, G>(cfg, cmds, runs),
        FormatKind::Binary => render_source::<P<BinaryFormat, Z, D, A>, _, G>(cfg, cmds, runs),
    }
}

/// [`by_format`] with a coverage plane of mode `A`.
fn aa_format<A: AaMode>(cfg: &Config, cmds: &[Command], runs: usize) -> Result<Rendered, Error> {
    by_format::<A, Depth16, OneLoopDither, AA_GROUPS>(cfg, cmds, runs)
}

/// [`RuntimeDither`] without its second span loop for level 0
/// ([`Dither::VARIES`] false): the dither of the coverage and texture
/// pipelines, whose pixels cost many span steps each. One span loop per
/// pipeline instead of two keeps the build within its memory (the same
/// pixels: the level-0 loop is an optimisation).
#[derive(Debug, Clone, Copy, Default)]
pub struct OneLoopDither(RuntimeDither);

impl Dither for OneLoopDither {
    const NEW: Self = OneLoopDither(RuntimeDither::NEW);
    #[inline(always)]
    fn log2(self) -> u32 {
        self.0.log2()
    }
    fn with_log2(log2: u32) -> Option<Self> {
        RuntimeDither::with_log2(log2).map(OneLoopDither)
    }
    #[inline(always)]
    fn carry(self, x: u32, y: u32) -> i32 {
        self.0.carry(x, y)
    }
}

/// The frame and a boxed tile of `G` groups for `cfg`, the tile shrunk
/// until it fits (the output does not depend on the tiling).
#[allow(clippy::type_complexity)]
pub(crate) fn frame_and_tile<C: TileConfig, const G: usize>(
    cfg: &Config,
) -> Result<(Frame, Box<Tile<G, C>>), Error> {
    let (mut tw, mut th) = cfg.tile;
    while tw as usize * th as usize > G * 8 {
        if tw >= th {
            tw = tw.div_ceil(2);
        } else {
            th = th.div_ceil(2);
        }
    }
    let mut frame = Frame::new(cfg.width, cfg.height, tw, th)?;
    frame.clear = cfg.clear;
    frame.cull = cfg.cull;
    let mut tile: Box<Tile<G, C>> = Box::default();
    // The planes and dither `cfg` names, where they are values (planes
    // and dithers fixed by type keep theirs).
    tile.enable_depth(cfg.depth);
    tile.enable_wid(cfg.wid);
    if let Some(d) = dither_log2(cfg.dither).and_then(C::Dither::with_log2) {
        tile.set_dither(d);
    }
    Ok((frame, tile))
}

/// The simulator's bins: 65,536 (tile, command) entries, 1,024 tiles per
/// pass (520 KB on the heap). Larger frames take more passes, with the
/// same output.
pub type HostBins = tilerast::bin::Bins<65536, 1024>;

/// Renders `cmds` with the tile types given, whatever `cfg` says about
/// format, planes, dither and coverage (its screen, tile size and clear
/// values are used): the entry point for sweeps over knobs that are types.
/// With `runs > 0` it first times that many renders, tiles discarded when
/// done (no copy, no flush) so that only the pipeline is timed, and
/// reports the median.
pub fn render_as<
    F: PixelFormat,
    Z: DepthMode,
    W: WidMode,
    D: Dither,
    A: AaMode,
    P: Precision,
    const G: usize,
>(
    cfg: &Config,
    cmds: &[Command],
    runs: usize,
) -> Result<Rendered, Error>
where
    Rgb888: From<F::Color>,
{
    render_source::<Planes<F, Z, W, D, A, P, AlphaBlending, QuadraticShading>, _, G>(
        cfg, cmds, runs,
    )
}

/// Perspective modes of textured triangles ([`tilerast::texture`]), by name.
#[derive(
    Debug,
    Clone,
    Copy,
    PartialEq,
    Eq,
    Default,
    serde::Deserialize,
    serde::Serialize,
    clap::ValueEnum,
)]
#[serde(rename_all = "lowercase")]
pub enum TexKind {
    /// No texturing compiled: textured triangles draw their shade.
    #[default]
    None,
    /// Affine in screen space.
    Affine,
    /// The RE's quadratic interpolation along each span.
    Quadratic,
    /// A division per pixel.
    Exact,
    /// The quadratic within two texels (`QuadraticTexturing<16>`): fewer
    /// segments split.
    #[serde(rename = "quadratic-2")]
    #[value(name = "quadratic-2")]
    Quadratic2,
    /// The quadratic never split (`QuadraticTexturing<NEVER_SPLIT>`): the
    /// seed's plain 32-pixel segments.
    #[serde(rename = "quadratic-nosplit")]
    #[value(name = "quadratic-nosplit")]
    QuadraticNoSplit,
}

impl TexKind {
    /// The three modes that texture.
    pub const TEXTURED: [TexKind; 3] = [TexKind::Affine, TexKind::Quadratic, TexKind::Exact];
    /// The quadratic mode's tolerance knob: half a texel (the default), two
    /// texels, never split (RGB888 and RGB565 only).
    pub const TOLERANCES: [TexKind; 3] = [
        TexKind::Quadratic,
        TexKind::Quadratic2,
        TexKind::QuadraticNoSplit,
    ];
    /// The name on the command line and in reports.
    pub fn name(self) -> &'static str {
        match self {
            TexKind::None => "none",
            TexKind::Affine => "affine",
            TexKind::Quadratic => "quadratic",
            TexKind::Exact => "exact",
            TexKind::Quadratic2 => "quadratic-2",
            TexKind::QuadraticNoSplit => "quadratic-nosplit",
        }
    }
}

/// Renders `cmds` with `textures` (a textured command's `tex` indexes
/// them) in perspective mode `kind`, timing `runs` renders first like
/// [`render_timed`]. Textured scenes are built with a 16-bit Z plane, no
/// window-ID plane, no coverage antialiasing and any dither (other
/// configurations: [`Error::BadSize`]; the tolerance variants
/// [`TexKind::TOLERANCES`] also need RGB888 or RGB565); with [`TexKind::None`] it is
/// [`render_timed`], textures unused.
pub fn render_textured(
    cfg: &Config,
    cmds: &[Command],
    textures: &[Texture<'_>],
    kind: TexKind,
    runs: usize,
) -> Result<Rendered, Error> {
    fn by_dither<F: PixelFormat, X: TextureMode>(
        cfg: &Config,
        src: &WithTextures<'_, [Command]>,
        runs: usize,
    ) -> Result<Rendered, Error>
    where
        Rgb888: From<F::Color>,
    {
        type P<F, X> = Planes<
            F,
            Depth16,
            NoWid,
            OneLoopDither,
            NoAa,
            FullPrecision,
            AlphaBlending,
            QuadraticShading,
            X,
        >;
        match dither_log2(cfg.dither) {
            Some(_) => render_source::<P<F, X>, _, SIM_GROUPS>(cfg, src, runs),
            None => Err(Error::BadSize),
        }
    }
    /// RGB888 and RGB565 (all the tolerance knob's variants compile: each
    /// configuration is a copy of the draw code).
    fn by_rgb<X: TextureMode>(
        cfg: &Config,
        src: &WithTextures<'_, [Command]>,
        runs: usize,
    ) -> Result<Rendered, Error> {
        match cfg.format {
            FormatKind::Rgb888 => by_dither::<Rgb888Format, X>(cfg, src, runs),
            FormatKind::Rgb565 => by_dither::<Rgb565Format, X>(cfg, src, runs),
            _ => Err(Error::BadSize),
        }
    }
    /// Every format.
    fn by_format<X: TextureMode>(
        cfg: &Config,
        src: &WithTextures<'_, [Command]>,
        runs: usize,
    ) -> Result<Rendered, Error> {
        match cfg.format {
            FormatKind::Rgb444 => by_dither::<Rgb444Format, X>(cfg, src, runs),
            FormatKind::Gray8 => by_dither::<Gray8Format, X>(cfg, src, runs),
            FormatKind::Binary => by_dither::<BinaryFormat, X>(cfg, src, runs),
            FormatKind::Rgb888 | FormatKind::Rgb565 => by_rgb::<X>(cfg, src, runs),
        }
    }
    if kind == TexKind::None {
        return render_timed(cfg, cmds, runs);
    }
    if !cfg.depth || cfg.wid || cfg.aa != AaKind::None {
        return Err(Error::BadSize);
    }
    let src = WithTextures::new(cmds, textures);
    match kind {
        TexKind::None | TexKind::Affine => by_format::<AffineTexturing>(cfg, &src, runs),
        TexKind::Quadratic => by_format::<QuadraticTexturing>(cfg, &src, runs),
        TexKind::Exact => by_format::<ExactTexturing>(cfg, &src, runs),
        TexKind::Quadratic2 => by_rgb::<QuadraticTexturing<16>>(cfg, &src, runs),
        TexKind::QuadraticNoSplit => {
            by_rgb::<QuadraticTexturing<{ tilerast::texture::NEVER_SPLIT }>>(cfg, &src, runs)
        }
    }
}

/// [`render_as`] for any tile configuration and command source.
fn render_source<C: TileConfig, S: CommandSource + ?Sized, const G: usize>(
    cfg: &Config,
    cmds: &S,
    runs: usize,
) -> Result<Rendered, Error>
where
    Rgb888: From<<C::Format as PixelFormat>::Color>,
{
    let (frame, mut tile) = frame_and_tile::<C, G>(cfg)?;
    let mut bins: Box<HostBins> = Box::default();
    let (w, h) = (cfg.width as u32, cfg.height as u32);
    let mut times: Vec<f64> = (0..runs)
        .map(|_| {
            let start = std::time::Instant::now();
            frame
                .render_binned(&mut tile, &mut *bins, cmds, |t| {
                    std::hint::black_box(t.raw(t.area().x, t.area().y));
                    Ok::<(), core::convert::Infallible>(())
                })
                .map_err(Error::from)?;
            Ok(start.elapsed().as_nanos() as f64 / (w as f64 * h as f64))
        })
        .collect::<Result<_, Error>>()?;
    times.sort_by(f64::total_cmp);
    let mut image = Image::new(w, h);
    let mut raw = vec![0u32; (w * h) as usize];
    let mut depth = vec![u16::MAX; (w * h) as usize];
    let stats = frame
        .render_binned(&mut tile, &mut *bins, cmds, |t| {
            copy_tile(t, &mut image, &mut raw, &mut depth);
            Ok::<(), core::convert::Infallible>(())
        })
        .map_err(Error::from)?;
    Ok(Rendered {
        image,
        raw,
        depth,
        bits_per_pixel: tile.bits_in_use(),
        stats,
        ns_per_pixel: times.get(times.len() / 2).copied(),
    })
}

/// Copies a finished tile into the frame's image, packed pixels and depth
/// (all `image.width` wide).
pub(crate) fn copy_tile<C: TileConfig, const G: usize>(
    t: &Tile<G, C>,
    image: &mut Image,
    raw: &mut [u32],
    depth: &mut [u16],
) where
    Rgb888: From<<C::Format as PixelFormat>::Color>,
{
    let (a, w) = (t.area(), image.width);
    for y in a.y..a.y + a.h as i32 {
        for x in a.x..a.x + a.w as i32 {
            let i = (y as u32 * w + x as u32) as usize;
            let r = t.raw(x, y).expect("inside the tile");
            raw[i] = r;
            let c = Rgb888::from(C::Format::to_color(r));
            image.pixels[i] = [c.r(), c.g(), c.b()];
            depth[i] = t.depth(x, y).expect("inside the tile");
        }
    }
}

use embedded_graphics_core::pixelcolor::RgbColor;
