//! The ground-truth world of a cell (Sec. 3.4, Fig. 2): location types with their obstacle
//! boxes, approaches (base stances) and nominal part pose; part types with their grasps;
//! location instances on the floor plan; the demonstrations' clearance r_d and the true
//! acceptable clearance r (Sec. 4.1, ε = r_d − r).
//!
//! Only the demonstration generator and validation read it: learning and the runtime never
//! see the true geometry. The format is documented in `docs/formats.md`; the built-in example
//! is `offline/data/example-world.json`.

pub mod floorplan;
pub mod geometry;

use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use prf_files::line_of;
use prf_shared::se3::{Pose, pose_from_xyz_rpy};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// The built-in example cell.
/// Why a world file was refused; every message names the file, the line and the value.
#[derive(Debug, thiserror::Error)]
pub enum WorldError {
    #[error("{path}: cannot read the world file")]
    Read {
        path: String,
        #[source]
        source: std::io::Error,
    },
    #[error("{file}:{line}:{column}: {detail}")]
    Json {
        file: String,
        line: usize,
        column: usize,
        /// What the JSON parser found.
        detail: String,
    },
    /// The file parses but describes no valid cell (the message says where and why).
    #[error("{0}")]
    Invalid(String),
}

/// Returns `WorldError::Invalid` with a formatted message.
macro_rules! invalid {
    ($($arg:tt)*) => {
        return Err(WorldError::Invalid(format!($($arg)*)))
    };
}

pub const EXAMPLE_WORLD: &str = include_str!("../../../data/example-world.json");
/// Name shown for the built-in world in messages.
pub const EXAMPLE_WORLD_NAME: &str = "<built-in example-world.json>";
/// The built-in plant: twelve locations of four types, three part types
/// (`offline/data/plant-world.json`, `--world plant`).
pub const PLANT_WORLD: &str = include_str!("../../../data/plant-world.json");
/// Name shown for the built-in plant in messages.
pub const PLANT_WORLD_NAME: &str = "<built-in plant-world.json>";

/// Value of the `format` field.
pub const FORMAT: &str = "prf-world";
/// Supported `version`.
pub const VERSION: u32 = 1;

#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct World {
    pub format: String,
    pub version: u32,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub description: Option<String>,
    pub clearance: Clearance,
    /// Home pose of the platform in the world.
    pub home: Planar,
    pub location_types: Vec<LocationType>,
    pub part_types: Vec<PartType>,
    pub locations: Vec<Location>,
    pub parts: Vec<Part>,
    /// Which tasks the cell has ([`World::tasks`]).
    #[serde(default, skip_serializing_if = "TaskRule::is_first_instances")]
    pub tasks: TaskRule,
    /// Where the world was read from (for messages).
    #[serde(skip)]
    pub source: PathBuf,
}

/// Which location instances a cell's tasks run between.
#[derive(Clone, Copy, Debug, Default, PartialEq, Deserialize, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum TaskRule {
    /// Per ordered pair of location types, from the first instance of the first type to the
    /// first other instance of the second (the example cell's 18 tasks).
    #[default]
    FirstInstances,
    /// Between every ordered pair of distinct location instances (a plant, whose archive
    /// holds programs between all its machines).
    EveryPair,
}

impl TaskRule {
    fn is_first_instances(&self) -> bool {
        *self == TaskRule::FirstInstances
    }
}

/// Clearances, m.
#[derive(Clone, Copy, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Clearance {
    /// r_d: the conservative clearance every demonstration keeps from every obstacle.
    pub demonstration: f64,
    /// r: the true acceptable clearance (r < r_d).
    pub acceptable: f64,
    /// Minimum distance between non-adjacent robot parts (self-collision).
    #[serde(rename = "self")]
    pub self_collision: f64,
}

impl Clearance {
    /// ε = r_d − r, the dilation of the learned workspace (Eq. 14).
    pub fn epsilon(&self) -> f64 {
        self.demonstration - self.acceptable
    }
}

/// A planar pose on the floor: x, y in m, yaw in degrees.
#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Planar {
    pub x: f64,
    pub y: f64,
    pub yaw_deg: f64,
}

/// [x, y, yaw (rad)] of a pose on the floor: the runtime's, one definition for both.
pub use prf_runtime::executor::planar;

