//! Golden images: the demo scenes render pixel-exactly as committed.

use tilerast_sim::render::{render_textured, FormatKind, TexKind};
use tilerast_sim::texscene::{ramp, ramp_texels, tilted_quad};
use tilerast_sim::Scene;
use tilerast_tests::{assert_golden, config, scene};

fn check(name: &str) {
    let s = Scene::load(scene(&format!("{name}.toml"))).unwrap();
    let r = s.render().unwrap();
    assert_golden(name, &r.image);
}

#[test]
fn demo_matches_golden() {
    check("demo");
}

#[test]
fn ssd1306_matches_golden() {
    check("ssd1306");
}

#[test]
fn lines_match_golden() {
    check("lines");
}

#[test]
fn edges_match_golden() {
    check("edges");
}

/// Area sampling through the α-channel (seed 001 §IV.5).
#[test]
fn area_matches_golden() {
    check("area");
}

#[test]
fn ruf_matches_golden() {
    check("ruf");
}

#[test]
fn glass_matches_golden() {
    check("glass");
}

/// A frame of the occlusion-culling city (seed 004), culled in one pass;
/// the other modes draw the same pixels (`occlusion.rs`).
#[test]
fn city_matches_golden() {
    check("city");
}

/// Textured meshes (spherical projection and OBJ `vt` + `map_Kd`), fast
/// Phong and a translucent panel: seed 001 §IV together.
#[test]
fn textured_matches_golden() {
    check("textured");
}

/// The ramp rectangle at depth ratio 4 in each perspective mode: what
/// each mode's texel addressing draws, pixel for pixel.
#[test]
fn perspective_modes_match_goldens() {
    let mut cfg = config(96, 64, FormatKind::Rgb888);
    cfg.depth = true;
    cfg.tile = (32, 32);
    let texels = ramp_texels();
    let cmds = tilted_quad(96, 64, 4.0);
    for kind in TexKind::TEXTURED {
        let r = render_textured(&cfg, &cmds, &[ramp(&texels)], kind, 0).unwrap();
        assert_golden(&format!("tilted_{}", kind.name()), &r.image);
    }
}
