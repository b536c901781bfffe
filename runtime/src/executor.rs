//! The executor: a state machine over a program's segments, ticked once per Δt = 1 ms.
//!
//! `tick(now, measured)` does bounded work (at most one RDMP step, Alg. 2, or one unit of an
//! arm segment's preparation, and one segment transition), allocates nothing and cannot
//! panic. Arm segments integrate the planned RDMP one step per tick from the previous setpoint
//! (open loop in the measured state, so the executed trajectory is exactly the planned one);
//! the reversal replays it backwards ([`crate::reverse`]); gripper and platform segments
//! command and wait for the measured state, with timeouts.
//!
//! Preparing an arm segment (decoding its RDMP from the blob, then starting the run) costs
//! several RDMP steps, so it is split into two units of one tick each, done ahead during the
//! platform and gripper segments before it, where the arm holds still and ticks are cheap. An
//! arm segment that could not be prepared ahead holds the arm for its first two ticks. A
//! reversal's first resume is likewise done ahead ([`Reversal::prepare`]).
//!
//! A fault (timeout, tracking error, non-finite input, clock going backwards) moves the
//! executor to `Fault`, which holds the last safe setpoint at rest and says why.

use crate::load::{LoadError, Runtime};
use crate::program::{Program, Segment};
use crate::retract::{Connect, Playback};
use crate::reverse::{Reversal, ReverseError};
use embassy_time::{Duration, Instant};
use prf_shared::dmp::{Basis, DmpError, DmpParams};
use prf_shared::rdmp::{Rdmp, RdmpError, RdmpRun};
use prf_shared::se3::Pose;
use prf_shared::{JointVector, NA};

/// Tolerances and timeouts of the executor.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ExecutorConfig {
    /// Longest wait for the gripper to open or close.
    pub gripper_timeout: Duration,
    /// Longest wait for the platform to reach a goal.
    pub base_timeout: Duration,
    /// The platform has arrived within this distance, m.
    pub base_position_tolerance: f64,
    /// The platform has arrived within this yaw, rad.
    pub base_yaw_tolerance: f64,
    /// Largest allowed |measured − previous setpoint| of any arm joint, rad.
    pub tracking_tolerance: f64,
    /// The gripper counts as closed at or above, open at or below these (0 open, 1 closed).
    pub gripper_closed: f64,
    /// The gripper counts as open at or below this.
    pub gripper_open: f64,
    /// A recovery's retraction ([`Segment::Retract`]) moves at this fraction of the arm's
    /// speed, acceleration and jerk limits back onto the path, and then plays the path back at
    /// this many samples per tick (0 < x ≤ 1; another value means the default, 0.25).
    pub retract_speed: f64,
    /// Ticks over which the playback speeds up from rest.
    pub retract_ramp: u32,
}

impl Default for ExecutorConfig {
    fn default() -> Self {
        ExecutorConfig {
            gripper_timeout: Duration::from_secs(5),
            base_timeout: Duration::from_secs(120),
            base_position_tolerance: 0.005,
            base_yaw_tolerance: 0.01,
            tracking_tolerance: 0.1,
            gripper_closed: 0.95,
            gripper_open: 0.05,
            retract_speed: crate::retract::DEFAULT_SPEED,
            retract_ramp: 1000,
        }
    }
}

/// The measured state of the cell.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Measured {
    /// Arm joints, rad.
    pub arm: [f64; NA],
    /// Platform [x, y, yaw] in the world.
    pub base: [f64; 3],
    /// 0 open … 1 closed.
    pub gripper: f64,
}

/// What the executor is doing. Its `u8` value is the one encoding of the mode everywhere
/// (setpoint records, IPC messages, the firmware's per-mode figures).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u8)]
pub enum Mode {
    /// Waiting for the platform to reach `base_goal`.
    Base = 0,
    /// Moving the arm.
    Arm = 1,
    /// Waiting for the gripper.
    Gripper = 2,
    /// Program complete; holding.
    Done = 3,
    /// Stopped by a fault; holding the last safe setpoint.
    Fault = 4,
}

