//! `prf check-dataset`: validates a dataset directory, and with `--world` re-checks every
//! program against the ground-truth cell.

use crate::cli::progress::Bar;
use anyhow::bail;
use prf_files::dataset::Dataset;
use prf_shared::robot::RobotModel;
use prf_shared::se3::{Pose, pose_from_array};
use prf_sim::navigation::{PartTracker, drive_phases, part_size};
use prf_sim::validate::{self, MotionLimits};
use prf_sim::world::World;
use prf_sim::world::geometry::{Cell, DriveClearance};
use rayon::prelude::*;
use std::path::PathBuf;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// Dataset directory (with manifest.json).
    pub dir: PathBuf,
    /// Also re-check every program against a ground-truth world: a world file, or `example`
    /// or `plant` for a built-in one. Clearance ≥ r_d, self clearance, joint limits, speed and
    /// acceleration limits, densely re-sampled between the stored samples; the held part
    /// (from its recorded start pose, picked up when the gripper closes) keeps r_d from every
    /// box but the surfaces it rests on, and does not sink into those. Columns: drive =
    /// robot during drives, part = held part during drives, held = held part over the whole
    /// time it is held, rest = its surface against its supports (0: resting on them).
    #[arg(long)]
    pub world: Option<String>,
    /// Re-sampling resolution of the ground-truth check: largest motion of any collision
    /// sphere between two checked configurations, m.
    #[arg(long, default_value_t = 0.001)]
    pub resolution: f64,
}

