//! The host cell: the no_std runtime's executor in a 1 kHz loop paced by embassy-time, each
//! setpoint passed through a Ruckig output stage (the iiwa's speed, acceleration and jerk
//! limits) and sent over iceoryx2 shared memory to the joint controller (`firmware-sim`),
//! whose joint state comes back as the executor's measured state.
//!
//! Per tick: wake (Ticker) → newest joint state → executor tick → Ruckig → publish + wake the
//! controller. A controller that goes silent for `silent_cycles` ticks, or reports that its
//! watchdog or its limit check stopped the arm, stops the cell with a fault. Deadline misses
//! (a setpoint published after its 1 ms period ended) are counted, never hidden.

pub mod pacing;
pub mod stats;

use anyhow::{Result, bail};
use embassy_time::{Duration, Instant, Ticker};
use prf_firmware_sim::clock::now_ns;
use prf_firmware_sim::link::{self, CellPorts, Ipc};
use prf_firmware_sim::motion::Online;
use prf_runtime::Runtime;
use prf_runtime::executor::{Executor, ExecutorConfig, Measured, Mode};
use prf_runtime::program::Program;
use prf_runtime::reverse::Reversal;
use prf_shared::ipc::{JointStateMsg, SetpointMsg, flags, mode, status};
use prf_shared::limits::MotionLimits;
use prf_shared::se3::Pose;
use serde::Serialize;

/// Position gain of the Ruckig output stage, 1/s (see [`Online::track`]).
pub const TRACKING_GAIN: f64 = 20.0;

/// Settings of the host cell.
#[derive(Clone, Debug)]
pub struct CellConfig {
    /// Cell name: the services are `prf/<cell>/…`.
    pub cell: String,
    pub executor: ExecutorConfig,
    /// Milliseconds without a new joint state after which the cell asks iceoryx2 whether the
    /// controller's process is alive, and stops with a fault if it is not.
    pub dead_after_ms: f64,
    /// Milliseconds without a new joint state after which the cell stops with a fault even
    /// though the controller's process is alive.
    pub silent_after_ms: f64,
    /// How long to wait for the controller's first joint state.
    pub connect_timeout: std::time::Duration,
    /// Stop (brake, end the session) after this long, if set.
    pub stop_after: Option<std::time::Duration>,
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
    /// Setpoints published after the end of their 1 ms period.
    pub deadline_misses: u64,
    /// Wake-up lateness after the scheduled tick, µs: p50, p99, p99.9, max.
    pub wake_late_us: [f64; 4],
    /// Setpoint one-way latency cell → controller, µs: p50, p99, p99.9, max.
    pub latency_us: [f64; 4],
}

/// The host cell's connection to its controller, kept across tasks.
pub struct Cell {
    _node: iceoryx2::node::Node<Ipc>,
    ports: CellPorts,
    pub cfg: CellConfig,
    limits: MotionLimits,
    last: JointStateMsg,
}

impl Cell {
    /// Opens the services and waits for the controller's first joint state.
    pub fn connect(cfg: CellConfig, rt: &Runtime<'_>) -> Result<Self> {
        let node = link::node(&format!("prf-cell-{}", std::process::id()))?;
        let ports = CellPorts::open(&node, &cfg.cell)?;
        let t0 = std::time::Instant::now();
        let last = loop {
            if let Some(js) = ports.newest()? {
                break js;
            }
            if t0.elapsed() > cfg.connect_timeout {
                bail!(
                    "no joint state on prf/{}/joint-state within {:.1} s: is `prf firmware-sim --cell {}` running?",
                    cfg.cell,
                    cfg.connect_timeout.as_secs_f64(),
                    cfg.cell
                );
            }
            std::thread::sleep(std::time::Duration::from_millis(1));
        };
        Ok(Cell {
            _node: node,
            ports,
            cfg,
            limits: MotionLimits::kmr_iiwa(&rt.model),
            last,
        })
    }

    /// Tells the controller to exit.
    pub fn shutdown(&self) -> Result<()> {
        self.ports.send(SetpointMsg {
            t_ns: now_ns(),
            flags: flags::SHUTDOWN,
            ..SetpointMsg::default()
        })
    }

