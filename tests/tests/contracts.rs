//! The two numeric contracts for opaque Gouraud triangles, side by side on
//! a real mesh (the teapot through the on-device geometry stage):
//!
//! - the fused mesh path (vertex cache -> tile, no command built) draws
//!   exactly what the same triangles draw as commands, under each contract;
//! - each contract is invariant under tiling (random tile sizes, proptest);
//! - the plane contract ([`PlaneContract`]) stays within one unit of the
//!   exact contract on every channel and every pixel after packing, and
//!   differs on few pixels.

use proptest::prelude::*;
use std::sync::OnceLock;
use tilerast::geometry::*;
use tilerast::prelude::*;

const SIDE: u16 = 96;
type Exact = Planes<Rgb565Format, Depth16, NoWid, NoDither, NoAa, FullPrecision>;
type Fast = Planes<Rgb565Format, Depth16, NoWid, NoDither, NoAa, PlaneContract>;

/// The teapot in the geometry stage's mesh format (exported once).
fn teapot() -> &'static [u8] {
    static BYTES: OnceLock<Vec<u8>> = OnceLock::new();
    BYTES.get_or_init(|| {
        tilerast_sim::mesh::export_mesh(
            &tilerast_tests::repo().join("assets/models/teapot.obj"),
            &tilerast_sim::Limits::default(),
        )
        .unwrap()
    })
}

/// The teapot turned by `turn` (1/65536 of a turn), lit, at SIDE x SIDE.
fn scene<'a>(slots: &'a mut [VertexSlot], mesh: &Mesh<'a>, turn: u16) -> Scene<'a, f32, 1> {
    let mut scene = Scene::new(slots);
    scene.set_camera(
        Mat4::look_at([0.0, 0.0, 3.0], [0.0; 3], [0.0, 1.0, 0.0]).unwrap(),
        Mat4::perspective(Angle::degrees(40), 1.0, 1.0, 5.0).unwrap(),
    );
    scene
        .set_viewport(Rect::new(0, 0, SIDE as u32, SIDE as u32))
        .unwrap();
    scene.set_lighting(Lighting::white([0.4, 0.6, 1.0], 0.2).unwrap());
    let model =
        Mat4::rotation_x(Angle::degrees(20)).mul(&Mat4::rotation_y(Angle::from_turn_q16(turn)));
    scene.draw(mesh, &model, &DrawOptions::default()).unwrap();
    scene
}

/// A floor 40 units square and a cube on it, seen from 0.3 above the
/// floor at `k` of 8 headings: the floor's near-clipped triangles reach
/// thousands of pixels off the screen (the plane contract's far
/// triangles, `tilerast::tile::mesh`).
fn floor_scene<'a>(slots: &'a mut [VertexSlot], mesh: &Mesh<'a>, k: u16) -> Scene<'a, f32, 2> {
    let mut scene = Scene::new(slots);
    let a = std::f32::consts::TAU * k as f32 / 8.0;
    let eye = [0.7 * a.cos(), 0.3, 0.7 * a.sin()];
    scene.set_camera(
        Mat4::look_at(eye, [0.0, 0.1, 0.0], [0.0, 1.0, 0.0]).unwrap(),
        Mat4::perspective(Angle::degrees(70), 1.0, 0.05, 30.0).unwrap(),
    );
    scene
        .set_viewport(Rect::new(0, 0, SIDE as u32, SIDE as u32))
        .unwrap();
    scene.set_lighting(Lighting::white([0.4, 0.6, 1.0], 0.2).unwrap());
    let floor = Mat4::translation([0.0, -0.05, 0.0]).mul(&Mat4::scale([40.0, 0.1, 40.0]));
    scene.draw(mesh, &floor, &DrawOptions::default()).unwrap();
    let block = Mat4::translation([0.0, 0.15, 0.0]).mul(&Mat4::scale([0.3; 3]));
    scene.draw(mesh, &block, &DrawOptions::default()).unwrap();
    scene
}

