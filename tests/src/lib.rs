//! Helpers shared by the integration tests: paths, golden images, a small
//! deterministic PRNG, and configurations.

use std::path::PathBuf;
use tilerast::prelude::*;
use tilerast_sim::{Config, FormatKind, Image};

/// The repository root.
pub fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// A scene file under `scenes/`.
pub fn scene(name: &str) -> PathBuf {
    repo().join("scenes").join(name)
}

/// Compares `img` pixel-exactly with `tests/golden/<name>.png`. With
/// `TILERAST_BLESS=1` the golden is (re)written instead.
pub fn assert_golden(name: &str, img: &Image) {
    let path = repo().join("tests/golden").join(format!("{name}.png"));
    if std::env::var_os("TILERAST_BLESS").is_some() {
        img.save_png(&path).unwrap();
        return;
    }
    let golden = Image::load_png(&path)
        .unwrap_or_else(|e| panic!("{e} (run with TILERAST_BLESS=1 to create it)"));
    let d = tilerast_sim::metrics::compare(img, &golden).unwrap();
    if d.differing != 0 {
        let out = std::env::temp_dir().join(format!("{name}.actual.png"));
        img.save_png(&out).unwrap();
        panic!(
            "{name}: {} pixels differ from the golden (max {}); actual written to {}",
            d.differing,
            d.max_abs,
            out.display()
        );
    }
}

/// xorshift64*: deterministic and dependency-free.
pub struct Rng(u64);

impl Rng {
    /// A generator from a seed.
    pub fn new(seed: u64) -> Self {
        Rng(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1)
    }
    /// Next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }
    /// Uniform in `lo..hi`.
    pub fn range(&mut self, lo: i64, hi: i64) -> i64 {
        lo + (self.next_u64() % (hi - lo) as u64) as i64
    }
    /// A random byte.
    pub fn byte(&mut self) -> u8 {
        self.next_u64() as u8
    }
}

/// A configuration with everything off but the format.
pub fn config(w: u16, h: u16, format: FormatKind) -> Config {
    Config {
        width: w,
        height: h,
        format,
        tile: (w, h),
        dither: 0,
        depth: false,
        wid: false,
        clear: Clear::default(),
    }
}

/// A vertex from sub-pixel units (1/16 px).
pub fn vsub(x: i64, y: i64, z: u16, c: [u8; 3]) -> Vertex {
    Vertex::new(
        Coord::from_bits(x as i32),
        Coord::from_bits(y as i32),
        z,
        Rgb::new(c[0], c[1], c[2]),
    )
}

/// A triangle command in window `wid`.
pub fn tri(v: [Vertex; 3], wid: u8) -> Command {
    Command::Triangle {
        v,
        state: State {
            wid,
            ..State::default()
        },
    }
}
