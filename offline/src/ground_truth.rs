//! A planned program against the true cell: what a risk-0 plan promises (Sec. 4.1: clearance
//! ≥ r from every box the demonstrations kept r_d from), checked by executing the program and
//! measuring the arm, gripper, held part and platform against the world file's boxes and floor.

use prf_host::ideal::{Execution, execute};
use prf_runtime::Runtime;
use prf_runtime::executor::{ExecutorConfig, Mode, planar};
use prf_runtime::plan::Plan;
use prf_runtime::program::Segment;
use prf_shared::JointVector;
use prf_shared::kinematics::ArmKinematics;
use prf_sim::navigation::{CHECK_STEP, PartTracker, drive_phases, execute_navigating, part_size};
use prf_sim::tasks::FloorTask;
use prf_sim::validate::check_held_part;
use prf_sim::world::World;
use prf_sim::world::geometry::Cell;

/// Ticks an execution may take before it counts as stuck.
const MAX_TICKS: usize = 600_000;

/// The smallest true clearances of an executed program, m.
#[derive(Clone, Debug, PartialEq)]
pub struct TrueClearance {
    /// Arm and gripper spheres during the arm motions, at every 1 ms tick, platform at the
    /// planned stances.
    pub arm: f64,
    /// What the arm came closest to (a box's name, or the floor).
    pub arm_contact: String,
    /// The held part to every box but its supports (re-sampled every 2 mm of its motion).
    pub held: f64,
    /// Platform, arm, gripper and held part on the drives (checked every [`CHECK_STEP`]).
    pub drives: f64,
}

impl TrueClearance {
    /// Whether the program keeps `r`: the arm at every tick; the held part and the drives,
    /// whose checks step up to [`CHECK_STEP`], within half of it.
    pub fn keeps(&self, r: f64) -> bool {
        self.arm >= r && self.held.min(self.drives) >= r - CHECK_STEP / 2.0
    }

    /// The smallest of the three.
    pub fn min(&self) -> f64 {
        self.arm.min(self.held).min(self.drives)
    }
}

/// An error unless `run` went to the program's end without a fault: a check of part of a
/// program proves nothing about the rest.
fn completed(ft: &FloorTask, run: &Execution) -> anyhow::Result<()> {
    if let Some(fault) = run.fault {
        anyhow::bail!("{}: the program faulted: {fault:?}", ft.label());
    }
    if run.setpoints.last().map(|s| s.mode) != Some(Mode::Done) {
        anyhow::bail!(
            "{}: the program did not end within {MAX_TICKS} ticks",
            ft.label()
        );
    }
    Ok(())
}

/// The arm motions of `plan`'s program (executed on the ideal cell) against `cell`: the
/// smallest clearance of arm and gripper at any tick, and what it was to.
pub fn arm_clearance(
    rt: &Runtime<'_>,
    cell: &Cell,
    ft: &FloorTask,
    plan: &Plan,
) -> anyhow::Result<(f64, String)> {
    let program = plan
        .program
        .as_ref()
        .ok_or_else(|| anyhow::anyhow!("{}: no program", ft.label()))?;
    let (s1, s2) = plan
        .stances
        .ok_or_else(|| anyhow::anyhow!("{}: no stances", ft.label()))?;
    let run = execute(rt, program, &ft.home, ExecutorConfig::default(), MAX_TICKS);
    completed(ft, &run)?;
    let mut worst = (f64::INFINITY, String::new());
    for (i, seg) in program.segments.iter().enumerate() {
        if !matches!(seg, Segment::Arm { .. } | Segment::Reverse { .. }) {
            continue;
        }
        // Segments 0–3 run at the pick stance, the rest at the place stance.
        let platform = if i < 4 { s1 } else { s2 };
        let base = platform * rt.model.mount;
        let near = cell.obstacles_near(planar(&platform));
        let arm = run
            .setpoints
            .iter()
            .filter(|s| s.mode == Mode::Arm && s.segment as usize == i);
        for s in arm {
            let kin = ArmKinematics::new(&rt.model, &JointVector::from(s.arm));
            let c = cell.arm_clearance(&base, &kin, &near);
            if c.world < worst.0 {
                worst = (c.world, format!("{:?} in segment {i}", c.world_contact));
            }
        }
    }
    Ok(worst)
}

/// `plan`'s program for task `ft` against the true cell of `world`: the arm motions on the
/// ideal cell, the drives and the held part on the navigating cell.
pub fn true_clearance(
    world: &World,
    rt: &Runtime<'_>,
    ft: &FloorTask,
    plan: &Plan,
) -> anyhow::Result<TrueClearance> {
    let cell = Cell::new(world, &rt.model);
    let (arm, arm_contact) = arm_clearance(rt, &cell, ft, plan)?;
    let Some(program) = &plan.program else {
        anyhow::bail!("{}: no program", ft.label());
    };
    let (run, _) = execute_navigating(world, rt, program, ft, MAX_TICKS)
        .map_err(|e| anyhow::anyhow!("{}: the drives: {e:?}", ft.label()))?;
    completed(ft, &run)?;
    let part = || PartTracker::new(part_size(world, &ft.part.1), ft.part_pose);
    let drives = drive_phases(&cell, &run.samples, part())
        .iter()
        .map(|ph| ph.min.robot.min(ph.min.part))
        .fold(f64::INFINITY, f64::min);
    let held = check_held_part(&cell, &run.samples, part(), 0.002).min;
    Ok(TrueClearance {
        arm,
        arm_contact,
        held,
        drives,
    })
}
