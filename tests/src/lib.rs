//! Helpers shared by the integration tests: paths, golden images, a small
//! deterministic PRNG, and configurations.

use std::path::PathBuf;
use tilerast::prelude::*;
use tilerast_sim::{Config, FormatKind, Image};

/// The repository root.
pub fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// A scene file under `scenes/`.
pub fn scene(name: &str) -> PathBuf {
    repo().join("scenes").join(name)
}

/// Compares `img` pixel-exactly with `tests/golden/<name>.png`. With
/// `TILERAST_BLESS=1` the golden is (re)written instead.
pub fn assert_golden(name: &str, img: &Image) {
    let path = repo().join("tests/golden").join(format!("{name}.png"));
    if std::env::var_os("TILERAST_BLESS").is_some() {
        img.save_png(&path).unwrap();
        return;
    }
    let golden = Image::load_png(&path)
        .unwrap_or_else(|e| panic!("{e} (run with TILERAST_BLESS=1 to create it)"));
    let d = tilerast_sim::metrics::compare(img, &golden).unwrap();
    if d.differing != 0 {
        let out = std::env::temp_dir().join(format!("{name}.actual.png"));
        img.save_png(&out).unwrap();
        panic!(
            "{name}: {} pixels differ from the golden (max {}); actual written to {}",
            d.differing,
            d.max_abs,
            out.display()
        );
    }
}

pub use tilerast_sim::rng::Rng;

pub mod fuzz;
pub mod memory;

/// Two overlapping window claims (IDs 1 and 2) and then `n` random
/// commands ([`random_command`]) in windows 0..3.
pub fn windowed_commands(seed: u64, n: usize) -> Vec<Command> {
    let mut rng = Rng::new(seed);
    let mut cmds = vec![
        Command::WidFill {
            rect: Rect::new(0, 0, 50, 40),
            wid: 1,
        },
        Command::WidFill {
            rect: Rect::new(30, 20, 60, 50),
            wid: 2,
        },
    ];
    for _ in 0..n {
        let wid = rng.range(0, 3) as u8;
        cmds.push(random_command(&mut rng, wid));
    }
    cmds
}

/// A configuration with everything off but the format.
pub fn config(w: u16, h: u16, format: FormatKind) -> Config {
    Config {
        width: w,
        height: h,
        format,
        tile: (w, h),
        dither: 0,
        depth: false,
        wid: false,
        clear: Clear::default(),
        aa: tilerast_sim::AaKind::None,
        cull: Cull::None,
    }
}

/// A vertex from sub-pixel units (1/16 px).
pub fn vsub(x: i64, y: i64, z: u16, c: [u8; 3]) -> Vertex {
    Vertex::new(
        Coord::from_bits(x as i32),
        Coord::from_bits(y as i32),
        z,
        Rgb::new(c[0], c[1], c[2]),
    )
}

/// A triangle command in window `wid`.
pub fn tri(v: [Vertex; 3], wid: u8) -> Command {
    Command::Triangle {
        v,
        state: State {
            wid,
            ..State::default()
        },
    }
}

/// The numeric contract's colour bound, LSB ([`tilerast::numeric`]).
pub const COLOR_BOUND: f64 = 0.5 + 1.0 / 32.0 + 1.0 / 1024.0;
/// The numeric contract's Z bound, LSB.
pub const Z_BOUND: f64 = 0.5 + 1.0 / 8.0 + 1.0 / 512.0;

