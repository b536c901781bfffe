//! Pacing of the host cell's 1 kHz loop by embassy-time's `Ticker` (std driver: a timer
//! thread) without an async executor: the loop thread parks until the timer wakes it, so it
//! uses no CPU between ticks (busy polling collapses on a 2-core machine under load).

use std::future::Future;
use std::pin::pin;
use std::sync::Arc;
use std::task::{Context, Poll, Wake, Waker};
use std::thread::{self, Thread};

struct Unpark(Thread);

impl Wake for Unpark {
    fn wake(self: Arc<Self>) {
        self.0.unpark();
    }
    fn wake_by_ref(self: &Arc<Self>) {
        self.0.unpark();
    }
}

/// Runs futures to completion on the calling thread, parking it while they are pending.
pub struct Parker {
    waker: Waker,
}

impl Parker {
    /// One waker for the thread, made once (nothing is allocated per wait).
    pub fn new() -> Self {
        Parker {
            waker: Waker::from(Arc::new(Unpark(thread::current()))),
        }
    }

    pub fn block_on<F: Future>(&self, f: F) -> F::Output {
        let mut f = pin!(f);
        let mut cx = Context::from_waker(&self.waker);
        loop {
            if let Poll::Ready(v) = f.as_mut().poll(&mut cx) {
                return v;
            }
            thread::park();
        }
    }
}

impl Default for Parker {
    fn default() -> Self {
        Self::new()
    }
}
