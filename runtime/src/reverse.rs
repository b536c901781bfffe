//! ¬π_ArmRDMP: playing a forward RDMP motion backwards, exactly, without a buffer of the
//! whole motion.
//!
//! The forward motion q_0 … q_n is cut into blocks of [`BLOCK`] steps aligned to its end:
//! [n−B, n), [n−2B, n−B), …, [0, …). While it runs forward, the runtime keeps the last
//! block's configurations and an [`RdmpCheckpoint`] at the start of every other block.
//! Backwards, it plays one block from a buffer while it re-integrates the previous block from
//! its checkpoint into a second buffer, one RDMP step per tick. Re-integration from a
//! checkpoint is bit-identical, so the reversed motion visits exactly the forward
//! configurations (and therefore has exactly the planned risk). RAM: two blocks of
//! configurations and the checkpoints, independent of the per-tick work (one step).
//!
//! Resuming from a checkpoint costs about as much as a step, so it is done in a tick without
//! one: the tick that completes a block's re-integration starts the next block's, and
//! [`Reversal::prepare`] starts the first one ahead (during the gripper segment before the
//! reversal). The re-integration runs in the caller's slot of the motion's run: once the
//! forward run has finished, its resumes keep its bases ([`RdmpRun::resume_from`]) and the
//! run is never copied.

use prf_shared::rdmp::{Rdmp, RdmpCheckpoint, RdmpConfig, RdmpError, RdmpRun};
use prf_shared::robot::RobotModel;
use prf_shared::{JointVector, NA};

/// Steps per block.
pub const BLOCK: usize = 256;
/// Checkpoints kept (blocks before the last).
pub const MAX_CHECKPOINTS: usize = 40;
/// The longest motion that can be reversed, steps (41 × 256 = 10.5 s at 1 kHz).
pub const MAX_STEPS: usize = BLOCK * (MAX_CHECKPOINTS + 1);

/// Recording of a forward motion and its backward playback.
pub struct Reversal {
    /// Steps n of the forward motion.
    n: usize,
    checkpoints: heapless::Vec<RdmpCheckpoint, MAX_CHECKPOINTS>,
    buffers: [[[f64; NA]; BLOCK]; 2],
    /// Backward tick i (emits q_{n−1−i}).
    i: usize,
    /// Re-integration of the block after the one playing.
    refill: Option<Refill>,
}

/// The re-integration of block `block` into its buffer, at position `pos` (by the run in
/// the caller's slot).
#[derive(Clone, Copy)]
struct Refill {
    pos: usize,
    block: usize,
}

impl Reversal {
    /// Empty working memory.
    pub const fn new() -> Self {
        Reversal {
            n: 0,
            checkpoints: heapless::Vec::new(),
            buffers: [[[0.0; NA]; BLOCK]; 2],
            i: 0,
            refill: None,
        }
    }

    /// Start of block j (block 0 ends at n).
    fn block_start(&self, j: usize) -> usize {
        self.n.saturating_sub((j + 1) * BLOCK)
    }

    /// Number of blocks.
    fn blocks(&self) -> usize {
        self.n.div_ceil(BLOCK)
    }

    /// Begins recording a forward motion of `n` steps. Errors if it is longer than
    /// [`MAX_STEPS`].
    pub fn begin(&mut self, n: usize) -> Result<(), ReverseError> {
        if n > MAX_STEPS {
            return Err(ReverseError::TooLong { steps: n });
        }
        self.n = n;
        self.checkpoints.clear();
        self.i = 0;
        self.refill = None;
        Ok(())
    }

    /// Records the forward run at step k (before it steps from q_k).
    pub fn record(&mut self, run: &RdmpRun) {
        let k = run.progress().0;
        let last = self.block_start(0);
        if k >= last {
            if let Some(slot) = self.buffers[0].get_mut(k - last) {
                *slot = (*run.q()).into();
            }
        } else if k == 0 || (self.n - k).is_multiple_of(BLOCK) {
            // Blocks before the last one: at most MAX_CHECKPOINTS (checked by `begin`).
            let _ = self.checkpoints.push(run.checkpoint());
        }
    }

    /// True once q_0 was played.
    pub fn finished(&self) -> bool {
        self.i >= self.n
    }

