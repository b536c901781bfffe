//! The controller process: a 1 kHz cycle synchronous with the cell's setpoints. Each setpoint
//! (woken by its event) advances the plant by one cycle towards it; when a cycle passes with
//! none, the reference coasts at its last velocity. Setpoints that arrive late, for cycles the
//! reference already coasted through, replace that extrapolation without a further cycle, so
//! the plant never runs ahead of the wall clock. After `watchdog_cycles` silent cycles
//! the arm and the platform brake to standstill with Ruckig. Cycles are counted as they run:
//! when the process itself stalls (more than ten periods late), the cycle resynchronises and
//! the stall is logged, not counted as the cell's silence — a real controller does not stall,
//! and on a shared host the cell was stopped too. Every cycle publishes the
//! measured state. A refused setpoint also brakes; the next session (flag FIRST) clears it.

use crate::guard::{Admission, Guard};
use crate::platform::Platform;
use crate::servo::{ArmServo, ServoConfig};
use iceoryx2::prelude::*;
use iceoryx2::waitset::WaitSetRunResult;
use prf_ipc::clock::now_ns;
use prf_ipc::link::{self, ControllerPorts, IpcError};
use prf_ipc::messages::{JointStateMsg, SetpointMsg, flags, status};
use prf_ruckig::{DT, Online, RuckigError};
use prf_shared::NA;
use prf_shared::limits::MotionLimits;
use prf_shared::robot::RobotModel;
use std::io::Write;
use std::path::PathBuf;
use std::time::{Duration, Instant};

