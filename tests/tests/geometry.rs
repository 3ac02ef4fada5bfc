//! The geometry stage (`tilerast::geometry`) at its extremes: a camera
//! inside a closed mesh (near-plane clipping leaves no hole), a mesh behind
//! the camera or beside the view (culled whole, nothing lit), NaN,
//! infinities and fixed-point overflow (errors naming what failed),
//! degenerate projections, and both back ends against the f64 reference.

use proptest::prelude::*;
use tilerast::geometry::*;
use tilerast::prelude::*;
use tilerast_fw::spin;

type Cfg = Planes<Rgb888Format, Depth16, NoWid, NoDither>;
const W: u16 = 64;
const H: u16 = 48;
const BG: Rgb = Rgb::new(1, 2, 3);

/// Renders the scene into a W x H image (one tile per 16x16).
fn render<S: Real>(scene: &Scene<'_, S>) -> Vec<u32> {
    let mut frame = Frame::new(W, H, 16, 16).unwrap();
    frame.clear.color = BG;
    let mut tile: Tile<{ groups(16, 16) }, Cfg> = Tile::new();
    let mut img = vec![0u32; W as usize * H as usize];
    let mut bins: Bins<4096, 16> = Bins::new();
    frame
        .render_binned(&mut tile, &mut bins, scene, |t| keep(&mut img, t))
        .unwrap();
    img
}

/// Copies a finished tile into the W x H image.
fn keep(img: &mut [u32], t: &Tile<{ groups(16, 16) }, Cfg>) -> Result<(), ()> {
    let r = t.area();
    for y in r.y..r.y + r.h as i32 {
        for x in r.x..r.x + r.w as i32 {
            img[(y * W as i32 + x) as usize] = t.raw(x, y).unwrap();
        }
    }
    Ok(())
}

fn cube_scene<'a, S: Real>(
    slots: &'a mut [VertexSlot],
    mesh: &Mesh<'a>,
    eye: [f32; 3],
    target: [f32; 3],
    turn: u16,
    cull: Cull,
) -> Result<(Scene<'a, S>, DrawStats), DrawError> {
    let q = |v: f32| S::from_q((v * 65536.0) as i64, 16);
    let mut scene: Scene<'_, S> = Scene::new(slots);
    let view = Mat4::look_at(eye.map(q), target.map(q), [q(0.0), q(1.0), q(0.0)])
        .map_err(|_| DrawError::Degenerate)?;
    let proj = Mat4::perspective(Angle::degrees(70), q(W as f32 / H as f32), q(0.05), q(10.0))
        .map_err(|_| DrawError::Degenerate)?;
    scene.set_camera(view, proj);
    scene
        .set_viewport(Rect::new(0, 0, W as u32, H as u32))
        .unwrap();
    scene.set_lighting(Lighting::white([q(0.3), q(1.0), q(0.5)], q(0.3)).unwrap());
    let opts = DrawOptions {
        cull,
        ..DrawOptions::default()
    };
    let st = scene.draw(mesh, &Mat4::rotation_y(Angle::from_turn_q16(turn)), &opts)?;
    Ok((scene, st))
}

/// Inside a closed cube, looking anywhere, every pixel sees a wall: the
/// triangles the near plane cuts are split, never dropped (a dropped one
/// shows the background through a hole).
fn inside_sees_walls<S: Real>(eye: [f32; 3], target: [f32; 3], turn: u16) {
    let mut buf = [0u8; spin::CUBE_BYTES];
    let mesh = spin::cube(&mut buf).unwrap();
    let mut slots = [VertexSlot::EMPTY; 24];
    let (scene, st) = cube_scene::<S>(&mut slots, &mesh, eye, target, turn, Cull::None).unwrap();
    let img = render(&scene);
    let bg = Rgb888Format::pack_rgb(BG);
    let holes = img.iter().filter(|&&p| p == bg).count();
    assert_eq!(holes, 0, "{} eye {eye:?} -> {target:?}: {st:?}", S::NAME);
}

