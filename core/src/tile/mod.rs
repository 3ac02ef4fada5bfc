//! The tile framebuffer (pipeline stage *tile planes*): colour, depth and
//! window-ID planes for up to `8 N` pixels, each plane chosen by type.
//!
//! A frame is rendered tile by tile ([`crate::frame`]): a 240x240 RGB565
//! screen is 115 KB, a 64x32 tile with 16-bit Z is 8 KB. Planes the scene does
//! not need are `()` — they cost no byte ([`Tile::bits_per_pixel`] reports
//! the exact cost) and their per-pixel test is the constant `true`.

mod draw;
mod mesh;

use crate::command::State;
use crate::config::TileConfig;
use crate::error::Error;
use crate::format::{ColorPlane, Lanes, PixelFormat, Rgb};
use crate::fragment::dither::quantize_carry;
use crate::fragment::dither::Dither;
use crate::fragment::{DepthMode, DepthPlane, WidMode, WidPlane};
use crate::geom::Rect;
use crate::numeric::{Precision, COLOR_FRAC, Z_FRAC};
use crate::raster::coverage::{AaMode, AaPlane};
use core::marker::PhantomData;
use embedded_graphics_core::{
    draw_target::DrawTarget,
    geometry::{Dimensions, Point, Size},
    primitives::Rectangle,
    Pixel,
};

/// The phases of a frame, in pipeline order: a frame rendered *until* a
/// phase ([`Frame::render_until`](crate::frame::Frame::render_until)) does
/// the work of that phase and every one before it and nothing after, so
/// firmware measures each phase's cost as the difference of two runs with
/// its own clock — counters with no probe inside the hot loops.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[repr(u8)]
pub enum Phase {
    /// The binning passes over the list (each decodes every command).
    Bin = 0,
    /// Clearing each tile's planes.
    Clear = 1,
    /// Reading each tile's commands in place (decode of the binned keys).
    Decode = 2,
    /// Triangle setup: edge functions and attribute planes.
    Setup = 3,
    /// Traversal: each triangle's covered pixels, row by row.
    Traverse = 4,
    /// Everything: span loops, fragment tests and stores, the other
    /// commands, coverage resolve — and the flush hook.
    All = 5,
}

impl Phase {
    pub(crate) const ALL: u8 = Phase::All as u8;
}

/// Values every tile starts with.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Clear {
    /// Background colour.
    pub color: Rgb,
    /// Depth (65535: farthest).
    pub depth: u16,
    /// Window ID.
    pub wid: u8,
}

impl Default for Clear {
    fn default() -> Self {
        Clear {
            color: Rgb::default(),
            depth: u16::MAX,
            wid: 0,
        }
    }
}

/// A tile of up to `8 N` pixels in display format `F`, with depth plane `Z`,
/// window-ID plane `W` and dither `D`.
///
/// ```
/// use tilerast::prelude::*;
/// let mut tile: Tile<8, Planes<Rgb888Format, Depth16>> = Tile::new(); // 64 pixels
/// tile.begin(Rect::new(16, 8, 8, 8), &Clear::default())?;
/// tile.draw(&Command::fill(Rect::new(0, 0, 20, 10), Rgb::new(9, 8, 7)))?;
/// assert_eq!(tile.raw(19, 9), Some(0x090807));
/// assert_eq!(tile.raw(20, 9), Some(0));      // outside the fill
/// assert_eq!(tile.raw(15, 9), None);         // outside the tile
/// assert_eq!(tile.depth(16, 8), Some(0xFFFF));
/// # Ok::<(), Error>(())
/// ```
pub struct Tile<const N: usize, C: TileConfig> {
    pub(crate) color: <C::Format as PixelFormat>::Plane<N>,
    pub(crate) depth: <C::Depth as DepthMode>::Plane<N>,
    pub(crate) wid: <C::Wid as WidMode>::Plane<N>,
    pub(crate) aa: <C::Aa as AaMode>::Plane<N>,
    /// The dither, a value ([`Tile::set_dither`]; zero-sized when fixed by
    /// type).
    pub(crate) dither: C::Dither,
    pub(crate) area: Rect,
    /// Coverage resolved into the colour plane ([`Tile::finish`]).
    resolved: bool,
    /// A command of a kind the configuration's `CommandSet` leaves out
    /// reached the tile since [`Tile::begin`] (reported as
    /// [`Error::ConfigMismatch`]).
    pub(crate) refused: bool,
    _config: PhantomData<C>,
}

