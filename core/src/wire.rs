//! The display-list wire format: commands as little-endian bytes, so a scene
//! converted on the host lives in a firmware's flash and is replayed tile by
//! tile without ever being copied to RAM. This layer only encodes and
//! decodes; drawing is [`crate::tile`]'s business.
//!
//! Each command starts with a tag byte: the low 5 bits name the command, bit
//! 7 says a 4-byte plane mask follows the window ID, bit 6 that a 2-byte
//! object tag follows (after the mask), bit 5 that the command carries
//! opacity: a blend-mode byte follows (after the tag; 0 opaque, 1 alpha,
//! 2 alpha with Z write) and every vertex, span and fill body ends with an
//! `alpha: u8` (so opaque commands pay no byte for it).
//!
//! | tag | command | body after `wid` \[`mask`\] |
//! | --- | --- | --- |
//! | 1 | triangle, 32-bit coordinates | 3 x (`x: i32, y: i32, z: u16, r, g, b`) |
//! | 2 | triangle, 16-bit coordinates (`\|x\|, \|y\| < 2048` px) | 3 x (`x: i16, y: i16, z: u16, r, g, b`) |
//! | 3 | span | `x: i32, y: i32, len: u16, rgb: 3 x u32, drgb: 3 x i32, z: u32, dz: i32` (raw 16.16) |
//! | 4 | fill | `x: i32, y: i32, w: u32, h: u32, r, g, b` |
//! | 5 | Z fill | `x: i32, y: i32, w: u32, h: u32, z: u16` |
//! | 6 | window-ID fill | `x: i32, y: i32, w: u32, h: u32` (its `wid` is the ID; no mask) |
//! | 8 | line | `x0, y0, x1, y1: i32, z0, z1: u16, r, g, b, pattern: u16, scale: u8, phase: u16, antialias: u8` |
//! | 9 | antialiased solid edge, 32-bit coordinates | 2 x (`x: i32, y: i32, z: u16, r, g, b`), `interior: u8` (0 left, 1 right) |
//! | 10 | antialiased solid edge, 16-bit coordinates | 2 x (`x: i16, y: i16, z: u16, r, g, b`), `interior: u8` |
//! | 11 | quadratic (fast Phong) triangle, 32-bit coordinates | 3 x (`x: i32, y: i32, z: u16, r, g, b`, midpoint `r, g, b`), then one α |
//! | 12 | quadratic triangle, 16-bit coordinates | 3 x (`x: i16, y: i16, z: u16, r, g, b`, midpoint `r, g, b`), then one α |
//! | 13 | textured triangle, 32-bit coordinates | `tex: u8`, 3 x (`x: i32, y: i32, z: u16`, `u, v, q: u16`, `shade: u8`), then one α |
//! | 14 | textured triangle, 16-bit coordinates | `tex: u8`, 3 x (`x: i16, y: i16, z: u16`, `u, v, q: u16`, `shade: u8`), then one α |
//! | 15 | triangle with edge flags ([`Vertex::edge_flag`]), 32-bit coordinates | as tag 1, then `flags: u8` (bit `i`: vertex `i`'s edge; not 0) |
//! | 16 | triangle with edge flags, 16-bit coordinates | as tag 2, then `flags: u8` |
//! | 7 | indexed mesh: triangles sharing vertices | `nv: u16, nt: u16`, `nv` x (`x: i16, y: i16, z: u16, r, g, b`), `nt` x 3 x `u16` index |
//!
//! A mesh record replays as its `nt` triangles, in order, each with the
//! record's state — the same commands as the triangles written one by one,
//! in about 40% of the bytes for a typical OBJ model ([`encode_mesh`]).
//!
//! Decoding validates every command ([`Command::validate`]).

use core::ops::Range;

use crate::command::{Blend, Command, Cull, QuadVertex, SpanCmd, State, Vertex};
use crate::error::Error;
use crate::format::Rgb;
use crate::geom::{MeshVertex, Rect};
use crate::numeric::{ColorFix, ColorStep, Coord, ZFix, ZStep};
use crate::raster::line::{EdgeCmd, LineCmd, LineStyle, Side};
use crate::texture::TexVertex;

const MASK_FLAG: u8 = 0x80;
const TAG_FLAG: u8 = 0x40;
const ALPHA_FLAG: u8 = 0x20;
const FLAGS: u8 = MASK_FLAG | TAG_FLAG | ALPHA_FLAG;

/// Largest encoded command, in bytes.
pub const MAX_ENCODED: usize = 64;

/// Writes little-endian fields into a buffer.
struct Writer<'a> {
    buf: &'a mut [u8],
    pos: usize,
    /// Whether the command carries opacity (bodies end with `alpha`).
    alpha: bool,
}

