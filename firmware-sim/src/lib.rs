//! `prf-firmware-sim`: the simulated KUKA iiwa joint controller of the host cell, a process of
//! its own. It takes the cell's setpoints from iceoryx2 shared memory, tracks them with a
//! per-joint servo model, drives the platform and the gripper, and publishes the measured
//! joint state at 1 kHz. It refuses setpoints beyond the joint or speed limits and brakes to
//! standstill (Ruckig) when the setpoints stop. With a world file the platform navigates on
//! its floor map ([`platform`]).

pub mod cli;
pub mod controller;
pub mod guard;
pub mod platform;
pub mod servo;