#[test]
fn camera_inside_a_cube_clips_and_leaves_no_hole() {
    // The walls are 0.5 from the centre; the near plane (0.05 away, its
    // corners 0.077) must stay inside, so the eye keeps 0.08 from them. It
    // cuts the walls beside the camera.
    for eye in [[0.0, 0.0, 0.0], [0.0, 0.0, 0.4], [0.3, -0.2, 0.1]] {
        for target in [[0.0, 0.0, 1.0], [1.0, 0.3, 0.0], [-0.2, -1.0, 0.1]] {
            inside_sees_walls::<f32>(eye, target, 0);
            inside_sees_walls::<Fx>(eye, target, 0);
        }
    }
    // The counts: a camera against a wall clips triangles and drops none.
    let mut buf = [0u8; spin::CUBE_BYTES];
    let mesh = spin::cube(&mut buf).unwrap();
    let mut slots = [VertexSlot::EMPTY; 24];
    let (_, st) = cube_scene::<f32>(
        &mut slots,
        &mesh,
        [0.0, 0.0, 0.4],
        [0.0, 0.0, 1.0],
        0,
        Cull::None,
    )
    .unwrap();
    assert!(st.clipped > 0, "{st:?}");
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]
    #[test]
    fn anywhere_inside_the_cube_every_pixel_is_a_wall(
        e in prop::array::uniform3(-0.42f32..0.42),
        d in prop::array::uniform3(-1.0f32..1.0),
        turn in any::<u16>(),
    ) {
        // Inside the cube's inscribed sphere less the near plane's reach,
        // whatever the cube's turn.
        prop_assume!(e.iter().map(|v| v * v).sum::<f32>() < 0.42 * 0.42);
        prop_assume!(d.iter().map(|v| v * v).sum::<f32>() > 0.05);
        prop_assume!(d[0].abs() + d[2].abs() > 0.05); // up must not be the view axis
        let t = [e[0] + d[0], e[1] + d[1], e[2] + d[2]];
        inside_sees_walls::<f32>(e, t, turn);
        inside_sees_walls::<Fx>(e, t, turn);
    }
}

/// The teapot scene with the camera inside the model: the old f64 path
/// dropped 1,914 of its 6,320 triangles; the core clips them.
#[test]
fn teapot_with_the_camera_inside_is_clipped_not_dropped() {
    let obj = tilerast_sim::obj::load(
        &tilerast_tests::repo().join("assets/models/teapot.obj"),
        &tilerast_sim::Limits::default(),
    )
    .unwrap();
    let mut spec = tilerast_sim::mesh::MeshSpec::new("teapot.obj");
    spec.eye = [0.0, 0.1, 0.3];
    spec.clip = [0.1, 5.0];
    let build = |spec: &tilerast_sim::mesh::MeshSpec| {
        let (mut cmds, mut edges, mut tags) = (Vec::new(), Vec::new(), 0);
        let st = tilerast_sim::mesh::build(&obj, spec, (96, 96), &mut cmds, &mut edges, &mut tags);
        (st, cmds)
    };
    let (core, cmds) = build(&spec);
    assert_eq!(core.dropped, 0);
    assert!(core.clipped > 100, "{core:?}");
    assert!(cmds.iter().all(|c| c.validate().is_ok()));
    spec.geometry = tilerast_sim::mesh::GeometryKind::Reference;
    let (reference, _) = build(&spec);
    assert!(
        reference.dropped > 100,
        "the reference drops: {reference:?}"
    );
}

#[test]
fn meshes_behind_or_beside_the_camera_are_culled_whole() {
    let mut buf = [0u8; spin::CUBE_BYTES];
    let mesh = spin::cube(&mut buf).unwrap();
    for (eye, target) in [
        ([0.0, 0.0, 3.0], [0.0, 0.0, 6.0]),  // looking away
        ([5.0, 0.0, 3.0], [5.0, 0.0, 0.0]),  // beside
        ([0.0, 0.0, 30.0], [0.0, 0.0, 0.0]), // beyond the far plane
    ] {
        let mut slots = [VertexSlot::EMPTY; 24];
        let (scene, st) = cube_scene::<f32>(&mut slots, &mesh, eye, target, 0, Cull::Back).unwrap();
        assert_eq!(st.meshes_culled, 1, "{eye:?}");
        assert_eq!((st.vertices, st.lit), (0, 0), "nothing transformed or lit");
        let mut n = 0;
        scene.each(|_| n += 1).unwrap();
        assert_eq!(n, 0);
    }
}

