//! The f64 reference renderer: the same display list, rendered the obvious
//! way — every pixel of a triangle's bounding box tested against exact edge
//! functions (same sub-pixel vertices, same top-left rule), colour and depth
//! interpolated in f64 with barycentric weights, depth compared in f64, no
//! dither, no quantization. It shares no rasterization code with the core.
//!
//! Partial plane masks are not modelled (a masked command writes its whole
//! colour): scenes that use them compare with an error.

use crate::image::Image;
use crate::render::Config;
use tilerast::line::{EdgeCmd, Side};
use tilerast::prelude::*;

/// An f64 frame: colour on the 0..255 scale (luma replicated for grey
/// formats) and depth on the 0..65535 scale.
#[derive(Debug, Clone)]
pub struct RefFrame {
    /// Width.
    pub width: u32,
    /// Height.
    pub height: u32,
    /// Colour per pixel.
    pub color: Vec<[f64; 3]>,
    /// Depth per pixel.
    pub depth: Vec<f64>,
    /// Window ID per pixel.
    pub wid: Vec<u8>,
}

impl RefFrame {
    /// Rounded to an 8-bit image.
    pub fn to_image(&self) -> Image {
        Image {
            width: self.width,
            height: self.height,
            pixels: self
                .color
                .iter()
                .map(|c| c.map(|v| v.round().clamp(0.0, 255.0) as u8))
                .collect(),
        }
    }
}

fn rgb(c: Rgb) -> [f64; 3] {
    [c.r as f64, c.g as f64, c.b as f64]
}

/// Renders `cmds` in f64.
pub fn render(cfg: &Config, cmds: &[Command]) -> RefFrame {
    render_shaded(cfg, cmds, &|_, _| None)
}

