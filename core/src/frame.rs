//! Frames, binning and flush (pipeline stages 3 and 9): a frame is cut into
//! tiles; each tile is cleared, replays the display-list commands whose
//! bounds touch it, and is flushed to the display. The result is
//! byte-identical to rendering the frame as one big tile.

use crate::bin::{Bins, Grid};
use crate::command::{Command, Cull};
use crate::config::TileConfig;
use crate::error::{Error, FlushError};
use crate::format::PixelFormat;
use crate::geom::Rect;
use crate::hash::WordHash;
use crate::list::DisplayList;
use crate::numeric::MAX_SIDE;
use crate::raster::coverage::AaMode;
use crate::tile::Tile;
pub use crate::tile::{Clear, Phase};
use core::hash::Hash;
use embedded_graphics_core::draw_target::DrawTarget;

/// What rendering a frame did.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct FrameStats {
    /// Tiles rendered.
    pub tiles: u32,
    /// Commands replayed, summed over tiles (binning skips the others).
    pub replayed: u32,
    /// Passes over the command list that binned commands (one per band of
    /// tiles; 1 when the whole frame fits the bins).
    pub bin_passes: u32,
    /// Most bin entries one band used.
    pub bin_peak: u32,
    /// Tiles that replayed the whole list unbinned (the bins were disabled,
    /// or too small for that tile alone).
    pub unbinned_tiles: u32,
    /// Tiles neither drawn nor handed on because their commands were those
    /// of the last frame ([`Frame::render_changed`]).
    pub unchanged_tiles: u32,
}

/// Where a frame's commands come from: a slice, a [`DisplayList`], or an
/// encoded list in flash ([`Encoded`](crate::wire::Encoded)).
///
/// A source names each command by a *key* (its index, counting each of an
/// encoded mesh's triangles as one): the binning pass ([`crate::bin`])
/// visits every command once with its key, and each tile then replays only
/// its own keys, read in place — no command is copied into the bins.
pub trait CommandSource {
    /// Calls `f(key, command)` with each command, in order, validating each
    /// (the first invalid command ends the walk with its error). Keys
    /// strictly increase.
    fn each_keyed(&self, f: impl FnMut(u32, &Command)) -> Result<(), Error>;
    /// Calls `f` with the commands of `keys` (increasing, each a key
    /// [`Self::each_keyed`] gave), in that order.
    fn replay(&self, keys: impl Iterator<Item = u32>, f: impl FnMut(&Command));
    /// Checks every command.
    fn validate(&self) -> Result<(), Error> {
        self.each_keyed(|_, _| {})
    }
    /// Calls `f` with each command, in order. Commands reaching `f` are
    /// valid.
    fn each(&self, mut f: impl FnMut(&Command)) -> Result<(), Error> {
        self.each_keyed(|_, c| f(c))
    }
    /// Draws the commands of `keys` (as [`Self::replay`] takes them) into
    /// `tile`, each as [`Tile::draw`] would; returns how many it drew. The
    /// frame calls it for each binned tile. The default replays each
    /// command; a source that can reach the tile more directly overrides
    /// it — the geometry stage's [`Scene`](crate::geometry::Scene) hands
    /// its mesh triangles over straight from the vertex cache.
    ///
    /// ```
    /// use tilerast::prelude::*;
    /// let list = [Command::fill(Rect::new(0, 0, 4, 4), Rgb::new(9, 9, 9)),
    ///             Command::fill(Rect::new(2, 2, 4, 4), Rgb::new(1, 2, 3))];
    /// let mut tile: Tile<8, Rgb888Format> = Tile::new();
    /// tile.begin(Rect::new(0, 0, 8, 8), &Clear::default())?;
    /// assert_eq!(list[..].draw_keys([1].into_iter(), &mut tile), 1);
    /// assert_eq!((tile.raw(0, 0), tile.raw(2, 2)), (Some(0), Some(0x010203)));
    /// # Ok::<(), Error>(())
    /// ```
    fn draw_keys<const N: usize, C: TileConfig>(
        &self,
        keys: impl Iterator<Item = u32>,
        tile: &mut Tile<N, C>,
    ) -> u32 {
        replay_commands(self, keys, tile)
    }
    /// The textures the source's textured triangles index
    /// ([`WithTextures`]); none by default.
    fn textures(&self) -> &[crate::texture::Texture<'_>] {
        &[]
    }
    /// What binning reads: calls `f(key, bounds)` with each command's key
    /// and the screen pixels it can touch, validating as
    /// [`Self::each_keyed`] does. `bounds` is [`Command::bounds`], or
    /// [`Command::coverage_bounds`] for every triangle when `cells` (coverage
    /// antialiasing) and for an edge-flagged one when `area` (area
    /// sampling); `None` for a triangle `cull` drops
    /// ([`Command::culled_by`]). The default decodes each command; a
    /// source that can find bounds cheaper overrides it — an
    /// [encoded](crate::wire::Encoded) mesh reads only its vertices'
    /// positions.
    ///
    /// ```
    /// use tilerast::prelude::*;
    /// let list = [Command::fill(Rect::new(2, 3, 4, 5), Rgb::new(1, 2, 3))];
    /// let mut seen = vec![];
    /// list[..].each_bounds(false, false, Cull::None, |key, b| seen.push((key, b)))?;
    /// assert_eq!(seen, [(0, Some(Rect::new(2, 3, 4, 5)))]);
    /// # Ok::<(), Error>(())
    /// ```
    fn each_bounds(
        &self,
        cells: bool,
        area: bool,
        cull: Cull,
        mut f: impl FnMut(u32, Option<Rect>),
    ) -> Result<(), Error> {
        self.each_keyed(|k, c| f(k, bin_bounds(c, cells, area, cull)))
    }
    /// [`Self::each_bounds`] for a band of tiles: a command whose pixels
    /// miss the pixel rows `rows` may be reported with `None` bounds, if
    /// that is cheaper than finding them (validation is unchanged). The
    /// default reports every command's bounds.
    ///
    /// ```
    /// use tilerast::prelude::*;
    /// let list = [Command::fill(Rect::new(2, 3, 4, 5), Rgb::new(1, 2, 3))];
    /// let mut seen = vec![];
    /// list[..].each_bounds_in(false, false, Cull::None, 0..3, |key, b| seen.push((key, b)))?;
    /// // A slice reports every command's bounds.
    /// assert_eq!(seen, [(0, Some(Rect::new(2, 3, 4, 5)))]);
    /// # Ok::<(), Error>(())
    /// ```
    fn each_bounds_in(
        &self,
        cells: bool,
        area: bool,
        cull: Cull,
        rows: core::ops::Range<i32>,
        f: impl FnMut(u32, Option<Rect>),
    ) -> Result<(), Error> {
        let _ = rows;
        self.each_bounds(cells, area, cull, f)
    }
}