impl Writer<'_> {
    /// A command's tag byte and state; the plane mask only when partial,
    /// the blend mode only when `alpha` (the command blends or carries a
    /// non-opaque α, which then follows each vertex, span or fill body).
    fn head(&mut self, tag: u8, st: &State, alpha: bool) -> Result<(), Error> {
        let masked = st.plane_mask != u32::MAX;
        let tagged = st.tag != 0;
        self.alpha = alpha || st.blend != Blend::Opaque;
        let flags = if masked { MASK_FLAG } else { 0 }
            | if tagged { TAG_FLAG } else { 0 }
            | if self.alpha { ALPHA_FLAG } else { 0 };
        self.put(&[tag | flags, st.wid])?;
        if masked {
            self.put(&st.plane_mask.to_le_bytes())?;
        }
        if tagged {
            self.put(&st.tag.to_le_bytes())?;
        }
        if self.alpha {
            self.put(&[st.blend as u8])?;
        }
        Ok(())
    }

    /// The `alpha` byte closing a body, when the command carries opacity.
    fn alpha(&mut self, a: u8) -> Result<(), Error> {
        if self.alpha {
            self.put(&[a])?;
        }
        Ok(())
    }

    /// A vertex: `x, y` as `i16` (`small`) or `i32` sub-pixels, `z`, colour
    /// \[, α\].
    fn vertex(&mut self, v: &Vertex, small: bool) -> Result<(), Error> {
        self.point(v, small)?;
        self.alpha(v.alpha)
    }

    /// A vertex without its α.
    fn point(&mut self, v: &Vertex, small: bool) -> Result<(), Error> {
        self.xyz(v, small)?;
        self.put(&[v.color.r, v.color.g, v.color.b])
    }

    /// A vertex's position and depth.
    fn xyz(&mut self, v: &Vertex, small: bool) -> Result<(), Error> {
        if small {
            self.put(&(v.x.to_bits() as i16).to_le_bytes())?;
            self.put(&(v.y.to_bits() as i16).to_le_bytes())?;
        } else {
            self.put(&v.x.to_bits().to_le_bytes())?;
            self.put(&v.y.to_bits().to_le_bytes())?;
        }
        self.put(&v.z.to_le_bytes())
    }

    fn put(&mut self, bytes: &[u8]) -> Result<(), Error> {
        let end = self.pos + bytes.len();
        self.buf
            .get_mut(self.pos..end)
            .ok_or(Error::BufferTooSmall)?
            .copy_from_slice(bytes);
        self.pos = end;
        Ok(())
    }
}

/// Reads little-endian fields.
struct Reader<'a> {
    buf: &'a [u8],
    pos: usize,
    /// Whether the command carries opacity (bodies end with `alpha`).
    alpha: bool,
}

impl Reader<'_> {
    fn take<const K: usize>(&mut self) -> Result<[u8; K], Error> {
        let s = self
            .buf
            .get(self.pos..self.pos + K)
            .ok_or(Error::Malformed)?;
        self.pos += K;
        Ok(s.try_into().unwrap_or([0; K]))
    }
    fn u8(&mut self) -> Result<u8, Error> {
        Ok(self.take::<1>()?[0])
    }
    fn u16(&mut self) -> Result<u16, Error> {
        self.take().map(u16::from_le_bytes)
    }
    fn i16(&mut self) -> Result<i16, Error> {
        self.take().map(i16::from_le_bytes)
    }
    fn u32(&mut self) -> Result<u32, Error> {
        self.take().map(u32::from_le_bytes)
    }
    fn i32(&mut self) -> Result<i32, Error> {
        self.take().map(i32::from_le_bytes)
    }
    // Inlined: the mesh decoder calls this for every vertex of every
    // triangle in every tile; as a call it made whole frames 2.5x slower on
    // the Cortex-M0 (measured under QEMU).
    #[inline(always)]
    fn vertex(&mut self, small: bool) -> Result<Vertex, Error> {
        let v = self.point(small)?;
        Ok(v.with_alpha(self.alpha()?))
    }
    /// A vertex without its α (opaque).
    #[inline(always)]
    fn point(&mut self, small: bool) -> Result<Vertex, Error> {
        let (x, y, z) = self.xyz(small)?;
        Ok(Vertex::new(x, y, z, self.rgb()?))
    }
    /// A position and depth.
    #[inline(always)]
    fn xyz(&mut self, small: bool) -> Result<(Coord, Coord, u16), Error> {
        let (x, y) = if small {
            (self.i16()? as i32, self.i16()? as i32)
        } else {
            (self.i32()?, self.i32()?)
        };
        Ok((Coord::from_bits(x), Coord::from_bits(y), self.u16()?))
    }
    fn rgb(&mut self) -> Result<Rgb, Error> {
        let [r, g, b] = self.take()?;
        Ok(Rgb::new(r, g, b))
    }
    /// The `alpha` byte closing a body (255 when the command carries none).
    #[inline(always)]
    fn alpha(&mut self) -> Result<u8, Error> {
        if self.alpha {
            self.u8()
        } else {
            Ok(255)
        }
    }
    /// A command's tag byte and state (window ID, optional plane mask).
    fn head(&mut self) -> Result<(u8, State), Error> {
        let tag = self.u8()?;
        let wid = self.u8()?;
        let plane_mask = if tag & MASK_FLAG != 0 {
            self.u32()?
        } else {
            u32::MAX
        };
        let obj = if tag & TAG_FLAG != 0 { self.u16()? } else { 0 };
        self.alpha = tag & ALPHA_FLAG != 0;
        let blend = if self.alpha {
            match self.u8()? {
                0 => Blend::Opaque,
                1 => Blend::Alpha,
                2 => Blend::AlphaZWrite,
                _ => return Err(Error::Malformed),
            }
        } else {
            Blend::Opaque
        };
        Ok((
            tag,
            State {
                wid,
                plane_mask,
                tag: obj,
                blend,
            },
        ))
    }
    fn rect(&mut self) -> Result<Rect, Error> {
        Ok(Rect::new(
            self.i32()?,
            self.i32()?,
            self.u32()?,
            self.u32()?,
        ))
    }
}

fn rect_bytes(w: &mut Writer<'_>, r: &Rect) -> Result<(), Error> {
    w.put(&r.x.to_le_bytes())?;
    w.put(&r.y.to_le_bytes())?;
    w.put(&r.w.to_le_bytes())?;
    w.put(&r.h.to_le_bytes())
}

/// Whether a vertex fits the 16-bit coordinate encoding.
fn small(v: &Vertex) -> bool {
    i16::try_from(v.x.to_bits()).is_ok() && i16::try_from(v.y.to_bits()).is_ok()
}