/// Renders one triangle with the core (RGB888, 16-bit Z, tiles of `tile`)
/// and with the f64 reference, and checks that they cover the same pixel
/// centres and that every covered pixel's colour and Z are within the
/// bounds; returns the largest errors.
pub fn check_triangle(
    w: u16,
    h: u16,
    tile: (u16, u16),
    v: [Vertex; 3],
) -> Result<(f64, f64), proptest::test_runner::TestCaseError> {
    use proptest::{prop_assert, prop_assert_eq};
    let mut c = config(w, h, FormatKind::Rgb888);
    c.depth = true;
    c.tile = tile;
    let cmds = [tri(v, 0)];
    let ours = tilerast_sim::render(&c, &cmds).unwrap();
    let exact = tilerast_sim::reference::render(&c, &cmds);
    let (mut max_c, mut max_z) = (0.0f64, 0.0f64);
    for i in 0..ours.raw.len() {
        let covered = exact.depth[i] < 65535.0;
        prop_assert_eq!(
            ours.depth[i] < 65535,
            covered,
            "coverage differs at pixel {}",
            i
        );
        if !covered {
            continue;
        }
        let p = ours.raw[i];
        let got = [(p >> 16) & 255, (p >> 8) & 255, p & 255];
        for (g, e) in got.iter().zip(exact.color[i]) {
            max_c = max_c.max((*g as f64 - e).abs());
        }
        max_z = max_z.max((ours.depth[i] as f64 - exact.depth[i]).abs());
    }
    prop_assert!(
        max_c <= COLOR_BOUND,
        "colour error {} > {}",
        max_c,
        COLOR_BOUND
    );
    prop_assert!(max_z <= Z_BOUND, "Z error {} > {}", max_z, Z_BOUND);
    Ok((max_c, max_z))
}

/// A random command for a screen of about 100x80 pixels, drawing into window
/// `wid`, sometimes with a partial plane mask, sometimes translucent (with
/// or without Z write): fills, Z fills, ramps (span commands whose colour
/// and depth stay in range), styled lines, antialiased solid edges and
/// triangles reaching beyond the screen.
pub fn random_command(rng: &mut Rng, wid: u8) -> Command {
    let mask = if rng.range(0, 4) == 0 {
        rng.next_u64() as u32
    } else {
        u32::MAX
    };
    let state = State {
        wid,
        plane_mask: mask,
        tag: rng.range(0, 4) as u16,
        blend: match rng.range(0, 6) {
            0 => Blend::Alpha,
            1 => Blend::AlphaZWrite,
            _ => Blend::Opaque,
        },
    };
    match rng.range(0, 8) {
        7 => {
            let v = rng.triangle((-400, 1900), (-400, 1500));
            let tv = v.map(|v| TexVertex {
                x: v.x,
                y: v.y,
                z: v.z,
                u: rng.next_u64() as u16,
                v: rng.next_u64() as u16,
                q: rng.range(1, 65536) as u16,
            });
            Command::Textured {
                tex: rng.range(0, 3) as u8,
                alpha: rng.range(0, 256) as u8,
                shade: [rng.byte(), rng.byte(), rng.byte()],
                v: tv,
                state,
            }
        }
        6 => {
            let v = rng.triangle((-400, 1900), (-400, 1500));
            let edge = tilerast::line::EdgeCmd::of_triangle(&v, rng.range(0, 3) as usize);
            Command::Edge { edge, state }
        }
        5 => {
            let mut p = || {
                (
                    Coord::from_bits(rng.range(-400, 1900) as i32),
                    Coord::from_bits(rng.range(-400, 1500) as i32),
                )
            };
            let (p0, p1) = (p(), p());
            let z = [rng.range(0, 65536) as u16, rng.range(0, 65536) as u16];
            let style = if rng.range(0, 2) == 0 {
                LineStyle::SOLID
            } else {
                LineStyle {
                    pattern: rng.next_u64() as u16,
                    scale: rng.range(0, 4) as u8,
                    phase: rng.range(0, 64) as u16,
                }
            };
            Command::Line {
                line: LineCmd {
                    p0,
                    p1,
                    z,
                    color: rng.rgb(),
                    style,
                    antialias: rng.range(0, 2) == 0,
                },
                state,
            }
        }
        0 => Command::Fill {
            rect: rng.rect((-20, 100), (-20, 80), 90, 70),
            color: rng.rgb(),
            alpha: rng.range(0, 256) as u8,
            state,
        },
        1 => Command::ZFill {
            rect: rng.rect((-20, 100), (-20, 80), 90, 70),
            z: rng.range(0, 65536) as u16,
            state,
        },
        2 => {
            let len = rng.range(0, 200) as u16;
            let steps = (len as i64 - 1).max(1);
            // From a towards b over the span: the end value lies between them
            // (a step beyond I16F16's range is shortened towards zero).
            let mut ramp = |max: i64| {
                let (a, b) = (rng.range(0, max) << 16, rng.range(0, max) << 16);
                (
                    a,
                    ((b - a) / steps).clamp(-(i32::MAX as i64), i32::MAX as i64),
                )
            };
            let c = [ramp(256), ramp(256), ramp(256)];
            let (z, dz) = ramp(65536);
            let span = SpanCmd {
                x: rng.range(-100, 100) as i32,
                y: rng.range(-5, 85) as i32,
                len,
                color: c.map(|(a, _)| ColorFix::from_bits(a as u32)),
                dcolor: c.map(|(_, d)| ColorStep::from_bits(d as i32)),
                z: ZFix::from_bits(z as u32),
                dz: ZStep::from_bits(dz as i32),
                alpha: rng.range(0, 256) as u8,
            };
            Command::Span { span, state }
        }
        _ => Command::Triangle {
            v: rng
                .triangle((-400, 1900), (-400, 1500))
                .map(|v| v.with_alpha(rng.range(0, 256) as u8)),
            state,
        },
    }
}

