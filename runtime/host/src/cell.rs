//! The host cell: the no_std runtime's executor in a 1 kHz loop paced by embassy-time, each
//! setpoint passed through a Ruckig output stage (the iiwa's speed, acceleration and jerk
//! limits) and sent over iceoryx2 shared memory to the joint controller (`firmware-sim`),
//! whose joint state comes back as the executor's measured state.
//!
//! Per tick: wake (Ticker) → receive the newest joint state → executor step (tick, then the
//! Ruckig output stage as the plant) → send the setpoint and wake the controller. A controller that goes silent for `silent_cycles` ticks, or reports that its
//! watchdog or its limit check stopped the arm, stops the cell with a fault. Deadline misses
//! (a setpoint published after its 1 ms period ended) are counted, never hidden.

use crate::liveness::Liveness;
use crate::stall::{self, Silence};
use crate::{pacing, realtime, stats};
use embassy_time::{Duration, Instant, Ticker};
use prf_ipc::clock::now_ns;
use prf_ipc::link::{self, CellPorts, Ipc, IpcError};
use prf_ipc::messages::{JointStateMsg, SetpointMsg, flags, status};
use prf_ruckig::{OutputStage, RuckigError};
use prf_runtime::Runtime;
use prf_runtime::executor::{Executor, ExecutorConfig, Measured, Mode, Setpoint};
use prf_runtime::program::Program;
use prf_runtime::reverse::Reversal;
use prf_shared::NA;
use prf_shared::limits::{LimitRatios, MotionLimits};
use prf_shared::se3::Pose;
use serde::Serialize;

/// Why the host cell could not run.
#[derive(Debug, thiserror::Error)]
pub enum CellError {
    #[error(transparent)]
    Ipc(#[from] IpcError),
    #[error("the output stage failed")]
    Ruckig(#[from] RuckigError),
    #[error(
        "no joint state on prf/{cell}/joint-state within {seconds:.1} s: is `prf firmware-sim --cell {cell}` running?"
    )]
    NoController { cell: String, seconds: f64 },
    #[error(
        "the arm on prf/{cell}/joint-state did not come to rest within {seconds:.1} s (largest joint speed {speed:.4} rad/s)"
    )]
    NotAtRest {
        cell: String,
        seconds: f64,
        speed: f64,
    },
    #[error("starting the controller liveness thread failed")]
    Thread(#[source] std::io::Error),
}

/// Settings of the host cell.
#[derive(Clone, Debug)]
pub struct CellConfig {
    /// Cell name: the services are `prf/<cell>/…`.
    pub cell: String,
    pub executor: ExecutorConfig,
    /// Milliseconds without a new joint state after which the cell asks iceoryx2 whether the
    /// controller's process is alive, and stops with a fault if it is not.
    pub dead_after_ms: f64,
    /// Milliseconds without a fresh joint state after which the cell stops with a fault even
    /// though the controller's process is alive, counted while the cell listened (its own
    /// stalls are not the controller's silence: [`crate::stall`]). A joint state stamped
    /// more than this before (or after) it arrives is stale: it is counted and not used.
    pub silent_after_ms: f64,
    /// How long to wait for the controller's first joint state.
    pub connect_timeout: std::time::Duration,
    /// Stop (brake, end the session) after this long, if set.
    pub stop_after: Option<std::time::Duration>,
    /// Allocations so far on the calling thread, if the binary counts them: the report then
    /// gives the loop's own ([`CellReport::loop_allocations`]).
    pub alloc_probe: Option<fn() -> u64>,
    /// How the loop thread waits for its tick.
    pub wait: pacing::Wait,
    /// Run the loop thread as `SCHED_FIFO` at this priority with memory locked, where the
    /// process may (it falls back to normal scheduling otherwise; the report says which).
    pub realtime: Option<i32>,
}

