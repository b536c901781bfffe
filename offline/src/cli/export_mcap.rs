//! `prf export-mcap` (a dataset, or a blob's knowledge) and `prf plan --mcap` (a planned
//! program): ROS 2 bags for Foxglove and rerun, written by `prf_offline::export_mcap`.

use crate::cli::args::{WorldArgs, read_blob, runtime};
use anyhow::Context;
use prf_files::bag::messages::{ARROW, CUBE, Marker};
use prf_files::dataset::Dataset;
use prf_files::robot::{self, ChainNames};
use prf_offline::export_mcap::{Exporter, T0, marker, program_risk, rgba};
use prf_offline::view::drawn_part_size;
use prf_runtime::RuntimeConfig;
use prf_runtime::plan::Plan;
use prf_shared::se3::{Pose, pose_from_array};
use prf_sim::tasks::FloorTask;
use prf_sim::world::World;
use prf_sim::world::geometry::Cell;
use std::path::{Path, PathBuf};

#[derive(clap::Args, Debug)]
#[command(group = clap::ArgGroup::new("what").required(true).args(["dataset", "blob"]))]
pub struct Args {
    /// Export a dataset: its programs one after the other (1 s apart), the locations of
    /// their tasks, and each task's part at its start and goal poses.
    #[arg(long)]
    pub dataset: Option<PathBuf>,
    /// Export a blob's knowledge: each location type's workspace Ω+ (as a point cloud with
    /// the signed distance) and learned stances (arrows) at every location of the world of
    /// that type, and each part type's grasps (arrows along the TCP's approach axis) on the
    /// part at every location.
    #[arg(long)]
    pub blob: Option<PathBuf>,
    /// The world whose locations and obstacles are drawn (default: the built-in example).
    #[command(flatten)]
    pub world: WorldArgs,
    /// Rate of joint states and transforms, Hz.
    #[arg(long, default_value_t = 100.0)]
    pub rate: f64,
    /// The bag to write (.mcap).
    #[arg(short, long)]
    pub out: PathBuf,
}

/// The example robot's URDF and its names (the blob's and the datasets' robot).
fn robot_description() -> anyhow::Result<(&'static str, ChainNames)> {
    let names = robot::chain_names(robot::EXAMPLE_URDF, "offline/data/kmr_iiwa14.urdf")?;
    Ok((robot::EXAMPLE_URDF, names))
}

fn create(path: &Path) -> anyhow::Result<Exporter> {
    let (urdf, names) = robot_description()?;
    Ok(Exporter::create(path, urdf, names)?)
}

/// The world's locations as frames.
fn location_frames(world: &World) -> Vec<(String, Pose)> {
    (0..world.locations.len())
        .map(|i| (world.locations[i].id.clone(), world.location_pose(i)))
        .collect()
}

/// The world's obstacles as grey boxes.
fn obstacles(world: &World) -> Vec<Marker> {
    let cell = Cell::new(world, &prf_shared::robot::RobotModel::kmr_iiwa14());
    cell.obstacles
        .iter()
        .enumerate()
        .map(|(i, o)| {
            let (c, yaw, half) = o.cuboid();
            let pose = Pose::from_parts(
                c.into(),
                nalgebra::UnitQuaternion::from_axis_angle(&nalgebra::Vector3::z_axis(), yaw),
            );
            let size = [2.0 * half.x, 2.0 * half.y, 2.0 * half.z];
            marker(
                "obstacles",
                i as i32,
                CUBE,
                "map",
                &pose,
                size,
                rgba(0.6, 0.6, 0.65, 0.8),
            )
        })
        .collect()
}

/// A part at `start` (blue) and its goal (green).
fn part_markers(id: i32, size: [f64; 3], start: &Pose, goal: &Pose) -> [Marker; 2] {
    [
        marker(
            "part",
            2 * id,
            CUBE,
            "map",
            start,
            size,
            rgba(0.2, 0.4, 0.9, 0.9),
        ),
        marker(
            "part goal",
            2 * id + 1,
            CUBE,
            "map",
            goal,
            size,
            rgba(0.2, 0.8, 0.3, 0.5),
        ),
    ]
}

