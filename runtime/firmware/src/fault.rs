//! Ending the firmware: exit codes over semihosting, and every exception and panic exits with
//! a message (under QEMU a fault would otherwise hang forever).

use cortex_m_rt::{ExceptionFrame, exception};
use cortex_m_semihosting::{debug, hprintln};

/// Exit statuses: the process status of `qemu-system-arm`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u8)]
pub enum Exit {
    Done = 0,
    NoBlob = 2,
    CorruptBlob = 3,
    NoTask = 4,
    Plan = 5,
    NoProgram = 6,
    /// The program ended in a fault or did not finish.
    NotDone = 7,
    /// The setpoint stream could not be written to the host.
    Output = 8,
    /// The task cannot be done safely: J* above the risk threshold (or the planning budget ran
    /// out with no plan below it). Nothing is executed.
    Risky = 9,
    Exception = 101,
    Panic = 103,
}

/// Ends the run with `status` (semihosting SYS_EXIT_EXTENDED, so QEMU exits with it).
pub fn exit(status: Exit) -> ! {
    const SYS_EXIT_EXTENDED: usize = 0x20;
    const APPLICATION_EXIT: usize = 0x2_0026;
    let block = [APPLICATION_EXIT, status as usize];
    // SAFETY: the host reads the two-word block during the call.
    unsafe { cortex_m_semihosting::syscall(SYS_EXIT_EXTENDED, &block) };
    // A host without the extension: the plain exit (status 0 or 1).
    debug::exit(if status == Exit::Done {
        debug::EXIT_SUCCESS
    } else {
        debug::EXIT_FAILURE
    });
    loop {
        cortex_m::asm::bkpt();
    }
}

fn fail(status: Exit, what: core::fmt::Arguments) -> ! {
    hprintln!("prf-firmware: {}", what);
    exit(status)
}

#[exception]
unsafe fn HardFault(ef: &ExceptionFrame) -> ! {
    fail(
        Exit::Exception,
        format_args!("HardFault at pc {:#010x}, lr {:#010x}", ef.pc(), ef.lr()),
    )
}

#[exception]
unsafe fn DefaultHandler(irqn: i16) {
    fail(
        Exit::Exception,
        format_args!("unexpected exception or interrupt {}", irqn),
    )
}

#[panic_handler]
fn panic(info: &core::panic::PanicInfo) -> ! {
    fail(Exit::Panic, format_args!("panic: {}", info))
}