/// Why the controller stopped with an error.
#[derive(Debug, thiserror::Error)]
pub enum ControllerError {
    #[error(transparent)]
    Ipc(#[from] IpcError),
    #[error("braking or driving the platform")]
    Ruckig(#[from] RuckigError),
    #[error("iceoryx2 wait set: {0}")]
    WaitSet(String),
    #[error("creating the log {path}")]
    CreateLog {
        path: String,
        #[source]
        source: std::io::Error,
    },
    #[error("writing the log")]
    Log(#[from] std::io::Error),
    #[error("reading the world file")]
    World(#[from] prf_sim::world::WorldError),
}

/// The result of a controller operation.
pub type Result<T> = std::result::Result<T, ControllerError>;

/// Where the controller's measured states go: the shared-memory port, or the observer of a
/// [`replay`].
pub trait StateSink {
    fn publish(&self, msg: JointStateMsg) -> Result<()>;
}

impl StateSink for ControllerPorts {
    fn publish(&self, msg: JointStateMsg) -> Result<()> {
        Ok(ControllerPorts::publish(self, msg)?)
    }
}

/// A replay's observer: a closure that sees every published state.
impl<F: Fn(&JointStateMsg)> StateSink for F {
    fn publish(&self, msg: JointStateMsg) -> Result<()> {
        self(&msg);
        Ok(())
    }
}

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
    /// The cell's world: the platform navigates on its floor map (None: straight lines).
    pub world: Option<prf_sim::world::World>,
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
            world: None,
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
    platform: Platform,
    base_goal: [f64; 3],
    gripper: f64,
    close: bool,
    brake: Option<Online<NA>>,
    /// The brake trajectory reached standstill (Ruckig finished).
    braked: bool,
    limits: MotionLimits,
    gripper_rate: f64,
    /// Cycles the reference has coasted past the newest setpoint: the setpoints for them are
    /// late, and each that comes takes the place of one coasted cycle.
    lag: u32,
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
            platform: Platform::new(cfg.base, &limits, cfg.world.as_ref()),
            base_goal: cfg.base,
            gripper: 0.0,
            close: false,
            brake: None,
            braked: false,
            limits,
            gripper_rate: 1.0 / cfg.gripper_time.max(1e-3),
            lag: 0,
        }
    }

    /// Takes a setpoint as the new reference. Returns whether it is on time (the plant steps
    /// towards it); a late one, for a cycle the reference coasted through, only replaces the
    /// extrapolation: the reference becomes the setpoint coasted over the cycles still lagging.
    fn follow(&mut self, sp: &SetpointMsg) -> bool {
        let on_time = self.lag == 0;
        self.lag = self.lag.saturating_sub(1);
        let ahead = self.lag as f64 * DT;
        for j in 0..NA {
            self.qdd_ref[j] = (sp.qd[j] - self.qd_ref[j]) / DT;
            self.q_ref[j] = sp.q[j] + sp.qd[j] * ahead;
        }
        self.qd_ref = sp.qd;
        self.close = sp.flags & flags::GRIPPER_CLOSE != 0;
        if sp.base_goal != self.base_goal {
            self.base_goal = sp.base_goal;
            let holding = self.holding();
            self.platform.go_to(sp.base_goal, &self.servo.q, holding);
        }
        on_time
    }

    /// No setpoint this cycle: the reference coasts at its velocity.
    fn coast(&mut self) {
        for j in 0..NA {
            self.q_ref[j] += self.qd_ref[j] * DT;
        }
        self.qdd_ref = [0.0; NA];
        self.lag += 1;
    }

    /// Starts braking arm and platform from the current reference.
    fn start_brake(&mut self) {
        if self.brake.is_some() {
            return;
        }
        let l = &self.limits;
        let mut b = Online::new(&self.q_ref, &l.arm_speed, &l.arm_acceleration, &l.arm_jerk);
        let a: [f64; NA] = core::array::from_fn(|j| {
            self.qdd_ref[j].clamp(-l.arm_acceleration[j], l.arm_acceleration[j])
        });
        b.set_state(&self.q_ref, &self.qd_ref, &a);
        b.brake();
        self.brake = Some(b);
        self.platform.brake();
    }

    /// One cycle of everything.
    fn step(&mut self) -> Result<()> {
        if let Some(b) = self.brake.as_mut() {
            self.braked = b.step()?;
            self.q_ref = *b.position();
            self.qd_ref = *b.velocity();
            self.qdd_ref = *b.acceleration();
        }
        self.servo
            .step(&self.q_ref, &self.qd_ref, &self.qdd_ref, DT);
        self.platform.step()?;
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
        self.platform.pose()
    }

    /// The gripper is closed far enough to hold a part.
    fn holding(&self) -> bool {
        self.gripper >= prf_sim::navigation::HOLDING
    }

    /// The robot's clearance while the platform drives on a map (NaN otherwise).
    fn drive_clearance(&self) -> f64 {
        self.platform.clearance()
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
    /// Times this process's own cycle came more than ten periods late with no setpoint
    /// waiting, and resynchronised.
    pub own_stalls: u32,
    pub max_tracking_error: f64,
    /// Drives on the floor map, and the smallest clearance any of them kept, m.
    pub drives: u32,
    pub min_drive_clearance: f64,
}

/// How long past one period after a late setpoint the controller waits for the next one
/// before it coasts again: a fifth of a period, so that the cycle locks onto arrivals.
const RELOCK_GRACE: Duration = Duration::from_micros(200);

/// What a setpoint did.
enum Flow {
    /// The plant stepped and the state was published.
    Stepped,
    /// A repeated setpoint, ignored, or a late one that took the place of a coasted cycle.
    Skipped,
    /// A late setpoint that brought the reference back onto the stream: the next cycle waits
    /// for the next setpoint (one period and a grace from now) to lock onto arrivals again.
    CaughtUp,
    /// SHUTDOWN: the controller exits.
    Exit,
}

/// The controller's state between cycles: the plant, the admission guard, the session and the
/// log. One cycle is [`Controller::on_setpoint`] (a setpoint came) or
/// [`Controller::on_silence`] (a period passed without one); each ends in
/// [`Controller::publish`].
struct Controller<'c> {
    cfg: &'c Config,
    model: RobotModel,
    limits: MotionLimits,
    sink: &'c dyn StateSink,
    log: Box<dyn Write>,
    start: Instant,
    plant: Plant,
    guard: Guard,
    summary: Summary,
    active: bool,
    /// Watchdog or refusal: latched (setpoints ignored, arm braked) until the next FIRST.
    halted: bool,
    state_bits: u32,
    /// Cycles run without a setpoint since the last one (the watchdog's count).
    silent_cycles: u32,
    js_seq: u64,
    window_error: f64,
    window_latency: u64,
    last_sp_seq: u64,
    last_latency: u64,
    /// Smallest clearance of the drive under way (NaN: not driving), and whether the current
    /// goal's missing path was logged.
    drive_min: f64,
    no_path_logged: bool,
}

impl<'c> Controller<'c> {
    /// A controller at rest that publishes to `sink` and logs to `log`.
    fn new(cfg: &'c Config, sink: &'c dyn StateSink, mut log: Box<dyn Write>) -> Result<Self> {
        let model = RobotModel::kmr_iiwa14();
        let limits = MotionLimits::kmr_iiwa(&model);
        writeln!(
            log,
            "# prf firmware-sim, cell {:?}, servo {:.1} Hz ζ {:.2}, watchdog {} cycles, gripper {:.2} s",
            cfg.cell,
            cfg.servo.bandwidth_hz,
            cfg.servo.damping,
            cfg.watchdog_cycles,
            cfg.gripper_time
        )?;
        writeln!(log, "# t_s event details")?;
        log.flush()?;
        Ok(Controller {
            plant: Plant::new(cfg, &model, limits),
            cfg,
            model,
            limits,
            sink,
            log,
            start: Instant::now(),
            guard: Guard::new(cfg.watchdog_cycles),
            summary: Summary::default(),
            active: false,
            halted: false,
            state_bits: 0,
            silent_cycles: 0,
            js_seq: 0,
            window_error: 0.0,
            window_latency: 0,
            last_sp_seq: 0,
            last_latency: 0,
            drive_min: f64::NAN,
            no_path_logged: false,
        })
    }

