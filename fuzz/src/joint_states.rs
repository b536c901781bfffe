//! Target `joint_states`: the cell's tick on hostile joint states — the measured state the
//! executor checks (finite, clock forward, tracking) and the output stage that brakes on a
//! fault — running a real planned program (Part1 CNC1 → Table1 on the committed blob) against
//! the ideal cell, exactly as the host cell's loop calls them.
//!
//! Input: one tag byte per tick or run of ticks:
//! - below 0xC0: one tick measured honestly (the ideal cell's state);
//! - 0xC0 + n (n < 16): 2ⁿ honest ticks (to reach the arm motions quickly);
//! - 0xD0 + n: 1 + n ticks on which no new joint state came (the newest one is reused);
//! - 0xE0 and above: one tick whose state is the honest one with one value replaced (even tag)
//!   or offset (odd tag) by an f64 that follows, after a byte choosing the value (A1–A7, x, y,
//!   yaw, gripper).
//!
//! After the input the cell runs on honestly for up to [`TAIL_TICKS`]. Every emitted setpoint
//! must stay within the position, speed, acceleration and jerk limits, the executor must never
//! return an error, and a faulted program must end with the arm at rest.

use crate::bytes::Reader;
use crate::fixture::{RUNTIME, TASKS};
use embassy_time::Instant;
use prf_ruckig::StagedCell;
use prf_ruckig::{DT, OutputStage};
use prf_runtime::executor::{Executor, ExecutorConfig, Measured, Mode, Plant, Setpoint};
use prf_runtime::ideal::IdealCell;
use prf_runtime::plan;
use prf_runtime::program::Program;
use prf_runtime::reverse::Reversal;
use prf_shared::se3::Pose;
use std::sync::LazyLock;

/// Honest ticks after the input: enough to brake from any speed and settle.
pub const TAIL_TICKS: u64 = 3_000;

/// Ticks of one input at most (a long program is cut there).
pub const MAX_TICKS: u64 = 60_000;

/// Relative tolerance on the emitted stream's ratios to the limits (finite differences of
/// Ruckig's samples).
const RATIO_TOLERANCE: f64 = 1e-6;

/// The program the cell runs, and its home.
pub static PROGRAM: LazyLock<(Program, Pose)> = LazyLock::new(|| {
    let task = TASKS
        .iter()
        .find(|t| t.label() == "Part1 CNC1 → Table1")
        .expect("the example cell has Part1 CNC1 → Table1");
    let p = plan(&RUNTIME, &task.task())
        .unwrap_or_else(|e| panic!("the committed blob cannot plan {}: {e}", task.label()));
    let program = p.program.expect("a program for Part1 CNC1 → Table1");
    (program, task.home)
});

/// What one tick measures.
enum Tick {
    Honest,
    Stale,
    /// Replace (false) or offset (true) value `index` by `value`.
    Hostile {
        index: u8,
        offset: bool,
        value: f64,
    },
}

pub fn run(data: &[u8]) {
    let (rt, home) = (&*RUNTIME, &PROGRAM.1);
    let mut reversal = Box::new(Reversal::new());
    let mut ex = executor(&mut reversal);
    let mut ideal = IdealCell::new(rt.model.home, home, DT);
    let mut stage = OutputStage::new(&rt.model.home, &rt.limits, ideal.measured());
    let mut seen = ideal.measured();
    let mut r = Reader::new(data);
    let (mut k, mut pending) = (0u64, (0u64, Tick::Honest));
    let mut tail = 0u64;
    while k < MAX_TICKS {
        if pending.0 == 0 {
            pending = match next(&mut r) {
                Some(p) => p,
                None => {
                    let ended = (ex.done() || ex.fault().is_some()) && stage.settled();
                    if ended || tail == TAIL_TICKS {
                        break;
                    }
                    tail += 1;
                    (1, Tick::Honest)
                }
            };
        }
        pending.0 -= 1;
        match pending.1 {
            Tick::Honest => seen = ideal.measured(),
            Tick::Stale => {}
            Tick::Hostile {
                index,
                offset,
                value,
            } => {
                seen = ideal.measured();
                hostile(&mut seen, index, offset, value);
            }
        }
        k += 1;
        stage.set_measured(seen);
        let now = Instant::from_micros(k * 1_000);
        let sp = match ex.step(now, &mut stage) {
            Ok(sp) => sp,
            Err(e) => panic!("tick {k}: the output stage failed ({e}) on {seen:?}"),
        };
        ideal.apply(&stage.emitted(&sp));
        check_emitted(&stage, k);
    }
    if ex.fault().is_some() && k < MAX_TICKS {
        assert!(
            stage.settled(),
            "tick {k}: faulted ({:?}) but the arm is not at rest {TAIL_TICKS} ticks after the input",
            ex.fault()
        );
    }
}

