//! Target `blob`: [`Blob::parse`](prf_shared::blob::Blob::parse) and
//! [`Runtime::load`], then planning one of the example cell's 18 tasks on whatever loads.
//!
//! Input: one byte choosing the task, then the blob. The blob is read as it is (header,
//! length and CRC-32 checks) and once more sealed — its length and CRC-32 rewritten — so
//! that mutations get past the checksum to the decoder, the validation and the planner.

use crate::fixture::{TASKS, check_plan, config};
use prf_runtime::Runtime;
use prf_shared::blob::HEADER_LEN;

pub fn run(data: &[u8]) {
    let Some((&pick, bytes)) = data.split_first() else {
        return;
    };
    if let Err(e) = Runtime::load(bytes) {
        assert!(!e.to_string().is_empty());
    }
    let sealed = seal(bytes);
    match Runtime::load_with(&sealed, config()) {
        Ok(rt) => check_plan(&rt, &TASKS[pick as usize % TASKS.len()].task()),
        Err(e) => assert!(!e.to_string().is_empty()),
    }
}

/// `bytes` sealed: its header's length and CRC-32 made to match.
pub fn seal(bytes: &[u8]) -> Vec<u8> {
    crate::bytes::seal(bytes, HEADER_LEN, 12, 16)
}
