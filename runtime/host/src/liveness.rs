//! Whether the controller's process is alive, asked off the 1 kHz loop. iceoryx2 answers by
//! listing its nodes, which reads a directory and allocates: a helper thread does that when
//! the loop asks (an atomic and a wake-up, nothing else on the loop's side).

use prf_ipc::link::controller_alive;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::thread::JoinHandle;

/// Question and answer between the loop and the helper.
#[derive(Default)]
struct Shared {
    /// Number of the last question asked.
    asked: AtomicU64,
    /// Number of the last question answered, and the answer.
    answered: AtomicU64,
    alive: AtomicBool,
    stop: AtomicBool,
}

/// A helper thread that tells whether the controller of a cell is alive, on request.
pub struct Liveness {
    shared: Arc<Shared>,
    thread: Option<JoinHandle<()>>,
}

impl Liveness {
    /// Starts the helper for `cell`.
    pub fn start(cell: &str) -> std::io::Result<Self> {
        let shared = Arc::new(Shared::default());
        let (s, cell) = (shared.clone(), cell.to_string());
        let thread = std::thread::Builder::new()
            .name("prf-liveness".into())
            .spawn(move || {
                while !s.stop.load(Ordering::Acquire) {
                    let q = s.asked.load(Ordering::Acquire);
                    if q > s.answered.load(Ordering::Acquire) {
                        // An error is no answer: the loop's silence limit still applies.
                        if let Ok(alive) = controller_alive(&cell) {
                            s.alive.store(alive, Ordering::Release);
                            s.answered.store(q, Ordering::Release);
                        }
                    }
                    std::thread::park_timeout(std::time::Duration::from_millis(50));
                }
            })?;
        Ok(Liveness {
            shared,
            thread: Some(thread),
        })
    }

    /// Asks again; returns the question's number.
    pub fn ask(&self) -> u64 {
        let q = self.shared.asked.fetch_add(1, Ordering::AcqRel) + 1;
        if let Some(t) = &self.thread {
            t.thread().unpark();
        }
        q
    }

    /// The answer to question `q` or a later one, if there is one yet.
    pub fn answer(&self, q: u64) -> Option<bool> {
        (self.shared.answered.load(Ordering::Acquire) >= q)
            .then(|| self.shared.alive.load(Ordering::Acquire))
    }
}

impl Drop for Liveness {
    fn drop(&mut self) {
        self.shared.stop.store(true, Ordering::Release);
        if let Some(t) = self.thread.take() {
            t.thread().unpark();
            let _ = t.join();
        }
    }
}
