#![doc = include_str!("../README.md")]
//!
//! # The library
//!
//! A `#![no_std]`, fixed-point tile rasterizer for microcontrollers that drive
//! small displays (SSD1306, ST7789, ILI9341 class). It implements the raster
//! engine of the seed paper *"고성능 그래픽스 전용 프로세서 개발"* (REjr/RE):
//! span interpolation of R, G, B and Z with DDAs, 16-bit Z, 8-bit window-ID
//! clipping, plane masks, and ordered dithering computed from the pixel address
//! bits — rendered tile by tile so that a 240x240 frame needs a few KB of RAM.
//!
//! ## The pipeline, in reading order
//!
//! The source is laid out by stage (`core/src/`), and a stage imports only
//! the stages before it. Stages marked *internal* are private: their work
//! shows through the public types.
//!
//! | stage | where | what it does |
//! | --- | --- | --- |
//! | base | [`geom`], [`numeric`], [`format`], [`error`] | rectangles and vertices, the fixed-point contract, display formats and packing, errors |
//! | commands | [`command`], [`list`] | the display list: spans, triangles, lines, antialiased edges, fills, with constructors |
//! | setup | `setup` (internal) | vertices to exact integer edge functions and attribute planes (seed 001 §III) |
//! | raster | `raster` (internal): `traverse`, `span`, [`line`](mod@line), [`coverage`] | exact per-row coverage with the top-left fill rule; the span DDA every primitive ends in (seed 001 §II.1); Bresenham and two-point (Wu) lines and edge antialiasing (seed 003); coverage masks and the RUF buffer (seed 000) |
//! | fragment | [`fragment`], [`dither`] | window-ID test, Z test (less-than, read-modify-write), then one store path: address-bit ordered dither (seed 001 §II.3), pack, plane mask, store |
//! | tile planes | [`config`], [`tile`] | colour, depth, window-ID and coverage planes chosen by one configuration type; drawing into them |
//! | bin | [`bin`] | one pass sorts the frame's commands into per-tile lists in bins of a capacity the user picks (a frame that overflows them is split into bands, never refused) |
//! | frame, flush | [`frame`] | a screen cut into tiles, each replaying its binned commands, then flushed to any `embedded-graphics` `DrawTarget` |
//!
//! Beside the pipeline: [`wire`] encodes display lists as bytes (for flash),
//! [`hash`] checks output bit for bit (a CRC32 `DrawTarget`).
//!
//! ## Model only what the scene requires
//!
//! A [`Tile`](tile::Tile)'s planes are one configuration type ([`config`]). An absent depth or
//! window-ID plane is `()`: zero bytes, and its test compiles to nothing.
//!
//! ```
//! use tilerast::prelude::*;
//!
//! // 64x64 pixels, RGB565, 16-bit Z, no window IDs, 4x4 dither.
//! type MyTile = Tile<{ groups(64, 64) }, Planes<Rgb565Format, Depth16, NoWid, Bayer4>>;
//! assert_eq!(MyTile::bits_per_pixel(), 16 + 16);
//! // The same tile without depth costs only its colour plane.
//! assert_eq!(Tile::<512, Rgb565Format>::bits_per_pixel(), 16);
//! ```
//!
//! ## A whole frame
//!
//! ```
//! use tilerast::prelude::*;
//! use embedded_graphics_core::pixelcolor::Rgb565;
//! # use embedded_graphics_core::{prelude::*, primitives::Rectangle};
//! # struct Screen;
//! # impl OriginDimensions for Screen { fn size(&self) -> Size { Size::new(96, 64) } }
//! # impl DrawTarget for Screen {
//! #     type Color = Rgb565; type Error = core::convert::Infallible;
//! #     fn draw_iter<I: IntoIterator<Item = Pixel<Rgb565>>>(&mut self, _: I) -> Result<(), Self::Error> { Ok(()) }
//! # }
//! # let mut display = Screen;
//! let mut list: DisplayList<8> = DisplayList::new();
//! let v = |x: i32, y: i32, c: [u8; 3]| Vertex::new(Coord::from_num(x), Coord::from_num(y), 0, Rgb::new(c[0], c[1], c[2]));
//! list.push(Command::Triangle {
//!     v: [v(4, 4, [255, 0, 0]), v(90, 10, [0, 255, 0]), v(40, 60, [0, 0, 255])],
//!     state: State::default(),
//! })?;
//! type Small = Tile<{ groups(32, 32) }, Planes<Rgb565Format, NoDepth, NoWid, Bayer4>>;
//! let frame = Small::frame::<32, 32>(96, 64)?;
//! let mut tile = Small::new();
//! frame.render(&mut tile, &list, &mut display).map_err(|_| Error::TileTooLarge)?;
//! # Ok::<(), tilerast::Error>(())
//! ```
#![no_std]
#![deny(missing_docs)]
#![deny(unsafe_code)]

