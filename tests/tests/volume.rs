//! Volume rendering with normal blending (seed 002): the equality of §4.2
//! within its rounding bound, tiling, the Z test against geometry, the
//! extremes, and that scenes without a volume carry nothing of it.

use proptest::prelude::*;
use tilerast::geometry::{Angle, Mat4};
use tilerast::prelude::*;
use tilerast::volume::*;
use tilerast_sim::render::{Config, FormatKind};
use tilerast_sim::volume::{
    equality_bound, render, ModeKind, NormalsKind, ViewKind, VolumeData, VolumeRun, VolumeScene,
    VolumeSpec,
};
use tilerast_sim::Scene;
use tilerast_tests::{assert_golden, cases, config, scene};

fn cfg(side: u16, tile: (u16, u16)) -> Config {
    Config {
        tile,
        depth: true,
        ..config(side, side, FormatKind::Rgb888)
    }
}

fn spec(
    transfer: Vec<[f64; 5]>,
    rotate: [f64; 3],
    lights: Vec<[f64; 4]>,
    slices: u16,
) -> VolumeSpec {
    VolumeSpec {
        slices,
        eye: [0.0, 0.0, 2.0],
        rotate,
        lights,
        ..VolumeSpec::new(transfer)
    }
}

fn volume_scene(data: VolumeData, spec: VolumeSpec) -> VolumeScene {
    let transfer = tilerast_sim::volume::transfer(&spec.transfer).unwrap();
    VolumeScene::new(data, transfer, spec).unwrap()
}

fn run(mode: ModeKind, slices: u16) -> VolumeRun {
    VolumeRun {
        mode,
        normals: NormalsKind::Quantized,
        view: ViewKind::Shaded,
        slices,
        skip_empty: true,
    }
}

