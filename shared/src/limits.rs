//! Motion limits of the KMR iiwa: the one home of the speed, acceleration and jerk limits that
//! the demonstration generator, the dataset check, the cell's Ruckig output stage and the
//! simulated joint controller all obey.

use crate::NA;
use crate::robot::RobotModel;

/// Speed, acceleration and jerk limits of the arm axes and the platform.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MotionLimits {
    /// Arm joint speed limits, rad/s.
    pub arm_speed: [f64; NA],
    /// Arm joint acceleration limits, rad/s².
    pub arm_acceleration: [f64; NA],
    /// Arm joint jerk limits, rad/s³.
    pub arm_jerk: [f64; NA],
    /// Platform speed limits: x, y (m/s), yaw (rad/s).
    pub base_speed: [f64; 3],
    /// Platform acceleration limits: m/s², m/s², rad/s².
    pub base_acceleration: [f64; 3],
    /// Platform jerk limits: m/s³, m/s³, rad/s³.
    pub base_jerk: [f64; 3],
}

impl MotionLimits {
    /// The KMR iiwa: arm speeds from the model (the iiwa 14 data sheet); accelerations of
    /// 2 × the speed limit per second (full speed in 0.5 s) and jerks of 100 × the
    /// acceleration limit per second (full acceleration in 10 ms; the learned RDMPs start with
    /// an acceleration step, which a slower jerk limit would turn into tens of mrad of lag in
    /// the cell's output stage); platform 0.5 m/s, 0.5 rad/s, 0.5 m/s²,
    /// 0.5 rad/s², 1 m/s³, 1 rad/s³ (the KMR omniMove's safe speed is below its 0.9 m/s maximum).
    pub fn kmr_iiwa(model: &RobotModel) -> Self {
        let arm_speed: [f64; NA] = core::array::from_fn(|j| model.joints[j].max_speed);
        let arm_acceleration = arm_speed.map(|v| 2.0 * v);
        MotionLimits {
            arm_speed,
            arm_acceleration,
            arm_jerk: arm_acceleration.map(|a| 100.0 * a),
            base_speed: [0.5, 0.5, 0.5],
            base_acceleration: [0.5, 0.5, 0.5],
            base_jerk: [1.0, 1.0, 1.0],
        }
    }
}
