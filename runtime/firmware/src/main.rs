//! PRF cell-controller firmware: the no_std runtime on a Cortex-M7.
//!
//! It reads the blob (BLOB region) and a task block (TASK region) in place, validates both,
//! plans the task, and executes the program through the output stage (`prf_ruckig`, the same
//! as the host cell's: a certified setpoint passes unchanged, anything else is shaped by Ruckig's
//! C++ core) against the runtime's ideal cell, paced at 1 kHz by embassy-time's `Ticker` on a
//! SysTick time driver. The stream is what the output stage emitted. Over semihosting it prints the timing
//! figures (instructions of loading, planning and every executor tick; under
//! `qemu-system-arm -icount shift=0` SysTick counts are instruction counts), static RAM
//! (data + bss + the stack's high-water mark) and a digest of the setpoint stream (CRC-32 of
//! its records, every 1000th setpoint); with `--stream FILE` on the semihosting command line
//! it writes every setpoint as a [`prf_runtime::stream`] record to FILE on the host, with
//! `--figures FILE` the figures as one [`prf_runtime::figures`] record. It exits
//! with a status ([`fault::Exit`]); every exception and panic exits with a message.
#![no_std]
#![no_main]

mod block_on;
mod board;
#[cfg(feature = "embed")]
mod embedded;
mod fault;
mod measure;
mod semihost;
mod time_driver;

use block_on::block_on;
use board::{BLOB_ADDRESS, PLAN_BUDGET_STEPS, TASK_ADDRESS, TICK_HZ};
use cortex_m_rt::entry;
use cortex_m_semihosting::hprintln;
use embassy_time::{Duration, Instant};
use fault::{Exit, exit};
use measure::{Metered, Stack};
use prf_ruckig::StagedCell;
use prf_runtime::executor::{Executor, ExecutorConfig, Mode, Plant};
use prf_runtime::figures::{self, Figures, ModeFigures};
use prf_runtime::ideal::IdealCell;
use prf_runtime::program::Program;
use prf_runtime::reverse::Reversal;
use prf_runtime::skill_plan::PlanBudget;
use prf_runtime::stream::{self, RECORD_LEN};
use prf_runtime::{Runtime, RuntimeConfig, Task, plan};
use prf_shared::blob::{Blob, CRC32};
use semihost::HostFile;
use time_driver::{COUNTS_PER_PERIOD, counts};

unsafe extern "C" {
    static _blob_start: u8;
    static _blob_end: u8;
    static _task_start: u8;
    static _task_end: u8;
}

/// A flash region of `memory.x` as bytes.
fn region(start: *const u8, end: *const u8) -> &'static [u8] {
    // SAFETY: the linker symbols bound a flash region that the firmware never writes.
    unsafe { core::slice::from_raw_parts(start, end as usize - start as usize) }
}

#[entry]
fn main() -> ! {
    let stack = Stack::paint();
    let Some(cp) = cortex_m::Peripherals::take() else {
        panic!("core peripherals taken twice");
    };
    time_driver::start(cp.SYST);
    let k = measure::instructions_per_count();
    hprintln!("SysTick: {} instructions per count (calibrated)", k);
    let mut cmdline = [0u8; 256];
    let cmdline = semihost::command_line(&mut cmdline);
    if semihost::flag(cmdline, "fault-test") {
        // Proves the exception path: an undefined instruction, escalated to HardFault.
        cortex_m::asm::udf();
    }
    let mut figures = Figures::default();
    let status = match load_and_plan(k, &mut figures) {
        Ok((rt, task, program)) => execute(
            &rt,
            &task,
            program,
            k,
            semihost::option(cmdline, "stream"),
            &mut figures,
        ),
        Err(status) => status,
    };
    let (data, bss) = measure::static_ram();
    let stack = stack.high_water_mark();
    (figures.ram_data, figures.ram_bss) = (data as u64, bss as u64);
    (figures.ram_stack, figures.ram_total) = (stack as u64, (data + bss + stack) as u64);
    hprintln!(
        "ram data {} bss {} stack {} total {} bytes",
        data,
        bss,
        stack,
        data + bss + stack
    );
    match semihost::option(cmdline, "figures") {
        Some(path) if !write_figures(path, &figures) => exit(Exit::Output),
        _ => exit(status),
    }
}

/// Writes the figures record to `path` on the host; false if that failed.
fn write_figures(path: &str, figures: &Figures) -> bool {
    let mut buf = [0u8; figures::MAX_LEN];
    let written = match (figures.encode(&mut buf), HostFile::create(path)) {
        (Some(bytes), Some(mut f)) => f.write_all(bytes),
        _ => false,
    };
    if !written {
        hprintln!("prf-firmware: writing the figures to {} failed", path);
    }
    written
}

