//! The renderer object: what a firmware author builds once and keeps across
//! frames. It owns the tile, the bins and the partial-update state, is built
//! from the panel size, and renders a display list, a mesh scene
//! ([`geometry::Scene`](crate::geometry::Scene)) or anything else that is a
//! [`CommandSource`] — flushing each finished tile to an `embedded-graphics`
//! `DrawTarget` or to a closure (a DMA transfer, a hash, a PNG).
//!
//! It is a thin layer over [`Frame`], [`Tile`], [`Bins`] and [`Damage`],
//! which stay public for programs that want to own each piece (two tiles
//! for a DMA ping-pong, bins shared between two screens).
//!
//! **The tile size is named once**, as the tile's capacity `N` in groups of
//! 8 pixels ([`groups`](crate::config::groups)); the renderer cuts the screen
//! into the widest tiles that fit it — whole rows, as many as fit (a
//! multiple of 8 for a 1-bit panel's pages) — or into the shape
//! [`Renderer::with_tile`] asks for, checked against `N`.
//!
//! **Capacities have defaults** (256 bin entries in bands of up to 32
//! tiles, 2.5 KB; partial-update hashes for 64 tiles, 320 bytes); bins too
//! small for a frame cost passes, never pixels or an error
//! ([`crate::bin`]), and tiles beyond the damage capacity are always sent.
//! `FrameStats::bin_passes` tells whether larger bins would pay: see
//! `docs/sizing.md`.
//!
//! ```
//! use tilerast::prelude::*;
//! # use embedded_graphics_core::{pixelcolor::Rgb565, prelude::*};
//! # struct Panel;
//! # impl OriginDimensions for Panel { fn size(&self) -> Size { Size::new(240, 240) } }
//! # impl DrawTarget for Panel {
//! #     type Color = Rgb565; type Error = core::convert::Infallible;
//! #     fn draw_iter<I: IntoIterator<Item = Pixel<Rgb565>>>(&mut self, _: I) -> Result<(), Self::Error> { Ok(()) }
//! # }
//! # let mut display = Panel;
//! // 240x240 RGB565 + 16-bit Z + 4x4 dither, in 2,400-pixel tiles (9.6 KB).
//! let mut renderer: Renderer<St7789Config, { groups(60, 40) }> = Renderer::new(240, 240)?;
//! assert_eq!(renderer.frame().tile_size(), (240, 10)); // whole rows
//! let mut list: DisplayList<4> = DisplayList::new();
//! list.push(Command::fill(Rect::new(0, 0, 240, 240), Rgb::new(0, 0, 64)))?;
//! list.push(Command::triangle([
//!     Vertex::px(20, 20, 0, Rgb::new(255, 0, 0)),
//!     Vertex::px(220, 60, 0, Rgb::new(0, 255, 0)),
//!     Vertex::px(90, 220, 0, Rgb::new(0, 0, 255)),
//! ]))?;
//! let stats = renderer.draw(&list, &mut display)?;
//! assert_eq!(stats.tiles, 24);
//! # Ok::<(), FlushError<core::convert::Infallible>>(())
//! ```

use crate::bin::Bins;
use crate::config::TileConfig;
use crate::error::{Error, FlushError};
use crate::format::PixelFormat;
use crate::frame::{Clear, CommandSource, Damage, Frame, FrameStats};
use crate::tile::Tile;
use embedded_graphics_core::draw_target::DrawTarget;

/// A frame renderer that owns its tile, bins and partial-update state: `C`
/// the tile's planes, `N` its capacity in groups of 8 pixels, `CAP` and
/// `TB` the bins' entries and tiles per band, `TILES` the tiles whose
/// output partial updates remember. See the [module](self) for an example.
pub struct Renderer<
    C: TileConfig,
    const N: usize,
    const CAP: usize = 256,
    const TB: usize = 32,
    const TILES: usize = 64,
> {
    frame: Frame,
    tile: Tile<N, C>,
    bins: Bins<CAP, TB>,
    damage: Damage<TILES>,
    partial: bool,
}