fn report(path: &Path, counts: &[(String, &'static str, u64)]) {
    println!(
        "{}: ROS 2 bag (MCAP, CDR) for Foxglove or rerun",
        path.display()
    );
    for (topic, schema, n) in counts {
        println!("  {topic:<32} {schema:<36} {n:>7} messages");
    }
}

/// `prf plan --mcap`: the executed program with its risk, both workspaces at their
/// locations, the world's obstacles and the part.
pub fn program(
    world: &World,
    rt: &prf_runtime::Runtime<'_>,
    ft: &FloorTask,
    plan: &Plan,
    samples: &[prf_files::dataset::Sample],
    rate: f64,
    path: &Path,
) -> anyhow::Result<()> {
    let mut x = create(path)?;
    let frames = location_frames(world);
    x.locations(&frames)?;
    for (id, t) in [
        (&ft.from.0, plan.resolved.from_type),
        (&ft.to.0, plan.resolved.to_type),
    ] {
        if let Some(field) = rt.workspace(t)? {
            x.workspace(id, id, &field)?;
        }
    }
    x.markers("/prf/obstacles", obstacles(world))?;
    let size = drawn_part_size(world, &ft.part.1);
    x.markers(
        "/prf/parts",
        part_markers(0, size, &ft.part_pose, &ft.goal).to_vec(),
    )?;
    let risk = program_risk(rt, plan, &ft.from_pose, &ft.to_pose, samples)?;
    let every = (1.0 / (rate * rt.config.rdmp.dt)).round().max(1.0) as usize;
    x.samples(T0, samples, every, Some(&risk))?;
    let counts = x.finish()?;
    report(path, &counts);
    Ok(())
}

pub fn run(a: &Args) -> anyhow::Result<()> {
    let world = a.world.load()?;
    let mut x = create(&a.out)?;
    if let Some(dir) = &a.dataset {
        let model = prf_shared::robot::RobotModel::kmr_iiwa14();
        let ds = Dataset::read(dir, &model)?;
        let mut frames = location_frames(&world);
        let mut parts = Vec::new();
        let mut t0 = T0;
        for (i, d) in ds.demonstrations.iter().enumerate() {
            for l in [&d.task.from, &d.task.to] {
                if !frames.iter().any(|(id, _)| *id == l.id) {
                    frames.push((l.id.clone(), pose(&l.pose, &d.id)?));
                }
            }
            let size = drawn_part_size(&world, &d.task.part.kind);
            let (start, goal) = (pose(&d.task.part.pose, &d.id)?, pose(&d.task.goal, &d.id)?);
            parts.extend(part_markers(i as i32, size, &start, &goal));
            let every = d.samples.windows(2).next().map_or(1, |w| {
                ((1.0 / a.rate) / (w[1].t - w[0].t)).round().max(1.0) as usize
            });
            x.samples(t0, &d.samples, every, None)?;
            let end = d.samples.last().map_or(0.0, |s| s.t);
            t0 += ((end + 1.0) * 1e9).round() as i64;
        }
        x.locations(&frames)?;
        x.markers("/prf/parts", parts)?;
    }
    if let Some(path) = &a.blob {
        let bytes = read_blob(path)?;
        let rt = runtime(&bytes, path, RuntimeConfig::default())?;
        x.locations(&location_frames(&world))?;
        let mut stances = Vec::new();
        for t in 0..rt.blob.payload.location_types.len() {
            let lt = rt
                .blob
                .location_type(t)
                .with_context(|| format!("location type {t} of {}", path.display()))?;
            let field = rt.workspace(t)?;
            for l in world.locations.iter().filter(|l| l.kind == lt.name) {
                if let Some(f) = &field {
                    x.workspace(&l.id, &l.id, f)?;
                }
                for s in &lt.stances {
                    let p = pose_from_array(*s).context("a stance of the blob")?;
                    let id = stances.len() as i32;
                    stances.push(marker(
                        "stances",
                        id,
                        ARROW,
                        &l.id,
                        &p,
                        [0.4, 0.06, 0.06],
                        rgba(0.95, 0.6, 0.1, 0.9),
                    ));
                }
            }
        }
        x.markers("/prf/stances", stances)?;
        x.markers("/prf/grasps", grasps(&rt, &world, path)?)?;
    }
    x.markers("/prf/obstacles", obstacles(&world))?;
    let counts = x.finish()?;
    report(&a.out, &counts);
    Ok(())
}

/// Each part type's learned grasps (the TCP, the arrow along its approach axis z) on the
/// part at its nominal pose at every location of the world.
fn grasps(
    rt: &prf_runtime::Runtime<'_>,
    world: &World,
    path: &Path,
) -> anyhow::Result<Vec<Marker>> {
    // The marker's arrow points along its x axis: turn x onto the TCP's z.
    let x_to_z = nalgebra::UnitQuaternion::from_axis_angle(
        &nalgebra::Vector3::y_axis(),
        -std::f64::consts::FRAC_PI_2,
    );
    let mut out = Vec::new();
    for t in 0..rt.blob.payload.part_types.len() {
        let pt = rt
            .blob
            .part_type(t)
            .with_context(|| format!("part type {t} of {}", path.display()))?;
        for l in 0..world.locations.len() {
            let part = world.part_pose_at(l);
            for g in &pt.grasps {
                let tcp = part * pose_from_array(*g).context("a grasp of the blob")?;
                let arrow = Pose::from_parts(tcp.translation, tcp.rotation * x_to_z);
                let id = out.len() as i32;
                out.push(marker(
                    &format!("grasps {}", pt.name),
                    id,
                    ARROW,
                    "map",
                    &arrow,
                    [0.12, 0.015, 0.015],
                    rgba(0.6, 0.2, 0.8, 0.9),
                ));
            }
        }
    }
    Ok(out)
}

fn pose(p: &[f64; 7], demonstration: &str) -> anyhow::Result<Pose> {
    pose_from_array(*p).with_context(|| format!("demonstration {demonstration}: a pose"))
}