    /// Seconds since the controller started (the log's time).
    fn t(&self) -> f64 {
        self.start.elapsed().as_secs_f64()
    }

    /// Writes one event line and flushes it.
    fn event(&mut self, what: std::fmt::Arguments) -> Result<()> {
        let t = self.t();
        writeln!(self.log, "{t:.3} {what}")?;
        self.log.flush()?;
        Ok(())
    }

    /// Counts drives (a drive that runs on into the next goal without stopping counts once),
    /// logs each one's smallest clearance when it ends, and logs a goal without a path.
    fn watch_drive(&mut self, clearance: f64) -> Result<()> {
        if !clearance.is_nan() {
            if self.drive_min.is_nan() {
                self.summary.drives += 1;
            }
            self.drive_min = self.drive_min.min(clearance);
            if self.summary.drives == 1 || clearance < self.summary.min_drive_clearance {
                self.summary.min_drive_clearance = self.drive_min;
            }
        } else if !self.drive_min.is_nan() {
            let (m, p) = (self.drive_min, self.plant.base_pose());
            self.drive_min = f64::NAN;
            self.event(format_args!(
                "drive ended at ({:.3}, {:.3}, {:.1}°): smallest clearance {:.1} mm",
                p[0],
                p[1],
                p[2].to_degrees(),
                m * 1e3
            ))?;
        }
        match self.plant.platform.no_path().map(|e| e.to_string()) {
            Some(why) if !self.no_path_logged => {
                self.no_path_logged = true;
                self.event(format_args!("platform: {why}"))?;
            }
            None => self.no_path_logged = false,
            _ => {}
        }
        Ok(())
    }

