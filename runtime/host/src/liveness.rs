//! Whether the controller's process is alive. At the start the controller's process is
//! opened as a pidfd: the kernel makes it readable when the process exits, which the loop
//! asks every tick in one system call that does not wait (a zero-timeout `poll`), so a dead
//! controller is found while the joint states it sent before dying are still being read (they
//! kept a killed controller's silence from starting for 4–5 ms). Where no pidfd could
//! be opened (a kernel before Linux 5.3, no process id recorded), iceoryx2 answers by listing
//! its nodes, which reads a directory and allocates: a helper thread does that when the loop
//! asks (an atomic and a wake-up on the loop's side), and its answer comes when the thread is
//! scheduled — under CPU contention a dead controller was found that way 10.9 and 18.0 ms
//! after its kill, too late for the 10 ms of test `killed_firmware_is_detected_within_10_ms`.
//! The helper runs only where no pidfd opened.
//!
//! The process id is the one the controller's node recorded, in the controller's PID
//! namespace: a controller in a container of its own would name another process here, and that
//! process's exit, during a silence of the controller, would stop the cell as if the
//! controller had died (stopping the arm, the safe side). Run both in one PID namespace.

use prf_ipc::link::{controller_alive, controller_pid};
use rustix::event::{PollFd, PollFlags, Timespec, poll};
use rustix::fd::OwnedFd;
use rustix::process::{Pid, PidfdFlags, pidfd_open};
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

/// Tells whether the controller of a cell is alive, on request: its pidfd, else a helper
/// thread.
pub struct Liveness {
    shared: Arc<Shared>,
    thread: Option<JoinHandle<()>>,
    /// The controller's process, when it could be opened as a pidfd.
    process: Option<OwnedFd>,
}

impl Liveness {
    /// Opens the process of `cell`'s live controller, or, where it cannot, starts the helper
    /// for `cell`.
    pub fn start(cell: &str) -> std::io::Result<Self> {
        let process = controller_pid(cell)
            .ok()
            .flatten()
            .and_then(Pid::from_raw)
            .and_then(|pid| pidfd_open(pid, PidfdFlags::empty()).ok());
        let shared = Arc::new(Shared::default());
        let thread = match process {
            Some(_) => None,
            None => Some(helper(shared.clone(), cell.to_string())?),
        };
        Ok(Liveness {
            shared,
            thread,
            process,
        })
    }

    /// True if the controller's process has exited, as its pidfd tells at once (one `poll`
    /// with a zero timeout, cheap enough for every tick); false without a pidfd.
    pub fn exited(&self) -> bool {
        let Some(fd) = &self.process else {
            return false;
        };
        let mut fds = [PollFd::new(fd, PollFlags::IN)];
        let now = Timespec {
            tv_sec: 0,
            tv_nsec: 0,
        };
        matches!(poll(&mut fds, Some(&now)), Ok(n) if n > 0)
    }

    /// Asks the helper again; returns the question's number. With a pidfd there is no helper
    /// and no answer ([`Liveness::exited`] tells).
    pub fn ask(&self) -> u64 {
        let q = self.shared.asked.fetch_add(1, Ordering::AcqRel) + 1;
        if let Some(t) = &self.thread {
            t.thread().unpark();
        }
        q
    }

    /// The helper's answer to question `q` or a later one, if there is one yet.
    pub fn answer(&self, q: u64) -> Option<bool> {
        (self.shared.answered.load(Ordering::Acquire) >= q)
            .then(|| self.shared.alive.load(Ordering::Acquire))
    }
}

/// Starts the helper thread answering the loop's questions about `cell`'s controller.
fn helper(s: Arc<Shared>, cell: String) -> std::io::Result<JoinHandle<()>> {
    std::thread::Builder::new()
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
        })
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

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::{Duration, Instant};

    /// A cell without a controller has no process to open: the helper answers, "dead".
    #[test]
    fn without_a_pidfd_the_helper_answers_for_the_controller() {
        let cell = format!("prf-liveness-test-{}", std::process::id());
        let l = Liveness::start(&cell).expect("start");
        assert!(l.process.is_none() && l.thread.is_some());
        assert!(!l.exited());
        let q = l.ask();
        let t0 = Instant::now();
        let answer = loop {
            if let Some(a) = l.answer(q) {
                break a;
            }
            assert!(t0.elapsed() < Duration::from_secs(10), "no answer in 10 s");
            std::thread::sleep(Duration::from_millis(1));
        };
        assert!(!answer, "no controller of {cell} runs");
    }
}