impl<const N: usize, C, F, Z, W, D, A, P> Default for Tile<N, C>
where
    C: TileConfig<Format = F, Depth = Z, Wid = W, Dither = D, Aa = A, Precision = P>,
    F: PixelFormat,
    Z: DepthMode,
    W: WidMode,
    D: Dither,
    A: AaMode,
    P: Precision,
{
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize, C, F, Z, W, D, A, P> Tile<N, C>
where
    C: TileConfig<Format = F, Depth = Z, Wid = W, Dither = D, Aa = A, Precision = P>,
    F: PixelFormat,
    Z: DepthMode,
    W: WidMode,
    D: Dither,
    A: AaMode,
    P: Precision,
{
    /// Pixel capacity: `8 N`.
    pub const CAPACITY: usize = 8 * N;

    /// A tile with no area yet; call [`Tile::begin`]. `const`, so a tile
    /// can be a `static` (placed by the linker, not on the stack):
    ///
    /// ```
    /// use tilerast::prelude::*;
    /// static TILE: Tile<300, Planes<Rgb565Format, Depth16>> = Tile::new(); // 60x40 px
    /// assert_eq!(Tile::<300, Planes<Rgb565Format, Depth16>>::plane_bytes(), 9600);
    /// assert!(core::mem::size_of_val(&TILE) < 9600 + 32);
    /// ```
    pub const fn new() -> Self {
        Tile {
            color: <F::Plane<N> as ColorPlane>::NEW,
            depth: <Z::Plane<N> as DepthPlane>::NEW,
            wid: <W::Plane<N> as WidPlane>::NEW,
            aa: <A::Plane<N> as AaPlane>::NEW,
            dither: D::NEW,
            area: Rect::new(0, 0, 0, 0),
            resolved: false,
            refused: false,
            _config: PhantomData,
        }
    }

    /// Exact RAM cost per pixel of this configuration, in bits (colour + Z + window ID).
    ///
    /// ```
    /// use tilerast::prelude::*;
    /// assert_eq!(Tile::<64, BinaryFormat>::bits_per_pixel(), 1);
    /// assert_eq!(Tile::<64, Planes<Rgb444Format, Depth16, Wid8>>::bits_per_pixel(), 16 + 16 + 8);
    /// assert_eq!(Tile::<64, Planes<Rgb888Format, Depth16, Wid8>>::bits_per_pixel(), 24 + 16 + 8);
    /// ```
    pub const fn bits_per_pixel() -> u32 {
        (Self::plane_bytes() * 8 / Self::CAPACITY) as u32
    }

    /// Bytes of all planes together (`size_of` of the planes, no padding added).
    pub const fn plane_bytes() -> usize {
        core::mem::size_of::<F::Plane<N>>()
            + core::mem::size_of::<Z::Plane<N>>()
            + core::mem::size_of::<W::Plane<N>>()
            + core::mem::size_of::<A::Plane<N>>()
    }

    /// The tile's dither (zero-sized when the configuration fixes it by
    /// type).
    pub fn dither(&self) -> D {
        self.dither
    }

    /// Sets the dither used from the next store on: what a
    /// [`RuntimeDither`](crate::dither::RuntimeDither) is for (a
    /// `Bayer<L>` has one value).
    ///
    /// ```
    /// use tilerast::prelude::*;
    /// let mut tile: Tile<8, Planes<Rgb565Format, NoDepth, NoWid, RuntimeDither>> = Tile::new();
    /// tile.set_dither(RuntimeDither::new(2)?); // 4x4, as Bayer4
    /// assert_eq!(tile.dither().log2(), 2);
    /// # Ok::<(), Error>(())
    /// ```
    pub fn set_dither(&mut self, d: D) {
        self.dither = d;
    }

    /// Switches a [`Switchable`](crate::fragment::Switchable) depth plane
    /// on or off, from the next [`Tile::begin`] on (a plane fixed by type
    /// ignores it).
    pub fn enable_depth(&mut self, on: bool) {
        self.depth.set_present(on);
    }

    /// Switches a [`Switchable`](crate::fragment::Switchable) window-ID
    /// plane on or off, from the next [`Tile::begin`] on (a plane fixed by
    /// type ignores it).
    pub fn enable_wid(&mut self, on: bool) {
        self.wid.set_present(on);
    }

    /// Bits per pixel of the planes in use: [`Tile::bits_per_pixel`] less
    /// a [`Switchable`](crate::fragment::Switchable) plane switched off —
    /// what the same tile with that plane left out by type would take.
    ///
    /// ```
    /// use tilerast::prelude::*;
    /// let mut tile: Tile<8, Planes<Rgb565Format, Switchable<Depth16>>> = Tile::new();
    /// assert_eq!(tile.bits_in_use(), 32);
    /// tile.enable_depth(false);
    /// assert_eq!(tile.bits_in_use(), Tile::<8, Rgb565Format>::bits_per_pixel());
    /// ```
    pub fn bits_in_use(&self) -> u32 {
        let off = |present: bool, bits: u32| if present { 0 } else { bits };
        Self::bits_per_pixel()
            - off(self.depth.present(), Z::BITS)
            - off(self.wid.present(), W::BITS)
    }

    /// The screen rectangle the tile currently holds.
    pub fn area(&self) -> Rect {
        self.area
    }

    /// Starts a tile at screen rectangle `area` and clears its planes.
    ///
    /// The rectangle must lie inside the guard band
    /// `[-COORD_LIMIT, COORD_LIMIT]` on both axes (the numeric contract's
    /// domain; [`Error::CoordOutOfRange`] otherwise), so every pixel
    /// address of the tile fits an `i32` with room to spare.
    ///
    /// ```
    /// use tilerast::prelude::*;
    /// let mut tile: Tile<8, Rgb565Format> = Tile::new();
    /// assert_eq!(tile.begin(Rect::new(i32::MAX - 3, 0, 4, 1), &Clear::default()),
    ///            Err(Error::CoordOutOfRange));
    /// ```
    pub fn begin(&mut self, area: Rect, clear: &Clear) -> Result<(), Error> {
        if area.w == 0 || area.h == 0 {
            return Err(Error::BadSize);
        }
        if area.area() > Self::CAPACITY as u64 {
            return Err(Error::TileTooLarge);
        }
        let lim = crate::numeric::COORD_LIMIT as i64;
        let inside = |lo: i32, hi: i64| lo as i64 >= -lim && hi <= lim;
        if !inside(area.x, area.x1()) || !inside(area.y, area.y1()) {
            return Err(Error::CoordOutOfRange);
        }
        self.area = area;
        self.resolved = false;
        self.refused = false;
        let c = F::pack_rgb(clear.color);
        let n = area.area() as usize;
        // Plane by plane, as slice fills (the Cortex-M4's 64x32 RGB565 + Z16
        // tile: 3.4 instructions a pixel a pixel at a time, measured).
        self.color.fill(0..n, c);
        self.depth.put_range(0..n, clear.depth);
        self.wid.put_range(0..n, clear.wid);
        if A::SAMPLES > 0 {
            for i in 0..n {
                self.aa.clear(i, clear.depth, clear.color);
            }
        }
        Ok(())
    }

    /// With coverage antialiasing ([`crate::raster::coverage`]): resolves every
    /// pixel's samples into the colour plane (dithered and packed like any
    /// fragment), sets the depth plane, if any, to the nearest sample, and
    /// returns `true` — spans and lines are then drawn over the resolved
    /// pixels by drawing the commands again ([`crate::frame::Frame`] does).
    /// Without, or when already resolved, it does nothing and returns `false`.
    pub fn finish(&mut self) -> bool {
        if A::SAMPLES == 0 || self.resolved {
            return false;
        }
        let a = self.area;
        let bias = self.dither.round_bias();
        for i in 0..a.area() as usize {
            // Covered samples plus the background (the colour plane: the
            // clear colour or a fill) on the uncovered ones, in the output
            // scale with 16 fraction bits.
            let (sum, free) = self.aa.resolve(i);
            let bg = F::unpack(self.color.get(i));
            let cov = F::lanes_from_rgb(sum.map(|v| (v as i64) << (COLOR_FRAC - 8)));
            let v = cov.zip(bg, |c, b| c + ((b << COLOR_FRAC) >> 8) * free as i32 + bias);
            let (x, y) = (a.x + (i as u32 % a.w) as i32, a.y + (i as u32 / a.w) as i32);
            self.store::<false, _>(self.dither, i, x as u32, y as u32, v, F::MASK_ALL);
            self.depth.put(i, self.aa.nearest(i));
        }
        self.resolved = true;
        true
    }

    /// The fragment store (pipeline stage 8), the one path every shaded
    /// colour write takes — span loop, blends, coverage resolve: ordered
    /// dither from the pixel address bits, pack to the display format,
    /// plane mask (when `MASKED`), store. `v` is in the output channel
    /// scale with [`COLOR_FRAC`] fraction bits, rounding bias included.
    /// `d` is the tile's dither, passed in so that a loop reads it once.
    #[inline(always)]
    fn store<const MASKED: bool, Dd: Dither>(
        &mut self,
        d: Dd,
        i: usize,
        x: u32,
        y: u32,
        v: F::Lanes,
        mask: u32,
    ) {
        self.store_carry::<MASKED, false>(i, d.carry(x, y), v, mask);
    }

    /// [`Self::store`] with the dither's carry at the pixel already known
    /// (a span loop walks it: [`Dither::cursor`]). With `IN_RANGE` the
    /// lanes are each in `0..`[`Self::lane_limit`]: the quantization's
    /// saturation and clamp cannot act, so a lane is a shift (the same
    /// value, fewer instructions).
    #[inline(always)]
    fn store_carry<const MASKED: bool, const IN_RANGE: bool>(
        &mut self,
        i: usize,
        carry: i32,
        v: F::Lanes,
        mask: u32,
    ) {
        let raw = if IN_RANGE {
            F::pack(v.map(|v| (v as u32 + carry as u32) as i32 >> COLOR_FRAC))
        } else {
            Self::pack_carry(carry, v)
        };
        self.put_packed::<MASKED>(i, raw, mask);
    }

    /// `v` (as in [`Self::store`]) dithered at screen `(x, y)`, quantized
    /// and packed.
    #[inline(always)]
    fn pack_at<Dd: Dither>(d: Dd, x: u32, y: u32, v: F::Lanes) -> u32 {
        Self::pack_carry(d.carry(x, y), v)
    }

    /// `v` with the dither's `carry` added, quantized and packed.
    #[inline(always)]
    fn pack_carry(carry: i32, v: F::Lanes) -> u32 {
        F::pack(v.zip(F::MAX, |v, max| quantize_carry(v, max, carry)))
    }

    /// The bound of lane `i` below which (and from 0) a value quantizes
    /// without its clamp at every address: `2^16 (max + 1)` less the
    /// dither's largest carry (at most 2^30, what
    /// [`ends_in`](crate::numeric::ends_in) takes).
    #[inline(always)]
    fn lane_limit(d: D, i: usize) -> u32 {
        let top = ((F::MAX.lane(i) as u64 + 1) << COLOR_FRAC).min(1 << 30);
        top as u32 - d.carry_max() as u32
    }

    /// Composites a premultiplied colour `lanes` (output scale,
    /// [`COLOR_FRAC`] fraction bits) over pixel `i` at screen `(x, y)`,
    /// keeping `keep` (Q1.15) of the old colour: `C = lanes + C_old keep`,
    /// then dither and pack. The volume stage's last step.
    #[inline]
    pub(crate) fn over(&mut self, i: usize, x: u32, y: u32, lanes: F::Lanes, keep: i32) {
        let old = F::unpack(self.color.get(i));
        let bias = self.dither.round_bias();
        let v = lanes.zip(old, |p, o| {
            p + ((o as i64 * keep as i64) >> 15) as i32 + bias
        });
        self.store::<false, _>(self.dither, i, x, y, v, F::MASK_ALL);
    }

    /// The end of [`Self::store`] for an already packed value (flat fills
    /// and overlays, which have nothing to dither): plane mask, store.
    #[inline(always)]
    fn put_packed<const MASKED: bool>(&mut self, i: usize, raw: u32, mask: u32) {
        let raw = if MASKED {
            (self.color.get(i) & !mask) | (raw & mask)
        } else {
            raw
        };
        self.color.set(i, raw);
    }

    /// The index of screen pixel `(x, y)`, which the caller has clipped
    /// to the tile, in 32-bit arithmetic (a tile's offsets fit 16 bits):
    /// the product of 64-bit coordinates was a library call per span on
    /// the Cortex-M0 (`__aeabi_lmul`, about 40 instructions: measured).
    #[inline(always)]
    pub(crate) fn offset(&self, x: i64, y: i64) -> usize {
        let a = self.area;
        debug_assert!((a.x as i64..a.x1()).contains(&x) && (a.y as i64..a.y1()).contains(&y));
        let dx = (x as i32).wrapping_sub(a.x) as u32;
        let dy = (y as i32).wrapping_sub(a.y) as u32;
        dy.wrapping_mul(a.w).wrapping_add(dx) as usize
    }

    fn index(&self, x: i32, y: i32) -> Option<usize> {
        let a = self.area;
        let (dx, dy) = (x as i64 - a.x as i64, y as i64 - a.y as i64);
        // The product in 32 bits ([`Self::offset`]).
        ((0..a.w as i64).contains(&dx) && (0..a.h as i64).contains(&dy))
            .then(|| (dy as u32 * a.w + dx as u32) as usize)
    }

    /// The packed pixel at screen `(x, y)`, `None` outside the tile.
    pub fn raw(&self, x: i32, y: i32) -> Option<u32> {
        self.index(x, y).map(|i| self.color.get(i))
    }

    /// The colour at screen `(x, y)`, `None` outside the tile.
    pub fn pixel(&self, x: i32, y: i32) -> Option<F::Color> {
        self.raw(x, y).map(F::to_color)
    }

    /// The depth at screen `(x, y)` (65535 without a depth plane).
    pub fn depth(&self, x: i32, y: i32) -> Option<u16> {
        self.index(x, y).map(|i| self.depth.read(i))
    }

    /// The window ID at screen `(x, y)` (0 without a window-ID plane).
    pub fn wid(&self, x: i32, y: i32) -> Option<u8> {
        self.index(x, y).map(|i| self.wid.read(i))
    }

    /// The tile's pixels in row-major order, as colours.
    pub fn colors(&self) -> impl Iterator<Item = F::Color> + '_ {
        (0..self.area.area() as usize).map(|i| F::to_color(self.color.get(i)))
    }

    /// Bytes [`Tile::panel_bytes`] writes for a `w x h` tile: what a display
    /// controller's RAM-write command takes for that window.
    pub const fn panel_len(w: u32, h: u32) -> usize {
        let n = w as usize * h as usize;
        match F::MASK_ALL.count_ones() {
            1 => n / 8,
            12 => (3 * n).div_ceil(2),
            b => n * (b as usize).div_ceil(8),
        }
    }

    /// The tile's pixels as the panel's RAM-write command takes them, into
    /// `out`; returns the bytes written. Row-major, and: RGB565 big-endian
    /// (ST7789, ILI9341 in 16-bit mode); RGB444 two pixels in three bytes
    /// (their 12-bit mode); RGB888 and Gray8 a byte per channel; 1-bit in
    /// SSD1306 page order — a byte per column of 8 rows, bit 0 on top (the
    /// tile's height must be a multiple of 8, or [`Error::BadSize`]). What a
    /// DMA transfer sends while the next tile renders.
    ///
    /// ```
    /// use tilerast::prelude::*;
    /// let mut tile: Tile<1, Rgb565Format> = Tile::new();
    /// tile.begin(Rect::new(0, 0, 2, 1), &Clear::default())?;
    /// tile.draw(&Command::fill(Rect::new(1, 0, 1, 1), Rgb::new(255, 0, 0)))?;
    /// let mut buf = [0u8; 4];
    /// assert_eq!(tile.panel_bytes(&mut buf)?, 4);
    /// assert_eq!(buf, [0x00, 0x00, 0xF8, 0x00]); // big-endian RGB565
    ///
    /// let mut oled: Tile<2, BinaryFormat> = Tile::new();
    /// oled.begin(Rect::new(0, 0, 2, 8), &Clear::default())?;
    /// oled.draw(&Command::fill(Rect::new(1, 2, 1, 3), Rgb::new(255, 255, 255)))?;
    /// let mut page = [0u8; 2];
    /// assert_eq!(oled.panel_bytes(&mut page)?, 2);
    /// assert_eq!(page, [0, 0b0001_1100]); // column 1, rows 2..5
    /// # Ok::<(), Error>(())
    /// ```
    pub fn panel_bytes(&self, out: &mut [u8]) -> Result<usize, Error> {
        let a = self.area;
        let n = a.area() as usize;
        let len = Self::panel_len(a.w, a.h);
        let out = out.get_mut(..len).ok_or(Error::BufferTooSmall)?;
        let px = |i: usize| self.color.get(i);
        match F::MASK_ALL.count_ones() {
            1 => {
                if a.h % 8 != 0 {
                    return Err(Error::BadSize);
                }
                let w = a.w as usize;
                for (k, byte) in out.iter_mut().enumerate() {
                    let (page, x) = (k / w, k % w);
                    *byte = (0..8).fold(0, |b, bit| {
                        b | ((px((page * 8 + bit) * w + x) as u8 & 1) << bit)
                    });
                }
            }
            12 => {
                for (k, o) in out.chunks_mut(3).enumerate() {
                    let p0 = px(2 * k);
                    let p1 = if 2 * k + 1 < n { px(2 * k + 1) } else { 0 };
                    let b = [(p0 >> 4) as u8, ((p0 << 4) | (p1 >> 8)) as u8, p1 as u8];
                    let m = o.len();
                    o.copy_from_slice(&b[..m]);
                }
            }
            bits => {
                let bytes = (bits as usize).div_ceil(8);
                for (i, o) in out.chunks_exact_mut(bytes).enumerate() {
                    let p = px(i);
                    for (j, b) in o.iter_mut().enumerate() {
                        *b = (p >> (8 * (bytes - 1 - j))) as u8;
                    }
                }
            }
        }
        Ok(len)
    }

    /// A 32-bit hash of the tile's area and colour plane (multiply-xor,
    /// about 4 instructions a pixel): what [`Damage`](crate::frame::Damage)
    /// compares between frames.
    pub fn content_hash(&self) -> u32 {
        let a = self.area;
        let mut h = crate::hash::WordHash::new();
        [a.x as u32, a.y as u32, a.w, a.h]
            .into_iter()
            .chain((0..a.area() as usize).map(|i| self.color.get(i)))
            .for_each(|v| h.add(v));
        h.value()
    }

    /// Flushes the tile to a display with `color` converting each packed
    /// pixel ([`Tile::raw`]): e.g. the front half of an
    /// [`Rgb444PairFormat`](crate::format::Rgb444PairFormat) plane.
    ///
    /// ```
    /// use tilerast::prelude::*;
    /// use embedded_graphics_core::{pixelcolor::Rgb888, prelude::*};
    /// # struct Screen(Vec<Rgb888>);
    /// # impl OriginDimensions for Screen { fn size(&self) -> Size { Size::new(4, 4) } }
    /// # impl DrawTarget for Screen {
    /// #     type Color = Rgb888; type Error = core::convert::Infallible;
    /// #     fn draw_iter<I: IntoIterator<Item = Pixel<Rgb888>>>(&mut self, p: I) -> Result<(), Self::Error> {
    /// #         self.0.extend(p.into_iter().map(|p| p.1)); Ok(()) }
    /// # }
    /// let mut tile: Tile<2, Rgb444PairFormat> = Tile::new();
    /// tile.begin(Rect::new(0, 0, 4, 4), &Clear { color: Rgb::new(255, 255, 255), ..Clear::default() })?;
    /// let mut screen = Screen(vec![]);
    /// let high = |raw| Rgb444PairFormat::half(raw, Half::High).into();
    /// tile.flush_with(&mut screen, high).unwrap();
    /// assert!(screen.0.iter().all(|&c| c == Rgb888::WHITE));
    /// # Ok::<(), Error>(())
    /// ```
    pub fn flush_with<T: DrawTarget>(
        &self,
        target: &mut T,
        color: impl Fn(u32) -> T::Color,
    ) -> Result<(), T::Error> {
        let a = self.area;
        let rect = Rectangle::new(Point::new(a.x, a.y), Size::new(a.w, a.h));
        let raw = (0..a.area() as usize).map(|i| color(self.color.get(i)));
        target.fill_contiguous(&rect, raw)
    }

    /// Flushes the tile to a display: one `fill_contiguous` over the tile
    /// rectangle, converting each pixel to the display's colour type.
    pub fn flush<T>(&self, target: &mut T) -> Result<(), T::Error>
    where
        T: DrawTarget,
        T::Color: From<F::Color>,
    {
        let a = self.area;
        let rect = Rectangle::new(Point::new(a.x, a.y), Size::new(a.w, a.h));
        target.fill_contiguous(&rect, self.colors().map(Into::into))
    }
}