/// One setpoint, once per tick.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Setpoint {
    /// Sequence number: 1 for the first tick, +1 every tick.
    pub seq: u32,
    /// The tick's time.
    pub t: Instant,
    /// Arm joint setpoint, rad.
    pub arm: [f64; NA],
    /// Arm joint velocity, rad/s.
    pub arm_velocity: [f64; NA],
    /// Close the gripper (else open it).
    pub close_gripper: bool,
    /// Platform goal [x, y, yaw] (world).
    pub base_goal: [f64; 3],
    /// What the executor is doing.
    pub mode: Mode,
    /// Index of the program segment.
    pub segment: u8,
}

impl Setpoint {
    /// The program is over: done, or stopped by a fault. The last setpoint a drive loop sends.
    pub fn is_final(&self) -> bool {
        matches!(self.mode, Mode::Done | Mode::Fault)
    }
}

/// What an executor drives: where the measured state comes from and where each setpoint goes
/// (the ideal cell, the host cell's output stage, a real drive). One [`Executor::step`] per
/// tick hands them over in the one order every platform uses: measure → tick → command.
pub trait Plant {
    /// Why the plant could not take a setpoint.
    type Error;
    /// The state measured now.
    fn measured(&self) -> Measured;
    /// Takes the tick's setpoint.
    fn command(&mut self, sp: &Setpoint) -> Result<(), Self::Error>;
    /// What the plant passed on for the last commanded `sp` (an output stage's emitted
    /// setpoint); by default `sp` itself.
    fn emitted(&self, sp: &Setpoint) -> Setpoint {
        *sp
    }
}

/// Why the executor stopped.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Fault {
    /// Segment `segment` waited longer than its timeout.
    Timeout {
        /// Index of the segment.
        segment: u8,
    },
    /// Joint `joint` is `error` rad from the previous setpoint.
    Tracking {
        /// The joint, 0-based.
        joint: u8,
        /// Its distance from the setpoint, rad.
        error: f64,
    },
    /// The measured state has a non-finite value.
    NonFinite,
    /// `now` went backwards.
    ClockBackwards,
    /// The RDMP of segment `segment` could not be stepped.
    Rdmp {
        /// Index of the segment.
        segment: u8,
        /// Why the step failed.
        error: RdmpError,
    },
    /// The reversal of segment `segment` failed.
    Reverse {
        /// Index of the segment.
        segment: u8,
        /// Why the reversal failed.
        error: ReverseError,
    },
    /// Segment `segment` does not fit the program (a reversal without a forward motion).
    Program {
        /// Index of the segment.
        segment: u8,
    },
    /// The blob could not be read.
    Load(LoadError),
}

impl core::fmt::Display for Fault {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Fault::Timeout { segment } => write!(f, "segment {segment} timed out"),
            Fault::Tracking { joint, error } => write!(
                f,
                "joint A{} is {error:.4} rad from its setpoint",
                *joint as usize + 1
            ),
            Fault::NonFinite => write!(f, "the measured state is not finite"),
            Fault::ClockBackwards => write!(f, "time went backwards"),
            Fault::Rdmp { segment, error } => write!(f, "segment {segment}: RDMP: {error}"),
            Fault::Reverse { segment, error } => write!(f, "segment {segment}: reversal: {error}"),
            Fault::Program { segment } => write!(f, "segment {segment} is malformed"),
            Fault::Load(e) => write!(f, "{e}"),
        }
    }
}

impl core::error::Error for Fault {}

pub use prf_shared::kinematics::planar;
pub use prf_shared::se3::wrap;

/// The executor of one program.
pub struct Executor<'r, 'a> {
    rt: &'r Runtime<'a>,
    program: Program,
    cfg: ExecutorConfig,
    reversal: &'r mut Reversal,
    segment: usize,
    /// When the current segment was entered (None: not yet).
    entered: Option<Instant>,
    /// The arm segment whose RDMP `rdmp` is (and, once started, whose `run` is); `rdmp` is
    /// meaningless while None.
    prepared: Option<usize>,
    rdmp: Rdmp,
    /// The prepared segment's run: forward, then, once finished, the reversal's
    /// re-integration of the same motion ([`Reversal::next`]), without a copy.
    run: Option<RdmpRun>,
    /// The last arm segment's phase bases: the next run starts on them when its DMP's
    /// parameters are the same, so the tick that starts a run computes no bases (n_g
    /// exponentials); they are computed in a tick of their own when the parameters differ.
    basis: Option<Basis>,
    last: Setpoint,
    fault: Option<Fault>,
    /// Where a retraction is (None outside Retract segments).
    retract: Option<Retraction>,
}