    /// Publishes the measured state of this cycle.
    fn publish(&mut self, sp_seq: u64, latency: u64) -> Result<()> {
        self.js_seq += 1;
        self.summary.cycles += 1;
        let e = self.plant.tracking_error();
        self.summary.max_tracking_error = self.summary.max_tracking_error.max(e);
        let clearance = self.plant.drive_clearance();
        self.watch_drive(clearance)?;
        self.sink.publish(JointStateMsg {
            seq: self.js_seq,
            t_ns: now_ns(),
            setpoint_seq: sp_seq,
            setpoint_latency_ns: latency,
            q: self.plant.servo.q,
            qd: self.plant.servo.qd,
            base: self.plant.base_pose(),
            gripper: self.plant.gripper,
            tracking_error: e,
            drive_clearance: clearance,
            status: self.state_bits
                | if self.plant.platform.no_path().is_some() {
                    status::NO_PATH
                } else {
                    0
                },
            lost: self.guard.lost,
            repeated: self.guard.repeated,
            rejected: self.guard.rejected,
        })?;
        Ok(())
    }

    /// One cycle driven by setpoint `sp`: session bookkeeping, admission, one plant step,
    /// publish.
    fn on_setpoint(&mut self, sp: SetpointMsg) -> Result<Flow> {
        let latency = now_ns().saturating_sub(sp.t_ns);
        if sp.flags & flags::SHUTDOWN != 0 {
            self.event(format_args!("shutdown requested"))?;
            return Ok(Flow::Exit);
        }
        if sp.flags & flags::FIRST != 0 {
            self.start_session()?;
        }
        let admission = self
            .guard
            .admit(&sp, &self.plant.q_ref, &self.model, &self.limits, DT);
        self.summary.setpoints += 1;
        let step = match admission {
            Admission::Follow if !self.halted => self.plant.follow(&sp),
            Admission::Follow => true,
            Admission::Repeated => return Ok(Flow::Skipped),
            Admission::Refuse(r) => {
                self.event(format_args!("refused setpoint {}: {r}; braking", sp.seq))?;
                self.halted = true;
                self.state_bits |= status::REJECTED | status::BRAKING;
                self.plant.start_brake();
                true
            }
        };
        self.last_sp_seq = sp.seq;
        self.last_latency = latency;
        self.window_latency = self.window_latency.max(latency);
        if step {
            self.plant.step()?;
            self.window_error = self.window_error.max(self.plant.tracking_error());
            self.publish(sp.seq, latency)?;
        }
        self.silent_cycles = 0;
        if sp.flags & flags::LAST != 0 {
            self.end_session(sp.seq)?;
        }
        if sp.seq.is_multiple_of(100) {
            self.log_window(sp.seq)?;
        }
        Ok(match (step, self.plant.lag) {
            (true, _) => Flow::Stepped,
            (false, 0) => Flow::CaughtUp,
            (false, _) => Flow::Skipped,
        })
    }

    /// A FIRST setpoint: a new session clears a latched halt.
    fn start_session(&mut self) -> Result<()> {
        self.active = true;
        self.halted = false;
        self.plant.brake = None;
        self.plant.braked = false;
        self.plant.lag = 0;
        self.summary.sessions += 1;
        self.state_bits = status::ACTIVE;
        let t = self.t();
        writeln!(self.log, "{t:.3} session start")?;
        Ok(())
    }

    /// A LAST setpoint: the session's counts go into the summary.
    fn end_session(&mut self, seq: u64) -> Result<()> {
        self.active = false;
        self.state_bits &= !status::ACTIVE;
        let g = &self.guard;
        self.summary.lost += g.lost as u64;
        self.summary.repeated += g.repeated as u64;
        self.summary.rejected += g.rejected as u64;
        let (lost, repeated, rejected) = (g.lost, g.repeated, g.rejected);
        self.event(format_args!(
            "session end: {seq} setpoints, lost {lost}, repeated {repeated}, refused {rejected}"
        ))
    }

    /// Every 100th setpoint: the window's largest tracking error and latency.
    fn log_window(&mut self, seq: u64) -> Result<()> {
        let t = self.t();
        writeln!(
            self.log,
            "{t:.3} track seq {seq} max_error_mrad {:.3} max_latency_us {:.1}",
            self.window_error * 1e3,
            self.window_latency as f64 * 1e-3
        )?;
        self.window_error = 0.0;
        self.window_latency = 0;
        Ok(())
    }

