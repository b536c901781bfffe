//! The smallest executor: polls one future, sleeping (WFI) until an interrupt wakes it.

use core::future::Future;
use core::pin::pin;
use core::sync::atomic::{AtomicBool, Ordering};
use core::task::{Context, Poll, RawWaker, RawWakerVTable, Waker};

static WOKEN: AtomicBool = AtomicBool::new(false);

fn raw() -> RawWaker {
    RawWaker::new(core::ptr::null(), &VTABLE)
}
static VTABLE: RawWakerVTable = RawWakerVTable::new(
    |_| raw(),
    |_| WOKEN.store(true, Ordering::SeqCst),
    |_| WOKEN.store(true, Ordering::SeqCst),
    |_| {},
);

/// Runs `f` to completion on this core.
pub fn block_on<F: Future>(f: F) -> F::Output {
    let mut f = pin!(f);
    // SAFETY: the vtable's functions ignore the data pointer and are thread-safe.
    let waker = unsafe { Waker::from_raw(raw()) };
    let mut cx = Context::from_waker(&waker);
    loop {
        WOKEN.store(false, Ordering::SeqCst);
        if let Poll::Ready(v) = f.as_mut().poll(&mut cx) {
            return v;
        }
        // With interrupts masked, a wake between the check and WFI still ends WFI (the
        // interrupt is pending); unmasking then runs it.
        cortex_m::interrupt::disable();
        if !WOKEN.load(Ordering::SeqCst) {
            cortex_m::asm::wfi();
        }
        // SAFETY: re-enables what was disabled just above; no critical section spans this.
        unsafe { cortex_m::interrupt::enable() };
    }
}
