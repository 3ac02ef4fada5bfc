//! Commands (pipeline stage 1): what the geometry side sends to the raster
//! engine, like REjr's instruction FIFO — spans, triangles, lines,
//! antialiased solid edges, area fills, Z fills and window-ID fills, each
//! with its per-command [`State`].

use crate::error::Error;
use crate::format::Rgb;
use crate::geom::Rect;
pub use crate::geom::{QuadVertex, Vertex};
use crate::numeric::{ColorFix, ColorStep, ZFix, ZStep, COORD_LIMIT};

/// How a command's fragments combine with the colour plane: replace it
/// (opaque, the default) or alpha-blend over it (seed 001 §IV.4, the RE's
/// α-channel): `C = α C_src + (1 - α) C_dst`.
///
/// A translucent command takes its opacity from its vertices
/// ([`Vertex::alpha`], interpolated like a colour channel), its span
/// ([`SpanCmd::alpha`]) or its fill (`Command::Fill::alpha`). It tests Z but
/// does not write it unless it is [`Blend::AlphaZWrite`]; drawing
/// translucent commands back to front is the application's business.
/// Lines, antialiased edges and Z and window-ID fills ignore the mode.
///
/// Blending is compiled only into tiles whose configuration asks for it
/// ([`AlphaBlending`](crate::fragment::AlphaBlending) in
/// [`Planes`](crate::config::Planes)); any other tile draws translucent
/// commands opaque and carries no blending code (the host simulator
/// always blends).
///
/// **Rounding.** The weight is `w = round(256 α / 255)` in 1/256 after
/// interpolation, so `α = 255` replaces exactly and `α = 0` leaves the
/// pixel; the blend is `C_dst + (C_src - C_dst) w / 256` in the output
/// channel scale with 16 fraction bits, then dithered and packed like every
/// fragment. Error against the exact blend of the same two colours: at most
/// half an output LSB before the final rounding (`tests/tests/alpha.rs`).
///
/// ```
/// use tilerast::prelude::*;
/// let v = |x: i32, y: i32| Vertex::new(Coord::from_num(x), Coord::from_num(y), 9, Rgb::new(255, 0, 0)).with_alpha(128);
/// let glass = Command::triangle([v(0, 0), v(8, 0), v(0, 8)]).blend(Blend::Alpha);
/// assert_eq!(glass.state().map(|s| s.blend), Some(Blend::Alpha));
/// assert_eq!(State::default().blend, Blend::Opaque);
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[repr(u8)]
pub enum Blend {
    /// Fragments replace the pixel and write Z (α is ignored).
    #[default]
    Opaque = 0,
    /// Fragments blend over the pixel; Z is tested, not written.
    Alpha = 1,
    /// Fragments blend over the pixel; Z is tested and written.
    AlphaZWrite = 2,
}

impl Blend {
    /// Whether fragments blend (every mode but [`Blend::Opaque`]).
    pub const fn translucent(self) -> bool {
        !matches!(self, Blend::Opaque)
    }
}

/// Which triangles a draw drops by their winding: the geometry stage's
/// option ([`DrawOptions::cull`](crate::geometry::DrawOptions::cull), fronts
/// by their winding in model space) and a frame's
/// ([`Frame::cull`](crate::frame::Frame::cull), fronts by their winding on
/// screen: for meshes projected offline, a raster-only list).
///
/// On screen a *front* face is one whose vertices run counter-clockwise as
/// seen on the display: a negative doubled area `(x1 - x0)(y2 - y0) -
/// (y1 - y0)(x2 - x0)` in the y-down screen coordinates. That is how an
/// OBJ model's outside faces (counter-clockwise seen from outside) reach
/// the screen through a projection. A triangle of zero area draws nothing
/// either way.
///
/// ```
/// use tilerast::prelude::*;
/// let v = |x: i32, y: i32| Vertex::new(Coord::from_num(x), Coord::from_num(y), 9, Rgb::new(255, 0, 0));
/// // Clockwise as seen on the display: a back face.
/// let back = Command::triangle([v(0, 0), v(8, 0), v(0, 8)]);
/// assert!(back.culled_by(Cull::Back) && !back.culled_by(Cull::Front));
/// let front = Command::triangle([v(0, 0), v(0, 8), v(8, 0)]);
/// assert!(!front.culled_by(Cull::Back) && front.culled_by(Cull::Front));
/// assert!(!front.culled_by(Cull::None));
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[repr(u8)]
pub enum Cull {
    /// Draw both sides.
    None = 0,
    /// Drop triangles seen from behind (the geometry stage's default).
    #[default]
    Back = 1,
    /// Drop triangles seen from the front.
    Front = 2,
}