impl Planar {
    pub fn pose(&self) -> Pose {
        Isometry3::from_parts(
            Translation3::new(self.x, self.y, 0.0),
            UnitQuaternion::from_axis_angle(&Vector3::z_axis(), self.yaw_deg.to_radians()),
        )
    }
}

/// A pose given as translation (m) and fixed-axis roll, pitch, yaw (degrees),
/// R = Rz(yaw) Ry(pitch) Rx(roll).
#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct PoseSpec {
    pub xyz: [f64; 3],
    pub rpy_deg: [f64; 3],
}

impl PoseSpec {
    pub fn pose(&self) -> Pose {
        pose_from_xyz_rpy(self.xyz, self.rpy_deg.map(f64::to_radians))
    }
}

/// An axis-aligned obstacle box in the location frame.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct BoxSpec {
    pub name: String,
    pub min: [f64; 3],
    pub max: [f64; 3],
}

/// A way to stand at a location: the base stance T_b^ℓ and the waypoints the platform drives
/// from the stance out into the aisle (the reverse on arrival).
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Approach {
    pub name: String,
    pub stance: Planar,
    pub exit: Vec<Planar>,
}

#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct LocationType {
    pub name: String,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub description: Option<String>,
    /// Nominal pose of a part at this location, in the location frame.
    pub part_pose: PoseSpec,
    pub boxes: Vec<BoxSpec>,
    pub approaches: Vec<Approach>,
}

/// A grasp: the TCP pose T_e^p in the part frame.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Grasp {
    pub name: String,
    pub tcp: PoseSpec,
}

#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct PartType {
    pub name: String,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub description: Option<String>,
    /// Bounding box of the part, m (documentation and plots; parts are not obstacles).
    pub size: [f64; 3],
    pub grasps: Vec<Grasp>,
}

/// A location instance on the floor plan.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Location {
    pub id: String,
    #[serde(rename = "type")]
    pub kind: String,
    pub x: f64,
    pub y: f64,
    pub yaw_deg: f64,
}

#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Part {
    pub id: String,
    #[serde(rename = "type")]
    pub kind: String,
}

/// A task T: move part `part` from location `from` to location `to` (indices into the world's
/// lists), part and locations at their nominal poses.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Task {
    pub part: usize,
    pub from: usize,
    pub to: usize,
}

/// An afforded task T_A (Sec. 7): a task with the approach used at each location and the
/// grasp (indices into the location types' approaches and the part type's grasps).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct AffordedTask {
    pub task: Task,
    pub approach_from: usize,
    pub approach_to: usize,
    pub grasp: usize,
}

impl World {
    /// The built-in example cell.
    pub fn example() -> World {
        // The built-in file is checked by the tests; failing to parse it is a build defect.
        Self::parse(EXAMPLE_WORLD, Path::new(EXAMPLE_WORLD_NAME))
            .expect("the built-in example world is valid")
    }

    /// The built-in plant ([`PLANT_WORLD`]).
    pub fn plant() -> World {
        Self::parse(PLANT_WORLD, Path::new(PLANT_WORLD_NAME))
            .expect("the built-in plant world is valid")
    }

    /// The world `name` names: `example` or `plant` for a built-in one (unless a file of that
    /// name exists), otherwise the world file at that path ([`World::load`]).
    pub fn named(name: &Path) -> Result<World, WorldError> {
        match name.to_str() {
            Some("example") if !name.exists() => Ok(World::example()),
            Some("plant") if !name.exists() => Ok(World::plant()),
            _ => World::load(name),
        }
    }

    /// Reads and validates a world file.
    pub fn load(path: &Path) -> Result<World, WorldError> {
        let text = std::fs::read_to_string(path).map_err(|source| WorldError::Read {
            path: path.display().to_string(),
            source,
        })?;
        Self::parse(&text, path)
    }

    /// Parses and validates world JSON; errors name the file, the line and the value.
    pub fn parse(text: &str, source: &Path) -> Result<World, WorldError> {
        let mut world: World = serde_json::from_str(text).map_err(|e| WorldError::Json {
            file: source.display().to_string(),
            line: e.line(),
            column: e.column(),
            detail: e.to_string(),
        })?;
        world.source = source.to_path_buf();
        world.validate(text)?;
        Ok(world)
    }

