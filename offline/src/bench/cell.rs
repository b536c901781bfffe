//! `prf bench-cell`: the host cell's figures. (1) Setpoint one-way latency from this process
//! to a peer process through iceoryx2 against a Unix-domain datagram socket with the same
//! payload size, in the same run: 1 kHz sends, the peer asleep between messages (woken by an
//! iceoryx2 event / by the socket) and, for iceoryx2, also a peer that polls. (2) The 1 kHz
//! loop against firmware-sim for `--loop` seconds: wake-up lateness, deadline misses,
//! latency, beside a probe of the machine's own stalls ([`crate::bench::stall_probe`]).
//! (3) Ruckig's per-update time and allocations in the output stage.

use crate::bench::alloc_count::allocations;
use crate::bench::stall_probe::StallProbe;
use crate::cli::args::{read_blob, runtime};
use crate::cli::child::{ChildGuard, spawn_firmware};
use anyhow::{Context, Result, anyhow, bail};
use prf_host::cell::{Cell, CellConfig};
use prf_host::ideal::execute;
use prf_host::pacing::Wait;
use prf_host::stats::percentiles;
use prf_ipc::clock::now_ns;
use prf_ipc::link;
use prf_ipc::messages::SetpointMsg;
use prf_ruckig::{Online, RuckigError, TRACKING_GAIN, baseline};
use prf_runtime::executor::{ExecutorConfig, planar};
use prf_runtime::plan::plan;
use prf_shared::limits::MotionLimits;
use prf_sim::tasks::FloorTask;
use prf_sim::world::World;
use std::io::BufRead;
use std::os::unix::net::UnixDatagram;
use std::path::PathBuf;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

#[derive(clap::Args, Debug)]
pub struct Args {
    /// The blob (from `prf learn` or `prf demo`).
    pub blob: PathBuf,
    /// Messages per transport in the latency comparison (sent at 1 kHz).
    #[arg(long, default_value_t = 5000)]
    pub messages: u64,
    /// Seconds of the 1 kHz loop against firmware-sim, per pacing (three pacings).
    #[arg(long, default_value_t = 60.0)]
    pub loop_seconds: f64,
    /// Busy-wait this long before each tick in the real-time pacing (µs).
    #[arg(long, default_value_t = 0)]
    pub spin_us: u64,
}

/// SCHED_FIFO priority of the loop thread in the real-time pacing.
const REALTIME_PRIORITY: i32 = 80;

/// The receiving side of the latency comparison (a child process of `prf bench-cell`).
#[derive(clap::Args, Debug)]
pub struct PeerArgs {
    /// iceoryx2-event, iceoryx2-poll or uds.
    pub transport: String,
    /// Service name or socket path.
    pub name: String,
}

const PAYLOAD: usize = std::mem::size_of::<SetpointMsg>();
const END: u64 = u64::MAX;

/// A setpoint's bytes for the socket: seq and t_ns, then the rest of the payload's size.
fn encode(seq: u64, t_ns: u64) -> [u8; PAYLOAD] {
    let mut b = [0u8; PAYLOAD];
    b[..8].copy_from_slice(&seq.to_le_bytes());
    b[8..16].copy_from_slice(&t_ns.to_le_bytes());
    b
}

fn header(b: &[u8]) -> (u64, u64) {
    let word = |i: usize| u64::from_le_bytes(b[i..i + 8].try_into().unwrap_or([0; 8]));
    (word(0), word(8))
}