#[test]
fn back_faces_are_culled_by_winding_either_way() {
    let mut buf = [0u8; spin::CUBE_BYTES];
    let mesh = spin::cube(&mut buf).unwrap();
    let count = |cull: Cull, clockwise: bool| {
        let mut slots = [VertexSlot::EMPTY; 24];
        let mut scene: Scene<'_, f32> = Scene::new(&mut slots);
        scene.set_camera(
            Mat4::look_at([1.5, 1.2, 2.5], [0.0; 3], [0.0, 1.0, 0.0]).unwrap(),
            Mat4::perspective(Angle::degrees(50), 1.0, 0.5, 10.0).unwrap(),
        );
        scene.set_viewport(Rect::new(0, 0, 64, 64)).unwrap();
        let o = DrawOptions {
            cull,
            clockwise,
            ..DrawOptions::default()
        };
        scene.draw(&mesh, &Mat4::IDENTITY, &o).unwrap()
    };
    // Three faces of a cube face a camera off its corner.
    assert_eq!(count(Cull::Back, false).front, 6);
    assert_eq!(count(Cull::Front, false).front, 6);
    assert_eq!(count(Cull::Back, true).front, 6);
    assert_eq!(count(Cull::None, false).front, 12);
    assert_eq!(
        count(Cull::Back, false).lit,
        12,
        "only the visible faces' vertices"
    );
}

#[test]
fn bad_numbers_are_errors_with_the_reason() {
    let mut buf = [0u8; spin::CUBE_BYTES];
    let mesh = spin::cube(&mut buf).unwrap();
    // NaN and infinite cameras.
    assert_eq!(
        Mat4::<f32>::look_at([f32::NAN, 0.0, 3.0], [0.0; 3], [0.0, 1.0, 0.0]),
        Err(Error::Degenerate)
    );
    assert_eq!(
        Mat4::<f32>::look_at([f32::INFINITY, 0.0, 3.0], [0.0; 3], [0.0, 1.0, 0.0]),
        Err(Error::Degenerate)
    );
    let setup = |slots: &mut [VertexSlot; 24]| {
        let mut scene: Scene<'_, f32> = Scene::new(slots);
        scene.set_camera(
            Mat4::look_at([0.0, 0.0, 3.0], [0.0; 3], [0.0, 1.0, 0.0]).unwrap(),
            Mat4::perspective(Angle::degrees(40), 1.0, 1.0, 5.0).unwrap(),
        );
        scene.set_viewport(Rect::new(0, 0, 32, 32)).unwrap();
        let mut m = Mat4::IDENTITY;
        m.m[0][0] = f32::NAN;
        scene.draw(&mesh, &m, &DrawOptions::default()).err()
    };
    assert_eq!(
        setup(&mut [VertexSlot::EMPTY; 24]),
        Some(DrawError::Degenerate)
    );
    // f32 overflow to infinity in the transform.
    let mut slots = [VertexSlot::EMPTY; 24];
    let mut scene: Scene<'_, f32> = Scene::new(&mut slots);
    scene.set_camera(
        Mat4::look_at([0.0, 0.0, 3.0], [0.0; 3], [0.0, 1.0, 0.0]).unwrap(),
        Mat4::perspective(Angle::degrees(40), 1.0, 1.0, 5.0).unwrap(),
    );
    scene.set_viewport(Rect::new(0, 0, 32, 32)).unwrap();
    let huge = Mat4::scale([f32::MAX; 3]);
    let e = scene
        .draw(&mesh, &huge, &DrawOptions::default())
        .unwrap_err();
    assert!(
        matches!(e, DrawError::Degenerate | DrawError::NotFinite { .. }),
        "{e:?}"
    );
    // Fixed-point overflow: every entry of the transform fits I16F16 (the
    // largest, 2.75 x 10,000 = 27,500), but a vertex's sum with the
    // translation (27,500 + 10,000) does not: the error names the vertex.
    let mut slots = [VertexSlot::EMPTY; 24];
    let mut scene: Scene<'_, Fx> = Scene::new(&mut slots);
    let q = |v: i32| Fx::from_i32(v);
    scene.set_camera(
        Mat4::look_at([q(0), q(0), q(3)], [q(0); 3], [q(0), q(1), q(0)]).unwrap(),
        Mat4::perspective(Angle::degrees(40), Fx::ONE, q(1), q(5)).unwrap(),
    );
    scene.set_viewport(Rect::new(0, 0, 32, 32)).unwrap();
    let model = Mat4::translation([q(3636), q(0), q(0)]).mul(&Mat4::scale([q(20000); 3]));
    assert!(model.is_finite());
    let e = scene
        .draw(&mesh, &model, &DrawOptions::default())
        .unwrap_err();
    assert!(matches!(e, DrawError::NotFinite { .. }), "{e:?}");
    assert!(e.to_string().contains("is not finite"), "{e}");
    // A matrix that itself overflows is degenerate.
    assert_eq!(
        scene.draw(&mesh, &Mat4::scale([q(30000); 3]), &DrawOptions::default()),
        Err(DrawError::Degenerate)
    );
    // A full cache is refused with the counts.
    let mut few = [VertexSlot::EMPTY; 8];
    let mut scene: Scene<'_, f32> = Scene::new(&mut few);
    scene.set_viewport(Rect::new(0, 0, 32, 32)).unwrap();
    assert_eq!(
        scene.draw(&mesh, &Mat4::IDENTITY, &DrawOptions::default()),
        Err(DrawError::CacheFull {
            needed: 24,
            free: 8
        })
    );
}

