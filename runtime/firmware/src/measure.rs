//! What the timing and RAM figures are measured with: SysTick counts converted to
//! instructions (under `qemu-system-arm -icount shift=0` every instruction takes 1 ns of
//! virtual time, so counts are deterministic instruction counts), and a painted stack.

use crate::time_driver::counts;
use core::cell::Cell;
use prf_runtime::executor::{Measured, Plant, Setpoint};

/// Instructions per SysTick count, measured on a loop of exactly 2 instructions per
/// iteration (40 on mps2-an500 under `-icount shift=0`: 1 ns per instruction, 25 MHz).
pub fn instructions_per_count() -> u64 {
    let n: u32 = 1_000_000;
    let c = counts();
    // SAFETY: a register-only countdown loop.
    unsafe {
        core::arch::asm!("2:", "subs {0}, {0}, #1", "bne 2b", inout(reg) n => _, options(nomem, nostack));
    }
    let elapsed = (counts() - c).max(1);
    (2 * n as u64 + elapsed / 2) / elapsed
}

const PAINT: u32 = 0xA5A5_A5A5;
/// Bytes below the stack pointer painted to find the stack's high-water mark.
const PAINT_BYTES: usize = 256 * 1024;

/// The painted stack: its top (the stack pointer at start) and the lowest painted word.
#[derive(Clone, Copy)]
pub struct Stack {
    top: usize,
    bottom: usize,
}

impl Stack {
    /// Paints up to [`PAINT_BYTES`] below the current stack pointer, never below the end of
    /// bss (on a controller with little RAM the stack grows towards it). Call first thing in
    /// `main`.
    #[inline(always)]
    pub fn paint() -> Stack {
        let top = cortex_m::register::msp::read() as usize;
        let live = top - 256;
        let bss_end = (&raw const __ebss as usize).next_multiple_of(4);
        let bottom = live.saturating_sub(PAINT_BYTES).max(bss_end);
        for a in (bottom..live).step_by(4) {
            // SAFETY: RAM between the end of bss and the live stack: free, since cortex-m-rt
            // puts the stack at the top of RAM and data and bss at its start.
            unsafe { core::ptr::write_volatile(a as *mut u32, PAINT) };
        }
        Stack { top, bottom }
    }

    /// Deepest stack use since painting, bytes.
    pub fn high_water_mark(&self) -> usize {
        let mut a = self.bottom;
        // SAFETY: reads the painted range only.
        while a < self.top && unsafe { core::ptr::read_volatile(a as *const u32) } == PAINT {
            a += 4;
        }
        self.top - a
    }
}

unsafe extern "C" {
    static __sdata: u8;
    static __edata: u8;
    static __sbss: u8;
    static __ebss: u8;
}

/// Static RAM: (data, bss) bytes.
pub fn static_ram() -> (usize, usize) {
    let data = &raw const __edata as usize - &raw const __sdata as usize;
    let bss = &raw const __ebss as usize - &raw const __sbss as usize;
    (data, bss)
}

/// A plant whose `command` and `emitted` are counted ([`counts`]): the output stage and the
/// hand-off to the cell, told apart from the executor's own work in a tick. It borrows the
/// plant: the output stage's Ruckig generator (20 KiB) is not moved (a move costs a second
/// copy on the stack).
pub struct Metered<'a, P> {
    /// The plant measured.
    pub plant: &'a mut P,
    /// SysTick counts spent in the plant since the last [`Metered::take`].
    spent: Cell<u64>,
}

impl<'a, P> Metered<'a, P> {
    /// `plant`, nothing counted yet.
    pub fn new(plant: &'a mut P) -> Self {
        Metered {
            plant,
            spent: Cell::new(0),
        }
    }

    /// The counts spent in the plant since the last call.
    pub fn take(&mut self) -> u64 {
        self.spent.take()
    }
}

impl<P: Plant> Plant for Metered<'_, P> {
    type Error = P::Error;

    fn measured(&self) -> Measured {
        self.plant.measured()
    }

    fn command(&mut self, sp: &Setpoint) -> Result<(), P::Error> {
        let start = counts();
        let done = self.plant.command(sp);
        self.spent.set(self.spent.get() + (counts() - start));
        done
    }

    fn emitted(&self, sp: &Setpoint) -> Setpoint {
        let start = counts();
        let out = self.plant.emitted(sp);
        self.spent.set(self.spent.get() + (counts() - start));
        out
    }
}
