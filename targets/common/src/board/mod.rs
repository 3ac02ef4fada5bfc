//! The board runtime (feature `board`): what every firmware's `main` calls,
//! over a [`Port`] — the few things that differ between instruction sets:
//! an instruction clock, a line of output, a stack to measure, a way out.
//!
//! - [`cortex_m`] (feature `cortex-m`): SysTick, semihosting, `cortex-m-rt`'s
//!   painted stack. ARMv6-M, ARMv7E-M and ARMv8-M Mainline boards.
//! - [`riscv`] (feature `riscv`): `minstret`, the 16550 UART, the test
//!   device's exit. RV32 boards (QEMU `virt`).
//!
//! Instructions are counted as the project's design notes prescribe: QEMU
//! runs with `-icount shift=0` (one instruction per virtual nanosecond). On
//! Arm, SysTick counts the core clock, so one tick is a fixed number of
//! instructions per board (40 on `mps2-an386` at 25 MHz, 50 on `mps2-an505`
//! at 20 MHz, 62.5 on `microbit` at 16 MHz); each measured section is
//! shorter than SysTick's 2^24-tick period and laps are summed. On RISC-V,
//! `minstret` counts retired instructions: one tick is one instruction.
//! Every run starts with a `calibrate` line, a loop of known length timed
//! by the same clock, which the firmware test checks against the stated
//! instructions per tick; counts are exact to a tick and repeat run after
//! run.

use crate::Clock;
use core::fmt::Write;

#[cfg(feature = "cortex-m")]
pub mod cortex_m;
#[cfg(feature = "riscv")]
pub mod riscv;

/// What a board tells the report.
pub struct Board {
    /// Board name.
    pub name: &'static str,
    /// CPU core.
    pub cpu: &'static str,
    /// Instructions per clock tick under `-icount shift=0`.
    pub instr_per_tick: &'static str,
}

/// What differs between instruction sets: implemented by [`cortex_m::CortexM`]
/// and [`riscv::Virt`].
pub trait Port {
    /// Where the report goes.
    type Out: Write;
    /// The instruction clock.
    type Clock: Clock;
    /// Opens the output and starts the clock; `None` if either cannot be.
    fn start(self) -> Option<(Self::Out, Self::Clock)>;
    /// The stack's lowest address and the address past its top, filled with
    /// `0xCCCCCCCC` before `main` (or by [`Port::start`]).
    fn stack() -> (usize, usize);
    /// Runs `n` iterations (`n > 0`) of a two-instruction loop: exactly
    /// `2 n` instructions, for the clock's calibration.
    fn spin_loop(n: u32);
    /// Ends the run: QEMU exits with status 0 when `ok`, else 1.
    fn exit(ok: bool) -> !;
}

/// Bytes of stack ever used: the stack was filled with `0xCCCCCCCC` at
/// reset; the lowest scrubbed word marks the peak.
fn stack_used<P: Port>() -> usize {
    let (lo, hi) = P::stack();
    let mut p = lo;
    // SAFETY: `P::stack` delimits RAM owned by the stack; reading it word
    // by word (volatile, aligned) has no side effect.
    while p < hi && unsafe { core::ptr::read_volatile(p as *const u32) } == 0xCCCC_CCCC {
        p += 4;
    }
    hi - p
}

/// Iterations of the calibration loop: 2 M instructions.
const CALIBRATION: u32 = 1_000_000;

/// Prints `calibrate loop_instructions N ticks T`: a loop of exactly `N`
/// instructions timed by the clock the report uses.
fn calibrate<P: Port>(out: &mut impl Write, clock: &mut impl Clock) -> core::fmt::Result {
    clock.lap();
    P::spin_loop(CALIBRATION);
    let t = clock.lap();
    writeln!(
        out,
        "calibrate loop_instructions {} ticks {t}",
        2 * CALIBRATION
    )
}

#[cfg(feature = "demo")]
static DEMO: &[u8] = include_bytes!(concat!(env!("TILERAST_SCENES"), "/demo.bin"));
#[cfg(feature = "teapot")]
static TEAPOT: &[u8] = include_bytes!(concat!(env!("TILERAST_SCENES"), "/teapot.bin"));
#[cfg(feature = "teapot")]
static TEAPOT_CULL: &[u8] = include_bytes!(concat!(env!("TILERAST_SCENES"), "/teapot_cull.bin"));
#[cfg(feature = "spin_teapot")]
static TEAPOT_MESH: &[u8] = include_bytes!(concat!(env!("TILERAST_SCENES"), "/teapot.mesh"));
#[cfg(feature = "ssd1306")]
static SSD1306: &[u8] = include_bytes!(concat!(env!("TILERAST_SCENES"), "/ssd1306.bin"));