    /// Runs `program` from the platform at `home` in real time until it completes or faults.
    pub fn execute(
        &mut self,
        rt: &Runtime<'_>,
        program: &Program,
        home: &Pose,
    ) -> Result<CellReport> {
        let mut reversal = Box::new(Reversal::new());
        let mut ex = Executor::new(rt, program.clone(), home, self.cfg.executor, &mut reversal);
        let l = &self.limits;
        let mut out = Online::new(&self.last.q, &l.arm_speed, &l.arm_acceleration, &l.arm_jerk);
        let period = Duration::from_hz(1000);
        // At most 10 minutes of timing samples, allocated and touched before the loop (no
        // page faults inside it).
        let cap = 600_000;
        let (mut late, mut latency) = (vec![0.0f64; cap], vec![0.0f64; cap]);
        let (mut n_late, mut n_latency) = (0usize, 0usize);
        let mut report = CellReport::default();
        let parker = pacing::Parker::new();
        let mut last_rx = std::time::Instant::now();
        let mut seen_sp = 0u64;
        let stop_ticks = self.cfg.stop_after.map(|d| d.as_millis() as u64);
        let mut ticker = Ticker::every(period);
        let t0 = Instant::now();
        let mut k = 0u64;
        loop {
            parker.block_on(ticker.next());
            k += 1;
            let scheduled = t0 + period * k as u32;
            let woke = Instant::now();
            if n_late < cap {
                late[n_late] = woke.saturating_duration_since(scheduled).as_micros() as f64;
                n_late += 1;
            }
            if let Some(js) = self.ports.newest()? {
                self.last = js;
                last_rx = std::time::Instant::now();
            }
            // Silence in wall time, not ticks: after a late wake-up the ticker catches up with
            // ticks in quick succession, faster than the controller answers.
            let silent = last_rx.elapsed().as_secs_f64() * 1e3;
            let js = self.last;
            if js.setpoint_seq > seen_sp && js.setpoint_seq <= k {
                seen_sp = js.setpoint_seq;
                if n_latency < cap {
                    latency[n_latency] = js.setpoint_latency_ns as f64 * 1e-3;
                    n_latency += 1;
                }
                report.max_tracking_error = report.max_tracking_error.max(js.tracking_error);
                (report.lost, report.repeated, report.rejected) =
                    (js.lost, js.repeated, js.rejected);
            }
            let dead = silent >= self.cfg.dead_after_ms
                && (silent >= self.cfg.silent_after_ms || !link::controller_alive(&self.cfg.cell)?);
            let stop = if dead {
                Some(format!(
                    "firmware-sim {}: no joint state for {silent:.1} ms (last seq {})",
                    if silent >= self.cfg.silent_after_ms {
                        "silent"
                    } else {
                        "dead"
                    },
                    js.seq
                ))
            } else if js.status & (status::WATCHDOG | status::REJECTED) != 0 && js.setpoint_seq > 0
            {
                Some(format!(
                    "firmware-sim stopped the arm: {}",
                    if js.status & status::WATCHDOG != 0 {
                        "watchdog"
                    } else {
                        "setpoint refused"
                    }
                ))
            } else {
                None
            };
            if let Some(why) = stop {
                // No controller to brake with: nothing more is sent.
                report.fault = Some(why);
                report.fault_t_ns = Some(now_ns());
                break;
            }
            let measured = Measured {
                arm: js.q,
                base: js.base,
                gripper: js.gripper,
            };
            let sp = ex.tick(woke, &measured);
            let stopping = stop_ticks.is_some_and(|n| k >= n);
            if sp.mode == Mode::Fault || stopping {
                if let (None, Some(f)) = (&report.fault, ex.fault()) {
                    report.fault = Some(format!("executor: {f}"));
                    report.fault_t_ns = Some(now_ns());
                }
                report.stopped = stopping;
                out.brake();
            } else {
                out.track(&sp.arm, &sp.arm_velocity, TRACKING_GAIN);
            }
            let settled = out.step()?;
            let finished = (ex.done() || report.fault.is_some() || stopping) && settled;
            let mut f = if k == 1 { flags::FIRST } else { 0 };
            if sp.close_gripper {
                f |= flags::GRIPPER_CLOSE;
            }
            if report.fault.is_some() {
                f |= flags::FAULT;
            }
            if finished {
                f |= flags::LAST;
            }
            self.ports.send(SetpointMsg {
                seq: k,
                t_ns: now_ns(),
                q: core::array::from_fn(|j| out.position()[j]),
                qd: core::array::from_fn(|j| out.velocity()[j]),
                base_goal: sp.base_goal,
                mode: match sp.mode {
                    Mode::Base => mode::BASE,
                    Mode::Arm => mode::ARM,
                    Mode::Gripper => mode::GRIPPER,
                    Mode::Done => mode::DONE,
                    Mode::Fault => mode::FAULT,
                },
                flags: f,
            })?;
            if Instant::now() > scheduled + period {
                report.deadline_misses += 1;
            }
            if finished {
                report.completed = ex.done();
                break;
            }
        }
        report.ticks = k;
        report.duration_s = k as f64 * 1e-3;
        report.wake_late_us = stats::percentiles(&mut late[..n_late]);
        report.latency_us = stats::percentiles(&mut latency[..n_latency]);
        Ok(report)
    }
}
