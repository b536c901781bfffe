//! The board: QEMU `mps2-an500` (Cortex-M7 with the double-precision FPU). Adapting to a real
//! cell controller: set [`SYSTICK_HZ`] to its core clock (SysTick runs on it) and the regions
//! in the top-level `memory.x` (see docs/firmware.md).

/// SysTick clock, Hz: the core clock. mps2-an500 runs at 25 MHz.
pub const SYSTICK_HZ: u32 = 25_000_000;

/// Control rate, Hz: the executor ticks and SysTick interrupts at this rate.
pub const TICK_HZ: u32 = 1_000;

/// Where the blob and the task block are flashed (`memory.x` BLOB and TASK), for messages.
pub const BLOB_ADDRESS: u32 = 0x0030_0000;
pub const TASK_ADDRESS: u32 = 0x003F_0000;

/// Planning budget per task, RDMP integration steps (all candidates together, failed ones
/// included). At about 23,400 instructions per step (planning, risk and pacing together) an
/// infeasible task stops within the firmware's planning bound of 300 M instructions; the
/// example cell's feasible tasks need 6,000–7,600 steps.
pub const PLAN_BUDGET_STEPS: u64 = 11_000;