impl<const N: usize, C, F, Z, W, D, A, P> Dimensions for Tile<N, C>
where
    C: TileConfig<Format = F, Depth = Z, Wid = W, Dither = D, Aa = A, Precision = P>,
    F: PixelFormat,
    Z: DepthMode,
    W: WidMode,
    D: Dither,
    A: AaMode,
    P: Precision,
{
    /// The tile's screen rectangle: `embedded-graphics` drawing is clipped to it.
    fn bounding_box(&self) -> Rectangle {
        let a = self.area;
        Rectangle::new(Point::new(a.x, a.y), Size::new(a.w, a.h))
    }
}

/// A tile is itself a `DrawTarget` in screen coordinates: text and
/// primitives drawn with `embedded-graphics` land on top of (or, drawn
/// before the commands, under) the rasterized content, clipped to the tile.
/// They write colour only: no window-ID or Z test, no plane mask (use
/// [`Tile::overlay`] for those).
///
/// ```
/// use tilerast::prelude::*;
/// use embedded_graphics_core::{pixelcolor::Rgb565, prelude::*};
/// let mut tile: Tile<8, Rgb565Format> = Tile::new();
/// tile.begin(Rect::new(8, 0, 8, 8), &Clear::default())?;
/// tile.draw_iter([Pixel(Point::new(9, 1), Rgb565::RED), Pixel(Point::new(0, 0), Rgb565::RED)]).ok();
/// assert_eq!(tile.pixel(9, 1), Some(Rgb565::RED));
/// # Ok::<(), Error>(())
/// ```
impl<const N: usize, C, F, Z, W, D, A, P> DrawTarget for Tile<N, C>
where
    C: TileConfig<Format = F, Depth = Z, Wid = W, Dither = D, Aa = A, Precision = P>,
    F: PixelFormat,
    Z: DepthMode,
    W: WidMode,
    D: Dither,
    A: AaMode,
    P: Precision,
{
    type Color = F::Color;
    type Error = core::convert::Infallible;

    fn draw_iter<I: IntoIterator<Item = Pixel<F::Color>>>(
        &mut self,
        pixels: I,
    ) -> Result<(), Self::Error> {
        for Pixel(p, c) in pixels {
            if let Some(i) = self.index(p.x, p.y) {
                self.color.set(i, F::from_color(c));
            }
        }
        Ok(())
    }

    fn fill_solid(&mut self, area: &Rectangle, color: F::Color) -> Result<(), Self::Error> {
        let c = F::from_color(color);
        self.for_each_pixel(&Rect::from(*area), |t, i| t.color.set(i, c));
        Ok(())
    }
}

