//! `prf import-bag`: a ROS 2 bag (MCAP, CDR) and its task annotation as a dataset
//! (`prf_files::bag`; formats in `docs/formats.md`).

use prf_files::bag::{self, BagConfig, PlatformSource};
use prf_files::dataset::Dataset;
use prf_files::robot;
use std::path::PathBuf;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// The bag: an MCAP file as rosbag2 records it (CDR messages).
    pub bag: PathBuf,
    /// The task annotation (YAML, or JSON for .json): r_d, the gripper joint, parts,
    /// locations, and per program its time span and task.
    #[arg(long)]
    pub tasks: PathBuf,
    /// Dataset directory to write.
    #[arg(short, long)]
    pub out: PathBuf,
    /// Robot URDF whose arm joint names the joint states use; default: the example cell's
    /// KMR iiwa 14 (offline/data/kmr_iiwa14.urdf).
    #[arg(long, requires = "spheres")]
    pub urdf: Option<PathBuf>,
    /// Collision-sphere file for --urdf (to validate the imported programs' joint limits).
    #[arg(long, requires = "urdf")]
    pub spheres: Option<PathBuf>,
    /// The sensor_msgs/msg/JointState topic.
    #[arg(long, default_value = "/joint_states")]
    pub joints: String,
    /// The nav_msgs/msg/Odometry topic giving the platform pose in the world.
    #[arg(long, default_value = "/odom", conflicts_with = "tf")]
    pub odom: String,
    /// Take the platform pose from tf2_msgs/msg/TFMessage on /tf instead: PARENT,CHILD frames
    /// (e.g. map,base_footprint).
    #[arg(long, value_parser = parse_frames)]
    pub tf: Option<(String, String)>,
    /// The /tf topic for --tf.
    #[arg(long, default_value = "/tf")]
    pub tf_topic: String,
    /// Longest silence of a topic inside a program, ms.
    #[arg(long, default_value_t = 100.0)]
    pub max_gap_ms: f64,
    /// Sample rate of the written trajectories, Hz.
    #[arg(long, default_value_t = 100.0)]
    pub rate: f64,
}

fn parse_frames(s: &str) -> Result<(String, String), String> {
    match s.split_once(',') {
        Some((p, c)) if !p.is_empty() && !c.is_empty() => Ok((p.into(), c.into())),
        _ => Err(format!("{s:?}: expected PARENT,CHILD")),
    }
}

pub fn run(a: &Args) -> anyhow::Result<()> {
    let (model, arm) = match (&a.urdf, &a.spheres) {
        (Some(u), Some(s)) => {
            let text = std::fs::read_to_string(u)
                .map_err(|e| anyhow::anyhow!("{}: cannot read: {e}", u.display()))?;
            let arm = robot::chain_names(&text, &u.display().to_string())?.arm_joints;
            (robot::load(u, s)?, arm)
        }
        _ => (
            robot::example()?,
            robot::chain_names(robot::EXAMPLE_URDF, "offline/data/kmr_iiwa14.urdf")?.arm_joints,
        ),
    };
    let cfg = BagConfig {
        joint_topic: a.joints.clone(),
        platform: match &a.tf {
            Some((parent, child)) => PlatformSource::Tf {
                topic: a.tf_topic.clone(),
                parent: parent.clone(),
                child: child.clone(),
            },
            None => PlatformSource::Odometry {
                topic: a.odom.clone(),
            },
        },
        max_gap_s: a.max_gap_ms * 1e-3,
        rate_hz: a.rate,
    };
    let annotation = bag::read_annotation(&a.tasks)?;
    let dataset = bag::import(&a.bag, &annotation, &arm, &cfg)?;
    dataset.write(&a.out)?;
    // The written dataset passes exactly the reader's validation (limits, poses, ids).
    let back = Dataset::read(&a.out, &model)?;
    let samples: usize = back.demonstrations.iter().map(|d| d.samples.len()).sum();
    println!(
        "{}: {} programs, {} samples at {} Hz from {} ({}, platform from {}) → {}",
        a.bag.display(),
        back.demonstrations.len(),
        samples,
        a.rate,
        a.tasks.display(),
        a.joints,
        match &cfg.platform {
            PlatformSource::Odometry { topic } => format!("odometry {topic}"),
            PlatformSource::Tf {
                topic,
                parent,
                child,
            } => format!("{topic} {parent} → {child}"),
        },
        a.out.display()
    );
    Ok(())
}
