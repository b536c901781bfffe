//! The task block: a task as bytes, for a cell controller that gets its task from flash or a
//! host link rather than a floor-plan file. Layout: magic `PRFTASK\0`, payload length (u32
//! LE), CRC-32 of the payload (u32 LE), then the postcard payload ([`TaskRecord`]). Decoding
//! borrows the names from the bytes and allocates nothing.

use crate::task::{Placed, Task};
use prf_shared::blob::crc32;
use prf_shared::se3::{pose_from_array, pose_to_array};
use serde::{Deserialize, Serialize};

/// Magic at the start of every task block.
pub const MAGIC: [u8; 8] = *b"PRFTASK\0";
/// Header bytes: magic (8), payload length (4), CRC-32 (4).
pub const HEADER_LEN: usize = 16;

/// Why a task block was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TaskBlockError {
    /// No magic at the start: no block was written.
    Missing,
    /// Shorter than its header says.
    Truncated,
    /// The CRC-32 does not match.
    Checksum,
    /// The payload does not decode.
    Decode,
    /// A pose is not finite or has a zero quaternion.
    Pose,
    /// The buffer is too small to encode into.
    Capacity,
}

impl core::fmt::Display for TaskBlockError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        let s = match self {
            TaskBlockError::Missing => "no task block (magic PRFTASK missing)",
            TaskBlockError::Truncated => "task block truncated",
            TaskBlockError::Checksum => "task block CRC-32 mismatch",
            TaskBlockError::Decode => "task block does not decode",
            TaskBlockError::Pose => "task block has an invalid pose",
            TaskBlockError::Capacity => "buffer too small for the task block",
        };
        f.write_str(s)
    }
}

impl core::error::Error for TaskBlockError {}

/// The serialized task: (id, type) names and poses as `[x, y, z, qw, qx, qy, qz]`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct TaskRecord<'a> {
    /// Part [id, type].
    #[serde(borrow)]
    pub part: [&'a str; 2],
    /// Location ℓ1 [id, type].
    #[serde(borrow)]
    pub from: [&'a str; 2],
    /// Location ℓ2 [id, type].
    #[serde(borrow)]
    pub to: [&'a str; 2],
    /// Part start pose.
    pub part_pose: [f64; 7],
    /// Pose of ℓ1.
    pub from_pose: [f64; 7],
    /// Pose of ℓ2.
    pub to_pose: [f64; 7],
    /// Part goal pose.
    pub goal: [f64; 7],
    /// Platform home pose.
    pub home: [f64; 7],
}

/// Writes `task` as a block into `out`; returns the block's length.
pub fn encode(task: &Task<'_>, out: &mut [u8]) -> Result<usize, TaskBlockError> {
    let rec = TaskRecord {
        part: [task.part.id, task.part.kind],
        from: [task.from.id, task.from.kind],
        to: [task.to.id, task.to.kind],
        part_pose: pose_to_array(&task.part.pose),
        from_pose: pose_to_array(&task.from.pose),
        to_pose: pose_to_array(&task.to.pose),
        goal: pose_to_array(&task.goal),
        home: pose_to_array(&task.home),
    };
    let (head, body) = out
        .split_at_mut_checked(HEADER_LEN)
        .ok_or(TaskBlockError::Capacity)?;
    let n = postcard::to_slice(&rec, body)
        .map_err(|_| TaskBlockError::Capacity)?
        .len();
    head[..8].copy_from_slice(&MAGIC);
    head[8..12].copy_from_slice(&(n as u32).to_le_bytes());
    head[12..16].copy_from_slice(&crc32(&body[..n]).to_le_bytes());
    Ok(HEADER_LEN + n)
}

/// The task of the block at the start of `region` (trailing bytes are ignored: the block may
/// sit at the start of a flash region).
pub fn decode(region: &[u8]) -> Result<Task<'_>, TaskBlockError> {
    if region.len() < HEADER_LEN || region[..8] != MAGIC {
        return Err(TaskBlockError::Missing);
    }
    let word =
        |i: usize| u32::from_le_bytes([region[i], region[i + 1], region[i + 2], region[i + 3]]);
    let n = word(8) as usize;
    let body = region
        .get(HEADER_LEN..HEADER_LEN.saturating_add(n))
        .ok_or(TaskBlockError::Truncated)?;
    if crc32(body) != word(12) {
        return Err(TaskBlockError::Checksum);
    }
    let rec: TaskRecord<'_> = postcard::from_bytes(body).map_err(|_| TaskBlockError::Decode)?;
    let pose = |a: [f64; 7]| pose_from_array(a).ok_or(TaskBlockError::Pose);
    Ok(Task {
        part: Placed {
            id: rec.part[0],
            kind: rec.part[1],
            pose: pose(rec.part_pose)?,
        },
        from: Placed {
            id: rec.from[0],
            kind: rec.from[1],
            pose: pose(rec.from_pose)?,
        },
        to: Placed {
            id: rec.to[0],
            kind: rec.to[1],
            pose: pose(rec.to_pose)?,
        },
        goal: pose(rec.goal)?,
        home: pose(rec.home)?,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use prf_shared::se3::pose_from_xyz_rpy;

    #[test]
    fn round_trip_and_corruption() {
        let p = |x: f64| pose_from_xyz_rpy([x, 0.5, 0.8], [0.1, 0.2, 0.3]);
        let task = Task {
            part: Placed {
                id: "Part1",
                kind: "Bracket",
                pose: p(1.0),
            },
            from: Placed {
                id: "CNC1",
                kind: "CNC",
                pose: p(2.0),
            },
            to: Placed {
                id: "Table1",
                kind: "Table",
                pose: p(3.0),
            },
            goal: p(4.0),
            home: p(5.0),
        };
        let mut buf = [0u8; 512];
        let n = encode(&task, &mut buf).unwrap();
        let back = decode(&buf).unwrap();
        assert_eq!((back.part.id, back.to.kind), ("Part1", "Table"));
        assert!((back.goal.translation.vector - task.goal.translation.vector).norm() < 1e-15);
        assert!(back.goal.rotation.angle_to(&task.goal.rotation) < 1e-12);
        // encoding the decoded task again gives the same bytes
        let mut again = [0u8; 512];
        assert_eq!(encode(&back, &mut again).unwrap(), n);
        assert_eq!(buf[..n], again[..n]);
        buf[HEADER_LEN + 3] ^= 1;
        assert_eq!(decode(&buf).err(), Some(TaskBlockError::Checksum));
        assert_eq!(decode(&[0u8; 64]).err(), Some(TaskBlockError::Missing));
        assert_eq!(
            decode(&buf[..HEADER_LEN + 2]).err(),
            Some(TaskBlockError::Truncated)
        );
        assert_eq!(
            encode(&task, &mut [0u8; 40]).err(),
            Some(TaskBlockError::Capacity)
        );
    }
}
