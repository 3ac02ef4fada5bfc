//! Whole frames and filled triangles on the host, timed in one run
//! (median of repeated renders; `tilerast-lab frames`, run by
//! `cargo xtask report`): the core tiled and binned against one big tile
//! and against the f64 reference renderer on the seeds' meshes, and
//! filled triangles against `embedded-graphics` and `tiny-skia`.

use std::time::Instant;
use tilerast::prelude::*;
use tilerast_sim::render::render_timed;
use tilerast_sim::{reference, rng::Rng, Scene};

/// Median wall time of `runs` calls of `f`, in seconds.
pub fn median(runs: usize, mut f: impl FnMut()) -> f64 {
    let mut t: Vec<f64> = (0..runs)
        .map(|_| {
            let s = Instant::now();
            f();
            s.elapsed().as_secs_f64()
        })
        .collect();
    t.sort_by(f64::total_cmp);
    t[t.len() / 2]
}

/// One timed scene: core tiled, core as one tile, f64 reference (ms).
pub struct FrameTimes {
    /// Scene name.
    pub name: String,
    /// Triangles in the scene.
    pub triangles: usize,
    /// Core, the scene's tiles, binned.
    pub tiled_ms: f64,
    /// Core, one tile the size of the screen.
    pub whole_ms: f64,
    /// The f64 reference renderer.
    pub reference_ms: f64,
}

/// Times a scene file three ways.
pub fn frame(
    path: &std::path::Path,
    runs: usize,
) -> Result<FrameTimes, Box<dyn std::error::Error>> {
    frame_of(Scene::load(path)?, path, runs, true)
}

/// [`frame`] of a loaded scene; `whole`: the one-big-tile render too
/// (`NaN` otherwise).
fn frame_of(
    s: Scene,
    path: &std::path::Path,
    runs: usize,
    whole: bool,
) -> Result<FrameTimes, Box<dyn std::error::Error>> {
    let cmds = &s.commands;
    // The pipeline alone (`render_timed`: tiles and bins allocated once,
    // each finished tile discarded), in seconds per frame.
    let px = s.config.width as f64 * s.config.height as f64;
    let timed = |cfg: &tilerast_sim::Config| -> Result<f64, Box<dyn std::error::Error>> {
        Ok(render_timed(cfg, cmds, runs)?
            .ns_per_pixel
            .unwrap_or(f64::NAN)
            * px
            * 1e-9)
    };
    let tiled = timed(&s.config)?;
    let whole_t = if whole {
        let mut one = s.config;
        one.tile = (one.width, one.height);
        timed(&one)?
    } else {
        f64::NAN
    };
    let reference_t = median(runs.min(5), || {
        std::hint::black_box(reference::render(&s.config, cmds));
    });
    Ok(FrameTimes {
        name: path
            .file_stem()
            .unwrap_or_default()
            .to_string_lossy()
            .into(),
        triangles: cmds
            .iter()
            .filter(|c| matches!(c, Command::Triangle { .. }))
            .count(),
        tiled_ms: tiled * 1e3,
        whole_ms: whole_t * 1e3,
        reference_ms: reference_t * 1e3,
    })
}

/// Filled triangles, one size class: ns per covered pixel for ours (flat
/// RGB565, no Z, one 256x256 tile), `embedded-graphics`' `Triangle` into
/// the same tile as a `DrawTarget`, and `tiny-skia`'s path fill (no AA).
pub struct FillTimes {
    /// "small" or "large".
    pub size: &'static str,
    /// Approximate pixels per triangle.
    pub pixels_each: f64,
    /// Ours.
    pub ours_ns: f64,
    /// embedded-graphics.
    pub eg_ns: f64,
    /// tiny-skia.
    pub skia_ns: f64,
}

/// The side of [`FillScene`]'s screen.
pub const FILL_SIDE: u32 = 256;

type FillTile = Tile<{ groups(FILL_SIDE as u16, FILL_SIDE as u16) }, Rgb565Format>;