/// A random density field: a few soft blobs (seeded).
fn blobs(seed: u64, n: u16) -> VolumeData {
    let mut rng = tilerast_tests::Rng::new(seed);
    let centres: Vec<[f64; 4]> = (0..4)
        .map(|_| {
            [
                rng.range(0, n as i64) as f64,
                rng.range(0, n as i64) as f64,
                rng.range(0, n as i64) as f64,
                rng.range(2, n as i64 / 2) as f64,
            ]
        })
        .collect();
    let mut d = Vec::new();
    for z in 0..n {
        for y in 0..n {
            for x in 0..n {
                let v: f64 = centres
                    .iter()
                    .map(|c| {
                        let r2 = (x as f64 - c[0]).powi(2)
                            + (y as f64 - c[1]).powi(2)
                            + (z as f64 - c[2]).powi(2);
                        255.0 * (1.0 - r2.sqrt() / c[3]).max(0.0)
                    })
                    .fold(0.0, f64::max);
                d.push(v as u8);
            }
        }
    }
    let dir = std::env::temp_dir().join(format!("tilerast-blobs-{seed}-{n}.raw"));
    std::fs::write(&dir, &d).unwrap();
    VolumeData::load_raw(&dir, [n; 3]).unwrap()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(cases(12)))]

    /// §4.2: with one colour, normal blending (shade once) and per-slice
    /// shading (shade every sample) agree within the rounding bound, on
    /// random volumes, rotations, lights and slice counts.
    #[test]
    fn normal_blending_equals_per_slice_shading_within_the_bound(
        seed in 0u64..1000,
        rot in prop::array::uniform3(-180.0f64..180.0),
        light in prop::array::uniform3(-1.0f64..1.0),
        kd in 0.1f64..1.5,
        two in any::<bool>(),
        slices in 4u16..48,
        alpha in 30.0f64..255.0,
    ) {
        prop_assume!(light.iter().map(|v| v * v).sum::<f64>() > 0.01);
        let mut lights = vec![[light[0], light[1], light[2], kd]];
        if two {
            lights.push([-light[1], light[0], 0.5, 0.4]);
        }
        let tf = vec![[40.0, 0.0, 200.0, 180.0, 90.0], [200.0, alpha, 200.0, 180.0, 90.0]];
        let vs = volume_scene(blobs(seed, 20), spec(tf, rot, lights.clone(), slices));
        let c = cfg(40, (40, 40));
        let (a, ta) = render(&c, &[], &vs, run(ModeKind::Normal, slices), &lights).unwrap();
        let (b, tb) = render(&c, &[], &vs, run(ModeKind::PerSlice, slices), &lights).unwrap();
        prop_assert_eq!(ta.stats, tb.stats);
        let bound = equality_bound(&lights, 0.2, slices as u32);
        let worst = a.image.pixels.iter().zip(&b.image.pixels)
            .flat_map(|(p, q)| (0..3).map(move |i| p[i].abs_diff(q[i])))
            .max().unwrap();
        prop_assert!(worst as f64 <= bound, "max difference {} > bound {:.2}", worst, bound);
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(cases(16)))]

    /// Empty-space skipping changes no byte: random volumes, rotations,
    /// transfer thresholds, brick sides, by bricks or by cells, and both
    /// compositing modes give the same image, depth and counts with and
    /// without it (the cells walk no more samples), and only the skipped
    /// samples (never a blended one) go unfetched.
    #[test]
    fn skipping_empty_bricks_changes_nothing(
        seed in 0u64..1000,
        rot in prop::array::uniform3(-180.0f64..180.0),
        clear in 0.0f64..250.0,
        shift in tilerast::volume::BRICK_SHIFTS,
        per_slice in any::<bool>(),
        by_cells in any::<bool>(),
        slices in 4u16..40,
    ) {
        let tf = vec![[clear, 0.0, 200.0, 180.0, 90.0], [(clear + 5.0).min(255.0), 150.0, 90.0, 180.0, 200.0]];
        let data = blobs(seed, 20).with_brick_shift(shift).unwrap();
        let lights = vec![[0.3, 0.5, 1.0, 0.8]];
        let mut vs = volume_scene(data, spec(tf, rot, lights.clone(), slices));
        if !by_cells {
            vs.cells.clear();
        }
        let c = cfg(40, (40, 20));
        let mode = if per_slice { ModeKind::PerSlice } else { ModeKind::Normal };
        let on = run(mode, slices);
        let off = VolumeRun { skip_empty: false, ..on };
        let (a, ta) = render(&c, &[], &vs, on, &lights).unwrap();
        let (b, tb) = render(&c, &[], &vs, off, &lights).unwrap();
        prop_assert_eq!(&a.raw, &b.raw);
        prop_assert_eq!(&a.depth, &b.depth);
        if by_cells {
            // The cells' box: the samples around it are not walked.
            prop_assert!(ta.stats.samples <= tb.stats.samples);
        } else {
            prop_assert_eq!(ta.stats.samples, tb.stats.samples);
        }
        prop_assert_eq!(ta.stats.composited, tb.stats.composited);
        prop_assert_eq!(tb.stats.skipped, 0);
        prop_assert!(ta.stats.skipped + ta.stats.composited <= ta.stats.samples);
    }
}

/// Skipping skips: on the sphere, most of the transparent samples around
/// it are never fetched.
#[test]
fn skipping_empty_bricks_skips_the_empty_space() {
    let tf = vec![
        [100.0, 0.0, 255.0, 120.0, 60.0],
        [230.0, 200.0, 255.0, 255.0, 255.0],
    ];
    let vs = volume_scene(
        VolumeData::sphere(32).unwrap(),
        spec(tf, [20.0, 30.0, 0.0], vec![[0.3, 0.5, 1.0, 0.8]], 32),
    );
    let l = vs.spec.lights.clone();
    let (_, t) = render(&cfg(64, (32, 32)), &[], &vs, run(ModeKind::Normal, 32), &l).unwrap();
    let transparent = t.stats.samples - t.stats.composited;
    assert!(
        t.stats.skipped * 2 > transparent,
        "{} of {transparent} transparent samples skipped",
        t.stats.skipped
    );
}