/// Encodes one command into `buf`, returning the bytes written.
///
/// ```
/// use tilerast::prelude::*;
/// use tilerast::wire;
/// let cmd = Command::Fill { rect: Rect::new(1, 2, 3, 4), color: Rgb::new(5, 6, 7), alpha: 96, state: State::default() }
///     .blend(Blend::Alpha);
/// let mut buf = [0u8; wire::MAX_ENCODED];
/// let n = wire::encode(&cmd, &mut buf)?;
/// assert_eq!(wire::decode(&buf[..n])?, (cmd, n));
/// # Ok::<(), Error>(())
/// ```
pub fn encode(cmd: &Command, buf: &mut [u8]) -> Result<usize, Error> {
    let mut w = Writer {
        buf,
        pos: 0,
        alpha: false,
    };
    match cmd {
        Command::Triangle { v, state } => {
            let small = v.iter().all(small);
            let alpha = v.iter().any(|v| v.alpha != 255);
            let flags = v
                .iter()
                .enumerate()
                .fold(0u8, |f, (i, v)| f | ((v.edge_flag as u8) << i));
            let tag = match (flags != 0, small) {
                (false, s) => 1 + s as u8,
                (true, s) => 15 + s as u8,
            };
            w.head(tag, state, alpha)?;
            for v in v {
                w.vertex(v, small)?;
            }
            if flags != 0 {
                w.put(&[flags])?;
            }
        }
        Command::Quadratic { alpha, v, state } => {
            let small = v.iter().all(|q| small(&q.vertex()));
            w.head(if small { 12 } else { 11 }, state, *alpha != 255)?;
            for q in v {
                w.point(&q.vertex(), small)?;
                w.put(&[q.mid.r, q.mid.g, q.mid.b])?;
            }
            w.alpha(*alpha)?;
        }
        Command::Textured {
            tex,
            alpha,
            shade,
            v,
            state,
        } => {
            let small = v.iter().all(|t| small(&t.vertex(0)));
            w.head(if small { 14 } else { 13 }, state, *alpha != 255)?;
            w.put(&[*tex])?;
            for (t, l) in v.iter().zip(shade) {
                w.xyz(&t.vertex(0), small)?;
                for c in [t.u, t.v, t.q] {
                    w.put(&c.to_le_bytes())?;
                }
                w.put(&[*l])?;
            }
            w.alpha(*alpha)?;
        }
        Command::Edge { edge, state } => {
            let small = edge.v.iter().all(small);
            let alpha = edge.v.iter().any(|v| v.alpha != 255);
            w.head(if small { 10 } else { 9 }, state, alpha)?;
            for v in &edge.v {
                w.vertex(v, small)?;
            }
            w.put(&[(edge.interior == Side::Right) as u8])?;
        }
        Command::Span { span: s, state } => {
            w.head(3, state, s.alpha != 255)?;
            w.put(&s.x.to_le_bytes())?;
            w.put(&s.y.to_le_bytes())?;
            w.put(&s.len.to_le_bytes())?;
            for c in &s.color {
                w.put(&c.to_bits().to_le_bytes())?;
            }
            for d in &s.dcolor {
                w.put(&d.to_bits().to_le_bytes())?;
            }
            w.put(&s.z.to_bits().to_le_bytes())?;
            w.put(&s.dz.to_bits().to_le_bytes())?;
            w.alpha(s.alpha)?;
        }
        Command::Line { line: l, state } => {
            w.head(8, state, false)?;
            for c in [l.p0.0, l.p0.1, l.p1.0, l.p1.1] {
                w.put(&c.to_bits().to_le_bytes())?;
            }
            w.put(&l.z[0].to_le_bytes())?;
            w.put(&l.z[1].to_le_bytes())?;
            w.put(&[l.color.r, l.color.g, l.color.b])?;
            w.put(&l.style.pattern.to_le_bytes())?;
            w.put(&[l.style.scale])?;
            w.put(&l.style.phase.to_le_bytes())?;
            w.put(&[l.antialias as u8])?;
        }
        Command::Fill {
            rect,
            color,
            alpha,
            state,
        } => {
            w.head(4, state, *alpha != 255)?;
            rect_bytes(&mut w, rect)?;
            w.put(&[color.r, color.g, color.b])?;
            w.alpha(*alpha)?;
        }
        Command::ZFill { rect, z, state } => {
            w.head(5, state, false)?;
            rect_bytes(&mut w, rect)?;
            w.put(&z.to_le_bytes())?;
        }
        Command::WidFill { rect, wid } => {
            w.put(&[6, *wid])?;
            rect_bytes(&mut w, rect)?;
        }
    }
    Ok(w.pos)
}