/// The pixels `cmd` can touch in tiles with coverage antialiasing
/// (`cells`) or area sampling (`area`), or neither, in a frame that culls
/// `cull` ([`CommandSource::each_bounds`]).
#[inline(always)]
pub(crate) fn bin_bounds(cmd: &Command, cells: bool, area: bool, cull: Cull) -> Option<Rect> {
    if cull != Cull::None && cmd.culled_by(cull) {
        None
    } else if cells || area && cmd.edge_flagged() {
        cmd.coverage_bounds()
    } else {
        cmd.bounds()
    }
}

/// [`CommandSource::draw_keys`]' default: each key's command replayed
/// and drawn; how many were drawn.
#[inline(always)]
pub(crate) fn replay_commands<S: CommandSource + ?Sized, const N: usize, C: TileConfig>(
    src: &S,
    keys: impl Iterator<Item = u32>,
    tile: &mut Tile<N, C>,
) -> u32 {
    let mut n = 0;
    src.replay(keys, |cmd| {
        tile.draw_valid(cmd, src.textures());
        n += 1;
    });
    n
}

impl CommandSource for [Command] {
    fn each_keyed(&self, mut f: impl FnMut(u32, &Command)) -> Result<(), Error> {
        self.iter().zip(0..).try_for_each(|(c, k)| {
            c.validate()?;
            f(k, c);
            Ok(())
        })
    }
    fn replay(&self, keys: impl Iterator<Item = u32>, f: impl FnMut(&Command)) {
        keys.filter_map(|k| self.get(k as usize)).for_each(f)
    }
}

impl<const CAP: usize> CommandSource for DisplayList<CAP> {
    fn each_keyed(&self, mut f: impl FnMut(u32, &Command)) -> Result<(), Error> {
        // Validated by `push`.
        self.iter().zip(0..).for_each(|(c, k)| f(k, c));
        Ok(())
    }
    fn replay(&self, keys: impl Iterator<Item = u32>, f: impl FnMut(&Command)) {
        keys.filter_map(|k| self.get(k as usize)).for_each(f)
    }
}

/// A screen cut into tiles.
///
/// ```
/// use tilerast::prelude::*;
/// let f = Frame::new(100, 50, 64, 32)?;
/// let tiles: Vec<Rect> = f.tiles().collect();
/// assert_eq!(tiles, [Rect::new(0, 0, 64, 32), Rect::new(64, 0, 36, 32),
///                    Rect::new(0, 32, 64, 18), Rect::new(64, 32, 36, 18)]);
/// # Ok::<(), Error>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Frame {
    width: u16,
    height: u16,
    tile_w: u16,
    tile_h: u16,
    /// Values each tile is cleared to.
    pub clear: Clear,
    /// Triangles the frame drops by their winding on screen ([`Cull`];
    /// default [`Cull::None`]): binning reads each triangle's positions and
    /// drops those facing away, so they cost no setup, traversal or
    /// fragment in any tile — a closed mesh projected offline draws about
    /// half its triangles. For lists whose every triangle is a face of a
    /// mesh; the geometry stage culls its own draws
    /// ([`DrawOptions::cull`](crate::geometry::DrawOptions::cull)).
    pub cull: Cull,
}