/// Loads the blob and the task block from flash and plans the task; exits on any error, and
/// returns [`Exit::Risky`] for a task it cannot do safely (after its figures are taken).
#[inline(never)]
fn load_and_plan(
    k: u64,
    figures: &mut Figures,
) -> Result<(Runtime<'static>, Task<'static>, Program), Exit> {
    let blob = region(&raw const _blob_start, &raw const _blob_end);
    let Some(bytes) = Blob::stored_len(blob).ok().and_then(|n| blob.get(..n)) else {
        hprintln!(
            "prf-firmware: no blob at {:#010x} (flash one: -device loader,file=cell.blob,addr={:#010x})",
            BLOB_ADDRESS,
            BLOB_ADDRESS
        );
        exit(Exit::NoBlob);
    };
    let t0 = counts();
    let config = RuntimeConfig {
        plan_budget: PlanBudget {
            steps: PLAN_BUDGET_STEPS,
        },
        ..RuntimeConfig::default()
    };
    let rt = match Runtime::load_with(bytes, config) {
        Ok(rt) => rt,
        Err(e) => {
            hprintln!(
                "prf-firmware: corrupt blob at {:#010x}: {}",
                BLOB_ADDRESS,
                e
            );
            exit(Exit::CorruptBlob);
        }
    };
    let load = counts() - t0;
    (figures.blob_bytes, figures.load_instructions) = (bytes.len() as u64, load * k);
    hprintln!(
        "blob {} B valid; load {} instructions",
        bytes.len(),
        load * k
    );
    let task = match prf_runtime::task_block::decode(region(
        &raw const _task_start,
        &raw const _task_end,
    )) {
        Ok(t) => t,
        Err(e) => {
            hprintln!(
                "prf-firmware: {} at {:#010x} (write one with `prf plan … --task-block task.bin`)",
                e,
                TASK_ADDRESS
            );
            exit(Exit::NoTask);
        }
    };
    hprintln!("task {} {} -> {}", task.part.id, task.from.id, task.to.id);
    let t1 = counts();
    let p = match plan(&rt, &task) {
        Ok(p) => p,
        Err(e) => {
            hprintln!("prf-firmware: plan: {}", e);
            exit(Exit::Plan);
        }
    };
    let s = &p.skills;
    figures.feasible = s.feasible;
    figures.integrations = s.stats.integrations as u64;
    figures.planning_instructions = (counts() - t1) * k;
    hprintln!(
        "plan J* {:.6e} feasible {} integrations {} steps {} instructions {}",
        s.j,
        figures.feasible,
        figures.integrations,
        s.stats.steps,
        figures.planning_instructions
    );
    if !s.feasible {
        match s.exhausted {
            Some(lower) => hprintln!(
                "prf-firmware: risky: J* ≥ {:.1} mm after {} integrations (the planning budget of {} steps is spent; best plan found: J = {:.1} mm, inf if none); nothing executed",
                lower * 1e3,
                s.stats.integrations,
                PLAN_BUDGET_STEPS,
                s.j * 1e3
            ),
            None => hprintln!(
                "prf-firmware: risky: J* = {:.1} mm after {} integrations; nothing executed",
                s.j * 1e3,
                s.stats.integrations
            ),
        }
        return Err(Exit::Risky);
    }
    let Some(program) = p.program else {
        hprintln!("prf-firmware: the task has no program");
        exit(Exit::NoProgram);
    };
    Ok((rt, task, program))
}

/// Setpoint records buffered before a write to the host.
const BUFFERED: usize = 32;