    /// A cycle without a setpoint: the reference coasts, or after `watchdog_cycles` the
    /// watchdog brakes; one plant step; publish.
    fn on_silence(&mut self) -> Result<()> {
        if self.active && !self.halted {
            self.silent_cycles = self.silent_cycles.saturating_add(1);
            if self.silent_cycles >= self.cfg.watchdog_cycles {
                let (n, seq) = (self.silent_cycles, self.last_sp_seq);
                self.event(format_args!(
                    "watchdog: no setpoint for {n} cycles after seq {seq}; braking"
                ))?;
                self.summary.watchdog_trips += 1;
                self.halted = true;
                self.state_bits |= status::WATCHDOG | status::BRAKING;
                self.plant.start_brake();
            } else {
                self.plant.coast();
            }
        }
        self.plant.step()?;
        if self.plant.braked && self.state_bits & status::BRAKING != 0 {
            self.state_bits &= !status::BRAKING;
            self.event(format_args!("standstill"))?;
        }
        self.publish(self.last_sp_seq, self.last_latency)
    }

    /// The process itself stalled: its cycle came `late` (more than ten periods) and
    /// resynchronises. Logged and counted; the missed cycles are not run, so neither the plant
    /// nor the watchdog counts them.
    fn own_stall(&mut self, late: Duration) -> Result<()> {
        self.summary.own_stalls += 1;
        self.event(format_args!(
            "own cycle {:.1} ms late (this process or the host stalled): resynchronised, the missed cycles not run",
            late.as_secs_f64() * 1e3
        ))
    }

    /// The exit line of the log; the summary.
    fn finish(mut self) -> Result<Summary> {
        let s = self.summary.clone();
        self.event(format_args!("exit: {s}"))?;
        Ok(s)
    }
}

impl std::fmt::Display for Summary {
    /// "N cycles, N sessions, N setpoints, lost …, max tracking error … mrad".
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} cycles, {} sessions, {} setpoints, lost {}, repeated {}, refused {}, watchdog trips {}, max tracking error {:.3} mrad",
            self.cycles,
            self.sessions,
            self.setpoints,
            self.lost,
            self.repeated,
            self.rejected,
            self.watchdog_trips,
            self.max_tracking_error * 1e3
        )?;
        if self.drives > 0 {
            write!(
                f,
                ", {} drives on the floor map, smallest clearance {:.1} mm",
                self.drives,
                self.min_drive_clearance * 1e3
            )?;
        }
        if self.own_stalls > 0 {
            write!(f, ", own stalls {}", self.own_stalls)?;
        }
        Ok(())
    }
}

