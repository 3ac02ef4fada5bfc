//! The bodies of the fuzz targets (`fuzz/`, cargo-fuzz) and of their
//! stable replay (`tests/tests/fuzz_replay.rs`): each takes arbitrary bytes
//! and panics only on a finding; it returns whether the input got past
//! parsing to the oracles (the replay checks that some do). One body per
//! input surface:
//!
//! | target | input | oracle |
//! | --- | --- | --- |
//! | [`wire()`] | an encoded scene (firmware flash) | decode never panics; every decoded command encodes and decodes to itself; tiled and whole-frame renders are equal |
//! | [`commands`] | a configuration and a command list | tiling changes nothing; removing window W's commands changes no pixel outside W; a plane mask keeps every other bit |
//! | [`tile_api`] | a sequence of tile calls | results match the documented contract (begin's errors, reads inside the area only, flush size) |
//! | [`scene`] | scene-file text | parse errors, not panics; a parsed scene renders and survives the wire round trip |
//! | [`obj`] | OBJ text | every index in range; the mesh builds and renders |
//! | [`mesh()`] | a model-space mesh and camera parameters | parse and draw errors, not panics; every emitted triangle valid; keys increase and replay to the same commands; tiling changes nothing |
//! | [`volume()`] | a density volume, transfer points, camera and lights | slicing errors, not panics; tiling changes nothing; normal blending equals per-slice shading within the rounding bound (one colour) |
//! | [`occlusion()`] | object boxes, two cameras, a threshold | building, projecting and walking never panic; at threshold 0 every culling mode draws both frames exactly as no culling |

use crate::{config, random_command, Rng};
use tilerast::prelude::*;
use tilerast::wire::{self, SceneHeader, MAX_ENCODED};
use tilerast_sim::{render, AaKind, Config, FormatKind, Limits, Scene};

/// Bytes read as numbers; zeros past the end.
struct Bytes<'a>(&'a [u8]);

impl Bytes<'_> {
    fn u8(&mut self) -> u8 {
        let (b, rest) = self.0.split_first().map_or((0, &[][..]), |(b, r)| (*b, r));
        self.0 = rest;
        b
    }
    fn u32(&mut self) -> u32 {
        u32::from_le_bytes([self.u8(), self.u8(), self.u8(), self.u8()])
    }
    fn u64(&mut self) -> u64 {
        self.u32() as u64 | (self.u32() as u64) << 32
    }
    /// A coordinate, biased towards the edges of the numeric domain.
    fn coord(&mut self) -> i32 {
        let lim = tilerast::numeric::COORD_LIMIT;
        match self.u8() % 8 {
            0 => i32::MAX - (self.u8() as i32),
            1 => i32::MIN + (self.u8() as i32),
            2 => lim - (self.u8() as i32),
            3 => -lim + (self.u8() as i32) - 8,
            _ => self.u8() as i32 - 64,
        }
    }
    fn is_empty(&self) -> bool {
        self.0.is_empty()
    }
}

const LIMITS: Limits = Limits {
    max_bytes: 1 << 20,
    max_line: 1 << 12,
};

/// Screens larger than this are cut down before rendering (speed only).
const MAX_RENDER_SIDE: u16 = 96;

fn small(mut c: Config) -> Config {
    c.width = c.width.min(MAX_RENDER_SIDE);
    c.height = c.height.min(MAX_RENDER_SIDE);
    c.tile = (c.tile.0.min(c.width), c.tile.1.min(c.height));
    c
}

/// Renders tiled and as one tile; both must agree (or fail alike).
fn tiling_is_invisible(c: &Config, cmds: &[Command]) -> Option<tilerast_sim::Rendered> {
    let whole = Config {
        tile: (c.width, c.height),
        ..*c
    };
    match (render(c, cmds), render(&whole, cmds)) {
        (Ok(a), Ok(b)) => {
            assert_eq!(a.raw, b.raw, "tiling changed the colour");
            assert_eq!(a.depth, b.depth, "tiling changed the depth");
            Some(a)
        }
        (Err(a), Err(b)) => {
            assert_eq!(a, b);
            None
        }
        (a, b) => panic!("tiled {:?} vs whole {:?}", a.err(), b.err()),
    }
}