/// `n` random flat white triangles of about `radius` pixels on a 256x256
/// screen, ready to draw three ways: ours (RGB565, no Z, one tile),
/// `embedded-graphics`' `Triangle` into the same tile as a `DrawTarget`,
/// and `tiny-skia`'s path fill without antialiasing (RGBA8888 pixmap).
/// [`fills`] times them here, the `raster` criterion bench too.
pub struct FillScene {
    /// Pixels covered, summed over the triangles (our own render of each).
    pub pixels: u64,
    /// Triangles.
    pub n: usize,
    cmds: Vec<Command>,
    tris: Vec<[(i64, i64); 3]>,
    tile: Box<FillTile>,
    pixmap: tiny_skia::Pixmap,
    paint: tiny_skia::Paint<'static>,
    paths: Vec<tiny_skia::Path>,
}

impl FillScene {
    /// The scene (seeded by `radius`: the same triangles every time).
    pub fn new(n: usize, radius: i64) -> FillScene {
        use embedded_graphics::{pixelcolor::Rgb565, prelude::*};
        let s = FILL_SIDE as i64;
        let mut rng = Rng::new(0xF111_7E57 + radius as u64);
        let tris: Vec<[(i64, i64); 3]> = (0..n)
            .map(|_| {
                let (cx, cy) = (rng.range(radius, s - radius), rng.range(radius, s - radius));
                [(); 3].map(|_| {
                    (
                        cx + rng.range(-radius, radius),
                        cy + rng.range(-radius, radius),
                    )
                })
            })
            .collect();
        let white = Rgb::new(255, 255, 255);
        let cmds: Vec<Command> = tris
            .iter()
            .map(|t| {
                Command::triangle(
                    t.map(|(x, y)| Vertex::new(Coord::from_num(x), Coord::from_num(y), 0, white)),
                )
            })
            .collect();
        let mut tile: Box<FillTile> = Box::default();
        let mut pixels = 0u64;
        for c in &cmds {
            tile.begin(Self::area(), &Clear::default()).unwrap();
            tile.draw(c).unwrap();
            pixels += tile.colors().filter(|c| *c != Rgb565::BLACK).count() as u64;
        }
        let mut paint = tiny_skia::Paint::default();
        paint.set_color_rgba8(255, 255, 255, 255);
        paint.anti_alias = false;
        let paths = tris
            .iter()
            .filter_map(|t| {
                let mut pb = tiny_skia::PathBuilder::new();
                pb.move_to(t[0].0 as f32, t[0].1 as f32);
                pb.line_to(t[1].0 as f32, t[1].1 as f32);
                pb.line_to(t[2].0 as f32, t[2].1 as f32);
                pb.close();
                pb.finish()
            })
            .collect();
        FillScene {
            pixels,
            n,
            cmds,
            tris,
            tile,
            pixmap: tiny_skia::Pixmap::new(FILL_SIDE, FILL_SIDE).expect("size"),
            paint,
            paths,
        }
    }

    fn area() -> Rect {
        Rect::new(0, 0, FILL_SIDE, FILL_SIDE)
    }

    /// Ours: clear the tile, draw every triangle.
    pub fn ours(&mut self) {
        self.tile.begin(Self::area(), &Clear::default()).unwrap();
        for c in &self.cmds {
            self.tile.draw(std::hint::black_box(c)).unwrap();
        }
    }

    /// `embedded-graphics`: clear the tile, fill every `Triangle`.
    pub fn eg(&mut self) {
        use embedded_graphics::{pixelcolor::Rgb565, prelude::*, primitives::*};
        let style = PrimitiveStyle::with_fill(Rgb565::WHITE);
        self.tile.begin(Self::area(), &Clear::default()).unwrap();
        for t in &self.tris {
            let [a, b, c] = t.map(|(x, y)| Point::new(x as i32, y as i32));
            let _ = Triangle::new(a, b, c)
                .into_styled(style)
                .draw(&mut *self.tile);
        }
    }