/// Runs `program` on the ideal cell at 1 kHz until it is done or faults.
#[inline(never)]
fn execute(
    rt: &Runtime<'_>,
    task: &Task<'_>,
    program: Program,
    k: u64,
    stream_path: Option<&str>,
    figures: &mut Figures,
) -> Exit {
    let mut file = match stream_path.map(|p| (p, HostFile::create(p))) {
        Some((p, None)) => {
            hprintln!("prf-firmware: cannot create {} on the host", p);
            return Exit::Output;
        }
        Some((_, f)) => f,
        None => None,
    };
    let mut buffer = [0u8; BUFFERED * RECORD_LEN];
    let mut buffered = 0;
    let mut reversal = Reversal::new();
    let mut ex = Executor::new(
        rt,
        program,
        &task.home,
        ExecutorConfig::default(),
        &mut reversal,
    );
    let ideal = IdealCell::new(rt.model.home, &task.home, rt.config.rdmp.dt);
    let mut staged = StagedCell::new(ideal, &rt.limits);
    let mut cell = Metered::new(&mut staged);
    let period = Duration::from_hz(TICK_HZ as u64);
    let mut t = Instant::from_ticks(0);
    let (mut late, mut busy, mut misses) = (0u64, 0, 0);
    // The slowest executor tick: instructions' counts, seq, mode.
    let mut worst = (0u64, 0u32, Mode::Base);
    // Per mode (Base, Arm, Gripper, Done, Fault): ticks, max, sum; without the plant's
    // counts (the output stage and the hand-off): max, sum.
    let mut by_mode = [(0u64, 0u64, 0u64, 0u64, 0u64); 5];
    let mut crc = CRC32.digest();
    let (mut ticker, mut due) = time_driver::aligned_ticker(period);
    let sp = loop {
        block_on(ticker.next());
        let woke = counts();
        late = late.max(woke.saturating_sub(due));
        let sp = match ex.step(t, &mut cell) {
            Ok(sp) => cell.emitted(&sp),
            Err(e) => {
                hprintln!("prf-firmware: the output stage failed: {}", e);
                return Exit::NotDone;
            }
        };
        let used = counts() - woke;
        let core = used.saturating_sub(cell.take());
        let record = stream::encode(&sp);
        crc.update(&record);
        let work = counts().saturating_sub(due);
        busy = busy.max(work);
        misses += (work >= COUNTS_PER_PERIOD as u64) as u64;
        if used > worst.0 {
            worst = (used, sp.seq, sp.mode);
        }
        let m = &mut by_mode[sp.mode as usize];
        *m = (
            m.0 + 1,
            m.1.max(used),
            m.2 + used,
            m.3.max(core),
            m.4 + core,
        );
        let end = sp.is_final();
        if let Some(f) = file.as_mut() {
            buffer[buffered * RECORD_LEN..][..RECORD_LEN].copy_from_slice(&record);
            buffered += 1;
            if (buffered == BUFFERED || end) && !f.write_all(&buffer[..buffered * RECORD_LEN]) {
                hprintln!("prf-firmware: writing the setpoint stream failed");
                return Exit::Output;
            }
            buffered %= BUFFERED;
        }
        if sp.seq % 1000 == 1 || end {
            let q = sp.arm;
            hprintln!(
                "sp {} {} {:.17e} {:.17e} {:.17e} {:.17e} {:.17e} {:.17e} {:.17e}",
                sp.seq,
                sp.mode as u8,
                q[0],
                q[1],
                q[2],
                q[3],
                q[4],
                q[5],
                q[6]
            );
        }
        if end {
            break sp;
        }
        t += period;
        due += COUNTS_PER_PERIOD as u64;
    };
    let ticks: u64 = by_mode.iter().map(|m| m.0).sum();
    let sum: u64 = by_mode.iter().map(|m| m.2).sum();
    figures.ticks = ticks;
    (figures.tick_max, figures.tick_max_seq) = (worst.0 * k, worst.1 as u64);
    figures.tick_mean = sum * k / ticks.max(1);
    (figures.loop_max, figures.lateness_max) = (busy * k, late * k);
    figures.overruns = misses;
    figures.shaped = cell.plant.stage.shaped().0;
    for (f, (n, max, sum, core_max, core_sum)) in figures.by_mode.iter_mut().zip(by_mode) {
        *f = ModeFigures {
            ticks: n,
            max: max * k,
            mean: sum * k / n.max(1),
            core_max: core_max * k,
            core_mean: core_sum * k / n.max(1),
        };
    }
    figures.crc32 = crc.finalize();
    hprintln!(
        "ticks {} executor max {} (seq {} {:?}) mean {} instructions; loop max {} wake-up lateness max {} instructions; overruns {}",
        ticks,
        worst.0 * k,
        worst.1,
        worst.2,
        sum * k / ticks.max(1),
        busy * k,
        late * k,
        misses
    );
    for (name, (n, max, sum, core_max, core_sum)) in ["base", "arm", "gripper"].iter().zip(by_mode)
    {
        hprintln!(
            "  {} ticks {} max {} mean {} instructions; without the output stage max {} mean {}",
            name,
            n,
            max * k,
            sum * k / n.max(1),
            core_max * k,
            core_sum * k / n.max(1)
        );
    }
    hprintln!(
        "stream {} setpoints crc32 {:08x}; output stage shaped {} ticks",
        ticks,
        figures.crc32,
        figures.shaped
    );
    match ex.fault() {
        Some(f) => {
            hprintln!("prf-firmware: the executor stopped: {}", f);
            Exit::NotDone
        }
        None if sp.mode == Mode::Done => Exit::Done,
        None => Exit::NotDone,
    }
}