/// An encoded scene: header and command stream.
pub fn wire(data: &[u8]) -> bool {
    let Ok((h, stream)) = SceneHeader::parse(data) else {
        return false;
    };
    let cmds: Vec<Command> = stream.iter().map_while(Result::ok).take(256).collect();
    for c in &cmds {
        let mut buf = [0u8; MAX_ENCODED];
        let n = wire::encode(c, &mut buf).expect("a decoded command encodes");
        assert_eq!(wire::decode(&buf[..n]), Ok((*c, n)), "round trip");
    }
    match Config::from_header(&h) {
        Ok(c) => tiling_is_invisible(&small(c), &cmds).is_some(),
        Err(_) => false,
    }
}

const W: u16 = 48;
const H: u16 = 40;

fn windows() -> [Command; 3] {
    [
        Command::WidFill {
            rect: Rect::new(4, 4, 24, 20),
            wid: 1,
        },
        Command::WidFill {
            rect: Rect::new(20, 14, 26, 24),
            wid: 2,
        },
        Command::WidFill {
            rect: Rect::new(36, 0, 12, 8),
            wid: 3,
        },
    ]
}

/// A configuration and a command list, drawn through the window-isolation
/// and plane-mask oracles.
pub fn commands(data: &[u8]) -> bool {
    const FORMATS: [FormatKind; 5] = [
        FormatKind::Rgb888,
        FormatKind::Rgb565,
        FormatKind::Rgb444,
        FormatKind::Gray8,
        FormatKind::Binary,
    ];
    let mut b = Bytes(data);
    let mut c = config(W, H, FORMATS[b.u8() as usize % 5]);
    c.depth = b.u8() & 1 == 1;
    c.wid = true;
    c.dither = [0, 2, 4, 8, 16][b.u8() as usize % 5];
    c.tile = (1 + (b.u8() as u16 % W), 1 + (b.u8() as u16 % H));
    let aa = AaKind::ALL[b.u8() as usize % AaKind::ALL.len()];
    if [0, 4, 8].contains(&c.dither) && aa != AaKind::Grid8 {
        c.aa = aa;
    }
    let mut rng = Rng::new(b.u64());
    let mut cmds: Vec<Command> = (0..b.u8() % 8)
        .map(|_| {
            let wid = rng.range(0, 4) as u8;
            random_command(&mut rng, wid)
        })
        .collect();
    // The rest of the input as encoded commands (window fills left out:
    // the window layout is fixed).
    let rest = b.0;
    cmds.extend(
        wire::Encoded(rest)
            .iter()
            .map_while(Result::ok)
            .filter(|c| !matches!(c, Command::WidFill { .. }))
            .take(16),
    );
    let list = |cmds: &mut dyn Iterator<Item = Command>| -> Vec<Command> {
        windows().into_iter().chain(cmds).collect()
    };
    let Some(all) = tiling_is_invisible(&c, &list(&mut cmds.iter().copied())) else {
        return false;
    };
    // Window isolation: without window w's commands, nothing outside w changes.
    let w = rng.range(0, 4) as u8;
    let mut others = cmds
        .iter()
        .copied()
        .filter(|c| c.state().is_none_or(|s| s.wid != w));
    let without = render(&c, &list(&mut others)).expect("a subset of a valid list renders");
    let wid_at = |x: i32, y: i32| {
        windows().iter().fold(0, |id, c| match c {
            Command::WidFill { rect, wid } if rect.intersect(&Rect::new(x, y, 1, 1)).is_some() => {
                *wid
            }
            _ => id,
        })
    };
    for i in 0..(W as usize * H as usize) {
        let (x, y) = ((i % W as usize) as i32, (i / W as usize) as i32);
        if wid_at(x, y) != w {
            assert_eq!(
                all.raw[i], without.raw[i],
                "window {w}'s commands changed ({x}, {y})"
            );
            assert_eq!(
                all.depth[i], without.depth[i],
                "window {w}'s commands changed Z at ({x}, {y})"
            );
        }
    }
    // Plane mask: with every command masked by m, the other bits keep the
    // clear colour.
    let m = rng.next_u64() as u32;
    let masked: Vec<Command> = cmds
        .iter()
        .map(|c| {
            let mut c = *c;
            if let Some(s) = c.state_mut() {
                s.plane_mask &= m;
            }
            c
        })
        .collect();
    let clear = render(&c, &[]).expect("an empty list renders").raw[0];
    let r = render(&c, &list(&mut masked.into_iter())).expect("masks do not invalidate");
    for (i, &p) in r.raw.iter().enumerate() {
        assert_eq!(
            (p ^ clear) & !m,
            0,
            "bits outside mask {m:#x} changed at pixel {i}"
        );
    }
    true
}

