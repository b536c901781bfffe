//! The C ABI of `shim/prf_ruckig.cpp`: one cycle's inputs and outputs ([`Io`]) and the
//! generator's opaque storage ([`Storage`]), for 3 and 7 degrees of freedom.

use core::ffi::c_void;
use core::mem::MaybeUninit;

use crate::storage::STORAGE_BYTES;

/// One cycle's exchange with the shim: the same layout as its `Io<N>`.
#[repr(C)]
#[derive(Clone, Copy)]
pub(crate) struct Io<const N: usize> {
    pub current_position: [f64; N],
    pub current_velocity: [f64; N],
    pub current_acceleration: [f64; N],
    pub target_position: [f64; N],
    pub target_velocity: [f64; N],
    pub target_acceleration: [f64; N],
    pub max_velocity: [f64; N],
    pub max_acceleration: [f64; N],
    pub max_jerk: [f64; N],
    /// [`POSITION`] or [`VELOCITY`] (Ruckig's `ControlInterface`).
    pub control_interface: u8,
    /// [`TIME`] or [`PHASE`] (Ruckig's `Synchronization`).
    pub synchronization: u8,
    pub new_calculation: u8,
    pub new_position: [f64; N],
    pub new_velocity: [f64; N],
    pub new_acceleration: [f64; N],
    /// Duration of the current trajectory, s.
    pub duration: f64,
}

pub(crate) const POSITION: u8 = 0;
pub(crate) const VELOCITY: u8 = 1;
pub(crate) const TIME: u8 = 0;
pub(crate) const PHASE: u8 = 2;

/// Where a generator lives: `Ruckig<N>` with its input and output parameters, placed by the
/// shim. Their members are arrays, numbers, options of those and empty `std::vector`s, so
/// the generator may be moved bytewise with its owner.
#[repr(C, align(16))]
pub(crate) struct Storage(pub [MaybeUninit<u8>; STORAGE_BYTES]);

unsafe extern "C" {
    #[cfg(test)]
    pub(crate) fn prf_ruckig3_size() -> usize;
    #[cfg(test)]
    pub(crate) fn prf_ruckig3_io_size() -> usize;
    pub(crate) fn prf_ruckig3_init(storage: *mut c_void, dt: f64);
    pub(crate) fn prf_ruckig3_drop(storage: *mut c_void);
    pub(crate) fn prf_ruckig3_update(storage: *mut c_void, io: *mut c_void) -> i32;
    #[cfg(test)]
    pub(crate) fn prf_ruckig7_size() -> usize;
    #[cfg(test)]
    pub(crate) fn prf_ruckig7_io_size() -> usize;
    pub(crate) fn prf_ruckig7_init(storage: *mut c_void, dt: f64);
    pub(crate) fn prf_ruckig7_drop(storage: *mut c_void);
    pub(crate) fn prf_ruckig7_update(storage: *mut c_void, io: *mut c_void) -> i32;
}

/// Called by the controller build's `operator new` (`shim/bare_metal.cpp`): Ruckig asked for
/// heap memory, which the controller does not have. Never reached with compile-time DoFs.
#[cfg(target_os = "none")]
#[unsafe(no_mangle)]
extern "C" fn prf_ruckig_no_heap() -> ! {
    panic!("Ruckig asked for heap memory; the controller has none")
}