/// Receives until the END message, then prints "count p50 p99 p999 max" (µs) on stdout.
pub fn peer(a: &PeerArgs) -> Result<()> {
    let mut lat = Vec::with_capacity(1 << 20);
    match a.transport.as_str() {
        "uds" => {
            let sock = UnixDatagram::bind(&a.name).with_context(|| format!("bind {}", a.name))?;
            println!("ready");
            let mut buf = [0u8; PAYLOAD];
            loop {
                let n = sock.recv(&mut buf)?;
                let now = now_ns();
                let (seq, t) = header(&buf[..n]);
                if seq == END {
                    break;
                }
                lat.push(now.saturating_sub(t) as f64 * 1e-3);
            }
        }
        t @ ("iceoryx2-event" | "iceoryx2-poll") => {
            let node = link::node(&format!("prf-bench-peer-{}", std::process::id()))?;
            let ports = link::ControllerPorts::open(&node, &a.name)?;
            println!("ready");
            let poll = t == "iceoryx2-poll";
            'outer: loop {
                if !poll {
                    ports
                        .ready
                        .blocking_wait(|_| {})
                        .map_err(|e| anyhow!("wait: {e:?}"))?;
                }
                while let Some(s) = ports.setpoint.receive().map_err(|e| anyhow!("{e:?}"))? {
                    let now = now_ns();
                    if s.seq == END {
                        break 'outer;
                    }
                    lat.push(now.saturating_sub(s.t_ns) as f64 * 1e-3);
                }
                if poll {
                    std::hint::spin_loop();
                }
            }
        }
        other => bail!("unknown transport {other:?}"),
    }
    let p = percentiles(&mut lat);
    println!("{} {} {} {} {}", lat.len(), p[0], p[1], p[2], p[3]);
    Ok(())
}

/// One transport: start the peer, send `n` messages at 1 kHz, collect its percentiles.
fn latency(transport: &str, n: u64) -> Result<[f64; 5]> {
    let name = match transport {
        "uds" => std::env::temp_dir()
            .join(format!("prf-bench-{}.sock", std::process::id()))
            .to_string_lossy()
            .into_owned(),
        _ => format!("bench-{}-{transport}", std::process::id()),
    };
    let _ = std::fs::remove_file(&name);
    let mut child = ChildGuard(
        Command::new(std::env::current_exe()?)
            .args(["ipc-peer", transport, &name])
            .stdout(Stdio::piped())
            .spawn()?,
    );
    let mut lines = std::io::BufReader::new(child.0.stdout.take().context("peer stdout")?).lines();
    if lines.next().transpose()?.as_deref() != Some("ready") {
        bail!("{transport} peer did not start");
    }
    let node = link::node(&format!("prf-bench-{}", std::process::id()))?;
    let send: Box<dyn Fn(u64) -> Result<()>> = if transport == "uds" {
        let sock = UnixDatagram::unbound()?;
        sock.connect(&name)?;
        Box::new(move |seq| {
            sock.send(&encode(seq, now_ns()))?;
            Ok(())
        })
    } else {
        let ports = link::CellPorts::open(&node, &name)?;
        Box::new(move |seq| {
            ports.send(SetpointMsg {
                seq,
                t_ns: now_ns(),
                ..SetpointMsg::default()
            })?;
            Ok(())
        })
    };
    let t0 = Instant::now();
    for k in 1..=n {
        let due = t0 + Duration::from_millis(k);
        std::thread::sleep(due.saturating_duration_since(Instant::now()));
        send(k)?;
    }
    std::thread::sleep(Duration::from_millis(5));
    send(END)?;
    let line = lines.next().transpose()?.context("peer result")?;
    let v: Vec<f64> = line
        .split_whitespace()
        .map(|x| x.parse::<f64>())
        .collect::<Result<_, _>>()?;
    let _ = std::fs::remove_file(&name);
    match v[..] {
        [c, a, b, d, e] => Ok([c, a, b, d, e]),
        _ => bail!("peer printed {line:?}"),
    }
}