    /// Starts re-integrating block `b` (≥ 1) from its checkpoint, in `run` (resumed when it
    /// holds a run of `rdmp`, which keeps its bases; made otherwise).
    fn start_refill(
        &mut self,
        b: usize,
        run: &mut Option<RdmpRun>,
        model: &RobotModel,
        rdmp: &Rdmp,
        cfg: &RdmpConfig,
    ) -> Result<(), ReverseError> {
        // Checkpoints are in time order: block b starts at checkpoint J − b.
        let c = self
            .checkpoints
            .len()
            .checked_sub(b)
            .and_then(|c| self.checkpoints.get(c))
            .ok_or(ReverseError::MissingCheckpoint)?;
        match run {
            Some(r) => r.resume_from(c),
            None => *run = Some(RdmpRun::resume(model, rdmp, cfg, c)?),
        }
        self.refill = Some(Refill { pos: 0, block: b });
        Ok(())
    }

    /// Work ahead of the first backward tick, for a tick without an RDMP step: starts
    /// re-integrating the second block in `run` (the slot of the motion's run, as for
    /// [`Reversal::next`]). Does nothing when done already or not needed.
    pub fn prepare(
        &mut self,
        run: &mut Option<RdmpRun>,
        model: &RobotModel,
        rdmp: &Rdmp,
        cfg: &RdmpConfig,
    ) -> Result<(), ReverseError> {
        let started = matches!(&self.refill, Some(r) if r.block == 1);
        if self.i == 0 && !started && self.blocks() > 1 {
            self.start_refill(1, run, model, rdmp, cfg)?;
        }
        Ok(())
    }

    /// The next configuration backwards (q_{n−1}, …, q_0), with at most one RDMP step of
    /// re-integration or one resume. `run` is the slot of the motion's run: the finished
    /// forward run of `rdmp` (its bases are kept) or None; the re-integration runs in it, so
    /// the caller leaves it alone until the playback ends.
    pub fn next(
        &mut self,
        run: &mut Option<RdmpRun>,
        model: &RobotModel,
        rdmp: &Rdmp,
        cfg: &RdmpConfig,
    ) -> Result<Option<JointVector>, ReverseError> {
        if self.finished() {
            return Ok(None);
        }
        let j = self.i / BLOCK;
        let start = self.block_start(j);
        let q = self.buffers[j % 2][self.n - 1 - self.i - start];
        let next_started = matches!(&self.refill, Some(r) if r.block == j + 1);
        if j + 1 < self.blocks() && !next_started {
            // Not started ahead.
            self.start_refill(j + 1, run, model, rdmp, cfg)?;
        }
        let len = start - self.block_start(j + 1);
        let mut complete = false;
        if let Some(r) = &mut self.refill
            && r.block == j + 1
            && r.pos < len
        {
            let run = run.as_mut().ok_or(ReverseError::RunDropped)?;
            self.buffers[(j + 1) % 2][r.pos] = (*run.q()).into();
            r.pos += 1;
            if r.pos < len {
                run.step(model, rdmp, cfg)?;
            } else {
                complete = true;
            }
        }
        if complete && j + 2 < self.blocks() {
            // This tick had no step: start the next block's re-integration.
            self.start_refill(j + 2, run, model, rdmp, cfg)?;
        }
        self.i += 1;
        Ok(Some(JointVector::from(q)))
    }
}

impl Default for Reversal {
    fn default() -> Self {
        Self::new()
    }
}

/// Why a motion cannot be played backwards.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ReverseError {
    /// The forward motion is longer than [`MAX_STEPS`].
    TooLong {
        /// Steps of the motion.
        steps: usize,
    },
    /// The forward motion was not recorded from its start.
    MissingCheckpoint,
    /// The run re-integrating the motion was dropped before the playback ended.
    RunDropped,
    /// Re-integration failed (it cannot, for a motion that ran forward).
    Rdmp(RdmpError),
}

impl core::fmt::Display for ReverseError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            ReverseError::TooLong { steps } => write!(
                f,
                "the motion has {steps} steps, at most {MAX_STEPS} can be played backwards"
            ),
            ReverseError::MissingCheckpoint => {
                write!(f, "the forward motion was not recorded from its start")
            }
            ReverseError::RunDropped => write!(
                f,
                "the run re-integrating the motion was dropped before the playback ended"
            ),
            ReverseError::Rdmp(e) => write!(f, "re-integrating the forward motion failed: {e}"),
        }
    }
}

