//! How close each antialiasing mode comes to the ideal picture — seed 003's
//! comparison (Bresenham vs two-point lines, aliased vs edge-antialiased
//! solids), measured instead of shown: every render is compared with the
//! 16x16 supersampled ideal ([`reference::supersample`]) by the RUF seed's
//! eq. 8 colour error, PSNR and max error. Peers render the same geometry:
//! `embedded-graphics`' `Line` and `tiny-skia`'s antialiased hairline and
//! path fill.
//!
//! Cost is measured elsewhere, on the same workloads' kind: criterion
//! (`host-sim/benches/raster.rs`) on the host and QEMU instruction counts on
//! the chips (`targets/`).

use tilerast::line::EdgeCmd;
use tilerast::prelude::*;
use tilerast_sim::image::Image;
use tilerast_sim::metrics::{compare, Diff};
use tilerast_sim::reference;
use tilerast_sim::render::{render, render_timed, AaKind, Config, FormatKind};
use tilerast_sim::rng::Rng;
use tilerast_sim::scene::Scene;

/// Supersampling of the ideal: 16x16 samples per pixel.
pub const IDEAL_SAMPLES: u32 = 16;

/// One measured render.
#[derive(Debug, Clone)]
pub struct Measured {
    /// What was drawn.
    pub subject: String,
    /// Who drew it, how.
    pub mode: String,
    /// Against the ideal.
    pub diff: Diff,
    /// The render.
    pub image: Image,
    /// Our renders' cost: host ns per screen pixel (median of
    /// [`TIMED_RUNS`]) and the tile's bits per pixel.
    pub cost: Option<(f64, u32)>,
}

/// Timed renders per measured mode of ours (the median is reported).
pub const TIMED_RUNS: usize = 5;

fn config(w: u16, h: u16) -> Config {
    Config {
        width: w,
        height: h,
        format: FormatKind::Rgb888,
        tile: (w, h),
        dither: 0,
        depth: false,
        wid: false,
        clear: Clear::default(),
        aa: tilerast_sim::render::AaKind::None,
        cull: tilerast::command::Cull::None,
    }
}

/// 40 white lines, 8 to 60 px long at every angle, with sub-pixel end
/// points, on black: 128x96 RGB888.
pub fn line_scene() -> (Config, Vec<Command>) {
    let mut rng = Rng::new(0x003A_A11E);
    let cmds = (0..40)
        .map(|_| {
            let (x, y) = (rng.range(8 * 16, 120 * 16), rng.range(8 * 16, 88 * 16));
            let angle = rng.range(0, 3600) as f64 / 3600.0 * std::f64::consts::TAU;
            let len = rng.range(8 * 16, 60 * 16) as f64;
            let (x1, y1) = (
                (x as f64 + len * angle.cos()).clamp(0.0, 127.0 * 16.0) as i32,
                (y as f64 + len * angle.sin()).clamp(0.0, 95.0 * 16.0) as i32,
            );
            Command::Line {
                line: LineCmd {
                    p0: (Coord::from_bits(x as i32), Coord::from_bits(y as i32)),
                    p1: (Coord::from_bits(x1), Coord::from_bits(y1)),
                    z: [0, 0],
                    color: Rgb::new(255, 255, 255),
                    style: LineStyle::SOLID,
                    antialias: false,
                },
                state: State::default(),
            }
        })
        .collect();
    (config(128, 96), cmds)
}

/// 24 flat-coloured triangles, 6 to 40 px across, at distinct depths over
/// a dark background: 128x96 RGB888 with Z, and the triangles.
pub fn solid_scene() -> (Config, Vec<[Vertex; 3]>) {
    let mut rng = Rng::new(0x003E_D6E5);
    let tris = (0..24)
        .map(|k| {
            let (cx, cy) = (rng.range(0, 128 * 16), rng.range(0, 96 * 16));
            let size = rng.range(6 * 16, 40 * 16);
            let c = Rgb::new(rng.byte() | 64, rng.byte() | 64, rng.byte() | 64);
            [0, 1, 2].map(|_| {
                let x = cx + rng.range(-size / 2, size / 2);
                let y = cy + rng.range(-size / 2, size / 2);
                Vertex::new(
                    Coord::from_bits(x as i32),
                    Coord::from_bits(y as i32),
                    1000 + 2000 * k as u16,
                    c,
                )
            })
        })
        .collect();
    let mut cfg = config(128, 96);
    cfg.depth = true;
    cfg.clear.color = Rgb::new(24, 24, 40);
    (cfg, tris)
}

