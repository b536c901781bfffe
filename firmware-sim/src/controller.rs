//! The controller process: a 1 kHz cycle synchronous with the cell's setpoints. Each setpoint
//! (woken by its event) advances the plant by one cycle towards it; when a cycle passes with
//! none, the reference coasts at its last velocity, and after `watchdog_cycles` silent cycles
//! the arm and the platform brake to standstill with Ruckig. Every cycle publishes the
//! measured state. A refused setpoint also brakes; the next session (flag FIRST) clears it.

use crate::guard::{Admission, Guard};
use crate::servo::{ArmServo, ServoConfig};
use anyhow::{Context, Result};
use iceoryx2::prelude::*;
use iceoryx2::waitset::WaitSetRunResult;
use prf_ipc::clock::now_ns;
use prf_ipc::link::{self, ControllerPorts};
use prf_ipc::messages::{JointStateMsg, SetpointMsg, flags, status};
use prf_ruckig::{DT, Online};
use prf_shared::NA;
use prf_shared::limits::MotionLimits;
use prf_shared::robot::RobotModel;
use prf_shared::se3::wrap;
use std::io::Write;
use std::path::PathBuf;
use std::time::{Duration, Instant};

/// Everything the controller is started with.
#[derive(Clone, Debug)]
pub struct Config {
    /// Cell name: the services are `prf/<cell>/…`.
    pub cell: String,
    pub servo: ServoConfig,
    /// Silent cycles before the watchdog brakes.
    pub watchdog_cycles: u32,
    /// Full open → closed time of the gripper, s.
    pub gripper_time: f64,
    /// Initial platform pose [x, y, yaw]; the arm starts at the model's home.
    pub base: [f64; 3],
    /// Where the log goes.
    pub log: PathBuf,
    /// Exit when the parent process goes away (for children of `prf demo` and tests).
    pub exit_with_parent: bool,
}

impl Config {
    pub fn new(cell: &str) -> Self {
        Config {
            cell: cell.to_string(),
            servo: ServoConfig::default(),
            watchdog_cycles: 100,
            gripper_time: 0.6,
            base: [0.0; 3],
            log: std::env::temp_dir().join(format!("prf-firmware-sim-{cell}.log")),
            exit_with_parent: false,
        }
    }
}

/// The simulated arm, platform and gripper.
struct Plant {
    servo: ArmServo,
    /// Reference (position, velocity, acceleration) the servo follows.
    q_ref: [f64; NA],
    qd_ref: [f64; NA],
    qdd_ref: [f64; NA],
    base: Online,
    base_goal: [f64; 3],
    gripper: f64,
    close: bool,
    brake: Option<Online>,
    /// The brake trajectory reached standstill (Ruckig finished).
    braked: bool,
    limits: MotionLimits,
    gripper_rate: f64,
}

impl Plant {
    fn new(cfg: &Config, model: &RobotModel, limits: MotionLimits) -> Self {
        Plant {
            servo: ArmServo::new(
                cfg.servo,
                model.home,
                limits.arm_speed,
                limits.arm_acceleration,
            ),
            q_ref: model.home,
            qd_ref: [0.0; NA],
            qdd_ref: [0.0; NA],
            base: Online::new(
                &cfg.base,
                &limits.base_speed,
                &limits.base_acceleration,
                &limits.base_jerk,
            ),
            base_goal: cfg.base,
            gripper: 0.0,
            close: false,
            brake: None,
            braked: false,
            limits,
            gripper_rate: 1.0 / cfg.gripper_time.max(1e-3),
        }
    }

    /// Takes a setpoint as the new reference.
    fn follow(&mut self, sp: &SetpointMsg) {
        for j in 0..NA {
            self.qdd_ref[j] = (sp.qd[j] - self.qd_ref[j]) / DT;
        }
        self.q_ref = sp.q;
        self.qd_ref = sp.qd;
        self.close = sp.flags & flags::GRIPPER_CLOSE != 0;
        if sp.base_goal != self.base_goal {
            self.base_goal = sp.base_goal;
            let yaw = self.base.current().0[2];
            let goal_yaw = yaw + wrap(sp.base_goal[2] - yaw);
            self.base
                .go_to(&[sp.base_goal[0], sp.base_goal[1], goal_yaw]);
        }
    }

    /// No setpoint this cycle: the reference coasts at its velocity.
    fn coast(&mut self) {
        for j in 0..NA {
            self.q_ref[j] += self.qd_ref[j] * DT;
        }
        self.qdd_ref = [0.0; NA];
    }

    /// Starts braking arm and platform from the current reference.
    fn start_brake(&mut self) {
        if self.brake.is_some() {
            return;
        }
        let l = &self.limits;
        let mut b = Online::new(&self.q_ref, &l.arm_speed, &l.arm_acceleration, &l.arm_jerk);
        let a: Vec<f64> = (0..NA)
            .map(|j| self.qdd_ref[j].clamp(-l.arm_acceleration[j], l.arm_acceleration[j]))
            .collect();
        b.set_state(&self.q_ref, &self.qd_ref, &a);
        b.brake();
        self.brake = Some(b);
        self.base.brake();
    }