impl Frame {
    /// A `width x height` screen in tiles of `tile_w x tile_h` (edge tiles
    /// are cropped). Sides must be in `1..=MAX_SIDE`.
    pub fn new(width: u16, height: u16, tile_w: u16, tile_h: u16) -> Result<Self, Error> {
        let ok = |s: u16| (1..=MAX_SIDE).contains(&s);
        if [width, height, tile_w, tile_h].into_iter().all(ok) {
            Ok(Frame {
                width,
                height,
                tile_w,
                tile_h,
                clear: Clear::default(),
                cull: Cull::None,
            })
        } else {
            Err(Error::BadSize)
        }
    }

    /// The screen rectangle.
    pub fn screen(&self) -> Rect {
        Rect::new(0, 0, self.width as u32, self.height as u32)
    }

    /// Tile size.
    pub fn tile_size(&self) -> (u16, u16) {
        (self.tile_w, self.tile_h)
    }

    /// Tile rectangles in row-major order.
    pub fn tiles(&self) -> impl Iterator<Item = Rect> + '_ {
        let (tw, th) = (self.tile_w as u32, self.tile_h as u32);
        (0..self.height as u32)
            .step_by(th as usize)
            .flat_map(move |y| {
                (0..self.width as u32).step_by(tw as usize).map(move |x| {
                    Rect::new(
                        x as i32,
                        y as i32,
                        tw.min(self.width as u32 - x),
                        th.min(self.height as u32 - y),
                    )
                })
            })
    }

    /// The tile grid.
    fn grid(&self) -> Grid {
        let (tw, th) = (self.tile_w as u32, self.tile_h as u32);
        Grid {
            w: self.width as u32,
            h: self.height as u32,
            tw,
            th,
            cols: (self.width as u32).div_ceil(tw),
            rows: (self.height as u32).div_ceil(th),
        }
    }

    /// The rectangle of tile `t` (row-major index).
    fn tile_rect(&self, g: &Grid, t: u32) -> Rect {
        let (x, y) = ((t % g.cols) * g.tw, (t / g.cols) * g.th);
        Rect::new(x as i32, y as i32, g.tw.min(g.w - x), g.th.min(g.h - y))
    }

    /// Renders every tile and hands each finished tile to `done` (an
    /// overlay drawn with `embedded-graphics`, then a flush, a hash, a copy
    /// into a PNG...), without bins: each tile walks the whole list
    /// ([`Frame::render_binned`] with `Bins<0, 0>`).
    pub fn render_with<const N: usize, C: TileConfig, S, E>(
        &self,
        tile: &mut Tile<N, C>,
        cmds: &S,
        done: impl FnMut(&mut Tile<N, C>) -> Result<(), E>,
    ) -> Result<FrameStats, FlushError<E>>
    where
        S: CommandSource + ?Sized,
    {
        self.render_binned(tile, &mut Bins::<0, 0>::new(), cmds, done)
    }

    /// Renders every tile and hands each finished tile to `done`, binning
    /// the commands first ([`crate::bin`]): each tile replays only the
    /// commands whose bounds touch it. Commands are validated once, by the
    /// first binning pass, before any tile is drawn. Bins too small for the
    /// frame split it into bands (more passes), never into an error; the
    /// output is the same whatever the bins.
    ///
    /// ```
    /// use tilerast::prelude::*;
    /// use tilerast::bin::Bins;
    /// type T = Tile<{ groups(16, 16) }, Rgb565Format>;
    /// let frame = T::frame::<16, 16>(64, 32)?; // 8 tiles
    /// let list = [Command::fill(Rect::new(0, 0, 20, 20), Rgb::new(9, 9, 9)),
    ///             Command::fill(Rect::new(40, 20, 4, 4), Rgb::new(1, 2, 3))];
    /// let mut tile = T::new();
    /// let mut bins: Bins<64, 8> = Bins::new();
    /// let stats = frame.render_binned(&mut tile, &mut bins, &list[..], |_| Ok::<(), ()>(()))
    ///     .map_err(|_| Error::BadSize)?;
    /// assert_eq!((stats.tiles, stats.replayed, stats.bin_passes), (8, 5, 1));
    /// # Ok::<(), Error>(())
    /// ```
    pub fn render_binned<const N: usize, C: TileConfig, S, E, const CAP: usize, const TB: usize>(
        &self,
        tile: &mut Tile<N, C>,
        bins: &mut Bins<CAP, TB>,
        cmds: &S,
        done: impl FnMut(&mut Tile<N, C>) -> Result<(), E>,
    ) -> Result<FrameStats, FlushError<E>>
    where
        S: CommandSource + ?Sized,
    {
        self.render_upto::<{ Phase::ALL }, false, _, _, _, _, _, _>(
            Phase::All,
            tile,
            bins,
            cmds,
            done,
            never,
        )
    }

    /// [`Frame::render_binned`] that draws and hands to `done` only the
    /// tiles whose input changed since the last frame rendered with
    /// `damage`: partial updates decided *before* drawing, as LVGL's
    /// invalidated areas are. Each tile first hashes its binned commands
    /// (read in place, hashed whole: a moved vertex, a new colour, a
    /// command that left or entered the tile all count), its place and the
    /// frame's [`Clear`]; when that equals the tile's hash from the last
    /// frame, the tile is skipped — the panel, whose memory is the front
    /// buffer, still shows it. [`FrameStats::unchanged_tiles`] counts the
    /// skipped tiles.
    ///
    /// A texture's texels are not hashed (only which texture a command
    /// names): after changing a texture's pixels, call
    /// [`Damage::invalidate`]. Hashes are 32 bits: a changed tile whose
    /// hash collides (odds 2^-32) keeps its old pixels until it changes
    /// again. Tiles beyond `TILES` are always drawn. A `Damage` used here
    /// holds input hashes: do not also pass it to [`Damage::changed`], which
    /// hashes output.
    ///
    /// ```
    /// use tilerast::prelude::*;
    /// use tilerast::bin::Bins;
    /// type T = Tile<{ groups(16, 16) }, Rgb565Format>;
    /// let frame = T::frame::<16, 16>(64, 32)?; // 8 tiles
    /// let (mut tile, mut bins) = (T::new(), Bins::<64, 8>::new());
    /// let mut damage = Damage::<8>::new();
    /// let mut draw = |x: i32| {
    ///     let list = [Command::fill(Rect::new(x, 4, 4, 4), Rgb::new(255, 0, 0))];
    ///     let mut sent = 0;
    ///     frame.render_changed(&mut tile, &mut bins, &list[..], &mut damage, |_| {
    ///         sent += 1;
    ///         Ok::<(), ()>(())
    ///     }).map(|_| sent).map_err(|_| Error::BadSize)
    /// };
    /// assert_eq!(draw(0)?, 8); // first frame: every tile
    /// assert_eq!(draw(0)?, 0); // nothing changed: nothing drawn or sent
    /// assert_eq!(draw(20)?, 2); // the fill left tile 0 for tile 1
    /// # Ok::<(), Error>(())
    /// ```
    pub fn render_changed<
        const N: usize,
        C: TileConfig,
        S,
        E,
        const CAP: usize,
        const TB: usize,
        const TILES: usize,
    >(
        &self,
        tile: &mut Tile<N, C>,
        bins: &mut Bins<CAP, TB>,
        cmds: &S,
        damage: &mut Damage<TILES>,
        done: impl FnMut(&mut Tile<N, C>) -> Result<(), E>,
    ) -> Result<FrameStats, FlushError<E>>
    where
        S: CommandSource + ?Sized,
    {
        self.render_upto::<{ Phase::ALL }, true, N, C, S, E, CAP, TB>(
            Phase::All,
            tile,
            bins,
            cmds,
            done,
            |t, h| damage.same(t as usize, h),
        )
    }

    /// [`Frame::render_binned`] stopped after `phase` ([`Phase`]): for
    /// measuring where a frame's time goes. Tiles are handed to `done`
    /// only with [`Phase::All`]; before it nothing is drawn.
    ///
    /// ```
    /// use tilerast::prelude::*;
    /// type T = Tile<{ groups(16, 16) }, Rgb565Format>;
    /// let frame = T::frame::<16, 16>(32, 32)?;
    /// let list = [Command::fill(Rect::new(0, 0, 20, 20), Rgb::new(9, 9, 9))];
    /// let (mut tile, mut bins) = (T::new(), Bins::<16, 4>::new());
    /// let mut flushed = 0;
    /// for phase in [Phase::Bin, Phase::Clear, Phase::Setup, Phase::All] {
    ///     frame.render_until(phase, &mut tile, &mut bins, &list[..], |_| { flushed += 1; Ok::<(), ()>(()) })
    ///         .map_err(|_| Error::BadSize)?;
    /// }
    /// assert_eq!(flushed, 4); // only the last run flushed its 4 tiles
    /// # Ok::<(), Error>(())
    /// ```
    pub fn render_until<const N: usize, C: TileConfig, S, E, const CAP: usize, const TB: usize>(
        &self,
        phase: Phase,
        tile: &mut Tile<N, C>,
        bins: &mut Bins<CAP, TB>,
        cmds: &S,
        done: impl FnMut(&mut Tile<N, C>) -> Result<(), E>,
    ) -> Result<FrameStats, FlushError<E>>
    where
        S: CommandSource + ?Sized,
    {
        match phase {
            // One instantiation for the phases that draw nothing (flash is
            // scarce on the micro:bit), one for each that draws part.
            Phase::Bin | Phase::Clear | Phase::Decode => {
                self.render_upto::<2, false, _, _, _, _, _, _>(phase, tile, bins, cmds, done, never)
            }
            Phase::Setup => {
                self.render_upto::<3, false, _, _, _, _, _, _>(phase, tile, bins, cmds, done, never)
            }
            Phase::Traverse => {
                self.render_upto::<4, false, _, _, _, _, _, _>(phase, tile, bins, cmds, done, never)
            }
            Phase::All => self.render_binned(tile, bins, cmds, done),
        }
    }

    /// The frame pipeline up to `phase`; with `HASH`, each tile first
    /// hashes its input and is skipped when `same(tile, hash)`.
    #[allow(clippy::too_many_arguments)]
    fn render_upto<
        const UPTO: u8,
        const HASH: bool,
        const N: usize,
        C: TileConfig,
        S,
        E,
        const CAP: usize,
        const TB: usize,
    >(
        &self,
        phase: Phase,
        tile: &mut Tile<N, C>,
        bins: &mut Bins<CAP, TB>,
        cmds: &S,
        mut done: impl FnMut(&mut Tile<N, C>) -> Result<(), E>,
        mut same: impl FnMut(u32, u32) -> bool,
    ) -> Result<FrameStats, FlushError<E>>
    where
        S: CommandSource + ?Sized,
    {
        let g = self.grid();
        let count = g.cols * g.rows;
        let mut stats = FrameStats::default();
        let aa = <C::Aa as AaMode>::SAMPLES > 0;
        let area = <C::Aa as AaMode>::AREA;
        let cull = self.cull;
        let bounds = |cmd: &Command| bin_bounds(cmd, aa, area, cull);
        let enabled = Bins::<CAP, TB>::enabled();
        if !enabled {
            cmds.validate()?;
        }
        // The window of tiles an overflowing pass counted: (first, len).
        let mut plan: Option<(u32, u32)> = None;
        let mut t0 = 0;
        while t0 < count {
            let planned = plan.filter(|&(base, len)| t0 < base + len);
            let band = match planned {
                Some((base, len)) => {
                    bins.plan_fit((t0 - base) as usize, (base + len - t0) as usize) as u32
                }
                None => (TB as u32).min(count - t0),
            };
            let t1 = t0 + band;
            let mut binned = false;
            if enabled && band > 0 {
                match planned {
                    Some((base, _)) => bins.reset_flat((t0 - base) as usize, band as usize),
                    None => bins.reset(band as usize),
                }
                // The tile rows this band meets: a command's rows outside
                // them are not walked (the micro:bit bins in several
                // bands, and most commands miss most of them).
                let band_rows = (t0 / g.cols, (t1 - 1) / g.cols);
                let pass = BinPass {
                    cull: self.cull,
                    cells: aa,
                    area,
                    spans: g.spans(),
                    cols: g.cols,
                    th: g.th,
                    band_rows,
                    tiles: (t0, t1),
                };
                pass.run(cmds, |t, k| bins.push(t, k))?;
                let full = bins.full();
                stats.bin_passes += 1;
                stats.bin_peak = stats.bin_peak.max(bins.len() as u32);
                if !full {
                    binned = true;
                } else if planned.is_none() {
                    // Cut this window into bands that fit, from its counts;
                    // a tile that alone overflows replays the whole list.
                    bins.keep_plan(band as usize);
                    plan = Some((t0, band));
                    continue;
                }
            }
            let last = if binned { t1 } else { t0 + 1 };
            for t in t0..last {
                if phase == Phase::Bin {
                    break;
                }
                let area = self.tile_rect(&g, t);
                let slot = binned.then_some((t - t0) as usize);
                if HASH {
                    let mut h = WordHash::new();
                    (area, self.clear.color, self.clear.depth, self.clear.wid).hash(&mut h);
                    tile_commands(cmds, bins, slot, &area, bounds, |cmd| cmd.hash(&mut h));
                    if same(t, h.value()) {
                        stats.unchanged_tiles += 1;
                        continue;
                    }
                }
                tile.begin(area, &self.clear)?;
                if phase == Phase::Clear {
                    continue;
                }
                let mut replay = |tile: &mut Tile<N, C>| {
                    if let (Some(slot), true) = (slot, UPTO == Phase::ALL) {
                        stats.replayed += cmds.draw_keys(bins.keys(slot), tile);
                        return;
                    }
                    let draw = |cmd: &Command| {
                        if UPTO == Phase::Decode as u8 {
                            core::hint::black_box(cmd);
                        } else if UPTO == Phase::ALL {
                            // One out-of-line call per command: inlined
                            // here, the whole pipeline in one function
                            // spilled more than the call costs (measured).
                            tile.draw_valid(cmd, cmds.textures());
                        } else {
                            tile.draw_upto::<UPTO>(cmd);
                        }
                        stats.replayed += 1;
                    };
                    tile_commands(cmds, bins, slot, &area, bounds, draw);
                };
                replay(tile);
                if UPTO < Phase::ALL {
                    continue;
                }
                // With coverage antialiasing: resolve, then spans and lines
                // over the resolved pixels.
                if tile.finish() {
                    replay(tile);
                }
                // A command kind the tile's `CommandSet` leaves out.
                if core::mem::take(&mut tile.refused) {
                    return Err(FlushError::Raster(Error::ConfigMismatch));
                }
                done(tile).map_err(FlushError::Target)?;
                stats.tiles += 1;
            }
            if !binned {
                stats.unbinned_tiles += 1;
            }
            t0 = last;
        }
        Ok(stats)
    }

    /// Renders every tile and flushes it to `target`.
    pub fn render<const N: usize, C: TileConfig, S, T>(
        &self,
        tile: &mut Tile<N, C>,
        cmds: &S,
        target: &mut T,
    ) -> Result<FrameStats, FlushError<T::Error>>
    where
        S: CommandSource + ?Sized,
        T: DrawTarget,
        T::Color: From<<C::Format as PixelFormat>::Color>,
    {
        self.render_with(tile, cmds, |t| t.flush(target))
    }
}