pub fn run(args: &Args) -> anyhow::Result<()> {
    let model = RobotModel::kmr_iiwa14();
    let dataset = Dataset::read(&args.dir, &model)?;
    let samples: usize = dataset.demonstrations.iter().map(|d| d.samples.len()).sum();
    println!(
        "{}: {} demonstrations, {} samples, {} parts, {} locations: format OK",
        args.dir.display(),
        dataset.demonstrations.len(),
        samples,
        dataset.parts.len(),
        dataset.locations.len()
    );
    let Some(world) = &args.world else {
        return Ok(());
    };
    let world = World::named(&PathBuf::from(world))?;
    for d in &dataset.demonstrations {
        for placed in [&d.task.from, &d.task.to] {
            if world.location_index(&placed.id).is_none() {
                bail!(
                    "{}: location {} is not in the world {}",
                    d.id,
                    placed.id,
                    world.source.display()
                );
            }
        }
    }
    if !(args.resolution > 0.0) {
        bail!("--resolution must be positive, got {}", args.resolution);
    }
    let cell = Cell::new(&world, &model);
    let limits = MotionLimits::kmr_iiwa(&model);
    let bar = Bar::new("checking", "demonstrations", false);
    bar.report(prf_files::Progress::Total(
        dataset.demonstrations.len() as u64
    ));
    let reports: Vec<_> = dataset
        .demonstrations
        .par_iter()
        .map(|d| {
            let r = validate::check(&cell, &limits, &d.samples, args.resolution);
            let drives = drive_minimum(&world, &cell, d);
            let held =
                validate::check_held_part(&cell, &d.samples, tracker(&world, d), args.resolution);
            bar.inc();
            (r, (drives, held))
        })
        .collect();
    let (reports, parts): (Vec<_>, Vec<_>) = reports.into_iter().unzip();
    bar.finish();
    let c = world.clearance;
    // The r_d the programs are checked against: the one the dataset states (what learning
    // will use), else the world's.
    let (r_d, whose) = match dataset.clearance_demo {
        Some(v) => (v, "stated by the dataset"),
        None => (
            c.demonstration,
            "the world's; the dataset states none, and `prf learn` will refuse it",
        ),
    };
    println!(
        "{:<6} {:>7} {:>12} {:>10} {:>8} {:>8} {:>11} {:>10} {:>10} {:>10}  closest obstacle",
        "demo",
        "T [s]",
        "clear. [mm]",
        "self [mm]",
        "v/vmax",
        "a/amax",
        "drive [mm]",
        "part [mm]",
        "held [mm]",
        "rest [mm]"
    );
    let mut failed = 0;
    for ((d, r), (drive, held)) in dataset.demonstrations.iter().zip(&reports).zip(&parts) {
        // The held part keeps r_d from every box but its supports, and does not sink into
        // those.
        let part_ok = held.min >= r_d && held.support >= -validate::SINK_TOLERANCE;
        let ok = r.ok(r_d, c.self_collision, validate::LIMIT_TOLERANCE) && part_ok;
        failed += usize::from(!ok);
        let contact = format!("{:?}", r.world_contact);
        let mm = |x: f64| {
            if x.is_finite() {
                format!("{:.1}", x * 1e3)
            } else {
                "-".into()
            }
        };
        println!(
            "{:<6} {:>7.1} {:>12.1} {:>10.1} {:>8.3} {:>8.3} {:>11} {:>10} {:>10} {:>10}  {}{}",
            d.id,
            d.samples.last().map_or(0.0, |s| s.t),
            r.min_world * 1e3,
            r.min_self * 1e3,
            r.max_speed_ratio,
            r.max_acceleration_ratio,
            mm(drive.robot),
            mm(drive.part),
            mm(held.min),
            mm(held.support),
            contact,
            if ok { "" } else { "  <-- FAILS" }
        );
        if !part_ok {
            println!(
                "       held part: {:.1} mm from {} at t = {:.2} s; {:.1} mm into its support {} at t = {:.2} s",
                held.min * 1e3,
                held.obstacle,
                held.min_t,
                -held.support * 1e3,
                held.support_name,
                held.support_t
            );
        }
        if !ok {
            println!(
                "       fastest: {} at t = {:.2} s; hardest acceleration: {} at t = {:.2} s",
                r.max_speed_at.1,
                r.max_speed_at.0,
                r.max_acceleration_at.1,
                r.max_acceleration_at.0
            );
        }
        if let Some((t, j, v)) = r.limit_violation {
            println!(
                "       a{j} = {:.2} deg outside its limits at t = {t:.2} s",
                v.to_degrees()
            );
        }
    }
    let configurations: usize = reports.iter().map(|r| r.configurations).sum();
    println!(
        "{configurations} configurations checked; r_d = {:.0} mm ({whose}), self clearance = {:.0} mm",
        r_d * 1e3,
        c.self_collision * 1e3
    );
    if let Some((d, kept)) = dataset
        .demonstrations
        .iter()
        .zip(&reports)
        .map(|(d, r)| (&d.id, r.min_world))
        .min_by(|a, b| a.1.total_cmp(&b.1))
    {
        println!("smallest clearance kept: {:.1} mm ({d})", kept * 1e3);
        if dataset.clearance_demo.is_some() && kept < r_d {
            bail!(
                "the dataset states r_d = {:.1} mm, but {d} keeps only {:.1} mm: a stated r_d larger than the programs kept makes risk 0 unsafe; state at most {:.1} mm in manifest.json (clearance_demo_m)",
                r_d * 1e3,
                kept * 1e3,
                (kept * 1e4).floor() / 10.0
            );
        }
    }
    if failed > 0 {
        bail!("{failed} demonstrations violate the ground truth");
    }
    println!(
        "all programs keep r_d (the robot, and the held part from all but its supports), self clearance, joint, speed and acceleration limits"
    );
    Ok(())
}

/// The smallest clearances of a program's drives (platform, arm and gripper; the held part
/// separately, tracked from the gripper from its recorded start pose), every sample against
/// the true boxes.
fn drive_minimum(
    world: &World,
    cell: &Cell,
    d: &prf_files::dataset::Demonstration,
) -> DriveClearance {
    drive_phases(cell, &d.samples, tracker(world, d))
        .iter()
        .fold(
            DriveClearance {
                robot: f64::INFINITY,
                part: f64::INFINITY,
            },
            |m, p| DriveClearance {
                robot: m.robot.min(p.min.robot),
                part: m.part.min(p.min.part),
            },
        )
}

/// The program's part at its recorded start pose, picked up when the gripper closes.
fn tracker(world: &World, d: &prf_files::dataset::Demonstration) -> PartTracker {
    PartTracker::new(
        part_size(world, &d.task.part.kind),
        pose_from_array(d.task.part.pose).unwrap_or_else(Pose::identity),
    )
}
