//! [`Online`]: one Ruckig online generator over `N` axes (3: the platform, 7: the arm),
//! stepped once per 1 ms cycle; Ruckig re-plans only when the target changes.

use core::ffi::c_void;
use core::fmt;
use core::mem::MaybeUninit;

use crate::ffi::{self, Io, Storage};

/// Controller cycle of Ruckig, s.
pub const DT: f64 = 1e-3;

/// Why Ruckig refused a cycle (its `Result` codes).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Code {
    Unclassified,
    InvalidInput,
    TrajectoryDuration,
    PositionalLimits,
    ZeroLimits,
    ExecutionTimeCalculation,
    SynchronizationCalculation,
    Unknown(i32),
}

impl Code {
    pub(crate) fn from_result(r: i32) -> Code {
        match r {
            -1 => Code::Unclassified,
            -100 => Code::InvalidInput,
            -101 => Code::TrajectoryDuration,
            -102 => Code::PositionalLimits,
            -104 => Code::ZeroLimits,
            -110 => Code::ExecutionTimeCalculation,
            -111 => Code::SynchronizationCalculation,
            other => Code::Unknown(other),
        }
    }
}

impl fmt::Display for Code {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Code::Unclassified => write!(f, "an unclassified error"),
            Code::InvalidInput => write!(
                f,
                "invalid input (a state that is not finite, a limit that is not positive, or a target beyond the limits)"
            ),
            Code::TrajectoryDuration => write!(f, "the trajectory would last too long"),
            Code::PositionalLimits => write!(f, "the trajectory leaves the positional limits"),
            Code::ZeroLimits => write!(f, "a zero limit conflicts with the motion"),
            Code::ExecutionTimeCalculation => {
                write!(f, "no time-optimal profile for an axis (step 1)")
            }
            Code::SynchronizationCalculation => {
                write!(f, "the axes could not be synchronised (step 2)")
            }
            Code::Unknown(c) => write!(f, "unknown result code {c}"),
        }
    }
}

/// Ruckig refused an update: why, and the position it started from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RuckigError {
    pub code: Code,
    /// Axes used in `position`.
    pub axes: usize,
    pub position: [f64; 7],
}

impl RuckigError {
    pub(crate) fn new(code: Code, position: &[f64]) -> Self {
        let mut p = [0.0; 7];
        let axes = position.len().min(7);
        p[..axes].copy_from_slice(&position[..axes]);
        RuckigError {
            code,
            axes,
            position: p,
        }
    }
}

impl fmt::Display for RuckigError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "Ruckig could not compute the next cycle ({}) from position {:?}",
            self.code,
            &self.position[..self.axes]
        )
    }
}

impl core::error::Error for RuckigError {}

/// One online trajectory generator over `N` axes (3 or 7) through the project's shim over the
/// Ruckig C++ core: no heap, no exceptions; the generator lives inside this value.
pub struct Online<const N: usize> {
    io: Io<N>,
    storage: Storage,
}

impl<const N: usize> Online<N> {
    /// At rest at `position`, with the given limits.
    pub fn new(
        position: &[f64; N],
        speed: &[f64; N],
        acceleration: &[f64; N],
        jerk: &[f64; N],
    ) -> Self {
        const { assert!(N == 3 || N == 7, "the shim is built for 3 and 7 axes") };
        let zero = [0.0; N];
        let mut o = Online {
            io: Io {
                current_position: *position,
                current_velocity: zero,
                current_acceleration: zero,
                target_position: *position,
                target_velocity: zero,
                target_acceleration: zero,
                max_velocity: *speed,
                max_acceleration: *acceleration,
                max_jerk: *jerk,
                control_interface: ffi::POSITION,
                synchronization: ffi::TIME,
                new_calculation: 0,
                new_position: *position,
                new_velocity: zero,
                new_acceleration: zero,
                duration: 0.0,
            },
            storage: Storage([MaybeUninit::uninit(); crate::storage::STORAGE_BYTES]),
        };
        let s = o.storage_ptr();
        // SAFETY: the storage is large and aligned enough (checked by the shim's
        // static_asserts against the same STORAGE_BYTES) and not yet initialised.
        unsafe {
            match N {
                3 => ffi::prf_ruckig3_init(s, DT),
                _ => ffi::prf_ruckig7_init(s, DT),
            }
        }
        o
    }

