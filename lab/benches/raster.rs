//! Host throughput of the core's inner loops, in pixels per second
//! (criterion; figures go to the README, never into a timed test).
//!
//! Each benchmark renders into one 64x64 tile (512 groups of 8 pixels):
//! 300 random Gouraud triangles (about 20 px across) with and without Z,
//! window ID and dither, and flat area fills — throughput counts pixels
//! rasterized (covered pixels summed over triangles, overdraw included) —
//! and the firmware's line workload, Bresenham, Wu, `embedded-graphics`'
//! `Line` and `tiny-skia`'s antialiased hairline, whose throughput counts
//! steps along the lines' major axes. The triangles are also drawn with all
//! their edges antialiased (seed 003 eq. 8), counted by the same pixels.
//!
//! Group `large`: the firmware's large-triangle workloads (eight triangles
//! in pairs covering a 32x32 tile, `tilerast_fw::workloads`), the same
//! commands and tile types whose instructions per pixel
//! `reports/targets.md` counts on the M0 and M4 — Gouraud, + Z, + Z +
//! window ID + 8x8 dither, alpha-blended, fast Phong, textured (affine,
//! quadratic, exact). Group `filled`: flat filled triangles, small (~3 px)
//! and large (~1,160 px), ours against `embedded-graphics`' `Triangle` and
//! `tiny-skia`'s path fill without antialiasing
//! ([`tilerast_lab::frames::FillScene`]), per covered pixel.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use std::hint::black_box;
use tilerast::prelude::*;
use tilerast_sim::rng::Rng;

const T: u32 = 64;
type Base<F, Z, W, D> = Tile<512, Planes<F, Z, W, D>>;

fn triangles() -> Vec<Command> {
    let mut rng = Rng::new(0x1234_5678_9ABC_DEF1);
    (0..300)
        .map(|_| {
            let (cx, cy) = (rng.range(0, T as i64 * 16), rng.range(0, T as i64 * 16));
            let mut v = || {
                let c = Rgb::new(rng.byte(), rng.byte(), rng.byte());
                let (x, y) = (cx + rng.range(-200, 200), cy + rng.range(-200, 200));
                Vertex::new(
                    Coord::from_bits(x as i32),
                    Coord::from_bits(y as i32),
                    rng.range(0, 65535) as u16,
                    c,
                )
            };
            Command::Triangle {
                v: [v(), v(), v()],
                state: State::default(),
            }
        })
        .collect()
}

fn bench_tile<F: PixelFormat, Z: DepthMode, W: WidMode, D: Dither>(
    c: &mut Criterion,
    group: &str,
    name: &str,
    cmds: &[Command],
    pixels: u64,
) {
    bench_config::<512, Planes<F, Z, W, D>>(c, group, name, cmds, &[], T, pixels);
}