/// The lines switched to two-point antialiasing (or back).
pub fn with_line_aa(cmds: &[Command], aa: bool) -> Vec<Command> {
    cmds.iter()
        .map(|c| match *c {
            Command::Line { line, state } => Command::Line {
                line: LineCmd {
                    antialias: aa,
                    ..line
                },
                state,
            },
            other => other,
        })
        .collect()
}

/// The triangles, then (with `aa`) every edge of each, antialiased.
pub fn solids(tris: &[[Vertex; 3]], aa: bool) -> Vec<Command> {
    let state = State::default();
    let mut cmds: Vec<Command> = tris
        .iter()
        .map(|&v| Command::Triangle { v, state })
        .collect();
    if aa {
        for v in tris {
            cmds.extend((0..3).map(|i| Command::Edge {
                edge: EdgeCmd::of_triangle(v, i),
                state,
            }));
        }
    }
    cmds
}

/// An RGB888 image as an `embedded-graphics` target.
pub(crate) struct Canvas(pub(crate) Image);

impl embedded_graphics::prelude::OriginDimensions for Canvas {
    fn size(&self) -> embedded_graphics::prelude::Size {
        embedded_graphics::prelude::Size::new(self.0.width, self.0.height)
    }
}

impl embedded_graphics::draw_target::DrawTarget for Canvas {
    type Color = embedded_graphics::pixelcolor::Rgb888;
    type Error = core::convert::Infallible;
    fn draw_iter<I>(&mut self, pixels: I) -> Result<(), Self::Error>
    where
        I: IntoIterator<Item = embedded_graphics::Pixel<Self::Color>>,
    {
        use embedded_graphics::pixelcolor::RgbColor;
        let (w, h) = (self.0.width as i32, self.0.height as i32);
        for embedded_graphics::Pixel(p, c) in pixels {
            if (0..w).contains(&p.x) && (0..h).contains(&p.y) {
                self.0.pixels[(p.y * w + p.x) as usize] = [c.r(), c.g(), c.b()];
            }
        }
        Ok(())
    }
}

fn background(cfg: &Config) -> Image {
    let c = cfg.clear.color;
    let mut img = Image::new(cfg.width as u32, cfg.height as u32);
    img.pixels.fill([c.r, c.g, c.b]);
    img
}

/// The lines drawn by `embedded-graphics`' `Line` (1 px stroke, end points
/// rounded to whole pixels, as its integer API requires).
pub fn eg_lines(cfg: &Config, cmds: &[Command]) -> Image {
    use embedded_graphics::{
        pixelcolor::Rgb888,
        prelude::*,
        primitives::{Line, PrimitiveStyle},
    };
    let mut canvas = Canvas(background(cfg));
    let px = |(x, y): (Coord, Coord)| {
        Point::new(
            (x - Coord::from_num(0.5)).round().to_num(),
            (y - Coord::from_num(0.5)).round().to_num(),
        )
    };
    for c in cmds {
        if let Command::Line { line: l, .. } = c {
            let color = Rgb888::new(l.color.r, l.color.g, l.color.b);
            let _ = Line::new(px(l.p0), px(l.p1))
                .into_styled(PrimitiveStyle::with_stroke(color, 1))
                .draw(&mut canvas);
        }
    }
    canvas.0
}

fn pixmap(cfg: &Config) -> tiny_skia::Pixmap {
    let mut p = tiny_skia::Pixmap::new(cfg.width as u32, cfg.height as u32).expect("size");
    let c = cfg.clear.color;
    p.fill(tiny_skia::Color::from_rgba8(c.r, c.g, c.b, 255));
    p
}

fn from_pixmap(p: &tiny_skia::Pixmap) -> Image {
    Image {
        width: p.width(),
        height: p.height(),
        pixels: p
            .pixels()
            .iter()
            .map(|c| [c.red(), c.green(), c.blue()])
            .collect(),
    }
}

fn paint(c: Rgb) -> tiny_skia::Paint<'static> {
    let mut paint = tiny_skia::Paint::default();
    paint.set_color_rgba8(c.r, c.g, c.b, 255);
    paint.anti_alias = true;
    paint
}

