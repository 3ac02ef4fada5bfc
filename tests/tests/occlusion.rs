//! Occlusion culling (seed 004): exactness on every frame of camera paths,
//! the block summary against brute force, the k-d tree's order, the
//! threshold's pixel loss.

use proptest::prelude::*;
use tilerast::geometry::{Mat4, Scene, VertexSlot};
use tilerast::occlusion::{Aabb, CullMode, CullStats, Culler, HiZ, KdTree, TestCost};
use tilerast::prelude::*;
use tilerast_fw::city::{self, City};

type Cfg = St7789Config;
const TILE: u16 = 32;
const G: usize = (TILE as usize * TILE as usize) / 8;
const SCREEN: u16 = 96;

/// Every frame's pixels (rows of packed values) of a walk through `c`.
fn walk(c: &City, frames: u32, mode: CullMode, threshold: u8) -> (Vec<Vec<u32>>, CullStats) {
    let mut frame = Tile::<G, Cfg>::frame::<TILE, TILE>(SCREEN, SCREEN).unwrap();
    frame.clear.color = city::SKY;
    let (out, walked, _) =
        tilerast_sim::city::walk_pixels::<Cfg, G, 16, 3>(c, &frame, frames, mode, threshold)
            .unwrap();
    let mut total = CullStats::default();
    for f in walked {
        total += f.stats;
    }
    (out, total)
}

#[test]
fn every_mode_equals_the_unculled_frame_on_every_frame() {
    for sub in [1, 3] {
        let c = City {
            side: 5,
            sub,
            seed: 3,
        };
        let (reference, none) = walk(&c, 24, CullMode::Off, 0);
        for mode in [CullMode::StopAndWait, CullMode::Chc, CullMode::SinglePass] {
            let (frames, st) = walk(&c, 24, mode, 0);
            for (k, (a, b)) in frames.iter().zip(&reference).enumerate() {
                assert!(a == b, "sub {sub}, {}: frame {k} differs", mode.name());
            }
            // Culling happened: fewer commands drawn than without.
            assert!(
                st.nodes_culled > 0 && st.commands < none.commands,
                "sub {sub}, {}: {st:?} vs {none:?}",
                mode.name()
            );
        }
    }
}

#[test]
fn single_pass_reads_less_than_queries_and_tests_early() {
    let c = City {
        side: 5,
        sub: 3,
        seed: 3,
    };
    let (_, chc) = walk(&c, 16, CullMode::Chc, 0);
    let (_, sw) = walk(&c, 16, CullMode::StopAndWait, 0);
    let (_, sp) = walk(&c, 16, CullMode::SinglePass, 0);
    // CHC tests fewer boxes than stop-and-wait (coherence); the single
    // pass tests the same boxes as CHC, reading the summary instead of
    // every pixel, and skips hidden primitives early.
    assert!(chc.boxes_tested < sw.boxes_tested, "{chc:?} {sw:?}");
    assert!(sp.cost.reads < chc.cost.reads, "{sp:?} {chc:?}");
    assert!(sp.prims_culled > 0 && sp.commands < chc.commands);
}

#[test]
fn a_threshold_loses_few_pixels_and_culls_more() {
    let c = City {
        side: 5,
        sub: 2,
        seed: 9,
    };
    let (reference, _) = walk(&c, 12, CullMode::Off, 0);
    for thr in [0u8, 16, 128] {
        let (frames, st) = walk(&c, 12, CullMode::SinglePass, thr);
        let lost: usize = frames
            .iter()
            .zip(&reference)
            .map(|(a, b)| a.iter().zip(b).filter(|(x, y)| x != y).count())
            .sum();
        if thr == 0 {
            assert_eq!(lost, 0);
        }
        // A node skipped for t fragments in a tile loses at most the
        // pixels it had there, over all frames: bounded by the culled
        // visits times t (and the whole screen).
        assert!(
            lost as u64 <= st.nodes_culled as u64 * thr as u64,
            "threshold {thr}: {lost} pixels lost, {} visits culled",
            st.nodes_culled
        );
    }
}

#[test]
fn threshold_beyond_seven_bits_is_refused() {
    let boxes = [Aabb::new([0.0f32; 3], [1.0; 3])];
    let mut c: Culler<f32, 1> = Culler::new(KdTree::build(&boxes).unwrap());
    assert_eq!(c.set_threshold(129), Err(Error::BadSize));
    assert_eq!(c.set_threshold(128), Ok(()));
}

