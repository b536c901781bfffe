//! The messages between the host cell and the joint controller (firmware-sim): `#[repr(C)]`,
//! fixed size, no pointers, so iceoryx2 can hand them across processes without copying. They
//! derive iceoryx2's `ZeroCopySend` with an explicit type name, so two separately built
//! binaries agree on the payload.
//!
//! Sequence numbers make lost or repeated messages visible: a setpoint session starts at
//! `seq = 1` with [`flags::FIRST`] and counts up by one per tick.

use iceoryx2::prelude::ZeroCopySend;
use prf_shared::NA;

/// Bits of [`SetpointMsg::flags`].
pub mod flags {
    /// First setpoint of a session: the controller resets its sequence bookkeeping and arms its
    /// watchdog.
    pub const FIRST: u32 = 1;
    /// Last setpoint of a session: the controller holds it and disarms the watchdog.
    pub const LAST: u32 = 1 << 1;
    /// Close the gripper (else open it).
    pub const GRIPPER_CLOSE: u32 = 1 << 2;
    /// The cell is in a fault and brakes: the setpoint decelerates to rest.
    pub const FAULT: u32 = 1 << 3;
    /// The controller process exits after this message.
    pub const SHUTDOWN: u32 = 1 << 4;
}

/// Bits of [`JointStateMsg::status`].
pub mod status {
    /// No new setpoint for the watchdog's number of cycles: braking or stopped.
    pub const WATCHDOG: u32 = 1;
    /// A setpoint broke a joint limit or a speed limit and was refused: braking or stopped.
    pub const REJECTED: u32 = 1 << 1;
    /// The arm is braking (Ruckig stop trajectory).
    pub const BRAKING: u32 = 1 << 2;
    /// A setpoint session is active (between FIRST and LAST).
    pub const ACTIVE: u32 = 1 << 3;
    /// The platform found no collision-free path to its goal and holds where it is.
    pub const NO_PATH: u32 = 1 << 4;
}

/// Executor modes as sent in [`SetpointMsg::mode`]: `prf_runtime::executor::Mode` as u32.
pub mod mode {
    use prf_runtime::executor::Mode;
    pub const BASE: u32 = Mode::Base as u32;
    pub const ARM: u32 = Mode::Arm as u32;
    pub const GRIPPER: u32 = Mode::Gripper as u32;
    pub const DONE: u32 = Mode::Done as u32;
    pub const FAULT: u32 = Mode::Fault as u32;
}

/// One setpoint from the cell, once per 1 ms tick.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, ZeroCopySend)]
#[type_name("prf::SetpointMsg/1")]
pub struct SetpointMsg {
    /// 1, 2, 3, … within a session.
    pub seq: u64,
    /// Send time, CLOCK_MONOTONIC ns (shared by the processes of one machine).
    pub t_ns: u64,
    /// Arm joint positions, rad, and velocities, rad/s.
    pub q: [f64; NA],
    pub qd: [f64; NA],
    /// Platform goal [x, y, yaw] in the world, m and rad.
    pub base_goal: [f64; 3],
    /// Executor mode, see [`mode`].
    pub mode: u32,
    /// See [`flags`].
    pub flags: u32,
}

/// The measured state from the joint controller, once per controller cycle.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, ZeroCopySend)]
#[type_name("prf::JointStateMsg/2")]
pub struct JointStateMsg {
    /// 1, 2, 3, … over the controller's life.
    pub seq: u64,
    /// Publish time, CLOCK_MONOTONIC ns.
    pub t_ns: u64,
    /// Newest setpoint applied (0: none in this session).
    pub setpoint_seq: u64,
    /// One-way latency of that setpoint: its receive time − its `t_ns`, ns.
    pub setpoint_latency_ns: u64,
    /// Measured arm joint positions, rad, and velocities, rad/s.
    pub q: [f64; NA],
    pub qd: [f64; NA],
    /// Platform pose [x, y, yaw] in the world, m and rad.
    pub base: [f64; 3],
    /// Gripper: 0 open … 1 closed.
    pub gripper: f64,
    /// Largest |reference − measured| of any joint in this cycle, rad.
    pub tracking_error: f64,
    /// While the platform drives on a known floor map: the robot's clearance to the nearest
    /// obstacle (platform, arm, gripper and a held part), m; NaN otherwise.
    pub drive_clearance: f64,
    /// See [`status`].
    pub status: u32,
    /// Setpoints lost (sequence gaps), repeated (sequence not increasing) and refused in this
    /// session.
    pub lost: u32,
    pub repeated: u32,
    pub rejected: u32,
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The layout two separately built binaries rely on: fixed sizes, 8-byte alignment.
    #[test]
    fn message_layout_is_fixed() {
        assert_eq!(core::mem::size_of::<SetpointMsg>(), 160);
        assert_eq!(core::mem::size_of::<JointStateMsg>(), 208);
        assert_eq!(core::mem::align_of::<SetpointMsg>(), 8);
        assert_eq!(core::mem::align_of::<JointStateMsg>(), 8);
    }
}
