//! Fragment tests (seed 001, §II.4–5): the window-ID test, then the Z test.
//!
//! A fragment is written only where the tile's window-ID plane holds the
//! command's ID, and only where its Z is **less than** the stored Z, which it
//! then replaces (read-modify-write, as REjr's Z channel). Either plane can be
//! absent: `NoDepth` and `NoWid` store `()`, and their tests are the constant
//! `true`, so the inner loop carries no trace of them.

use crate::format::{Cell, ColorPlane, Plane};

/// Depth-plane storage.
pub trait DepthPlane {
    /// A new plane (contents are set by the tile's clear).
    fn new() -> Self;
    /// Sets pixel `i` to `z`.
    fn put(&mut self, i: usize, z: u16);
    /// Reads pixel `i` (65535 when there is no plane).
    fn read(&self, i: usize) -> u16;
    /// The Z test: passes and stores when `z` is less than the stored value.
    fn test_and_set(&mut self, i: usize, z: u16) -> bool;
    /// The Z test without the write (partial-coverage fragments).
    fn test(&self, i: usize, z: u16) -> bool;
}

/// Window-ID plane storage.
pub trait WidPlane {
    /// A new plane.
    fn new() -> Self;
    /// Sets pixel `i` to `id`.
    fn put(&mut self, i: usize, id: u8);
    /// Reads pixel `i` (0 when there is no plane).
    fn read(&self, i: usize) -> u8;
    /// The window-ID test.
    fn pass(&self, i: usize, id: u8) -> bool;
}

/// Whether a tile has a depth plane, chosen by type.
pub trait DepthMode: 'static {
    /// Storage for `8 N` pixels.
    type Plane<const N: usize>: DepthPlane;
    /// Bits per pixel of the plane.
    const BITS: u32;
}

/// Whether a tile has a window-ID plane, chosen by type.
pub trait WidMode: 'static {
    /// Storage for `8 N` pixels.
    type Plane<const N: usize>: WidPlane;
    /// Bits per pixel of the plane.
    const BITS: u32;
}

/// 16-bit Z plane, less-than test.
#[derive(Debug, Clone, Copy, Default)]
pub struct Depth16;
/// No depth plane: every fragment passes.
#[derive(Debug, Clone, Copy, Default)]
pub struct NoDepth;
/// 8-bit window-ID plane (256 windows).
#[derive(Debug, Clone, Copy, Default)]
pub struct Wid8;
/// No window-ID plane: every fragment passes.
#[derive(Debug, Clone, Copy, Default)]
pub struct NoWid;

impl DepthMode for Depth16 {
    type Plane<const N: usize> = Plane<u16, N>;
    const BITS: u32 = 16;
}
impl DepthMode for NoDepth {
    type Plane<const N: usize> = ();
    const BITS: u32 = 0;
}
impl WidMode for Wid8 {
    type Plane<const N: usize> = Plane<u8, N>;
    const BITS: u32 = 8;
}
impl WidMode for NoWid {
    type Plane<const N: usize> = ();
    const BITS: u32 = 0;
}

impl<const N: usize> DepthPlane for Plane<u16, N> {
    fn new() -> Self {
        <Self as ColorPlane>::new()
    }
    #[inline(always)]
    fn put(&mut self, i: usize, z: u16) {
        self.0.as_flattened_mut()[i] = z;
    }
    #[inline(always)]
    fn read(&self, i: usize) -> u16 {
        self.0.as_flattened()[i]
    }
    #[inline(always)]
    fn test(&self, i: usize, z: u16) -> bool {
        z < self.0.as_flattened()[i]
    }
    #[inline(always)]
    fn test_and_set(&mut self, i: usize, z: u16) -> bool {
        let cell = &mut self.0.as_flattened_mut()[i];
        if z < *cell {
            *cell = z;
            true
        } else {
            false
        }
    }
}

impl DepthPlane for () {
    fn new() -> Self {}
    #[inline(always)]
    fn put(&mut self, _: usize, _: u16) {}
    #[inline(always)]
    fn read(&self, _: usize) -> u16 {
        u16::MAX
    }
    #[inline(always)]
    fn test_and_set(&mut self, _: usize, _: u16) -> bool {
        true
    }
    #[inline(always)]
    fn test(&self, _: usize, _: u16) -> bool {
        true
    }
}

impl<const N: usize> WidPlane for Plane<u8, N> {
    fn new() -> Self {
        <Self as ColorPlane>::new()
    }
    #[inline(always)]
    fn put(&mut self, i: usize, id: u8) {
        self.0.as_flattened_mut()[i] = id;
    }
    #[inline(always)]
    fn read(&self, i: usize) -> u8 {
        self.0.as_flattened()[i].to_u32() as u8
    }
    #[inline(always)]
    fn pass(&self, i: usize, id: u8) -> bool {
        self.0.as_flattened()[i] == id
    }
}

impl WidPlane for () {
    fn new() -> Self {}
    #[inline(always)]
    fn put(&mut self, _: usize, _: u8) {}
    #[inline(always)]
    fn read(&self, _: usize) -> u8 {
        0
    }
    #[inline(always)]
    fn pass(&self, _: usize, _: u8) -> bool {
        true
    }
}