/// The lines drawn by `tiny-skia` with antialiasing: `width` 0 is its
/// hairline (it also draws strokes up to 1 px wide as hairlines).
pub fn skia_lines(cfg: &Config, cmds: &[Command], width: f32) -> Image {
    let mut pm = pixmap(cfg);
    let stroke = tiny_skia::Stroke {
        width,
        ..Default::default()
    };
    for c in cmds {
        if let Command::Line { line: l, .. } = c {
            let mut pb = tiny_skia::PathBuilder::new();
            pb.move_to(l.p0.0.to_num(), l.p0.1.to_num());
            pb.line_to(l.p1.0.to_num(), l.p1.1.to_num());
            if let Some(path) = pb.finish() {
                pm.stroke_path(
                    &path,
                    &paint(l.color),
                    &stroke,
                    tiny_skia::Transform::identity(),
                    None,
                );
            }
        }
    }
    from_pixmap(&pm)
}

/// The triangles filled by `tiny-skia` with antialiasing, far to near.
pub fn skia_fill(cfg: &Config, tris: &[[Vertex; 3]]) -> Image {
    let mut pm = pixmap(cfg);
    let mut order: Vec<&[Vertex; 3]> = tris.iter().collect();
    order.sort_by_key(|t| std::cmp::Reverse(t[0].z));
    for t in order {
        let mut pb = tiny_skia::PathBuilder::new();
        pb.move_to(t[0].x.to_num(), t[0].y.to_num());
        pb.line_to(t[1].x.to_num(), t[1].y.to_num());
        pb.line_to(t[2].x.to_num(), t[2].y.to_num());
        pb.close();
        if let Some(path) = pb.finish() {
            pm.fill_path(
                &path,
                &paint(t[0].color),
                tiny_skia::FillRule::Winding,
                tiny_skia::Transform::identity(),
                None,
            );
        }
    }
    from_pixmap(&pm)
}

fn measured(subject: &str, mode: &str, image: Image, ideal: &Image) -> Measured {
    Measured {
        subject: subject.into(),
        mode: mode.into(),
        diff: compare(&image, ideal).expect("same size"),
        image,
        cost: None,
    }
}

fn ours(cfg: &Config, cmds: &[Command]) -> Image {
    render(cfg, cmds).expect("valid scene").image
}

/// Our render in antialiasing mode `aa`, timed, measured against `ideal`.
fn ours_measured(
    subject: &str,
    mode: &str,
    cfg: &Config,
    aa: AaKind,
    cmds: &[Command],
    ideal: &Image,
) -> Measured {
    let cfg = Config { aa, ..*cfg };
    let r = render_timed(&cfg, cmds, TIMED_RUNS).expect("valid scene");
    Measured {
        cost: Some((r.ns_per_pixel.unwrap_or(0.0), r.bits_per_pixel)),
        ..measured(subject, mode, r.image, ideal)
    }
}

/// The coverage families beside the aliased render and seed 003's edges:
/// the RE's area sampling through α (seed 001 §IV.5), the RUF buffer
/// (seed 000) and supersampling at the same 8 samples.
fn coverage_rows(s: &str, cfg: &Config, cmds: &[Command], ideal: &Image) -> Vec<Measured> {
    [
        (AaKind::Area, "tilerast area sampling (α, seed 001)"),
        (AaKind::Ruf8, "tilerast RUF-8 (seed 000)"),
        (AaKind::Ss8, "tilerast supersampling, 8 sparse"),
    ]
    .iter()
    .map(|&(aa, mode)| ours_measured(s, mode, cfg, aa, cmds, ideal))
    .collect()
}