impl Cull {
    /// Whether a triangle of doubled signed area `area2` (y-down screen
    /// coordinates, negative for a front face) is dropped.
    #[inline(always)]
    pub const fn drops(self, area2: i64) -> bool {
        match self {
            Cull::None => false,
            Cull::Back => area2 > 0,
            Cull::Front => area2 < 0,
        }
    }
}

/// Per-command state (the seed's window ID and plane mask, the RUF seed's
/// object tag and the RE's blend mode): 8 bytes.
///
/// ```
/// use tilerast::command::State;
/// let s = State { wid: 3, ..State::default() };
/// assert_eq!(s.plane_mask, u32::MAX);
/// assert_eq!(core::mem::size_of::<State>(), 8);
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct State {
    /// The command draws only where the window-ID plane holds this ID
    /// (ignored by tiles without a window-ID plane).
    pub wid: u8,
    /// Bits of the packed pixel the command may change (in the display
    /// format's packing, e.g. `0xF800` = red of RGB565). Default: all.
    pub plane_mask: u32,
    /// Object tag (seed 000): triangles of one object share it, so the RUF
    /// buffer merges their fragments. Used only by coverage antialiasing.
    pub tag: u16,
    /// Opaque (default) or alpha-blended ([`Blend`]).
    pub blend: Blend,
}

impl State {
    /// Window `wid`, every plane writable, object tag 0.
    pub const fn new(wid: u8) -> Self {
        State {
            wid,
            plane_mask: u32::MAX,
            tag: 0,
            blend: Blend::Opaque,
        }
    }
}

impl Default for State {
    fn default() -> Self {
        State::new(0)
    }
}

/// The raster engine's span command: start position, pixel count, start
/// colour and depth and their per-pixel steps (seed 001, §II.1).
///
/// ```
/// use tilerast::prelude::*;
/// let s = SpanCmd {
///     x: 0, y: 0, len: 256,
///     color: [ColorFix::ZERO; 3],
///     dcolor: [ColorStep::ONE, ColorStep::ZERO, ColorStep::ZERO], // 0..255 ramp
///     z: ZFix::ZERO, dz: ZStep::ZERO, alpha: 255,
/// };
/// assert!(s.validate().is_ok());
/// assert_eq!(SpanCmd { len: 257, ..s }.validate(), Err(Error::SpanOutOfRange));
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct SpanCmd {
    /// Screen column of the first pixel.
    pub x: i32,
    /// Screen row.
    pub y: i32,
    /// Number of pixels.
    pub len: u16,
    /// Colour of the first pixel, 0..255 scale.
    pub color: [ColorFix; 3],
    /// Colour step per pixel.
    pub dcolor: [ColorStep; 3],
    /// Depth of the first pixel.
    pub z: ZFix,
    /// Depth step per pixel.
    pub dz: ZStep,
    /// Opacity of every pixel, `0..=255`, when the command blends
    /// ([`Blend`]); ignored otherwise.
    pub alpha: u8,
}