/// Decodes and validates the command at the start of `buf`, returning it
/// and the bytes it used. Truncated or unknown input is
/// [`Error::Malformed`].
pub fn decode(buf: &[u8]) -> Result<(Command, usize), Error> {
    let mut r = Reader {
        buf,
        pos: 0,
        alpha: false,
    };
    let (tag, state) = r.head()?;
    let cmd = match tag & !FLAGS {
        t @ (1 | 2 | 15 | 16) => {
            let small = matches!(t, 2 | 16);
            let mut v = [r.vertex(small)?, r.vertex(small)?, r.vertex(small)?];
            if t >= 15 {
                let flags = r.u8()?;
                if flags == 0 || flags > 7 {
                    return Err(Error::Malformed);
                }
                for (i, v) in v.iter_mut().enumerate() {
                    v.edge_flag = flags & (1 << i) != 0;
                }
            }
            Command::Triangle { v, state }
        }
        t @ (11 | 12) => {
            let mut q = || -> Result<QuadVertex, Error> {
                let v = r.point(t == 12)?;
                Ok(QuadVertex::new(v, r.rgb()?))
            };
            let v = [q()?, q()?, q()?];
            Command::Quadratic {
                alpha: r.alpha()?,
                v,
                state,
            }
        }
        t @ (13 | 14) => {
            let tex = r.u8()?;
            let mut shade = [0u8; 3];
            let mut one = |l: &mut u8| -> Result<TexVertex, Error> {
                let (x, y, z) = r.xyz(t == 14)?;
                let (u, v, q) = (r.u16()?, r.u16()?, r.u16()?);
                *l = r.u8()?;
                Ok(TexVertex { x, y, z, u, v, q })
            };
            let [l0, l1, l2] = &mut shade;
            let v = [one(l0)?, one(l1)?, one(l2)?];
            Command::Textured {
                tex,
                alpha: r.alpha()?,
                shade,
                v,
                state,
            }
        }
        t @ (9 | 10) => {
            let v = [r.vertex(t == 10)?, r.vertex(t == 10)?];
            let interior = match r.u8()? {
                0 => Side::Left,
                1 => Side::Right,
                _ => return Err(Error::Malformed),
            };
            Command::Edge {
                edge: EdgeCmd { v, interior },
                state,
            }
        }
        3 => {
            let (x, y, len) = (r.i32()?, r.i32()?, r.u16()?);
            let color = [r.u32()?, r.u32()?, r.u32()?].map(ColorFix::from_bits);
            let dcolor = [r.i32()?, r.i32()?, r.i32()?].map(ColorStep::from_bits);
            let (z, dz) = (ZFix::from_bits(r.u32()?), ZStep::from_bits(r.i32()?));
            Command::Span {
                span: SpanCmd {
                    x,
                    y,
                    len,
                    color,
                    dcolor,
                    z,
                    dz,
                    alpha: r.alpha()?,
                },
                state,
            }
        }
        8 => {
            let mut c = || r.i32().map(Coord::from_bits);
            let (p0, p1) = ((c()?, c()?), (c()?, c()?));
            let z = [r.u16()?, r.u16()?];
            let color = r.rgb()?;
            let style = LineStyle {
                pattern: r.u16()?,
                scale: r.u8()?,
                phase: r.u16()?,
            };
            let antialias = match r.u8()? {
                0 => false,
                1 => true,
                _ => return Err(Error::Malformed),
            };
            Command::Line {
                line: LineCmd {
                    p0,
                    p1,
                    z,
                    color,
                    style,
                    antialias,
                },
                state,
            }
        }
        4 => Command::Fill {
            rect: r.rect()?,
            color: r.rgb()?,
            alpha: r.alpha()?,
            state,
        },
        5 => Command::ZFill {
            rect: r.rect()?,
            z: r.u16()?,
            state,
        },
        6 if tag & FLAGS == 0 => Command::WidFill {
            rect: r.rect()?,
            wid: state.wid,
        },
        _ => return Err(Error::Malformed),
    };
    cmd.validate()?;
    Ok((cmd, r.pos))
}

/// Size of an encoded mesh vertex (one more, its α, in a mesh record that
/// carries opacity).
const MESH_VERTEX: usize = 9;

/// Encodes triangles sharing `state` as one indexed-mesh record:
/// `vertices` (at most 65535, each coordinate within `i16` sub-pixel range)
/// and `tris` indexing them. Returns the bytes written.
///
/// ```
/// use tilerast::prelude::*;
/// use tilerast::wire::{encode_mesh, Encoded};
/// let v = |x: i32, y: i32| Vertex::new(Coord::from_num(x), Coord::from_num(y), 7, Rgb::new(1, 2, 3));
/// let verts = [v(0, 0), v(10, 0), v(0, 10), v(10, 10)];
/// let mut buf = [0u8; 64];
/// let n = encode_mesh(&verts, &[[0, 1, 2], [1, 3, 2]], &State::default(), &mut buf)?;
/// let cmds: Vec<Command> = Encoded(&buf[..n]).iter().collect::<Result<_, _>>()?;
/// assert_eq!(cmds[1], Command::Triangle { v: [verts[1], verts[3], verts[2]], state: State::default() });
/// # Ok::<(), Error>(())
/// ```
pub fn encode_mesh(
    vertices: &[Vertex],
    tris: &[[u16; 3]],
    state: &State,
    buf: &mut [u8],
) -> Result<usize, Error> {
    let nv = u16::try_from(vertices.len()).map_err(|_| Error::BufferTooSmall)?;
    let nt = u16::try_from(tris.len()).map_err(|_| Error::BufferTooSmall)?;
    let mut w = Writer {
        buf,
        pos: 0,
        alpha: false,
    };
    w.head(7, state, vertices.iter().any(|v| v.alpha != 255))?;
    w.put(&nv.to_le_bytes())?;
    w.put(&nt.to_le_bytes())?;
    for v in vertices {
        if !small(v) {
            return Err(Error::CoordOutOfRange);
        }
        w.vertex(v, true)?;
    }
    for t in tris {
        if t.iter().any(|&i| i >= nv) {
            return Err(Error::Malformed);
        }
        for i in t {
            w.put(&i.to_le_bytes())?;
        }
    }
    Ok(w.pos)
}

/// What [`Encoded::walk`] meets: a mesh triangle (its record's cursor and
/// the offset of its indices there), or any other command, decoded.
enum Item<'c, 'a> {
    Triangle(&'c MeshCursor<'a>, usize),
    Command(&'c Command),
}

/// A mesh record being replayed.
#[derive(Debug, Clone, Copy)]
struct MeshCursor<'a> {
    vertices: &'a [u8],
    indices: &'a [u8],
    state: State,
    /// Whether each vertex carries its α (a tenth byte).
    alpha: bool,
}

