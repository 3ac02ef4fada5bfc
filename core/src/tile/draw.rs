//! Drawing into a tile (pipeline stages 4 to 8 over the tile's planes):
//! each command is clipped to the tile and walked — triangles by the
//! traversal ([`crate::raster::traverse`]) one span per row, lines by their
//! Bresenham or two-point walks ([`crate::raster::line`]), antialiased edges,
//! fills — and every fragment then passes the window-ID and Z tests
//! ([`crate::fragment`]) and goes through **one store path**,
//! [`Tile::store`]: ordered dither from the address bits
//! ([`crate::fragment::dither`]), pack to the display format ([`crate::format`]),
//! plane mask, store. Coverage antialiasing diverts solids into the
//! coverage plane ([`crate::raster::coverage`]) until the tile is resolved.

use super::{Phase, Tile};
use crate::command::{Blend, Command, QuadVertex, SpanCmd, State};
use crate::config::{CommandSet, TileConfig};
use crate::error::Error;
use crate::format::{ColorPlane, Lanes, PixelFormat, Rgb};
use crate::fragment::dither::{packed_carry, packed_step, Dither, NoDither};
use crate::fragment::{BlendMode, DepthMode, DepthPlane, ShadingMode, WidMode, WidPlane};
use crate::geom::cell_bounds;
use crate::geom::{MeshVertex, Rect, SubBox};
use crate::numeric::{
    ends_in, ones_abs, steps_bounded, Precision, CLAMP_FREE_SPANS, SUBPIXEL as SUBPIXEL_I64, Z_FRAC,
};
use crate::raster::area::{AreaSetup, Cover, Cursor};
use crate::raster::coverage::{AaMode, AaPlane};
use crate::raster::span::{quantize_color, quantize_z, SpanStart};
use crate::raster::texmap::{self, TexSetup, TexSpan};
use crate::raster::traverse::{Row, Spans};
use crate::setup::{alpha_weight, fits_box, fits_i32, EdgeInt, QuadPlane, TriangleSetup};
use crate::texture::{
    TexVertex, Texture, TextureMode, PERSPECTIVE_AFFINE, PERSPECTIVE_EXACT, PERSPECTIVE_NONE,
    PERSPECTIVE_QUADRATIC,
};
use core::ops::Range;