impl SpanCmd {
    /// Checks position and that every channel stays in range up to the last
    /// pixel (`[0, 256)` for colour, `[0, 65536)` for Z).
    pub fn validate(&self) -> Result<(), Error> {
        let lim = COORD_LIMIT as i64;
        let x_ok = (-lim..lim).contains(&(self.x as i64)) && self.x as i64 + self.len as i64 <= lim;
        if !x_ok || !(-lim..lim).contains(&(self.y as i64)) {
            return Err(Error::CoordOutOfRange);
        }
        let last = self.len.saturating_sub(1) as i64;
        let in_range = |start: i64, step: i64, max: i64| {
            let end = start + step * last;
            (0..max).contains(&start) && (0..max).contains(&end)
        };
        let colors_ok = (0..3).all(|i| {
            in_range(
                self.color[i].to_bits() as i64,
                self.dcolor[i].to_bits() as i64,
                256 << 16,
            )
        });
        if colors_ok
            && in_range(
                self.z.to_bits() as i64,
                self.dz.to_bits() as i64,
                65536 << 16,
            )
        {
            Ok(())
        } else {
            Err(Error::SpanOutOfRange)
        }
    }
}

/// One display-list command.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
// A plain tag byte: without it the compiler hides the tag in `Blend`'s
// spare values (56 bytes instead of 60), and telling a triangle from the
// other commands takes a range test — 3% more instructions a teapot frame
// on the Cortex-M4 (measured: binning and decoding).
#[repr(u8)]
pub enum Command {
    /// A Gouraud-shaded, Z-tested triangle (either winding).
    Triangle {
        /// The vertices.
        v: [Vertex; 3],
        /// Window ID and plane mask.
        state: State,
    },
    /// A quadratically shaded, Z-tested triangle (either winding): the RE's
    /// fast Phong (seed 001 §IV.2). Each channel is the quadratic through
    /// the three vertex colours and the three edge-midpoint colours
    /// ([`QuadVertex::mid`]), stepped by second-order forward differences:
    /// two additions per channel and pixel. The geometry stage fills the
    /// midpoints from the lighting ([`crate::geometry::Shading::FastPhong`]).
    ///
    /// A sliver — `κ² (|M| + 16) > 2^45`, with `κ = max over edges of
    /// (|dy| bw + |dx| bh) / area2` (sub-pixels; `bw`, `bh` the vertices'
    /// extent plus one pixel) and `|M|` the largest `|2 mid - c_p - c_q|`
    /// over edges and channels: a triangle so much thinner than its box
    /// that even an `f64` setup would lose precision for its curvature
    /// (past `2^16` the setup already runs in `f64`) — is
    /// drawn Gouraud-shaded, as are all quadratic triangles in tiles configured without quadratic shading
    /// ([`QuadraticShading`](crate::fragment::QuadraticShading) in
    /// [`Planes`](crate::config::Planes)) and under coverage antialiasing.
    Quadratic {
        /// Opacity of the whole triangle when the command blends
        /// ([`Blend`]); ignored otherwise. (First, so that the command
        /// packs tightly.)
        alpha: u8,
        /// The vertices with their edges' midpoint colours.
        v: [QuadVertex; 3],
        /// Window ID and plane mask.
        state: State,
    },
    /// A textured, Z-tested triangle (either winding), seed 001 §IV.3:
    /// texture `tex` of the frame's ([`crate::frame::WithTextures`]),
    /// mapped through the vertices' `u`, `v`, `q` with the tile's
    /// perspective mode ([`crate::texture::TextureMode`]) and modulated by
    /// the Gouraud-interpolated grey `shade` (255: the texel itself).
    /// Tiles without texturing, and a `tex` past the frame's textures,
    /// draw the shade alone.
    Textured {
        /// Index of the texture.
        tex: u8,
        /// Opacity of the whole triangle when the command blends.
        alpha: u8,
        /// Light at each vertex, `0..=255`, multiplying the texel.
        shade: [u8; 3],
        /// The vertices.
        v: [crate::texture::TexVertex; 3],
        /// Window ID and plane mask.
        state: State,
    },
    /// A span with per-pixel colour and depth steps.
    Span {
        /// The span.
        span: SpanCmd,
        /// Window ID and plane mask.
        state: State,
    },
    /// A styled line (end point excluded), Z-tested like every command.
    Line {
        /// The line.
        line: crate::raster::line::LineCmd,
        /// Window ID and plane mask.
        state: State,
    },
    /// An antialiased edge of a solid, blended after the solids are drawn
    /// (seed 003 eq. 8; see [`crate::raster::line::EdgeCmd`]).
    Edge {
        /// The edge.
        edge: crate::raster::line::EdgeCmd,
        /// Window ID and plane mask.
        state: State,
    },
    /// Area fill with a flat colour: window-ID test and plane mask, no Z, no
    /// dither (a translucent fill blends and dithers like every fragment).
    Fill {
        /// Pixels to fill (clipped to the screen).
        rect: Rect,
        /// The colour.
        color: Rgb,
        /// Opacity, `0..=255`, when the command blends ([`Blend`]).
        alpha: u8,
        /// Window ID and plane mask.
        state: State,
    },
    /// Z fill: sets depth where the window-ID test passes.
    ZFill {
        /// Pixels to fill.
        rect: Rect,
        /// The depth.
        z: u16,
        /// Window ID (the plane mask is not used).
        state: State,
    },
    /// Window-ID fill: claims pixels for a window, unconditionally.
    WidFill {
        /// Pixels to claim.
        rect: Rect,
        /// The window ID.
        wid: u8,
    },
}