impl MeshCursor<'_> {
    /// Vertex `i`, read from one fixed-size chunk of `S` bytes (no per-field
    /// `Result`: the mesh path decodes every triangle of a frame twice,
    /// binning and drawing); `S = MESH_VERTEX + 1` reads its α too. The
    /// caller has checked that the chunk lies in the vertex list; a vertex
    /// is returned bare, never in a `Result` or `Option`, whose
    /// discriminant would live in the edge flag's spare bit patterns and
    /// cost a test per vertex (measured: the M4 teapot's binning).
    #[inline(always)]
    fn vertex<const S: usize>(&self, i: u16) -> Vertex {
        let c = self.chunk::<S>(i);
        Vertex::new(
            Coord::from_bits(i16::from_le_bytes([c[0], c[1]]) as i32),
            Coord::from_bits(i16::from_le_bytes([c[2], c[3]]) as i32),
            u16::from_le_bytes([c[4], c[5]]),
            Rgb::new(c[6], c[7], c[8]),
        )
        .with_alpha(if S > MESH_VERTEX { c[S - 1] } else { 255 })
    }

    /// Vertex `i`'s `S` bytes (zeros past the list, which the callers'
    /// index checks rule out).
    #[inline(always)]
    fn chunk<const S: usize>(&self, i: u16) -> &[u8; S] {
        let at = i as usize * S;
        self.vertices
            .get(at..at + S)
            .and_then(|c| c.try_into().ok())
            .unwrap_or(&[0; S])
    }

    /// The triangle whose indices start `at` bytes into the index list
    /// (whether vertices carry α is decided once per triangle).
    #[inline(always)]
    fn triangle(&self, at: usize) -> Result<Command, Error> {
        if self.alpha {
            self.triangle_of::<{ MESH_VERTEX + 1 }>(at)
        } else {
            self.triangle_of::<MESH_VERTEX>(at)
        }
    }

    #[inline(always)]
    fn triangle_of<const S: usize>(&self, at: usize) -> Result<Command, Error> {
        let i = self.indices_of::<S>(at)?;
        let v = [
            self.vertex::<S>(i[0]),
            self.vertex::<S>(i[1]),
            self.vertex::<S>(i[2]),
        ];
        Ok(Command::Triangle {
            v,
            state: self.state,
        })
    }

    /// The triangle at `at` in the compact form the tile's mesh path
    /// draws ([`Tile::draw_mesh_triangle`](crate::tile::Tile)), for a
    /// record whose vertices carry no α: the same vertices as
    /// [`Self::triangle`]'s command.
    #[inline(always)]
    fn mesh_triangle(&self, at: usize) -> Result<[MeshVertex; 3], Error> {
        debug_assert!(!self.alpha);
        let i = self.indices_of::<MESH_VERTEX>(at)?;
        let read = |i: u16| {
            // `indices_of` checked that the chunk lies in the list.
            let c = self.chunk::<MESH_VERTEX>(i);
            MeshVertex {
                x: i16::from_le_bytes([c[0], c[1]]) as i32,
                y: i16::from_le_bytes([c[2], c[3]]) as i32,
                z: u16::from_le_bytes([c[4], c[5]]),
                rgb: [c[6], c[7], c[8]],
                code: 0,
                spare: 0,
            }
        };
        Ok([read(i[0]), read(i[1]), read(i[2])])
    }

    /// The vertex indices of the triangle at `at`, each checked to name a
    /// whole vertex of `S` bytes (one range check for the three).
    #[inline(always)]
    fn indices_of<const S: usize>(&self, at: usize) -> Result<[u16; 3], Error> {
        let c: &[u8; 6] = self
            .indices
            .get(at..at + 6)
            .and_then(|c| c.try_into().ok())
            .ok_or(Error::Malformed)?;
        let i = [[c[0], c[1]], [c[2], c[3]], [c[4], c[5]]].map(u16::from_le_bytes);
        let top = i[0].max(i[1]).max(i[2]) as usize;
        if (top + 1) * S > self.vertices.len() {
            return Err(Error::Malformed);
        }
        Ok(i)
    }

    /// What binning needs of the triangle at `at`: its pixels
    /// ([`Command::bounds`]; none when `cull` drops it), or its cells with
    /// `cells`
    /// ([`Command::coverage_bounds`]; a mesh vertex has no edge flag), from
    /// the vertices' positions alone (the first four bytes of each); `None`
    /// as well when they miss the pixel rows `rows` (the band of tiles being
    /// binned), found from the y coordinates before the x are read (the
    /// micro:bit bins its demo frame in four passes, and most triangles
    /// miss most bands).
    #[inline(always)]
    fn bounds(
        &self,
        at: usize,
        cells: bool,
        rows: &Range<i32>,
        cull: Cull,
    ) -> Result<Option<Rect>, Error> {
        if cull != Cull::None && self.culls(at, cull)? {
            return Ok(None);
        }
        if self.alpha {
            self.bounds_of::<{ MESH_VERTEX + 1 }>(at, cells, rows)
        } else {
            self.bounds_of::<MESH_VERTEX>(at, cells, rows)
        }
    }

    /// Whether `cull` drops the triangle at `at` (its winding, from its
    /// positions). Out of line and answering only yes or no, so the frames
    /// that do not cull keep their binning loop as it was (measured: with
    /// the test inlined, the M4 teapot's binning took 13 instructions more
    /// a triangle; with the bounds of both paths merged, the Cortex-M0
    /// copied them through `memcpy`, 80 more).
    #[inline(never)]
    fn culls(&self, at: usize, cull: Cull) -> Result<bool, Error> {
        let [a, b, c] = if self.alpha {
            self.positions::<{ MESH_VERTEX + 1 }>(at)?
        } else {
            self.positions::<MESH_VERTEX>(at)?
        };
        Ok(cull.drops(crate::command::area2_i32(a, b, c)))
    }

    /// The positions (sub-pixels) of the triangle at `at`, vertices of `S`
    /// bytes.
    #[inline(always)]
    fn positions<const S: usize>(&self, at: usize) -> Result<[(i32, i32); 3], Error> {
        let i = self.indices_of::<S>(at)?;
        Ok(i.map(|i| {
            let v = self.vertex::<S>(i);
            (v.x.to_bits(), v.y.to_bits())
        }))
    }

    #[inline(always)]
    fn bounds_of<const S: usize>(
        &self,
        at: usize,
        cells: bool,
        rows: &Range<i32>,
    ) -> Result<Option<Rect>, Error> {
        let [a, b, c] = self.indices_of::<S>(at)?;
        // Not `[a, b, c].map(..)`: at the micro:bit's `opt-level = "s"` an
        // array map is a loop through the stack (22 instructions a vertex).
        let read = |i: u16| {
            let at = i as usize * S;
            // `indices_of` checked that the chunk lies in the list.
            match self.vertices.get(at..at + 4) {
                Some(&[x0, x1, y0, y1]) => {
                    (i16::from_le_bytes([x0, x1]), i16::from_le_bytes([y0, y1]))
                }
                _ => (0, 0),
            }
        };
        let (a, b, c) = (read(a), read(b), read(c));
        // Three coordinates' span, in `i16` until widened once.
        let span = |a: i16, b: i16, c: i16| {
            let (lo, hi) = (a.min(b).min(c) as i32, a.max(b).max(c) as i32);
            if cells {
                crate::geom::cell_span(lo, hi)
            } else {
                crate::geom::pixel_span(lo, hi)
            }
        };
        let (y0, y1) = span(a.1, b.1, c.1);
        if y0 > y1 || y1 < rows.start || y0 >= rows.end {
            return Ok(None);
        }
        let (x0, x1) = span(a.0, b.0, c.0);
        Ok((x0 <= x1).then(|| Rect::new(x0, y0, (x1 - x0 + 1) as u32, (y1 - y0 + 1) as u32)))
    }
}