/// The floor scene's cube (one quad a face).
fn floor_mesh(buf: &mut [u8]) -> Mesh<'_> {
    tilerast_fw::city::cube(1, Rgb::new(150, 120, 90), buf).unwrap()
}

/// Renders `src` in tiles of `tw x th` into packed pixels and depths.
fn render<C: TileConfig, S: CommandSource + ?Sized>(src: &S, tw: u16, th: u16) -> Vec<(u32, u16)> {
    let frame = Frame::new(SIDE, SIDE, tw, th).unwrap();
    let mut tile: Box<Tile<{ groups(64, 64) }, C>> = Box::new(Tile::new());
    let mut bins: Box<Bins<16384, 256>> = Box::new(Bins::new());
    let mut img = vec![(0, 0); SIDE as usize * SIDE as usize];
    frame
        .render_binned(&mut tile, &mut bins, src, |t| {
            let r = t.area();
            for y in r.y..r.y + r.h as i32 {
                for x in r.x..r.x + r.w as i32 {
                    img[(y * SIDE as i32 + x) as usize] =
                        (t.raw(x, y).unwrap(), t.depth(x, y).unwrap());
                }
            }
            Ok::<(), ()>(())
        })
        .unwrap();
    img
}

/// The scene's triangles as a command list.
fn commands<const D: usize>(scene: &Scene<'_, f32, D>) -> Vec<Command> {
    let mut cmds = vec![];
    scene.each(|c| cmds.push(*c)).unwrap();
    cmds
}

/// Asserts that `a` and `b` draw the same pixels and depths in tiles of
/// `tiles`, under each contract.
fn assert_same_draw<A: CommandSource + ?Sized, B: CommandSource + ?Sized>(
    a: &A,
    b: &B,
    (tw, th): (u16, u16),
    what: &str,
) {
    assert_eq!(
        render::<Exact, _>(a, tw, th),
        render::<Exact, _>(b, tw, th),
        "exact, {what}"
    );
    assert_eq!(
        render::<Fast, _>(a, tw, th),
        render::<Fast, _>(b, tw, th),
        "plane, {what}"
    );
}

/// The geometry stage's fused mesh path (vertex cache -> tile) and an
/// encoded mesh record (`tilerast::wire`, what the firmware's scenes are,
/// replayed to the tile's mesh path undecoded) draw the same pixels and
/// depths as their triangles drawn as commands, under each contract and in
/// several tilings.
#[test]
fn the_mesh_paths_draw_what_the_commands_draw() {
    use tilerast::wire::{encode_mesh, Encoded};
    let mesh = Mesh::parse(teapot()).unwrap();
    let mut slots = vec![VertexSlot::EMPTY; mesh.vertices() as usize];
    for turn in [0u16, 9000, 30000, 47000] {
        let s = scene(&mut slots, &mesh, turn);
        let cmds = commands(&s);
        assert!(cmds.len() > 1000);
        assert_same_draw(&s, &cmds[..], (32, 16), &format!("scene, turn {turn}"));
        let (mut verts, mut tris) = (vec![], vec![]);
        for c in &cmds {
            let Command::Triangle { v, state } = c else {
                panic!("not a Gouraud triangle: {c:?}");
            };
            assert_eq!(*state, State::default());
            let k = verts.len() as u16;
            verts.extend_from_slice(v);
            tris.push([k, k + 1, k + 2]);
        }
        let mut buf = vec![0u8; 16 * verts.len() + 8 * tris.len() + 64];
        let n = encode_mesh(&verts, &tris, &State::default(), &mut buf).unwrap();
        let enc = Encoded(&buf[..n]);
        for tiles in [(32, 16), (64, 64), (7, 5)] {
            let what = format!("encoded, turn {turn}, tiles {tiles:?}");
            assert_same_draw(&enc, &cmds[..], tiles, &what);
        }
    }
}

