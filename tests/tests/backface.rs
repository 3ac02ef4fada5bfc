//! Back-face culling in the frame (`Frame::cull`): a frame that culls
//! draws exactly the list without the triangles facing that way — binned
//! through any bins (overflowing ones included) or unbinned, from a RAM list
//! or an encoded mesh read in place, and in the f64 reference — and the
//! teapot with culling keeps its picture but for the pixels where its
//! inside shows through its open rim and spout.

use proptest::prelude::*;
use tilerast::prelude::*;
use tilerast::wire::SceneHeader;
use tilerast_sim::{reference, render, FormatKind, Scene};
use tilerast_tests::{config, frame_raw, random_command, scene, Rng};

type C = Planes<Rgb565Format, Depth16, NoWid, NoDither>;

/// The list without the triangles `cull` drops.
fn kept(cmds: &[Command], cull: Cull) -> Vec<Command> {
    cmds.iter()
        .filter(|c| !c.culled_by(cull))
        .copied()
        .collect()
}

#[test]
fn winding_decides_which_side_is_dropped() {
    let v = |x: i32, y: i32| {
        Vertex::new(
            Coord::from_num(x),
            Coord::from_num(y),
            9,
            Rgb::new(255, 0, 0),
        )
    };
    // Counter-clockwise as seen on the display (negative doubled area):
    // a front face.
    let front = Command::triangle([v(0, 0), v(0, 8), v(8, 0)]);
    let back = Command::triangle([v(0, 0), v(8, 0), v(0, 8)]);
    let flat = Command::triangle([v(0, 0), v(4, 4), v(8, 8)]);
    for (cmd, b, f) in [
        (front, false, true),
        (back, true, false),
        (flat, false, false),
    ] {
        assert!(!cmd.culled_by(Cull::None));
        assert_eq!(cmd.culled_by(Cull::Back), b);
        assert_eq!(cmd.culled_by(Cull::Front), f);
    }
    // Other commands are never culled.
    let fill = Command::fill(Rect::new(0, 0, 4, 4), Rgb::new(1, 2, 3));
    assert!(!fill.culled_by(Cull::Back) && !fill.culled_by(Cull::Front));
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(tilerast_tests::cases(48)))]

    /// Random commands of every kind: a frame that culls, binned (bins
    /// large, overflowing, or none) in any tiling, and the reference
    /// renderer, draw exactly the list without the culled triangles.
    #[test]
    fn a_culling_frame_draws_the_list_without_its_culled_triangles(
        seed in any::<u64>(), tile in 0usize..3, front in any::<bool>(),
    ) {
        let mut rng = Rng::new(seed);
        let cmds: Vec<Command> = (0..24).map(|_| random_command(&mut rng, 0)).collect();
        let cull = if front { Cull::Front } else { Cull::Back };
        let rest = kept(&cmds, cull);
        let (tw, th) = [(100, 80), (32, 16), (7, 5)][tile];
        let mut frame = Frame::new(100, 80, tw, th).unwrap();
        let (want, plain) = frame_raw::<2048, C, _, 4096, 256>(&frame, &rest[..]);
        frame.cull = cull;
        let (a, sa) = frame_raw::<2048, C, _, 4096, 256>(&frame, &cmds[..]);
        let (b, _) = frame_raw::<2048, C, _, 7, 3>(&frame, &cmds[..]);
        let (c, _) = frame_raw::<2048, C, _, 0, 0>(&frame, &cmds[..]);
        prop_assert_eq!(&a, &want);
        prop_assert_eq!(&b, &want);
        prop_assert_eq!(&c, &want);
        prop_assert_eq!(sa.replayed, plain.replayed);
        // The simulator's configuration and the reference renderer agree.
        let mut cfg = config(100, 80, FormatKind::Rgb565);
        cfg.depth = true;
        cfg.cull = cull;
        let (ra, rb) = (reference::render(&cfg, &cmds), {
            cfg.cull = Cull::None;
            reference::render(&cfg, &rest)
        });
        prop_assert!(ra.color == rb.color && ra.depth == rb.depth);
    }
}

/// An encoded mesh read in place (its binning reads positions alone)
/// culls as the decoded list does, and the header carries the mode.
#[test]
fn an_encoded_teapot_culls_as_its_list() {
    let two = Scene::load(scene("teapot.toml")).unwrap();
    for cull in [Cull::Back, Cull::Front] {
        let mut s = Scene::load(scene("teapot.toml")).unwrap();
        s.config.cull = cull;
        let bytes = s.encode().unwrap();
        let (h, cmds) = SceneHeader::parse(&bytes).unwrap();
        assert_eq!(h.cull, cull);
        let frame = h.frame((64, 32)).unwrap();
        let (flash, stats) = frame_raw::<2048, C, _, 8192, 32>(&frame, &cmds);
        let mut plain = Frame::new(240, 240, 64, 32).unwrap();
        plain.clear = h.clear;
        let (list, want) =
            frame_raw::<2048, C, _, 8192, 32>(&plain, &kept(&two.commands, cull)[..]);
        assert_eq!(flash, list, "{cull:?}");
        assert_eq!(stats.replayed, want.replayed, "{cull:?}");
    }
}

/// `scenes/teapot_cull.toml`: half the (triangle, tile) pairs, and the
/// two-sided picture but where the inside shows (85 pixels of 57,600: the
/// rim under the lid, the spout's mouth).
#[test]
fn the_culled_teapot_keeps_its_picture() {
    let two = Scene::load(scene("teapot.toml")).unwrap();
    let one = Scene::load(scene("teapot_cull.toml")).unwrap();
    assert_eq!(two.commands, one.commands);
    assert_eq!(one.config.cull, Cull::Back);
    let (a, b) = (
        render(&two.config, &two.commands).unwrap(),
        render(&one.config, &one.commands).unwrap(),
    );
    let differ = a.raw.iter().zip(&b.raw).filter(|(p, q)| p != q).count();
    assert!((1..=100).contains(&differ), "{differ} pixels differ");
    assert!(
        b.stats.replayed * 100 < a.stats.replayed * 55,
        "{} of {} pairs",
        b.stats.replayed,
        a.stats.replayed
    );
}