/// `slot` set to the bases of `p`, built in a frame of its own: inlined, the bases'
/// temporary (0.8 KiB) raised the Cortex-M7's static RAM from 117.3 to 118.0 KiB
/// (`prf firmware`).
#[inline(never)]
fn renew(slot: &mut Option<Basis>, p: &DmpParams) -> Result<(), DmpError> {
    *slot = Some(Basis::new(p)?);
    Ok(())
}

/// The phases of a [`Segment::Retract`] once prepared: re-integrate the forward motion up to
/// step k without moving (recording it for the reversal), move onto q_k, play back to q_0.
#[derive(Clone, Copy, Debug)]
enum Retraction {
    Replay,
    /// The playback is filled ahead while the move runs.
    Connect(Connect, Playback),
    Playback(Playback),
}

impl<'r, 'a> Executor<'r, 'a> {
    /// An executor at the program's start: arm at q_a,H, gripper open, platform at `home`.
    /// `reversal` is the (large) working memory of the reversed motions.
    pub fn new(
        rt: &'r Runtime<'a>,
        program: Program,
        home: &Pose,
        cfg: ExecutorConfig,
        reversal: &'r mut Reversal,
    ) -> Self {
        let last = Setpoint {
            seq: 0,
            t: Instant::from_ticks(0),
            arm: rt.model.home,
            arm_velocity: [0.0; NA],
            close_gripper: false,
            base_goal: planar(home),
            mode: Mode::Base,
            segment: 0,
        };
        Executor {
            rt,
            program,
            cfg,
            reversal,
            segment: 0,
            entered: None,
            prepared: None,
            rdmp: Rdmp::empty(),
            run: None,
            basis: None,
            last,
            fault: None,
            retract: None,
        }
    }

    /// An executor that starts from the arm, gripper and platform as measured in `start`
    /// instead of q_a,H, open and at `home`: the executor of a recovery program
    /// ([`crate::recover`]), whose first segment brings the arm back to q_a,H.
    pub fn resuming(
        rt: &'r Runtime<'a>,
        program: Program,
        home: &Pose,
        start: &Measured,
        cfg: ExecutorConfig,
        reversal: &'r mut Reversal,
    ) -> Self {
        let mut ex = Self::new(rt, program, home, cfg, reversal);
        ex.last.arm = start.arm;
        ex.last.close_gripper = start.gripper >= cfg.gripper_closed;
        // The platform holds where it is until a Base segment moves it.
        ex.last.base_goal = start.base;
        ex
    }

    /// The fault that stopped the executor, if any.
    pub fn fault(&self) -> Option<Fault> {
        self.fault
    }

    /// True once every segment completed.
    pub fn done(&self) -> bool {
        self.fault.is_none() && self.segment >= self.program.segments.len()
    }

    /// One tick: the setpoint for `now` given the state measured at `now`.
    pub fn tick(&mut self, now: Instant, measured: &Measured) -> Setpoint {
        let mut sp = self.last;
        sp.seq = self.last.seq.wrapping_add(1);
        if self.fault.is_none()
            && let Err(f) = self.advance(now, measured, &mut sp)
        {
            self.fault = Some(f);
            sp = self.last;
            sp.seq = self.last.seq.wrapping_add(1);
        }
        if self.fault.is_some() {
            sp.mode = Mode::Fault;
            sp.arm_velocity = [0.0; NA];
        }
        sp.t = now;
        self.last = sp;
        sp
    }

    /// One drive step: the plant's measured state → [`Executor::tick`] → the setpoint
    /// commanded to the plant. Every drive loop (ideal cell, bench, host cell, firmware) is a
    /// sequence of these, one per tick, until [`Setpoint::is_final`].
    pub fn step<P: Plant>(&mut self, now: Instant, plant: &mut P) -> Result<Setpoint, P::Error> {
        let sp = self.tick(now, &plant.measured());
        plant.command(&sp)?;
        Ok(sp)
    }

