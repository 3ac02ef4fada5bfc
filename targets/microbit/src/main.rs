//! tilerast on the BBC micro:bit v1 (nRF51822: Cortex-M0 at 16 MHz, 16 KB of
//! RAM) under QEMU: the same report as the Cortex-M4 firmware. The demo's
//! exported 64x32 tile (40 bits per pixel: 10 KB) leaves too little of 16 KB
//! for the stack, so this board renders it in 32x32 tiles (5 KB) — the
//! output is the same, since tiling does not change pixels.
//!
//! Build and run (after exporting the scenes, see `targets/README.md`):
//! `TILERAST_SCENES=/abs/path cargo run --release`.
#![no_std]
#![no_main]

use panic_semihosting as _;
use tilerast_fw::board::{cortex_m::CortexM, run, Board};

const DEMO_TILE: (u16, u16) = (32, 32);

/// Bin entries: 720 x 8 bytes (5.6 KB), about what the 16 KB leave beside
/// the 5 KB tile and the stack (peak measured: see `reports/targets.md`;
/// the demo's mesh path under the plane contract takes 600 bytes more
/// stack than the command path did, and 800 entries left 60 bytes free).
/// The demo still bins in four passes.
const BIN_ENTRIES: usize = 720;

#[cortex_m_rt::entry]
fn main() -> ! {
    let board = Board {
        name: "microbit",
        cpu: "cortex-m0",
        instr_per_tick: "62.5",
    };
    run::<_, { 32 * 32 / 8 }, BIN_ENTRIES, 64>(&board, CortexM, DEMO_TILE)
}