    fn validate(&self, text: &str) -> Result<(), WorldError> {
        let at = |needle: &str| {
            format!(
                "{}:{}",
                self.source.display(),
                line_of(text, needle).unwrap_or(1)
            )
        };
        if self.format != FORMAT {
            invalid!(
                "{}: format {:?}, expected {FORMAT:?}",
                at("\"format\""),
                self.format
            );
        }
        if self.version != VERSION {
            invalid!(
                "{}: version {}, this build reads {VERSION}",
                at("\"version\""),
                self.version
            );
        }
        let c = &self.clearance;
        let ordered = c.acceptable > 0.0
            && c.demonstration > c.acceptable
            && c.demonstration.is_finite()
            && c.self_collision >= 0.0
            && c.self_collision.is_finite();
        if !ordered {
            invalid!(
                "{}: clearances must satisfy 0 < acceptable < demonstration and self >= 0, \
                 got demonstration {} acceptable {} self {}",
                at("\"clearance\""),
                c.demonstration,
                c.acceptable,
                c.self_collision
            );
        }
        finite(&[self.home.x, self.home.y, self.home.yaw_deg], || {
            at("\"home\"")
        })?;
        unique(
            self.location_types.iter().map(|t| t.name.as_str()),
            "location type",
            &at,
        )?;
        unique(
            self.part_types.iter().map(|t| t.name.as_str()),
            "part type",
            &at,
        )?;
        unique(
            self.locations.iter().map(|l| l.id.as_str()),
            "location id",
            &at,
        )?;
        unique(self.parts.iter().map(|p| p.id.as_str()), "part id", &at)?;
        for t in &self.location_types {
            let here = || at(&format!("\"{}\"", t.name));
            if t.approaches.is_empty() {
                invalid!("{}: location type {} has no approach", here(), t.name);
            }
            unique(
                t.approaches.iter().map(|a| a.name.as_str()),
                "approach",
                &at,
            )?;
            finite(&[t.part_pose.xyz, t.part_pose.rpy_deg].concat(), here)?;
            for b in &t.boxes {
                let line = || at(&format!("\"{}\"", b.name));
                finite(&[b.min, b.max].concat(), line)?;
                if (0..3).any(|k| b.min[k] >= b.max[k]) {
                    invalid!(
                        "{}: box {} of {}: min {:?} is not below max {:?}",
                        line(),
                        b.name,
                        t.name,
                        b.min,
                        b.max
                    );
                }
            }
            for a in &t.approaches {
                for p in std::iter::once(&a.stance).chain(&a.exit) {
                    finite(&[p.x, p.y, p.yaw_deg], || at(&format!("\"{}\"", a.name)))?;
                }
            }
        }
        for p in &self.part_types {
            let here = || at(&format!("\"{}\"", p.name));
            if p.grasps.is_empty() {
                invalid!("{}: part type {} has no grasp", here(), p.name);
            }
            unique(p.grasps.iter().map(|g| g.name.as_str()), "grasp", &at)?;
            for g in &p.grasps {
                finite(&[g.tcp.xyz, g.tcp.rpy_deg].concat(), here)?;
            }
        }
        for l in &self.locations {
            let here = || at(&format!("\"{}\"", l.id));
            finite(&[l.x, l.y, l.yaw_deg], here)?;
            if self.location_type_index(&l.kind).is_none() {
                invalid!(
                    "{}: location {} has unknown type {:?}",
                    here(),
                    l.id,
                    l.kind
                );
            }
        }
        for p in &self.parts {
            if self.part_type_index(&p.kind).is_none() {
                invalid!(
                    "{}: part {} has unknown type {:?}",
                    at(&format!("\"{}\"", p.id)),
                    p.id,
                    p.kind
                );
            }
        }
        Ok(())
    }

    pub fn location_type_index(&self, name: &str) -> Option<usize> {
        self.location_types.iter().position(|t| t.name == name)
    }

    pub fn part_type_index(&self, name: &str) -> Option<usize> {
        self.part_types.iter().position(|t| t.name == name)
    }

