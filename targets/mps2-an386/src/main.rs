//! tilerast on the Arm MPS2 AN386 (Cortex-M4F, 25 MHz) under QEMU: renders
//! the exported scenes tile by tile into a CRC32 `DrawTarget`, runs the
//! measured workloads, and reports over semihosting.
//!
//! Build and run (after exporting the scenes, see `targets/README.md`):
//! `TILERAST_SCENES=/abs/path cargo run --release`.
#![no_std]
#![no_main]

use panic_semihosting as _;
use tilerast_fw::board::{cortex_m::CortexM, run, Board};

/// The demo and the teapot in the demo's exported 64x32 tiles.
const DEMO_TILE: (u16, u16) = (64, 32);

/// Bin entries (8 bytes each): enough for the teapot frame in one pass.
const BIN_ENTRIES: usize = 12288;

#[cortex_m_rt::entry]
fn main() -> ! {
    let board = Board {
        name: "mps2-an386",
        cpu: "cortex-m4f",
        instr_per_tick: "40",
    };
    run::<_, { 64 * 32 / 8 }, BIN_ENTRIES, 32>(&board, CortexM, DEMO_TILE)
}