    /// One cycle of everything.
    fn step(&mut self) -> Result<()> {
        if let Some(b) = self.brake.as_mut() {
            self.braked = b.step()?;
            for j in 0..NA {
                self.q_ref[j] = b.position()[j];
                self.qd_ref[j] = b.velocity()[j];
                self.qdd_ref[j] = b.acceleration()[j];
            }
        }
        self.servo
            .step(&self.q_ref, &self.qd_ref, &self.qdd_ref, DT);
        self.base.step()?;
        let dir = if self.close { 1.0 } else { -1.0 };
        self.gripper = (self.gripper + dir * self.gripper_rate * DT).clamp(0.0, 1.0);
        Ok(())
    }

    fn tracking_error(&self) -> f64 {
        (0..NA)
            .map(|j| (self.q_ref[j] - self.servo.q[j]).abs())
            .fold(0.0, f64::max)
    }

    fn base_pose(&self) -> [f64; 3] {
        let p = self.base.current().0;
        [p[0], p[1], wrap(p[2])]
    }
}

/// What the controller did, printed at exit.
#[derive(Clone, Debug, Default)]
pub struct Summary {
    pub cycles: u64,
    pub sessions: u32,
    pub setpoints: u64,
    pub lost: u64,
    pub repeated: u64,
    pub rejected: u64,
    pub watchdog_trips: u32,
    pub max_tracking_error: f64,
}