    fn finish_segment(&mut self) {
        self.segment += 1;
        self.entered = None;
        self.retract = None;
    }

    /// One unit of preparing arm segment `i` from the arm's current setpoint: decode its RDMP,
    /// or else compute its phase's bases if the last ones are not its own, or else start its
    /// run on them. True when the segment is ready to step (no work done then).
    /// A retraction's run starts at q_a,H (where its forward motion started) and records
    /// only its first `from` steps.
    fn prepare(&mut self, i: usize) -> Result<bool, Fault> {
        let segment = i as u8;
        let (skill, goal, steps, scale, recorded, q0) = match self.program.segments.get(i) {
            Some(&Segment::Arm {
                skill,
                goal,
                steps,
                scale,
            }) => (skill, goal, steps, scale, steps, self.last.arm),
            Some(&Segment::Retract {
                skill,
                goal,
                steps,
                scale,
                from,
            }) if from <= steps => (skill, goal, steps, scale, from, self.rt.model.home),
            _ => return Err(Fault::Program { segment }),
        };
        if self.prepared != Some(i) {
            self.prepared = None;
            self.run = None;
            let has = self
                .rt
                .skill_rdmp_into(skill as usize, &mut self.rdmp)
                .map_err(Fault::Load)?;
            if !has {
                return Err(Fault::Program { segment });
            }
            self.rdmp = self.rdmp.time_scaled(scale);
            self.prepared = Some(i);
            return Ok(false);
        }
        if self.run.is_some() {
            return Ok(true);
        }
        let params = &self.rdmp.position.params;
        if !self.basis.as_ref().is_some_and(|b| b.is_for(params)) {
            renew(&mut self.basis, params).map_err(|e| Fault::Rdmp {
                segment,
                error: e.into(),
            })?;
            return Ok(false);
        }
        let q0 = JointVector::from(q0);
        let mut run = RdmpRun::new_on(
            self.basis.as_ref(),
            self.rt.chain(),
            &self.rt.model,
            &self.rdmp,
            &q0,
            &goal,
            &self.rt.config.rdmp,
        )
        .map_err(|error| Fault::Rdmp { segment, error })?;
        run.set_steps(steps as usize);
        self.reversal
            .begin(recorded as usize)
            .map_err(|error| Fault::Reverse { segment, error })?;
        self.run = Some(run);
        Ok(false)
    }

    /// During a platform or gripper segment (the arm holds still): one unit of preparing the
    /// next arm motion, if only platform and gripper segments come before it (an arm segment:
    /// [`Executor::prepare`]; a reversal: its first resume, [`Reversal::prepare`]).
    fn prepare_ahead(&mut self) -> Result<(), Fault> {
        let later = self.program.segments.get(self.segment + 1..).unwrap_or(&[]);
        let Some(k) = later
            .iter()
            .position(|s| !matches!(s, Segment::Base { .. } | Segment::Grip { .. }))
        else {
            return Ok(());
        };
        let i = self.segment + 1 + k;
        match later.get(k) {
            Some(Segment::Arm { .. } | Segment::Retract { .. }) => {
                self.prepare(i)?;
            }
            Some(Segment::Reverse { .. }) if self.prepared.is_some() => {
                self.reversal
                    .prepare(
                        &mut self.run,
                        &self.rt.model,
                        &self.rdmp,
                        &self.rt.config.rdmp,
                    )
                    .map_err(|error| Fault::Reverse {
                        segment: i as u8,
                        error,
                    })?;
            }
            _ => {}
        }
        Ok(())
    }

    /// The tick's work after the checks: the current segment's step into `sp`.
    fn advance(&mut self, now: Instant, m: &Measured, sp: &mut Setpoint) -> Result<(), Fault> {
        self.check(now, m)?;
        let Some(seg) = self.program.segments.get(self.segment).copied() else {
            sp.mode = Mode::Done;
            sp.arm_velocity = [0.0; NA];
            return Ok(());
        };
        let index = self.segment as u8;
        sp.segment = index;
        let entered = *self.entered.get_or_insert(now);
        let waited = now
            .checked_duration_since(entered)
            .unwrap_or(Duration::from_ticks(0));
        match seg {
            Segment::Base { goal } => self.base(&goal, m, waited, sp),
            Segment::Grip { close } => self.grip(close, m, waited, sp),
            Segment::Arm { .. } => self.arm(sp),
            Segment::Reverse { .. } => self.reverse(sp),
            Segment::Retract { from, .. } => self.retract(from, sp),
        }
    }