/// No tile is the same as last frame's: every tile is drawn
/// ([`Frame::render_upto`] without `HASH`).
fn never(_: u32, _: u32) -> bool {
    false
}

/// Calls `f` with each command of the tile at `area`: its keys in bins
/// slot `slot` replayed, or without bins (`None`) every command whose
/// bounds meet it.
#[inline(always)]
fn tile_commands<S, const CAP: usize, const TB: usize>(
    cmds: &S,
    bins: &Bins<CAP, TB>,
    slot: Option<usize>,
    area: &Rect,
    bounds: impl Fn(&Command) -> Option<Rect>,
    mut f: impl FnMut(&Command),
) where
    S: CommandSource + ?Sized,
{
    match slot {
        Some(slot) => cmds.replay(bins.keys(slot), f),
        None => {
            // Validated already: no error can come back.
            let _ = cmds.each(|cmd| {
                if bounds(cmd).and_then(|b| b.intersect(area)).is_some() {
                    f(cmd);
                }
            });
        }
    }
}

/// One binning pass over a band of tiles: which tiles each command's
/// bounds meet, pushed into the bins by `push`.
struct BinPass {
    cells: bool,
    area: bool,
    cull: Cull,
    spans: crate::bin::GridSpans,
    cols: u32,
    th: u32,
    /// The band's first and last tile rows.
    band_rows: (u32, u32),
    /// The band's tiles, `[t0, t1)`.
    tiles: (u32, u32),
}