/// Every mode on the line scene, the solid scene and the scene files given
/// (rendered with edge antialiasing off and on), each with its ideal.
pub fn measure(scenes: &[Scene]) -> Vec<(Image, Vec<Measured>)> {
    let mut out = Vec::new();

    let (cfg, lines) = line_scene();
    let ideal = reference::supersample(&cfg, &lines, IDEAL_SAMPLES).to_image();
    let s = "40 lines, 128x96";
    out.push((
        ideal.clone(),
        vec![
            measured(s, "tilerast Bresenham", ours(&cfg, &lines), &ideal),
            measured(s, "embedded-graphics Line", eg_lines(&cfg, &lines), &ideal),
            measured(
                s,
                "tilerast two-point (Wu)",
                ours(&cfg, &with_line_aa(&lines, true)),
                &ideal,
            ),
            measured(
                s,
                "tiny-skia hairline, AA",
                skia_lines(&cfg, &lines, 0.0),
                &ideal,
            ),
        ],
    ));

    let (cfg, tris) = solid_scene();
    let ideal = reference::supersample(&cfg, &solids(&tris, false), IDEAL_SAMPLES).to_image();
    let s = "24 triangles, 128x96";
    let (plain, edged) = (solids(&tris, false), solids(&tris, true));
    let mut rows = vec![
        ours_measured(s, "tilerast aliased", &cfg, AaKind::None, &plain, &ideal),
        ours_measured(
            s,
            "tilerast edge AA (eq. 8)",
            &cfg,
            AaKind::None,
            &edged,
            &ideal,
        ),
    ];
    rows.extend(coverage_rows(s, &cfg, &plain, &ideal));
    rows.push(measured(
        s,
        "tiny-skia path fill, AA",
        skia_fill(&cfg, &tris),
        &ideal,
    ));
    out.push((ideal.clone(), rows));

    for scene in scenes {
        let mut sc = scene.clone();
        let mut cfg = sc.config;
        cfg.format = FormatKind::Rgb888;
        cfg.dither = 0;
        let s = format!("{}, {}x{}", sc.name, cfg.width, cfg.height);
        sc.set_edge_aa(false);
        let ideal = reference::supersample(&cfg, &sc.commands, IDEAL_SAMPLES).to_image();
        let plain = sc.commands.clone();
        let mut rows = vec![ours_measured(
            &s,
            "tilerast aliased",
            &cfg,
            AaKind::None,
            &plain,
            &ideal,
        )];
        sc.set_edge_aa(true);
        rows.push(ours_measured(
            &s,
            "tilerast edge AA (eq. 8)",
            &cfg,
            AaKind::None,
            &sc.commands,
            &ideal,
        ));
        rows.extend(coverage_rows(&s, &cfg, &plain, &ideal));
        out.push((ideal.clone(), rows));
    }
    out
}

/// The measurements as a Markdown table.
pub fn table(groups: &[(Image, Vec<Measured>)]) -> String {
    let mut s = String::from(
        "| subject | renderer, mode | eq. 8 error per pixel | PSNR (dB) | max abs error | host ns / px | tile bits / px |\n| --- | --- | ---: | ---: | ---: | ---: | ---: |\n",
    );
    for (_, rows) in groups {
        for m in rows {
            let (ns, bits) = match m.cost {
                Some((ns, bits)) => (format!("{ns:.1}"), bits.to_string()),
                None => ("—".into(), "—".into()),
            };
            s += &format!(
                "| {} | {} | {:.1} | {:.2} | {} | {ns} | {bits} |\n",
                m.subject, m.mode, m.diff.mse_per_pixel, m.diff.psnr, m.diff.max_abs
            );
        }
    }
    s
}

/// One row per subject: the ideal, then each mode, side by side, each
/// enlarged `zoom` times (nearest neighbour), 4 px apart on grey.
pub fn montage(groups: &[(Image, Vec<Measured>)], zoom: u32) -> Image {
    let gap = 4;
    let rows: Vec<Vec<&Image>> = groups
        .iter()
        .map(|(ideal, ms)| {
            std::iter::once(ideal)
                .chain(ms.iter().map(|m| &m.image))
                .collect()
        })
        .collect();
    let width = rows
        .iter()
        .map(|r| r.iter().map(|i| i.width * zoom + gap).sum::<u32>())
        .max()
        .unwrap_or(0);
    let height: u32 = rows
        .iter()
        .map(|r| r.iter().map(|i| i.height * zoom).max().unwrap_or(0) + gap)
        .sum();
    let mut out = Image::new(width, height);
    out.pixels.fill([128; 3]);
    let mut y0 = 0;
    for r in rows {
        let mut x0 = 0;
        for img in &r {
            for y in 0..img.height * zoom {
                for x in 0..img.width * zoom {
                    out.pixels[((y0 + y) * width + x0 + x) as usize] = img.get(x / zoom, y / zoom);
                }
            }
            x0 += img.width * zoom + gap;
        }
        y0 += r.iter().map(|i| i.height * zoom).max().unwrap_or(0) + gap;
    }
    out
}