impl Command {
    /// A Gouraud-shaded, Z-tested triangle in window 0 (either winding).
    ///
    /// ```
    /// use tilerast::prelude::*;
    /// let v = |x: i32, y: i32| Vertex::new(Coord::from_num(x), Coord::from_num(y), 100, Rgb::new(255, 0, 0));
    /// let t = Command::triangle([v(0, 0), v(8, 0), v(0, 8)]).window(2).plane_mask(0xF800);
    /// assert_eq!(t.state(), Some(&State { wid: 2, plane_mask: 0xF800, ..State::default() }));
    /// ```
    pub const fn triangle(v: [Vertex; 3]) -> Command {
        Command::Triangle {
            v,
            state: State::new(0),
        }
    }

    /// A quadratically shaded (fast Phong) triangle in window 0, opaque.
    ///
    /// ```
    /// use tilerast::prelude::*;
    /// let q = |x: i32, y: i32| QuadVertex::new(Vertex::new(Coord::from_num(x), Coord::from_num(y), 9, Rgb::new(90, 0, 0)), Rgb::new(120, 0, 0));
    /// let t = Command::quadratic([q(0, 0), q(8, 0), q(0, 8)]);
    /// assert_eq!(t.bounds(), Some(Rect::new(0, 0, 8, 8)));
    /// assert_eq!(core::mem::size_of::<Command>(), 64);
    /// ```
    pub const fn quadratic(v: [QuadVertex; 3]) -> Command {
        Command::Quadratic {
            alpha: 255,
            v,
            state: State::new(0),
        }
    }

    /// A textured triangle in window 0, opaque, drawing texture `tex`
    /// modulated by the vertices' `shade` ([`Command::Textured`]).
    pub const fn textured(tex: u8, v: [crate::texture::TexVertex; 3], shade: [u8; 3]) -> Command {
        Command::Textured {
            tex,
            alpha: 255,
            shade,
            v,
            state: State::new(0),
        }
    }

    /// The plain vertices of a textured triangle: position, depth, shade.
    pub(crate) fn textured_vertices(
        v: &[crate::texture::TexVertex; 3],
        shade: &[u8; 3],
    ) -> [Vertex; 3] {
        [
            v[0].vertex(shade[0]),
            v[1].vertex(shade[1]),
            v[2].vertex(shade[2]),
        ]
    }