/// A tile driven call by call.
pub fn tile_api(data: &[u8]) -> bool {
    use tilerast::coverage::Ruf8;
    let mut b = Bytes(data);
    match b.u8() % 3 {
        0 => calls(
            &mut b,
            &mut Tile::<64, Planes<Rgb565Format, Depth16, Wid8, Bayer4>>::new(),
        ),
        1 => calls(
            &mut b,
            &mut Tile::<64, Planes<Rgb888Format, Depth16, Wid8, NoDither, Ruf8>>::new(),
        ),
        _ => calls(&mut b, &mut Tile::<64, Ssd1306Config>::new()),
    }
}

fn calls<const N: usize, C: TileConfig>(b: &mut Bytes, t: &mut Tile<N, C>) -> bool
where
    <C::Format as PixelFormat>::Color: Default,
{
    use embedded_graphics_core::{draw_target::DrawTarget, geometry::Point, Pixel};
    let mut begun = false;
    for _ in 0..64 {
        if b.is_empty() {
            break;
        }
        match b.u8() % 6 {
            0 => {
                let r = Rect::new(b.coord(), b.coord(), b.u8() as u32 % 40, b.u8() as u32 % 40);
                let lim = tilerast::numeric::COORD_LIMIT as i64;
                let want = if r.w == 0 || r.h == 0 {
                    Err(Error::BadSize)
                } else if r.area() > 8 * N as u64 {
                    Err(Error::TileTooLarge)
                } else if (r.x as i64) < -lim || r.x1() > lim || (r.y as i64) < -lim || r.y1() > lim
                {
                    Err(Error::CoordOutOfRange)
                } else {
                    Ok(())
                };
                assert_eq!(t.begin(r, &Clear::default()), want, "{r:?}");
                begun |= want.is_ok();
            }
            1 if begun => {
                if let Ok((c, n)) = wire::decode(b.0) {
                    b.0 = &b.0[n..];
                    t.draw(&c).expect("decoded commands are valid");
                } else {
                    let _ = b.u8();
                }
            }
            2 if begun => {
                t.finish();
            }
            3 if begun => {
                let (x, y) = (b.coord(), b.coord());
                let a = t.area();
                let inside = (a.x as i64..a.x1()).contains(&(x as i64))
                    && (a.y as i64..a.y1()).contains(&(y as i64));
                assert_eq!(t.raw(x, y).is_some(), inside);
                assert_eq!(t.depth(x, y).is_some(), inside);
                assert_eq!(t.wid(x, y).is_some(), inside);
            }
            4 if begun => {
                let p = Point::new(b.coord(), b.coord());
                let _ = t.draw_iter([Pixel(p, Default::default())]);
            }
            5 if begun => {
                let a = t.area();
                assert_eq!(t.colors().count() as u64, a.area());
            }
            _ => {}
        }
    }
    begun
}