    /// `tiny-skia`: clear the pixmap, fill every path (no antialiasing).
    pub fn skia(&mut self) {
        self.pixmap.fill(tiny_skia::Color::BLACK);
        for p in &self.paths {
            self.pixmap.fill_path(
                std::hint::black_box(p),
                &self.paint,
                tiny_skia::FillRule::Winding,
                tiny_skia::Transform::identity(),
                None,
            );
        }
    }
}

/// The two size classes [`FillScene`] is measured at: name, triangles,
/// radius (about 3 and 1,160 pixels a triangle).
pub const FILL_SIZES: [(&str, usize, i64); 2] = [("small", 4000, 3), ("large", 200, 60)];

/// Times `n` random triangles of about `radius` pixels ([`FillScene`]).
pub fn fills(size: &'static str, n: usize, radius: i64, runs: usize) -> FillTimes {
    let mut s = FillScene::new(n, radius);
    let ours = median(runs, || s.ours());
    let eg = median(runs, || s.eg());
    let skia = median(runs, || s.skia());
    let per = |t: f64| t * 1e9 / s.pixels as f64;
    FillTimes {
        size,
        pixels_each: s.pixels as f64 / n as f64,
        ours_ns: per(ours),
        eg_ns: per(eg),
        skia_ns: per(skia),
    }
}

/// The scene at `k` times its size: screen and vertex positions scaled, so
/// each triangle covers `k^2` times the pixels (its setup costs the same).
/// Triangles only (what the mesh scenes hold).
pub fn scaled(mut s: Scene, k: u16) -> Result<Scene, Box<dyn std::error::Error>> {
    let dim = |d: u16| d.checked_mul(k).ok_or("scaled: the screen outgrows u16");
    (s.config.width, s.config.height) = (dim(s.config.width)?, dim(s.config.height)?);
    for c in &mut s.commands {
        let Command::Triangle { v, .. } = c else {
            return Err("scaled: a scene of triangles only".into());
        };
        for p in v.iter_mut() {
            p.x = Coord::from_bits(p.x.to_bits() * k as i32);
            p.y = Coord::from_bits(p.y.to_bits() * k as i32);
        }
    }
    Ok(s)
}

/// Screen scales of [`report`]'s size series.
pub const SCALES: [u16; 4] = [1, 2, 4, 8];

/// The rotating teapot as the Cortex-M4 firmware draws it
/// (`tilerast_fw::spin`: the f32 vertex stage, the plane contract,
/// RGB565 + Z16 in 64x32 tiles), timed on the host over its frames, and
/// the f64 reference drawing the same triangles (the stage's output).
pub struct SpinTimes {
    /// Frames timed (one turn).
    pub frames: u32,
    /// Triangles drawn, a frame on average.
    pub triangles: f64,
    /// The core: vertex stage, binning and raster, ms a frame.
    pub core_ms: f64,
    /// The core's vertex stage alone, ms a frame.
    pub vertex_ms: f64,
    /// The f64 reference on the stage's triangles, ms a frame.
    pub reference_ms: f64,
}