impl BinPass {
    /// Walks `cmds` once; `push(tile - t0, key)` for every tile of the
    /// band a command meets.
    fn run<S: CommandSource + ?Sized>(
        &self,
        cmds: &S,
        mut push: impl FnMut(usize, u32),
    ) -> Result<(), Error> {
        let (band_y0, band_y1) = self.band_rows;
        let (t0, t1) = self.tiles;
        let rows = (band_y0 * self.th) as i32..((band_y1 + 1) * self.th) as i32;
        // Inlined into the source's walk: out of line, each call copied the
        // closure's state and the bounds through memory (the M4 teapot's
        // binning: 148 instructions a triangle in the call, measured).
        cmds.each_bounds_in(
            self.cells,
            self.area,
            self.cull,
            rows,
            #[inline(always)]
            |key, b| {
                let Some((x0, x1, y0, y1)) = b.and_then(|b| self.spans.span(&b)) else {
                    return;
                };
                if x0 == x1 && y0 == y1 {
                    // One tile, no row or column loop: most of a mesh's
                    // triangles (the M4 teapot's: 97%).
                    let t = y0 * self.cols + x0;
                    if (band_y0..=band_y1).contains(&y0) && (t0..t1).contains(&t) {
                        push((t - t0) as usize, key);
                    }
                    return;
                }
                // Exclusive ranges: an inclusive one keeps an exhausted flag
                // (the M4 teapot's binning: 45,000 instructions more, measured).
                for ty in y0.max(band_y0)..y1.min(band_y1) + 1 {
                    let row = ty * self.cols;
                    let lo = (row + x0).max(t0);
                    let hi = (row + x1 + 1).min(t1);
                    for t in lo..hi {
                        push((t - t0) as usize, key);
                    }
                }
            },
        )
    }
}