impl CellConfig {
    pub fn new(cell: &str) -> Self {
        CellConfig {
            cell: cell.to_string(),
            executor: ExecutorConfig::default(),
            dead_after_ms: 3.0,
            silent_after_ms: 100.0,
            connect_timeout: std::time::Duration::from_secs(5),
            stop_after: None,
            alloc_probe: None,
            wait: pacing::Wait::default(),
            realtime: None,
        }
    }
}

/// What one execution did.
#[derive(Clone, Debug, Default, Serialize)]
pub struct CellReport {
    pub ticks: u64,
    pub duration_s: f64,
    /// Every segment of the program completed.
    pub completed: bool,
    /// Stopped on request (`stop_after`) before completion, without a fault.
    pub stopped: bool,
    /// Why the cell stopped early, if it did.
    pub fault: Option<String>,
    /// When the fault was detected, CLOCK_MONOTONIC ns.
    pub fault_t_ns: Option<u64>,
    /// Largest |reference − measured| of any joint the controller reported, rad.
    pub max_tracking_error: f64,
    /// Setpoints the controller saw lost, repeated or refused.
    pub lost: u32,
    pub repeated: u32,
    pub rejected: u32,
    /// Joint states that came stamped more than `silent_after_ms` away from the cell's clock,
    /// and were not used.
    pub stale_states: u64,
    /// Setpoints published after the end of their 1 ms period.
    pub deadline_misses: u64,
    /// The loop's own stalls (gaps between its polls longer than
    /// [`crate::stall::OWN_STALL`]: its process or the host stopped), and the longest, ms.
    pub own_stalls: u64,
    pub longest_own_stall_ms: f64,
    /// Ticks skipped after the loop's own stalls because the controller was stopped too
    /// ([`crate::stall::ticks_to_skip`]): neither the stream nor the controller moved.
    pub skipped_ticks: u64,
    /// Wake-up lateness after the scheduled tick, µs: p50, p99, p99.9, max.
    pub wake_late_us: [f64; 4],
    /// Setpoint one-way latency cell → controller, µs: p50, p99, p99.9, max.
    pub latency_us: [f64; 4],
    /// Ticks whose setpoint the output stage had to change to stay within the limits (0 for a
    /// planned program: it is emitted as certified), and the largest change, rad.
    pub shaped: u64,
    pub max_shaping: f64,
    /// Smallest clearance the controller measured while the platform drove on its floor map,
    /// m (None: no drive on a map).
    pub min_drive_clearance: Option<f64>,
    /// Allocations on the loop's thread from its first tick to its last (with
    /// [`CellConfig::alloc_probe`]).
    pub loop_allocations: Option<u64>,
    /// How the loop was paced: the wait and what real-time scheduling was granted.
    pub pacing: String,
    /// Peak limit ratios of the emitted stream (1 ms finite differences).
    #[serde(serialize_with = "ratios_json")]
    pub emitted: LimitRatios,
}

/// The limit ratios as a JSON object.
fn ratios_json<S: serde::Serializer>(r: &LimitRatios, s: S) -> Result<S::Ok, S::Error> {
    use serde::ser::SerializeMap;
    let mut m = s.serialize_map(Some(4))?;
    m.serialize_entry("position", &r.position)?;
    m.serialize_entry("speed", &r.speed)?;
    m.serialize_entry("acceleration", &r.acceleration)?;
    m.serialize_entry("jerk", &r.jerk)?;
    m.end()
}