    /// A span in window 0 ([`SpanCmd`]).
    pub const fn span(span: SpanCmd) -> Command {
        Command::Span {
            span,
            state: State::new(0),
        }
    }

    /// A line in window 0 ([`crate::raster::line::LineCmd`]).
    pub const fn line(line: crate::raster::line::LineCmd) -> Command {
        Command::Line {
            line,
            state: State::new(0),
        }
    }

    /// An antialiased solid edge in window 0 ([`crate::raster::line::EdgeCmd`]).
    pub const fn edge(edge: crate::raster::line::EdgeCmd) -> Command {
        Command::Edge {
            edge,
            state: State::new(0),
        }
    }

    /// A flat fill of `rect` in window 0.
    ///
    /// ```
    /// use tilerast::prelude::*;
    /// let f = Command::fill(Rect::new(0, 0, 240, 240), Rgb::new(8, 8, 16));
    /// assert_eq!(f.bounds(), Some(Rect::new(0, 0, 240, 240)));
    /// ```
    pub const fn fill(rect: Rect, color: Rgb) -> Command {
        Command::Fill {
            rect,
            color,
            alpha: 255,
            state: State::new(0),
        }
    }

    /// A Z fill of `rect` in window 0.
    pub const fn zfill(rect: Rect, z: u16) -> Command {
        Command::ZFill {
            rect,
            z,
            state: State::new(0),
        }
    }

    /// Claims `rect` for window `wid`, unconditionally.
    pub const fn wid_fill(rect: Rect, wid: u8) -> Command {
        Command::WidFill { rect, wid }
    }

    /// The same command drawing into window `wid` (a [`Command::WidFill`]
    /// claims its pixels for `wid` instead).
    pub const fn window(mut self, wid: u8) -> Command {
        if let Command::WidFill { wid: w, .. } = &mut self {
            *w = wid;
        } else if let Some(state) = self.state_mut() {
            state.wid = wid;
        }
        self
    }

    /// The same command writing only the colour bits in `mask` (in the
    /// packed format's bits; no effect on window-ID and Z fills).
    pub const fn plane_mask(mut self, mask: u32) -> Command {
        if let Some(state) = self.state_mut() {
            state.plane_mask = mask;
        }
        self
    }

    /// The same command blended by `mode` ([`Blend`]; no effect on window-ID
    /// fills).
    pub const fn blend(mut self, mode: Blend) -> Command {
        if let Some(state) = self.state_mut() {
            state.blend = mode;
        }
        self
    }

    /// Whether `cull` drops the command: a triangle (Gouraud, quadratic or
    /// textured) whose winding on screen it culls ([`Cull`]). A frame that
    /// culls ([`Frame::cull`](crate::frame::Frame::cull)) bins no such
    /// triangle.
    #[inline]
    pub fn culled_by(&self, cull: Cull) -> bool {
        let p = match self {
            Command::Triangle { v, .. } => v.map(|v| (v.x, v.y)),
            Command::Quadratic { v, .. } => v.map(|v| (v.x, v.y)),
            Command::Textured { v, .. } => v.map(|v| (v.x, v.y)),
            _ => return false,
        };
        cull != Cull::None && {
            let q = p.map(|(x, y)| (x.to_bits(), y.to_bits()));
            cull.drops(area2_i32(q[0], q[1], q[2]))
        }
    }

    /// The command's state (window ID, plane mask, object tag); `None` for
    /// [`Command::WidFill`], which has none.
    ///
    /// ```
    /// use tilerast::prelude::*;
    /// let f = Command::fill(Rect::new(0, 0, 2, 2), Rgb::new(1, 2, 3)).window(4);
    /// assert_eq!(f.state().map(|s| s.wid), Some(4));
    /// assert_eq!(Command::WidFill { rect: Rect::new(0, 0, 2, 2), wid: 4 }.state(), None);
    /// ```
    pub const fn state(&self) -> Option<&State> {
        match self {
            Command::Triangle { state, .. }
            | Command::Quadratic { state, .. }
            | Command::Textured { state, .. }
            | Command::Span { state, .. }
            | Command::Line { state, .. }
            | Command::Edge { state, .. }
            | Command::Fill { state, .. }
            | Command::ZFill { state, .. } => Some(state),
            Command::WidFill { .. } => None,
        }
    }