impl<const N: usize, C, F, Z, W, D, A, P> Tile<N, C>
where
    C: TileConfig<Format = F, Depth = Z, Wid = W, Dither = D, Aa = A, Precision = P>,
    F: PixelFormat,
    Z: DepthMode,
    W: WidMode,
    D: Dither,
    A: AaMode,
    P: Precision,
{
    /// A `DrawTarget` over this tile whose pixels pass the fragment tests
    /// like a command's: the window-ID test for `state.wid`, a Z test at
    /// depth `z` (read only: text does not claim depth) and the plane mask.
    /// Text in window 1 stays inside window 1 and behind nearer geometry.
    ///
    /// ```
    /// use tilerast::prelude::*;
    /// use embedded_graphics_core::{pixelcolor::Rgb565, prelude::*};
    /// let mut tile: Tile<8, Planes<Rgb565Format, Depth16, Wid8>> = Tile::new();
    /// tile.begin(Rect::new(0, 0, 8, 8), &Clear::default())?;
    /// tile.draw(&Command::wid_fill(Rect::new(0, 0, 4, 8), 1))?;
    /// tile.draw(&Command::zfill(Rect::new(0, 0, 8, 1), 10).window(1))?;
    /// tile.overlay(State::new(1), 100)
    ///     .fill_solid(&Rect::new(0, 0, 8, 8).into(), Rgb565::RED).ok();
    /// assert_eq!(tile.pixel(1, 1), Some(Rgb565::RED));   // window 1, nothing nearer
    /// assert_eq!(tile.pixel(1, 0), Some(Rgb565::BLACK)); // behind depth 10
    /// assert_eq!(tile.pixel(5, 1), Some(Rgb565::BLACK)); // window 0
    /// # Ok::<(), Error>(())
    /// ```
    pub fn overlay(&mut self, state: State, z: u16) -> Overlay<'_, N, C> {
        Overlay {
            tile: self,
            state,
            z: (z as i32) << Z_FRAC,
        }
    }
}