impl core::error::Error for ReverseError {}

impl From<RdmpError> for ReverseError {
    fn from(e: RdmpError) -> Self {
        ReverseError::Rdmp(e)
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use prf_shared::dmp::DmpParams;
    use prf_shared::kinematics::ArmKinematics;
    use prf_shared::rdmp::null_space_coordinate;
    use std::vec::Vec;

    /// An RDMP of `n` steps at 1 ms, trained on a smooth joint motion away from home.
    fn rdmp(model: &RobotModel, n: usize) -> Rdmp {
        let home = model.home;
        let q: Vec<[f64; NA]> = (0..=n)
            .map(|k| {
                let s = k as f64 / n as f64;
                let s = s * s * (3.0 - 2.0 * s);
                core::array::from_fn(|i| home[i] + s * [0.3, 0.2, -0.2, 0.25, 0.1, -0.2, 0.3][i])
            })
            .collect();
        let mut gamma = std::vec![0.0; q.len()];
        null_space_coordinate(model, &q, 0.01, &mut gamma).expect("gamma");
        Rdmp::train(model, &q, &gamma, 1e-3, &DmpParams::default()).expect("train")
    }

    #[test]
    fn the_reversal_replays_the_forward_motion_exactly() {
        let model = RobotModel::kmr_iiwa14();
        let cfg = RdmpConfig::default();
        let mut rev = std::boxed::Box::new(Reversal::new());
        // Shorter than a block, one block, a block and a bit, several blocks; with the first
        // resume prepared ahead or not; re-integrating in the forward run or in a new one.
        for (n, prepared, kept) in
            [40, BLOCK, BLOCK + 1, 3 * BLOCK + 77]
                .into_iter()
                .flat_map(|n| {
                    [
                        (n, false, false),
                        (n, true, false),
                        (n, false, true),
                        (n, true, true),
                    ]
                })
        {
            let r = rdmp(&model, n);
            let q0 = JointVector::from(model.home);
            let goal = ArmKinematics::new(
                &model,
                &JointVector::from(core::array::from_fn(|i| {
                    model.home[i] + [0.2, 0.1, -0.1, 0.2, 0.1, -0.1, 0.2][i]
                })),
            )
            .tcp;
            let mut run = RdmpRun::new(&model, &r, &q0, &goal, &cfg).expect("run");
            let steps = run.progress().1;
            assert_eq!(steps, n);
            rev.begin(steps).expect("fits");
            let mut forward = std::vec![q0];
            while !run.finished() {
                rev.record(&run);
                forward.push(run.step(&model, &r, &cfg).expect("step").q);
            }
            let mut slot = kept.then_some(run);
            if prepared {
                rev.prepare(&mut slot, &model, &r, &cfg).expect("prepare");
            }
            let mut backward = Vec::new();
            while let Some(q) = rev.next(&mut slot, &model, &r, &cfg).expect("reverse") {
                backward.push(q);
            }
            forward.pop();
            forward.reverse();
            assert_eq!(
                backward, forward,
                "n = {n}, prepared {prepared}, forward run kept {kept}: bit-identical reversal"
            );
        }
        // A slot emptied while a block is being re-integrated is an error, not a panic.
        let r = rdmp(&model, 2 * BLOCK);
        let q0 = JointVector::from(model.home);
        let goal = ArmKinematics::new(
            &model,
            &JointVector::from(core::array::from_fn(|i| model.home[i] + 0.1)),
        )
        .tcp;
        let mut run = RdmpRun::new(&model, &r, &q0, &goal, &cfg).expect("run");
        rev.begin(run.progress().1).expect("fits");
        while !run.finished() {
            rev.record(&run);
            run.step(&model, &r, &cfg).expect("step");
        }
        let mut slot = Some(run);
        rev.next(&mut slot, &model, &r, &cfg).expect("first");
        slot = None;
        assert_eq!(
            rev.next(&mut slot, &model, &r, &cfg),
            Err(ReverseError::RunDropped)
        );
        assert_eq!(
            rev.begin(MAX_STEPS + 1),
            Err(ReverseError::TooLong {
                steps: MAX_STEPS + 1
            })
        );
    }
}
