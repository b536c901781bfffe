//! A setpoint as a fixed-size little-endian record, so a controller can stream every setpoint
//! it produced to a host (the firmware writes them over semihosting) and the host can compare
//! them number for number with its own run. Layout ([`RECORD_LEN`] bytes): seq (u32), mode
//! (u8), segment (u8), close_gripper (u8), 0 (u8), arm q (7 × f64), base goal (3 × f64).

use crate::executor::Setpoint;
use prf_shared::NA;

/// Bytes of one record.
pub const RECORD_LEN: usize = 8 + 8 * NA + 8 * 3;

/// The fields of a setpoint that a record carries.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Record {
    /// Sequence number.
    pub seq: u32,
    /// [`crate::executor::Mode`] as u8.
    pub mode: u8,
    /// Index of the program segment.
    pub segment: u8,
    /// Close the gripper.
    pub close_gripper: bool,
    /// Arm joint setpoint, rad.
    pub arm: [f64; NA],
    /// Platform goal [x, y, yaw].
    pub base_goal: [f64; 3],
}

/// Writes `sp` as a record.
pub fn encode(sp: &Setpoint) -> [u8; RECORD_LEN] {
    let mut out = [0u8; RECORD_LEN];
    out[..4].copy_from_slice(&sp.seq.to_le_bytes());
    out[4] = sp.mode as u8;
    out[5] = sp.segment;
    out[6] = sp.close_gripper as u8;
    let values = sp.arm.iter().chain(&sp.base_goal);
    for (chunk, v) in out[8..].chunks_exact_mut(8).zip(values) {
        chunk.copy_from_slice(&v.to_le_bytes());
    }
    out
}

/// Reads a record.
pub fn decode(bytes: &[u8; RECORD_LEN]) -> Record {
    let f = |i: usize| {
        let at = 8 + 8 * i;
        let mut b = [0u8; 8];
        b.copy_from_slice(&bytes[at..at + 8]);
        f64::from_le_bytes(b)
    };
    Record {
        seq: u32::from_le_bytes([bytes[0], bytes[1], bytes[2], bytes[3]]),
        mode: bytes[4],
        segment: bytes[5],
        close_gripper: bytes[6] != 0,
        arm: core::array::from_fn(f),
        base_goal: core::array::from_fn(|i| f(NA + i)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::executor::Mode;
    use embassy_time::Instant;

    #[test]
    fn a_record_round_trips() {
        let sp = Setpoint {
            seq: 70_001,
            t: Instant::from_ticks(5),
            arm: core::array::from_fn(|i| -1.5 + 0.4 * i as f64 + 1e-13),
            arm_velocity: [0.25; NA],
            close_gripper: true,
            base_goal: [3.25, -1.0e-300, f64::MIN_POSITIVE],
            mode: Mode::Gripper,
            segment: 6,
        };
        let r = decode(&encode(&sp));
        assert_eq!(r.seq, sp.seq);
        assert_eq!(r.mode, Mode::Gripper as u8);
        assert_eq!(r.segment, 6);
        assert!(r.close_gripper);
        assert_eq!(r.arm.map(f64::to_bits), sp.arm.map(f64::to_bits));
        assert_eq!(
            r.base_goal.map(f64::to_bits),
            sp.base_goal.map(f64::to_bits)
        );
    }
}
