//! The Cortex-M port (feature `cortex-m`): SysTick at the core clock,
//! output over semihosting, exit through semihosting's `SYS_EXIT`, the stack
//! `cortex-m-rt` paints at reset (its feature `paint-stack`). One port for
//! ARMv6-M, ARMv7E-M and ARMv8-M Mainline: the code differs only in what
//! the compiler emits.

use super::Port;
use crate::Clock;
#[cfg(feature = "profile")]
use core::fmt::Write;
use cortex_m::peripheral::{syst::SystClkSource, SYST};
use cortex_m_semihosting::{debug, hio};

/// A Cortex-M board under QEMU with semihosting enabled.
pub struct CortexM;

/// SysTick, counting down from 2^24 - 1 at the core clock.
pub struct SysTickClock {
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

impl Port for CortexM {
    type Out = hio::HostStream;
    type Clock = SysTickClock;

    fn start(self) -> Option<(Self::Out, Self::Clock)> {
        let out = hio::hstdout().ok()?;
        let mut cp = cortex_m::Peripherals::take()?;
        cp.SYST.set_clock_source(SystClkSource::Core);
        cp.SYST.set_reload(0x00FF_FFFF);
        cp.SYST.clear_current();
        cp.SYST.enable_counter();
        let clock = SysTickClock {
            last: SYST::get_current(),
        };
        Some((out, clock))
    }

    fn stack() -> (usize, usize) {
        extern "C" {
            static _stack_end: u32;
            static _stack_start: u32;
        }
        // `cortex-m-rt`'s symbols: the bottom and the top of the stack.
        (
            core::ptr::addr_of!(_stack_end) as usize,
            core::ptr::addr_of!(_stack_start) as usize,
        )
    }

    fn spin_loop(n: u32) {
        // SAFETY: registers only; `n > 0`, so the loop ends after `n`
        // iterations of two instructions.
        unsafe {
            core::arch::asm!(
                "2:",
                "subs {n}, #1",
                "bne 2b",
                n = inout(reg) n => _,
                options(nomem, nostack),
            );
        }
    }

    fn exit(ok: bool) -> ! {
        debug::exit(if ok {
            debug::EXIT_SUCCESS
        } else {
            debug::EXIT_FAILURE
        });
        #[allow(clippy::empty_loop)]
        loop {}
    }
}

/// The report's writer: after each line it calls [`tilerast_report_line`],
/// the mark `qemu-prof` splits its instruction profile at, so each line's
/// work (what was measured, and printing the line before) is one segment
/// (`tests/qemu-prof/segprof.c`, `reports/profile.md`). One call a line,
/// outside every timed section. Feature `profile` only.
#[cfg(feature = "profile")]
pub(super) struct Lines<W>(pub(super) W);

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