/// Partial updates: remembers a hash of every tile last sent to the display,
/// so a frame flushes only the tiles whose pixels changed — what LVGL's
/// invalidated areas achieve, found from the output itself, so no command
/// has to be tracked. An animation that moves a needle resends a few tiles
/// instead of the screen (`reports/targets.md` measures the bytes).
///
/// The hash ([`Tile::content_hash`]) is 32 bits: a changed tile whose hash
/// collides (odds 2^-32 per changed tile) keeps its old pixels until it
/// changes again; [`Damage::invalidate`] forces a full refresh (after a
/// display reset, or every few seconds for certainty). `TILES` hashes cost
/// `5 TILES` bytes; tiles beyond `TILES` are always sent.
///
/// ```
/// use tilerast::prelude::*;
/// type T = Tile<{ groups(16, 16) }, Rgb565Format>;
/// let frame = T::frame::<16, 16>(32, 16)?; // two tiles
/// let (mut tile, mut damage) = (T::new(), Damage::<2>::new());
/// let mut sent = |x: i32, damage: &mut Damage<2>| {
///     let list = [Command::fill(Rect::new(x, 0, 4, 4), Rgb::new(255, 0, 0))];
///     let mut n = 0;
///     frame.render_with(&mut tile, &list[..], |t| {
///         n += damage.changed(&frame, t) as u32;
///         Ok::<(), ()>(())
///     }).map(|_| n).map_err(|_| Error::BadSize)
/// };
/// assert_eq!(sent(0, &mut damage)?, 2); // first frame: everything
/// assert_eq!(sent(0, &mut damage)?, 0); // nothing moved
/// assert_eq!(sent(20, &mut damage)?, 2); // left tile cleared, right one drawn
/// assert_eq!(sent(24, &mut damage)?, 1); // moved within the right tile
/// # Ok::<(), Error>(())
/// ```
#[derive(Debug, Clone)]
pub struct Damage<const TILES: usize> {
    hash: [u32; TILES],
    known: [bool; TILES],
}

