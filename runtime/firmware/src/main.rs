//! PRF cell-controller firmware: the no_std runtime on the Cortex-M7.
//!
//! It reads the blob (BLOB region) and a task block (TASK region) in place, validates both,
//! plans the task, executes the whole program tick by tick against the runtime's ideal cell,
//! and prints over semihosting: a digest of the setpoint stream (every 1000th setpoint and the
//! last, full precision), the instructions of planning and of every tick (SysTick under
//! `qemu-system-arm -icount shift=0`, calibrated at start; resolution 40 instructions), and RAM
//! use (data + bss + the stack's high-water mark). It exits with a status; any exception exits with a message.
#![no_std]
#![no_main]

use core::sync::atomic::{AtomicU32, Ordering};
use cortex_m::peripheral::syst::SystClkSource;
use cortex_m_rt::{ExceptionFrame, entry, exception};
use cortex_m_semihosting::{debug, hprintln};
use embassy_time::{Duration, Instant};
use prf_runtime::executor::{Executor, ExecutorConfig, Mode};
use prf_runtime::ideal::IdealCell;
use prf_runtime::reverse::Reversal;
use prf_runtime::{Runtime, plan};

unsafe extern "C" {
    static _blob_start: u8;
    static _blob_end: u8;
    static _task_start: u8;
    static _task_end: u8;
    static __sdata: u8;
    static __edata: u8;
    static __sbss: u8;
    static __ebss: u8;
}

/// A linker-defined flash region as bytes.
fn region(start: *const u8, end: *const u8) -> &'static [u8] {
    // SAFETY: the symbols bound a flash region of memory.x that the firmware never writes.
    unsafe { core::slice::from_raw_parts(start, end as usize - start as usize) }
}

const RELOAD: u32 = 0x00FF_FFFF;
static WRAPS: AtomicU32 = AtomicU32::new(0);

/// SysTick count since start (SysTick counts under `-icount shift=0`).
fn cycles() -> u64 {
    loop {
        let w = WRAPS.load(Ordering::SeqCst);
        let v = cortex_m::peripheral::SYST::get_current();
        if WRAPS.load(Ordering::SeqCst) == w {
            return w as u64 * (RELOAD as u64 + 1) + (RELOAD - v) as u64;
        }
    }
}

const STACK_PAINT: u32 = 0xA5A5_A5A5;
/// Bytes below the stack pointer painted to measure the stack's high-water mark.
const PAINT_BYTES: usize = 512 * 1024;

fn sp() -> usize {
    cortex_m::register::msp::read() as usize
}

fn paint_stack() -> usize {
    let top = sp() - 64;
    let bottom = top - PAINT_BYTES;
    for a in (bottom..top).step_by(4) {
        // SAFETY: RAM below the live stack (4 MiB RAM, nothing else lives there).
        unsafe { core::ptr::write_volatile(a as *mut u32, STACK_PAINT) };
    }
    bottom
}

/// Deepest stack use since painting, from the top of RAM's stack start.
fn stack_used(bottom: usize, stack_top: usize) -> usize {
    let mut a = bottom;
    // SAFETY: reads the painted area only.
    while a < stack_top && unsafe { core::ptr::read_volatile(a as *const u32) } == STACK_PAINT {
        a += 4;
    }
    stack_top - a
}

fn exit(code: i32) -> ! {
    if code == 0 {
        debug::exit(debug::EXIT_SUCCESS);
    } else {
        debug::exit(debug::EXIT_FAILURE);
    }
    loop {
        cortex_m::asm::bkpt();
    }
}

#[entry]
fn main() -> ! {
    let stack_top = sp();
    let paint_bottom = paint_stack();
    let mut cp = cortex_m::Peripherals::take().unwrap_or_else(|| exit(104));
    cp.SYST.set_clock_source(SystClkSource::Core);
    cp.SYST.set_reload(RELOAD);
    cp.SYST.clear_current();
    cp.SYST.enable_interrupt();
    cp.SYST.enable_counter();
    // The first reload happens on the first count: wait for it, so counts are monotonic.
    while cortex_m::peripheral::SYST::get_current() == 0 {}
    run(stack_top, paint_bottom)
}

/// Instructions per SysTick count: under `-icount shift=0` each instruction takes 1 ns of
/// virtual time and SysTick runs at the board's 25 MHz, so 40; measured here on a loop of
/// exactly 2 instructions per iteration rather than assumed.
fn instructions_per_count() -> u64 {
    let n: u32 = 1_000_000;
    let c = cycles();
    // SAFETY: a register-only countdown loop.
    unsafe {
        core::arch::asm!("2:", "subs {0}, {0}, #1", "bne 2b", inout(reg) n => _, options(nomem, nostack));
    }
    let counts = (cycles() - c).max(1);
    (2 * n as u64 + counts / 2) / counts
}

