//! The simulator's frames rendered `n` times, with its planes and dither as
//! values (`tilerast_sim::render`) or fixed by type (`render_as`, what the
//! simulator compiled before): run under `valgrind --tool=callgrind` with
//! `n` and `0` and take the difference, for instruction counts that do not
//! move with code layout the way criterion's times do (`cargo xtask bench`
//! writes them to `reports/bench.md`).
//!
//! `sim_cost <demo|ssd1306|teapot> <values|types> <n>`

use std::hint::black_box;
use tilerast::area::AreaAa;
use tilerast::prelude::*;
use tilerast_sim::render::{render_as, SIM_GROUPS};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let [_, scene, variant, n] = &args[..] else {
        eprintln!("usage: sim_cost <demo|ssd1306|teapot> <values|types> <n>");
        std::process::exit(2);
    };
    let n: usize = n.parse().expect("a count");
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../scenes")
        .join(format!("{scene}.toml"));
    let s = tilerast_sim::Scene::load(&path).expect("scene loads");
    let cfg = s.config;
    macro_rules! types {
        ($f:ty, $z:ty, $w:ty, $d:ty) => {
            for _ in 0..n {
                black_box(
                    render_as::<$f, $z, $w, $d, AreaAa, FullPrecision, SIM_GROUPS>(
                        &cfg,
                        black_box(&s.commands),
                        0,
                    )
                    .unwrap(),
                );
            }
        };
    }
    match (scene.as_str(), variant.as_str()) {
        (_, "values") => {
            for _ in 0..n {
                black_box(tilerast_sim::render(&cfg, black_box(&s.commands)).unwrap());
            }
        }
        ("demo", "types") => types!(Rgb444Format, Depth16, Wid8, Bayer8),
        ("ssd1306", "types") => types!(BinaryFormat, Depth16, NoWid, Bayer4),
        ("teapot", "types") => types!(Rgb565Format, Depth16, NoWid, NoDither),
        _ => {
            eprintln!("unknown scene or variant");
            std::process::exit(2);
        }
    }
}