    /// The measured state is finite, time runs forward, and every arm joint tracks the
    /// previous setpoint.
    fn check(&self, now: Instant, m: &Measured) -> Result<(), Fault> {
        let finite = m.arm.iter().chain(&m.base).all(|v| v.is_finite()) && m.gripper.is_finite();
        if !finite {
            return Err(Fault::NonFinite);
        }
        if self.last.seq > 0 && now < self.last.t {
            return Err(Fault::ClockBackwards);
        }
        for (j, (q, s)) in m.arm.iter().zip(&self.last.arm).enumerate() {
            let error = f64::abs(q - s);
            if error > self.cfg.tracking_tolerance {
                return Err(Fault::Tracking {
                    joint: j as u8,
                    error,
                });
            }
        }
        Ok(())
    }

    /// π_BaseMove: command the platform goal and wait for the platform to arrive, preparing
    /// the next arm motion meanwhile.
    fn base(
        &mut self,
        goal: &Pose,
        m: &Measured,
        waited: Duration,
        sp: &mut Setpoint,
    ) -> Result<(), Fault> {
        sp.mode = Mode::Base;
        sp.arm_velocity = [0.0; NA];
        sp.base_goal = planar(goal);
        let g = sp.base_goal;
        let (dx, dy) = (m.base[0] - g[0], m.base[1] - g[1]);
        let there = prf_shared::float::sqrt(dx * dx + dy * dy) <= self.cfg.base_position_tolerance
            && f64::abs(wrap(m.base[2] - g[2])) <= self.cfg.base_yaw_tolerance;
        self.prepare_ahead()?;
        self.finish_or_wait(there, waited, self.cfg.base_timeout, sp.segment)
    }

    /// π_Grip: command the gripper and wait for it, preparing the next arm motion meanwhile.
    fn grip(
        &mut self,
        close: bool,
        m: &Measured,
        waited: Duration,
        sp: &mut Setpoint,
    ) -> Result<(), Fault> {
        sp.mode = Mode::Gripper;
        sp.arm_velocity = [0.0; NA];
        sp.close_gripper = close;
        let there = if close {
            m.gripper >= self.cfg.gripper_closed
        } else {
            m.gripper <= self.cfg.gripper_open
        };
        self.prepare_ahead()?;
        self.finish_or_wait(there, waited, self.cfg.gripper_timeout, sp.segment)
    }

    /// A waiting segment ends when its target is reached, or faults after `timeout`.
    fn finish_or_wait(
        &mut self,
        there: bool,
        waited: Duration,
        timeout: Duration,
        segment: u8,
    ) -> Result<(), Fault> {
        if there {
            self.finish_segment();
        } else if waited > timeout {
            return Err(Fault::Timeout { segment });
        }
        Ok(())
    }

    /// π_ArmRDMP: one RDMP step (Alg. 2), recorded for the reversal; the arm holds while the
    /// segment is still being prepared.
    fn arm(&mut self, sp: &mut Setpoint) -> Result<(), Fault> {
        let index = sp.segment;
        sp.mode = Mode::Arm;
        if !self.prepare(self.segment)? {
            // Not prepared ahead: hold the arm while preparing.
            sp.arm_velocity = [0.0; NA];
            return Ok(());
        }
        let (model, cfg) = (&self.rt.model, &self.rt.config.rdmp);
        let Some(run) = self.run.as_mut() else {
            return Err(Fault::Program { segment: index });
        };
        let rdmp = &self.rdmp;
        self.reversal.record(run);
        let step = run.step(model, rdmp, cfg).map_err(|error| Fault::Rdmp {
            segment: index,
            error,
        })?;
        sp.arm = step.q.into();
        sp.arm_velocity = step.qd.into();
        if run.finished() {
            // The run stays: a reversal re-integrates in it.
            self.finish_segment();
        }
        Ok(())
    }