pub fn run(a: &Args) -> Result<()> {
    // (1) Latency.
    println!(
        "setpoint one-way latency, {} messages of {PAYLOAD} B at 1 kHz to a peer process (µs)",
        a.messages
    );
    println!(
        "  {:<34} {:>8} {:>8} {:>8} {:>8}",
        "transport", "p50", "p99", "p99.9", "max"
    );
    let mut rows = Vec::new();
    for (t, label) in [
        ("uds", "Unix datagram socket, blocking recv"),
        ("iceoryx2-event", "iceoryx2, peer woken by event"),
        ("iceoryx2-poll", "iceoryx2, peer polling"),
    ] {
        let r = latency(t, a.messages)?;
        println!(
            "  {label:<34} {:>8.1} {:>8.1} {:>8.1} {:>8.1}",
            r[1], r[2], r[3], r[4]
        );
        rows.push(r);
    }
    println!(
        "  p50 ratio to the socket: iceoryx2 event {:.2}, iceoryx2 polling {:.2}",
        rows[1][1] / rows[0][1],
        rows[2][1] / rows[0][1]
    );

    // (3) Ruckig in the output stage, on a real program.
    let bytes = read_blob(&a.blob)?;
    let rt = runtime(&bytes, &a.blob, Default::default())?;
    let world = World::example();
    let ft = FloorTask::new(&world, "Part1", "CNC1", "CNC2")?;
    let p = plan(&rt, &ft.task()).map_err(|e| anyhow!("task {}: {e}", ft.label()))?;
    let program = p.program.context("no program")?;
    let ideal = execute(&rt, &program, &ft.home, ExecutorConfig::default(), 1 << 24);
    let l = MotionLimits::kmr_iiwa(&rt.model);
    let q0 = &rt.model.home;
    let (v, acc, j) = (&l.arm_speed, &l.arm_acceleration, &l.arm_jerk);
    let mut shim = Online::new(q0, v, acc, j);
    let mut crate_ = baseline::Online::new(q0, v, acc, j);
    // Alternating passes over the same setpoints, so both meet the same machine load.
    let (mut t_shim, mut t_crate) = (Vec::new(), Vec::new());
    let (mut a_shim, mut a_crate) = (0, 0);
    for _ in 0..3 {
        a_shim += track_program(&mut shim, &ideal.setpoints, &mut t_shim)?;
        a_crate += track_program(&mut crate_, &ideal.setpoints, &mut t_crate)?;
    }
    let n = t_shim.len() as f64;
    let (r_shim, r_crate) = (percentiles(&mut t_shim), percentiles(&mut t_crate));
    println!(
        "\nRuckig as the output stage's safety net (7 axes, velocity interface; a planned program passes without it), 3 × {} updates along a {:.1} s program, per update:",
        ideal.setpoints.len(),
        ideal.setpoints.len() as f64 * 1e-3
    );
    println!(
        "  {:<44} {:>8} {:>8} {:>8} {:>12}",
        "", "p50 µs", "p99 µs", "max µs", "allocations"
    );
    for (label, r, allocs) in [
        ("project's shim (prf_ruckig::Online<7>)", &r_shim, a_shim),
        ("`ruckig` crate (cxx wrapper, baseline)", &r_crate, a_crate),
    ] {
        println!(
            "  {label:<44} {:>8.2} {:>8.2} {:>8.1} {:>12.1}",
            r[0],
            r[1],
            r[3],
            allocs as f64 / n
        );
    }
    println!("  median ratio shim / crate: {:.2}", r_shim[0] / r_crate[0]);

    // (2) The 1 kHz loop against firmware-sim.
    let cell_name = format!("bench-{}", std::process::id());
    let log = std::env::temp_dir().join(format!("prf-firmware-sim-{cell_name}.log"));
    let _fw = ChildGuard(spawn_firmware(&cell_name, planar(&ft.home), &log, None)?);
    let cfg = CellConfig {
        alloc_probe: Some(crate::bench::alloc_count::thread_allocations),
        ..CellConfig::new(&cell_name)
    };
    let mut cell = Cell::connect(cfg, &rt)?;
    println!(
        "\n1 kHz host cell loop against firmware-sim, ≥ {:.0} s per pacing (task {} repeated):",
        a.loop_seconds,
        ft.label()
    );
    let spin_us = a.spin_us;
    let variants = [
        (Wait::AlarmThread, None),
        (Wait::InThread { spin_us: 0 }, None),
        (Wait::InThread { spin_us }, Some(REALTIME_PRIORITY)),
    ];
    let mut rows = Vec::new();
    for (wait, realtime) in variants {
        (cell.cfg.wait, cell.cfg.realtime) = (wait, realtime);
        let probe = StallProbe::start(realtime).context("starting the stall probe's thread")?;
        let figures = loop_figures(&mut cell, &rt, &program, &ft, a.loop_seconds);
        let p = probe.stop();
        println!(
            "  beside it, a probe thread ({}; an absolute clock_nanosleep each 1 ms, no work): {} wake-ups, late p50 {:.0} µs p99 {:.0} µs max {:.0} µs, {} a whole period late ({:.3} %)",
            p.scheduling,
            p.wakes,
            p.late_p50,
            p.late_p99,
            p.late_max,
            p.misses,
            p.miss_percent()
        );
        rows.push((figures?, p));
    }
    cell.shutdown()?;
    println!(
        "\n  {:<72} {:>8} {:>8} {:>9} {:>9}",
        "pacing (wake-up lateness, µs; medians over the runs)", "p50", "p99", "misses %", "probe %"
    );
    for (r, p) in &rows {
        println!(
            "  {:<72} {:>8.1} {:>8.1} {:>9.3} {:>9.3}",
            r.pacing,
            r.late_p50,
            r.late_p99,
            r.miss_percent,
            p.miss_percent()
        );
    }
    println!(
        "  probe %: the probe thread's wake-ups a whole period late, the misses the machine imposes on any thread so scheduled"
    );
    Ok(())
}