    fn storage_ptr(&mut self) -> *mut c_void {
        self.storage.0.as_mut_ptr().cast()
    }

    /// Restarts from the state (position, velocity, acceleration).
    pub fn set_state(&mut self, p: &[f64; N], v: &[f64; N], a: &[f64; N]) {
        self.io.current_position = *p;
        self.io.current_velocity = *v;
        self.io.current_acceleration = *a;
    }

    /// Rest-to-rest moves follow the straight line between start and target in every axis
    /// (Ruckig's phase synchronisation).
    pub fn set_phase_synchronised(&mut self) {
        self.io.synchronization = ffi::PHASE;
    }

    /// Drive to `target` (position interface), arriving at rest.
    pub fn go_to(&mut self, target: &[f64; N]) {
        self.io.control_interface = ffi::POSITION;
        self.io.target_position = *target;
        self.io.target_velocity = [0.0; N];
        self.io.target_acceleration = [0.0; N];
    }

    /// Track a moving reference (position p, velocity v): the output stage's safety net.
    /// Ruckig's velocity interface steers, jerk-limited, to the velocity v + K·(p − position),
    /// within the speed limit. (Its position interface would plan to reach the state (p, v) as
    /// if it stood still, and lags a moving reference by hundreds of ms.)
    pub fn track(&mut self, p: &[f64; N], v: &[f64; N], gain: f64) {
        self.io.control_interface = ffi::VELOCITY;
        for j in 0..N {
            // 2 % below the limit: a jerk-limited approach may overshoot its target speed.
            let m = 0.98 * self.io.max_velocity[j];
            self.io.target_velocity[j] =
                (v[j] + gain * (p[j] - self.io.current_position[j])).clamp(-m, m);
        }
        self.io.target_acceleration = [0.0; N];
    }

    /// Brake to standstill as fast as the acceleration and jerk limits allow (velocity
    /// interface, target velocity 0).
    pub fn brake(&mut self) {
        self.io.control_interface = ffi::VELOCITY;
        self.io.target_velocity = [0.0; N];
        self.io.target_acceleration = [0.0; N];
    }

    /// One cycle: the new (position, velocity, acceleration), which also becomes the current
    /// state. True once the target is reached.
    pub fn step(&mut self) -> Result<bool, RuckigError> {
        let s = self.storage_ptr();
        let io: *mut c_void = (&raw mut self.io).cast();
        // SAFETY: the storage holds a generator initialised by `new` for N axes, and `io` has
        // the shim's Io<N> layout (checked by the test `io_layout_matches_the_shim`).
        let r = unsafe {
            match N {
                3 => ffi::prf_ruckig3_update(s, io),
                _ => ffi::prf_ruckig7_update(s, io),
            }
        };
        let finished = match r {
            0 => false,
            1 => true,
            e => {
                return Err(RuckigError::new(
                    Code::from_result(e),
                    &self.io.current_position,
                ));
            }
        };
        self.io.current_position = self.io.new_position;
        self.io.current_velocity = self.io.new_velocity;
        self.io.current_acceleration = self.io.new_acceleration;
        Ok(finished)
    }

    pub fn position(&self) -> &[f64; N] {
        &self.io.new_position
    }
    pub fn velocity(&self) -> &[f64; N] {
        &self.io.new_velocity
    }
    pub fn acceleration(&self) -> &[f64; N] {
        &self.io.new_acceleration
    }
    /// The current state (also before the first step).
    pub fn current(&self) -> (&[f64; N], &[f64; N], &[f64; N]) {
        (
            &self.io.current_position,
            &self.io.current_velocity,
            &self.io.current_acceleration,
        )
    }
    /// Whether the last step planned a new trajectory (the input had changed).
    pub fn new_calculation(&self) -> bool {
        self.io.new_calculation != 0
    }
}

impl<const N: usize> Drop for Online<N> {
    fn drop(&mut self) {
        let s = self.storage_ptr();
        // SAFETY: initialised by `new`, dropped once.
        unsafe {
            match N {
                3 => ffi::prf_ruckig3_drop(s),
                _ => ffi::prf_ruckig7_drop(s),
            }
        }
    }
}