/// The next tag of the input.
fn next(r: &mut Reader<'_>) -> Option<(u64, Tick)> {
    let tag = r.u8()?;
    Some(match tag {
        0..0xC0 => (1, Tick::Honest),
        0xC0..0xD0 => (1 << (tag - 0xC0), Tick::Honest),
        0xD0..0xE0 => (1 + (tag - 0xD0) as u64, Tick::Stale),
        _ => {
            let index = r.u8().unwrap_or(0) % 11;
            let value = r.f64().unwrap_or(f64::NAN);
            (
                1,
                Tick::Hostile {
                    index,
                    offset: tag & 1 == 1,
                    value,
                },
            )
        }
    })
}

/// Value `index` of `m` (A1–A7, x, y, yaw, gripper) replaced or offset by `value`.
fn hostile(m: &mut Measured, index: u8, offset: bool, value: f64) {
    let slot = match index {
        0..7 => &mut m.arm[index as usize],
        7..10 => &mut m.base[index as usize - 7],
        _ => &mut m.gripper,
    };
    *slot = if offset { *slot + value } else { value };
}

/// The emitted stream so far is finite and within every limit.
fn check_emitted(stage: &OutputStage, k: u64) {
    let (q, v) = stage.output();
    assert!(
        q.iter().chain(&v).all(|x| x.is_finite()),
        "tick {k}: emitted a non-finite setpoint {q:?} {v:?}"
    );
    let r = stage.ratios();
    let within = [r.position, r.speed, r.acceleration, r.jerk]
        .iter()
        .all(|x| *x <= 1.0 + RATIO_TOLERANCE);
    assert!(within, "tick {k}: the emitted stream exceeds a limit: {r}");
}

/// An input of `ticks` honest ticks (fast-forward tags).
pub fn honest(mut ticks: u64) -> Vec<u8> {
    let mut out = Vec::new();
    for n in (0..16).rev() {
        while ticks >= 1 << n {
            out.push(0xC0 + n as u8);
            ticks -= 1 << n;
        }
    }
    out
}

/// A fresh executor of the program.
fn executor(reversal: &mut Reversal) -> Executor<'_, 'static> {
    let (program, home) = &*PROGRAM;
    Executor::new(
        &RUNTIME,
        program.clone(),
        home,
        ExecutorConfig::default(),
        reversal,
    )
}

/// Runs the program honestly on the ideal cell behind the output stage (the firmware's cell),
/// calling `each` with every tick (from 1), its setpoint and the cell until it returns false
/// or [`MAX_TICKS`] pass.
pub fn honest_run(mut each: impl FnMut(u64, &Setpoint, &StagedCell<IdealCell>) -> bool) {
    let (rt, home) = (&*RUNTIME, &PROGRAM.1);
    let mut reversal = Box::new(Reversal::new());
    let mut ex = executor(&mut reversal);
    let mut cell = StagedCell::new(IdealCell::new(rt.model.home, home, DT), &rt.limits);
    for k in 1..MAX_TICKS {
        let sp = ex
            .step(Instant::from_micros(k * 1_000), &mut cell)
            .expect("an honest tick");
        if !each(k, &sp, &cell) {
            break;
        }
    }
}

/// Tick of the first arm motion of the program (1-based), measured honestly.
pub fn first_arm_tick() -> u64 {
    let mut first = MAX_TICKS;
    honest_run(|k, sp, _| {
        if sp.mode == Mode::Arm {
            first = k;
        }
        sp.mode != Mode::Arm
    });
    first
}