impl<const N: usize, C, F, Z, W, D, A, P, B, S, X> Tile<N, C>
where
    C: TileConfig<
        Format = F,
        Depth = Z,
        Wid = W,
        Dither = D,
        Aa = A,
        Precision = P,
        Blending = B,
        Shading = S,
        Texturing = X,
    >,
    F: PixelFormat,
    Z: DepthMode,
    W: WidMode,
    D: Dither,
    A: AaMode,
    P: Precision,
    B: BlendMode,
    S: ShadingMode,
    X: TextureMode,
{
    /// Whether a span of one colour is a slice fill: no plane to test
    /// (Z, window ID) and no dither to vary it by address (a constant
    /// where the planes and dither are fixed by type).
    #[inline(always)]
    fn slice_fills(&self) -> bool {
        !self.depth.present() && !self.wid.present() && self.dither.log2() == 0
    }

    /// Validates and draws one command, clipped to the tile (a textured
    /// triangle without its texture: [`Self::draw_textured`]).
    pub fn draw(&mut self, cmd: &Command) -> Result<(), Error> {
        self.draw_textured(cmd, &[])
    }

    /// Validates and draws one command, clipped to the tile, a textured
    /// triangle with its texture from `textures`
    /// ([`Command::Textured`]).
    /// A command of a kind the configuration's
    /// [`CommandSet`] leaves out draws nothing
    /// and is [`Error::ConfigMismatch`].
    pub fn draw_textured(&mut self, cmd: &Command, textures: &[Texture<'_>]) -> Result<(), Error> {
        cmd.validate()?;
        self.draw_valid(cmd, textures);
        if core::mem::take(&mut self.refused) {
            return Err(Error::ConfigMismatch);
        }
        Ok(())
    }

    /// Draws a command already validated.
    ///
    /// With coverage antialiasing a frame draws its commands twice
    /// ([`Tile::finish`] between): solids merge into the coverage plane in
    /// the first pass; spans, lines, translucent commands and every command
    /// with a partial plane mask are drawn over the resolved pixels in the
    /// second, so the mask keeps the bits it protects (coverage samples hold
    /// whole colours, not planes) and a translucent command blends over the
    /// finished solids.
    /// A triangle set up, and traversed from [`Phase::Traverse`] on, but
    /// not drawn: what the frame's phase counters measure before
    /// [`Phase::All`] ([`Frame::render_until`](crate::frame::Frame::render_until)).
    pub(crate) fn draw_upto<const UPTO: u8>(&mut self, cmd: &Command) {
        if let Command::Triangle { v, .. } = cmd {
            if UPTO >= Phase::Setup as u8 {
                if fits_i32(v) {
                    self.triangle_upto::<UPTO, i32>(v);
                } else {
                    self.triangle_upto::<UPTO, i64>(v);
                }
            }
        }
    }

    pub(crate) fn draw_valid(&mut self, cmd: &Command, textures: &[Texture<'_>]) {
        if !<C::Commands as CommandSet>::draws(cmd) {
            // Not compiled in (each arm below tests the set's constant too).
            self.refused = true;
            return;
        }
        let all = <C::Commands as CommandSet>::ALL;
        if A::SAMPLES > 0 {
            // Masked and translucent solids go over the resolved pixels.
            let late = match cmd {
                Command::Triangle { state, .. }
                | Command::Quadratic { state, .. }
                | Command::Textured { state, .. }
                | Command::Fill { state, .. } => {
                    state.plane_mask & F::MASK_ALL != F::MASK_ALL
                        || (B::ALPHA && state.blend.translucent())
                }
                _ => false,
            };
            match (self.resolved, cmd) {
                (
                    false,
                    Command::Triangle { .. }
                    | Command::Quadratic { .. }
                    | Command::Textured { .. }
                    | Command::Fill { .. },
                ) if late => return,
                (
                    true,
                    Command::Triangle { .. }
                    | Command::Quadratic { .. }
                    | Command::Textured { .. }
                    | Command::Fill { .. },
                ) if late => {}
                (false, Command::Triangle { v, state }) => return self.triangle_aa(v, state),
                // Coverage samples hold one colour per fragment: Gouraud.
                (false, Command::Quadratic { v, state, .. }) if all => {
                    return self.triangle_aa(&v.map(|q| q.vertex()), state)
                }
                (
                    false,
                    Command::Textured {
                        v, shade, state, ..
                    },
                ) => return self.triangle_aa(&Command::textured_vertices(v, shade), state),
                (
                    false,
                    Command::Fill {
                        rect, color, state, ..
                    },
                ) => {
                    // The colour plane keeps the background of the samples
                    // no fragment covers until the tile is resolved.
                    let (wid, c) = (state.wid, F::pack_rgb(*color));
                    return self.for_each_pixel(rect, |t, i| {
                        if t.wid.pass(i, wid) {
                            t.color.set(i, c);
                            t.aa.fill(i, *color)
                        }
                    });
                }
                (false, Command::ZFill { rect, z, state }) => {
                    let wid = state.wid;
                    return self.for_each_pixel(rect, |t, i| {
                        if t.wid.pass(i, wid) {
                            t.aa.zfill(i, *z)
                        }
                    });
                }
                (false, Command::WidFill { .. }) => {}
                // Spans and lines go over the resolved pixels; edge
                // antialiasing is what the coverage already does.
                (true, Command::Span { .. } | Command::Line { .. }) => {}
                _ => return,
            }
        }
        match cmd {
            Command::Triangle { v, state } => self.gouraud(v, state),
            Command::Quadratic { alpha, v, state } if all => self.quadratic(v, *alpha, state),
            Command::Textured {
                tex,
                alpha,
                shade,
                v,
                state,
            } => {
                let vs = Command::textured_vertices(v, shade).map(|v| v.with_alpha(*alpha));
                match textures.get(*tex as usize) {
                    Some(texture) if X::MODE != PERSPECTIVE_NONE => {
                        self.textured(&vs, v, shade, texture, state)
                    }
                    _ => self.gouraud(&vs, state),
                }
            }
            Command::Span { span, state } if all => self.span_cmd(span, state),
            Command::Line { line, state } if all => self.line(line, state),
            Command::Edge { edge, state } if all => self.edge(edge, state),
            // Left out by the command set (refused above).
            Command::Quadratic { .. }
            | Command::Span { .. }
            | Command::Line { .. }
            | Command::Edge { .. } => {}
            Command::Fill {
                rect,
                color,
                alpha,
                state,
            } => self.fill(rect, *color, *alpha, state),
            Command::ZFill { rect, z, state } => {
                let wid = state.wid;
                self.for_each_pixel(rect, |t, i| {
                    if t.wid.pass(i, wid) {
                        t.depth.put(i, *z)
                    }
                })
            }
            Command::WidFill { rect, wid } => {
                self.for_each_row(rect, |t, r| t.wid.put_range(r, *wid))
            }
        }
    }

    /// Setup, and traversal from [`Phase::Traverse`] on, of a triangle,
    /// without drawing it.
    #[inline(always)]
    fn triangle_upto<const UPTO: u8, T: EdgeInt>(&mut self, v: &[crate::command::Vertex; 3]) {
        // As the draw does: the edges, the first covered row, then the
        // attribute planes of a triangle that covers a pixel.
        let Some(mut t) = TriangleSetup::<_, T>::edges_in(v, &SubBox::of(v)) else {
            return;
        };
        let mut rows = Spans::new(&t.e, &t.bounds, &self.area);
        if rows.next().is_some() {
            t.p = t.planes::<F>(v, false);
        }
        if UPTO >= Phase::Traverse as u8 {
            for row in rows {
                core::hint::black_box(row);
            }
        } else {
            core::hint::black_box(&t);
        }
    }

    /// A Gouraud-shaded triangle, opaque or blended by its state (one copy
    /// for plain and untextured triangles: the M0's flash).
    fn gouraud(&mut self, v: &[crate::command::Vertex; 3], st: &State) {
        if A::AREA && v.iter().any(|v| v.edge_flag) {
            // The 64-bit edges only on the Cortex-M0 (one copy of the
            // span loop for the area path in its flash).
            return if fits_i32(v) && !cfg!(target_abi = "eabi") {
                self.gouraud_area::<i32>(v, st)
            } else {
                self.gouraud_area::<i64>(v, st)
            };
        }
        if Self::plane_path(st)
            && self.plane_triangle(v.each_ref().map(MeshVertex::of).each_ref(), st)
        {
            return;
        }
        // Borrowed where it was returned: moved out of the `Option`, the
        // setup was copied once more per triangle and tile (184
        // instructions on the Cortex-M0, where `new` is out of line). The
        // attribute planes wait for a covered row.
        let b = SubBox::of(v);
        if fits_box(&b) {
            if let Some(t) = &mut TriangleSetup::<_, i32>::edges_in(v, &b) {
                self.triangle::<_, true>(t, v, st);
            }
        } else if let Some(t) = &mut TriangleSetup::<_, i64>::edges_in(v, &b) {
            self.triangle::<_, true>(t, v, st);
        }
    }

    /// A textured triangle ([`crate::texture`]): set up like a Gouraud
    /// one (edges, Z, blend weight), plus its texture coordinates.
    fn textured(
        &mut self,
        v: &[crate::command::Vertex; 3],
        tv: &[TexVertex; 3],
        shade: &[u8; 3],
        tex: &Texture<'_>,
        st: &State,
    ) {
        // The 64-bit edges only: a texel costs far more than a row's edge
        // step, and one copy of the span loops per mode fits the M0's
        // flash beside the other workloads.
        let blend = B::ALPHA && st.blend.translucent();
        if let Some(t) = &TriangleSetup::<_, i64>::new::<F>(v, blend) {
            self.textured_setup(t, &TexSetup::new(tv, shade, t, X::TOLERANCE), tex, st);
        }
    }

    #[inline(always)]
    fn textured_setup<T: EdgeInt>(
        &mut self,
        t: &TriangleSetup<F::Lanes, T>,
        ts: &TexSetup,
        tex: &Texture<'_>,
        st: &State,
    ) {
        let blend = B::ALPHA && st.blend.translucent();
        match (X::MODE, blend) {
            (PERSPECTIVE_AFFINE, false) => {
                self.textured_rows::<T, PERSPECTIVE_AFFINE, false>(t, ts, tex, st)
            }
            (PERSPECTIVE_AFFINE, true) => {
                self.textured_rows::<T, PERSPECTIVE_AFFINE, true>(t, ts, tex, st)
            }
            (PERSPECTIVE_QUADRATIC, false) => {
                self.textured_rows::<T, PERSPECTIVE_QUADRATIC, false>(t, ts, tex, st)
            }
            (PERSPECTIVE_QUADRATIC, true) => {
                self.textured_rows::<T, PERSPECTIVE_QUADRATIC, true>(t, ts, tex, st)
            }
            (_, false) => self.textured_rows::<T, PERSPECTIVE_EXACT, false>(t, ts, tex, st),
            (_, true) => self.textured_rows::<T, PERSPECTIVE_EXACT, true>(t, ts, tex, st),
        }
    }

    /// The rows of a textured triangle: per pixel the window-ID and Z
    /// tests, the texel at the span's coordinates ([`crate::raster::texmap`])
    /// times the shade, then blend (`BLEND`) and the one store path.
    #[inline(always)]
    fn textured_rows<T: EdgeInt, const MODE: u8, const BLEND: bool>(
        &mut self,
        t: &TriangleSetup<F::Lanes, T>,
        ts: &TexSetup,
        tex: &Texture<'_>,
        st: &State,
    ) {
        let ga = t.p.alpha[1];
        let zwrite = !BLEND || st.blend == Blend::AlphaZWrite;
        let mask = st.plane_mask & F::MASK_ALL;
        let d = self.dither;
        let bias = d.round_bias();
        let starts = RowStarts::new::<P, T>(t);
        let area = self.area;
        let mut sp = TexSpan::default();
        for row in Spans::new(&t.e, &t.bounds, &area) {
            let (start, a) = starts.at::<P, BLEND, T>(t, &row);
            let first = self.offset(row.x0, row.py);
            let tile = &mut *self;
            ts.span::<MODE>(&row, row.x0, &mut sp);
            let (mut z, mut a) = (start.z + (1 << (Z_FRAC - 1)), a.wrapping_add(1 << 15));
            let (mut x, mut idx) = (row.x0 as u32, first);
            let mut n = (row.x1 - row.x0) as usize;
            // Spans are clipped to the tile: saying so lets the compiler
            // drop the planes' per-pixel index checks.
            debug_assert!(first + n <= Self::CAPACITY);
            if first + n > Self::CAPACITY {
                continue;
            }
            // Runs of pixels between the quadratic mode's segment ends
            // (the whole span in the other modes), each stepping a copy of
            // the span's state that lives in registers.
            loop {
                let run = sp.run::<MODE>(n);
                let mut px = sp.px;
                // `idx + run <= first + n`, within the tile: the bound
                // says so to the compiler for the quadratic mode's later
                // runs too (no per-pixel index check: 4 instructions a
                // pixel on the M4).
                for idx in idx..(idx + run).min(Self::CAPACITY) {
                    let pass = tile.wid.pass(idx, st.wid)
                        && if zwrite {
                            tile.depth.test_and_set(idx, z)
                        } else {
                            tile.depth.test(idx, z)
                        };
                    if pass {
                        let (u, v) = texmap::coords::<MODE>(ts, &px);
                        let c = tex.sample(u, v);
                        // The shade (8.16 on the 0..255 scale) as a fraction
                        // of full scale (0.16): x 257/256 for / 255.
                        let l = ((px.l.max(0) as u32 >> 8) * 257) >> 8;
                        let src = F::lanes_modulated([c.r, c.g, c.b], l);
                        let out = if BLEND {
                            let old = F::unpack_masked(tile.color.get(idx), mask);
                            mix(src, old, a >> 16, bias, false)
                        } else {
                            src.map(|v| v + bias)
                        };
                        if mask == F::MASK_ALL {
                            tile.store::<false, _>(d, idx, x, row.py as u32, out, mask);
                        } else {
                            tile.store::<true, _>(d, idx, x, row.py as u32, out, mask);
                        }
                    }
                    texmap::step::<MODE>(&mut px);
                    z = z.wrapping_add(start.dz);
                    a = a.wrapping_add(ga);
                    x = x.wrapping_add(1);
                }
                idx += run;
                n -= run;
                if n == 0 {
                    break;
                }
                sp.px = px;
                ts.next_segment(&mut sp);
            }
        }
    }

    /// Draws a set-up triangle, opaque or blended by its state.
    #[inline(always)]
    fn triangle<T: EdgeInt, const LAZY: bool>(
        &mut self,
        t: &mut TriangleSetup<F::Lanes, T>,
        v: &[crate::command::Vertex; 3],
        st: &State,
    ) {
        self.triangle_shaded::<T, false, LAZY>(t, v, &QuadPlane::unused(), st);
    }

    /// A quadratic (fast Phong) triangle: its quadratic colour planes when
    /// the configuration compiles them ([`ShadingMode`]) and the triangle is
    /// not a sliver ([`QuadPlane::new`]); otherwise Gouraud from the vertex
    /// colours. A translucent one has one opacity.
    fn quadratic(&mut self, q: &[QuadVertex; 3], alpha: u8, st: &State) {
        let v = q.map(|q| q.vertex().with_alpha(alpha));
        let blend = B::ALPHA && st.blend.translucent();
        let b = SubBox::of(&v);
        if fits_box(&b) {
            if let Some(t) = &mut TriangleSetup::<_, i32>::new_in::<F>(&v, &b, blend) {
                self.quadratic_setup(q, &v, t, st);
            }
        } else if let Some(t) = &mut TriangleSetup::<_, i64>::new_in::<F>(&v, &b, blend) {
            self.quadratic_setup(q, &v, t, st);
        }
    }

    #[inline(always)]
    fn quadratic_setup<T: EdgeInt>(
        &mut self,
        q: &[QuadVertex; 3],
        v: &[crate::command::Vertex; 3],
        t: &mut TriangleSetup<F::Lanes, T>,
        st: &State,
    ) {
        // The opaque span's rounding bias rides in the planes (a
        // translucent span rounds in its blend instead).
        let bias = if B::ALPHA && st.blend.translucent() {
            0
        } else {
            self.dither.round_bias()
        };
        match S::QUADRATIC.then(|| QuadPlane::new::<F, T>(q, t, bias)) {
            Some(Some(p)) => self.triangle_shaded::<T, true, false>(t, v, &p, st),
            _ => self.triangle::<T, false>(t, v, st),
        }
    }

    /// A set-up triangle, opaque or blended by its state, Gouraud or (with
    /// `QUAD`) quadratic, from the vertices `v`; with `LAZY`, only its
    /// edges are set up so far.
    #[inline(always)]
    fn triangle_shaded<T: EdgeInt, const QUAD: bool, const LAZY: bool>(
        &mut self,
        t: &mut TriangleSetup<F::Lanes, T>,
        v: &[crate::command::Vertex; 3],
        q: &QuadPlane<F::Lanes>,
        st: &State,
    ) {
        if B::ALPHA && st.blend.translucent() {
            self.triangle_rows::<T, true, QUAD, LAZY>(t, v, q, st);
        } else {
            self.triangle_rows::<T, false, QUAD, LAZY>(t, v, q, st);
        }
    }

    /// The rows of a triangle, each one span; `BLEND`: through
    /// [`Self::blend_span`] with the triangle's blend-weight plane; `QUAD`:
    /// colour from the quadratic planes `q` instead of the linear ones.
    /// With `LAZY` (a triangle whose edges only are set up, from the
    /// vertices `v`) an opaque triangle's attribute planes are set up once
    /// the first covered row is found: none for a triangle that covers no
    /// pixel of the tile.
    #[inline(always)]
    fn triangle_rows<T: EdgeInt, const BLEND: bool, const QUAD: bool, const LAZY: bool>(
        &mut self,
        t: &mut TriangleSetup<F::Lanes, T>,
        v: &[crate::command::Vertex; 3],
        q: &QuadPlane<F::Lanes>,
        st: &State,
    ) {
        let area = self.area;
        if !LAZY || BLEND {
            // One copy of the traversal for translucent triangles, whose
            // span loop the copy below slowed (the M4's blend workload
            // 5,044 -> 5,107 ticks, measured).
            if LAZY {
                t.p = t.planes::<F>(v, BLEND);
            }
            let t = &*t;
            let starts = RowStarts::new::<P, T>(t);
            for row in Spans::new(&t.e, &t.bounds, &area) {
                self.triangle_row::<T, BLEND, QUAD>(t, q, &starts, &row, st);
            }
            return;
        }
        // The first row peeled off, its own copy of the row's code, then
        // the same loop as above (on the Cortex-M4 a flag tested per row
        // cost 3% of a teapot frame and one loop that takes the first row
        // first 20%: measured).
        let mut rows = Spans::new(&t.e, &t.bounds, &area);
        let Some(first) = rows.next() else {
            return;
        };
        t.p = t.planes::<F>(v, BLEND);
        let starts = RowStarts::new::<P, T>(t);
        if !QUAD
            && self.slice_fills()
            && v[0].color == v[1].color
            && v[1].color == v[2].color
            && st.plane_mask & F::MASK_ALL == F::MASK_ALL
        {
            // One colour, nothing to test or dither: every row is the
            // span loop's slice fill of the same packed value (the colour
            // planes are constant), without a row start or span entry per
            // row (host, 1,077-px flat triangles: 0.47 -> 0.36 ns/px with
            // the fill and traversal as they are now, measured).
            let (s, _) = starts.at::<P, false, T>(t, &first);
            let c = Self::pack_at(self.dither, 0, 0, s.c.map(|c| c + self.dither.round_bias()));
            for row in core::iter::once(first).chain(rows) {
                let idx = self.offset(row.x0, row.py);
                let end = idx + (row.x1 - row.x0) as usize;
                if end <= Self::CAPACITY {
                    self.color.fill(idx..end, c);
                }
            }
            return;
        }
        self.triangle_row::<T, BLEND, QUAD>(t, q, &starts, &first, st);
        for row in rows {
            self.triangle_row::<T, BLEND, QUAD>(t, q, &starts, &row, st);
        }
    }

    /// One row of a set-up triangle: its pixels from `row.x0` to `row.x1`.
    #[inline(always)]
    fn triangle_row<T: EdgeInt, const BLEND: bool, const QUAD: bool>(
        &mut self,
        t: &TriangleSetup<F::Lanes, T>,
        q: &QuadPlane<F::Lanes>,
        starts: &RowStarts<F::Lanes>,
        row: &Row,
        st: &State,
    ) {
        let (start, a) = starts.at::<P, BLEND, T>(t, row);
        let (x0, py, n) = (row.x0, row.py, row.x1 - row.x0);
        let start = if QUAD {
            let (c, dc) = q.at(x0, py);
            SpanStart { c, dc, ..start }
        } else {
            start
        };
        if BLEND {
            self.blend_span::<true, QUAD>(x0, py, n, start, q.ddc, (a, t.p.alpha[1]), st);
        } else {
            self.span_with::<QUAD, false>(x0, py, n, start, q.ddc, st);
        }
    }

    /// A Gouraud triangle whose flagged edges are area-sampled
    /// ([`crate::area`]): per row, the edge pixels at each end through
    /// [`Self::area_pixel`], the fully covered run between them through the
    /// opaque span loop exactly as an aliased triangle's row. A translucent
    /// one goes pixel by pixel (its opacity times the coverage), which
    /// keeps one copy of the span loop here.
    fn gouraud_area<T: EdgeInt>(&mut self, v: &[crate::command::Vertex; 3], st: &State) {
        let Some(s) = AreaSetup::new(v) else { return };
        let area = self.area;
        let Some(cells) = cell_bounds(v).intersect(&area) else {
            return;
        };
        let blend = B::ALPHA && st.blend.translucent();
        let t = if blend {
            None
        } else {
            TriangleSetup::<_, T>::new::<F>(v, false)
        };
        let starts = t.as_ref().map(RowStarts::new::<P, T>);
        let mut rows = t
            .as_ref()
            .map(|t| Spans::new(&t.e, &t.bounds, &area).peekable());
        let (lo, hi) = (cells.x as i64, cells.x1());
        for py in cells.y as i64..cells.y1() {
            let row = rows.as_mut().and_then(|r| r.next_if(|r| r.py == py));
            let (Some(r), Some(t), Some(starts)) = (row, &t, &starts) else {
                // No pixel centre inside on this row, or a translucent
                // triangle: every covered pixel through the edge path.
                self.area_walk::<true>(&s, lo, py, hi - lo, None, st);
                continue;
            };
            // Inside the centres' run: edge pixels at each end, then the
            // fully covered run between them through the span loop.
            let xa =
                r.x0 + self.area_walk::<true>(&s, r.x0, py, r.x1 - r.x0, Some(Cover::Full), st);
            let xb =
                r.x1 - self.area_walk::<false>(&s, r.x1 - 1, py, r.x1 - xa, Some(Cover::Full), st);
            if xb > xa {
                let inner = Row {
                    x0: xa,
                    x1: xb,
                    ..r
                };
                self.triangle_row::<T, false, false>(t, &QuadPlane::unused(), starts, &inner, st);
            }
            // The covered pixels are one run: walk out from the centres'.
            self.area_walk::<false>(&s, r.x0 - 1, py, r.x0 - lo, Some(Cover::Out), st);
            self.area_walk::<true>(&s, r.x1, py, hi - r.x1, Some(Cover::Out), st);
        }
    }

    /// Walks at most `n` pixels of row `y` from `x`, rightwards (`RIGHT`)
    /// or leftwards,
    /// drawing the covered ones through [`Self::area_pixel`], until a pixel
    /// stands as `stop`; returns the pixels walked before it.
    // Inlined where flash is plenty (the Cortex-M4; not measured apart:
    // the change came with the polygon's, together 40,199 -> 35,592
    // ticks on the area-sampled workload); one copy per direction on the
    // soft-float Cortex-M0, whose 256 KB hold every workload only so.
    #[cfg_attr(target_abi = "eabi", inline(never))]
    #[cfg_attr(not(target_abi = "eabi"), inline(always))]
    fn area_walk<const RIGHT: bool>(
        &mut self,
        s: &AreaSetup,
        x: i64,
        y: i64,
        n: i64,
        stop: Option<Cover>,
        st: &State,
    ) -> i64 {
        if n <= 0 {
            return 0;
        }
        let mut c = s.cursor(x, y);
        for k in 0..n {
            let cover = s.cover(&c);
            if Some(cover) == stop {
                return k;
            }
            if cover != Cover::Out {
                self.area_pixel(s, &c, if RIGHT { x + k } else { x - k }, y, st);
            }
            s.step::<RIGHT>(&mut c);
        }
        n
    }

    /// One edge pixel of an area-sampled triangle: its colour blended by
    /// its coverage (times its opacity when the command blends), after the
    /// window-ID and Z tests; depth written where the centre is inside.
    fn area_pixel(&mut self, s: &AreaSetup, c: &Cursor, x: i64, y: i64, st: &State) {
        let translucent = B::ALPHA && st.blend.translucent();
        let Some(p) = s.pixel(c, translucent) else {
            return;
        };
        let (w, zwrite) = if translucent {
            (
                (p.w as i32 * p.alpha as i32 + 127) / 255,
                p.inside && st.blend == Blend::AlphaZWrite,
            )
        } else {
            (p.w as i32, p.inside)
        };
        let z = (p.z as i32) << Z_FRAC;
        self.blend(x, y, lanes::<F>(p.color), w, z, zwrite, st);
    }

    /// A triangle through the coverage plane: one fragment per pixel of
    /// the tile it covers any sample of ([`crate::raster::coverage::fragments`]).
    fn triangle_aa(&mut self, v: &[crate::command::Vertex; 3], st: &State) {
        let a = self.area;
        let ztest = self.depth.present();
        crate::raster::coverage::fragments::<A::Pattern>(v, &a, |px, py, m, color, z| {
            let i = self.offset(px, py);
            if self.wid.pass(i, st.wid) {
                self.aa.fragment(i, m, |k| z.at(k), ztest, color, st.tag);
            }
        });
    }

    fn line(&mut self, l: &crate::raster::line::LineCmd, st: &State) {
        let Some(s) = l.setup() else { return };
        let a = self.area;
        let (lo, hi, mlo, mhi) = if s.y_major {
            (a.y as i64, a.y1(), a.x as i64, a.x1())
        } else {
            (a.x as i64, a.x1(), a.y as i64, a.y1())
        };
        let c = lanes::<F>(l.color);
        let xy = |major: i64, minor: i64| {
            if s.y_major {
                (minor, major)
            } else {
                (major, minor)
            }
        };
        if l.antialias {
            s.walk_wu(lo, hi, |k, major, minor, w0, w1, z| {
                if l.style.on(k) {
                    for (m, w) in [(minor, w0), (minor + 1, w1)] {
                        if w > 0 && (mlo..mhi).contains(&m) {
                            let (x, y) = xy(major, m);
                            self.blend(x, y, c, w, z, false, st);
                        }
                    }
                }
            });
        } else {
            let dc = c.map(|_| 0);
            s.walk(lo, hi, |k, major, minor, z| {
                if (mlo..mhi).contains(&minor) && l.style.on(k) {
                    let (x, y) = xy(major, minor);
                    self.span(x, y, 1, SpanStart { c, dc, z, dz: 0 }, st);
                }
            });
        }
    }

    /// Edge antialiasing (seed 003 eq. 8): the outside pixel along the
    /// edge gets `I_b + (I_o - I_b) d` through [`Self::blend`], with `I_o`
    /// interpolated along the edge's major axis from the vertex colours.
    /// The colour DDA starts at the edge's first column whatever the tile
    /// (so tiling cannot change it) and is clamped to the two vertex colours,
    /// which the end columns' centres may lie beyond.
    fn edge(&mut self, e: &crate::raster::line::EdgeCmd, st: &State) {
        let Some(s) = e.setup() else { return };
        let a = self.area;
        let (lo, hi, mlo, mhi) = if s.y_major {
            (a.y as i64, a.y1(), a.x as i64, a.x1())
        } else {
            (a.x as i64, a.x1(), a.y as i64, a.y1())
        };
        let [ca, cb] = s.ends(e.v.map(|v| lanes::<F>(v.color)));
        let (len, t0) = s.extent();
        // Colour at the first column's centre, t0 sub-pixels from a, and its
        // step per column: |cb - ca| < 2^24, so products stay below 2^42.
        let c0 = ca.zip(cb, |a, b| {
            (a as i64 + crate::numeric::div_round(t0 * (b - a) as i64, len)) as i32
        });
        let dc = ca.zip(cb, |a, b| {
            crate::numeric::div_round(SUBPIXEL_I64 * (b - a) as i64, len) as i32
        });
        let (cmin, cmax) = (ca.zip(cb, i32::min), ca.zip(cb, i32::max));
        let up = e.interior_up(&s);
        s.walk_edge(up, lo, hi, |major, minor, w, k, z| {
            if (mlo..mhi).contains(&minor) {
                let c = c0
                    .zip(dc, |v, d| v.wrapping_add((k as i32).wrapping_mul(d)))
                    .zip(cmin, i32::max)
                    .zip(cmax, i32::min);
                let (x, y) = if s.y_major {
                    (minor, major)
                } else {
                    (major, minor)
                };
                self.blend(x, y, c, w, z, false, st);
            }
        });
    }

    /// Blends colour `c` (output scale, 16 fraction bits) with weight `w`
    /// (in 1/256) over the pixel at screen `(x, y)` — seed 003 eq. 7,
    /// `C = C_bg + (C_line - C_bg) w` — after the window-ID test and a
    /// read-only Z test (partial coverage does not claim depth), then
    /// dither, pack and plane mask as every fragment. With `zwrite` the Z
    /// test writes (an area-sampled pixel whose centre is inside).
    #[allow(clippy::too_many_arguments)]
    fn blend(&mut self, x: i64, y: i64, c: F::Lanes, w: i32, z: i32, zwrite: bool, st: &State) {
        let idx = self.offset(x, y);
        let z = z + (1 << (Z_FRAC - 1));
        let pass = self.wid.pass(idx, st.wid)
            && if zwrite {
                self.depth.test_and_set(idx, z)
            } else {
                self.depth.test(idx, z)
            };
        if !pass {
            return;
        }
        let mask = st.plane_mask & F::MASK_ALL;
        let old = F::unpack_masked(self.color.get(idx), mask);
        let v = mix(c, old, w, self.dither.round_bias(), false);
        self.store::<true, _>(self.dither, idx, x as u32, y as u32, v, mask);
    }

    /// Draws `n >= 1` translucent pixels from screen `(x, y)` (clipped by
    /// the caller): the span DDA of [`Self::span`] plus the blend weight
    /// `(a, da)` (1/256 with 16 fraction bits), each fragment
    /// `C_dst + (C_src - C_dst) w` ([`crate::command::Blend`]) after the
    /// window-ID test and a Z test that writes only for
    /// [`Blend::AlphaZWrite`]. Fills pass `ZTEST = false`: they have no depth.
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    fn blend_span<const ZTEST: bool, const QUAD: bool>(
        &mut self,
        x: i64,
        y: i64,
        n: i64,
        s: SpanStart<F::Lanes>,
        ddc: F::Lanes,
        (a, da): (i32, i32),
        st: &State,
    ) {
        let idx = self.offset(x, y);
        let s = SpanStart {
            z: s.z + (1 << (Z_FRAC - 1)),
            ..s
        };
        // The weight rounds to nearest: bias folded into the start.
        let a = (a.wrapping_add(1 << 15), da);
        let mask = st.plane_mask & F::MASK_ALL;
        let (xs, ys, n) = (x as u32, y as u32, n as usize);
        let (w, q) = (st.wid, (s, ddc));
        match (ZTEST, st.blend == Blend::AlphaZWrite, QUAD) {
            (false, _, _) => self.span_masked::<BLEND_NO_Z>(idx, xs, ys, n, q, a, w, mask),
            (true, false, false) => self.span_masked::<BLEND>(idx, xs, ys, n, q, a, w, mask),
            (true, true, false) => self.span_masked::<BLEND_Z_WRITE>(idx, xs, ys, n, q, a, w, mask),
            (true, false, true) => {
                self.span_masked::<{ BLEND | QUAD_STEP }>(idx, xs, ys, n, q, a, w, mask)
            }
            (true, true, true) => {
                self.span_masked::<{ BLEND_Z_WRITE | QUAD_STEP }>(idx, xs, ys, n, q, a, w, mask)
            }
        }
    }

    /// [`Self::span_loop`] with or without the plane mask.
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    fn span_masked<const MODE: u8>(
        &mut self,
        idx: usize,
        x: u32,
        y: u32,
        n: usize,
        s: (SpanStart<F::Lanes>, F::Lanes),
        a: (i32, i32),
        wid: u8,
        mask: u32,
    ) {
        if mask == F::MASK_ALL {
            self.span_loop::<MODE, false>(idx, x, y, n, s, a, wid, mask);
        } else {
            self.span_loop::<MODE, true>(idx, x, y, n, s, a, wid, mask);
        }
    }

    /// The span loop every span ends in: window-ID test, Z test, then the
    /// one store path. `MODE` is [`OPAQUE`] (Z test and write, the fragment
    /// replaces the pixel) or a translucent mode ([`BLEND_NO_Z`],
    /// [`BLEND`], [`BLEND_Z_WRITE`]: the fragment blends over the pixel
    /// with the weight `a`, stepped by `da`, which opaque spans leave
    /// unused and the compiler removes). With [`QUAD_STEP`] in `MODE` the
    /// colour steps by second-order forward differences: `dc` itself grows
    /// by `ddc` every pixel (quadratic triangles, [`QuadPlane`]).
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    fn span_loop<const MODE: u8, const MASKED: bool>(
        &mut self,
        idx: usize,
        x: u32,
        y: u32,
        n: usize,
        (s, ddc): (SpanStart<F::Lanes>, F::Lanes),
        (a, da): (i32, i32),
        wid: u8,
        mask: u32,
    ) {
        let bias = self.dither.round_bias();
        let (mut c, mut dc, z) = (s.c, s.dc, s.z);
        let end = idx + n;
        if Self::scaled_blend::<MODE, D>(self.dither) {
            c = c.map(|v| v.wrapping_add(bias).wrapping_shl(8));
            dc = dc.map(|v| v.wrapping_shl(8));
        }
        // Callers clip every span to the tile; saying so here lets the
        // compiler drop the per-pixel index checks of the planes.
        debug_assert!(end <= Self::CAPACITY);
        if end > Self::CAPACITY {
            return;
        }
        if MODE & !IN_RANGE == OPAQUE
            && !MASKED
            && self.slice_fills()
            && (0..F::Lanes::LEN).all(|i| dc.lane(i) == 0)
        {
            // A flat span with nothing to test or dither: one colour,
            // stored as a slice fill (flat-shaded triangles and span
            // commands; host: see `reports/frames.md`).
            let c = Self::pack_at(self.dither, x, y, c);
            self.color.fill(idx..end, c);
            return;
        }
        let st = SpanState { c, dc, ddc, z, a };
        let steps = (s.dz, da);
        // Known in range: a span's values within half an output unit of
        // convex combinations of in-range vertex values, which rounding to
        // nearest (no dither's carry) keeps in range.
        let known = MODE & IN_RANGE != 0 && self.dither.carry_max() == 0;
        if CLAMP_FREE_SPANS
            && MODE & !IN_RANGE == OPAQUE
            && !MASKED
            && (known || n > 2 && Self::in_range(self.dither, self.depth.present(), &st, s.dz, n))
        {
            // Every value in range: the loop without its clamps (the
            // micro:bit's large Gouraud + Z workload 77.0 -> 60.3
            // instructions a pixel, the per-span test included: measured).
            self.span_pixels::<MODE, MASKED, false>(idx..end, x, y, st, steps, wid, mask);
        } else if MODE & QUAD_STEP != 0 {
            self.span_pixels_apart::<MODE, MASKED>(idx..end, (x, y), st, steps, (wid, mask));
        } else {
            self.span_pixels::<MODE, MASKED, true>(idx..end, x, y, st, steps, wid, mask);
        }
    }

    /// [`Self::span_pixels`] with its clamps, out of line: a quadratic
    /// span steps three more values a pixel (`dc += ddc`), which do not
    /// fit the registers the row loop around it leaves (the M4 spilled
    /// 7.5 of its 27 instructions a pixel to the stack, inlined); a call
    /// a span saves the row loop's registers once instead. Inlined on the
    /// Cortex-M0 (`eabi`: soft float), whose loop spills either way and
    /// pays for the call (its fast-Phong workload 12,861 -> 13,152 ticks
    /// out of line: measured).
    #[cfg_attr(target_abi = "eabi", inline(always))]
    #[cfg_attr(not(target_abi = "eabi"), inline(never))]
    fn span_pixels_apart<const MODE: u8, const MASKED: bool>(
        &mut self,
        range: Range<usize>,
        (x, y): (u32, u32),
        st: SpanState<F::Lanes>,
        steps: (i32, i32),
        (wid, mask): (u8, u32),
    ) {
        self.span_pixels::<MODE, MASKED, true>(range, x, y, st, steps, wid, mask);
    }

    /// Whether a translucent span of `MODE` steps its colour scaled:
    /// Gouraud spans of a format whose channels fit 7 bits step their
    /// colour scaled by 2^8, the rounding bias folded in ([`mix`]): the
    /// same values modulo 2^32, scaled, and below 2^31 at every pixel
    /// (convex combinations of the vertices' colours, 5.24 at most).
    /// Quadratic colour may overshoot its vertices, so it keeps the plain
    /// form, whose 32-bit products hold values 2^8 times larger.
    #[inline(always)]
    fn scaled_blend<const MODE: u8, Dd: Dither>(d: Dd) -> bool {
        MODE & !(QUAD_STEP | IN_RANGE) != OPAQUE
            && MODE & QUAD_STEP == 0
            && d.round_bias() >= 1 << 8
            && (0..F::Lanes::LEN).all(|i| F::MAX.lane(i) < 128)
    }

    /// Whether an opaque linear span's colour lanes and depth stay, at
    /// each of its `n` pixels, where the store's clamps cannot act
    /// ([`Self::lane_limit`], depth in `0..2^30`): the steps are bounded
    /// and both ends in range ([`ends_in`]).
    #[inline(always)]
    fn in_range(dither: D, depth: bool, st: &SpanState<F::Lanes>, dz: i32, n: usize) -> bool {
        let n = u32::try_from(n).unwrap_or(u32::MAX);
        let mut m = if depth { ones_abs(dz) } else { 0 };
        let mut ends = !depth || ends_in(st.z, dz, n, 1 << 30);
        // Through `from_fn`, unrolled by hand: at `opt-level = "s"` (the
        // micro:bit) a loop over the lanes stays a loop, each lane's
        // limit computed in it (measured).
        F::Lanes::from_fn(|i| {
            let (v, d) = (st.c.lane(i), st.dc.lane(i));
            m |= ones_abs(d);
            ends &= ends_in(v, d, n, Self::lane_limit(dither, i));
            0
        });
        ends && steps_bounded(m, n)
    }

    /// The pixels `range` of [`Self::span_loop`] from screen `(x, y)`: per
    /// pixel the window-ID and Z tests, the blend, the one store path,
    /// then every value steps (after the last pixel too: a dead step is
    /// cheaper than a second exit test). With `CLAMP` false (an opaque
    /// span [`Self::in_range`]) the Z test and the store skip their clamps.
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    fn span_pixels<const MODE: u8, const MASKED: bool, const CLAMP: bool>(
        &mut self,
        range: Range<usize>,
        x: u32,
        y: u32,
        st: SpanState<F::Lanes>,
        steps: (i32, i32),
        wid: u8,
        mask: u32,
    ) {
        // A dither chosen at run time ([`Dither::VARIES`]) at level 0 takes
        // the loop of `NoDither` (the same numbers: no carry, the same
        // rounding), whose stores add nothing: the simulator's undithered
        // scenes cost what they did when the dither was a type.
        if D::VARIES && self.dither.log2() == 0 {
            self.span_pixels_with::<MODE, MASKED, CLAMP, NoDither>(
                NoDither::NEW,
                range,
                x,
                y,
                st,
                steps,
                wid,
                mask,
            );
        } else {
            let d = self.dither;
            self.span_pixels_with::<MODE, MASKED, CLAMP, D>(d, range, x, y, st, steps, wid, mask);
        }
    }

    /// [`Self::span_pixels`] with dither `d` (the tile's, read once: a
    /// value the stores cannot change).
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    fn span_pixels_with<const MODE: u8, const MASKED: bool, const CLAMP: bool, Dd: Dither>(
        &mut self,
        d: Dd,
        range: Range<usize>,
        mut x: u32,
        y: u32,
        SpanState {
            mut c,
            mut dc,
            ddc,
            mut z,
            mut a,
        }: SpanState<F::Lanes>,
        (dz, da): (i32, i32),
        wid: u8,
        mask: u32,
    ) {
        let blend = MODE & !(QUAD_STEP | IN_RANGE);
        let bias = d.round_bias();
        let scaled = Self::scaled_blend::<MODE, Dd>(d);
        let mut row = d.packed_row(x, y);
        for idx in range {
            let pass = self.wid.pass(idx, wid)
                && match blend {
                    BLEND_NO_Z => true,
                    BLEND => self.depth.test(idx, z),
                    _ if CLAMP => self.depth.test_and_set(idx, z),
                    _ => self.depth.test_and_set_in_range(idx, z),
                };
            if pass {
                let v = if blend == OPAQUE {
                    c
                } else {
                    let raw = self.color.get(idx);
                    let old = if MASKED {
                        F::unpack_masked(raw, mask)
                    } else {
                        F::unpack(raw)
                    };
                    mix(c, old, a >> 16, bias, scaled)
                };
                let carry = if d.packed() {
                    packed_carry(row)
                } else {
                    d.carry(x, y)
                };
                if CLAMP {
                    self.store_carry::<MASKED, false>(idx, carry, v, mask);
                } else {
                    self.store_carry::<MASKED, true>(idx, carry, v, mask);
                }
            }
            row = packed_step(row);
            x = x.wrapping_add(1);
            c = c.zip(dc, |v, d| v.wrapping_add(d));
            if MODE & QUAD_STEP != 0 {
                dc = dc.zip(ddc, |d, dd| d.wrapping_add(dd));
            }
            z = z.wrapping_add(dz);
            if blend != OPAQUE {
                a = a.wrapping_add(da);
            }
        }
    }

    fn fill(&mut self, rect: &Rect, color: Rgb, alpha: u8, st: &State) {
        if B::ALPHA && st.blend.translucent() {
            // Row by row through the translucent span loop, without Z.
            let Some(r) = rect.intersect(&self.area) else {
                return;
            };
            let s = SpanStart {
                c: lanes::<F>(color),
                dc: F::Lanes::from_fn(|_| 0),
                z: 0,
                dz: 0,
            };
            for y in r.y as i64..r.y1() {
                let a = (alpha_weight(alpha), 0);
                self.blend_span::<false, false>(r.x as i64, y, r.w as i64, s, s.dc, a, st);
            }
            return;
        }
        let c = F::pack_rgb(color);
        let mask = st.plane_mask & F::MASK_ALL;
        let wid = st.wid;
        if mask == F::MASK_ALL {
            self.fill_packed::<false>(rect, c, mask, wid);
        } else {
            self.fill_packed::<true>(rect, c, mask, wid);
        }
    }

    fn fill_packed<const MASKED: bool>(&mut self, rect: &Rect, c: u32, mask: u32, wid: u8) {
        if !MASKED && !self.wid.present() {
            // Nothing to test or keep: whole rows at once.
            return self.for_each_row(rect, |t, r| t.color.fill(r, c));
        }
        self.for_each_pixel(rect, |t, i| {
            if t.wid.pass(i, wid) {
                t.put_packed::<MASKED>(i, c, mask)
            }
        });
    }

    /// Calls `f(self, index)` for each tile pixel inside `rect`.
    #[inline]
    pub(super) fn for_each_pixel(&mut self, rect: &Rect, mut f: impl FnMut(&mut Self, usize)) {
        self.for_each_row(rect, |t, r| {
            for i in r {
                f(t, i);
            }
        });
    }

    /// Calls `f(self, indices)` for each row of tile pixels inside `rect`.
    #[inline]
    fn for_each_row(&mut self, rect: &Rect, mut f: impl FnMut(&mut Self, Range<usize>)) {
        let Some(r) = rect.intersect(&self.area) else {
            return;
        };
        let a = self.area;
        for y in 0..r.h {
            let row = ((r.y - a.y) as u32 + y) * a.w + (r.x - a.x) as u32;
            let row = row as usize;
            f(self, row..row + r.w as usize);
        }
    }

    /// Draws `n >= 1` pixels from screen `(x, y)`, which the caller has
    /// clipped to this tile.
    #[inline(always)]
    pub(crate) fn span(&mut self, x: i64, y: i64, n: i64, s: SpanStart<F::Lanes>, st: &State) {
        self.span_with::<false, false>(x, y, n, s, s.dc, st);
    }

    /// [`Self::span`], with `QUAD`: the colour step `s.dc` grows by `ddc`
    /// every pixel.
    #[inline(always)]
    pub(crate) fn span_with<const QUAD: bool, const KNOWN: bool>(
        &mut self,
        x: i64,
        y: i64,
        n: i64,
        s: SpanStart<F::Lanes>,
        ddc: F::Lanes,
        st: &State,
    ) {
        let idx = self.offset(x, y);
        let bias = self.dither.round_bias();
        let s = SpanStart {
            // A quadratic span's colour has it already ([`QuadPlane::new`]).
            c: if QUAD { s.c } else { s.c.map(|v| v + bias) },
            z: s.z + (1 << (Z_FRAC - 1)),
            ..s
        };
        let mask = st.plane_mask & F::MASK_ALL;
        // Screen addresses are non-negative inside a tile; only their low
        // bits reach the dither.
        let (xs, ys) = (x as u32, y as u32);
        let n = n as usize;
        let (q, w) = ((s, ddc), st.wid);
        match (QUAD, KNOWN) {
            (true, _) => {
                self.span_masked::<{ OPAQUE | QUAD_STEP }>(idx, xs, ys, n, q, (0, 0), w, mask)
            }
            (false, true) => {
                self.span_masked::<{ OPAQUE | IN_RANGE }>(idx, xs, ys, n, q, (0, 0), w, mask)
            }
            (false, false) => self.span_masked::<OPAQUE>(idx, xs, ys, n, q, (0, 0), w, mask),
        }
    }

    /// The span command: clipped to the tile. Its values are converted to
    /// the DDA formats at a restart point that does not depend on the tiling
    /// (its first pixel at or right of `min(tile.x, 0)`, exactly, from the
    /// command's own 16.16 values) and advanced from there to the tile, so a
    /// span drawn across tiles equals the span drawn whole.
    pub(crate) fn span_cmd(&mut self, s: &SpanCmd, st: &State) {
        let a = self.area;
        if (s.y as i64) < a.y as i64 || s.y as i64 >= a.y1() {
            return;
        }
        let x0 = (s.x as i64).max(a.x as i64);
        let x1 = (s.x as i64 + s.len as i64).min(a.x1());
        if x0 >= x1 {
            return;
        }
        let xr = (s.x as i64).max((a.x as i64).min(0));
        let k = xr - s.x as i64;
        let at = |start: i64, step: i64| start + k * step;
        let rgb = |f: &dyn Fn(usize) -> i64| [f(0), f(1), f(2)];
        // 16.16 inputs to the DDA formats (colour: output scale x.16; Z: 16.14).
        let c = F::lanes_from_rgb(rgb(&|i| {
            at(s.color[i].to_bits() as i64, s.dcolor[i].to_bits() as i64)
        }));
        let dc = F::lanes_from_rgb(rgb(&|i| s.dcolor[i].to_bits() as i64));
        let zshift = 16 - Z_FRAC;
        let z = (at(s.z.to_bits() as i64, s.dz.to_bits() as i64) >> zshift) as i32;
        let dz = crate::numeric::div_round(s.dz.to_bits() as i64, 1 << zshift) as i32;
        let start = SpanStart { c, dc, z, dz }
            .quantized::<P>()
            .advanced(x0 - xr);
        if B::ALPHA && st.blend.translucent() {
            let a = (alpha_weight(s.alpha), 0);
            self.blend_span::<true, false>(x0, s.y as i64, x1 - x0, start, start.dc, a, st);
        } else {
            self.span(x0, s.y as i64, x1 - x0, start, st);
        }
    }
}

/// What a span loop steps per pixel ([`Tile::span_loop`]): colour `c`
/// and its step `dc` (which grows by `ddc` with [`QUAD_STEP`]), depth
/// `z`, blend weight `a`.
struct SpanState<L> {
    c: L,
    dc: L,
    ddc: L,
    z: i32,
    a: i32,
}

/// Span-loop modes ([`Tile::span_loop`]): opaque (Z test and write, the
/// bias already in the colour start); translucent without Z (fills), with
/// the Z test, with the Z test and write.
const OPAQUE: u8 = 0;
const BLEND_NO_Z: u8 = 1;
const BLEND: u8 = 2;
const BLEND_Z_WRITE: u8 = 3;
/// Added to a span-loop mode: second-order colour stepping.
const QUAD_STEP: u8 = 4;
/// Added to [`OPAQUE`]: every value of the span is known to lie where the
/// store's clamps cannot act once rounded to nearest (the plane contract's
/// spans: `crate::tile::mesh`), so without a dither the loop skips both
/// the clamps and the check ([`Tile::in_range`]).
pub(super) const IN_RANGE: u8 = 8;

/// A colour in the output channel scale with [`COLOR_FRAC`](crate::numeric::COLOR_FRAC) fraction bits.
#[inline(always)]
fn lanes<F: PixelFormat>(c: Rgb) -> F::Lanes {
    F::lanes_from_rgb8([c.r, c.g, c.b])
}

/// `C_dst + (C_src - C_dst) w + bias` per lane: `src` in the output scale
/// with [`COLOR_FRAC`](crate::numeric::COLOR_FRAC) fraction bits, `dst` unpacked (whole output units),
/// `w` in 1/256 (`0..=256`). Dropping 8 of the source's 16 fraction bits
/// keeps the products within `i32` and costs less than 2^-8 of an output
/// unit. Computed as `(src >> 8) w + bias + dst (256 - w) 2^8`: since
/// `dst 2^16` is a multiple of 2^8 this equals
/// `dst 2^16 + ((src - dst 2^16) >> 8) w + bias` exactly, in two
/// multiply-accumulates per lane (the Cortex-M's `MLA`) instead of a
/// subtract, a multiply and two adds (measured: see `reports/targets.md`).
///
/// `scaled` (formats whose channels are below 2^7, RGB565 and smaller):
/// `src` is `(C + bias) 2^8`, so its top halfword is `(C >> 8) + bias / 2^8`
/// and the source product is one `SMLATT` on the Cortex-M4 (top halfword
/// times top halfword, the weight being the top of the 8.16 weight plane),
/// and the bias is split between the two weights:
/// `bias = (bias / 2^8) w + (256 - w) bias / 2^8`, the first part riding
/// in `src`, the second, `k2`, as the accumulator of `d k` (one `MLA`).
/// The same integer as the unscaled form for every `w` (a bias of at
/// least 2^8, a multiple of it: every dither); the Cortex-M4's translucent
/// pixel 40 -> 37 instructions with the Z test in 16.14
/// (`ZPlane::test`), the workload's blended / opaque ratio 1.67 -> 1.50
/// (`reports/targets.md`).
#[inline(always)]
fn mix<L: Lanes>(src: L, dst: L, w: i32, bias: i32, scaled: bool) -> L {
    let k = (256 - w) << 8;
    let k2 = (256 - w) * (bias >> 8);
    src.zip(dst, |s, d| {
        if scaled {
            ((s >> 16) as i16 as i32) * (w as i16 as i32) + (d * k + k2)
        } else {
            (s >> 8) * w + bias + d * k
        }
    })
}

/// Where each row of a set-up triangle starts: the DDA start (colour, Z)
/// and the blend weight at the row's first pixel in the tile — the same
/// values whichever tile asks. Built once per triangle and tile; the row
/// loops call [`RowStarts::at`] inline (no closure per row: the M4 spent
/// 100 instructions a row on the call).
struct RowStarts<L: Lanes> {
    /// Small triangles: the anchored planes, rounded once to the DDA's
    /// precision; each row's start is `c + i gc + j gcy` (modulo 2^32).
    /// The blend weight keeps every fraction bit (it is not a DDA channel
    /// of the seed's datapath widths).
    plane: SpanStart<L>,
    gcy: L,
    gzy: i32,
    ax: i64,
    ay: i64,
}

impl<L: Lanes> RowStarts<L> {
    #[inline(always)]
    fn new<P: Precision, T: EdgeInt>(t: &TriangleSetup<L, T>) -> Self {
        RowStarts {
            plane: SpanStart {
                c: t.p.c,
                dc: t.p.gc,
                z: t.p.z,
                dz: t.p.gz,
            }
            .quantized::<P>(),
            gcy: quantize_color::<P, _>(t.p.gcy),
            gzy: quantize_z::<P>(t.p.gzy),
            ax: t.bounds.x as i64,
            ay: t.bounds.y as i64,
        }
    }

    /// The DDA start and (with `BLEND`) the blend weight at `row.x0`.
    #[inline(always)]
    fn at<P: Precision, const BLEND: bool, T: EdgeInt>(
        &self,
        t: &TriangleSetup<L, T>,
        row: &Row,
    ) -> (SpanStart<L>, i32) {
        let Row {
            py, xr, x0, e1, e2, ..
        } = *row;
        let [a_anchor, ga, gay] = t.p.alpha;
        if T::EXACT_ROWS {
            // Restart from the plane equation at xr, then advance to x0
            // by multiplication: exactly the values x0 - xr DDA steps
            // give, so the output does not depend on the tiling.
            let (c, z) = t.start(e1, e2);
            let k = x0 - xr;
            let a = if BLEND {
                t.alpha_start(e1, e2)
                    .wrapping_add((k as i32).wrapping_mul(ga))
            } else {
                0
            };
            let s = SpanStart {
                c,
                dc: t.p.gc,
                z,
                dz: t.p.gz,
            };
            (s.quantized::<P>().advanced(k), a)
        } else {
            let j = (py - self.ay) as i32;
            let s = SpanStart {
                c: self
                    .plane
                    .c
                    .zip(self.gcy, |c, g| c.wrapping_add(j.wrapping_mul(g))),
                z: self.plane.z.wrapping_add(j.wrapping_mul(self.gzy)),
                ..self.plane
            };
            let i = (x0 - self.ax) as i32;
            let a = if BLEND {
                a_anchor
                    .wrapping_add(j.wrapping_mul(gay))
                    .wrapping_add(i.wrapping_mul(ga))
            } else {
                0
            };
            (s.advanced(x0 - self.ax), a)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::Planes;
    use crate::format::{Rgb444Format, Rgb565Format};
    use crate::fragment::dither::{Bayer8, NoDither};
    use crate::fragment::{Depth16, Depth32, NoWid};
    use crate::numeric::xorshift;
    use crate::tile::Clear;

    /// The opaque span loop's two paths give the same pixels and depths:
    /// with the clamps, and without them on the spans it finds in range
    /// ([`Tile::in_range`]), whose values are chosen around every limit
    /// (lanes and depth at 0 and at their bounds, steps from none to
    /// `i32::MIN`, spans up to the tile's width), over random depths.
    /// Returns how many spans took each path.
    fn clamp_free_equals_clamped<C: TileConfig>(seed: u64) -> (u32, u32) {
        const W: u32 = 64;
        let mut next = xorshift(seed);
        let (mut fast, mut slow) = (0, 0);
        for _ in 0..4000 {
            let mut t: [Tile<32, C>; 2] = [Tile::new(), Tile::new()];
            let zs: [u16; 256] = core::array::from_fn(|_| next() as u16);
            for t in &mut t {
                t.begin(Rect::new(0, 0, W, 4), &Clear::default()).unwrap();
                for (i, &z) in zs.iter().enumerate() {
                    t.depth.put(i, z);
                }
            }
            let (x, y) = ((next() % W as u64) as u32, (next() % 4) as u32);
            let n = 1 + (next() % (W - x) as u64) as usize;
            let inside = next() % 2 == 0;
            let mut pick = |lim: u32| -> (i32, i32) {
                if inside {
                    // A span that stays in range, at times to its ends.
                    let v = (next() % lim as u64) as i64;
                    let k = (n as i64 - 1).max(1);
                    let (lo, hi) = (-v / k, (lim as i64 - 1 - v) / k);
                    let d = match next() % 3 {
                        0 => lo,
                        1 => hi,
                        _ => lo + (next() % (hi - lo + 1) as u64) as i64,
                    };
                    return (v as i32, d as i32);
                }
                let v = match next() % 4 {
                    0 => (next() % lim as u64) as i32,
                    1 => lim as i32 - 1 - (next() % 2) as i32,
                    2 => (next() % 2) as i32 - 1,
                    _ => next() as i32 >> (next() % 32),
                };
                let d = match next() % 4 {
                    0 => (next() as i32) >> (next() % 32),
                    1 => ((lim as i64 - 2 * v as i64) / n.max(2) as i64) as i32,
                    2 => i32::MIN,
                    _ => (next() % 512) as i32 - 256,
                };
                (v, d)
            };
            let lanes: [(i32, i32); 3] = core::array::from_fn(|i| {
                pick(Tile::<32, C>::lane_limit(
                    <C::Dither as Dither>::NEW,
                    i.min(<C::Format as PixelFormat>::Lanes::LEN - 1),
                ))
            });
            let (z, dz) = pick(1 << 30);
            let c = <C::Format as PixelFormat>::Lanes::from_fn(|i| lanes[i].0);
            let dc = <C::Format as PixelFormat>::Lanes::from_fn(|i| lanes[i].1);
            let st = || SpanState {
                c,
                dc,
                ddc: dc,
                z,
                a: 0,
            };
            if Tile::<32, C>::in_range(
                <C::Dither as Dither>::NEW,
                <C::Depth as DepthMode>::BITS > 0,
                &st(),
                dz,
                n,
            ) {
                fast += 1;
            } else {
                slow += 1;
            }
            let idx = (y * W + x) as usize;
            let s = SpanStart { c, dc, z, dz };
            let [a, b] = &mut t;
            let mask = <C::Format as PixelFormat>::MASK_ALL;
            a.span_loop::<OPAQUE, false>(idx, x, y, n, (s, dc), (0, 0), 0, mask);
            b.span_pixels::<OPAQUE, false, true>(idx..idx + n, x, y, st(), (dz, 0), 0, mask);
            for i in 0..256 {
                assert_eq!(a.color.get(i), b.color.get(i), "{s:?} {n}");
                assert_eq!(a.depth.read(i), b.depth.read(i), "{s:?} {n}");
            }
        }
        (fast, slow)
    }

    #[test]
    fn clamp_free_spans_equal_clamped_spans() {
        for (fast, slow) in [
            clamp_free_equals_clamped::<Planes<Rgb565Format, Depth16>>(1),
            clamp_free_equals_clamped::<Planes<Rgb565Format, Depth16, NoWid, Bayer8>>(2),
            clamp_free_equals_clamped::<Planes<Rgb444Format, Depth32, NoWid, NoDither>>(3),
        ] {
            assert!(fast > 400 && slow > 400, "{fast} {slow}");
        }
    }
}