/// A mesh vertex's coordinates are `i16` sub-pixels: always inside the
/// documented domain ([`Vertex::validate`]), so a mesh triangle needs no
/// validation beyond its indices.
const _: () = assert!(
    (i16::MAX as i64) < crate::numeric::COORD_LIMIT as i64 * crate::numeric::SUBPIXEL
        && (i16::MIN as i64) >= -(crate::numeric::COORD_LIMIT as i64 * crate::numeric::SUBPIXEL)
);

/// Reads a mesh record's header; returns the cursor and the record length
/// (the index list is its last `6 nt` bytes).
fn mesh_record(buf: &[u8]) -> Result<(MeshCursor<'_>, usize), Error> {
    let mut r = Reader {
        buf,
        pos: 0,
        alpha: false,
    };
    let (_, state) = r.head()?;
    let (nv, nt) = (r.u16()? as usize, r.u16()? as usize);
    let vs = r.pos;
    let is = vs + nv * (MESH_VERTEX + r.alpha as usize);
    let end = is + nt * 6;
    if end > buf.len() {
        return Err(Error::Malformed);
    }
    let cursor = MeshCursor {
        vertices: &buf[vs..is],
        indices: &buf[is..end],
        state,
        alpha: r.alpha,
    };
    Ok((cursor, end))
}

/// An encoded display list (e.g. in flash), replayable as a
/// [`CommandSource`](crate::frame::CommandSource).
///
/// ```
/// use tilerast::prelude::*;
/// use tilerast::wire::Encoded;
/// let bytes = [6, 1, 0, 0, 0, 0, 0, 0, 0, 0, 4, 0, 0, 0, 4, 0, 0, 0]; // window 1 on 4x4 pixels
/// let cmds: Result<Vec<Command>, Error> = Encoded(&bytes).iter().collect();
/// assert_eq!(cmds?, [Command::WidFill { rect: Rect::new(0, 0, 4, 4), wid: 1 }]);
/// # Ok::<(), Error>(())
/// ```
#[derive(Debug, Clone, Copy)]
pub struct Encoded<'a>(pub &'a [u8]);

/// Whether a tag byte starts an indexed-mesh record.
fn is_mesh(tag: u8) -> bool {
    tag & !FLAGS == 7
}

impl<'a> Encoded<'a> {
    /// Calls `f(key, item)` with every command, in order: a plain loop, not
    /// `keyed()` (the iterator's `Result`s copied every 58-byte command
    /// three times: 2.5 M instructions a teapot frame on the Cortex-M4,
    /// measured), each command built once, in place, and lent to `f`, and a
    /// mesh triangle left to `f` to decode as far as it needs. The first
    /// error, the walk's or `f`'s, ends it.
    #[inline(always)]
    fn walk(&self, mut f: impl FnMut(u32, Item<'_, 'a>) -> Result<(), Error>) -> Result<(), Error> {
        let all = self.0;
        let (mut pos, mut key) = (0usize, 0u32);
        while let Some(rest) = all.get(pos..).filter(|r| !r.is_empty()) {
            if is_mesh(rest[0]) {
                let (m, n) = mesh_record(rest)?;
                let mut at = 0;
                while at + 6 <= m.indices.len() {
                    f(key, Item::Triangle(&m, at))?;
                    key = key.wrapping_add(1);
                    at += 6;
                }
                pos += n;
            } else {
                let (cmd, n) = decode(rest)?;
                f(key, Item::Command(&cmd))?;
                key = key.wrapping_add(1);
                pos += n;
            }
        }
        Ok(())
    }

    /// The commands, decoded and validated one by one (a mesh record yields
    /// its triangles). Decoding stops after the first error.
    pub fn iter(&self) -> impl Iterator<Item = Result<Command, Error>> + 'a {
        self.keyed().map(|r| r.map(|(_, c)| c))
    }

    /// The commands with their keys (their ordinals: a mesh record's
    /// triangles count one each).
    fn keyed(&self) -> impl Iterator<Item = Result<(u32, Command), Error>> + 'a {
        let all = self.0;
        let (mut pos, mut key) = (0usize, 0u32);
        // The mesh being replayed: its cursor and how far it has got.
        let mut mesh: Option<(MeshCursor<'a>, usize)> = None;
        core::iter::from_fn(move || loop {
            if let Some((m, at)) = &mut mesh {
                if *at + 6 <= m.indices.len() {
                    let tri = m.triangle(*at).and_then(|c| c.validate().map(|()| c));
                    *at += 6;
                    if tri.is_err() {
                        pos = all.len();
                        mesh = None;
                    }
                    let k = key;
                    key = key.wrapping_add(1);
                    return Some(tri.map(|c| (k, c)));
                }
                mesh = None;
            }
            let rest = all.get(pos..).filter(|r| !r.is_empty())?;
            let step = if is_mesh(rest[0]) {
                mesh_record(rest).map(|(m, n)| {
                    mesh = Some((m, 0));
                    (None, n)
                })
            } else {
                decode(rest).map(|(cmd, n)| (Some(cmd), n))
            };
            match step {
                Ok((cmd, n)) => {
                    pos += n;
                    if let Some(cmd) = cmd {
                        let k = key;
                        key = key.wrapping_add(1);
                        return Some(Ok((k, cmd)));
                    }
                }
                Err(e) => {
                    pos = all.len();
                    return Some(Err(e));
                }
            }
        })
    }
}