/// Scene-file text (meshes load relative to `scenes/`, as the corpus's
/// copies of the repository's scenes expect).
pub fn scene(data: &[u8]) -> bool {
    let text = String::from_utf8_lossy(data);
    let base = crate::repo().join("scenes");
    let Ok(s) = Scene::parse_with(&text, &base, &LIMITS) else {
        return false;
    };
    if let Ok(bytes) = s.encode() {
        let (_, stream) = SceneHeader::parse(&bytes).expect("own header parses");
        let back: Vec<Command> = stream
            .iter()
            .collect::<Result<_, _>>()
            .expect("own stream decodes");
        assert_eq!(back, s.commands, "wire round trip");
    }
    s.commands.len() > 8192 || tiling_is_invisible(&small(s.config), &s.commands).is_some()
}

/// OBJ text, read, built into a mesh and drawn.
pub fn obj(data: &[u8]) -> bool {
    let Ok(o) = tilerast_sim::obj::parse(data, "fuzz.obj", None, &LIMITS) else {
        return false;
    };
    for m in &o.models {
        let n = m.positions.len();
        assert_eq!(m.finite.len(), n);
        assert!(m.normals.is_empty() || m.normals.len() == n);
        assert!(m
            .triangles
            .iter()
            .flatten()
            .chain(m.lines.iter().flatten())
            .all(|&i| (i as usize) < n));
        assert!(
            m.finite.iter().all(|&f| f),
            "faces with a bad vertex are dropped"
        );
    }
    let mut spec = tilerast_sim::mesh::MeshSpec::new("fuzz.obj");
    spec.edge_aa = true;
    spec.wireframe = Some([255, 255, 0]);
    let (mut cmds, mut edges, mut tags) = (Vec::new(), Vec::new(), 0);
    tilerast_sim::mesh::build(&o, &spec, (64, 48), &mut cmds, &mut edges, &mut tags);
    cmds.extend(edges);
    let mut c = config(64, 48, FormatKind::Rgb565);
    c.depth = true;
    c.tile = (16, 16);
    tiling_is_invisible(&c, &cmds).expect("built meshes are valid");
    !cmds.is_empty()
}

/// A model-space mesh (`tilerast::geometry::Mesh`, firmware flash) drawn
/// by the geometry stage: the first 8 bytes choose the back end, culling,
/// rotation, eye distance and clip planes; the rest is the mesh. Parsing
/// and drawing never panic (overflow checks on); every emitted triangle is
/// valid; keys strictly increase and replaying them gives the same
/// commands; tiling changes nothing.
pub fn mesh(data: &[u8]) -> bool {
    use tilerast::geometry::{Fx, Mesh};
    if data.len() < 8 {
        return false;
    }
    let (p, bytes) = data.split_at(8);
    let Ok(m) = Mesh::parse(bytes) else {
        return false;
    };
    let drawn = if p[0] & 1 == 0 {
        mesh_frame::<f32>(&m, p)
    } else {
        mesh_frame::<Fx>(&m, p)
    };
    let Some(cmds) = drawn else {
        return false; // a documented DrawError
    };
    let mut c = config(48, 32, FormatKind::Rgb565);
    c.depth = true;
    c.tile = (16, 8);
    tiling_is_invisible(&c, &cmds);
    !cmds.is_empty()
}