    pub fn location_index(&self, id: &str) -> Option<usize> {
        self.locations.iter().position(|l| l.id == id)
    }

    pub fn part_index(&self, id: &str) -> Option<usize> {
        self.parts.iter().position(|p| p.id == id)
    }

    /// Type of location instance `i`.
    pub fn location_type(&self, i: usize) -> &LocationType {
        let name = &self.locations[i].kind;
        &self.location_types[self.location_type_index(name).unwrap_or(0)]
    }

    /// Type of part instance `i`.
    pub fn part_type(&self, i: usize) -> &PartType {
        let name = &self.parts[i].kind;
        &self.part_types[self.part_type_index(name).unwrap_or(0)]
    }

    /// Pose T_ℓ of location instance `i` in the world.
    pub fn location_pose(&self, i: usize) -> Pose {
        let l = &self.locations[i];
        Planar {
            x: l.x,
            y: l.y,
            yaw_deg: l.yaw_deg,
        }
        .pose()
    }

    /// Nominal pose of a part at location `i`, in the world.
    pub fn part_pose_at(&self, i: usize) -> Pose {
        self.location_pose(i) * self.location_type(i).part_pose.pose()
    }

    /// The tasks of the cell, by its [`TaskRule`]: every part between every ordered pair of
    /// location types, from the first instance of the first type to the first instance of
    /// the second type that is not the start (so CNC → CNC is CNC1 → CNC2), or every part
    /// between every ordered pair of distinct instances. Parts and locations at nominal poses.
    pub fn tasks(&self) -> Vec<Task> {
        let mut out = Vec::new();
        if self.tasks == TaskRule::EveryPair {
            let n = self.locations.len();
            for part in 0..self.parts.len() {
                for from in 0..n {
                    for to in (0..n).filter(|&to| to != from) {
                        out.push(Task { part, from, to });
                    }
                }
            }
            return out;
        }
        for part in 0..self.parts.len() {
            for t1 in &self.location_types {
                for t2 in &self.location_types {
                    let from = self.locations.iter().position(|l| l.kind == t1.name);
                    let Some(from) = from else { continue };
                    let to = (0..self.locations.len())
                        .find(|&i| i != from && self.locations[i].kind == t2.name);
                    if let Some(to) = to {
                        out.push(Task { part, from, to });
                    }
                }
            }
        }
        out
    }

    /// Every afforded task: each task × approach at `from` × approach at `to` × grasp.
    pub fn afforded_tasks(&self) -> Vec<AffordedTask> {
        let mut out = Vec::new();
        for task in self.tasks() {
            let n_from = self.location_type(task.from).approaches.len();
            let n_to = self.location_type(task.to).approaches.len();
            let n_grasp = self.part_type(task.part).grasps.len();
            for approach_from in 0..n_from {
                for approach_to in 0..n_to {
                    for grasp in 0..n_grasp {
                        out.push(AffordedTask {
                            task,
                            approach_from,
                            approach_to,
                            grasp,
                        });
                    }
                }
            }
        }
        out
    }

    /// A short human-readable label, e.g. `Part1 CNC1.front -> Table1.side, grasp top`.
    pub fn label(&self, a: &AffordedTask) -> String {
        let t = &a.task;
        format!(
            "{} {}.{} -> {}.{}, grasp {}",
            self.parts[t.part].id,
            self.locations[t.from].id,
            self.location_type(t.from).approaches[a.approach_from].name,
            self.locations[t.to].id,
            self.location_type(t.to).approaches[a.approach_to].name,
            self.part_type(t.part).grasps[a.grasp].name,
        )
    }
}

fn finite(values: &[f64], at: impl Fn() -> String) -> Result<(), WorldError> {
    if let Some(v) = values.iter().find(|v| !v.is_finite()) {
        invalid!("{}: non-finite value {v}", at());
    }
    Ok(())
}

fn unique<'a>(
    names: impl Iterator<Item = &'a str>,
    what: &str,
    at: &dyn Fn(&str) -> String,
) -> Result<(), WorldError> {
    let mut seen = std::collections::HashSet::new();
    for n in names {
        if !seen.insert(n) {
            invalid!("{}: duplicate {what} {n:?}", at(&format!("\"{n}\"")));
        }
    }
    Ok(())
}
