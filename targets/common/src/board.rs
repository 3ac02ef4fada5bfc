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
        let now = SYST::get_current();
        let d = self.last.wrapping_sub(now) & 0x00FF_FFFF;
        self.last = now;
        d
    }
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
    let mut out = match hio::hstdout() {
        Ok(o) => o,
        Err(()) => {
            debug::exit(debug::EXIT_FAILURE);
            loop {}
        }
    };
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
        #[cfg(feature = "ssd1306")]
        crate::report::report_scene::<crate::report::Ssd1306, NS, BC, BT>(
            SSD1306, ssd_tile, &mut out, &mut clock,
        )?;
        #[cfg(feature = "bench")]
        crate::report::report_benches(&mut out, &mut clock)?;
        #[cfg(feature = "anim")]
        crate::report::report_anim(&mut out, &mut clock)?;
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
