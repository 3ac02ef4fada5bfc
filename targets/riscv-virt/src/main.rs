//! tilerast on QEMU's RISC-V `virt` machine, RV32IMAC (the instruction set
//! of the ESP32-C6, and of the ESP32-C3 and the RP2350's Hazard3 cores but
//! for their extensions): the same report as the Cortex-M4 firmware — the
//! scenes, the workloads, the rotating teapot (fixed point: no FPU), the
//! volume and the culled city — over the UART, timed by `minstret`.
//!
//! Build and run (after exporting the scenes, see `targets/README.md`):
//! `TILERAST_SCENES=/abs/path cargo run --release`.
#![no_std]
#![no_main]

use core::fmt::Write;
use tilerast_fw::board::riscv::{Uart, Virt};
use tilerast_fw::board::{run, Board, Port};

/// The demo and the teapot in the demo's exported 64x32 tiles.
const DEMO_TILE: (u16, u16) = (64, 32);

/// Bin entries (8 bytes each): enough for the teapot frame in one pass.
const BIN_ENTRIES: usize = 12288;

#[riscv_rt::entry]
fn main() -> ! {
    let board = Board {
        name: "riscv-virt",
        cpu: "rv32imac",
        instr_per_tick: "1",
    };
    run::<_, { 64 * 32 / 8 }, BIN_ENTRIES, 32>(&board, Virt, DEMO_TILE)
}

/// A panic prints its message on the UART and ends QEMU with status 1.
#[panic_handler]
fn panic(info: &core::panic::PanicInfo) -> ! {
    let _ = writeln!(Uart, "panic: {info}");
    Virt::exit(false)
}