/// Property-test case count: `default`, or `PROPTEST_CASES` when set (to
/// run a deeper search locally than CI's time budget allows).
pub fn cases(default: u32) -> u32 {
    std::env::var("PROPTEST_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

/// One triangle of a core mesh (model space, `±16000 / 32768` of the unit
/// cube, in the z = 0 plane) with vertex `normals` and `material`,
/// encoded into `buf`.
pub fn triangle_mesh<'a>(
    buf: &'a mut [u8],
    normals: &'a [[i16; 3]; 3],
    material: tilerast::geometry::Material,
) -> tilerast::geometry::Mesh<'a> {
    use tilerast::geometry::{Group, Mesh, MeshData};
    let data = MeshData {
        center: [0; 3],
        extent: 1 << 16,
        positions: &[[-16000, -16000, 0], [16000, -16000, 0], [0, 16000, 0]],
        normals: Some(normals),
        colors: None,
        groups: &[Group {
            first_triangle: 0,
            triangles: 1,
            first_vertex: 0,
            vertices: 3,
            material,
        }],
        triangles: &[[0, 1, 2]],
    };
    let n = data.encode(buf).expect("room for one triangle");
    Mesh::parse(&buf[..n]).expect("just encoded")
}

/// Points `scene` down -z at the origin from z = 3 (40° field of view)
/// onto a 64x64 viewport.
pub fn front_camera(scene: &mut tilerast::geometry::Scene<'_, f32>) {
    use tilerast::geometry::{Angle, Mat4};
    scene.set_camera(
        Mat4::look_at([0.0, 0.0, 3.0], [0.0; 3], [0.0, 1.0, 0.0]).unwrap(),
        Mat4::perspective(Angle::degrees(40), 1.0, 1.0, 5.0).unwrap(),
    );
    scene
        .set_viewport(tilerast::prelude::Rect::new(0, 0, 64, 64))
        .unwrap();
}

/// A frame's packed pixels, row-major, rendered in tiles of `N` pixels of
/// configuration `C` through bins of `CAP` entries and `TB` tiles (0: no
/// bins, every tile walks the list), and its counts.
pub fn frame_raw<const N: usize, C, S, const CAP: usize, const TB: usize>(
    frame: &Frame,
    cmds: &S,
) -> (Vec<u32>, tilerast::frame::FrameStats)
where
    C: tilerast::config::TileConfig,
    S: tilerast::frame::CommandSource + ?Sized,
{
    let mut tile: Box<Tile<N, C>> = Box::default();
    let mut bins: Box<tilerast::bin::Bins<CAP, TB>> = Box::default();
    let s = frame.screen();
    let mut out = vec![0u32; s.area() as usize];
    let stats = frame
        .render_binned(&mut tile, &mut *bins, cmds, |t| {
            let a = t.area();
            for y in a.y..a.y + a.h as i32 {
                for x in a.x..a.x + a.w as i32 {
                    out[(y as u32 * s.w + x as u32) as usize] = t.raw(x, y).unwrap();
                }
            }
            Ok::<(), ()>(())
        })
        .unwrap();
    (out, stats)
}

/// The front page's Rust blocks (`README.md`), compiled by `cargo test
/// --doc -p tilerast-tests`: its getting-started cannot rot.
#[cfg(doctest)]
#[doc = include_str!("../../README.md")]
pub struct ReadmeDoctests;
