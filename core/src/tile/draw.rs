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
use crate::command::{Command, SpanCmd, State};
use crate::config::TileConfig;
use crate::error::Error;
use crate::format::{ColorPlane, Lanes, PixelFormat, Rgb};
use crate::fragment::dither::{round_bias, Dither};
use crate::fragment::{DepthMode, DepthPlane, WidMode, WidPlane};
use crate::geom::Rect;
use crate::numeric::{Precision, COLOR_FRAC, SUBPIXEL as SUBPIXEL_I64, Z_FRAC};
use crate::raster::coverage::{AaMode, AaPlane};
use crate::raster::span::{quantize_color, quantize_z, SpanStart};
use crate::raster::traverse::{Row, Spans};
use crate::setup::{fits_i32, EdgeInt, TriangleSetup};

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
    /// Validates and draws one command, clipped to the tile.
    pub fn draw(&mut self, cmd: &Command) -> Result<(), Error> {
        cmd.validate()?;
        self.draw_valid(cmd);
        Ok(())
    }

    /// Draws a command already validated.
    ///
    /// With coverage antialiasing a frame draws its commands twice
    /// ([`Tile::finish`] between): solids merge into the coverage plane in
    /// the first pass; spans, lines and every command with a partial plane
    /// mask are drawn over the resolved pixels in the second, so the mask
    /// keeps the bits it protects (coverage samples hold whole colours,
    /// not planes).
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

    pub(crate) fn draw_valid(&mut self, cmd: &Command) {
        if A::SAMPLES > 0 {
            let masked = match cmd {
                Command::Triangle { state, .. } | Command::Fill { state, .. } => {
                    state.plane_mask & F::MASK_ALL != F::MASK_ALL
                }
                _ => false,
            };
            match (self.resolved, cmd) {
                (false, Command::Triangle { .. } | Command::Fill { .. }) if masked => return,
                (true, Command::Triangle { .. } | Command::Fill { .. }) if masked => {}
                (false, Command::Triangle { v, state }) => return self.triangle_aa(v, state),
                (false, Command::Fill { rect, color, state }) => {
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
            Command::Triangle { v, state } => {
                if fits_i32(v) {
                    if let Some(t) = TriangleSetup::<_, i32>::new::<F>(v) {
                        self.triangle(&t, state);
                    }
                } else if let Some(t) = TriangleSetup::<_, i64>::new::<F>(v) {
                    self.triangle(&t, state);
                }
            }
            Command::Span { span, state } => self.span_cmd(span, state),
            Command::Line { line, state } => self.line(line, state),
            Command::Edge { edge, state } => self.edge(edge, state),
            Command::Fill { rect, color, state } => self.fill(rect, *color, state),
            Command::ZFill { rect, z, state } => {
                let wid = state.wid;
                self.for_each_pixel(rect, |t, i| {
                    if t.wid.pass(i, wid) {
                        t.depth.put(i, *z)
                    }
                })
            }
            Command::WidFill { rect, wid } => self.for_each_pixel(rect, |t, i| t.wid.put(i, *wid)),
        }
    }

    /// Setup, and traversal from [`Phase::Traverse`] on, of a triangle,
    /// without drawing it.
    #[inline(always)]
    fn triangle_upto<const UPTO: u8, T: EdgeInt>(&mut self, v: &[crate::command::Vertex; 3]) {
        let Some(t) = TriangleSetup::<_, T>::new::<F>(v) else {
            return;
        };
        if UPTO >= Phase::Traverse as u8 {
            for row in Spans::new(&t.e, &t.bounds, &self.area) {
                core::hint::black_box(row);
            }
        } else {
            core::hint::black_box(&t);
        }
    }

    #[inline(always)]
    fn triangle<T: EdgeInt>(&mut self, t: &TriangleSetup<F::Lanes, T>, st: &State) {
        let area = self.area;
        // Small triangles: the anchored planes, rounded once to the DDA's
        // precision; each row's start is `c + i gc + j gcy` (modulo 2^32).
        let plane = SpanStart {
            c: t.c,
            dc: t.gc,
            z: t.z,
            dz: t.gz,
        }
        .quantized::<P>();
        let (gcy, gzy) = (quantize_color::<P, _>(t.gcy), quantize_z::<P>(t.gzy));
        let (ax, ay) = (t.bounds.x as i64, t.bounds.y as i64);
        for Row {
            py,
            xr,
            x0,
            x1,
            e1,
            e2,
        } in Spans::new(&t.e, &t.bounds, &area)
        {
            let start = if T::EXACT_ROWS {
                // Restart from the plane equation at xr, then advance to x0
                // by multiplication: exactly the values x0 - xr DDA steps
                // give, so the output does not depend on the tiling.
                let (c, z) = t.start(e1, e2);
                SpanStart {
                    c,
                    dc: t.gc,
                    z,
                    dz: t.gz,
                }
                .quantized::<P>()
                .advanced(x0 - xr)
            } else {
                let j = (py - ay) as i32;
                SpanStart {
                    c: plane.c.zip(gcy, |c, g| c.wrapping_add(j.wrapping_mul(g))),
                    z: plane.z.wrapping_add(j.wrapping_mul(gzy)),
                    ..plane
                }
                .advanced(x0 - ax)
            };
            self.span(x0, py, x1 - x0, start, st);
        }
    }

    /// A triangle through the coverage plane: one fragment per pixel of
    /// the tile it covers any sample of ([`crate::raster::coverage::fragments`]).
    fn triangle_aa(&mut self, v: &[crate::command::Vertex; 3], st: &State) {
        let a = self.area;
        crate::raster::coverage::fragments::<A::Pattern>(v, &a, |px, py, m, color, z| {
            let i = ((py - a.y as i64) * a.w as i64 + (px - a.x as i64)) as usize;
            if self.wid.pass(i, st.wid) {
                self.aa
                    .fragment(i, m, |k| z.at(k), Z::BITS > 0, color, st.tag);
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
        let c = l.color;
        let c = F::lanes_from_rgb([c.r as i64, c.g as i64, c.b as i64].map(|v| v << COLOR_FRAC));
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
                            self.blend(x, y, c, w, z, st);
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
        let lanes = |c: crate::format::Rgb| {
            F::lanes_from_rgb([c.r as i64, c.g as i64, c.b as i64].map(|v| v << COLOR_FRAC))
        };
        let [ca, cb] = s.ends(e.v.map(|v| lanes(v.color)));
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
                self.blend(x, y, c, w, z, st);
            }
        });
    }

    /// Blends colour `c` (output scale, 16 fraction bits) with weight `w`
    /// (in 1/256) over the pixel at screen `(x, y)` — seed 003 eq. 7,
    /// `C = C_bg + (C_line - C_bg) w` — after the window-ID test and a
    /// read-only Z test (partial coverage does not claim depth), then
    /// dither, pack and plane mask as every fragment.
    fn blend(&mut self, x: i64, y: i64, c: F::Lanes, w: i32, z: i32, st: &State) {
        let a = self.area;
        let idx = ((y - a.y as i64) * a.w as i64 + (x - a.x as i64)) as usize;
        if !self.wid.pass(idx, st.wid) || !self.depth.test(idx, z + (1 << (Z_FRAC - 1))) {
            return;
        }
        let old = F::unpack_masked(self.color.get(idx), st.plane_mask & F::MASK_ALL);
        let bias = round_bias::<D>();
        // (line - old) has at most 8 integer bits; dropping 8 of its 16
        // fraction bits keeps the product with w <= 256 within i32.
        let v = c.zip(old, |line, bg| {
            let bg = bg << COLOR_FRAC;
            bg + (((line - bg) >> 8) * w) + bias
        });
        self.store::<true>(idx, x as u32, y as u32, v, st.plane_mask & F::MASK_ALL);
    }

    fn fill(&mut self, rect: &Rect, color: Rgb, st: &State) {
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
        self.for_each_pixel(rect, |t, i| {
            if t.wid.pass(i, wid) {
                t.put_packed::<MASKED>(i, c, mask)
            }
        });
    }

    /// Calls `f(self, index)` for each tile pixel inside `rect`.
    #[inline]
    pub(super) fn for_each_pixel(&mut self, rect: &Rect, mut f: impl FnMut(&mut Self, usize)) {
        let Some(r) = rect.intersect(&self.area) else {
            return;
        };
        let a = self.area;
        for y in 0..r.h {
            let row = ((r.y - a.y) as u32 + y) * a.w + (r.x - a.x) as u32;
            let row = row as usize;
            for i in row..row + r.w as usize {
                f(self, i);
            }
        }
    }

    /// Draws `n >= 1` pixels from screen `(x, y)`, which the caller has
    /// clipped to this tile.
    #[inline(always)]
    pub(crate) fn span(&mut self, x: i64, y: i64, n: i64, s: SpanStart<F::Lanes>, st: &State) {
        let a = self.area;
        let idx = ((y - a.y as i64) * a.w as i64 + (x - a.x as i64)) as usize;
        let bias = round_bias::<D>();
        let s = SpanStart {
            c: s.c.map(|v| v + bias),
            z: s.z + (1 << (Z_FRAC - 1)),
            ..s
        };
        let mask = st.plane_mask & F::MASK_ALL;
        // Screen addresses are non-negative inside a tile; only their low
        // bits reach the dither.
        let (xs, ys) = (x as u32, y as u32);
        if mask == F::MASK_ALL {
            self.span_loop::<false>(idx, xs, ys, n as usize, s, st.wid, mask);
        } else {
            self.span_loop::<true>(idx, xs, ys, n as usize, s, st.wid, mask);
        }
    }

    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    fn span_loop<const MASKED: bool>(
        &mut self,
        mut idx: usize,
        mut x: u32,
        y: u32,
        n: usize,
        s: SpanStart<F::Lanes>,
        wid: u8,
        mask: u32,
    ) {
        let (mut c, mut z) = (s.c, s.z);
        let end = idx + n;
        loop {
            if self.wid.pass(idx, wid) && self.depth.test_and_set(idx, z) {
                self.store::<MASKED>(idx, x, y, c, mask);
            }
            idx += 1;
            if idx == end {
                break;
            }
            x = x.wrapping_add(1);
            c = c.zip(s.dc, |v, d| v + d);
            z += s.dz;
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
        self.span(x0, s.y as i64, x1 - x0, start, st);
    }
}
