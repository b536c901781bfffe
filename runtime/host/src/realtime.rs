//! The loop thread as a real-time thread: `SCHED_FIFO` and locked memory where the process
//! may have them, the normal scheduler otherwise.
// pthread_{get,set}schedparam have no safe wrapper in rustix; the calls below pass the
// calling thread and valid pointers to stack values.
#![allow(unsafe_code)]

/// The calling thread as a real-time thread while this lives: `SCHED_FIFO` at a priority and
/// every page of the process locked in memory, each only if the process may; dropped, the
/// thread gets its old policy back and the memory is unlocked.
pub struct RealTime {
    previous: Option<(libc::c_int, libc::sched_param)>,
    locked: bool,
    /// What was granted and what was refused, in words.
    pub status: String,
}

impl RealTime {
    /// Tries `SCHED_FIFO` at `priority` (1–99) and `mlockall`.
    pub fn enter(priority: i32) -> Self {
        RealTime::enter_with(priority, true)
    }

    /// Tries `SCHED_FIFO` at `priority` only, leaving the memory as it is: for a thread
    /// beside one that locks and unlocks the process's memory itself.
    pub fn enter_scheduling(priority: i32) -> Self {
        RealTime::enter_with(priority, false)
    }

    fn enter_with(priority: i32, lock: bool) -> Self {
        let (previous, fifo) = set_fifo(priority);
        let locked = if lock {
            lock_memory()
        } else {
            Err("not asked".to_string())
        };
        let status = format!(
            "{}, {}",
            match fifo {
                Ok(()) => format!("SCHED_FIFO {priority}"),
                Err(e) => format!("normal scheduling (SCHED_FIFO refused: {e})"),
            },
            match &locked {
                Ok(()) => "memory locked".to_string(),
                Err(why) => format!("memory not locked ({why})"),
            }
        );
        RealTime {
            previous,
            locked: locked.is_ok(),
            status,
        }
    }
}

impl Drop for RealTime {
    fn drop(&mut self) {
        if let Some((policy, param)) = self.previous {
            // SAFETY: pthread_self is the calling thread; param is a valid sched_param.
            unsafe { libc::pthread_setschedparam(libc::pthread_self(), policy, &param) };
        }
        if self.locked {
            let _ = rustix::mm::munlockall();
        }
    }
}

/// Makes the calling thread SCHED_FIFO; returns its previous policy (if read) and the outcome.
fn set_fifo(
    priority: i32,
) -> (
    Option<(libc::c_int, libc::sched_param)>,
    std::io::Result<()>,
) {
    let mut policy = 0;
    let mut param = libc::sched_param { sched_priority: 0 };
    // SAFETY: pthread_self is the calling thread; both out-pointers are valid.
    let read =
        unsafe { libc::pthread_getschedparam(libc::pthread_self(), &mut policy, &mut param) };
    let previous = (read == 0).then_some((policy, param));
    let fifo = libc::sched_param {
        sched_priority: priority.clamp(1, 99),
    };
    // SAFETY: as above.
    let rc = unsafe { libc::pthread_setschedparam(libc::pthread_self(), libc::SCHED_FIFO, &fifo) };
    let outcome = match rc {
        0 => Ok(()),
        e => Err(std::io::Error::from_raw_os_error(e)),
    };
    (previous.filter(|_| rc == 0), outcome)
}

/// Locks every current and future page, only where the memory-lock limit cannot make later
/// allocations fail (root, or an unlimited RLIMIT_MEMLOCK).
fn lock_memory() -> Result<(), String> {
    use rustix::mm::MlockAllFlags;
    use rustix::process::{Resource, geteuid, getrlimit};
    let unlimited = getrlimit(Resource::Memlock).current.is_none();
    if !(unlimited || geteuid().is_root()) {
        return Err("RLIMIT_MEMLOCK is limited".into());
    }
    rustix::mm::mlockall(MlockAllFlags::CURRENT | MlockAllFlags::FUTURE)
        .map_err(|e| format!("mlockall refused: {e}"))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn policy() -> libc::c_int {
        let (mut policy, mut param) = (0, libc::sched_param { sched_priority: 0 });
        // SAFETY: the calling thread, valid out-pointers.
        unsafe { libc::pthread_getschedparam(libc::pthread_self(), &mut policy, &mut param) };
        policy
    }

    /// Granted or refused, leaving the scope gives the thread its old policy back.
    #[test]
    fn the_old_policy_comes_back() {
        let before = policy();
        {
            let rt = RealTime::enter(10);
            let granted = rt.status.starts_with("SCHED_FIFO");
            assert_eq!(policy() == libc::SCHED_FIFO, granted, "{}", rt.status);
        }
        assert_eq!(policy(), before);
    }
}