/// Times [`SpinTimes`]: each frame `runs` times, medians summed.
pub fn spin(model: &std::path::Path, runs: usize) -> Result<SpinTimes, Box<dyn std::error::Error>> {
    use tilerast::geometry::{Mesh, VertexSlot};
    use tilerast_fw::spin;
    let bytes = tilerast_sim::mesh::export_mesh(model, &tilerast_sim::Limits::default())?;
    let mesh = Mesh::parse(&bytes)?;
    let mut slots = vec![VertexSlot::EMPTY; mesh.vertices() as usize];
    let mut tile = Box::new(Tile::<{ groups(64, 32) }, spin::SpinConfig>::new());
    let mut bins = Box::new(Bins::<4096, 32>::new());
    let cfg = tilerast_sim::Config {
        width: spin::SIDE,
        height: spin::SIDE,
        format: tilerast_sim::FormatKind::Rgb565,
        tile: (64, 32),
        dither: 0,
        depth: true,
        wid: false,
        clear: Clear {
            color: spin::BACKGROUND,
            ..Clear::default()
        },
        aa: tilerast_sim::AaKind::None,
        cull: tilerast::command::Cull::None,
    };
    const FRAMES: u32 = 8;
    let mut t = SpinTimes {
        frames: FRAMES,
        triangles: 0.0,
        core_ms: 0.0,
        vertex_ms: 0.0,
        reference_ms: 0.0,
    };
    for k in 0..FRAMES {
        let mut frame = |each: Option<&mut dyn FnMut(&Command)>| {
            spin::frame_discard::<f32, { groups(64, 32) }, 4096, 32>(
                &mesh,
                &mut slots,
                &mut tile,
                &mut bins,
                (64, 32),
                (k, FRAMES),
                each,
            )
        };
        let mut cmds = Vec::new();
        frame(Some(&mut |c: &Command| cmds.push(*c)))?;
        t.triangles += cmds.len() as f64 / FRAMES as f64;
        t.core_ms += 1e3
            * median(runs, || {
                std::hint::black_box(frame(None).unwrap());
            });
        t.vertex_ms += 1e3
            * median(runs, || {
                spin::vertex_only::<f32>(&mesh, &mut slots, (k, FRAMES)).unwrap();
            });
        t.reference_ms += 1e3
            * median(runs, || {
                std::hint::black_box(reference::render(&cfg, &cmds));
            });
    }
    let n = FRAMES as f64;
    (t.core_ms, t.vertex_ms, t.reference_ms) = (t.core_ms / n, t.vertex_ms / n, t.reference_ms / n);
    Ok(t)
}