#[test]
fn degenerate_projections_and_viewports_are_refused() {
    let p = |fov: i32, near: f32, far: f32| {
        Mat4::<f32>::perspective(Angle::degrees(fov), 1.0, near, far)
    };
    assert!(p(40, 1.0, 5.0).is_ok());
    for bad in [
        p(0, 1.0, 5.0),
        p(180, 1.0, 5.0),
        p(40, 0.0, 5.0),
        p(40, -1.0, 5.0),
        p(40, 5.0, 5.0),
        p(40, 5.0, 1.0),
        p(40, f32::NAN, 5.0),
    ] {
        assert_eq!(bad, Err(Error::Degenerate));
    }
    assert_eq!(
        Mat4::<f32>::perspective(Angle::degrees(40), 0.0, 1.0, 5.0),
        Err(Error::Degenerate)
    );
    assert_eq!(
        Mat4::<f32>::orthographic(1.0, 1.0, -1.0, 1.0, 0.0, 1.0),
        Err(Error::Degenerate)
    );
    assert_eq!(
        Mat4::<Fx>::perspective(Angle::degrees(40), Fx::ONE, Fx::ZERO, Fx::ONE),
        Err(Error::Degenerate)
    );
    let mut slots = [VertexSlot::EMPTY; 4];
    let mut scene: Scene<'_, f32> = Scene::new(&mut slots);
    assert_eq!(
        scene.set_viewport(Rect::new(0, 0, 0, 10)),
        Err(Error::Degenerate)
    );
    assert_eq!(
        scene.set_viewport(Rect::new(9000, 0, 10, 10)),
        Err(Error::Degenerate)
    );
    // Drawing before a viewport is set is refused, not garbage.
    let mut buf = [0u8; spin::CUBE_BYTES];
    let mesh = spin::cube(&mut buf).unwrap();
    let mut slots = [VertexSlot::EMPTY; 24];
    let mut scene: Scene<'_, f32> = Scene::new(&mut slots);
    assert_eq!(
        scene.draw(&mesh, &Mat4::IDENTITY, &DrawOptions::default()),
        Err(DrawError::Degenerate)
    );
}