impl CellReport {
    /// One line: "11.2 s, emitted at 0.961 of the limits …, max tracking error 1.30 mrad, lost
    /// 0, …, setpoint latency p50 …".
    pub fn summary(&self) -> String {
        let drives = self.min_drive_clearance.map_or(String::new(), |c| {
            format!(", drives kept ≥ {:.1} mm from every obstacle", c * 1e3)
        });
        let stalls = if self.own_stalls > 0 {
            format!(
                ", the loop itself stalled {} times (longest {:.1} ms; {} ticks skipped with the controller, stopped too)",
                self.own_stalls, self.longest_own_stall_ms, self.skipped_ticks
            )
        } else {
            String::new()
        };
        let allocations = self.loop_allocations.map_or(String::new(), |n| {
            format!(
                ", {n} allocations in the loop ({:.2} per tick)",
                n as f64 / self.ticks.max(1) as f64
            )
        });
        format!(
            "{:.1} s, emitted at {:.3} of the limits (acceleration {:.3}, jerk {:.3}), {} ticks shaped (max {:.2} mrad), max tracking error {:.2} mrad, lost {}, repeated {}, refused {}, deadline misses {}, wake-up late p50 {:.0} µs p99 {:.0} µs max {:.0} µs, setpoint latency p50 {:.1} µs p99 {:.1} µs max {:.0} µs{}{}{}",
            self.duration_s,
            self.emitted.max(),
            self.emitted.acceleration,
            self.emitted.jerk,
            self.shaped,
            self.max_shaping * 1e3,
            self.max_tracking_error * 1e3,
            self.lost,
            self.repeated,
            self.rejected,
            self.deadline_misses,
            self.wake_late_us[0],
            self.wake_late_us[1],
            self.wake_late_us[3],
            self.latency_us[0],
            self.latency_us[1],
            self.latency_us[3],
            drives,
            stalls,
            allocations
        )
    }
}

/// The host cell's connection to its controller, kept across tasks.
pub struct Cell {
    _node: iceoryx2::node::Node<Ipc>,
    ports: CellPorts,
    pub cfg: CellConfig,
    limits: MotionLimits,
    last: JointStateMsg,
    liveness: Liveness,
    /// Stale joint states received (see [`CellConfig::silent_after_ms`]), and the largest gap
    /// between a stale one's stamp and its arrival, ms.
    stale: u64,
    stale_ms: f64,
}

/// Timing samples of one execution, allocated and touched before the loop (no page faults
/// inside it): at most 10 minutes at 1 kHz.
struct Timing {
    late: Vec<f64>,
    latency: Vec<f64>,
    n_late: usize,
    n_latency: usize,
}

impl Timing {
    const CAP: usize = 600_000;

    fn new() -> Self {
        // A non-zero fill writes every page now; a zero fill would come from calloc as
        // untouched pages, each faulting in on its first sample inside the loop.
        Timing {
            late: vec![-1.0; Self::CAP],
            latency: vec![-1.0; Self::CAP],
            n_late: 0,
            n_latency: 0,
        }
    }

    fn push(v: &mut [f64], n: &mut usize, x: f64) {
        if let Some(slot) = v.get_mut(*n) {
            *slot = x;
            *n += 1;
        }
    }

    fn late(&mut self, us: f64) {
        Self::push(&mut self.late, &mut self.n_late, us);
    }

    fn latency(&mut self, us: f64) {
        Self::push(&mut self.latency, &mut self.n_latency, us);
    }

    fn into_report(mut self, report: &mut CellReport) {
        report.wake_late_us = stats::percentiles(&mut self.late[..self.n_late]);
        report.latency_us = stats::percentiles(&mut self.latency[..self.n_latency]);
    }
}

impl Cell {
    /// Opens the services and waits for the controller's first joint state.
    pub fn connect(cfg: CellConfig, rt: &Runtime<'_>) -> Result<Self, CellError> {
        let node = link::node(&format!("prf-cell-{}", std::process::id()))?;
        let ports = CellPorts::open(&node, &cfg.cell)?;
        let t0 = std::time::Instant::now();
        let last = loop {
            if let Some(js) = ports.newest()? {
                break js;
            }
            if t0.elapsed() > cfg.connect_timeout {
                return Err(CellError::NoController {
                    cell: cfg.cell.clone(),
                    seconds: cfg.connect_timeout.as_secs_f64(),
                });
            }
            std::thread::sleep(std::time::Duration::from_millis(1));
        };
        let liveness = Liveness::start(&cfg.cell).map_err(CellError::Thread)?;
        Ok(Cell {
            _node: node,
            ports,
            cfg,
            limits: MotionLimits::kmr_iiwa(&rt.model),
            last,
            liveness,
            stale: 0,
            stale_ms: 0.0,
        })
    }

