//! The cell-controller firmware seen from the host (errors: [`FirmwareError`]): build it and run it under QEMU with a blob
//! and a task block (both through `scripts/firmware.sh`, the one home of the QEMU command
//! line), read the figures record and the setpoint stream it writes, and compare that stream
//! with the host runtime's for the same blob and task block.

use prf_host::ideal::{IdealCell, execute_on};
use prf_ruckig::StagedCell;
use prf_runtime::executor::{ExecutorConfig, Mode, Setpoint};
pub use prf_runtime::figures::Figures;
use prf_runtime::stream::{RECORD_LEN, Record, decode};
use prf_runtime::{Runtime, plan, task_block};
use prf_shared::limits::{ArmMeter, LimitRatios, MotionLimits};
use prf_sim::tasks::FloorTask;
use std::path::{Path, PathBuf};
use std::process::Command;

/// Hard budget of one executor tick: 20 % of a 1 ms tick at 480 MHz.
pub const MAX_TICK_INSTRUCTIONS: u64 = 100_000;
/// The goal per tick.
pub const GOAL_TICK_INSTRUCTIONS: u64 = 15_000;
/// Issue 20's goal for an arm tick without the output stage: mean and max.
pub const GOAL_CORE_MEAN: u64 = 8_000;
/// Issue 20's goal for the largest arm tick without the output stage.
pub const GOAL_CORE_MAX: u64 = 10_000;
/// Stated bound of planning one task: 0.625 s at 480 MHz (one instruction per cycle).
pub const MAX_PLANNING_INSTRUCTIONS: u64 = 300_000_000;
/// Static RAM budget: data + bss + the stack's high-water mark.
pub const MAX_STATIC_RAM: u64 = 128 * 1024;
/// Firmware and host setpoints agree within this, rad (arm) and m / rad (platform goal): 0,
/// bit for bit — both run the same Rust code, and every transcendental function in the
/// stream's path is computed by the same code on both: the `libm` crate's (atan2), or
/// `prf_shared`'s own (FK's `float::sincos`, `float::exp_neg`, the SO(3) series).
pub const STREAM_TOLERANCE: f64 = 0.0;
/// Ticks the host reference runs at most (an hour at 1 kHz).
const MAX_TICKS: usize = 3_600_000;

