//! The RISC-V port (feature `riscv`) for QEMU's `virt` machine: `minstret`
//! (instructions retired; deterministic under `-icount shift=0`, where
//! QEMU derives it from the instruction count rather than the host clock),
//! output on the 16550 UART at `0x1000_0000`, exit through the SiFive test
//! device at `0x10_0000`, and a stack this port paints itself (`riscv-rt`
//! does not).

use super::Port;
use crate::Clock;

/// QEMU's `virt` machine (RV32).
pub struct Virt;

/// The 16550 UART's transmit register (and, at +5, its line status).
const UART: usize = 0x1000_0000;
/// The SiFive test device: a write ends the emulation.
const TEST: usize = 0x0010_0000;
/// The bytes `start` leaves unpainted below its own frame.
const PAINT_MARGIN: usize = 256;

/// Writes to the UART, byte by byte.
pub struct Uart;

impl core::fmt::Write for Uart {
    fn write_str(&mut self, s: &str) -> core::fmt::Result {
        for b in s.bytes() {
            // SAFETY: the UART's registers on `virt`: the line status
            // (bit 5, transmitter empty) read, then the transmit register
            // written, both volatile, byte wide.
            unsafe {
                while core::ptr::read_volatile((UART + 5) as *const u8) & 0x20 == 0 {}
                core::ptr::write_volatile(UART as *mut u8, b);
            }
        }
        Ok(())
    }
}

/// `minstret`, the retired-instruction counter (its low 32 bits: each lap
/// is shorter than 2^32 instructions).
pub struct Minstret {
    last: u32,
}

impl Clock for Minstret {
    fn lap(&mut self) -> u32 {
        let now = ::riscv::register::minstret::read() as u32;
        let d = now.wrapping_sub(self.last);
        self.last = now;
        d
    }
}

extern "C" {
    /// `riscv-rt`'s bottom of the stack.
    static __estack: u32;
    /// Its top.
    static _stack_start: u32;
}

impl Port for Virt {
    type Out = Uart;
    type Clock = Minstret;

    fn start(self) -> Option<(Self::Out, Self::Clock)> {
        let (lo, _) = Self::stack();
        let here = 0u32;
        let top = (core::ptr::addr_of!(here) as usize).saturating_sub(PAINT_MARGIN) & !3;
        let mut p = lo;
        while p < top {
            // SAFETY: below this frame by `PAINT_MARGIN` and above the
            // stack's bottom: stack no call has reached yet.
            unsafe { core::ptr::write_volatile(p as *mut u32, 0xCCCC_CCCC) };
            p += 4;
        }
        let clock = Minstret {
            last: ::riscv::register::minstret::read() as u32,
        };
        Some((Uart, clock))
    }

    fn stack() -> (usize, usize) {
        (
            core::ptr::addr_of!(__estack) as usize,
            core::ptr::addr_of!(_stack_start) as usize,
        )
    }

    fn spin_loop(n: u32) {
        // SAFETY: registers only; `n > 0`, so the loop ends after `n`
        // iterations of two instructions.
        unsafe {
            core::arch::asm!(
                "2:",
                "addi {n}, {n}, -1",
                "bnez {n}, 2b",
                n = inout(reg) n => _,
                options(nomem, nostack),
            );
        }
    }

    fn exit(ok: bool) -> ! {
        // 0x5555: pass; (code << 16) | 0x3333: fail with `code`.
        let v: u32 = if ok { 0x5555 } else { (1 << 16) | 0x3333 };
        // SAFETY: the test device's register on `virt`; the write ends QEMU.
        unsafe { core::ptr::write_volatile(TEST as *mut u32, v) };
        #[allow(clippy::empty_loop)]
        loop {}
    }
}