/// Renders `cmds` in f64 with `textures` for their textured triangles
/// ([`Command::Textured`]): the exact perspective coordinates
/// `u = Σ w_k u_k q_k / Σ w_k q_k` at every pixel centre, the texture
/// sampled there in f64 (nearest: the texel holding it; bilinear: the four
/// around `u - 1/2` with exact weights; wrap as the texture says), times
/// the Gouraud-interpolated shade `/ 255`. Without textures (or a `tex`
/// past them) a textured triangle draws its shade, as the core does.
pub fn render_textured(cfg: &Config, cmds: &[Command], textures: &[Texture<'_>]) -> RefFrame {
    render_full(cfg, cmds, &|_, _| None, textures)
}

/// The filtered colour of `t` at `(u, v)` texels, in f64 ([`render_textured`]).
pub fn sample(t: &Texture<'_>, u: f64, v: f64) -> [f64; 3] {
    let (wrap, filter) = t.modes();
    let (w, h) = t.size();
    let at = |i: f64, n: u16| -> u32 {
        let i = i as i64;
        match wrap {
            Wrap::Clamp => i.clamp(0, n as i64 - 1) as u32,
            Wrap::Repeat => i.rem_euclid(n as i64) as u32,
        }
    };
    match filter {
        Filter::Nearest => rgb(t.texel(at(u.floor(), w), at(v.floor(), h))),
        Filter::Bilinear => {
            let (u, v) = (u - 0.5, v - 0.5);
            let (i, j) = (u.floor(), v.floor());
            let (fu, fv) = (u - i, v - j);
            let c = |di: f64, dj: f64| rgb(t.texel(at(i + di, w), at(j + dj, h)));
            let (a, b, c, d) = (c(0.0, 0.0), c(1.0, 0.0), c(0.0, 1.0), c(1.0, 1.0));
            std::array::from_fn(|k| {
                let top = a[k] * (1.0 - fu) + b[k] * fu;
                let bot = c[k] * (1.0 - fu) + d[k] * fu;
                top * (1.0 - fv) + bot * fv
            })
        }
    }
}

/// The exact texture coordinates (texels) of a textured triangle at
/// barycentric weights `w` (command vertex order).
pub fn tex_coords(v: &[TexVertex; 3], w: [f64; 3]) -> (f64, f64) {
    let q: f64 = (0..3).map(|k| w[k] * v[k].q as f64).sum();
    let s = |f: fn(&TexVertex) -> u16| {
        (0..3)
            .map(|k| w[k] * v[k].q as f64 * f(&v[k]) as f64)
            .sum::<f64>()
            / (16.0 * q)
    };
    (s(|t| t.u), s(|t| t.v))
}

/// A triangle's colour at a point from its barycentric weights (in the
/// command's vertex order), or `None` for the command's own shading.
pub type Shader<'a> = dyn Fn(usize, [f64; 3]) -> Option<[f64; 3]> + 'a;

/// Renders `cmds` in f64, the colour of triangle command `k` at weights
/// `w` taken from `shader(k, w)` where it gives one (exact Phong: the
/// normal interpolated and normalised at every pixel).
pub fn render_shaded(cfg: &Config, cmds: &[Command], shader: &Shader<'_>) -> RefFrame {
    render_full(cfg, cmds, shader, &[])
}

fn render_full(
    cfg: &Config,
    cmds: &[Command],
    shader: &Shader<'_>,
    textures: &[Texture<'_>],
) -> RefFrame {
    let (w, h) = (cfg.width as u32, cfg.height as u32);
    let n = (w * h) as usize;
    let mut f = RefFrame {
        width: w,
        height: h,
        color: vec![rgb(cfg.clear.color); n],
        depth: vec![
            if cfg.depth {
                cfg.clear.depth as f64
            } else {
                f64::INFINITY
            };
            n
        ],
        wid: vec![cfg.clear.wid; n],
    };
    let screen = Rect::new(0, 0, w, h);
    for (k, cmd) in cmds.iter().enumerate() {
        // A triangle the frame culls draws nothing (`Frame::cull`).
        if cmd.culled_by(cfg.cull) {
            continue;
        }
        let shade_at = |w: [f64; 3], own: [f64; 3]| shader(k, w).unwrap_or(own);
        match cmd {
            Command::WidFill { rect, wid } => {
                if cfg.wid {
                    for_rect(rect, &screen, |x, y| f.wid[(y * w + x) as usize] = *wid);
                }
            }
            Command::Fill {
                rect,
                color,
                alpha,
                state,
            } => for_rect(rect, &screen, |x, y| {
                let i = (y * w + x) as usize;
                if !cfg.wid || f.wid[i] == state.wid {
                    f.color[i] = over(state, *alpha as f64 / 255.0, rgb(*color), f.color[i]);
                }
            }),
            Command::ZFill { rect, z, state } => for_rect(rect, &screen, |x, y| {
                let i = (y * w + x) as usize;
                if cfg.depth && (!cfg.wid || f.wid[i] == state.wid) {
                    f.depth[i] = *z as f64;
                }
            }),
            Command::Span { span, state } => {
                for k in 0..span.len as i64 {
                    let (x, y) = (span.x as i64 + k, span.y as i64);
                    if x < 0 || y < 0 || x >= w as i64 || y >= h as i64 {
                        continue;
                    }
                    let lin = |s: f64, d: f64| s + d * k as f64;
                    let c: [f64; 3] = std::array::from_fn(|i| {
                        lin(span.color[i].to_num(), span.dcolor[i].to_num())
                    });
                    let z = lin(span.z.to_num(), span.dz.to_num());
                    fragment(
                        &mut f,
                        cfg,
                        (y as u32 * w + x as u32) as usize,
                        (c, span.alpha as f64 / 255.0),
                        z,
                        state,
                    );
                }
            }
            Command::Triangle { v, state } => {
                triangle(&mut f, cfg, v, state, &|w| shade_at(w, gouraud(v, w)))
            }
            Command::Quadratic { alpha, v, state } => {
                let vs = v.map(|q| q.vertex().with_alpha(*alpha));
                let own = |w| {
                    if sliver(v) {
                        gouraud(&vs, w)
                    } else {
                        quadratic(v, w)
                    }
                };
                triangle(&mut f, cfg, &vs, state, &|w| shade_at(w, own(w)))
            }
            Command::Textured {
                tex,
                alpha,
                shade,
                v,
                state,
            } => {
                let vs = v.map(|t| t.vertex(0).with_alpha(*alpha));
                let tex = textures.get(*tex as usize);
                let own = |w: [f64; 3]| {
                    let l: f64 = (0..3).map(|k| w[k] * shade[k] as f64).sum();
                    match tex {
                        Some(t) => {
                            let (u, v) = tex_coords(v, w);
                            sample(t, u, v).map(|c| c * l / 255.0)
                        }
                        None => [l; 3],
                    }
                };
                triangle(&mut f, cfg, &vs, state, &|w| shade_at(w, own(w)))
            }
            Command::Line { line, state } => line_ref(&mut f, cfg, line, state.wid),
            Command::Edge { edge, state } => edge_ref(&mut f, cfg, edge, state.wid),
            other => unimplemented!("the reference does not model {other:?} yet"),
        }
    }
    if cfg.format.is_gray() {
        for c in &mut f.color {
            let y = (77.0 * c[0] + 150.0 * c[1] + 29.0 * c[2]) / 256.0;
            *c = [y; 3];
        }
    }
    f
}

fn for_rect(r: &Rect, screen: &Rect, mut f: impl FnMut(u32, u32)) {
    if let Some(r) = r.intersect(screen) {
        for y in r.y..r.y1() as i32 {
            for x in r.x..r.x1() as i32 {
                f(x as u32, y as u32);
            }
        }
    }
}

/// A fragment of colour `c` and opacity `a` (0..=1, used when the state
/// blends) after the window-ID and Z tests; Z is written unless the state
/// blends without Z write.
fn fragment(f: &mut RefFrame, cfg: &Config, i: usize, (c, a): ([f64; 3], f64), z: f64, st: &State) {
    if cfg.wid && f.wid[i] != st.wid {
        return;
    }
    if cfg.depth {
        // Less-than, as the core, but on exact (unquantized) depths.
        if z >= f.depth[i] {
            return;
        }
        if st.blend != Blend::Alpha {
            f.depth[i] = z;
        }
    }
    f.color[i] = over(st, a, c, f.color[i]);
}

/// `a c + (1 - a) dst` when the state blends, `c` otherwise.
fn over(st: &State, a: f64, c: [f64; 3], dst: [f64; 3]) -> [f64; 3] {
    if st.blend.translucent() {
        std::array::from_fn(|k| a * c[k] + (1.0 - a) * dst[k])
    } else {
        c
    }
}

/// Lines the obvious way: for each pixel centre along the major axis from
/// `p0` (included) to `p1` (excluded), the pixel containing the exact line.
fn line_ref(f: &mut RefFrame, cfg: &Config, l: &LineCmd, wid: u8) {
    if l.antialias {
        return wu_ref(f, cfg, l, wid);
    }
    let (p, q) = (
        (l.p0.0.to_bits() as i64, l.p0.1.to_bits() as i64),
        (l.p1.0.to_bits() as i64, l.p1.1.to_bits() as i64),
    );
    let y_major = (q.1 - p.1).abs() > (q.0 - p.0).abs();
    // (major, minor) coordinates.
    let (a, b) = if y_major {
        ((p.1, p.0), (q.1, q.0))
    } else {
        (p, q)
    };
    let len = b.0 - a.0;
    if len == 0 {
        return;
    }
    let dir = len.signum();
    // First pixel centre at or after p0 in the direction of travel.
    let mut c = if dir > 0 {
        (a.0 - 8).div_euclid(16) + ((a.0 - 8).rem_euclid(16) != 0) as i64
    } else {
        (a.0 - 8).div_euclid(16)
    };
    let mut k = 0u32;
    loop {
        let centre = 16 * c + 8;
        if (dir > 0 && centre >= b.0) || (dir < 0 && centre <= b.0) {
            break;
        }
        // minor = a.1 + (centre - a.0) (b.1 - a.1) / len, exactly, floored to a pixel.
        let (num, den) = (a.1 * len + (centre - a.0) * (b.1 - a.1), 16 * len);
        let (num, den) = if den < 0 { (-num, -den) } else { (num, den) };
        let minor = num.div_euclid(den);
        let t = (centre - a.0) as f64 / len as f64;
        let z = l.z[0] as f64 + t * (l.z[1] as f64 - l.z[0] as f64);
        let (x, y) = if y_major { (minor, c) } else { (c, minor) };
        if l.style.on(k) && x >= 0 && y >= 0 && x < f.width as i64 && y < f.height as i64 {
            let i = (y as u32 * f.width + x as u32) as usize;
            fragment(f, cfg, i, (rgb(l.color), 1.0), z, &State::new(wid));
        }
        c += dir;
        k += 1;
    }
}

/// The columns of a two-point walk in f64: for every column the segment's
/// extent touches along the major axis, calls `f(k, column, cover, t, u)`
/// with `k` the column's index from `p0`, `cover` the part of the column's
/// cell inside the extent, `t` the column centre's position along the
/// segment from its walk start (0..1, unclamped) and `u` the exact minor
/// position in pixel-centre units. Returns whether y is the major axis and
/// whether the walk runs from `p1` to `p0`.
fn cells_ref(
    p0: (Coord, Coord),
    p1: (Coord, Coord),
    mut f: impl FnMut(u32, i64, f64, f64, f64),
) -> (bool, bool) {
    let p = [p0, p1].map(|(x, y)| (x.to_bits() as f64, y.to_bits() as f64));
    let y_major = (p[1].1 - p[0].1).abs() > (p[1].0 - p[0].0).abs();
    let mm = p.map(|(x, y)| if y_major { (y, x) } else { (x, y) });
    let reversed = mm[1].0 < mm[0].0;
    let (a, b) = if reversed {
        (mm[1], mm[0])
    } else {
        (mm[0], mm[1])
    };
    if a.0 == b.0 {
        return (y_major, reversed);
    }
    let (first, last) = (
        (a.0 / 16.0).floor() as i64,
        ((b.0 - 1.0) / 16.0).floor() as i64,
    );
    for c in first..=last {
        let k = if reversed { last - c } else { c - first } as u32;
        let cell = 16.0 * c as f64;
        let cover = ((b.0.min(cell + 16.0) - a.0.max(cell)) / 16.0).clamp(0.0, 1.0);
        let t = (cell + 8.0 - a.0) / (b.0 - a.0);
        let minor = a.1 + t * (b.1 - a.1);
        f(k, c, cover, t, (minor - 8.0) / 16.0);
    }
    (y_major, reversed)
}

/// Blends `c` with weight `w` over pixel (major, minor), after the window-ID
/// and a read-only Z test.
#[allow(clippy::too_many_arguments)]
fn blend_ref(
    f: &mut RefFrame,
    cfg: &Config,
    y_major: bool,
    (major, minor): (i64, i64),
    c: [f64; 3],
    w: f64,
    z: f64,
    wid: u8,
) {
    let (x, y) = if y_major {
        (minor, major)
    } else {
        (major, minor)
    };
    if w <= 0.0 || x < 0 || y < 0 || x >= f.width as i64 || y >= f.height as i64 {
        return;
    }
    let i = (y as u32 * f.width + x as u32) as usize;
    if (cfg.wid && f.wid[i] != wid) || (cfg.depth && z >= f.depth[i]) {
        return;
    }
    f.color[i] = std::array::from_fn(|ch| f.color[i][ch] + (c[ch] - f.color[i][ch]) * w);
}

/// Two-point antialiased lines in f64: every column the line's extent
/// touches along the major axis, weighted by the part of the cell it covers;
/// the two pixels straddling the exact line at the column centre share that
/// weight by distance, and are blended over what is there (seed 003 eq. 7),
/// Z-tested without writing Z.
fn wu_ref(f: &mut RefFrame, cfg: &Config, l: &LineCmd, wid: u8) {
    let mut cells = Vec::new();
    let (y_major, reversed) = cells_ref(l.p0, l.p1, |k, c, cover, t, u| {
        cells.push((k, c, cover, t, u))
    });
    let z = if reversed { [l.z[1], l.z[0]] } else { l.z }.map(|z| z as f64);
    for (k, c, cover, t, u) in cells {
        if !l.style.on(k) {
            continue;
        }
        let r0 = u.floor();
        let w1 = (u - r0) * cover;
        let zc = z[0] + t * (z[1] - z[0]);
        for (r, w) in [(r0 as i64, cover - w1), (r0 as i64 + 1, w1)] {
            blend_ref(f, cfg, y_major, (c, r), rgb(l.color), w, zc, wid);
        }
    }
}

/// Edge antialiasing in f64 (seed 003 eq. 8): in every column, the pixel
/// outside the solid whose cell the exact edge crosses is blended toward the
/// edge colour (interpolated from the vertices, clamped to them) by the
/// part of it on the solid's side, times the column's cover.
fn edge_ref(f: &mut RefFrame, cfg: &Config, e: &EdgeCmd, wid: u8) {
    let mut cells = Vec::new();
    let [p0, p1] = e.v.map(|v| (v.x, v.y));
    let (y_major, reversed) = cells_ref(p0, p1, |_, c, cover, t, u| cells.push((c, cover, t, u)));
    let v = if reversed { [e.v[1], e.v[0]] } else { e.v };
    let (dx, dy) = (
        (e.v[1].x - e.v[0].x).to_num::<f64>(),
        (e.v[1].y - e.v[0].y).to_num::<f64>(),
    );
    // The solid's side along the minor axis: cross(d, q - p0) grows with +y by
    // dx and with +x by -dy.
    let right_up = if y_major { dy < 0.0 } else { dx > 0.0 };
    let up = right_up == (e.interior == Side::Right);
    for (c, cover, t, u) in cells {
        let r0 = u.floor();
        let d = u - r0;
        let (r, part) = if up {
            (r0, 0.5 - d)
        } else {
            (r0 + 1.0, d - 0.5)
        };
        let tc = t.clamp(0.0, 1.0);
        let col: [f64; 3] = std::array::from_fn(|ch| {
            let [a, b] = v.map(|v| rgb(v.color)[ch]);
            a + tc * (b - a)
        });
        let zc = v[0].z as f64 + t * (v[1].z as f64 - v[0].z as f64);
        blend_ref(f, cfg, y_major, (c, r as i64), col, part * cover, zc, wid);
    }
}

/// Linear interpolation of the vertex colours at weights `w`.
fn gouraud(v: &[Vertex; 3], w: [f64; 3]) -> [f64; 3] {
    std::array::from_fn(|ch| (0..3).map(|i| w[i] * rgb(v[i].color)[ch]).sum())
}

/// Whether the core draws a quadratic triangle Gouraud-shaded (the
/// documented rule of [`Command::Quadratic`]): `κ² (|M| + 16) > 2^45` with
/// `κ = max over edges of (|dy| bw + |dx| bh) / area2` (sub-pixel units,
/// `bw`, `bh` the vertices' extent plus 16) and `|M|` the largest
/// `|2 mid - c_p - c_q|`. Exact in `i128`.
pub fn sliver(v: &[QuadVertex; 3]) -> bool {
    let p = v.map(|v| (v.x.to_bits() as i128, v.y.to_bits() as i128));
    let ext = |f: fn(&(i128, i128)) -> i128| {
        let m = p.map(|q| f(&q));
        m.iter().max().unwrap() - m.iter().min().unwrap() + 16
    };
    let (bw, bh) = (ext(|q| q.0), ext(|q| q.1));
    let area2 =
        ((p[1].0 - p[0].0) * (p[2].1 - p[0].1) - (p[1].1 - p[0].1) * (p[2].0 - p[0].0)).abs();
    let curv = (0..3)
        .flat_map(|k| {
            let (c, d, m) = (rgb(v[k].color), rgb(v[(k + 1) % 3].color), rgb(v[k].mid));
            (0..3).map(move |i| (2.0 * m[i] - c[i] - d[i]).abs() as i128)
        })
        .max()
        .unwrap_or(0);
    (0..3).any(|k| {
        let (a, b) = (p[k], p[(k + 1) % 3]);
        let num = (b.1 - a.1).abs() * bw + (b.0 - a.0).abs() * bh;
        num * num * (curv + 16) > (1 << 45) * area2 * area2
    })
}

/// The quadratic through a [`QuadVertex`] triangle's vertex and midpoint
/// colours at weights `w` (P2 Lagrange form), saturated to `0..=255` as
/// the core saturates it: a bulging surface can overshoot the range
/// inside the triangle even when all six colours are in it.
pub fn quadratic(v: &[QuadVertex; 3], w: [f64; 3]) -> [f64; 3] {
    std::array::from_fn(|ch| {
        (0..3)
            .map(|k| {
                let n = (k + 1) % 3;
                let (c, d, m) = (rgb(v[k].color)[ch], rgb(v[n].color)[ch], rgb(v[k].mid)[ch]);
                w[k] * c + 4.0 * w[k] * w[n] * (m - (c + d) / 2.0)
            })
            .sum::<f64>()
            .clamp(0.0, 255.0)
    })
}

fn triangle(
    f: &mut RefFrame,
    cfg: &Config,
    v: &[Vertex; 3],
    st: &State,
    color: &dyn Fn([f64; 3]) -> [f64; 3],
) {
    // Sub-pixel units (1/16 px): exact integers, exact in f64 too.
    let p: Vec<(i64, i64)> = v
        .iter()
        .map(|v| (v.x.to_bits() as i64, v.y.to_bits() as i64))
        .collect();
    let mut idx = [0usize, 1, 2];
    let cross = |a: (i64, i64), b: (i64, i64), c: (i64, i64)| {
        (b.0 - a.0) * (c.1 - a.1) - (b.1 - a.1) * (c.0 - a.0)
    };
    let mut area = cross(p[0], p[1], p[2]);
    if area == 0 {
        return;
    }
    if area < 0 {
        idx.swap(1, 2);
        area = -area;
    }
    let q = idx.map(|i| p[i]);
    let vv = idx.map(|i| v[i]);
    // Edge i is opposite vertex i; top-left edges own their boundary pixels.
    let edges = [(q[1], q[2]), (q[2], q[0]), (q[0], q[1])];
    let owns = |a: (i64, i64), b: (i64, i64)| {
        let (dx, dy) = (b.0 - a.0, b.1 - a.1);
        dy < 0 || (dy == 0 && dx > 0)
    };
    let min = |k: fn(&(i64, i64)) -> i64| q.iter().map(k).min().unwrap();
    let max = |k: fn(&(i64, i64)) -> i64| q.iter().map(k).max().unwrap();
    let px0 = ((min(|p| p.0) - 8) as f64 / 16.0).ceil().max(0.0) as i64;
    let px1 = ((max(|p| p.0) - 8) as f64 / 16.0)
        .floor()
        .min(f.width as f64 - 1.0) as i64;
    let py0 = ((min(|p| p.1) - 8) as f64 / 16.0).ceil().max(0.0) as i64;
    let py1 = ((max(|p| p.1) - 8) as f64 / 16.0)
        .floor()
        .min(f.height as f64 - 1.0) as i64;
    for py in py0..=py1 {
        for px in px0..=px1 {
            let s = (16 * px + 8, 16 * py + 8);
            let e = edges.map(|(a, b)| cross(a, b, s));
            let inside = (0..3).all(|i| e[i] > 0 || (e[i] == 0 && owns(edges[i].0, edges[i].1)));
            if !inside {
                continue;
            }
            let w = e.map(|e| e as f64 / area as f64);
            let mut wc = [0.0; 3];
            for (i, &k) in idx.iter().enumerate() {
                wc[k] = w[i];
            }
            let c = color(wc);
            let z: f64 = (0..3).map(|i| w[i] * vv[i].z as f64).sum();
            let a: f64 = (0..3).map(|i| w[i] * vv[i].alpha as f64 / 255.0).sum();
            fragment(
                f,
                cfg,
                (py as u32 * f.width + px as u32) as usize,
                (c, a),
                z,
                st,
            );
        }
    }
}

/// The ideal scene, supersampled: an `n x n` regular grid of samples per
/// pixel (at `(i + 1/2) / n`), each with its own colour, depth and window ID,
/// resolved with a box filter. Triangles cover the samples inside their exact
/// edges (top-left rule on ties, as the pipeline), with colour and depth
/// interpolated at the sample; a line is the ideal 1-pixel-wide rectangle
/// from `p0` to `p1` (butt ends), Z-tested without writing Z, whatever its
/// drawing mode; edge-antialiasing commands are skipped (the ideal needs
/// none); fills and spans cover whole pixels. This is the "16x16
/// supersampled reference" that approximate modes are measured against.
///
/// Rendered in blocks of at most [`SAMPLE_BUDGET`] samples (8 rows of
/// the screen, fewer rows or a part of a row when `n` or the width is
/// large), so memory is 33 bytes per screen pixel for the result plus at
/// most 33 bytes per budgeted sample (about 69 MB) whatever `n`: a
/// 4096x8 screen at 64x64 samples needs no more than a 240x160 one.
pub fn supersample(cfg: &Config, cmds: &[Command], n: u32) -> RefFrame {
    supersample_within(cfg, cmds, n, SAMPLE_BUDGET)
}

/// [`supersample`] holding at most `budget` samples (at least one pixel's)
/// at once.
pub fn supersample_within(cfg: &Config, cmds: &[Command], n: u32, budget: u64) -> RefFrame {
    let (w, h) = (cfg.width as u32, cfg.height as u32);
    let mut out = render(cfg, &[]);
    let n = n.max(1);
    let nn = (n * n) as f64;
    let per_px = (n as u64 * n as u64).max(1);
    // Whole rows (up to 8) when they fit the budget, else part of one row.
    let rows = (budget / (per_px * w as u64)).clamp(1, 8) as u32;
    let cols = (budget / per_px).clamp(1, w as u64) as u32;
    for y0 in (0..h).step_by(rows as usize) {
        let bh = rows.min(h - y0);
        for x0 in (0..w).step_by(cols as usize) {
            let bw = cols.min(w - x0);
            let len = (bw * n * bh * n) as usize;
            let mut s = Samples {
                n,
                x0,
                y0,
                sw: bw * n,
                sh: bh * n,
                color: vec![rgb(cfg.clear.color); len],
                depth: vec![
                    if cfg.depth {
                        cfg.clear.depth as f64
                    } else {
                        f64::INFINITY
                    };
                    len
                ],
                wid: vec![cfg.clear.wid; len],
            };
            // Every command clips itself to the block's samples (the
            // pipeline's bounds are pixel-centre bounds; the ideal reaches
            // past them).
            for cmd in cmds.iter().filter(|c| !c.culled_by(cfg.cull)) {
                s.draw(cfg, cmd);
            }
            for py in 0..bh {
                for px in 0..bw {
                    let mut acc = [0.0; 3];
                    for j in 0..n {
                        for i in 0..n {
                            let c = s.color[((py * n + j) * s.sw + px * n + i) as usize];
                            (0..3).for_each(|ch| acc[ch] += c[ch]);
                        }
                    }
                    let o = ((y0 + py) * w + x0 + px) as usize;
                    out.color[o] = acc.map(|v| v / nn);
                    out.wid[o] = s.wid[(py * n * s.sw + px * n) as usize];
                }
            }
        }
    }
    if cfg.format.is_gray() {
        for c in &mut out.color {
            let y = (77.0 * c[0] + 150.0 * c[1] + 29.0 * c[2]) / 256.0;
            *c = [y; 3];
        }
    }
    out
}

/// Samples [`supersample`] holds at once (33 bytes each).
pub const SAMPLE_BUDGET: u64 = 1 << 21;

/// One block of samples.
struct Samples {
    n: u32,
    /// First pixel column of the block.
    x0: u32,
    /// First pixel row of the block.
    y0: u32,
    sw: u32,
    sh: u32,
    color: Vec<[f64; 3]>,
    depth: Vec<f64>,
    wid: Vec<u8>,
}

impl Samples {
    /// Sample index range covering pixel rectangle `r` (clipped), per row.
    fn pixels(&mut self, r: &Rect, mut f: impl FnMut(&mut Self, usize, i64, i64)) {
        let band = Rect::new(
            self.x0 as i32,
            self.y0 as i32,
            self.sw / self.n,
            self.sh / self.n,
        );
        let Some(r) = r.intersect(&band) else { return };
        let (n, x0) = (self.n as i64, self.x0 as i64);
        for py in r.y as i64..r.y1() {
            for px in r.x as i64..r.x1() {
                for j in 0..n {
                    for i in 0..n {
                        let sy = (py - self.y0 as i64) * n + j;
                        let idx = (sy * self.sw as i64 + (px - x0) * n + i) as usize;
                        f(self, idx, px, py);
                    }
                }
            }
        }
    }

    /// The window-ID and depth test of a sample; writes depth when `write_z`.
    fn pass(&mut self, cfg: &Config, i: usize, z: f64, wid: u8, write_z: bool) -> bool {
        if cfg.wid && self.wid[i] != wid {
            return false;
        }
        if cfg.depth {
            if z >= self.depth[i] {
                return false;
            }
            if write_z {
                self.depth[i] = z;
            }
        }
        true
    }

    /// Calls `f(self, index, x, y)` for every sample whose position (in
    /// pixels) lies in the bounding box `[x0, x1] x [y0, y1]`.
    fn samples_in(&mut self, bb: [f64; 4], mut f: impl FnMut(&mut Self, usize, f64, f64)) {
        let n = self.n as f64;
        let (ox, oy) = (self.x0 as f64, self.y0 as f64);
        let (sw, sh) = (self.sw as i64, self.sh as i64);
        // Sample (i, j) sits at (x0 + (i + 0.5) / n, y0 + (j + 0.5) / n).
        let i0 = (((bb[0] - ox) * n - 0.5).ceil() as i64).max(0);
        let i1 = (((bb[1] - ox) * n - 0.5).floor() as i64).min(sw - 1);
        let j0 = (((bb[2] - oy) * n - 0.5).ceil() as i64).max(0);
        let j1 = (((bb[3] - oy) * n - 0.5).floor() as i64).min(sh - 1);
        for j in j0..=j1 {
            for i in i0..=i1 {
                let (x, y) = (ox + (i as f64 + 0.5) / n, oy + (j as f64 + 0.5) / n);
                f(self, (j * sw + i) as usize, x, y);
            }
        }
    }

    fn draw(&mut self, cfg: &Config, cmd: &Command) {
        match cmd {
            Command::WidFill { rect, wid } => {
                if cfg.wid {
                    self.pixels(rect, |s, i, _, _| s.wid[i] = *wid);
                }
            }
            Command::Fill {
                rect,
                color,
                alpha,
                state,
            } => self.pixels(rect, |s, i, _, _| {
                if !cfg.wid || s.wid[i] == state.wid {
                    s.color[i] = over(state, *alpha as f64 / 255.0, rgb(*color), s.color[i]);
                }
            }),
            Command::ZFill { rect, z, state } => self.pixels(rect, |s, i, _, _| {
                if cfg.depth && (!cfg.wid || s.wid[i] == state.wid) {
                    s.depth[i] = *z as f64;
                }
            }),
            Command::Span { span, state } => {
                let r = Rect::new(span.x, span.y, span.len as u32, 1);
                self.pixels(&r, |s, i, px, _| {
                    let k = (px - span.x as i64) as f64;
                    let c = std::array::from_fn(|ch| {
                        span.color[ch].to_num::<f64>() + span.dcolor[ch].to_num::<f64>() * k
                    });
                    let z = span.z.to_num::<f64>() + span.dz.to_num::<f64>() * k;
                    if s.pass(cfg, i, z, state.wid, state.blend != Blend::Alpha) {
                        s.color[i] = over(state, span.alpha as f64 / 255.0, c, s.color[i]);
                    }
                });
            }
            Command::Triangle { v, state } => self.triangle(cfg, v, state, &|w| gouraud(v, w)),
            Command::Quadratic { alpha, v, state } => {
                let vs = v.map(|q| q.vertex().with_alpha(*alpha));
                if sliver(v) {
                    self.triangle(cfg, &vs, state, &|w| gouraud(&vs, w))
                } else {
                    self.triangle(cfg, &vs, state, &|w| quadratic(v, w))
                }
            }
            Command::Line { line, state } => self.line(cfg, line, state.wid),
            Command::Edge { .. } => {}
            other => unimplemented!("the ideal does not model {other:?} yet"),
        }
    }

    fn triangle(
        &mut self,
        cfg: &Config,
        v: &[Vertex; 3],
        st: &State,
        color: &dyn Fn([f64; 3]) -> [f64; 3],
    ) {
        let p = v.map(|v| (v.x.to_num::<f64>(), v.y.to_num::<f64>()));
        let cross = |a: (f64, f64), b: (f64, f64), c: (f64, f64)| {
            (b.0 - a.0) * (c.1 - a.1) - (b.1 - a.1) * (c.0 - a.0)
        };
        let mut idx = [0usize, 1, 2];
        let mut area = cross(p[0], p[1], p[2]);
        if area == 0.0 {
            return;
        }
        if area < 0.0 {
            idx.swap(1, 2);
            area = -area;
        }
        let q = idx.map(|i| p[i]);
        let vv = idx.map(|i| v[i]);
        let edges = [(q[1], q[2]), (q[2], q[0]), (q[0], q[1])];
        let owns = |a: (f64, f64), b: (f64, f64)| b.1 < a.1 || (b.1 == a.1 && b.0 > a.0);
        let bb = [
            q.iter().map(|p| p.0).fold(f64::INFINITY, f64::min),
            q.iter().map(|p| p.0).fold(f64::NEG_INFINITY, f64::max),
            q.iter().map(|p| p.1).fold(f64::INFINITY, f64::min),
            q.iter().map(|p| p.1).fold(f64::NEG_INFINITY, f64::max),
        ];
        self.samples_in(bb, |s, i, x, y| {
            let e = edges.map(|(a, b)| cross(a, b, (x, y)));
            if !(0..3).all(|k| e[k] > 0.0 || (e[k] == 0.0 && owns(edges[k].0, edges[k].1))) {
                return;
            }
            let wt = e.map(|e| e / area);
            let z: f64 = (0..3).map(|k| wt[k] * vv[k].z as f64).sum();
            if s.pass(cfg, i, z, st.wid, st.blend != Blend::Alpha) {
                let mut wc = [0.0; 3];
                for (j, &k) in idx.iter().enumerate() {
                    wc[k] = wt[j];
                }
                let c = color(wc);
                let a: f64 = (0..3).map(|k| wt[k] * vv[k].alpha as f64 / 255.0).sum();
                s.color[i] = over(st, a, c, s.color[i]);
            }
        });
    }

    fn line(&mut self, cfg: &Config, l: &LineCmd, wid: u8) {
        let [p, q] = [l.p0, l.p1].map(|(x, y)| (x.to_num::<f64>(), y.to_num::<f64>()));
        let (dx, dy) = (q.0 - p.0, q.1 - p.1);
        let len = (dx * dx + dy * dy).sqrt();
        if len == 0.0 {
            return;
        }
        let (ux, uy) = (dx / len, dy / len);
        let major = |x: f64, y: f64| if dy.abs() > dx.abs() { y } else { x };
        let bb = [
            p.0.min(q.0) - 0.5,
            p.0.max(q.0) + 0.5,
            p.1.min(q.1) - 0.5,
            p.1.max(q.1) + 0.5,
        ];
        let c = rgb(l.color);
        self.samples_in(bb, |s, i, x, y| {
            let (rx, ry) = (x - p.0, y - p.1);
            let t = rx * ux + ry * uy;
            let d = rx * uy - ry * ux;
            if !(0.0..len).contains(&t) || d.abs() > 0.5 {
                return;
            }
            // Style: pixels counted along the major axis from p0.
            let k = (major(x, y) - major(p.0, p.1)).abs().floor() as u32;
            let z = l.z[0] as f64 + t / len * (l.z[1] as f64 - l.z[0] as f64);
            if l.style.on(k) && s.pass(cfg, i, z, wid, false) {
                s.color[i] = c;
            }
        });
    }
}
