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
    for cmd in cmds {
        match cmd {
            Command::WidFill { rect, wid } => {
                if cfg.wid {
                    for_rect(rect, &screen, |x, y| f.wid[(y * w + x) as usize] = *wid);
                }
            }
            Command::Fill { rect, color, state } => for_rect(rect, &screen, |x, y| {
                let i = (y * w + x) as usize;
                if !cfg.wid || f.wid[i] == state.wid {
                    f.color[i] = rgb(*color);
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
                        c,
                        z,
                        state.wid,
                    );
                }
            }
            Command::Triangle { v, state } => triangle(&mut f, cfg, v, state.wid),
            Command::Line { line, state } => line_ref(&mut f, cfg, line, state.wid),
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

fn fragment(f: &mut RefFrame, cfg: &Config, i: usize, c: [f64; 3], z: f64, wid: u8) {
    if cfg.wid && f.wid[i] != wid {
        return;
    }
    if cfg.depth {
        // Less-than, as the core, but on exact (unquantized) depths.
        if z >= f.depth[i] {
            return;
        }
        f.depth[i] = z;
    }
    f.color[i] = c;
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
            fragment(f, cfg, i, rgb(l.color), z, wid);
        }
        c += dir;
        k += 1;
    }
}

/// Two-point antialiased lines in f64: every column the line's extent
/// touches along the major axis, weighted by the part of the cell it covers;
/// the two pixels straddling the exact line at the column centre share that
/// weight by distance, and are blended over what is there (seed 003 eq. 7),
/// Z-tested without writing Z.
fn wu_ref(f: &mut RefFrame, cfg: &Config, l: &LineCmd, wid: u8) {
    let p = [l.p0, l.p1].map(|(x, y)| (x.to_bits() as f64, y.to_bits() as f64));
    let y_major = (p[1].1 - p[0].1).abs() > (p[1].0 - p[0].0).abs();
    let mm = p.map(|(x, y)| if y_major { (y, x) } else { (x, y) });
    let reversed = mm[1].0 < mm[0].0;
    let (lo, hi) = if reversed { (1, 0) } else { (0, 1) };
    let (a, b) = (mm[lo], mm[hi]);
    let z = [l.z[lo] as f64, l.z[hi] as f64];
    if a.0 == b.0 {
        return;
    }
    let (first, last) = (
        (a.0 / 16.0).floor() as i64,
        ((b.0 - 1.0) / 16.0).floor() as i64,
    );
    for c in first..=last {
        let k = if reversed { last - c } else { c - first } as u32;
        if !l.style.on(k) {
            continue;
        }
        let cell = 16.0 * c as f64;
        let cover = ((b.0.min(cell + 16.0) - a.0.max(cell)) / 16.0).clamp(0.0, 1.0);
        let t = (cell + 8.0 - a.0) / (b.0 - a.0);
        let minor = a.1 + t * (b.1 - a.1);
        let u = (minor - 8.0) / 16.0;
        let r0 = u.floor();
        let w1 = (u - r0) * cover;
        let zc = z[0] + t * (z[1] - z[0]);
        for (r, w) in [(r0 as i64, cover - w1), (r0 as i64 + 1, w1)] {
            let (x, y) = if y_major { (r, c) } else { (c, r) };
            if w <= 0.0 || x < 0 || y < 0 || x >= f.width as i64 || y >= f.height as i64 {
                continue;
            }
            let i = (y as u32 * f.width + x as u32) as usize;
            if (cfg.wid && f.wid[i] != wid) || (cfg.depth && zc >= f.depth[i]) {
                continue;
            }
            let line = rgb(l.color);
            f.color[i] = std::array::from_fn(|ch| f.color[i][ch] + (line[ch] - f.color[i][ch]) * w);
        }
    }
}

fn triangle(f: &mut RefFrame, cfg: &Config, v: &[Vertex; 3], wid: u8) {
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
            let c: [f64; 3] =
                std::array::from_fn(|ch| (0..3).map(|i| w[i] * rgb(vv[i].color)[ch]).sum());
            let z: f64 = (0..3).map(|i| w[i] * vv[i].z as f64).sum();
            fragment(
                f,
                cfg,
                (py as u32 * f.width + px as u32) as usize,
                c,
                z,
                wid,
            );
        }
    }
}