/// The SSD1306 scene as a 1-bit display's firmware renders it, on every
/// board: in 128x8 tiles, the panel's own pages (128 bytes of pixels, 2 KB
/// of Z), binned into 224 entries (1.75 KB) in as many passes as it takes
/// (three) — what fits the 6 KB of RAM a minimal SSD1306 build has, stack
/// included, on the Cortex-M0 too (its frames take more stack than the M4's).
#[cfg(feature = "ssd1306")]
const SSD_TILE: (u16, u16) = (128, 8);
/// Its tile capacity, in groups of 8 pixels.
#[cfg(feature = "ssd1306")]
const SSD_GROUPS: usize = 128 * 8 / 8;
/// Its bin entries (8 bytes each).
#[cfg(feature = "ssd1306")]
const SSD_BINS: usize = 224;
/// Its tiles per binning pass: the whole 128x64 screen.
#[cfg(feature = "ssd1306")]
const SSD_BIN_TILES: usize = 8;

/// Runs the report on `port` and exits QEMU. `ND` is the tile capacity (in
/// groups of 8 pixels) for the demo and the teapot, rendered in tiles of
/// `demo_tile`; `BC`/`BT` their bins' entries and tiles per pass.
pub fn run<P: Port, const ND: usize, const BC: usize, const BT: usize>(
    b: &Board,
    port: P,
    demo_tile: (u16, u16),
) -> ! {
    let _ = demo_tile;
    let Some((out, mut clock)) = port.start() else {
        P::exit(false)
    };
    #[cfg(feature = "profile")]
    let out = cortex_m::Lines(out);
    let mut out = out;
    let mut body = || -> core::fmt::Result {
        writeln!(
            out,
            "board {} cpu {} instr_per_tick {}",
            b.name, b.cpu, b.instr_per_tick
        )?;
        calibrate::<P>(&mut out, &mut clock)?;
        #[cfg(feature = "demo")]
        crate::report::report_scene::<crate::report::Demo, ND, BC, BT>(
            DEMO, demo_tile, &mut out, &mut clock,
        )?;
        #[cfg(feature = "demo")]
        crate::report::report_phases::<crate::report::Demo, ND, BC, BT>(
            DEMO, demo_tile, &mut out, &mut clock,
        )?;
        #[cfg(feature = "teapot")]
        crate::report::report_scene::<crate::report::Teapot, ND, BC, BT>(
            TEAPOT, demo_tile, &mut out, &mut clock,
        )?;
        #[cfg(feature = "teapot")]
        crate::report::report_phases::<crate::report::Teapot, ND, BC, BT>(
            TEAPOT, demo_tile, &mut out, &mut clock,
        )?;
        #[cfg(feature = "teapot")]
        crate::report::report_scene::<crate::report::TeapotCull, ND, BC, BT>(
            TEAPOT_CULL,
            demo_tile,
            &mut out,
            &mut clock,
        )?;
        #[cfg(feature = "teapot")]
        crate::report::report_phases::<crate::report::TeapotCull, ND, BC, BT>(
            TEAPOT_CULL,
            demo_tile,
            &mut out,
            &mut clock,
        )?;
        #[cfg(feature = "ssd1306")]
        crate::report::report_scene::<crate::report::Ssd1306, SSD_GROUPS, SSD_BINS, SSD_BIN_TILES>(
            SSD1306, SSD_TILE, &mut out, &mut clock,
        )?;
        #[cfg(feature = "ssd_trade")]
        report_ssd_trade(&mut out, &mut clock)?;
        #[cfg(feature = "bench")]
        crate::report::report_benches(&mut out, &mut clock)?;
        #[cfg(feature = "bench_extra")]
        crate::report::report_extra_benches(&mut out, &mut clock)?;
        #[cfg(feature = "anim")]
        crate::report::report_anim(&mut out, &mut clock)?;
        #[cfg(feature = "volume")]
        crate::report::report_volume(&mut out, &mut clock)?;
        #[cfg(feature = "cull")]
        crate::report::report_city(&mut out, &mut clock)?;
        #[cfg(feature = "spin_teapot")]
        report_spin_teapot::<ND, BC, BT>(demo_tile, &mut out, &mut clock)?;
        #[cfg(feature = "spin_cube")]
        report_spin_cube::<ND, BT>(demo_tile, &mut out, &mut clock)?;
        writeln!(out, "stack_used {}", stack_used::<P>())?;
        writeln!(out, "done")
    };
    let ok = body().is_ok();
    P::exit(ok)
}