    /// The command's state, to change; `None` for [`Command::WidFill`].
    pub const fn state_mut(&mut self) -> Option<&mut State> {
        match self {
            Command::Triangle { state, .. }
            | Command::Quadratic { state, .. }
            | Command::Textured { state, .. }
            | Command::Span { state, .. }
            | Command::Line { state, .. }
            | Command::Edge { state, .. }
            | Command::Fill { state, .. }
            | Command::ZFill { state, .. } => Some(state),
            Command::WidFill { .. } => None,
        }
    }

    /// Checks the command against the numeric contract.
    pub fn validate(&self) -> Result<(), Error> {
        match self {
            Command::Triangle { v, .. } => v.iter().try_for_each(Vertex::validate),
            Command::Quadratic { v, .. } => v.iter().try_for_each(|q| q.vertex().validate()),
            Command::Textured { v, .. } => v.iter().try_for_each(|t| {
                if t.q == 0 {
                    return Err(Error::Degenerate);
                }
                t.vertex(0).validate()
            }),
            Command::Span { span, .. } => span.validate(),
            Command::Line { line, .. } => line.validate(),
            Command::Edge { edge, .. } => edge.validate(),
            _ => Ok(()),
        }
    }

    /// The pixels the command can touch with coverage antialiasing: for a
    /// triangle every pixel whose cell its box meets (a sample anywhere in
    /// the cell may be inside), otherwise [`Command::bounds`].
    pub fn coverage_bounds(&self) -> Option<Rect> {
        match self {
            Command::Triangle { v, .. } => Some(crate::geom::cell_bounds(v)),
            Command::Quadratic { v, .. } => Some(crate::geom::cell_bounds(&v.map(|q| q.vertex()))),
            Command::Textured { v, .. } => Some(crate::geom::cell_bounds(&v.map(|t| t.vertex(0)))),
            _ => self.bounds(),
        }
    }

    /// Whether the command is a triangle with an edge flagged for area
    /// sampling ([`Vertex::edge_flag`]): then it can touch every pixel of
    /// its [`Self::coverage_bounds`] in tiles configured with
    /// [`AreaAa`](crate::area::AreaAa).
    ///
    /// ```
    /// use tilerast::prelude::*;
    /// let v = Vertex::new(Coord::from_num(1), Coord::from_num(1), 0, Rgb::default());
    /// let w = Vertex::new(Coord::from_num(9), Coord::from_num(2), 0, Rgb::default());
    /// assert!(!Command::triangle([v, w, v]).edge_flagged());
    /// assert!(Command::triangle([v, w.with_edge_flag(true), v]).edge_flagged());
    /// ```
    pub fn edge_flagged(&self) -> bool {
        matches!(self, Command::Triangle { v, .. } if v.iter().any(|v| v.edge_flag))
    }

    /// The screen pixels the command can touch, `None` when it touches none.
    pub fn bounds(&self) -> Option<Rect> {
        match self {
            Command::Triangle { v, .. } => crate::geom::pixel_bounds(v),
            Command::Quadratic { v, .. } => crate::geom::pixel_bounds(&v.map(|q| q.vertex())),
            Command::Textured { v, .. } => crate::geom::pixel_bounds(&v.map(|t| t.vertex(0))),
            Command::Span { span, .. } if span.len > 0 => {
                Some(Rect::new(span.x, span.y, span.len as u32, 1))
            }
            Command::Span { .. } => None,
            Command::Line { line, .. } => line.bounds(),
            Command::Edge { edge, .. } => edge.bounds(),
            Command::Fill { rect, .. }
            | Command::ZFill { rect, .. }
            | Command::WidFill { rect, .. } => (rect.w > 0 && rect.h > 0).then_some(*rect),
        }
    }
}