/// Magic bytes of an encoded scene.
pub const MAGIC: [u8; 4] = *b"TRS1";
/// Bytes of an encoded [`SceneHeader`].
pub const HEADER_LEN: usize = 32;

/// What a scene needs, stored before its commands: screen, display format,
/// dither, planes, clear values, the frame's back-face culling and the tile
/// size it was made for. A
/// firmware compiled for some tile types checks it with
/// [`SceneHeader::check`] before rendering.
///
/// ```
/// use tilerast::prelude::*;
/// use tilerast::wire::{SceneHeader, HEADER_LEN};
/// let h = SceneHeader::new::<St7789Config>(96, 64, (32, 16), Clear::default());
/// let mut buf = [0u8; HEADER_LEN];
/// h.encode(&mut buf)?;
/// let (back, cmds) = SceneHeader::parse(&buf)?;
/// assert_eq!(back, h);
/// assert!(back.check::<St7789Config>().is_ok());
/// assert_eq!(back.check::<Planes<Rgb565Format, NoDepth, NoWid, Bayer4>>(), Err(Error::ConfigMismatch));
/// # Ok::<(), Error>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SceneHeader {
    /// Screen width.
    pub width: u16,
    /// Screen height.
    pub height: u16,
    /// Tile size the scene was exported with (a firmware may use another).
    pub tile: (u16, u16),
    /// Display format name ([`PixelFormat::NAME`](crate::format::PixelFormat::NAME)), zero-padded.
    pub format: [u8; 8],
    /// `log2` of the dither matrix side.
    pub dither_log2: u8,
    /// Depth-plane bits (0 or 16).
    pub depth_bits: u8,
    /// Window-ID-plane bits (0 or 8).
    pub wid_bits: u8,
    /// Tile clear values.
    pub clear: crate::frame::Clear,
    /// Triangles the frame culls by their winding
    /// ([`Frame::cull`](crate::frame::Frame::cull)); [`Cull::None`] from
    /// [`Self::new`].
    pub cull: Cull,
}

impl SceneHeader {
    /// The header for tiles of configuration `C` (its format, depth,
    /// window-ID and dither choices).
    pub fn new<C: crate::config::TileConfig>(
        width: u16,
        height: u16,
        tile: (u16, u16),
        clear: crate::frame::Clear,
    ) -> Self {
        use crate::{dither::Dither, format::PixelFormat, fragment::DepthMode, fragment::WidMode};
        type F<C> = <C as crate::config::TileConfig>::Format;
        let mut format = [0u8; 8];
        let name = <F<C> as PixelFormat>::NAME;
        let n = name.len().min(8);
        format[..n].copy_from_slice(&name.as_bytes()[..n]);
        SceneHeader {
            width,
            height,
            tile,
            format,
            dither_log2: <C::Dither as Dither>::NEW.log2() as u8,
            depth_bits: <C::Depth as DepthMode>::BITS as u8,
            wid_bits: <C::Wid as WidMode>::BITS as u8,
            clear,
            cull: Cull::None,
        }
    }

    /// `Ok` when the scene was made for tiles of configuration `C`.
    pub fn check<C: crate::config::TileConfig>(&self) -> Result<(), Error> {
        let want = SceneHeader {
            cull: self.cull,
            ..Self::new::<C>(self.width, self.height, self.tile, self.clear)
        };
        if want == *self {
            Ok(())
        } else {
            Err(Error::ConfigMismatch)
        }
    }

    /// A frame for this screen in tiles of `tile` (use [`SceneHeader::tile`] or smaller).
    pub fn frame(&self, tile: (u16, u16)) -> Result<crate::frame::Frame, Error> {
        let mut f = crate::frame::Frame::new(self.width, self.height, tile.0, tile.1)?;
        f.clear = self.clear;
        f.cull = self.cull;
        Ok(f)
    }

    /// Writes the [`HEADER_LEN`] header bytes.
    pub fn encode(&self, buf: &mut [u8]) -> Result<(), Error> {
        let mut w = Writer {
            buf,
            pos: 0,
            alpha: false,
        };
        w.put(&MAGIC)?;
        for v in [self.width, self.height, self.tile.0, self.tile.1] {
            w.put(&v.to_le_bytes())?;
        }
        w.put(&self.format)?;
        w.put(&[self.dither_log2, self.depth_bits, self.wid_bits])?;
        let c = &self.clear;
        w.put(&[c.color.r, c.color.g, c.color.b])?;
        w.put(&c.depth.to_le_bytes())?;
        w.put(&[c.wid, self.cull as u8, 0, 0])
    }

    /// Splits an encoded scene into its header and its commands.
    pub fn parse(bytes: &[u8]) -> Result<(SceneHeader, Encoded<'_>), Error> {
        let mut r = Reader {
            buf: bytes,
            pos: 0,
            alpha: false,
        };
        if r.take::<4>()? != MAGIC {
            return Err(Error::Malformed);
        }
        let (width, height, tw, th) = (r.u16()?, r.u16()?, r.u16()?, r.u16()?);
        let format = r.take::<8>()?;
        let [dither_log2, depth_bits, wid_bits] = r.take::<3>()?;
        let color = r.rgb()?;
        let depth = r.u16()?;
        let [wid, cull, _, _] = r.take::<4>()?;
        let cull = match cull {
            0 => Cull::None,
            1 => Cull::Back,
            2 => Cull::Front,
            _ => return Err(Error::Malformed),
        };
        let clear = crate::frame::Clear { color, depth, wid };
        let h = SceneHeader {
            width,
            height,
            tile: (tw, th),
            format,
            dither_log2,
            depth_bits,
            wid_bits,
            clear,
            cull,
        };
        Ok((h, Encoded(&bytes[HEADER_LEN..])))
    }
}

