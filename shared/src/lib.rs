//! `prf-shared`: the common language of the Program Reuse Framework (PRF) cell runtime.
//!
//! `#![no_std]` and allocation-free: everything here runs unchanged on the cell controller
//! (Cortex-M7) and on the host. Contents:
//! - [`se3`]: pose and SO(3) helpers (log/exp without quaternion double-cover flips);
//! - [`robot`]: the robot model as plain data (joints, limits, collision spheres), with the
//!   KMR iiwa 14 R820 as built-in default;
//! - [`kinematics`]: forward kinematics of every link, TCP pose, geometric Jacobian;
//! - [`nullspace`]: the sign-continuous compact null-space basis M(q) of Sec. 4.2.1;
//! - [`dmp`]: DMPs of Sec. 3.2 (position in R^n, rotation on SO(3));
//! - [`rdmp`]: redundancy DMPs, Alg. 1 (train) and Alg. 2 (integrate, one step per tick);
//! - [`motion`]: the motion classes Pick, Place, Move (Sec. 5.1, 5.3);
//! - [`field`], [`risk`]: the learned workspace as a conservative distance field and the
//!   risk of Eq. 16;
//! - [`limits`]: position, speed, acceleration and jerk limits of the KMR iiwa, and the meter
//!   that rates a joint stream against them;
//! - [`timing`]: an RDMP motion timed within the limits (time scaling of τ, settling to rest);
//! - [`profile`], [`linalg`], [`float`]: small helpers (time scaling, fixed-size solvers, the
//!   square root and e^{−x} at each platform's speed with the same bits).
//!
//! Section, equation and algorithm numbers refer to Toner, Tilbury, Barton, "PRF: A Program
//! Reuse Framework for Automated Programming by Learning from Existing Robot Programs",
//! Robotics 2024, 13(8):118.
#![no_std]
// The Cortex-M7's hardware square root ([`float::sqrt`]); the firmware's toolchain allows it.
#![cfg_attr(
    all(target_arch = "arm", target_feature = "vfp2"),
    feature(core_float_math)
)]

pub mod blob;
pub mod dmp;
pub mod field;
pub mod float;
pub mod kinematics;
pub mod limits;
pub mod linalg;
pub mod motion;
pub mod nullspace;
pub mod profile;
pub mod rdmp;
pub mod risk;
pub mod robot;
pub mod se3;
pub mod timing;

/// Number of arm axes n_a. The RDMP null space is n_a − 6 = 1 dimensional.
pub const NA: usize = 7;

/// Joint-space vector of the arm.
pub type JointVector = nalgebra::SVector<f64, NA>;

/// Geometric Jacobian of the arm, 6×n_a, rows [v; ω].
pub type Jacobian = nalgebra::SMatrix<f64, 6, NA>;