// The base every stage shares.
pub mod error;
pub mod format;
pub mod geom;
pub mod numeric;

// The pipeline, in order; a stage imports only the stages before it
// (the geometry stage, first in the pipeline, implements the frame's
// `CommandSource`, so it is declared last).
pub mod bin;
pub mod command;
pub mod list;
mod raster;
mod setup;
pub use raster::{area, coverage, line};
pub mod fragment;
pub use fragment::dither;
pub mod config;
pub mod frame;
pub mod geometry;
pub mod occlusion;
pub mod texture;
pub mod tile;
pub mod volume;
// The object a firmware keeps across frames, over all of the above.
pub mod renderer;

// Beside the pipeline.
pub mod hash;
pub mod wire;

/// The `embedded-graphics-core` crate, whose `DrawTarget` tiles flush to.
pub use embedded_graphics_core;
pub use error::Error;
/// The `fixed` crate, whose types the API uses ([`numeric`]).
pub use fixed;

/// Everything a firmware author needs, in one import.
pub mod prelude {
    pub use crate::area::AreaAa;
    pub use crate::bin::Bins;
    pub use crate::command::{Blend, Command, Cull, QuadVertex, SpanCmd, State, Vertex};
    pub use crate::config::{
        groups, AllCommands, CommandSet, MeshPlanes, Planes, Ssd1306Config, St7789Config,
        TileConfig, Triangles,
    };
    pub use crate::coverage::NoAa;
    pub use crate::error::{Error, FlushError};
    pub use crate::format::{
        BinaryFormat, Gray8Format, Half, PixelFormat, Rgb, Rgb444, Rgb444Format, Rgb444PairFormat,
        Rgb565Format, Rgb888Format,
    };
    pub use crate::fragment::dither::{
        Bayer, Bayer2, Bayer4, Bayer8, Dither, NoDither, RuntimeDither,
    };
    pub use crate::fragment::{
        AlphaBlending, BlendMode, Depth16, Depth24, Depth32, DepthMode, GouraudShading, NoBlending,
        NoDepth, NoWid, QuadraticShading, ShadingMode, Switchable, Wid8, WidMode,
    };
    pub use crate::frame::{Clear, CommandSource, Damage, Frame, FrameStats, Phase, WithTextures};
    pub use crate::geom::Rect;
    pub use crate::list::DisplayList;
    pub use crate::numeric::{
        Bits, ColorFix, ColorStep, Coord, FullPrecision, PlaneContract, Precision, ZFix, ZStep,
    };
    pub use crate::raster::line::{LineCmd, LineStyle};
    pub use crate::renderer::Renderer;
    pub use crate::texture::{
        AffineTexturing, ExactTexturing, Filter, NoTexturing, QuadraticTexturing, TexFormat,
        TexVertex, Texture, TextureMode, Wrap,
    };
    pub use crate::tile::Tile;
}
