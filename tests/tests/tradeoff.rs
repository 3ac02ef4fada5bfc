//! The speed-against-accuracy sweep (`tilerast-lab tradeoff`) on its
//! procedural scenes, quickly (2x2 ideal, one timed run): the report's
//! claims hold, and the precision knob keeps the pipeline's guarantees.

use tilerast::prelude::*;
use tilerast_lab::tradeoff::{self, Family, Options, Point};
use tilerast_sim::render::{render_as, SIM_GROUPS};
use tilerast_sim::FormatKind;
use tilerast_tests::{config, random_command, Rng};

fn sweep() -> Vec<Point> {
    tradeoff::run(&Options {
        models: None,
        runs: 1,
        ideal_samples: 2,
        progress: false,
    })
    .unwrap()
}

fn find<'a>(p: &'a [Point], scene: &str, setting: &str) -> &'a Point {
    p.iter()
        .find(|p| p.scene.starts_with(scene) && p.setting == setting)
        .unwrap_or_else(|| panic!("no point {scene} / {setting}"))
}

#[test]
fn the_sweep_measures_what_the_report_claims() {
    let p = sweep();
    // Colour bits: error against the exact pixel-centre values falls with
    // every two bits, and 16 bits are within the contract's rounding.
    let colour: Vec<f64> = [2, 4, 6, 8, 10, 12, 16]
        .iter()
        .map(|b| {
            find(&p, "gradient 240x160, rgb888", &format!("{b} colour bits"))
                .centre
                .mse_per_pixel
        })
        .collect();
    assert!(colour.windows(2).all(|w| w[1] < w[0]), "{colour:?}");
    assert!(colour[6] < 0.01 && colour[0] > 10.0, "{colour:?}");
    // Close surfaces: the 16-bit plane ties and shows the wrong surface;
    // fraction bits in the plane remove every such pixel, unless the DDA
    // drops them first.
    let art = |s: &str| find(&p, "crossing", s).artifacts.unwrap();
    assert!(art("Z16") > 100, "{}", art("Z16"));
    assert_eq!((art("Z24"), art("Z32, 14 Z bits")), (0, 0));
    assert!(art("Z32, 0 Z bits") > art("Z16"));
    // Dither trades per-pixel noise for less banding, in every format
    // with fewer than 8 bits a channel.
    for f in ["rgb565", "rgb444", "binary"] {
        let none = p
            .iter()
            .find(|q| q.scene.ends_with(f) && q.setting == "no dither")
            .unwrap();
        let b4 = p
            .iter()
            .find(|q| q.scene.ends_with(f) && q.setting == "4x4")
            .unwrap();
        assert!(b4.blur_rms < none.blur_rms / 2.0, "{f}");
    }
    // Wu lines: far closer to the ideal than Bresenham.
    let lines = |s| find(&p, "40 lines 128x96, rgb565", s).ideal.mse_per_pixel;
    assert!(lines("Wu") < lines("Bresenham") / 4.0);
    // Every family swept has a Pareto front, and a dominated point exists
    // where one setting is worse on both axes (Z32 with 0 Z bits).
    for f in [
        Family::ColourBits,
        Family::Depth,
        Family::Dither,
        Family::Lines,
    ] {
        assert!(p.iter().any(|q| q.family == f && q.pareto), "{f:?}");
    }
    assert!(!find(&p, "crossing", "Z32, 0 Z bits").pareto);
    // Shading: fast Phong is closer to exact Phong than Gouraud on the
    // specular sphere, and draws at most a few pixels far off it.
    let shade = |s| find(&p, "sphere, 12 slices", s);
    let (gouraud, fast) = (shade("Gouraud"), shade("fast Phong (ours)"));
    assert!(
        fast.centre.mse_per_pixel < gouraud.centre.mse_per_pixel / 2.0,
        "{} vs {}",
        fast.centre.mse_per_pixel,
        gouraud.centre.mse_per_pixel
    );
    assert!(fast.artifacts.unwrap() < gouraud.artifacts.unwrap());
    // Texturing at depth ratio 16: affine misses by texels, the quadratic
    // within its half texel, exact division closer still; the looser
    // tolerances lie between.
    let tex = |s| find(&p, "rectangle at depth ratio 16", s).texels.unwrap();
    assert!(tex("affine") > 2.0, "{}", tex("affine"));
    assert!(tex("quadratic within ½ texel") <= 0.5);
    assert!(tex("exact division") < 0.2, "{}", tex("exact division"));
    assert!(tex("quadratic within ½ texel") <= tex("quadratic within 2 texels"));
    assert!(tex("quadratic within 2 texels") <= tex("affine"));
    // Translucent panels drawn opaque are far off the blended picture;
    // blended, every pixel lies within the blend's rounding of it.
    let glass = |s| find(&p, "translucent panels", s);
    assert!(glass("opaque (α ignored)").artifacts.unwrap() > 5000);
    assert_eq!(glass("α-blended").artifacts, Some(0));
    assert!(glass("α-blended").centre.max_abs <= 2);
    for f in [Family::Shading, Family::Texturing, Family::Alpha] {
        assert!(p.iter().any(|q| q.family == f && q.pareto), "{f:?}");
    }
    // The CSV has a row per point.
    assert_eq!(tradeoff::csv(&p).lines().count(), p.len() + 1);
}

/// With fewer fraction bits the DDA restarts at the same tile-independent
/// points, so the output still does not depend on the tiling.
#[test]
fn reduced_precision_is_tile_independent() {
    let mut rng = Rng::new(0x7ade_0ff5);
    let cmds: Vec<Command> = (0..60).map(|_| random_command(&mut rng, 0)).collect();
    let mut cfg = config(100, 80, FormatKind::Rgb565);
    let draw = |cfg: &tilerast_sim::Config| {
        render_as::<
            Rgb565Format,
            Depth32,
            NoWid,
            Bayer4,
            tilerast::coverage::NoAa,
            Bits<5, 3>,
            SIM_GROUPS,
        >(cfg, &cmds, 0)
        .unwrap()
    };
    let whole = draw(&cfg);
    for tile in [(7, 5), (33, 17), (64, 1)] {
        cfg.tile = tile;
        let t = draw(&cfg);
        assert_eq!(t.raw, whole.raw, "tile {tile:?}");
        assert_eq!(t.depth, whole.depth, "tile {tile:?}");
    }
}
