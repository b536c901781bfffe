//! The robot model from a URDF (urdf-rs) plus a sphere file: the description the blob
//! compiler embeds, so another arm is a file change, not a code change.
//!
//! URDF convention: the root link is the platform base `b` (its collision box is the
//! platform body); fixed joints up to the first revolute joint give the arm mount; then
//! exactly 7 revolute joints; after the 7th, a fixed joint to the flange link (frame 8 of
//! the spheres) and fixed joints from there to the TCP link (the chain's last link).
//! The sphere file (JSON, `prf-spheres` v1) lists spheres by link name and the home
//! configuration. Errors name the file and, where the JSON has one, the line.

use crate::line_of;
use nalgebra::{Unit, Vector3};
use prf_shared::NA;
use prf_shared::robot::{Joint, MAX_SPHERES, PlatformBox, RobotModel, Sphere};
use prf_shared::se3::{Pose, pose_from_xyz_rpy};
use serde::Deserialize;
use std::path::Path;

/// The example cell's robot description, shipped with the project.
pub const EXAMPLE_URDF: &str = include_str!("../../data/kmr_iiwa14.urdf");
pub const EXAMPLE_SPHERES: &str = include_str!("../../data/kmr_iiwa14.spheres.json");

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SphereFile {
    format: String,
    version: u32,
    #[serde(default)]
    #[allow(dead_code)]
    comment: Option<String>,
    home_deg: [f64; NA],
    /// How far at least every sphere reaches beyond its link's surface, m (optional).
    #[serde(default)]
    margin_m: Option<f64>,
    spheres: Vec<SphereEntry>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SphereEntry {
    link: String,
    centre: [f64; 3],
    radius: f64,
}

/// Why a robot description was refused; every message names the file (and the line where the
/// JSON has one).
#[derive(Debug, thiserror::Error)]
pub enum RobotFileError {
    #[error("reading {path}")]
    Read {
        path: String,
        #[source]
        source: std::io::Error,
    },
    #[error("{file}: not a valid URDF")]
    Urdf {
        file: String,
        #[source]
        source: urdf_rs::UrdfError,
    },
    #[error("{file}:{line}: {detail}")]
    Json {
        file: String,
        line: usize,
        /// What the JSON parser found.
        detail: String,
    },
    #[error("{urdf} + {spheres}: invalid robot model: {error}")]
    Model {
        urdf: String,
        spheres: String,
        error: prf_shared::robot::ModelError,
    },
    /// The description parses but is not a robot the runtime takes (the message says why).
    #[error("{0}")]
    Invalid(String),
}

/// Returns `RobotFileError::Invalid` with a formatted message.
macro_rules! invalid {
    ($($arg:tt)*) => {
        return Err(RobotFileError::Invalid(format!($($arg)*)))
    };
}

fn pose(o: &urdf_rs::Pose) -> Pose {
    pose_from_xyz_rpy(o.xyz.0, o.rpy.0)
}

fn read_urdf(urdf: &str, urdf_name: &str) -> Result<urdf_rs::Robot, RobotFileError> {
    urdf_rs::read_from_string(urdf).map_err(|source| RobotFileError::Urdf {
        file: urdf_name.to_string(),
        source,
    })
}

/// A URDF's root link, its one chain of joints from there, and the indices in it of the
/// arm's [`NA`] consecutive revolute joints.
struct ArmChain<'a> {
    root: &'a urdf_rs::Link,
    chain: Vec<&'a urdf_rs::Joint>,
    revolute: Vec<usize>,
}