/// Draws `m` under the parameters `p`; `None` when the stage refuses.
fn mesh_frame<S: tilerast::geometry::Real>(
    m: &tilerast::geometry::Mesh<'_>,
    p: &[u8],
) -> Option<Vec<Command>> {
    use tilerast::frame::CommandSource;
    use tilerast::geometry::*;
    let q = |v: i32| S::from_q(v as i64, 4); // 1/16 units
    let mut slots = vec![VertexSlot::EMPTY; m.vertices() as usize];
    let mut scene: Scene<'_, S> = Scene::new(&mut slots);
    let eye = q(1 + p[2] as i32); // 1/16 .. 16 units
    let (near, far) = (
        q(1 + (p[3] % 32) as i32),
        q(2 + (p[3] % 32) as i32 + p[4] as i32),
    );
    let view = Mat4::look_at([q(0), q(0), eye], [q(0); 3], [q(0), q(16), q(0)]).ok()?;
    let proj = Mat4::perspective(Angle::degrees(10 + p[5] as i32 % 160), S::ONE, near, far).ok()?;
    scene.set_camera(view, proj);
    scene.set_viewport(Rect::new(-8, -4, 64, 40)).ok()?;
    scene.set_lighting(Lighting::white([q(-5), q(9), q(16)], q(3)).ok()?);
    let cull = [Cull::Back, Cull::Front, Cull::None][p[1] as usize % 3];
    let opts = DrawOptions {
        cull,
        clockwise: p[1] & 4 != 0,
        state: State {
            tag: (p[1] >> 4) as u16,
            ..State::default()
        },
        lit: p[1] & 8 == 0,
        shading: if p[1] & 16 != 0 {
            Shading::FastPhong
        } else {
            Shading::Gouraud
        },
    };
    let model = Mat4::rotation_x(Angle::from_turn_q16(u16::from_le_bytes([p[6], p[7]])))
        .mul(&Mat4::rotation_y(Angle::from_turn_q16((p[6] as u16) << 8)));
    scene.draw(m, &model, &opts).ok()?;
    let mut keyed = Vec::new();
    scene
        .each_keyed(|k, c| {
            assert!(c.validate().is_ok(), "invalid command {c:?}");
            keyed.push((k, *c));
        })
        .expect("a drawn scene walks");
    assert!(keyed.windows(2).all(|w| w[0].0 < w[1].0), "keys increase");
    let mut again = Vec::new();
    scene.replay(keyed.iter().map(|k| k.0), |c| again.push(*c));
    let cmds: Vec<Command> = keyed.into_iter().map(|k| k.1).collect();
    assert_eq!(again, cmds, "replay by key gives the walked commands");
    Some(cmds)
}

/// A density volume drawn by the volume stage (seed 002): the first 16
/// bytes choose the sides (2..=9 each), the back end, the normals, the
/// rotation, the eye distance, the slice count, two transfer points and a
/// light; the rest are densities (repeated to fill the volume). Slicing
/// never panics (overflow checks on) and fails only with documented
/// errors; tiles change no pixel; skipping by bricks or by cell bits
/// changes no pixel; with one colour, normal blending and per-slice
/// shading agree within [`tilerast_sim::volume::equality_bound`].
pub fn volume(data: &[u8]) -> bool {
    use tilerast::geometry::Fx;
    if data.len() < 17 {
        return false;
    }
    let (p, bytes) = data.split_at(16);
    let dims = [p[0], p[1], p[2]].map(|b| 2 + (b % 8) as u16);
    let n = dims.iter().map(|&d| d as usize).product::<usize>();
    let density: Vec<u8> = bytes.iter().copied().cycle().take(n).collect();
    if p[3] & 1 == 0 {
        volume_frames::<f32>(&density, dims, p)
    } else {
        volume_frames::<Fx>(&density, dims, p)
    }
}