/// Runs the controller until SIGINT/SIGTERM, a SHUTDOWN setpoint or (optionally) the loss of
/// its parent process.
pub fn run(cfg: &Config) -> Result<Summary> {
    let model = RobotModel::kmr_iiwa14();
    let limits = MotionLimits::kmr_iiwa(&model);
    let node = link::node(&link::controller_node_name(&cfg.cell))?;
    let ports = ControllerPorts::open(&node, &cfg.cell)?;
    let waitset = WaitSetBuilder::new()
        .create::<link::Ipc>()
        .map_err(|e| anyhow::anyhow!("waitset: {e:?}"))?;
    let _guard = waitset
        .attach_notification(&ports.ready)
        .map_err(|e| anyhow::anyhow!("waitset attach: {e:?}"))?;
    let log_file = std::fs::File::create(&cfg.log)
        .with_context(|| format!("creating the log {}", cfg.log.display()))?;
    let mut log = std::io::BufWriter::with_capacity(1 << 16, log_file);
    writeln!(
        log,
        "# prf firmware-sim, cell {:?}, servo {:.1} Hz ζ {:.2}, watchdog {} cycles, gripper {:.2} s",
        cfg.cell, cfg.servo.bandwidth_hz, cfg.servo.damping, cfg.watchdog_cycles, cfg.gripper_time
    )?;
    writeln!(log, "# t_s event details")?;
    log.flush()?;

    let parent = rustix::process::getppid();
    let start = Instant::now();
    let mut plant = Plant::new(cfg, &model, limits);
    let mut guard = Guard::default();
    let mut summary = Summary::default();
    let mut active = false;
    // Watchdog or refusal: latched (setpoints ignored, arm braked) until the next FIRST.
    let mut halted = false;
    let mut state_bits = 0u32;
    let mut last_setpoint = Instant::now();
    let mut next = Instant::now() + Duration::from_millis(1);
    let mut js_seq = 0u64;
    let mut window_error = 0.0f64;
    let mut window_latency = 0u64;
    let mut last_sp_seq = 0u64;
    let mut last_latency = 0u64;
    let period = Duration::from_millis(1);
    let t = |start: Instant| start.elapsed().as_secs_f64();

    let mut publish = |plant: &Plant,
                       bits: u32,
                       g: &Guard,
                       sp_seq: u64,
                       latency: u64,
                       summary: &mut Summary|
     -> Result<()> {
        js_seq += 1;
        summary.cycles += 1;
        let e = plant.tracking_error();
        summary.max_tracking_error = summary.max_tracking_error.max(e);
        ports.publish(JointStateMsg {
            seq: js_seq,
            t_ns: now_ns(),
            setpoint_seq: sp_seq,
            setpoint_latency_ns: latency,
            q: plant.servo.q,
            qd: plant.servo.qd,
            base: plant.base_pose(),
            gripper: plant.gripper,
            tracking_error: e,
            status: bits,
            lost: g.lost,
            repeated: g.repeated,
            rejected: g.rejected,
        })?;
        Ok(())
    };

    'cycle: loop {
        let timeout = next.saturating_duration_since(Instant::now());
        let run = waitset
            .wait_and_process_once_with_timeout(|_| CallbackProgression::Continue, timeout)
            .map_err(|e| anyhow::anyhow!("waitset: {e:?}"))?;
        if matches!(
            run,
            WaitSetRunResult::TerminationRequest | WaitSetRunResult::Interrupt
        ) {
            writeln!(log, "{:.3} exit signal", t(start))?;
            break;
        }
        ports
            .ready
            .try_wait(|_| {})
            .map_err(|e| anyhow::anyhow!("listener: {e:?}"))?;
        let mut stepped = false;
        while let Some(sample) = ports
            .setpoint
            .receive()
            .map_err(|e| anyhow::anyhow!("receive: {e:?}"))?
        {
            let sp = *sample;
            drop(sample);
            let latency = now_ns().saturating_sub(sp.t_ns);
            if sp.flags & flags::SHUTDOWN != 0 {
                writeln!(log, "{:.3} shutdown requested", t(start))?;
                break 'cycle;
            }
            if sp.flags & flags::FIRST != 0 {
                active = true;
                halted = false;
                plant.brake = None;
                plant.braked = false;
                summary.sessions += 1;
                state_bits = status::ACTIVE;
                writeln!(log, "{:.3} session start", t(start))?;
            }
            let admission = guard.admit(&sp, &plant.q_ref, &model, &limits, DT);
            summary.setpoints += 1;
            match admission {
                Admission::Follow if !halted => plant.follow(&sp),
                Admission::Follow => {}
                Admission::Repeated => continue,
                Admission::Refuse(r) => {
                    writeln!(
                        log,
                        "{:.3} refused setpoint {}: {r}; braking",
                        t(start),
                        sp.seq
                    )?;
                    log.flush()?;
                    halted = true;
                    state_bits |= status::REJECTED | status::BRAKING;
                    plant.start_brake();
                }
            }
            plant.step()?;
            last_sp_seq = sp.seq;
            last_latency = latency;
            window_latency = window_latency.max(latency);
            window_error = window_error.max(plant.tracking_error());
            publish(&plant, state_bits, &guard, sp.seq, latency, &mut summary)?;
            stepped = true;
            last_setpoint = Instant::now();
            if sp.flags & flags::LAST != 0 {
                active = false;
                state_bits &= !status::ACTIVE;
                summary.lost += guard.lost as u64;
                summary.repeated += guard.repeated as u64;
                summary.rejected += guard.rejected as u64;
                writeln!(
                    log,
                    "{:.3} session end: {} setpoints, lost {}, repeated {}, refused {}",
                    t(start),
                    sp.seq,
                    guard.lost,
                    guard.repeated,
                    guard.rejected
                )?;
                log.flush()?;
            }
            if sp.seq % 100 == 0 {
                writeln!(
                    log,
                    "{:.3} track seq {} max_error_mrad {:.3} max_latency_us {:.1}",
                    t(start),
                    sp.seq,
                    window_error * 1e3,
                    window_latency as f64 * 1e-3
                )?;
                window_error = 0.0;
                window_latency = 0;
            }
        }
        let now = Instant::now();
        if stepped {
            next = now + period;
            continue;
        }
        if now < next {
            continue;
        }
        // A cycle without a setpoint.
        if active && !halted {
            let silent = (now - last_setpoint).as_secs_f64() / DT;
            if silent >= cfg.watchdog_cycles as f64 {
                writeln!(
                    log,
                    "{:.3} watchdog: no setpoint for {:.1} ms after seq {}; braking",
                    t(start),
                    silent,
                    last_sp_seq
                )?;
                log.flush()?;
                summary.watchdog_trips += 1;
                halted = true;
                state_bits |= status::WATCHDOG | status::BRAKING;
                plant.start_brake();
            } else {
                plant.coast();
            }
        }
        plant.step()?;
        if plant.braked && state_bits & status::BRAKING != 0 {
            state_bits &= !status::BRAKING;
            writeln!(log, "{:.3} standstill", t(start))?;
            log.flush()?;
        }
        publish(
            &plant,
            state_bits,
            &guard,
            last_sp_seq,
            last_latency,
            &mut summary,
        )?;
        next = if now > next + period * 10 {
            now + period
        } else {
            next + period
        };
        if cfg.exit_with_parent && summary.cycles % 100 == 0 && rustix::process::getppid() != parent
        {
            writeln!(log, "{:.3} parent process gone; exiting", t(start))?;
            break;
        }
    }
    writeln!(
        log,
        "{:.3} exit: {} cycles, {} sessions, {} setpoints, lost {}, repeated {}, refused {}, watchdog trips {}, max tracking error {:.3} mrad",
        t(start),
        summary.cycles,
        summary.sessions,
        summary.setpoints,
        summary.lost,
        summary.repeated,
        summary.rejected,
        summary.watchdog_trips,
        summary.max_tracking_error * 1e3
    )?;
    log.flush()?;
    Ok(summary)
}