fn arm_chain<'a>(
    robot: &'a urdf_rs::Robot,
    urdf_name: &str,
) -> Result<ArmChain<'a>, RobotFileError> {
    let children: Vec<&str> = robot.joints.iter().map(|j| j.child.link.as_str()).collect();
    let roots: Vec<&urdf_rs::Link> = robot
        .links
        .iter()
        .filter(|l| !children.contains(&l.name.as_str()))
        .collect();
    let [root] = roots[..] else {
        invalid!(
            "{urdf_name}: expected one root link (the platform base), found {}",
            roots.len()
        );
    };
    // Walk the chain from the root.
    let mut chain: Vec<&urdf_rs::Joint> = Vec::new();
    let mut link = root.name.as_str();
    while let Some(j) = robot.joints.iter().find(|j| j.parent.link == link) {
        if robot
            .joints
            .iter()
            .filter(|k| k.parent.link == link)
            .count()
            > 1
        {
            invalid!("{urdf_name}: link '{link}' branches; the robot must be one chain");
        }
        if chain.iter().any(|k| std::ptr::eq(*k, j)) {
            invalid!(
                "{urdf_name}: joint '{}' closes a loop back to link '{link}'; the robot must be one chain",
                j.name
            );
        }
        chain.push(j);
        link = &j.child.link;
    }
    let revolute: Vec<usize> = chain
        .iter()
        .enumerate()
        .filter(|(_, j)| j.joint_type != urdf_rs::JointType::Fixed)
        .map(|(i, _)| i)
        .collect();
    if revolute.len() != NA
        || chain.iter().any(|j| {
            !matches!(
                j.joint_type,
                urdf_rs::JointType::Fixed | urdf_rs::JointType::Revolute
            )
        })
    {
        invalid!(
            "{urdf_name}: expected {NA} revolute joints and fixed joints only, found {} movable",
            revolute.len()
        );
    }
    if revolute.windows(2).any(|w| w[1] != w[0] + 1) {
        invalid!("{urdf_name}: fixed joints between the arm's revolute joints are not supported");
    }
    Ok(ArmChain {
        root,
        chain,
        revolute,
    })
}

/// The names a URDF gives the robot's frames and joints, as ROS messages use them.
#[derive(Clone, Debug, PartialEq)]
pub struct ChainNames {
    /// The root link: the platform frame that `/tf` places in the world.
    pub root_link: String,
    /// The arm's joints A1 … A7, in chain order (as joint states name them).
    pub arm_joints: Vec<String>,
}

/// The frame and joint names of a URDF.
pub fn chain_names(urdf: &str, urdf_name: &str) -> Result<ChainNames, RobotFileError> {
    let robot = read_urdf(urdf, urdf_name)?;
    let arm = arm_chain(&robot, urdf_name)?;
    Ok(ChainNames {
        root_link: arm.root.name.clone(),
        arm_joints: arm
            .revolute
            .iter()
            .map(|&i| arm.chain[i].name.clone())
            .collect(),
    })
}

