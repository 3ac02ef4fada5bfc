//! tilerast on the Arm MPS2+ AN505 (Cortex-M33 with FPU and DSP
//! extension, ARMv8-M Mainline, 20 MHz) under QEMU: the same report as the
//! Cortex-M4 firmware — the scenes, the workloads, the rotating teapot,
//! the volume and the culled city — from the chip class of the RP2350,
//! nRF5340 and STM32U5. It runs in the Secure state the core resets in.
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
        name: "mps2-an505",
        cpu: "cortex-m33",
        instr_per_tick: "50",
    };
    run::<_, { 64 * 32 / 8 }, BIN_ENTRIES, 32>(&board, CortexM, DEMO_TILE)
}