fn volume_frames<S: tilerast::geometry::Real>(density: &[u8], dims: [u16; 3], p: &[u8]) -> bool {
    use tilerast::geometry::*;
    use tilerast::volume::*;
    let Ok(vol) = Volume::new(density, dims) else {
        panic!("sides 2..=9 and the right length are a valid volume");
    };
    let mut normals = vec![0u8; 3 * density.len()];
    vol.compute_normals(&mut normals)
        .expect("room for the normals");
    let vol = if p[3] & 2 == 0 {
        vol.with_normals(&normals).expect("3 bytes a voxel")
    } else {
        vol
    };
    let q = |v: i32| S::from_q(v as i64, 4);
    let deg = |b: u8| Angle::degrees(b as i32 * 360 / 256);
    let model = Mat4::<S>::rotation_z(deg(p[4]))
        .mul(&Mat4::rotation_y(deg(p[5])))
        .mul(&Mat4::rotation_x(deg(p[6])));
    let eye = q(2 + p[7] as i32); // 1/8 .. 16 units: inside the box too
    let Ok(view_m) = Mat4::look_at([q(0), q(0), eye], [q(0); 3], [q(0), q(16), q(0)]) else {
        return false;
    };
    let Ok(proj) = Mat4::perspective(
        Angle::degrees(20 + p[8] as i32 % 120),
        S::ONE,
        q(1),
        eye + q(32),
    ) else {
        return false;
    };
    let slices = 1 + (p[9] % 40) as u16;
    let c = Rgb::new(200, 180, 90);
    let (d0, d1) = (p[10].min(254), p[11].max(p[10].min(254) + 1));
    let Ok(tf) = Transfer::from_points(&[TfPoint::new(d0, p[12], c), TfPoint::new(d1, p[13], c)])
    else {
        panic!("two increasing points are a transfer function");
    };
    let l = [p[14] as i32 - 128, p[15] as i32 - 128, 64].map(|v| S::from_q(v as i64, 6));
    let Ok(lights) = VolumeLights::new(&model, &[(l, S::from_q(3, 2))], S::from_q(1, 2)) else {
        return false;
    };
    let screen = Rect::new(0, 0, 24, 24);
    let view = match VolumeView::<'_, 40>::new(vol, &tf, &model, &view_m, &proj, screen, slices) {
        Ok(v) => v,
        Err(Error::Degenerate) => return false,
        Err(e) => panic!("slicing failed with {e:?}"),
    };
    type T = Tile<{ groups(24, 24) }, Planes<Rgb888Format, Depth16>>;
    fn draw<M: Compositor, const K: usize>(
        view: &VolumeView<'_, K>,
        comp: &M,
        lights: &VolumeLights,
        big: bool,
    ) -> (Vec<u32>, u32) {
        let frame = if big {
            T::frame::<24, 24>(24, 24)
        } else {
            T::frame::<8, 6>(24, 24)
        }
        .expect("a valid frame");
        let mut tile = T::new();
        let mut plane: Box<VolumePlane<{ groups(24, 24) }, M::Cell>> = Box::new(VolumePlane::new());
        let mut out = vec![0u32; 24 * 24];
        let mut blended = 0;
        frame
            .render_with(&mut tile, &[][..], |t| {
                blended += plane.composite(t, view, comp).composited;
                plane.shade(t, comp, lights);
                let a = t.area();
                for y in a.y..a.y + a.h as i32 {
                    for x in a.x..a.x + a.w as i32 {
                        out[(y * 24 + x) as usize] = t.raw(x, y).unwrap();
                    }
                }
                Ok::<(), ()>(())
            })
            .expect("renders");
        (out, blended)
    }
    let (a, blended) = draw(&view, &NormalBlending, &lights, true);
    let (b, _) = draw(&view, &NormalBlending, &lights, false);
    assert_eq!(a, b, "tiles changed the volume");
    // Empty-space skipping, bricks of a side the input picks: the same
    // image.
    let shift = 1 + (p[2] >> 4) as u32 % 5;
    let mut bricks = vec![0u8; brick_bytes(dims, shift)];
    vol.compute_bricks(shift, &mut bricks)
        .expect("room for the bricks");
    let sliced = |v| {
        VolumeView::<'_, 40>::new(v, &tf, &model, &view_m, &proj, screen, slices)
            .expect("the same slicing")
    };
    let skipping = sliced(vol.with_bricks(&bricks, shift).expect("the bricks' length"));
    let (s, _) = draw(&skipping, &NormalBlending, &lights, true);
    assert_eq!(a, s, "skipping empty bricks changed the volume");
    // And by the cells' bits, made for the table: the same image.
    let mut bits = vec![0u8; visible_cell_bytes(dims)];
    vol.compute_visible_cells(&tf, &mut bits)
        .expect("room for the bits");
    let culling = sliced(vol.with_visible_cells(&bits).expect("the bits' length"));
    let (c, _) = draw(&culling, &NormalBlending, &lights, true);
    assert_eq!(a, c, "skipping clear cells changed the volume");
    let (ps, _) = draw(&view, &PerSliceShading(&lights), &lights, true);
    let l64 = l.map(|v| v.to_fixed(16).unwrap_or(0) as f64 / 65536.0);
    let bound =
        tilerast_sim::volume::equality_bound(&[[l64[0], l64[1], l64[2], 0.75]], 0.5, slices as u32);
    for (x, y) in a.iter().zip(&ps) {
        for sh in [0, 8, 16] {
            let d = ((x >> sh) & 255).abs_diff((y >> sh) & 255);
            assert!(
                d as f64 <= bound,
                "normal blending and per-slice differ by {d} > {bound:.2}"
            );
        }
    }
    blended > 0
}