/// The loop's figures under one pacing.
struct LoopFigures {
    pacing: String,
    late_p50: f64,
    late_p99: f64,
    miss_percent: f64,
}

/// Runs the program repeatedly for at least `seconds` with the cell's current pacing.
fn loop_figures(
    cell: &mut Cell,
    rt: &prf_runtime::Runtime<'_>,
    program: &prf_runtime::program::Program,
    ft: &FloorTask,
    seconds: f64,
) -> Result<LoopFigures> {
    let (mut ticks, mut misses, mut total) = (0u64, 0u64, 0.0);
    let (mut p50, mut p99, mut pacing) = (Vec::new(), Vec::new(), String::new());
    while total < seconds {
        let a0 = allocations();
        let r = cell.execute(rt, program, &ft.home)?;
        let per_tick = (allocations() - a0) as f64 / r.ticks.max(1) as f64;
        println!(
            "  [{}] {}; process-wide (every thread, start-up included) {per_tick:.2} allocations per tick",
            r.pacing,
            r.summary()
        );
        if let Some(f) = &r.fault {
            bail!("the run faulted: {f}");
        }
        ticks += r.ticks;
        misses += r.deadline_misses;
        total += r.duration_s;
        p50.push(r.wake_late_us[0]);
        p99.push(r.wake_late_us[1]);
        pacing = r.pacing;
    }
    let miss_percent = misses as f64 / ticks as f64 * 100.0;
    println!(
        "  total: {ticks} ticks in {total:.1} s, {misses} deadline misses ({miss_percent:.3} %)"
    );
    let median = |v: &mut Vec<f64>| percentiles(v)[0];
    Ok(LoopFigures {
        pacing,
        late_p50: median(&mut p50),
        late_p99: median(&mut p99),
        miss_percent,
    })
}

/// The two Ruckig bindings' tracking interface, for timing them side by side.
trait Tracker {
    fn track(&mut self, p: &[f64; 7], v: &[f64; 7], gain: f64);
    fn step(&mut self) -> Result<bool, RuckigError>;
}

impl Tracker for Online<7> {
    fn track(&mut self, p: &[f64; 7], v: &[f64; 7], gain: f64) {
        Online::track(self, p, v, gain)
    }
    fn step(&mut self) -> Result<bool, RuckigError> {
        Online::step(self)
    }
}

impl Tracker for baseline::Online<7> {
    fn track(&mut self, p: &[f64; 7], v: &[f64; 7], gain: f64) {
        baseline::Online::track(self, p, v, gain)
    }
    fn step(&mut self) -> Result<bool, RuckigError> {
        baseline::Online::step(self)
    }
}

/// Tracks every setpoint once (track + step, as the safety net would): each update's time in
/// µs appended to `times`; the allocations made.
fn track_program(
    out: &mut impl Tracker,
    setpoints: &[prf_runtime::executor::Setpoint],
    times: &mut Vec<f64>,
) -> Result<u64> {
    times.reserve(setpoints.len());
    let a0 = allocations();
    for sp in setpoints {
        let t = Instant::now();
        out.track(&sp.arm, &sp.arm_velocity, TRACKING_GAIN);
        out.step()?;
        times.push(t.elapsed().as_nanos() as f64 * 1e-3);
    }
    Ok(allocations() - a0)
}