/// The bound is not vacuous: it stays within a few levels for the
/// report's largest case, and a rounding error of its size would show.
#[test]
fn the_equality_bound_is_tight_enough_to_mean_something() {
    let b = equality_bound(&[[0.4, 0.6, 1.0, 0.8]], 0.2, 256);
    assert!(b > 1.0 && b < 10.0, "{b}");
}

/// Tiles cannot change the picture: spans are solved per row from the
/// slice's exact plane, whatever the tile.
#[test]
fn tiles_do_not_change_the_volume() {
    let tf = vec![
        [60.0, 0.0, 255.0, 100.0, 50.0],
        [220.0, 180.0, 50.0, 200.0, 255.0],
    ];
    let vs = volume_scene(
        blobs(7, 24),
        spec(tf, [20.0, 35.0, 0.0], vec![[0.3, 0.5, 1.0, 0.8]], 24),
    );
    let l = vs.spec.lights.clone();
    let one = render(&cfg(48, (48, 48)), &[], &vs, run(ModeKind::Normal, 24), &l).unwrap();
    for tile in [(16, 16), (7, 5), (48, 1), (1, 48)] {
        let other = render(&cfg(48, tile), &[], &vs, run(ModeKind::Normal, 24), &l).unwrap();
        assert_eq!(one.0.raw, other.0.raw, "tile {tile:?}");
        assert_eq!(
            one.1.stats.composited, other.1.stats.composited,
            "tile {tile:?}"
        );
    }
}

/// Opaque geometry in front hides the volume (the Z test against the
/// slices); beside it the volume shows.
#[test]
fn geometry_in_front_hides_the_volume() {
    let tf = vec![
        [50.0, 0.0, 255.0, 255.0, 255.0],
        [150.0, 255.0, 255.0, 255.0, 255.0],
    ];
    let vs = volume_scene(
        VolumeData::sphere(24).unwrap(),
        spec(tf, [0.0; 3], vec![[0.0, 0.0, 1.0, 0.8]], 24),
    );
    let l = vs.spec.lights.clone();
    let c = cfg(48, (24, 24));
    let wall = [
        Command::fill(Rect::new(0, 0, 24, 48), Rgb::new(0, 0, 200)),
        Command::zfill(Rect::new(0, 0, 24, 48), 0),
    ];
    let (with, _) = render(&c, &wall, &vs, run(ModeKind::Normal, 24), &l).unwrap();
    let (without, _) = render(&c, &[], &vs, run(ModeKind::Normal, 24), &l).unwrap();
    for y in 0..48u32 {
        for x in 0..48u32 {
            let i = (y * 48 + x) as usize;
            if x < 24 {
                assert_eq!(
                    with.image.pixels[i],
                    [0, 0, 200],
                    "({x}, {y}) is behind the wall"
                );
            } else {
                assert_eq!(with.image.pixels[i], without.image.pixels[i], "({x}, {y})");
            }
        }
    }
    // The volume does show on the right.
    assert!(without.image.pixels[(24 * 48 + 30) as usize] != [0, 0, 0]);
}