#[test]
fn kd_tree_refuses_bad_input() {
    assert_eq!(KdTree::<f32, 8>::build(&[]).err(), Some(Error::BadSize));
    let nan = [Aabb::new([f32::NAN; 3], [1.0; 3])];
    assert_eq!(KdTree::<f32, 8>::build(&nan).err(), Some(Error::NotFinite));
    let inverted = [Aabb::new([1.0; 3], [0.0; 3])];
    assert_eq!(
        KdTree::<f32, 8>::build(&inverted).err(),
        Some(Error::NotFinite)
    );
    let five = [Aabb::new([0.0; 3], [1.0; 3]); 5];
    assert_eq!(KdTree::<f32, 8>::build(&five).err(), Some(Error::ListFull));
    assert!(KdTree::<f32, 9>::build(&five).is_ok());
}

/// The pixels of `p` inside the tile whose depth is farther than `z`.
fn brute_count<const N: usize, C: TileConfig>(tile: &Tile<N, C>, p: Rect, z: u16) -> u32 {
    let mut n = 0;
    for y in p.y..p.y + p.h as i32 {
        for x in p.x..p.x + p.w as i32 {
            if let Some(d) = tile.depth(x, y) {
                n += (z < d) as u32;
            }
        }
    }
    n
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    /// Front to back visits every object once, and along every split the
    /// camera's side comes first.
    #[test]
    fn kd_order_is_a_permutation_and_respects_splits(
        cs in prop::collection::vec((-50i32..50, -50i32..50, -50i32..50, 1i32..6), 1..40),
        eye in (-80i32..80, -80i32..80, -80i32..80),
    ) {
        let boxes: Vec<Aabb<f32>> = cs.iter().map(|&(x, y, z, s)| {
            let (x, y, z, s) = (x as f32, y as f32, z as f32, s as f32);
            Aabb::new([x, y, z], [x + s, y + s, z + s])
        }).collect();
        let tree: KdTree<f32, 80> = KdTree::build(&boxes).unwrap();
        prop_assert_eq!(tree.len(), 2 * boxes.len() - 1);
        let eye = [eye.0 as f32, eye.1 as f32, eye.2 as f32];
        let mut order = vec![];
        tree.front_to_back(eye, |o| order.push(o as usize));
        let mut sorted = order.clone();
        sorted.sort();
        prop_assert_eq!(sorted, (0..boxes.len()).collect::<Vec<_>>());
        // Every node's box holds its children's.
        for i in 0..tree.len() as u16 {
            if let Some((a, b)) = tree.near_far(i, eye) {
                let p = tree.node(i).bounds;
                for c in [a, b] {
                    let q = tree.node(c).bounds;
                    for k in 0..3 {
                        prop_assert!(p.lo[k] <= q.lo[k] && q.hi[k] <= p.hi[k]);
                    }
                }
            }
        }
    }

    /// The summary's count equals brute force, for any depth contents,
    /// rectangle, depth and block size.
    #[test]
    fn hiz_count_equals_brute_force(
        fills in prop::collection::vec((0i32..40, 0i32..30, 1u32..30, 1u32..20, 0u16..1000), 0..12),
        probes in prop::collection::vec((-5i32..45, -5i32..35, 1u32..50, 1u32..40, 0u16..1100), 1..12),
        w in 1u32..=40, h in 1u32..=30,
    ) {
        type T = Tile<150, Planes<Rgb565Format, Depth16>>;
        let mut tile = T::new();
        let area = Rect::new(3, 5, w, h);
        tile.begin(area, &Clear::default()).unwrap();
        let mut h2: HiZ<100, 2> = HiZ::new();
        let mut h3: HiZ<30, 3> = HiZ::new();
        let mut h5: HiZ<4, 5> = HiZ::new();
        h2.reset(area);
        h3.reset(area);
        h5.reset(area);
        for &(x, y, fw, fh, z) in &fills {
            let r = Rect::new(x, y, fw, fh);
            tile.draw(&Command::zfill(r, z)).unwrap();
            h2.touch(&r);
            h3.touch(&r);
            h5.touch(&r);
            for &(px, py, pw, ph, pz) in &probes {
                let p = Rect::new(px, py, pw, ph);
                let brute = brute_count(&tile, p, pz);
                let mut cost = TestCost::default();
                let all = u32::MAX;
                prop_assert_eq!(h2.count(&tile, p, pz, true, all, &mut cost), brute);
                prop_assert_eq!(h3.count(&tile, p, pz, true, all, &mut cost), brute);
                prop_assert_eq!(h5.count(&tile, p, pz, true, all, &mut cost), brute);
                prop_assert_eq!(h3.count(&tile, p, pz, false, all, &mut cost), brute);
                // Counting stops at the limit, never short of it.
                for limit in [1, 3, 17] {
                    prop_assert_eq!(h3.count(&tile, p, pz, true, limit, &mut cost).min(limit), brute.min(limit));
                    prop_assert!(h2.count(&tile, p, pz, true, limit, &mut cost) >= brute.min(limit));
                }
            }
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    /// A summary started at the cleared depth ([`HiZ::reset_to`]) and kept
    /// as bounds after depth-tested drawing ([`HiZ::touch_near`]: the
    /// nearest vertex depth less the walk's margin of 2) counts what brute
    /// force counts, for random Gouraud triangles and probes.
    #[test]
    fn hiz_near_bounds_count_equals_brute_force(
        tris in prop::collection::vec(
            prop::array::uniform3((-80i32..720, -80i32..560, 0u16..1200)), 0..10),
        probes in prop::collection::vec((-5i32..45, -5i32..35, 1u32..50, 1u32..40, 0u16..1300), 1..8),
        clear in 900u16..=u16::MAX,
    ) {
        type T = Tile<150, Planes<Rgb565Format, Depth16>>;
        let mut tile = T::new();
        let area = Rect::new(3, 5, 40, 30);
        let c = Clear { depth: clear, ..Clear::default() };
        tile.begin(area, &c).unwrap();
        let mut h3: HiZ<30, 3> = HiZ::new();
        let mut h2: HiZ<100, 2> = HiZ::new();
        h3.reset_to(area, clear);
        h2.reset_to(area, clear);
        for t in &tris {
            let v = t.map(|(x, y, z)| Vertex::new(Coord::from_bits(x), Coord::from_bits(y), z, Rgb::new(9, 9, 9)));
            let cmd = Command::Triangle { v, state: State::default() };
            if tile.draw(&cmd).is_err() {
                continue;
            }
            let Some(b) = cmd.bounds() else { continue };
            let near = v[0].z.min(v[1].z).min(v[2].z).saturating_sub(2);
            h3.touch_near(&b, near);
            h2.touch_near(&b, near);
            for &(px, py, pw, ph, pz) in &probes {
                let p = Rect::new(px, py, pw, ph);
                let brute = brute_count(&tile, p, pz);
                let mut cost = TestCost::default();
                prop_assert_eq!(h3.count(&tile, p, pz, true, u32::MAX, &mut cost), brute);
                prop_assert_eq!(h2.count(&tile, p, pz, true, u32::MAX, &mut cost), brute);
                prop_assert_eq!(h3.count(&tile, p, pz, true, 1, &mut cost).min(1), brute.min(1));
            }
        }
    }
}

/// A camera inside a building's box or looking from behind the near plane:
/// the box covers the viewport at depth 0 (always visible), never a wrong
/// rectangle.
#[test]
fn boxes_reaching_behind_the_camera_cover_the_screen() {
    let mut slots = [VertexSlot::EMPTY; 1];
    let mut scene: Scene<'_, f32> = Scene::new(&mut slots);
    scene.set_camera(
        Mat4::look_at([0.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]).unwrap(),
        Mat4::perspective(tilerast::geometry::Angle::degrees(60), 1.0, 0.1, 10.0).unwrap(),
    );
    scene.set_viewport(Rect::new(0, 0, 50, 40)).unwrap();
    let b = scene.screen_box([-1.0; 3], [1.0; 3]).unwrap();
    assert_eq!((b.rect, b.z), (Rect::new(0, 0, 50, 40), 0));
    // Wholly behind: outside the frustum.
    assert!(scene
        .screen_box([-1.0, -1.0, 2.0], [1.0, 1.0, 3.0])
        .is_none());
    // Extremes: huge and non-finite boxes never panic.
    let huge = scene.screen_box([-1e30; 3], [1e30; 3]);
    assert!(huge.is_some());
    let _ = scene.screen_box([f32::NAN; 3], [f32::INFINITY; 3]);
}

/// The `[city]` scene draws the same frame whatever its `cull`, and
/// reports the culling it did.
#[test]
fn city_scene_draws_the_same_frame_in_every_mode() {
    use tilerast_sim::city::CullKind;
    let mut scene = tilerast_sim::Scene::load(tilerast_tests::scene("city.toml")).unwrap();
    let reference = scene.render().unwrap();
    for kind in [CullKind::None, CullKind::StopAndWait, CullKind::Chc] {
        scene.city.as_mut().unwrap().cull = kind;
        let r = scene.render().unwrap();
        assert!(r.raw == reference.raw, "{kind:?}");
    }
    // Fewer commands with culling than without.
    scene.city.as_mut().unwrap().cull = CullKind::None;
    let none = scene.render().unwrap().stats.replayed;
    scene.city.as_mut().unwrap().cull = CullKind::SinglePass;
    let culled = scene.render().unwrap().stats.replayed;
    assert!(culled < none, "{culled} vs {none}");
}