/// Both back ends against the f64 reference on the teapot and the dolphins
/// at several angles. The bounds are the measured worst cases with a
/// margin; `reports/geometry.md` has the figures.
#[test]
fn back_ends_are_within_their_bounds_of_the_f64_reference() {
    use tilerast_sim::mesh::{geometry_error, MeshSpec};
    for model in ["teapot", "dolphins"] {
        let obj = tilerast_sim::obj::load(
            &tilerast_tests::repo().join(format!("assets/models/{model}.obj")),
            &tilerast_sim::Limits::default(),
        )
        .unwrap();
        for (rx, ry) in [(0.0, 0.0), (20.0, 37.0), (-65.0, 200.0)] {
            let mut spec = MeshSpec::new("x.obj");
            spec.rotate_x = rx;
            spec.rotate_y = ry;
            let f = geometry_error::<f32>(&obj, &spec, (240, 240));
            let x = geometry_error::<Fx>(&obj, &spec, (240, 240));
            println!("{model} {rx} {ry}\n  f32   {f:?}\n  fixed {x:?}");
            assert!(f.vertices > 100 && x.vertices > 100);
            // Position: the 1/16-pixel grid (<= 0.045 px Euclidean) plus
            // quantisation and arithmetic.
            assert!(f.max_position < F32_POS, "{model} f32 {f:?}");
            assert!(x.max_position < FX_POS, "{model} fixed {x:?}");
            assert!(f.max_depth < F32_Z, "{model} f32 {f:?}");
            assert!(x.max_depth < FX_Z, "{model} fixed {x:?}");
            assert!(f.max_color < F32_RGB, "{model} f32 {f:?}");
            assert!(x.max_color < FX_RGB, "{model} fixed {x:?}");
        }
    }
}

// Measured worst cases over these subjects (teapot, dolphins; three
// rotations): position 0.048 px (f32) / 0.051 px (fixed) — the 1/16-pixel
// grid alone is 0.044 px; depth 0.99 / 5.0 LSB of 65535 (`Fx` carries 16
// fraction bits, as many as the depth plane); colour 0.98 / 0.98 LSB
// (materials are 8-bit before lighting). Bounds with a margin:
const F32_POS: f64 = 0.06;
const FX_POS: f64 = 0.07;
const F32_Z: f64 = 1.25;
const FX_Z: f64 = 6.0;
const F32_RGB: f64 = 1.25;
const FX_RGB: f64 = 1.25;

/// Lighting: ambient + Lambert per light, summed, and a Blinn-Phong
/// highlight only where the material has `Ks`.
#[test]
fn lights_add_and_specular_needs_ks() {
    let lit = |ks: Rgb, second: bool| -> Rgb {
        let material = Material {
            kd: Rgb::new(100, 100, 100),
            ka: Rgb::new(100, 100, 100),
            ks,
            ns: 16,
        };
        let mut buf = [0u8; 128];
        let mesh = tilerast_tests::triangle_mesh(&mut buf, &[[0, 0, 32767]; 3], material);
        let mut slots = [VertexSlot::EMPTY; 3];
        let mut scene: Scene<'_, f32> = Scene::new(&mut slots);
        tilerast_tests::front_camera(&mut scene);
        // Towards the camera: N.L = N.H = 1 at every vertex.
        let mut l = Lighting::white([0.0, 0.0, 1.0], 0.2).unwrap();
        if second {
            l.add([1.0, 0.0, 0.0], [0.5; 3]).unwrap(); // grazing: N.L = 0
            l.add([0.0, 0.6, 0.8], [0.25; 3]).unwrap(); // N.L = 0.8
        }
        scene.set_lighting(l);
        scene
            .draw(&mesh, &Mat4::IDENTITY, &DrawOptions::default())
            .unwrap();
        scene.projected(0, 0).unwrap().color
    };
    // 100 * 0.2 ambient + 100 * 0.8 diffuse = 100.
    assert_eq!(lit(Rgb::new(0, 0, 0), false), Rgb::new(100, 100, 100));
    // + 0.25 * 0.8 * 100 = 20 from the third light; the grazing one adds 0.
    assert_eq!(lit(Rgb::new(0, 0, 0), true), Rgb::new(120, 120, 120));
    // + Ks * 0.8 * (N.H)^16 = 60 * 0.8 = 48 of highlight, red only.
    assert_eq!(lit(Rgb::new(60, 0, 0), false), Rgb::new(148, 100, 100));
}

