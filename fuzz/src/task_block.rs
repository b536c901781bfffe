//! Target `task_block`: [`task_block::decode`] of the firmware's TASK region, then planning
//! the task on the committed blob.
//!
//! Input: the region. It is decoded as it is and once more sealed (body length and CRC-32
//! rewritten), so that mutations reach the decoder, the task's validation and the planner.

use crate::fixture::{RUNTIME, check_plan};
use prf_runtime::task_block::{self, HEADER_LEN};

pub fn run(data: &[u8]) {
    if let Err(e) = task_block::decode(data) {
        assert!(!e.to_string().is_empty());
    }
    let sealed = seal(data);
    match task_block::decode(&sealed) {
        Ok(task) => check_plan(&RUNTIME, &task),
        Err(e) => assert!(!e.to_string().is_empty()),
    }
}

/// `region` sealed: its header's length and CRC-32 made to match.
pub fn seal(region: &[u8]) -> Vec<u8> {
    crate::bytes::seal(region, HEADER_LEN, 8, 12)
}