    /// ¬π_ArmRDMP: one step of the preceding arm motion played backwards.
    fn reverse(&mut self, sp: &mut Setpoint) -> Result<(), Fault> {
        let index = sp.segment;
        sp.mode = Mode::Arm;
        let (model, cfg) = (&self.rt.model, &self.rt.config.rdmp);
        if self.prepared.is_none() {
            return Err(Fault::Program { segment: index });
        }
        let rdmp = &self.rdmp;
        let q = self
            .reversal
            .next(&mut self.run, model, rdmp, cfg)
            .map_err(|error| Fault::Reverse {
                segment: index,
                error,
            })?
            .ok_or(Fault::Program { segment: index })?;
        let previous = JointVector::from(self.last.arm);
        sp.arm = q.into();
        sp.arm_velocity = ((q - previous) / cfg.dt).into();
        if self.reversal.finished() {
            self.finish_segment();
        }
        Ok(())
    }

    /// A recovery's retraction, one tick: prepare; re-integrate the forward motion to step
    /// `from` without moving (one RDMP step per tick, recorded for the reversal); move onto
    /// q_from ([`Connect`]); play q_from … q_0 back ([`Playback`], one reversal step per tick).
    fn retract(&mut self, from: u32, sp: &mut Setpoint) -> Result<(), Fault> {
        let segment = sp.segment;
        // Until it moves, the arm holds the last setpoint (`sp` starts as it).
        sp.mode = Mode::Arm;
        sp.arm_velocity = [0.0; NA];
        // Prepared once: the replay's run then re-integrates for the reversal.
        if self.retract.is_none() && !self.prepare(self.segment)? {
            return Ok(());
        }
        let (model, cfg) = (&self.rt.model, &self.rt.config.rdmp);
        let phase = self.retract.get_or_insert(Retraction::Replay);
        let rdmp = &self.rdmp;
        let reversal = &mut *self.reversal;
        let run = &mut self.run;
        let reverse_fault = |error| Fault::Reverse { segment, error };
        let q = match phase {
            Retraction::Replay => {
                let Some(forward) = run.as_mut() else {
                    return Err(Fault::Program { segment });
                };
                if forward.progress().0 < from as usize {
                    reversal.record(forward);
                    forward
                        .step(model, rdmp, cfg)
                        .map_err(|error| Fault::Rdmp { segment, error })?;
                    return Ok(());
                }
                let target = (*forward.q()).into();
                // A tick without a step: the reversal's first resume.
                reversal
                    .prepare(run, model, rdmp, cfg)
                    .map_err(reverse_fault)?;
                let speed = self.cfg.retract_speed;
                *phase = Retraction::Connect(
                    Connect::new(self.last.arm, target, &self.rt.limits, speed, cfg.dt),
                    Playback::new(target, from + 1, speed, self.cfg.retract_ramp),
                );
                return Ok(());
            }
            Retraction::Connect(c, p) => {
                if p.wants() {
                    p.feed(reversal_next(reversal, run, model, rdmp, cfg, segment)?);
                }
                let q = c.setpoint();
                if c.finished() {
                    *phase = Retraction::Playback(*p);
                }
                q
            }
            Retraction::Playback(p) => {
                // At most one reversal step per tick; at the start the playback waits at rest
                // until it holds three samples (if the move onto the path was shorter).
                if p.wants() {
                    p.feed(reversal_next(reversal, run, model, rdmp, cfg, segment)?);
                }
                if p.wants() {
                    return Ok(());
                }
                let q = p.setpoint();
                if p.finished() {
                    self.finish_segment();
                }
                q
            }
        };
        let previous = JointVector::from(self.last.arm);
        sp.arm = q;
        sp.arm_velocity = ((JointVector::from(q) - previous) / cfg.dt).into();
        Ok(())
    }
}

/// The reversal's next configuration for a retraction of segment `segment`.
fn reversal_next(
    reversal: &mut Reversal,
    run: &mut Option<RdmpRun>,
    model: &prf_shared::robot::RobotModel,
    rdmp: &Rdmp,
    cfg: &prf_shared::rdmp::RdmpConfig,
    segment: u8,
) -> Result<[f64; NA], Fault> {
    reversal
        .next(run, model, rdmp, cfg)
        .map_err(|error| Fault::Reverse { segment, error })?
        .map(Into::into)
        .ok_or(Fault::Program { segment })
}