/// Why the firmware could not be built, run or compared.
#[derive(Debug, thiserror::Error)]
pub enum FirmwareError {
    #[error("running {what}")]
    Spawn {
        what: String,
        #[source]
        source: std::io::Error,
    },
    #[error("{what} failed ({status}):\n{stderr}")]
    Script {
        what: String,
        status: std::process::ExitStatus,
        stderr: String,
    },
    #[error("{what} printed no path")]
    NoPath { what: String },
    #[error("{action} {path}")]
    File {
        action: &'static str,
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{path}: {len} bytes is not a whole number of {RECORD_LEN}-byte records")]
    Stream { path: PathBuf, len: usize },
    #[error("loading the blob: {0}")]
    Load(prf_runtime::LoadError),
    #[error("decoding the task block: {0}")]
    TaskBlock(task_block::TaskBlockError),
    #[error(transparent)]
    FloorTask(#[from] prf_sim::tasks::FloorTaskError),
    /// Planning failed (the message of the borrowing `PlanError`).
    #[error("plan: {0}")]
    Plan(String),
    #[error("the host's output stage failed: {0}")]
    OutputStage(prf_ruckig::RuckigError),
    #[error("the task has no program")]
    NoProgram,
    #[error("the host executor stopped: {0}")]
    HostFault(prf_runtime::executor::Fault),
}

/// The result of a firmware operation.
pub type Result<T> = std::result::Result<T, FirmwareError>;

fn repository() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn script() -> PathBuf {
    repository().join("scripts/firmware.sh")
}

/// Runs `scripts/firmware.sh` with `args` (a subcommand that builds): the ELF path it prints
/// last.
fn built_elf(args: &[&std::ffi::OsStr]) -> Result<PathBuf> {
    let what = format!("scripts/firmware.sh {}", args[0].to_string_lossy());
    let out = Command::new("bash")
        .arg(script())
        .args(args)
        .output()
        .map_err(|source| FirmwareError::Spawn {
            what: what.clone(),
            source,
        })?;
    if !out.status.success() {
        return Err(FirmwareError::Script {
            what,
            status: out.status,
            stderr: String::from_utf8_lossy(&out.stderr).into_owned(),
        });
    }
    let stdout = String::from_utf8_lossy(&out.stdout);
    let Some(elf) = stdout.lines().last() else {
        return Err(FirmwareError::NoPath { what });
    };
    Ok(repository().join(elf.trim()))
}

/// Builds the firmware (installing the toolchain and QEMU when missing); the ELF's path.
pub fn build() -> Result<PathBuf> {
    built_elf(&["build".as_ref()])
}

/// One run of the firmware under QEMU.
#[derive(Debug)]
pub struct Run {
    /// QEMU's exit status (the firmware's, see `runtime/firmware/src/fault.rs`); None if
    /// killed by a signal.
    pub status: Option<i32>,
    pub stdout: String,
    pub figures: Option<Figures>,
}

/// Runs `elf` under QEMU; `args` go to `scripts/firmware.sh run-image`: `--blob FILE` and
/// `--task FILE` flash them into their regions, `--stream FILE` has every setpoint written
/// there, `--fault-test` executes an undefined instruction. The firmware's figures come back
/// as a record in a file of their own (`--figures`).
pub fn run<I, S>(elf: &Path, args: I) -> Result<Run>
where
    I: IntoIterator<Item = S>,
    S: AsRef<std::ffi::OsStr>,
{
    static RUNS: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
    let n = RUNS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let figures_path =
        std::env::temp_dir().join(format!("prf-firmware-figures-{}-{n}", std::process::id()));
    let _ = std::fs::remove_file(&figures_path);
    let out = Command::new("bash")
        .arg(script())
        .arg("run-image")
        .arg(elf)
        .args(args)
        .arg("--figures")
        .arg(&figures_path)
        .output()
        .map_err(|source| FirmwareError::Spawn {
            what: "scripts/firmware.sh run-image".into(),
            source,
        })?;
    let figures = std::fs::read(&figures_path)
        .ok()
        .and_then(|b| Figures::decode(&b));
    let _ = std::fs::remove_file(&figures_path);
    Ok(Run {
        status: out.status.code(),
        figures,
        stdout: String::from_utf8_lossy(&out.stdout).into_owned(),
    })
}

/// Builds the self-contained image with `blob` and `task` linked in (feature `embed`); its
/// path.
pub fn image(blob: &Path, task: &Path) -> Result<PathBuf> {
    built_elf(&["image".as_ref(), blob.as_os_str(), task.as_os_str()])
}

/// Reads a setpoint stream the firmware wrote.
pub fn read_stream(path: &Path) -> Result<Vec<Record>> {
    let bytes = read(path)?;
    if !bytes.len().is_multiple_of(RECORD_LEN) {
        return Err(FirmwareError::Stream {
            path: path.to_path_buf(),
            len: bytes.len(),
        });
    }
    Ok(bytes
        .chunks_exact(RECORD_LEN)
        .map(|c| decode(c.try_into().expect("chunk of RECORD_LEN")))
        .collect())
}

/// The host runtime's emitted setpoints for the task in `block` on blob `blob`: the firmware's
/// computation (plan, then the executor through the output stage against the ideal cell), run
/// here.
pub fn host_stream(blob: &[u8], block: &[u8]) -> Result<Vec<Setpoint>> {
    let rt = Runtime::load(blob).map_err(FirmwareError::Load)?;
    let task = task_block::decode(block).map_err(FirmwareError::TaskBlock)?;
    let p = plan(&rt, &task).map_err(|e| FirmwareError::Plan(e.to_string()))?;
    let Some(program) = p.program else {
        return Err(FirmwareError::NoProgram);
    };
    let ideal = IdealCell::new(rt.model.home, &task.home, rt.config.rdmp.dt);
    let mut cell = StagedCell::new(ideal, &rt.limits);
    let run = execute_on(
        &rt,
        &program,
        &task.home,
        ExecutorConfig::default(),
        MAX_TICKS,
        &mut cell,
    )
    .map_err(FirmwareError::OutputStage)?;
    if let Some(f) = run.fault {
        return Err(FirmwareError::HostFault(f));
    }
    Ok(run.setpoints)
}

/// The bytes of a file.
fn read(path: &Path) -> Result<Vec<u8>> {
    std::fs::read(path).map_err(|source| FirmwareError::File {
        action: "reading",
        path: path.to_path_buf(),
        source,
    })
}

/// How far two setpoint streams are apart.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Comparison {
    pub setpoints: usize,
    /// Largest |q_firmware − q_host| over every joint and setpoint, rad.
    pub arm: f64,
    /// Largest difference of the platform goals, m or rad.
    pub base_goal: f64,
    /// Peak limit ratios of the firmware's arm stream (1 ms finite differences, from and to
    /// standstill): every one ≤ 1 for a certified program.
    pub emitted: LimitRatios,
}

/// Compares the firmware's stream with the host's: the same length, sequence numbers,
/// modes, segments and gripper commands, and numbers within [`STREAM_TOLERANCE`]; rates the
/// firmware's arm stream against `limits`. The error names the first setpoint that differs.
pub fn compare(
    host: &[Setpoint],
    firmware: &[Record],
    limits: &MotionLimits,
) -> std::result::Result<Comparison, String> {
    if host.len() != firmware.len() {
        return Err(format!(
            "{} firmware setpoints, {} host setpoints",
            firmware.len(),
            host.len()
        ));
    }
    let mut c = Comparison {
        setpoints: host.len(),
        arm: 0.0,
        base_goal: 0.0,
        emitted: LimitRatios::default(),
    };
    let mut meter = firmware
        .first()
        .map(|f| ArmMeter::at_rest(limits, 1e-3, &f.arm));
    let max_diff = |a: &[f64], b: &[f64]| {
        a.iter()
            .zip(b)
            .map(|(x, y)| (x - y).abs())
            .fold(0.0, f64::max)
    };
    for (h, f) in host.iter().zip(firmware) {
        let same = (h.seq, h.mode as u8, h.segment, h.close_gripper)
            == (f.seq, f.mode, f.segment, f.close_gripper);
        let (arm, base) = (
            max_diff(&h.arm, &f.arm),
            max_diff(&h.base_goal, &f.base_goal),
        );
        if !(same && arm <= STREAM_TOLERANCE && base <= STREAM_TOLERANCE) {
            return Err(format!(
                "setpoint {}: host (mode {:?}, segment {}, gripper {}, q {:?}) != firmware (mode {}, segment {}, gripper {}, q {:?}): |Δq| {arm:.3e}, |Δbase goal| {base:.3e}",
                h.seq,
                h.mode,
                h.segment,
                h.close_gripper,
                h.arm,
                f.mode,
                f.segment,
                f.close_gripper,
                f.arm
            ));
        }
        c.arm = c.arm.max(arm);
        c.base_goal = c.base_goal.max(base);
        if let Some(m) = meter.as_mut() {
            m.push(&f.arm);
        }
    }
    if let Some(mut m) = meter {
        m.stop();
        c.emitted = m.ratios();
    }
    if host.last().is_some_and(|h| h.mode != Mode::Done) {
        return Err("the streams agree but do not end in Done".into());
    }
    Ok(c)
}

/// The budgets a run exceeds (empty: within all): executor tick, planning, static RAM, and no
/// overrun of the 1 kHz tick.
pub fn violations(f: &Figures) -> Vec<String> {
    let mut v = Vec::new();
    if f.tick_max > MAX_TICK_INSTRUCTIONS {
        v.push(format!(
            "executor tick {} > {MAX_TICK_INSTRUCTIONS} instructions (seq {})",
            f.tick_max, f.tick_max_seq
        ));
    }
    if f.planning_instructions > MAX_PLANNING_INSTRUCTIONS {
        v.push(format!(
            "planning {} > {MAX_PLANNING_INSTRUCTIONS} instructions",
            f.planning_instructions
        ));
    }
    if f.ram_total > MAX_STATIC_RAM {
        v.push(format!(
            "static RAM {} > {MAX_STATIC_RAM} bytes",
            f.ram_total
        ));
    }
    if f.overruns > 0 {
        v.push(format!("{} ticks overran 1 ms", f.overruns));
    }
    v
}

/// One task on the firmware, checked against the host.
#[derive(Debug)]
pub struct TaskReport {
    pub label: String,
    pub run: Run,
    /// The streams compared (Err: why they differ, or why there is no firmware stream).
    pub comparison: std::result::Result<Comparison, String>,
}

/// Runs task `task` on the firmware with blob `blob` (task block and stream written into
/// `dir`) and compares its stream with the host's.
pub fn check_task(elf: &Path, blob: &Path, task: &FloorTask, dir: &Path) -> Result<TaskReport> {
    let name: String = task
        .label()
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '-' })
        .collect();
    let block_path = dir.join(format!("{name}.task"));
    let stream_path = dir.join(format!("{name}.stream"));
    let block = task.task_block()?;
    std::fs::write(&block_path, &block).map_err(|source| FirmwareError::File {
        action: "writing",
        path: block_path.clone(),
        source,
    })?;
    let _ = std::fs::remove_file(&stream_path);
    let args = [
        "--blob".as_ref(),
        blob.as_os_str(),
        "--task".as_ref(),
        block_path.as_os_str(),
        "--stream".as_ref(),
        stream_path.as_os_str(),
    ];
    let run = run(elf, args)?;
    let bytes = read(blob)?;
    let host = host_stream(&bytes, &block)?;
    let limits = Runtime::load(&bytes).map_err(FirmwareError::Load)?.limits;
    let comparison = match (run.status, read_stream(&stream_path)) {
        (Some(0), Ok(fw)) => compare(&host, &fw, &limits),
        (status, Ok(_)) => Err(format!("the firmware exited with {status:?}")),
        (_, Err(e)) => Err(match std::error::Error::source(&e) {
            Some(cause) => format!("{e}: {cause}"),
            None => e.to_string(),
        }),
    };
    Ok(TaskReport {
        label: task.label(),
        run,
        comparison,
    })
}

/// [`check_task`] for every task, `workers` QEMU runs at a time; `done` sees each report as
/// it completes. Reports are in the order of `tasks`.
pub fn check_tasks(
    elf: &Path,
    blob: &Path,
    tasks: &[FloorTask],
    dir: &Path,
    workers: usize,
    done: impl Fn(&Result<TaskReport>) + Sync,
) -> Vec<Result<TaskReport>> {
    let next = std::sync::atomic::AtomicUsize::new(0);
    let slots: Vec<std::sync::Mutex<Option<Result<TaskReport>>>> =
        tasks.iter().map(|_| std::sync::Mutex::new(None)).collect();
    std::thread::scope(|s| {
        for _ in 0..workers.max(1) {
            s.spawn(|| {
                loop {
                    let i = next.fetch_add(1, std::sync::atomic::Ordering::SeqCst);
                    let Some(task) = tasks.get(i) else { break };
                    let r = check_task(elf, blob, task, dir);
                    done(&r);
                    *slots[i].lock().expect("slot") = Some(r);
                }
            });
        }
    });
    slots
        .into_iter()
        .map(|m| m.into_inner().expect("slot").expect("every task ran"))
        .collect()
}
