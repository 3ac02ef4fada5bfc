//! Golden images: the demo scenes render pixel-exactly as committed.

use tilerast_sim::{render, Scene};
use tilerast_tests::{assert_golden, scene};

fn check(name: &str) {
    let s = Scene::load(scene(&format!("{name}.toml"))).unwrap();
    let r = render(&s.config, &s.commands).unwrap();
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

#[test]
fn ruf_matches_golden() {
    check("ruf");
}

#[test]
fn glass_matches_golden() {
    check("glass");
}