    /// Tells the controller to exit.
    pub fn shutdown(&self) -> Result<(), CellError> {
        self.ports.send(SetpointMsg {
            t_ns: now_ns(),
            flags: flags::SHUTDOWN,
            ..SetpointMsg::default()
        })?;
        Ok(())
    }

    /// Runs `program` from the platform at `home` in real time until it completes or faults:
    /// per tick receive → executor step through the output stage → send.
    pub fn execute(
        &mut self,
        rt: &Runtime<'_>,
        program: &Program,
        home: &Pose,
    ) -> Result<CellReport, CellError> {
        let mut reversal = Box::new(Reversal::new());
        let ex = Executor::new(rt, program.clone(), home, self.cfg.executor, &mut reversal);
        self.drive(ex)
    }

    /// The state the controller reported last.
    pub fn measured(&self) -> Measured {
        measured(&self.last)
    }

    /// Waits up to `timeout` for a fresh joint state with the arm at rest (after a fault the
    /// controller may still be braking, or silent): the state a recovery starts from.
    pub fn wait_at_rest(&mut self, timeout: std::time::Duration) -> Result<Measured, CellError> {
        let t0 = std::time::Instant::now();
        loop {
            if self.receive()? && self.last.qd.iter().all(|v| v.abs() < 1e-4) {
                return Ok(self.measured());
            }
            if t0.elapsed() > timeout {
                return Err(CellError::NotAtRest {
                    cell: self.cfg.cell.clone(),
                    seconds: timeout.as_secs_f64(),
                    speed: self.last.qd.iter().fold(0.0, |m, v| v.abs().max(m)),
                });
            }
            std::thread::sleep(std::time::Duration::from_millis(1));
        }
    }

    /// Runs a recovery program ([`prf_runtime::recover`]) from the state the controller
    /// reported last, like [`Cell::execute`].
    pub fn resume(
        &mut self,
        rt: &Runtime<'_>,
        program: &Program,
        home: &Pose,
    ) -> Result<CellReport, CellError> {
        let mut reversal = Box::new(Reversal::new());
        let start = self.measured();
        let cfg = self.cfg.executor;
        let ex = Executor::resuming(rt, program.clone(), home, &start, cfg, &mut reversal);
        self.drive(ex)
    }