/// [`render`] without bins: every tile replays the whole scene through
/// `each_keyed`, which culls each triangle itself.
fn render_unbinned<S: Real>(scene: &Scene<'_, S>) -> Vec<u32> {
    let mut frame = Frame::new(W, H, 16, 16).unwrap();
    frame.clear.color = BG;
    let mut tile: Tile<{ groups(16, 16) }, Cfg> = Tile::new();
    let mut img = vec![0u32; W as usize * H as usize];
    frame
        .render_with(&mut tile, scene, |t| keep(&mut img, t))
        .unwrap();
    img
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]
    /// Binning walks the front triangles the vertex stage noted in the
    /// cache's spare bits (when nothing is clipped): the same image as
    /// tiles that cull every triangle themselves, for every cull mode,
    /// winding, turn and camera — near ones clip, and then binning walks
    /// every triangle.
    #[test]
    fn binning_the_noted_front_triangles_draws_what_culling_each_draws(
        turn in any::<u16>(),
        cull in 0..3u8,
        dist in 0.3f32..4.0,
        height in -1.5f32..1.5,
    ) {
        let mut buf = [0u8; spin::CUBE_BYTES];
        let mesh = spin::cube(&mut buf).unwrap();
        let cull = [Cull::Back, Cull::Front, Cull::None][cull as usize];
        let mut slots = [VertexSlot::EMPTY; 24];
        let eye = [0.2, height, dist];
        if let Ok((scene, _)) = cube_scene::<f32>(&mut slots, &mesh, eye, [0.0; 3], turn, cull) {
            prop_assert_eq!(render(&scene), render_unbinned(&scene));
        };
    }
}

/// A draw's primitives as commands: mesh triangles converted.
fn primitives<S: Real>(scene: &Scene<'_, S>) -> Vec<Command> {
    let mut out = vec![];
    scene.each_primitive_of(0, |p| {
        out.push(match p {
            Primitive::Mesh(t) => t.command(),
            Primitive::Command(c) => *c,
        })
    });
    out
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]
    /// The culling walk's primitives are the draw's commands, in order,
    /// whether the clipped pieces are clipped on each call or kept in the
    /// cache once (`Scene::keep_clipped`), for every cull mode, turn and
    /// camera (near ones clip), in f32 and fixed point; with too few free
    /// slots nothing is kept and nothing changes.
    #[test]
    fn kept_clipped_pieces_are_the_draws_commands(
        turn in any::<u16>(),
        cull in 0..3u8,
        dist in 0.3f32..4.0,
        height in -1.5f32..1.5,
        fixed in any::<bool>(),
    ) {
        let mut buf = [0u8; spin::CUBE_BYTES];
        let mesh = spin::cube(&mut buf).unwrap();
        let cull = [Cull::Back, Cull::Front, Cull::None][cull as usize];
        let eye = [0.2, height, dist];
        fn check<S: Real>(mesh: &Mesh<'_>, eye: [f32; 3], turn: u16, cull: Cull, room: usize) -> Result<(), TestCaseError> {
            let mut slots = vec![VertexSlot::EMPTY; 24 + room];
            let Ok((mut scene, st)) = cube_scene::<S>(&mut slots, mesh, eye, [0.0; 3], turn, cull) else {
                return Ok(());
            };
            if scene.draw_count() == 0 {
                return Ok(());
            }
            let mut cmds = vec![];
            scene.each_of(0, |c| cmds.push(*c));
            prop_assert_eq!(&primitives(&scene), &cmds);
            let kept = scene.keep_clipped(0);
            prop_assert_eq!(&primitives(&scene), &cmds);
            if room >= 3 * 7 * 12 {
                prop_assert!(kept);
            }
            if st.clipped == 0 {
                prop_assert!(kept);
            }
            Ok(())
        }
        for room in [0, 3, 3 * 7 * 12] {
            if fixed {
                check::<Fx>(&mesh, eye, turn, cull, room)?;
            } else {
                check::<f32>(&mesh, eye, turn, cull, room)?;
            }
        }
    }
}