/// Clears a `side` x `side` tile of configuration `C` and draws `cmds`
/// (textured ones with `textures`), `pixels` elements an iteration.
fn bench_config<const N: usize, C: TileConfig>(
    c: &mut Criterion,
    group: &str,
    name: &str,
    cmds: &[Command],
    textures: &[Texture<'_>],
    side: u32,
    pixels: u64,
) {
    let mut g = c.benchmark_group(group);
    g.throughput(Throughput::Elements(pixels));
    let mut tile: Box<Tile<N, C>> = Box::default();
    let area = Rect::new(0, 0, side, side);
    g.bench_function(BenchmarkId::from_parameter(name), |b| {
        b.iter(|| {
            tile.begin(area, &Clear::default()).unwrap();
            for cmd in cmds {
                tile.draw_textured(black_box(cmd), textures).unwrap();
            }
            black_box(tile.raw(0, 0))
        })
    });
    g.finish();
}

/// The firmware's large-triangle workloads, per covered pixel.
fn large(c: &mut Criterion) {
    use tilerast_fw::workloads::*;
    const N: usize = groups(SIDE as u16, SIDE as u16);
    let px = covered_pixels(&LARGE_TRIANGLE_CMDS, SIDE).expect("32x32 fits");
    macro_rules! large {
        ($($cfg:ty, $name:literal, $cmds:expr, $tex:expr;)*) => {
            $(bench_config::<N, $cfg>(c, "large", $name, $cmds, $tex, SIDE, px);)*
        };
    }
    large! {
        Rgb565Format, "gouraud_rgb565", &LARGE_TRIANGLE_CMDS, &[];
        Planes<Rgb565Format, Depth16>, "gouraud_z_rgb565", &LARGE_TRIANGLE_CMDS, &[];
        Planes<Rgb565Format, Depth16, Wid8, Bayer8>, "gouraud_z_wid_dither8_rgb565", &LARGE_TRIANGLE_CMDS, &[];
        BlendBench, "blend_z_rgb565", &LARGE_BLEND_CMDS, &[];
        QuadBench, "fast_phong_z_rgb565", &LARGE_QUAD_CMDS, &[];
        TexBench<AffineTexturing>, "tex_affine_z_rgb565", &LARGE_TEX_CMDS, &TEXTURES;
        TexBench<QuadraticTexturing>, "tex_quadratic_z_rgb565", &LARGE_TEX_CMDS, &TEXTURES;
        TexBench<ExactTexturing>, "tex_exact_z_rgb565", &LARGE_TEX_CMDS, &TEXTURES;
    }
}

/// Flat filled triangles: ours, `embedded-graphics`, `tiny-skia`.
fn filled(c: &mut Criterion) {
    use tilerast_lab::frames::{FillScene, FILL_SIZES};
    for (size, n, radius) in FILL_SIZES {
        let mut s = FillScene::new(n, radius);
        let mut g = c.benchmark_group("filled");
        g.throughput(Throughput::Elements(s.pixels));
        g.bench_function(
            BenchmarkId::from_parameter(format!("{size}_ours_rgb565")),
            |b| b.iter(|| s.ours()),
        );
        g.bench_function(
            BenchmarkId::from_parameter(format!("{size}_eg_triangle_rgb565")),
            |b| b.iter(|| s.eg()),
        );
        g.bench_function(
            BenchmarkId::from_parameter(format!("{size}_tinyskia_fill_rgba8888")),
            |b| b.iter(|| s.skia()),
        );
        g.finish();
    }
}

fn raster(c: &mut Criterion) {
    let tris = triangles();
    let px = tilerast_fw::workloads::covered_pixels(&tris, T).expect("64x64 fits");
    macro_rules! tri {
        ($($f:ty, $z:ty, $w:ty, $d:ty, $name:literal;)*) => {
            $(bench_tile::<$f, $z, $w, $d>(c, "triangles", $name, &tris, px);)*
        };
    }
    // The same triangles with every edge antialiased (eq. 8) after them:
    // the pixel count stays the triangles', so the ratio is the edges' cost.
    let mut with_edges = tris.clone();
    for c in &tris {
        if let Command::Triangle { v, state } = c {
            with_edges.extend((0..3).map(|i| Command::Edge {
                edge: tilerast::line::EdgeCmd::of_triangle(v, i),
                state: *state,
            }));
        }
    }
    bench_tile::<Rgb565Format, Depth16, NoWid, NoDither>(
        c,
        "triangles",
        "gouraud_z_edge_aa_rgb565",
        &with_edges,
        px,
    );
    tri! {
        Rgb565Format, NoDepth, NoWid, NoDither, "gouraud_rgb565";
        Rgb565Format, Depth16, NoWid, NoDither, "gouraud_z_rgb565";
        Rgb565Format, Depth16, Wid8, NoDither, "gouraud_z_wid_rgb565";
        Rgb565Format, Depth16, Wid8, Bayer8, "gouraud_z_wid_dither8_rgb565";
        Rgb888Format, Depth16, NoWid, NoDither, "gouraud_z_rgb888";
        BinaryFormat, Depth16, NoWid, Bayer4, "gouraud_z_dither4_binary";
    }

    // Lines: per step along the major axis; ours and embedded-graphics' Line.
    use tilerast_fw::workloads::{self, LINE_CMDS, WU_LINE_CMDS};
    let steps = workloads::line_steps(&LINE_CMDS);
    bench_tile::<Rgb565Format, NoDepth, NoWid, NoDither>(
        c,
        "lines",
        "bresenham_rgb565",
        &LINE_CMDS,
        steps,
    );
    bench_tile::<Rgb565Format, NoDepth, NoWid, NoDither>(
        c,
        "lines",
        "wu_rgb565",
        &WU_LINE_CMDS,
        steps,
    );
    {
        let mut g = c.benchmark_group("lines");
        g.throughput(Throughput::Elements(steps));
        let mut tile: Box<Base<Rgb565Format, NoDepth, NoWid, NoDither>> = Box::default();
        g.bench_function(BenchmarkId::from_parameter("eg_line_rgb565"), |b| {
            b.iter(|| {
                workloads::eg_primitives(&mut tile, black_box(&LINE_CMDS), &mut || 0).unwrap()
            })
        });
        // tiny-skia's antialiased hairline, into its native premultiplied
        // RGBA8888 pixmap (cleared each time, as our tile is): compare with
        // our Wu line in RGB888.
        let paths: Vec<tiny_skia::Path> = LINE_CMDS
            .iter()
            .filter_map(|c| match c {
                Command::Line { line: l, .. } => {
                    let mut pb = tiny_skia::PathBuilder::new();
                    pb.move_to(l.p0.0.to_num(), l.p0.1.to_num());
                    pb.line_to(l.p1.0.to_num(), l.p1.1.to_num());
                    pb.finish()
                }
                _ => None,
            })
            .collect();
        let mut pixmap = tiny_skia::Pixmap::new(T, T).unwrap();
        let mut paint = tiny_skia::Paint::default();
        paint.set_color_rgba8(255, 255, 255, 255);
        paint.anti_alias = true;
        let hairline = tiny_skia::Stroke {
            width: 0.0,
            ..Default::default()
        };
        g.bench_function(
            BenchmarkId::from_parameter("tinyskia_hairline_aa_rgba8888"),
            |b| {
                b.iter(|| {
                    pixmap.fill(tiny_skia::Color::BLACK);
                    for p in &paths {
                        pixmap.stroke_path(
                            black_box(p),
                            &paint,
                            &hairline,
                            tiny_skia::Transform::identity(),
                            None,
                        );
                    }
                    black_box(pixmap.pixels()[0])
                })
            },
        );
        g.finish();
    }
    bench_tile::<Rgb888Format, NoDepth, NoWid, NoDither>(
        c,
        "lines",
        "wu_rgb888",
        &WU_LINE_CMDS,
        steps,
    );

    let fills: Vec<Command> = (0..16)
        .map(|i| Command::Fill {
            rect: Rect::new(0, 0, T, T),
            color: Rgb::new(i * 16, 100, 200),
            state: State::default(),
            alpha: 255,
        })
        .collect();
    let fpx = 16 * (T * T) as u64;
    bench_tile::<Rgb565Format, NoDepth, NoWid, NoDither>(c, "fill", "flat_rgb565", &fills, fpx);
    bench_tile::<Rgb565Format, NoDepth, Wid8, NoDither>(c, "fill", "flat_wid_rgb565", &fills, fpx);
}

/// The simulator's frames, its planes and dither values
/// ([`tilerast_sim::render`]: `Switchable` depth and window ID,
/// `RuntimeDither`) against the same frame with them fixed by type (the
/// simulator's pipelines before they were values), per screen pixel: what
/// the simulator's fast build costs in speed.
fn sim(c: &mut Criterion) {
    use tilerast::area::AreaAa;
    use tilerast_sim::render::{render_as, SIM_GROUPS};
    let scene = |name: &str| {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../scenes")
            .join(name);
        tilerast_sim::Scene::load(&path).expect("scene loads")
    };
    let mut g = c.benchmark_group("sim");
    macro_rules! pair {
        ($($file:literal, $name:literal, $f:ty, $z:ty, $w:ty, $d:ty;)*) => {$({
            let s = scene($file);
            let cfg = s.config;
            g.throughput(Throughput::Elements(cfg.width as u64 * cfg.height as u64));
            let fixed = render_as::<$f, $z, $w, $d, AreaAa, FullPrecision, SIM_GROUPS>(&cfg, &s.commands, 0).unwrap();
            assert_eq!(tilerast_sim::render(&cfg, &s.commands).unwrap().raw, fixed.raw, $file);
            g.bench_function(BenchmarkId::from_parameter(concat!($name, "_values")), |b| {
                b.iter(|| tilerast_sim::render(&cfg, black_box(&s.commands)).unwrap())
            });
            g.bench_function(BenchmarkId::from_parameter(concat!($name, "_types")), |b| {
                b.iter(|| {
                    render_as::<$f, $z, $w, $d, AreaAa, FullPrecision, SIM_GROUPS>(&cfg, black_box(&s.commands), 0)
                        .unwrap()
                })
            });
        })*};
    }
    pair! {
        "demo.toml", "demo_rgb444_z_wid_dither8", Rgb444Format, Depth16, Wid8, Bayer8;
        "ssd1306.toml", "ssd1306_1bit_z_dither4", BinaryFormat, Depth16, NoWid, Bayer4;
        "teapot.toml", "teapot_rgb565_z", Rgb565Format, Depth16, NoWid, NoDither;
    }
    g.finish();
}

criterion_group!(benches, raster, large, filled, sim);
criterion_main!(benches);