    /// The real-time loop: per tick receive → `ex` step through the output stage → send.
    fn drive(&mut self, mut ex: Executor<'_, '_>) -> Result<CellReport, CellError> {
        let mut stage = OutputStage::new(&self.last.q, &self.limits, measured(&self.last));
        let period = Duration::from_hz(1000);
        let mut timing = Timing::new();
        let mut report = CellReport::default();
        let realtime = self.cfg.realtime.map(realtime::RealTime::enter);
        let parker = pacing::Parker::new(self.cfg.wait);
        report.pacing = match &realtime {
            Some(r) => format!("{}; {}", self.cfg.wait, r.status),
            None => format!("{}; normal scheduling", self.cfg.wait),
        };
        (self.stale, self.stale_ms) = (0, 0.0);
        let mut silence = Silence::new(std::time::Instant::now());
        let mut asked = None;
        let mut seen_sp = 0u64;
        // A joint state of this session: stamped after it began and acknowledging one of its
        // setpoints. Until one comes, the controller may still report the last session's stop
        // (a recovery starts after a watchdog trip).
        let begun = now_ns();
        let mut acknowledged = false;
        let stop_ticks = self.cfg.stop_after.map(|d| d.as_millis() as u64);
        self.ports.connect()?;
        let mut ticker = Ticker::every(period);
        let probe = self.cfg.alloc_probe;
        let allocations_before = probe.map(|f| f());
        // The schedule's origin: moved on by the ticks skipped with a stopped controller.
        let mut t0 = Instant::now();
        let mut k = 0u64;
        loop {
            parker.block_on(ticker.next());
            k += 1;
            let scheduled = t0 + period * k as u32;
            let woke = Instant::now();
            let late = woke.saturating_duration_since(scheduled);
            timing.late(late.as_micros() as f64);
            let cycles_before = self.last.seq;
            let fresh = self.receive()?;
            silence.poll(std::time::Instant::now(), fresh);
            if fresh {
                asked = None;
            }
            // After the cell's own stall, the ticks a stopped controller did not run are
            // skipped, not burst out (crate::stall).
            if silence.after_stall() {
                let missed = late.as_ticks() / period.as_ticks();
                let cycles = self.last.seq.saturating_sub(cycles_before);
                let skip = stall::ticks_to_skip(missed, cycles);
                if skip > 0 {
                    t0 += period * skip as u32;
                    ticker.reset_at(t0 + period * k as u32);
                    report.skipped_ticks += skip;
                }
            }
            let js = self.last;
            acknowledged |= js.t_ns >= begun && (1..=k).contains(&js.setpoint_seq);
            if acknowledged && js.setpoint_seq > seen_sp && js.setpoint_seq <= k {
                seen_sp = js.setpoint_seq;
                timing.latency(js.setpoint_latency_ns as f64 * 1e-3);
                report.max_tracking_error = report.max_tracking_error.max(js.tracking_error);
                if js.drive_clearance.is_finite() {
                    let m = report.min_drive_clearance.get_or_insert(js.drive_clearance);
                    *m = m.min(js.drive_clearance);
                }
                (report.lost, report.repeated, report.rejected) =
                    (js.lost, js.repeated, js.rejected);
            }
            // Silence in wall time, not ticks: after a late wake-up the ticker catches up with
            // ticks in quick succession, faster than the controller answers. The cell's own
            // stalls are not counted (crate::stall).
            if let Some(why) = self.controller_stop(&silence, &mut asked, acknowledged) {
                // No controller to brake with: nothing more is sent.
                report.fault = Some(why);
                report.fault_t_ns = Some(now_ns());
                break;
            }
            stage.set_measured(measured(&js));
            if stop_ticks.is_some_and(|n| k >= n) {
                stage.stop();
            }
            let sp = ex.step(woke, &mut stage)?;
            if sp.mode == Mode::Fault || stage.stopping() {
                if let (None, Some(f)) = (&report.fault, ex.fault()) {
                    report.fault = Some(format!("executor: {f}"));
                    report.fault_t_ns = Some(now_ns());
                }
                report.stopped = stage.stopping();
            }
            let finished =
                (ex.done() || report.fault.is_some() || stage.stopping()) && stage.settled();
            self.send(k, &sp, stage.output(), report.fault.is_some(), finished)?;
            if Instant::now() > scheduled + period {
                report.deadline_misses += 1;
            }
            if finished {
                report.completed = ex.done();
                break;
            }
        }
        report.loop_allocations = probe.zip(allocations_before).map(|(f, a)| f() - a);
        drop(parker);
        drop(realtime);
        report.ticks = k;
        report.stale_states = self.stale;
        let (stalls, longest) = silence.own_stalls();
        report.own_stalls = stalls;
        report.longest_own_stall_ms = longest.as_secs_f64() * 1e3;
        report.duration_s = k as f64 * 1e-3;
        (report.shaped, report.max_shaping) = stage.shaped();
        report.emitted = stage.ratios();
        timing.into_report(&mut report);
        Ok(report)
    }