/// The extremes: a camera inside the volume, a volume far away (a few
/// pixels), the smallest volume, every voxel opaque, degenerate matrices.
#[test]
fn extreme_views_and_volumes() {
    let tf = vec![[0.0, 255.0, 255.0, 255.0, 255.0]];
    let l = vec![[0.0, 0.0, 1.0, 0.8]];
    for (data, eye) in [
        (VolumeData::sphere(16).unwrap(), [0.0, 0.0, 0.1]), // inside
        (VolumeData::sphere(16).unwrap(), [0.0, 0.0, 0.0]), // at the centre
        (VolumeData::sphere(16).unwrap(), [0.0, 0.0, 500.0]), // a dot
        (VolumeData::sphere(2).unwrap(), [0.0, 0.0, 2.0]),  // 2^3
    ] {
        let mut s = spec(tf.clone(), [10.0, 20.0, 30.0], l.clone(), 16);
        s.eye = eye;
        let vs = volume_scene(data, s);
        let r = render(&cfg(32, (32, 32)), &[], &vs, run(ModeKind::Normal, 16), &l);
        // A camera at the centre cannot look at it (look_at is degenerate):
        // an error, never a panic.
        if eye == [0.0, 0.0, 0.0] {
            assert!(r.is_err());
        } else {
            r.unwrap();
        }
    }
    // Every sample opaque: the accumulated opacity saturates at 1 exactly.
    let d = vec![255u8; 8 * 8 * 8];
    let vol = Volume::new(&d, [8; 3]).unwrap();
    let tf = Transfer::from_points(&[TfPoint::new(0, 255, Rgb::new(255, 255, 255))]).unwrap();
    let m = Mat4::<f32>::IDENTITY;
    let view = Mat4::look_at([0.0, 0.0, 2.0], [0.0; 3], [0.0, 1.0, 0.0]).unwrap();
    let proj = Mat4::perspective(Angle::degrees(40), 1.0, 0.5, 4.0).unwrap();
    let screen = Rect::new(0, 0, 16, 16);
    let v: VolumeView<'_, 64> = VolumeView::new(vol, &tf, &m, &view, &proj, screen, 64).unwrap();
    type T = Tile<{ groups(16, 16) }, Planes<Rgb888Format, Depth16>>;
    let mut tile = T::new();
    tile.begin(screen, &Clear::default()).unwrap();
    let mut plane = VolumePlane::<{ groups(16, 16) }, NormalCell>::new();
    plane.composite(&tile, &v, &NormalBlending);
    assert_eq!(plane.cell(8, 8).unwrap().a, 32768);
    // A zero scale is singular; a projection whose w depends on x is not
    // one the slicer takes; more slices than the capacity is an error.
    let zero = Mat4::<f32>::scale([0.0, 1.0, 1.0]);
    assert_eq!(
        VolumeView::<64>::new(vol, &tf, &zero, &view, &proj, screen, 8).err(),
        Some(Error::Degenerate)
    );
    let mut skew = proj;
    skew.m[3][0] = 0.5;
    assert_eq!(
        VolumeView::<64>::new(vol, &tf, &m, &view, &skew, screen, 8).err(),
        Some(Error::Degenerate)
    );
    assert_eq!(
        VolumeView::<4>::new(vol, &tf, &m, &view, &proj, screen, 8).err(),
        Some(Error::ListFull)
    );
    // Lights out of range.
    assert!(VolumeLights::new(&m, &[([0.0, 0.0, 1.0], 3.0)], 0.2).is_err());
    assert!(VolumeLights::new(&m, &[([0.0, 0.0, 0.0], 1.0)], 0.2).is_err());
}

/// A scene without a volume carries nothing of it: the tile's planes are
/// the configuration's alone (the volume plane is a separate object a
/// frame with a volume lends), and a firmware built without the `volume`
/// feature has no volume code at all (`firmware.rs`).
#[test]
fn scenes_without_a_volume_pay_nothing() {
    assert_eq!(
        Tile::<{ groups(32, 32) }, St7789Config>::plane_bytes(),
        4 * 32 * 32
    );
    assert_eq!(
        VolumePlane::<{ groups(32, 32) }, NormalCell>::bytes(),
        14 * 32 * 32
    );
    let s = Scene::load(scene("demo.toml")).unwrap();
    assert!(s.volume.is_none());
}

/// The volume scene renders pixel-exactly as committed.
#[test]
fn volume_scene_matches_golden() {
    let s = Scene::load(scene("volume.toml")).unwrap();
    assert!(s.volume.is_some());
    assert_golden("volume", &s.render().unwrap().image);
}