/// Occlusion culling (seed 004): up to 24 boxes (each a cube placed by
/// the input, possibly degenerate, huge or around the camera), a camera
/// and a threshold. Oracles: building, projecting and walking never panic;
/// with threshold 0 every mode draws both frames (the second with the
/// first's history) exactly as no culling does; any threshold's counts
/// stay consistent. Returns whether the frames were drawn.
pub fn occlusion(data: &[u8]) -> bool {
    use tilerast::geometry::*;
    use tilerast::occlusion::*;
    if data.len() < 8 {
        return false;
    }
    let (p, rest) = data.split_at(8);
    let n = (1 + p[0] as usize % 24).min(rest.len() / 6).max(1);
    if rest.len() < 6 {
        return false;
    }
    let mut bytes = [0u8; CUBE_BYTES];
    let Ok(cube) = Mesh::cube(&mut bytes) else {
        panic!("the cube encodes");
    };
    let s = |b: u8| (b as i8) as f32 / 8.0;
    let items: Vec<(Mesh<'_>, Mat4<f32>)> = rest
        .chunks_exact(6)
        .take(n)
        .map(|c| {
            let size = [c[3], c[4], c[5]].map(|b| (b % 64) as f32 / 8.0);
            let model = Mat4::translation([s(c[0]), s(c[1]), s(c[2])]).mul(&Mat4::scale(size));
            (cube, model)
        })
        .collect();
    let boxes: Vec<Aabb<f32>> = items.iter().map(|(m, t)| Aabb::of_mesh(m, t)).collect();
    let Ok(tree) = KdTree::<f32, 64>::build(&boxes) else {
        panic!("finite boxes within capacity build a tree");
    };
    let threshold = if p[1] & 1 == 0 { 0 } else { p[2] % 129 };
    let eye0 = [s(p[3]), s(p[4]), s(p[5]) + 12.0];
    type T = Tile<{ groups(16, 16) }, St7789Config>;
    let frame = T::frame::<16, 16>(40, 32).expect("a valid frame");
    let draw = |mode: CullMode,
                culler: &mut Culler<f32, 64>,
                eye: [f32; 3]|
     -> Option<(Vec<u32>, CullStats)> {
        let mut slots = vec![VertexSlot::EMPTY; 24 * items.len()];
        let mut scene: Scene<'_, f32, 24> = Scene::new(&mut slots);
        scene.set_camera(
            Mat4::look_at(eye, [0.0, 0.0, 0.0], [0.0, 1.0, 0.0]).ok()?,
            Mat4::perspective(Angle::degrees(30 + p[6] as i32 % 100), 1.25, 0.5, 40.0).ok()?,
        );
        scene.set_viewport(Rect::new(0, 0, 40, 32)).ok()?;
        let mut objects = MeshObjects::new(&mut scene, &items, DrawOptions::default()).ok()?;
        let (mut tile, mut hiz) = (T::new(), HiZ::<4, 3>::new());
        let mut px = vec![0u32; 40 * 32];
        let st = culler
            .render(mode, &frame, &mut tile, &mut hiz, eye, &mut objects, |t| {
                let a = t.area();
                for y in a.y..a.y + a.h as i32 {
                    for x in a.x..a.x + a.w as i32 {
                        px[(y * 40 + x) as usize] = t.raw(x, y).unwrap_or(0);
                    }
                }
                Ok::<(), ()>(())
            })
            .expect("rendering into a tile cannot fail");
        assert!(st.nodes_culled <= st.nodes_visited && st.prims_culled <= st.prims_tested);
        Some((px, st))
    };
    let eye1 = [eye0[0] + s(p[7]) / 4.0, eye0[1], eye0[2] - 1.0];
    let mut off = Culler::new(tree.clone());
    let Some(ref0) = draw(CullMode::Off, &mut off, eye0) else {
        return false;
    };
    let Some(ref1) = draw(CullMode::Off, &mut off, eye1) else {
        return false;
    };
    for mode in [CullMode::StopAndWait, CullMode::Chc, CullMode::SinglePass] {
        let mut c = Culler::new(tree.clone());
        c.set_threshold(threshold).expect("0..=128");
        let f0 = draw(mode, &mut c, eye0).expect("the same camera as the reference");
        let f1 = draw(mode, &mut c, eye1).expect("the same camera as the reference");
        if threshold == 0 {
            assert!(
                f0.0 == ref0.0,
                "{}: first frame differs from no culling",
                mode.name()
            );
            assert!(
                f1.0 == ref1.0,
                "{}: second frame differs from no culling",
                mode.name()
            );
        }
    }
    true
}

/// A PNG texture file, decoded with a limit of 256 pixels a side
/// ([`tilerast_png::Image::decode`]): never a panic or an allocation the
/// limit does not bound; a decoded image is within the limit and holds
/// exactly its pixels; an error is a sentence.
pub fn png(data: &[u8]) -> bool {
    match tilerast_png::Image::decode(std::io::Cursor::new(data), 256) {
        Ok(img) => {
            assert!(img.width <= 256 && img.height <= 256);
            assert_eq!(img.pixels.len(), img.width as usize * img.height as usize);
            true
        }
        Err(e) => {
            assert!(!e.is_empty() && !e.contains("Custom {"), "{e}");
            false
        }
    }
}

/// A NIfTI-1 volume, plain or gzipped, read with a limit of 1 MiB
/// ([`tilerast_sim::volume::VolumeData::read_nifti`]): never a panic,
/// never more than the limit read or allocated; a loaded volume has the
/// sides it declares (2..=1024) and one density and three normal bytes a
/// voxel; an error names the file.
///
/// The same bytes as a raw volume too
/// ([`tilerast_sim::volume::VolumeData::read_raw`]): the first
/// three bytes give its sides (2..=33), the rest are its voxels.
pub fn nifti(data: &[u8]) -> bool {
    use tilerast_sim::volume::VolumeData;
    if let [a, b, c, rest @ ..] = data {
        let dims = [*a, *b, *c].map(|s| (s % 32) as u16 + 2);
        let raw = std::path::Path::new("fuzz.raw");
        match VolumeData::read_raw(rest, raw, dims, 1 << 20) {
            Ok(v) => {
                let n = dims.iter().map(|&d| d as usize).product::<usize>();
                assert!(rest.len() >= n);
                assert_eq!((v.density.len(), v.normals.len()), (n, 3 * n));
            }
            Err(e) => {
                let e = e.to_string();
                assert!(e.starts_with("fuzz.raw: the file ends early"), "{e}");
            }
        }
    }
    let path = std::path::Path::new("fuzz.nii");
    match VolumeData::read_nifti(data, path, 1 << 20) {
        Ok(v) => {
            let n = v.dims.iter().map(|&d| d as usize).product::<usize>();
            assert!(v.dims.iter().all(|d| (2..=1024).contains(d)));
            assert!(n <= 1 << 20);
            assert_eq!((v.density.len(), v.normals.len()), (n, 3 * n));
            true
        }
        Err(e) => {
            let e = e.to_string();
            assert!(e.starts_with("fuzz.nii") && !e.contains("Custom {"), "{e}");
            false
        }
    }
}