/// A tile seen as a `DrawTarget` that tests window ID, depth and plane mask
/// ([`Tile::overlay`]).
pub struct Overlay<'t, const N: usize, C: TileConfig> {
    tile: &'t mut Tile<N, C>,
    state: State,
    /// Depth in the DDA's 16.14 format.
    z: i32,
}

impl<const N: usize, C, F, Z, W, D, A, P> Overlay<'_, N, C>
where
    C: TileConfig<Format = F, Depth = Z, Wid = W, Dither = D, Aa = A, Precision = P>,
    F: PixelFormat,
    Z: DepthMode,
    W: WidMode,
    D: Dither,
    A: AaMode,
    P: Precision,
{
    /// Writes packed colour `c` at pixel `i` if it passes the tests.
    fn put(t: &mut Tile<N, C>, i: usize, c: u32, st: &State, z: i32) {
        if t.wid.pass(i, st.wid) && t.depth.test(i, z) {
            t.put_packed::<true>(i, c, st.plane_mask & F::MASK_ALL);
        }
    }
}

impl<const N: usize, C, F, Z, W, D, A, P> Dimensions for Overlay<'_, N, C>
where
    C: TileConfig<Format = F, Depth = Z, Wid = W, Dither = D, Aa = A, Precision = P>,
    F: PixelFormat,
    Z: DepthMode,
    W: WidMode,
    D: Dither,
    A: AaMode,
    P: Precision,
{
    fn bounding_box(&self) -> Rectangle {
        self.tile.bounding_box()
    }
}

impl<const N: usize, C, F, Z, W, D, A, P> DrawTarget for Overlay<'_, N, C>
where
    C: TileConfig<Format = F, Depth = Z, Wid = W, Dither = D, Aa = A, Precision = P>,
    F: PixelFormat,
    Z: DepthMode,
    W: WidMode,
    D: Dither,
    A: AaMode,
    P: Precision,
{
    type Color = F::Color;
    type Error = core::convert::Infallible;

    fn draw_iter<I: IntoIterator<Item = Pixel<F::Color>>>(
        &mut self,
        pixels: I,
    ) -> Result<(), Self::Error> {
        for Pixel(p, c) in pixels {
            if let Some(i) = self.tile.index(p.x, p.y) {
                Self::put(self.tile, i, F::from_color(c), &self.state, self.z);
            }
        }
        Ok(())
    }

    fn fill_solid(&mut self, area: &Rectangle, color: F::Color) -> Result<(), Self::Error> {
        let (c, st, z) = (F::from_color(color), self.state, self.z);
        self.tile
            .for_each_pixel(&Rect::from(*area), |t, i| Self::put(t, i, c, &st, z));
        Ok(())
    }
}
