//! Renders a display list with the `no_std` core, choosing the tile's types
//! (format, depth plane, window-ID plane, dither) from a runtime [`Config`]:
//! the host pays the monomorphization, the firmware picks one.

use embedded_graphics_core::pixelcolor::Rgb888;
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
}

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
    match cfg.format {
        FormatKind::Rgb888 => by_depth::<Rgb888Format>(cfg, cmds),
        FormatKind::Rgb565 => by_depth::<Rgb565Format>(cfg, cmds),
        FormatKind::Rgb444 => by_depth::<Rgb444Format>(cfg, cmds),
        FormatKind::Gray8 => by_depth::<Gray8Format>(cfg, cmds),
        FormatKind::Binary => by_depth::<BinaryFormat>(cfg, cmds),
    }
}

fn by_depth<F: PixelFormat>(cfg: &Config, cmds: &[Command]) -> Result<Rendered, Error>
where
    Rgb888: From<F::Color>,
{
    if cfg.depth {
        by_wid::<F, Depth16>(cfg, cmds)
    } else {
        by_wid::<F, NoDepth>(cfg, cmds)
    }
}

fn by_wid<F: PixelFormat, Z: DepthMode>(cfg: &Config, cmds: &[Command]) -> Result<Rendered, Error>
where
    Rgb888: From<F::Color>,
{
    if cfg.wid {
        by_dither::<F, Z, Wid8>(cfg, cmds)
    } else {
        by_dither::<F, Z, NoWid>(cfg, cmds)
    }
}

fn by_dither<F: PixelFormat, Z: DepthMode, W: WidMode>(
    cfg: &Config,
    cmds: &[Command],
) -> Result<Rendered, Error>
where
    Rgb888: From<F::Color>,
{
    match cfg.dither {
        0 | 1 => run::<F, Z, W, NoDither>(cfg, cmds),
        2 => run::<F, Z, W, Bayer2>(cfg, cmds),
        4 => run::<F, Z, W, Bayer4>(cfg, cmds),
        8 => run::<F, Z, W, Bayer8>(cfg, cmds),
        16 => run::<F, Z, W, Bayer<4>>(cfg, cmds),
        _ => Err(Error::BadSize),
    }
}

fn run<F: PixelFormat, Z: DepthMode, W: WidMode, D: Dither>(
    cfg: &Config,
    cmds: &[Command],
) -> Result<Rendered, Error>
where
    Rgb888: From<F::Color>,
{
    let mut frame = Frame::new(cfg.width, cfg.height, cfg.tile.0, cfg.tile.1)?;
    frame.clear = cfg.clear;
    let mut tile: Box<Tile<SIM_GROUPS, F, Z, W, D>> = Box::default();
    let (w, h) = (cfg.width as u32, cfg.height as u32);
    let mut image = Image::new(w, h);
    let mut raw = vec![0u32; (w * h) as usize];
    let mut depth = vec![u16::MAX; (w * h) as usize];
    let stats = frame
        .render_with(&mut tile, cmds, |t| {
            let a = t.area();
            for y in a.y..a.y + a.h as i32 {
                for x in a.x..a.x + a.w as i32 {
                    let i = (y as u32 * w + x as u32) as usize;
                    let r = t.raw(x, y).expect("inside the tile");
                    raw[i] = r;
                    let c = Rgb888::from(F::to_color(r));
                    image.pixels[i] = [c.r(), c.g(), c.b()];
                    depth[i] = t.depth(x, y).expect("inside the tile");
                }
            }
            Ok::<(), core::convert::Infallible>(())
        })
        .map_err(|e| match e {
            FlushError::Raster(e) => e,
            FlushError::Target(never) => match never {},
        })?;
    Ok(Rendered {
        image,
        raw,
        depth,
        bits_per_pixel: Tile::<SIM_GROUPS, F, Z, W, D>::bits_per_pixel(),
        stats,
    })
}

use embedded_graphics_core::pixelcolor::RgbColor;