impl<const TILES: usize> Default for Damage<TILES> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const TILES: usize> Damage<TILES> {
    /// Nothing sent yet: every tile counts as changed.
    pub const fn new() -> Self {
        Damage {
            hash: [0; TILES],
            known: [false; TILES],
        }
    }

    /// Forgets what was sent: the next frame sends every tile.
    pub fn invalidate(&mut self) {
        self.known = [false; TILES];
    }

    /// Whether tile `t`'s hash `h` equals the one remembered for it; `h`
    /// is remembered either way. A tile beyond `TILES` is never the same.
    fn same(&mut self, t: usize, h: u32) -> bool {
        match (self.hash.get_mut(t), self.known.get_mut(t)) {
            (Some(old), Some(known)) => {
                let same = *known && *old == h;
                *old = h;
                *known = true;
                same
            }
            _ => false,
        }
    }

    /// Whether `tile` (a finished tile of `frame`) differs from what was
    /// last sent for its place — then it is remembered as sent, so call it
    /// once per tile, and flush the tile when it returns `true`.
    pub fn changed<const N: usize, C: TileConfig>(
        &mut self,
        frame: &Frame,
        tile: &Tile<N, C>,
    ) -> bool {
        let a = tile.area();
        let g = frame.grid();
        let t = (a.y.max(0) as u32 / g.th) * g.cols + a.x.max(0) as u32 / g.tw;
        !self.same(t as usize, tile.content_hash())
    }
}

/// A frame derived from the tile type, so the two cannot disagree.
impl<const N: usize, C: TileConfig> Tile<N, C> {
    /// A frame for a `width x height` screen in tiles of `TW x TH` pixels
    /// that this tile type holds: a tile size larger than the type's
    /// capacity does not compile (the screen size is checked at run time,
    /// as [`Frame::new`] does).
    ///
    /// ```
    /// use tilerast::prelude::*;
    /// type PanelTile = Tile<{ groups(60, 40) }, St7789Config>;
    /// let frame = PanelTile::frame::<60, 40>(240, 240)?;
    /// assert_eq!(frame.tile_size(), (60, 40));
    /// # Ok::<(), Error>(())
    /// ```
    ///
    /// ```compile_fail
    /// use tilerast::prelude::*;
    /// type PanelTile = Tile<{ groups(60, 40) }, St7789Config>;
    /// let frame = PanelTile::frame::<64, 40>(240, 240); // 2560 > 2400 pixels
    /// ```
    pub fn frame<const TW: u16, const TH: u16>(width: u16, height: u16) -> Result<Frame, Error> {
        const {
            assert!(
                TW as usize * TH as usize <= 8 * N,
                "the frame's tiles hold more pixels than the tile type"
            )
        };
        Frame::new(width, height, TW, TH)
    }
}