/// The model described by URDF text and sphere-file text (`urdf_name`, `spheres_name` name
/// the sources in errors).
pub fn parse(
    urdf: &str,
    urdf_name: &str,
    spheres: &str,
    spheres_name: &str,
) -> Result<RobotModel, RobotFileError> {
    let robot = read_urdf(urdf, urdf_name)?;
    let ArmChain {
        root,
        chain,
        revolute,
    } = arm_chain(&robot, urdf_name)?;
    let (first, last) = (revolute[0], revolute[NA - 1]);
    let mount = chain[..first]
        .iter()
        .fold(Pose::identity(), |p, j| p * pose(&j.origin));
    let after = &chain[last + 1..];
    let Some((flange_joint, to_tcp)) = after.split_first() else {
        invalid!("{urdf_name}: no fixed joint to a flange link after the last revolute joint");
    };
    let flange = pose(&flange_joint.origin);
    let tcp = to_tcp
        .iter()
        .fold(Pose::identity(), |p, j| p * pose(&j.origin));
    let mut joints = [Joint::unset(); NA];
    for (slot, &i) in joints.iter_mut().zip(&revolute) {
        let j = chain[i];
        let axis = Vector3::from(j.axis.xyz.0);
        if !(axis.norm() > 1e-9) {
            invalid!("{urdf_name}: joint '{}' has a zero axis", j.name);
        }
        *slot = Joint {
            origin: pose(&j.origin),
            axis: Unit::new_normalize(axis),
            lower: j.limit.lower,
            upper: j.limit.upper,
            max_speed: j.limit.velocity,
        };
    }
    let platform = root
        .collision
        .iter()
        .find_map(|c| match &c.geometry {
            urdf_rs::Geometry::Box { size } => Some(PlatformBox {
                centre: Vector3::from(c.origin.xyz.0),
                half_extents: Vector3::from(size.0) / 2.0,
            }),
            _ => None,
        })
        .ok_or_else(|| {
            RobotFileError::Invalid(format!(
                "{urdf_name}: root link '{}' has no collision box",
                root.name
            ))
        })?;
    // Frames of the sphere file: the arm base link, links 1..7, the flange.
    let mut frames: Vec<&str> = vec![chain[first].parent.link.as_str()];
    frames.extend(revolute.iter().map(|&i| chain[i].child.link.as_str()));
    frames.push(flange_joint.child.link.as_str());

    let file: SphereFile = serde_json::from_str(spheres).map_err(|e| RobotFileError::Json {
        file: spheres_name.to_string(),
        line: e.line(),
        detail: e.to_string(),
    })?;
    if file.format != "prf-spheres" || file.version != 1 {
        invalid!(
            "{spheres_name}: format '{}' v{}, expected 'prf-spheres' v1",
            file.format,
            file.version
        );
    }
    if file.spheres.len() > MAX_SPHERES {
        invalid!(
            "{spheres_name}: {} spheres, at most {MAX_SPHERES}",
            file.spheres.len()
        );
    }
    let mut list = heapless::Vec::new();
    for s in &file.spheres {
        let at = line_of(spheres, &format!("\"{}\"", s.link)).unwrap_or(0);
        let Some(link) = frames.iter().position(|f| *f == s.link) else {
            invalid!(
                "{spheres_name}:{at}: sphere on link '{}', which is not a frame of the arm ({})",
                s.link,
                frames.join(", ")
            );
        };
        if !(s.radius > 0.0 && s.radius.is_finite()) || s.centre.iter().any(|v| !v.is_finite()) {
            invalid!(
                "{spheres_name}:{at}: bad sphere on '{}': radius {}",
                s.link,
                s.radius
            );
        }
        let _ = list.push(Sphere {
            link: link as u8,
            centre: Vector3::from(s.centre),
            radius: s.radius,
        });
    }
    let model = RobotModel {
        mount,
        joints,
        flange,
        tcp,
        spheres: list,
        platform,
        home: file.home_deg.map(|d| d.to_radians()),
        sphere_margin: file.margin_m.unwrap_or(0.0),
    };
    model.validate().map_err(|error| RobotFileError::Model {
        urdf: urdf_name.to_string(),
        spheres: spheres_name.to_string(),
        error,
    })?;
    Ok(model)
}

/// Reads a URDF and a sphere file.
pub fn load(urdf: &Path, spheres: &Path) -> Result<RobotModel, RobotFileError> {
    let read = |path: &Path| {
        std::fs::read_to_string(path).map_err(|source| RobotFileError::Read {
            path: path.display().to_string(),
            source,
        })
    };
    let (u, s) = (read(urdf)?, read(spheres)?);
    parse(
        &u,
        &urdf.display().to_string(),
        &s,
        &spheres.display().to_string(),
    )
}

/// The example cell's robot, from the shipped URDF and sphere file.
pub fn example() -> Result<RobotModel, RobotFileError> {
    parse(
        EXAMPLE_URDF,
        "offline/data/kmr_iiwa14.urdf",
        EXAMPLE_SPHERES,
        "offline/data/kmr_iiwa14.spheres.json",
    )
}