/// The report: Markdown tables of both measurements.
pub fn report(
    scenes: &[std::path::PathBuf],
    runs: usize,
) -> Result<String, Box<dyn std::error::Error>> {
    let mut md = String::from(
        "# Host frames and fills\n\nGenerated by `tilerast-lab frames` (`cargo xtask report`): medians of \
         repeated renders in one process (this shared VM varies between runs; compare ratios \
         within a run).\n\n## Whole frames\n\n| scene | triangles | core, its tiles (binned) ms | \
         core, one big tile ms | f64 reference ms | tiled / big tile | reference / core |\n\
         | --- | ---: | ---: | ---: | ---: | ---: | ---: |\n",
    );
    for p in scenes {
        let f = frame(p, runs)?;
        md += &format!(
            "| {} | {} | {:.2} | {:.2} | {:.2} | {:.2}x | {:.1}x |\n",
            f.name,
            f.triangles,
            f.tiled_ms,
            f.whole_ms,
            f.reference_ms,
            f.tiled_ms / f.whole_ms,
            f.reference_ms / f.tiled_ms
        );
    }
    let s = spin(std::path::Path::new("assets/models/teapot.obj"), runs)?;
    md += &format!(
        "\n## The rotating teapot, as the firmware draws it\n\n\
         `tilerast_fw::spin` on the host: the f32 vertex stage (transform, cull, light), binning \
         and the plane contract's mesh path, RGB565 + Z16 in 64x32 tiles, each tile discarded, \
         over {} frames of a turn; the f64 reference draws the triangles the stage emits. \
         Milliseconds a frame.\n\n\
         | triangles drawn | core, whole frame | of which the vertex stage | the rest: binning \
         and raster | f64 reference, raster only | reference / core, whole frame | reference / \
         core, raster |\n| ---: | ---: | ---: | ---: | ---: | ---: | ---: |\n\
         | {:.0} | {:.3} | {:.3} | {:.3} | {:.3} | {:.1}x | {:.1}x |\n",
        s.frames,
        s.triangles,
        s.core_ms,
        s.vertex_ms,
        s.core_ms - s.vertex_ms,
        s.reference_ms,
        s.reference_ms / s.core_ms,
        s.reference_ms / (s.core_ms - s.vertex_ms)
    );
    if let Some(first) = scenes.first() {
        md += &format!(
            "\n## Triangle size: the first scene at 1x to {}x\n\n\
             The same triangles with the screen and every vertex scaled by `k` (`frames::scaled`): \
             setup per triangle stays, pixels per triangle grow `k^2` times. The core in its \
             tiles (binned) against the f64 reference, per triangle.\n\n\
             | scale | screen | core, its tiles ms | f64 reference ms | core ns / triangle | \
             reference ns / triangle | reference / core |\n\
             | --- | --- | ---: | ---: | ---: | ---: | ---: |\n",
            SCALES[SCALES.len() - 1]
        );
        for k in SCALES {
            let s = scaled(Scene::load(first)?, k)?;
            let (w, h) = (s.config.width, s.config.height);
            let f = frame_of(s, first, runs, false)?;
            let per = |ms: f64| ms * 1e6 / f.triangles as f64;
            md += &format!(
                "| {k}x | {w}x{h} | {:.2} | {:.2} | {:.0} | {:.0} | {:.1}x |\n",
                f.tiled_ms,
                f.reference_ms,
                per(f.tiled_ms),
                per(f.reference_ms),
                f.reference_ms / f.tiled_ms
            );
        }
    }
    md += "\n## Filled triangles (no antialiasing), ns per covered pixel\n\n\
           Ours: flat RGB565 triangles into one 256x256 tile (setup included); `embedded-graphics`: \
           `Triangle` with a fill style into the same tile as a `DrawTarget`; `tiny-skia`: \
           `fill_path`, anti-alias off, RGBA8888 pixmap.\n\n\
           | triangles | px each | ours | embedded-graphics | tiny-skia | e-g / ours | tiny-skia / ours |\n\
           | --- | ---: | ---: | ---: | ---: | ---: | ---: |\n";
    for f in FILL_SIZES.map(|(size, n, r)| fills(size, n, r, runs)) {
        md += &format!(
            "| {} | {:.0} | {:.2} | {:.2} | {:.2} | {:.2}x | {:.2}x |\n",
            f.size,
            f.pixels_each,
            f.ours_ns,
            f.eg_ns,
            f.skia_ns,
            f.eg_ns / f.ours_ns,
            f.skia_ns / f.ours_ns
        );
    }
    Ok(md)
}

#[cfg(test)]
mod tests {
    use super::*;

    const TRI: &str = "[screen]\nwidth = 40\nheight = 30\nformat = \"rgb565\"\n\n[[command]]\nkind = \"triangle\"\n\
                       v = [[4, 4, 100, 250, 0, 0], [30.5, 6, 100, 0, 250, 0], [5, 25.25, 100, 0, 0, 250]]\n";

    #[test]
    fn scaling_multiplies_the_screen_and_every_vertex() {
        let parse = |s: &str| Scene::parse(s, std::path::Path::new(".")).unwrap();
        let (one, two) = (parse(TRI), scaled(parse(TRI), 3).unwrap());
        assert_eq!((two.config.width, two.config.height), (120, 90));
        let (Command::Triangle { v: a, .. }, Command::Triangle { v: b, .. }) =
            (&one.commands[0], &two.commands[0])
        else {
            panic!("a triangle")
        };
        for (a, b) in a.iter().zip(b) {
            assert_eq!(b.x.to_bits(), 3 * a.x.to_bits());
            assert_eq!(b.y.to_bits(), 3 * a.y.to_bits());
            assert_eq!((b.z, b.color), (a.z, a.color));
        }
        let fill = "[screen]\nwidth = 8\nheight = 8\nformat = \"rgb565\"\n\n[[command]]\nkind = \"fill\"\n\
                    rect = [0, 0, 4, 4]\nrgb = [1, 2, 3]\n";
        assert!(scaled(parse(fill), 2).is_err());
        assert!(scaled(parse(TRI), 2000).is_err());
    }
}