impl<C: TileConfig, const N: usize, const CAP: usize, const TB: usize, const TILES: usize>
    core::fmt::Debug for Renderer<C, N, CAP, TB, TILES>
{
    /// The frame and capacities, not the planes' kilobytes.
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("Renderer")
            .field("frame", &self.frame)
            .field("tile_pixels", &(8 * N))
            .field("bin_entries", &CAP)
            .field("bin_tiles", &TB)
            .field("damage_tiles", &TILES)
            .field("partial", &self.partial)
            .finish()
    }
}

impl<C: TileConfig, const N: usize, const CAP: usize, const TB: usize, const TILES: usize>
    Renderer<C, N, CAP, TB, TILES>
{
    /// A renderer for a `width x height` panel in the widest tiles of at
    /// most `8 N` pixels: whole rows, as many as fit (rounded down to a
    /// multiple of 8 for a 1-bit format, whose panels take pages of 8
    /// rows), or, for a panel wider than the tile, one row of `8 N` pixels.
    ///
    /// ```
    /// use tilerast::prelude::*;
    /// let oled: Renderer<Ssd1306Config, { groups(128, 8) }> = Renderer::new(128, 64)?;
    /// assert_eq!(oled.frame().tile_size(), (128, 8));
    /// assert_eq!(Renderer::<Ssd1306Config, 4>::new(128, 64).unwrap_err(), Error::TileTooLarge);
    /// # Ok::<(), Error>(())
    /// ```
    pub fn new(width: u16, height: u16) -> Result<Self, Error> {
        let cap = 8 * N;
        let (w, h) = (width as usize, height as usize);
        let page = if <C::Format as PixelFormat>::MASK_ALL.count_ones() == 1 {
            8
        } else {
            1
        };
        let (tw, th) = if w == 0 || h == 0 {
            (w, h)
        } else if w <= cap {
            let rows = (cap / w).min(h);
            let rows = if rows >= page && rows < h {
                rows - rows % page
            } else {
                rows
            };
            (w, rows)
        } else {
            (cap, 1)
        };
        if tw == 0 || th == 0 {
            return Err(if w == 0 || h == 0 {
                Error::BadSize
            } else {
                Error::TileTooLarge
            });
        }
        if page == 8 && th % 8 != 0 && th < h {
            return Err(Error::TileTooLarge);
        }
        Self::with_tile(width, height, tw as u16, th as u16)
    }

    /// A renderer for a `width x height` panel in `tile_w x tile_h` tiles
    /// (edge tiles cropped); [`Error::TileTooLarge`] when a tile holds
    /// more than `8 N` pixels, [`Error::BadSize`] for a zero or too large
    /// side.
    ///
    /// ```
    /// use tilerast::prelude::*;
    /// let r: Renderer<St7789Config, { groups(64, 32) }> = Renderer::with_tile(240, 240, 64, 32)?;
    /// assert_eq!(r.frame().tiles().count(), 32);
    /// assert!(Renderer::<St7789Config, { groups(64, 32) }>::with_tile(240, 240, 64, 33).is_err());
    /// # Ok::<(), Error>(())
    /// ```
    pub fn with_tile(width: u16, height: u16, tile_w: u16, tile_h: u16) -> Result<Self, Error> {
        let frame = Frame::new(width, height, tile_w, tile_h)?;
        if tile_w as usize * tile_h as usize > 8 * N {
            return Err(Error::TileTooLarge);
        }
        Ok(Renderer {
            frame,
            tile: Tile::new(),
            bins: Bins::new(),
            damage: Damage::new(),
            partial: false,
        })
    }

    /// The same renderer with `clear` as every tile's starting values
    /// (background colour, depth, window ID).
    ///
    /// ```
    /// use tilerast::prelude::*;
    /// let r: Renderer<St7789Config, 300> = Renderer::new(240, 240)?
    ///     .with_clear(Clear { color: Rgb::new(8, 8, 16), ..Clear::default() });
    /// assert_eq!(r.frame().clear.color, Rgb::new(8, 8, 16));
    /// # Ok::<(), Error>(())
    /// ```
    pub fn with_clear(mut self, clear: Clear) -> Self {
        self.frame.clear = clear;
        self
    }

    /// The same renderer with partial updates on or off: with them, a tile
    /// whose input (its binned commands, place and clear values) has not
    /// changed since the last frame is neither drawn nor flushed — the
    /// panel's memory still shows it ([`Frame::render_changed`]). Off by
    /// default. After changing a texture's texels or the panel's contents
    /// behind the renderer's back, call [`Renderer::invalidate`].
    ///
    /// ```
    /// use tilerast::prelude::*;
    /// let mut r: Renderer<Rgb565Format, { groups(16, 16) }> =
    ///     Renderer::with_tile(64, 32, 16, 16)?.with_partial_updates(true);
    /// let mut sent = |r: &mut Renderer<Rgb565Format, 32>, x: i32| {
    ///     let list = [Command::fill(Rect::new(x, 4, 4, 4), Rgb::new(255, 0, 0))];
    ///     let mut n = 0;
    ///     r.render(&list[..], |_| { n += 1; Ok::<(), ()>(()) }).map(|_| n)
    /// };
    /// assert_eq!(sent(&mut r, 0)?, 8); // the first frame sends every tile
    /// assert_eq!(sent(&mut r, 0)?, 0); // nothing changed, nothing sent
    /// assert_eq!(sent(&mut r, 20)?, 2); // the square moved to the next tile
    /// # Ok::<(), FlushError<()>>(())
    /// ```
    pub fn with_partial_updates(mut self, on: bool) -> Self {
        self.partial = on;
        self.damage.invalidate();
        self
    }

    /// The frame: screen, tile size, clear values and culling, which may
    /// be changed between frames ([`Renderer::frame_mut`]).
    pub fn frame(&self) -> &Frame {
        &self.frame
    }

    /// The frame, to change its clear values or culling between frames.
    pub fn frame_mut(&mut self) -> &mut Frame {
        &mut self.frame
    }

    /// The tile (its planes hold the last tile rendered).
    pub fn tile(&self) -> &Tile<N, C> {
        &self.tile
    }

    /// The tile, to set a value-chosen dither or plane
    /// ([`Tile::set_dither`]) before rendering.
    pub fn tile_mut(&mut self) -> &mut Tile<N, C> {
        &mut self.tile
    }

    /// Forgets what partial updates remember: the next frame sends every
    /// tile.
    pub fn invalidate(&mut self) {
        self.damage.invalidate();
    }

    /// Bytes the renderer holds: the tile's planes, the bins and the
    /// partial-update hashes.
    ///
    /// ```
    /// use tilerast::prelude::*;
    /// type Panel = Renderer<St7789Config, { groups(60, 40) }>;
    /// assert_eq!(Panel::BYTES, 9600 + 8 * 256 + 16 * 32 + 5 * 64);
    /// ```
    pub const BYTES: usize = Tile::<N, C>::plane_bytes() + Bins::<CAP, TB>::BYTES + 5 * TILES;

    /// Renders `scene` tile by tile, handing each finished tile to `flush`
    /// (which sends it: a DMA transfer of
    /// [`Tile::panel_bytes`], a [`Tile::flush`] to a `DrawTarget`, a
    /// hash...). With partial updates, unchanged tiles are skipped.
    /// Errors: the core's ([`FlushError::Raster`], e.g. a command kind the
    /// configuration leaves out) or `flush`'s ([`FlushError::Target`]).
    pub fn render<S, E>(
        &mut self,
        scene: &S,
        flush: impl FnMut(&mut Tile<N, C>) -> Result<(), E>,
    ) -> Result<FrameStats, FlushError<E>>
    where
        S: CommandSource + ?Sized,
    {
        if self.partial {
            self.frame.render_changed(
                &mut self.tile,
                &mut self.bins,
                scene,
                &mut self.damage,
                flush,
            )
        } else {
            self.frame
                .render_binned(&mut self.tile, &mut self.bins, scene, flush)
        }
    }

    /// [`Renderer::render`] flushing each tile to an `embedded-graphics`
    /// `DrawTarget` (its colour type is the format's, or converts from it).
    pub fn draw<S, T>(
        &mut self,
        scene: &S,
        target: &mut T,
    ) -> Result<FrameStats, FlushError<T::Error>>
    where
        S: CommandSource + ?Sized,
        T: DrawTarget,
        T::Color: From<<C::Format as PixelFormat>::Color>,
    {
        self.render(scene, |t| t.flush(target))
    }
}
