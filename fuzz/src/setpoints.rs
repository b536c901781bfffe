//! Target `setpoints`: the joint controller (`firmware-sim`) on a hostile setpoint stream —
//! its admission guard, session bookkeeping, servo, watchdog and brake — through
//! [`controller::replay`], the same cycle code as the process, without shared memory.
//!
//! Input: records. A tag byte below 0x80 is followed by one [`SetpointMsg`] (its 160 bytes,
//! little-endian, in field order); a tag `t` ≥ 0x80 is `t − 0x7f` periods without a setpoint.
//! Every published joint state must be finite, within the joints' speed limits, and count
//! every lost, repeated and refused setpoint without wrapping.

use crate::bytes::{Reader, put_f64s};
use prf_firmware_sim::controller::{self, Config, Input};
use prf_ipc::messages::{JointStateMsg, SetpointMsg};
use prf_shared::NA;
use prf_shared::limits::MotionLimits;
use prf_shared::robot::RobotModel;

/// Bytes of one encoded setpoint.
pub const MSG_LEN: usize = 160;

pub fn run(data: &[u8]) {
    let inputs = decode(data);
    let limits = MotionLimits::kmr_iiwa(&RobotModel::kmr_iiwa14());
    let sink = |js: &JointStateMsg| check_state(js, &limits);
    if let Err(e) = controller::replay(&Config::new("fuzz"), inputs, &sink) {
        panic!("the controller stopped with an error on a hostile stream: {e}: {e:?}");
    }
}

/// A published state is finite and within the speed limits (the servo saturates there).
fn check_state(js: &JointStateMsg, limits: &MotionLimits) {
    let finite =
        js.q.iter()
            .chain(&js.qd)
            .chain(&js.base)
            .all(|v| v.is_finite())
            && js.gripper.is_finite()
            && js.tracking_error.is_finite();
    assert!(finite, "a non-finite joint state: {js:?}");
    for j in 0..NA {
        assert!(
            js.qd[j].abs() <= limits.arm_speed[j],
            "A{} at {} rad/s",
            j + 1,
            js.qd[j]
        );
    }
}

/// The inputs encoded in `data` (see the module).
pub fn decode(data: &[u8]) -> Vec<Input> {
    let mut r = Reader::new(data);
    let mut out = Vec::new();
    while let Some(tag) = r.u8() {
        if tag >= 0x80 {
            out.extend(std::iter::repeat_n(Input::Silence, (tag - 0x7f) as usize));
            continue;
        }
        let Some(msg) = message(&mut r) else { break };
        out.push(Input::Setpoint(msg));
    }
    out
}

fn message(r: &mut Reader<'_>) -> Option<SetpointMsg> {
    Some(SetpointMsg {
        seq: r.u64()?,
        t_ns: r.u64()?,
        q: r.f64s()?,
        qd: r.f64s()?,
        base_goal: r.f64s()?,
        mode: r.u32()?,
        flags: r.u32()?,
    })
}

/// `inputs` encoded for [`run`] (the seeds).
pub fn encode(inputs: &[Input]) -> Vec<u8> {
    let mut out = Vec::new();
    for input in inputs {
        match input {
            Input::Silence => out.push(0x80),
            Input::Setpoint(m) => {
                out.push(0);
                out.extend_from_slice(&m.seq.to_le_bytes());
                out.extend_from_slice(&m.t_ns.to_le_bytes());
                put_f64s(&mut out, &m.q);
                put_f64s(&mut out, &m.qd);
                put_f64s(&mut out, &m.base_goal);
                out.extend_from_slice(&m.mode.to_le_bytes());
                out.extend_from_slice(&m.flags.to_le_bytes());
            }
        }
    }
    out
}