    /// Takes the newest joint state, if a fresh one came since the last tick; a stale one is
    /// counted and dropped.
    fn receive(&mut self) -> Result<bool, CellError> {
        let Some(js) = self.ports.newest()? else {
            return Ok(false);
        };
        let gap_ms = now_ns().abs_diff(js.t_ns) as f64 * 1e-6;
        if gap_ms > self.cfg.silent_after_ms {
            self.stale += 1;
            self.stale_ms = self.stale_ms.max(gap_ms);
            return Ok(false);
        }
        self.last = js;
        Ok(true)
    }

    /// Why the controller can no longer be commanded, after its `silence` (without a joint
    /// state while the cell listened): it is dead or silent, or it stopped the arm
    /// itself (watchdog, refused setpoint).
    /// Its process having exited stops the cell at once ([`Liveness::exited`]); without a
    /// pidfd, after `dead_after_ms` of silence the liveness helper is asked once (`asked`
    /// holds the question until a joint state comes), and its answer "dead" stops the cell.
    /// Its stop flags count once it has `acknowledged` this session.
    fn controller_stop(
        &self,
        silence: &Silence,
        asked: &mut Option<u64>,
        acknowledged: bool,
    ) -> Option<String> {
        let js = &self.last;
        let silent = silence.listened().as_secs_f64() * 1e3;
        let dead = self.liveness.exited()
            || silent >= self.cfg.silent_after_ms
            || (silent >= self.cfg.dead_after_ms && {
                let q = *asked.get_or_insert_with(|| self.liveness.ask());
                self.liveness.answer(q) == Some(false)
            });
        if dead {
            let stale = if self.stale > 0 {
                format!(
                    "; {} stale ones came, stamped up to {:.1} ms from their arrival",
                    self.stale, self.stale_ms
                )
            } else {
                String::new()
            };
            let unheard = silence.unheard();
            let unheard = if unheard.is_zero() {
                String::new()
            } else {
                format!(
                    "; the cell's own stalls since then, {:.1} ms, not counted",
                    unheard.as_secs_f64() * 1e3
                )
            };
            Some(format!(
                "firmware-sim {}: no fresh joint state for {silent:.1} ms (last seq {}{stale}{unheard})",
                if silent >= self.cfg.silent_after_ms {
                    "silent"
                } else {
                    "dead"
                },
                js.seq
            ))
        } else if js.status & (status::WATCHDOG | status::REJECTED) != 0 && acknowledged {
            Some(format!(
                "firmware-sim stopped the arm: {}",
                if js.status & status::WATCHDOG != 0 {
                    "watchdog"
                } else {
                    "setpoint refused"
                }
            ))
        } else if js.status & status::NO_PATH != 0 {
            Some(format!(
                "firmware-sim: the platform has no collision-free path to its goal; it holds at ({:.3} m, {:.3} m, {:.1}°) (the controller's log says why)",
                js.base[0],
                js.base[1],
                js.base[2].to_degrees()
            ))
        } else {
            None
        }
    }

    /// Publishes tick `k`'s output-stage state with the executor's mode and gripper command.
    fn send(
        &self,
        k: u64,
        sp: &Setpoint,
        (q, qd): ([f64; NA], [f64; NA]),
        fault: bool,
        last: bool,
    ) -> Result<(), CellError> {
        let mut f = if k == 1 { flags::FIRST } else { 0 };
        if sp.close_gripper {
            f |= flags::GRIPPER_CLOSE;
        }
        if fault {
            f |= flags::FAULT;
        }
        if last {
            f |= flags::LAST;
        }
        self.ports.send(SetpointMsg {
            seq: k,
            t_ns: now_ns(),
            q,
            qd,
            base_goal: sp.base_goal,
            mode: sp.mode as u32,
            flags: f,
        })?;
        Ok(())
    }
}

/// The executor's measured state from a joint state message.
fn measured(js: &JointStateMsg) -> Measured {
    Measured {
        arm: js.q,
        base: js.base,
        gripper: js.gripper,
    }
}