/// The SSD1306 scene in each tile height (one page, two, the whole
/// screen) and bin capacity: what RAM buys in instructions (feature
/// `ssd_trade`: a copy of the 1-bit draw code per tile size, so on the
/// 4 MB boards only).
#[cfg(feature = "ssd_trade")]
fn report_ssd_trade(out: &mut impl Write, clock: &mut impl Clock) -> core::fmt::Result {
    use crate::report::report_ssd_trade as point;
    point::<{ 128 * 8 / 8 }, 224, 8>(SSD1306, (128, 8), out, clock)?;
    point::<{ 128 * 8 / 8 }, 512, 8>(SSD1306, (128, 8), out, clock)?;
    point::<{ 128 * 8 / 8 }, 2048, 8>(SSD1306, (128, 8), out, clock)?;
    point::<{ 128 * 16 / 8 }, 256, 4>(SSD1306, (128, 16), out, clock)?;
    point::<{ 128 * 16 / 8 }, 2048, 4>(SSD1306, (128, 16), out, clock)?;
    point::<{ 128 * 64 / 8 }, 256, 1>(SSD1306, (128, 64), out, clock)?;
    point::<{ 128 * 64 / 8 }, 2048, 1>(SSD1306, (128, 64), out, clock)
}

/// Frames of each rotating-mesh run.
#[cfg(any(feature = "spin_teapot", feature = "spin_cube"))]
pub const SPIN_FRAMES: u32 = 8;

/// The teapot's frames in `f32` where the chip has an FPU.
#[cfg(all(
    feature = "spin_teapot",
    not(any(
        target_abi = "eabi",
        all(target_arch = "riscv32", not(target_feature = "f"))
    ))
))]
mod backend {
    pub(super) type Frames = f32;
    pub(super) type Other = tilerast::geometry::Fx;
}

/// In fixed point where it has none (ARMv6-M's `eabi`, RISC-V without `f`).
#[cfg(all(
    feature = "spin_teapot",
    any(
        target_abi = "eabi",
        all(target_arch = "riscv32", not(target_feature = "f"))
    )
))]
mod backend {
    pub(super) type Frames = tilerast::geometry::Fx;
    pub(super) type Other = f32;
}

/// The teapot turning: 8 frames in `f32` (the FPU's back end), and the
/// vertex stage alone in fixed point for the comparison (a second raster
/// pipeline would be a second copy in flash). Built for a part without an
/// FPU (`thumbv6m`: the MPS2 board running Cortex-M0-class code, as an
/// RP2040 would with the teapot in its flash; `riscv32imac`, as an
/// ESP32-C3 or C6), the other way round.
#[cfg(feature = "spin_teapot")]
#[inline(never)]
fn report_spin_teapot<const N: usize, const BC: usize, const BT: usize>(
    tile: (u16, u16),
    out: &mut impl Write,
    clock: &mut impl Clock,
) -> core::fmt::Result {
    use backend::{Frames, Other};
    use tilerast::geometry::{Mesh, VertexSlot};
    let mesh = match Mesh::parse(TEAPOT_MESH) {
        Ok(m) => m,
        Err(e) => return writeln!(out, "spin teapot error {e}"),
    };
    let mut slots = [VertexSlot::EMPTY; 3648];
    crate::report::report_spin::<Frames, N, BC, BT>(
        "teapot",
        &mesh,
        &mut slots,
        tile,
        SPIN_FRAMES,
        out,
        clock,
    )?;
    crate::report::report_geom::<Other>("teapot", &mesh, &mut slots, 4, out, clock)
}

/// The cube turning: 8 frames in fixed point (the M0's back end), and the
/// vertex stage alone in `f32` (software floats) for the comparison.
#[cfg(feature = "spin_cube")]
#[inline(never)]
fn report_spin_cube<const N: usize, const BT: usize>(
    tile: (u16, u16),
    out: &mut impl Write,
    clock: &mut impl Clock,
) -> core::fmt::Result {
    use tilerast::geometry::{Fx, VertexSlot};
    let mut buf = [0u8; crate::spin::CUBE_BYTES];
    let mesh = match crate::spin::cube(&mut buf) {
        Ok(m) => m,
        Err(e) => return writeln!(out, "spin cube error {e}"),
    };
    let mut slots = [VertexSlot::EMPTY; 24];
    // 12 triangles (a few more where clipped) over a few tiles each: 256
    // bin entries (2 KB) are plenty.
    crate::report::report_spin::<Fx, N, 256, BT>(
        "cube",
        &mesh,
        &mut slots,
        tile,
        SPIN_FRAMES,
        out,
        clock,
    )?;
    crate::report::report_geom::<f32>("cube", &mesh, &mut slots, 4, out, clock)
}