/// Asserts that the plane contract draws `src` within one unit of the
/// exact contract on every channel and depth, covering the same pixels;
/// adds the covered pixels and those that differ to `counts`.
fn assert_within_one_unit<S: CommandSource + ?Sized>(src: &S, counts: &mut (u32, u32)) {
    let (covered, differ) = counts;
    let (exact, fast) = (
        render::<Exact, _>(src, 64, 32),
        render::<Fast, _>(src, 64, 32),
    );
    for (e, f) in exact.iter().zip(&fast) {
        assert_eq!(e.1 == u16::MAX, f.1 == u16::MAX, "coverage");
        if e.1 == u16::MAX {
            continue;
        }
        *covered += 1;
        *differ += (e.0 != f.0) as u32;
        let ch = |v: u32| [(v >> 11) as i32, (v >> 5 & 63) as i32, (v & 31) as i32];
        for (a, b) in ch(e.0).iter().zip(ch(f.0)) {
            assert!((a - b).abs() <= 1, "colour {:#06x} vs {:#06x}", e.0, f.0);
        }
        assert!(
            (e.1 as i32 - f.1 as i32).abs() <= 1,
            "depth {} vs {}",
            e.1,
            f.1
        );
    }
}

#[test]
fn the_plane_contract_is_within_one_unit_of_the_exact_one() {
    let mesh = Mesh::parse(teapot()).unwrap();
    let mut slots = vec![VertexSlot::EMPTY; mesh.vertices() as usize];
    let mut counts = (0, 0);
    for turn in (0..8u16).map(|k| k * 8192) {
        assert_within_one_unit(&scene(&mut slots, &mesh, turn), &mut counts);
    }
    let (covered, differ) = counts;
    assert!(covered > 10_000, "{covered}");
    assert!(
        differ * 200 < covered,
        "{differ} of {covered} pixels differ"
    );
}

/// The same on a near-clipped floor, whose triangles are the plane
/// contract's far ones (a side of 1024 pixels or more: checked), and in
/// tilings of every shape.
#[test]
fn far_triangles_are_within_one_unit_and_invariant_under_tiling() {
    let mut buf = vec![0u8; tilerast_fw::city::MESH_BYTES];
    let mesh = floor_mesh(&mut buf);
    let mut slots = vec![VertexSlot::EMPTY; 2 * mesh.vertices() as usize];
    let (mut counts, mut far) = ((0, 0), 0);
    for k in 0..8 {
        let s = floor_scene(&mut slots, &mesh, k);
        far += commands(&s)
            .iter()
            .filter(|c| {
                let Command::Triangle { v, .. } = c else {
                    return false;
                };
                let side = |f: fn(&Vertex) -> i32| {
                    v.iter().map(f).max().unwrap() - v.iter().map(f).min().unwrap()
                };
                side(|v| v.x.to_bits()) >= 1 << 14 || side(|v| v.y.to_bits()) >= 1 << 14
            })
            .count();
        assert_within_one_unit(&s, &mut counts);
        let one = render::<Fast, _>(&s, 64, 64);
        for tiles in [(7, 5), (40, 40), (48, 16), (64, 1)] {
            assert_eq!(
                render::<Fast, _>(&s, tiles.0, tiles.1),
                one,
                "{k}, {tiles:?}"
            );
        }
    }
    let (covered, differ) = counts;
    println!("{far} far triangles, {covered} pixels covered, {differ} differ");
    assert!(
        far >= 8 && covered > 30_000,
        "{far} far triangles, {covered} pixels"
    );
    assert!(
        differ * 100 < covered,
        "{differ} of {covered} pixels differ"
    );
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, ..ProptestConfig::default() })]

    /// Tiles of any size give the pixels of one 64x64-or-smaller tiling,
    /// under each contract.
    #[test]
    fn both_contracts_are_invariant_under_tiling(
        turn in any::<u16>(), tw in 1u16..=64, th in 1u16..=64,
    ) {
        let mesh = Mesh::parse(teapot()).unwrap();
        let mut slots = vec![VertexSlot::EMPTY; mesh.vertices() as usize];
        let s = scene(&mut slots, &mesh, turn);
        prop_assert_eq!(render::<Fast, _>(&s, tw, th), render::<Fast, _>(&s, 64, 64));
        prop_assert_eq!(render::<Exact, _>(&s, tw, th), render::<Exact, _>(&s, 64, 64));
    }
}