#[inline(never)]
fn run(stack_top: usize, paint_bottom: usize) -> ! {
    let k = instructions_per_count();
    hprintln!("SysTick: {} instructions per count (calibrated)", k);
    let blob_region = region(&raw const _blob_start, &raw const _blob_end);
    let bytes = match prf_shared::blob::Blob::stored_len(blob_region)
        .ok()
        .and_then(|n| blob_region.get(..n))
    {
        Some(b) => b,
        None => {
            hprintln!(
                "prf-firmware: no blob at 0x00300000 (flash one: -device loader,file=cell.blob,addr=0x00300000)"
            );
            exit(2);
        }
    };
    let t0 = cycles();
    let rt = match Runtime::load(bytes) {
        Ok(rt) => rt,
        Err(e) => {
            hprintln!("prf-firmware: corrupt blob at 0x00300000: {}", e);
            exit(3);
        }
    };
    let load = cycles() - t0;
    let task =
        match prf_runtime::task_block::decode(region(&raw const _task_start, &raw const _task_end))
        {
            Ok(t) => t,
            Err(e) => {
                hprintln!(
                    "prf-firmware: {} at 0x003F0000 (write one: prf plan … --task-block task.bin)",
                    e
                );
                exit(4);
            }
        };
    hprintln!(
        "blob {} B valid; load {} instructions",
        bytes.len(),
        load * k
    );
    hprintln!("task {} {} -> {}", task.part.id, task.from.id, task.to.id);
    let t1 = cycles();
    let p = match plan(&rt, &task) {
        Ok(p) => p,
        Err(e) => {
            hprintln!("prf-firmware: plan: {}", e);
            exit(5);
        }
    };
    let planning = cycles() - t1;
    hprintln!(
        "plan J* {:.6e} feasible {} integrations {} instructions {}",
        p.skills.j,
        p.skills.feasible,
        p.skills.stats.integrations,
        planning * k
    );
    let Some(program) = p.program else {
        hprintln!("prf-firmware: no program");
        exit(6);
    };
    let mut reversal = Reversal::new();
    let mut ex = Executor::new(
        &rt,
        program,
        &task.home,
        ExecutorConfig::default(),
        &mut reversal,
    );
    let mut cell = IdealCell::new(rt.model.home, &task.home);
    let dt = rt.config.rdmp.dt;
    let tick = Duration::from_micros(1000);
    let mut now = Instant::from_ticks(0);
    let (mut max, mut sum, mut n) = (0u64, 0u64, 0u64);
    let mut last = None;
    for k in 0..2_000_000u32 {
        let c = cycles();
        let sp = ex.tick(now, &cell.measured);
        let used = cycles() - c;
        max = max.max(used);
        sum += used;
        n += 1;
        cell.apply(&sp, dt);
        if k % 1000 == 0 || matches!(sp.mode, Mode::Done | Mode::Fault) {
            let q = sp.arm;
            hprintln!(
                "sp {} {} {:.17e} {:.17e} {:.17e} {:.17e} {:.17e} {:.17e} {:.17e}",
                sp.seq,
                sp.mode as u8,
                q[0],
                q[1],
                q[2],
                q[3],
                q[4],
                q[5],
                q[6]
            );
        }
        last = Some(sp);
        if matches!(sp.mode, Mode::Done | Mode::Fault) {
            break;
        }
        now += tick;
    }
    let done = last.is_some_and(|s| s.mode == Mode::Done);
    let data = &raw const __edata as usize - &raw const __sdata as usize;
    let bss = &raw const __ebss as usize - &raw const __sbss as usize;
    let stack = stack_used(paint_bottom, stack_top);
    hprintln!(
        "ticks {} max {} mean {} instructions; done {}",
        n,
        max * k,
        sum * k / n.max(1),
        done
    );
    hprintln!(
        "ram data {} bss {} stack {} total {}",
        data,
        bss,
        stack,
        data + bss + stack
    );
    exit(if done { 0 } else { 7 })
}

#[exception]
fn SysTick() {
    WRAPS.fetch_add(1, Ordering::SeqCst);
}

#[exception]
unsafe fn HardFault(ef: &ExceptionFrame) -> ! {
    hprintln!("prf-firmware: HardFault at pc {:#010x}", ef.pc());
    exit(101);
}

#[exception]
unsafe fn DefaultHandler(irqn: i16) {
    hprintln!("prf-firmware: unexpected exception {}", irqn);
    exit(102);
}

#[panic_handler]
fn panic(info: &core::panic::PanicInfo) -> ! {
    hprintln!("prf-firmware: panic: {}", info);
    exit(103);
}