/// Runs the controller until SIGINT/SIGTERM, a SHUTDOWN setpoint or (optionally) the loss of
/// its parent process: a setpoint wakes it for `Controller::on_setpoint`; a period without
/// one runs `Controller::on_silence`.
pub fn run(cfg: &Config) -> Result<Summary> {
    let node = link::node(&link::controller_node_name(&cfg.cell))?;
    let ports = ControllerPorts::open(&node, &cfg.cell)?;
    let waitset = WaitSetBuilder::new()
        .create::<link::Ipc>()
        .map_err(|e| ControllerError::WaitSet(format!("{e:?}")))?;
    let _guard = waitset
        .attach_notification(&ports.ready)
        .map_err(|e| ControllerError::WaitSet(format!("attach: {e:?}")))?;
    let log_file =
        std::fs::File::create(&cfg.log).map_err(|source| ControllerError::CreateLog {
            path: cfg.log.display().to_string(),
            source,
        })?;
    let log = std::io::BufWriter::with_capacity(1 << 16, log_file);
    let mut c = Controller::new(cfg, &ports, Box::new(log))?;
    let parent = rustix::process::getppid();
    let period = Duration::from_millis(1);
    let mut next = Instant::now() + period;
    'cycle: loop {
        let timeout = next.saturating_duration_since(Instant::now());
        let run = waitset
            .wait_and_process_once_with_timeout(|_| CallbackProgression::Continue, timeout)
            .map_err(|e| ControllerError::WaitSet(format!("{e:?}")))?;
        // SIGINT and SIGTERM end the loop: iceoryx2 reports them as a termination request
        // (a signal during the wait interrupts it, and the next wait reports it). Any other
        // interruption — SIGCONT after a SIGSTOP, for one — is not a request to exit.
        if run == WaitSetRunResult::TerminationRequest {
            c.event(format_args!("exit signal"))?;
            break;
        }
        ports
            .ready
            .try_wait(|_| {})
            .map_err(|e| IpcError::new("listener of the setpoint event", e))?;
        let (mut stepped, mut caught_up) = (false, false);
        while let Some(sample) = ports
            .setpoint
            .receive()
            .map_err(|e| IpcError::new("receive a setpoint", e))?
        {
            let sp = *sample;
            drop(sample);
            match c.on_setpoint(sp)? {
                Flow::Exit => break 'cycle,
                Flow::Stepped => stepped = true,
                Flow::CaughtUp => caught_up = true,
                Flow::Skipped => {}
            }
        }
        let now = Instant::now();
        if stepped {
            next = now + period;
            continue;
        }
        if caught_up {
            next = now + period + RELOCK_GRACE;
            continue;
        }
        if now < next {
            continue;
        }
        c.on_silence()?;
        next = if now > next + period * 10 {
            c.own_stall(now - next)?;
            now + period
        } else {
            next + period
        };
        if cfg.exit_with_parent
            && c.summary.cycles.is_multiple_of(100)
            && rustix::process::getppid() != parent
        {
            c.event(format_args!("parent process gone; exiting"))?;
            break;
        }
    }
    c.finish()
}

/// One input of a [`replay`]: a setpoint as it arrived, or a period that passed without one.
#[derive(Clone, Copy, Debug)]
pub enum Input {
    Setpoint(SetpointMsg),
    Silence,
}