/// An encoded list is a frame's command source read in place: it decodes
/// (and validates) as it goes. A command's key is its ordinal (each of a
/// mesh record's triangles counts one), so a tile decodes only its own
/// commands, straight from flash, and a list of fewer than 2^16 commands
/// has keys the bins store in 16 bits ([`crate::bin`]).
impl crate::frame::CommandSource for Encoded<'_> {
    fn each_keyed(&self, mut f: impl FnMut(u32, &Command)) -> Result<(), Error> {
        self.walk(|key, item| {
            match item {
                Item::Triangle(m, at) => {
                    // Valid once its indices are (the assertion on
                    // `MeshCursor::bounds`).
                    let cmd = m.triangle(at)?;
                    debug_assert!(cmd.validate().is_ok());
                    f(key, &cmd)
                }
                Item::Command(cmd) => f(key, cmd),
            }
            Ok(())
        })
    }

    fn each_bounds(
        &self,
        cells: bool,
        area: bool,
        cull: Cull,
        f: impl FnMut(u32, Option<Rect>),
    ) -> Result<(), Error> {
        self.each_bounds_in(cells, area, cull, i32::MIN..i32::MAX, f)
    }

    fn each_bounds_in(
        &self,
        cells: bool,
        area: bool,
        cull: Cull,
        rows: Range<i32>,
        mut f: impl FnMut(u32, Option<Rect>),
    ) -> Result<(), Error> {
        // A mesh triangle's colours and depths are not decoded, nor its x
        // when its y misses `rows`. Inlined into the walk: out of line, at
        // the micro:bit's `opt-level = "s"`, each triangle paid a call and
        // a 100-byte frame (its demo bins in four passes, each visiting
        // every triangle).
        self.walk(
            #[inline(always)]
            |key, item| {
                let b = match item {
                    Item::Triangle(m, at) => m.bounds(at, cells, &rows, cull)?,
                    Item::Command(cmd) => crate::frame::bin_bounds(cmd, cells, area, cull),
                };
                f(key, b);
                Ok(())
            },
        )
    }

    fn replay(&self, keys: impl Iterator<Item = u32>, mut f: impl FnMut(&Command)) {
        self.replay_items(keys, |item| match item {
            Item::Triangle(m, at) => {
                if let Ok(cmd) = m.triangle(at) {
                    f(&cmd);
                }
            }
            Item::Command(cmd) => f(cmd),
        });
    }

    /// Mesh triangles go to the tile's mesh path as their compact vertices,
    /// not as decoded commands: under the plane contract
    /// ([`PlaneContract`](crate::numeric::PlaneContract)) the fused
    /// routine draws them; under the exact contract the tile turns them
    /// back into the same commands, so the pixels are those of
    /// [`replay`](crate::frame::CommandSource::replay). Records whose
    /// vertices carry α keep the command path. Under the exact contract
    /// every triangle is replayed as its command, as by default (the mesh
    /// routine would only rebuild it, a deeper stack: the micro:bit's
    /// SSD1306-only build, 6 KB of RAM with its stack, measured 148 bytes
    /// over).
    fn draw_keys<const N: usize, C: crate::config::TileConfig>(
        &self,
        keys: impl Iterator<Item = u32>,
        tile: &mut crate::tile::Tile<N, C>,
    ) -> u32 {
        if !<C::Precision as crate::numeric::Precision>::PLANE {
            return crate::frame::replay_commands(self, keys, tile);
        }
        let mut n = 0;
        self.replay_items(keys, |item| match item {
            Item::Triangle(m, at) if !m.alpha => {
                if let Ok([a, b, c]) = m.mesh_triangle(at) {
                    tile.draw_mesh_triangle([&a, &b, &c], &m.state);
                    n += 1;
                }
            }
            Item::Triangle(m, at) => {
                if let Ok(cmd) = m.triangle(at) {
                    tile.draw_valid(&cmd, &[]);
                    n += 1;
                }
            }
            Item::Command(cmd) => {
                tile.draw_valid(cmd, &[]);
                n += 1;
            }
        });
        n
    }
}

impl Encoded<'_> {
    /// [`CommandSource::replay`](crate::frame::CommandSource::replay)'s
    /// walk: calls `f` with the item of each key, in order (a mesh
    /// triangle undecoded).
    #[inline(always)]
    fn replay_items(&self, keys: impl Iterator<Item = u32>, mut f: impl FnMut(Item<'_, '_>)) {
        let all = self.0;
        // A record start at or before every key still to come, and the key
        // of its first command.
        let (mut pos, mut next) = (0usize, 0usize);
        // The last mesh record met: its cursor, its first triangle's key
        // and its triangles.
        let mut mesh: Option<(MeshCursor<'_>, usize, usize)> = None;
        // The list was validated by `each_keyed`: nothing below can fail,
        // and a key that does not name a command is skipped.
        for key in keys.map(|k| k as usize) {
            if let Some((m, first, n)) = &mesh {
                let k = key.wrapping_sub(*first);
                if k < *n {
                    f(Item::Triangle(m, 6 * k));
                    continue;
                }
            }
            while let Some(rest) = all.get(pos..).filter(|r| !r.is_empty() && next <= key) {
                if is_mesh(rest[0]) {
                    let Ok((m, n)) = mesh_record(rest) else {
                        return;
                    };
                    let (first, count) = (next, m.indices.len() / 6);
                    pos += n;
                    next += count;
                    if key < next {
                        f(Item::Triangle(&m, 6 * (key - first)));
                        mesh = Some((m, first, count));
                        break;
                    }
                } else {
                    let Ok((cmd, n)) = decode(rest) else { return };
                    pos += n;
                    next += 1;
                    if next - 1 == key {
                        f(Item::Command(&cmd));
                        break;
                    }
                }
            }
        }
    }
}