/// The doubled signed area of the triangle `p0 p1 p2` (sub-pixels, y
/// down): `(x1 - x0)(y2 - y0) - (y1 - y0)(x2 - x0)` in 64 bits (validated
/// coordinates differ by less than 2^18: products below 2^36; others
/// wrap, harmlessly).
#[inline(always)]
pub(crate) fn area2_i32(p0: (i32, i32), p1: (i32, i32), p2: (i32, i32)) -> i64 {
    let d = |a: i32, b: i32| a.wrapping_sub(b);
    crate::numeric::wide_mul_i(d(p1.0, p0.0), d(p2.1, p0.1))
        - crate::numeric::wide_mul_i(d(p1.1, p0.1), d(p2.0, p0.0))
}

/// `defmt` formats for the types that hold `fixed` numbers (which have none
/// of their own): coordinates are logged in 1/16 px, span values as raw
/// 16.16 bits.
#[cfg(feature = "defmt")]
mod log {
    use super::{SpanCmd, Vertex};
    use crate::geom::QuadVertex;
    use crate::raster::line::{EdgeCmd, LineCmd};
    use crate::texture::TexVertex;

    impl defmt::Format for TexVertex {
        fn format(&self, f: defmt::Formatter) {
            defmt::write!(
                f,
                "TexVertex {{ x: {}/16, y: {}/16, z: {}, u: {}/16, v: {}/16, q: {} }}",
                self.x.to_bits(),
                self.y.to_bits(),
                self.z,
                self.u,
                self.v,
                self.q
            )
        }
    }

    impl defmt::Format for QuadVertex {
        fn format(&self, f: defmt::Formatter) {
            defmt::write!(
                f,
                "QuadVertex {{ x: {}/16, y: {}/16, z: {}, color: {}, mid: {} }}",
                self.x.to_bits(),
                self.y.to_bits(),
                self.z,
                self.color,
                self.mid
            )
        }
    }

    impl defmt::Format for Vertex {
        fn format(&self, f: defmt::Formatter) {
            defmt::write!(
                f,
                "Vertex {{ x: {}/16, y: {}/16, z: {}, color: {}, alpha: {}, edge_flag: {} }}",
                self.x.to_bits(),
                self.y.to_bits(),
                self.z,
                self.color,
                self.alpha,
                self.edge_flag
            )
        }
    }

    impl defmt::Format for SpanCmd {
        fn format(&self, f: defmt::Formatter) {
            defmt::write!(
                f,
                "SpanCmd {{ x: {}, y: {}, len: {}, color: {}, dcolor: {}, z: {}, dz: {}, alpha: {} }} (16.16 bits)",
                self.x,
                self.y,
                self.len,
                self.color.map(|c| c.to_bits()),
                self.dcolor.map(|c| c.to_bits()),
                self.z.to_bits(),
                self.dz.to_bits(),
                self.alpha
            )
        }
    }

    impl defmt::Format for LineCmd {
        fn format(&self, f: defmt::Formatter) {
            let p =
                |p: (crate::numeric::Coord, crate::numeric::Coord)| (p.0.to_bits(), p.1.to_bits());
            defmt::write!(
                f,
                "LineCmd {{ p0: {}/16, p1: {}/16, z: {}, color: {}, style: {}, antialias: {} }}",
                p(self.p0),
                p(self.p1),
                self.z,
                self.color,
                self.style,
                self.antialias
            )
        }
    }

    impl defmt::Format for EdgeCmd {
        fn format(&self, f: defmt::Formatter) {
            defmt::write!(
                f,
                "EdgeCmd {{ v: {}, interior: {} }}",
                self.v,
                self.interior
            )
        }
    }
}
