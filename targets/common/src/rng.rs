//! A small deterministic PRNG (xorshift64*) for workloads, tests and
//! benchmarks: the same numbers on every target, no dependency, and `const`
//! so that workloads are generated at compile time into flash.

use tilerast::prelude::*;

/// xorshift64*.
///
/// ```
/// use tilerast_fw::rng::Rng;
/// let (mut a, mut b) = (Rng::new(7), Rng::new(7));
/// assert_eq!(a.next_u64(), b.next_u64());
/// assert!((10..20).contains(&a.range(10, 20)));
/// ```
pub struct Rng(u64);

impl Rng {
    /// A generator from a seed.
    pub const fn new(seed: u64) -> Self {
        Rng(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1)
    }
    /// Next 64 random bits.
    pub const fn next_u64(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }
    /// Uniform in `lo..hi` (`lo < hi`).
    pub const fn range(&mut self, lo: i64, hi: i64) -> i64 {
        lo + (self.next_u64() % (hi - lo) as u64) as i64
    }
    /// A random byte.
    pub const fn byte(&mut self) -> u8 {
        self.next_u64() as u8
    }
    /// A random colour.
    pub const fn rgb(&mut self) -> Rgb {
        Rgb::new(self.byte(), self.byte(), self.byte())
    }
    /// A rectangle with corner in `x`, `y` ranges and size below `max_w`, `max_h`.
    pub fn rect(&mut self, x: (i64, i64), y: (i64, i64), max_w: i64, max_h: i64) -> Rect {
        Rect::new(
            self.range(x.0, x.1) as i32,
            self.range(y.0, y.1) as i32,
            self.range(0, max_w) as u32,
            self.range(0, max_h) as u32,
        )
    }
    /// A vertex with sub-pixel (1/16 px) coordinates in the given ranges,
    /// random depth and colour.
    pub const fn vertex(&mut self, x: (i64, i64), y: (i64, i64)) -> Vertex {
        let vx = self.range(x.0, x.1);
        let vy = self.range(y.0, y.1);
        let z = self.range(0, 65536) as u16;
        Vertex::new(
            Coord::from_bits(vx as i32),
            Coord::from_bits(vy as i32),
            z,
            self.rgb(),
        )
    }
    /// Three such vertices.
    pub const fn triangle(&mut self, x: (i64, i64), y: (i64, i64)) -> [Vertex; 3] {
        [self.vertex(x, y), self.vertex(x, y), self.vertex(x, y)]
    }
}