/// The controller's cycles on `inputs`, without shared memory or a wall clock (for fuzzing
/// and tests): one cycle per input, a setpoint or a period without one. Every published
/// state goes to `sink`; the log is discarded. Ends at the last input or at a SHUTDOWN
/// setpoint.
pub fn replay(
    cfg: &Config,
    inputs: impl IntoIterator<Item = Input>,
    sink: &dyn StateSink,
) -> Result<Summary> {
    let mut c = Controller::new(cfg, sink, Box::new(std::io::sink()))?;
    for input in inputs {
        match input {
            Input::Setpoint(sp) => {
                if let Flow::Exit = c.on_setpoint(sp)? {
                    break;
                }
            }
            Input::Silence => c.on_silence()?,
        }
    }
    c.finish()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Cycles of the test stream: every joint moves 0.5 rad rest to rest in 1 s (a quintic),
    /// then rests for 0.2 s.
    const CYCLES: usize = 1200;
    const AMPLITUDE: f64 = 0.5;

    /// The stream's setpoint for cycle `c` (1-based, as `seq`).
    fn setpoint(home: &[f64; NA], c: usize) -> SetpointMsg {
        let s = (c as f64 * DT).min(1.0);
        let pos = s * s * s * (10.0 - 15.0 * s + 6.0 * s * s);
        let vel = 30.0 * s * s * (1.0 - s) * (1.0 - s);
        SetpointMsg {
            seq: c as u64,
            q: core::array::from_fn(|j| home[j] + AMPLITUDE * pos),
            qd: [AMPLITUDE * vel; NA],
            ..SetpointMsg::default()
        }
    }

    /// Runs the plant as the controller's loop does, one wall-clock cycle at a time: when the
    /// setpoints of cycles `stall` have not come by their cycle, the cycle coasts, and they all
    /// come late, with the setpoint of the cycle after the stall. Returns the measured joint
    /// positions per cycle and the largest tracking error.
    fn run(stall: std::ops::Range<usize>) -> (Vec<[f64; NA]>, f64) {
        let model = RobotModel::kmr_iiwa14();
        let limits = MotionLimits::kmr_iiwa(&model);
        let mut plant = Plant::new(&Config::new("test"), &model, limits);
        let (mut measured, mut worst) = (Vec::new(), 0.0f64);
        for c in 1..=CYCLES {
            let stepped = if stall.contains(&c) {
                plant.coast();
                false
            } else {
                let late = if c == stall.end { stall.clone() } else { c..c };
                for l in late {
                    assert!(
                        !plant.follow(&setpoint(&model.home, l)),
                        "setpoint {l} is late"
                    );
                }
                plant.follow(&setpoint(&model.home, c))
            };
            assert!(stepped || stall.contains(&c), "setpoint {c} is on time");
            plant.step().unwrap();
            worst = worst.max(plant.tracking_error());
            measured.push(plant.servo.q);
        }
        (measured, worst)
    }

    /// A stall of the cell costs the plant no cycle: late setpoints replace the coasted
    /// reference instead of stepping again, so the arm stays on the wall clock. The tracking
    /// error grows only by the extrapolation error of the coasted cycles, ½·q̈max·(stall·Δt)²,
    /// and the arm ends where it ends without the stall.
    #[test]
    fn late_setpoints_replace_coasted_cycles() {
        let (on_time, e0) = run(0..0);
        let stall = 400..430; // 30 ms at the fastest part of the motion
        let (stalled, e1) = run(stall.clone());
        let qdd_max = AMPLITUDE * 10.0 / 3.0f64.sqrt(); // of the quintic over 1 s
        let extrapolation = 0.5 * qdd_max * (stall.len() as f64 * DT).powi(2);
        assert!(
            e1 <= e0 + extrapolation,
            "tracking error {:.3} mrad on time, {:.3} mrad with the stall (bound {:.3})",
            e0 * 1e3,
            e1 * 1e3,
            (e0 + extrapolation) * 1e3
        );
        let (a, b) = (on_time.last().unwrap(), stalled.last().unwrap());
        for j in 0..NA {
            assert!(
                (a[j] - b[j]).abs() < 1e-6,
                "A{}: {} vs {}",
                j + 1,
                a[j],
                b[j]
            );
        }
    }

    /// Published states, kept.
    struct Kept(std::cell::RefCell<Vec<JointStateMsg>>);

    impl StateSink for Kept {
        fn publish(&self, msg: JointStateMsg) -> Result<()> {
            self.0.borrow_mut().push(msg);
            Ok(())
        }
    }

    /// The watchdog counts the silent cycles the controller runs, and a setpoint restarts
    /// the count: 99 silent cycles, a setpoint, 99 more hold; the 100th in a row brakes.
    #[test]
    fn the_watchdog_trips_on_the_hundredth_silent_cycle_run() {
        let cfg = Config::new("test");
        assert_eq!(cfg.watchdog_cycles, 100);
        let home = RobotModel::kmr_iiwa14().home;
        let first = SetpointMsg {
            flags: flags::FIRST,
            ..setpoint(&home, 1)
        };
        let silent = |n| std::iter::repeat_n(Input::Silence, n);
        let inputs = std::iter::once(Input::Setpoint(first))
            .chain(silent(99))
            .chain([Input::Setpoint(setpoint(&home, 2))])
            .chain(silent(100));
        let kept = Kept(Default::default());
        let summary = replay(&cfg, inputs, &kept).unwrap();
        let states = kept.0.into_inner();
        // The second setpoint comes after coasted cycles: it replaces one and steps nothing.
        assert_eq!(states.len(), 200);
        let tripped: Vec<usize> = (0..states.len())
            .filter(|&i| states[i].status & status::WATCHDOG != 0)
            .collect();
        assert_eq!(
            tripped.first(),
            Some(&199),
            "the 100th silent cycle after seq 2"
        );
        assert_eq!(summary.watchdog_trips, 1);
    }
}