/// A frame, its tile and its commands as one `embedded-graphics`
/// [`Drawable`](embedded_graphics_core::Drawable): drawing it renders every
/// tile and flushes it to the target, so a display list composes with the
/// ecosystem's drawing code (`.draw(&mut display)`), and the tile's colour
/// type is the target's.
///
/// `Drawable::draw` can only fail with the target's error, so the raster
/// core's own error comes back in the output: `Ok(Ok(stats))` when the
/// frame was drawn, `Ok(Err(e))` when the core refused a command or size.
///
/// ```
/// use tilerast::prelude::*;
/// use embedded_graphics_core::{pixelcolor::Rgb565, prelude::*};
/// # struct Screen;
/// # impl OriginDimensions for Screen { fn size(&self) -> Size { Size::new(64, 48) } }
/// # impl DrawTarget for Screen {
/// #     type Color = Rgb565; type Error = core::convert::Infallible;
/// #     fn draw_iter<I: IntoIterator<Item = Pixel<Rgb565>>>(&mut self, _: I) -> Result<(), Self::Error> { Ok(()) }
/// # }
/// # let mut display = Screen;
/// type PanelTile = Tile<{ groups(32, 16) }, St7789Config>;
/// let mut tile = PanelTile::new();
/// let list = [Command::fill(Rect::new(0, 0, 64, 48), Rgb::new(0, 0, 255))];
/// let frame = PanelTile::frame::<32, 16>(64, 48)?;
/// let stats = frame.drawing(&mut tile, &list[..]).draw(&mut display).unwrap()?;
/// assert_eq!(stats.tiles, 6);
/// # Ok::<(), Error>(())
/// ```
pub struct Drawing<'a, const N: usize, C: TileConfig, S: CommandSource + ?Sized> {
    frame: &'a Frame,
    tile: core::cell::RefCell<&'a mut Tile<N, C>>,
    cmds: &'a S,
}

impl Frame {
    /// This frame's rendering of `cmds` with `tile`, as a
    /// [`Drawable`](embedded_graphics_core::Drawable) ([`Drawing`]).
    pub fn drawing<'a, const N: usize, C: TileConfig, S: CommandSource + ?Sized>(
        &'a self,
        tile: &'a mut Tile<N, C>,
        cmds: &'a S,
    ) -> Drawing<'a, N, C, S> {
        Drawing {
            frame: self,
            tile: core::cell::RefCell::new(tile),
            cmds,
        }
    }
}

impl<const N: usize, C: TileConfig, S: CommandSource + ?Sized> embedded_graphics_core::Drawable
    for Drawing<'_, N, C, S>
{
    type Color = <C::Format as PixelFormat>::Color;
    type Output = Result<FrameStats, Error>;

    fn draw<D>(&self, target: &mut D) -> Result<Self::Output, D::Error>
    where
        D: DrawTarget<Color = Self::Color>,
    {
        // The only borrow of the tile: `draw` cannot be re-entered.
        let mut tile = self.tile.borrow_mut();
        match self.frame.render(&mut tile, self.cmds, target) {
            Ok(stats) => Ok(Ok(stats)),
            Err(FlushError::Raster(e)) => Ok(Err(e)),
            Err(FlushError::Target(e)) => Err(e),
        }
    }
}

/// A command source with the textures its textured triangles name: what
/// [`Frame`] renders when a scene is textured.
///
/// ```
/// use tilerast::prelude::*;
/// static CHECKER: [u8; 4] = [0, 255, 255, 0];
/// let tex = [Texture::new(&CHECKER, 2, 2, TexFormat::Gray8)?];
/// let tv = |x: i32, y: i32, u: f32, v: f32| TexVertex::new(Coord::from_num(x), Coord::from_num(y), 0, (u, v), 1);
/// let list = [Command::textured(0, [tv(0, 0, 0.0, 0.0), tv(8, 0, 2.0, 0.0), tv(0, 8, 0.0, 2.0)], [255; 3])];
/// type T = Tile<{ groups(8, 8) }, Planes<Gray8Format, NoDepth, NoWid, NoDither, NoAa, FullPrecision, NoBlending, GouraudShading, AffineTexturing>>;
/// let frame = T::frame::<8, 8>(8, 8)?;
/// let mut tile = T::new();
/// frame.render_with(&mut tile, &WithTextures::new(&list[..], &tex), |_| Ok::<(), ()>(()))
///     .map_err(|_| Error::BadSize)?;
/// // Texel (0, 0) is black, (1, 0) white: each covers 4 x 4 pixels.
/// assert_eq!((tile.raw(1, 1), tile.raw(5, 1)), (Some(0), Some(255)));
/// # Ok::<(), Error>(())
/// ```
#[derive(Debug, Clone, Copy)]
pub struct WithTextures<'a, S: ?Sized> {
    cmds: &'a S,
    textures: &'a [crate::texture::Texture<'a>],
}

impl<'a, S: CommandSource + ?Sized> WithTextures<'a, S> {
    /// `cmds` drawn with `textures` (a textured triangle's `tex` indexes
    /// them; one past the end draws its shade).
    pub const fn new(cmds: &'a S, textures: &'a [crate::texture::Texture<'a>]) -> Self {
        WithTextures { cmds, textures }
    }
}

impl<S: CommandSource + ?Sized> CommandSource for WithTextures<'_, S> {
    fn each_keyed(&self, f: impl FnMut(u32, &Command)) -> Result<(), Error> {
        self.cmds.each_keyed(f)
    }
    fn replay(&self, keys: impl Iterator<Item = u32>, f: impl FnMut(&Command)) {
        self.cmds.replay(keys, f)
    }
    fn textures(&self) -> &[crate::texture::Texture<'_>] {
        self.textures
    }
}
