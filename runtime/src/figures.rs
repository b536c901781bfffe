//! The cell-controller firmware's figures as one postcard record, which the firmware writes
//! to the host and the host reads back (the printed report is for people, not parsed).
//! Times are instructions (SysTick counts under `-icount shift=0` × the calibration).

use serde::{Deserialize, Serialize};

/// Longest encoded [`Figures`] record, bytes (postcard varints: 31 u64 of at most 10 bytes,
/// a u32 of at most 5, a flag).
pub const MAX_LEN: usize = 320;

/// Ticks, max and mean instructions of the executor steps in one mode.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct ModeFigures {
    /// Ticks in the mode.
    pub ticks: u64,
    /// Largest instructions of one step.
    pub max: u64,
    /// Mean instructions of a step.
    pub mean: u64,
    /// Largest instructions of one step without the output stage and the hand-off to the
    /// cell (the plant's `command` and `emitted`): the executor's own work.
    pub core_max: u64,
    /// Mean instructions of a step without the output stage and the hand-off.
    pub core_mean: u64,
}

/// What one firmware run measured.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Figures {
    /// Blob size, bytes, and instructions to load and validate it.
    pub blob_bytes: u64,
    /// Instructions to load and validate the blob.
    pub load_instructions: u64,
    /// Planning: physically feasible, RDMP integrations, instructions.
    pub feasible: bool,
    /// RDMP integrations planning ran.
    pub integrations: u64,
    /// Instructions of planning.
    pub planning_instructions: u64,
    /// Executor steps (ticks): how many, the slowest (and its sequence number), the mean.
    pub ticks: u64,
    /// Largest instructions of one step.
    pub tick_max: u64,
    /// Its sequence number.
    pub tick_max_seq: u64,
    /// Mean instructions of a step.
    pub tick_mean: u64,
    /// Per mode: platform, arm, gripper.
    pub by_mode: [ModeFigures; 3],
    /// From the tick's due time to the end of its work (wake-up + step + record), largest.
    pub loop_max: u64,
    /// Wake-up lateness after the tick's due time, largest.
    pub lateness_max: u64,
    /// Ticks whose work overran the 1 ms period.
    pub overruns: u64,
    /// Ticks whose setpoint the output stage's Ruckig had to change (0 for a certified
    /// program).
    pub shaped: u64,
    /// CRC-32 of the setpoint stream's records ([`crate::stream`]).
    pub crc32: u32,
    /// Static RAM, bytes: data, bss, the stack's high-water mark, their sum.
    pub ram_data: u64,
    /// bss, bytes.
    pub ram_bss: u64,
    /// The stack's high-water mark, bytes.
    pub ram_stack: u64,
    /// data + bss + stack, bytes.
    pub ram_total: u64,
}

impl Figures {
    /// The record in `buf`; None if `buf` is too short.
    pub fn encode<'b>(&self, buf: &'b mut [u8]) -> Option<&'b [u8]> {
        postcard::to_slice(self, buf).ok().map(|s| &*s)
    }

    /// The figures of a record; None for bytes that are not one.
    pub fn decode(bytes: &[u8]) -> Option<Figures> {
        postcard::from_bytes(bytes).ok()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Round trip at the largest values, within [`MAX_LEN`].
    #[test]
    fn figures_round_trip_within_the_maximum_length() {
        let m = ModeFigures {
            ticks: u64::MAX,
            max: u64::MAX,
            mean: u64::MAX,
            core_max: u64::MAX,
            core_mean: u64::MAX,
        };
        let f = Figures {
            blob_bytes: u64::MAX,
            load_instructions: u64::MAX,
            feasible: true,
            integrations: u64::MAX,
            planning_instructions: u64::MAX,
            ticks: u64::MAX,
            tick_max: u64::MAX,
            tick_max_seq: u64::MAX,
            tick_mean: u64::MAX,
            by_mode: [m; 3],
            loop_max: u64::MAX,
            lateness_max: u64::MAX,
            overruns: u64::MAX,
            shaped: u64::MAX,
            crc32: u32::MAX,
            ram_data: u64::MAX,
            ram_bss: u64::MAX,
            ram_stack: u64::MAX,
            ram_total: u64::MAX,
        };
        let mut buf = [0u8; MAX_LEN];
        let bytes = f.encode(&mut buf).expect("fits");
        assert_eq!(Figures::decode(bytes), Some(f));
        assert_eq!(Figures::decode(&bytes[..bytes.len() - 1]), None);
    }
}
