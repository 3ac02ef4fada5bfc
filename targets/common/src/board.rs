//! The board runtime (feature `board`): what every firmware's `main` calls.
//!
//! Instructions are counted as the project's design notes prescribe: QEMU runs
//! with `-icount shift=0` (one instruction per virtual nanosecond) and
//! SysTick counts the core clock, so one tick is a fixed number of
//! instructions per board (40 on `mps2-an386`, 62.5 on `microbit`). Each
//! measured section is shorter than SysTick's 2^24-tick period and laps are
//! summed, so counts are exact to a tick and repeat run after run.

use crate::Clock;
use core::fmt::Write;
use cortex_m::peripheral::{syst::SystClkSource, SYST};
use cortex_m_semihosting::{debug, hio};

/// What a board tells the report.
pub struct Board {
    /// Board name.
    pub name: &'static str,
    /// CPU core.
    pub cpu: &'static str,
    /// Instructions per SysTick tick under `-icount shift=0`.
    pub instr_per_tick: &'static str,
}

/// SysTick, counting down from 2^24 - 1 at the core clock.
struct SysTickClock {
    last: u32,
}

impl Clock for SysTickClock {
    fn lap(&mut self) -> u32 {
        #[cfg(feature = "profile")]
        tilerast_lap();
        let now = SYST::get_current();
        let d = self.last.wrapping_sub(now) & 0x00FF_FFFF;
        self.last = now;
        d
    }
}

/// The report's writer: after each line it calls [`tilerast_report_line`],
/// the mark `qemu-prof` splits its instruction profile at, so each line's
/// work (what was measured, and printing the line before) is one segment
/// (`tests/qemu-prof/segprof.c`, `reports/profile.md`). One call a line,
/// outside every timed section. Feature `profile` only.
#[cfg(feature = "profile")]
struct Lines<W>(W);

#[cfg(feature = "profile")]
impl<W: Write> Write for Lines<W> {
    fn write_str(&mut self, s: &str) -> core::fmt::Result {
        self.0.write_str(s)?;
        for _ in s.bytes().filter(|&b| b == b'\n') {
            tilerast_report_line();
        }
        Ok(())
    }
}

/// Does nothing, out of line under a name the profiler finds in the ELF:
/// executing it marks the end of a report line.
#[cfg(feature = "profile")]
#[no_mangle]
#[inline(never)]
pub extern "C" fn tilerast_report_line() {
    // Not removable: a call to an empty function could be dropped.
    cortex_m::asm::nop();
}

/// The same for each reading of SysTick ([`Clock::lap`]): the profiler
/// splits there too, so it can tell the timed instructions (between a
/// line's first and last lap) from the rest. Four instructions a lap; two
/// `nop`s, so that the linker cannot fold it into the line's mark.
#[cfg(feature = "profile")]
#[no_mangle]
#[inline(never)]
pub extern "C" fn tilerast_lap() {
    cortex_m::asm::nop();
    cortex_m::asm::nop();
}

/// Bytes of stack ever used: `cortex-m-rt`'s `paint-stack` fills the stack
/// with `0xCCCCCCCC` at reset; the lowest scrubbed word marks the peak.
fn stack_used() -> usize {
    extern "C" {
        static _stack_end: u32;
        static _stack_start: u32;
    }
    // SAFETY: the linker symbols delimit RAM owned by the stack; reading it
    // word by word (volatile, aligned) has no side effect.
    unsafe {
        let lo = core::ptr::addr_of!(_stack_end) as usize;
        let hi = core::ptr::addr_of!(_stack_start) as usize;
        let mut p = lo;
        while p < hi && core::ptr::read_volatile(p as *const u32) == 0xCCCC_CCCC {
            p += 4;
        }
        hi - p
    }
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

/// Runs the report and exits QEMU. `ND`/`NS` are the tile capacities (in
/// groups of 8 pixels) for the demo and SSD1306 scenes, rendered in tiles of
/// `demo_tile` and `ssd_tile` (the teapot in the demo's); `BC`/`BT` the bins'
/// entries and tiles per pass.
pub fn run<const ND: usize, const NS: usize, const BC: usize, const BT: usize>(
    b: &Board,
    demo_tile: (u16, u16),
    ssd_tile: (u16, u16),
) -> ! {
    let _ = (demo_tile, ssd_tile);
    let out = match hio::hstdout() {
        Ok(o) => o,
        Err(()) => {
            debug::exit(debug::EXIT_FAILURE);
            loop {}
        }
    };
    #[cfg(feature = "profile")]
    let out = Lines(out);
    let mut out = out;
    let Some(mut cp) = cortex_m::Peripherals::take() else {
        debug::exit(debug::EXIT_FAILURE);
        loop {}
    };
    cp.SYST.set_clock_source(SystClkSource::Core);
    cp.SYST.set_reload(0x00FF_FFFF);
    cp.SYST.clear_current();
    cp.SYST.enable_counter();
    let mut clock = SysTickClock {
        last: SYST::get_current(),
    };
    let mut body = || -> core::fmt::Result {
        writeln!(
            out,
            "board {} cpu {} instr_per_tick {}",
            b.name, b.cpu, b.instr_per_tick
        )?;
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
        crate::report::report_scene::<crate::report::Ssd1306, NS, BC, BT>(
            SSD1306, ssd_tile, &mut out, &mut clock,
        )?;
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
        writeln!(out, "stack_used {}", stack_used())?;
        writeln!(out, "done")
    };
    let ok = body().is_ok();
    debug::exit(if ok {
        debug::EXIT_SUCCESS
    } else {
        debug::EXIT_FAILURE
    });
    loop {}
}

/// Frames of each rotating-mesh run.
#[cfg(any(feature = "spin_teapot", feature = "spin_cube"))]
pub const SPIN_FRAMES: u32 = 8;

/// The teapot turning: 8 frames in `f32` (the FPU's back end), and the
/// vertex stage alone in fixed point for the comparison (a second raster
/// pipeline would be a second copy in flash). Built for a part without an
/// FPU (`thumbv6m`: the MPS2 board running Cortex-M0-class code, as an
/// RP2040 would with the teapot in its flash), the other way round.
#[cfg(feature = "spin_teapot")]
#[inline(never)]
fn report_spin_teapot<const N: usize, const BC: usize, const BT: usize>(
    tile: (u16, u16),
    out: &mut impl Write,
    clock: &mut impl Clock,
) -> core::fmt::Result {
    use tilerast::geometry::{Fx, Mesh, VertexSlot};
    #[cfg(not(target_abi = "eabi"))]
    type Frames = f32;
    #[cfg(not(target_abi = "eabi"))]
    type Other = Fx;
    #[cfg(target_abi = "eabi")]
    type Frames = Fx;
    #[cfg(target_abi = "eabi")]
    type Other = f32;
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
