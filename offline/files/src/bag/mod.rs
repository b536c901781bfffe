//! ROS 2 bags as a dataset (`prf import-bag`): a bag in MCAP with CDR messages, as rosbag2
//! records it, and a task annotation (YAML or JSON, `docs/formats.md`) that says which time
//! spans are programs and what they did. Arm joints and the gripper come from
//! `sensor_msgs/msg/JointState` (matched by joint name, in any order), the platform from
//! `nav_msgs/msg/Odometry` or one transform of `/tf`. Times are header stamps. Each program is
//! resampled onto its own clock at the dataset rate by linear interpolation between the two
//! recorded samples around each instant (the yaw along the shorter turn). Every problem is a
//! [`BagError`] naming the topic, the time and the value at fault.

pub mod messages;
pub mod write;

use crate::dataset::{Dataset, Demonstration, Instance, Sample, TaskRecord};
use byteorder::{BigEndian, LittleEndian};
use messages::{JOINT_STATE, JointState, ODOMETRY, Odometry, TF_MESSAGE, TfMessage};
use prf_shared::NA;
use serde::Deserialize;
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

/// Where the platform pose comes from.
#[derive(Clone, Debug, PartialEq)]
pub enum PlatformSource {
    /// `nav_msgs/msg/Odometry` on this topic: its pose is the platform's in the world.
    Odometry { topic: String },
    /// The transform `parent` → `child` of `tf2_msgs/msg/TFMessage` on this topic.
    Tf {
        topic: String,
        parent: String,
        child: String,
    },
}

impl PlatformSource {
    fn topic(&self) -> &str {
        match self {
            PlatformSource::Odometry { topic } | PlatformSource::Tf { topic, .. } => topic,
        }
    }
}

/// How a bag is read.
#[derive(Clone, Debug, PartialEq)]
pub struct BagConfig {
    /// The `sensor_msgs/msg/JointState` topic.
    pub joint_topic: String,
    pub platform: PlatformSource,
    /// Longest silence of a topic inside a program, s.
    pub max_gap_s: f64,
    /// Rate of the dataset's trajectories, Hz.
    pub rate_hz: f64,
}

impl Default for BagConfig {
    fn default() -> Self {
        BagConfig {
            joint_topic: "/joint_states".into(),
            platform: PlatformSource::Odometry {
                topic: "/odom".into(),
            },
            max_gap_s: 0.1,
            rate_hz: 100.0,
        }
    }
}

/// The gripper's joint in the joint states and its positions when open and closed (the
/// dataset's 0 and 1; values in between map linearly).
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct GripperJoint {
    pub joint: String,
    pub open: f64,
    pub closed: f64,
}

/// One program of the recording: its time span (s after the first joint state's stamp) and
/// its task, as in a dataset task file.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Program {
    pub id: String,
    pub start: f64,
    pub end: f64,
    pub task: TaskRecord,
}

/// The task annotation of a bag.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Annotation {
    /// The robot the bag was recorded on (the dataset's `robot`).
    pub robot: String,
    #[serde(default)]
    pub description: Option<String>,
    /// r_d, m: the clearance the recorded programs kept (Sec. 4.1), stated by a person.
    pub clearance_demo_m: f64,
    pub gripper: GripperJoint,
    pub parts: Vec<Instance>,
    pub locations: Vec<Instance>,
    pub programs: Vec<Program>,
}

/// A gripper position this far outside open … closed (as a share of the stroke) is an error;
/// closer ones are clamped (sensor noise at the end stops).
const GRIPPER_SLACK: f64 = 0.05;

/// Why a bag or its annotation was refused.
#[derive(Debug, thiserror::Error)]
pub enum BagError {
    #[error("{path}: cannot read: {source}")]
    Read {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{path}: not a valid MCAP file: {source}")]
    Mcap {
        path: PathBuf,
        source: mcap::McapError,
    },
    #[error("{path}{}: {message}", line.map(|l| format!(":{l}")).unwrap_or_default())]
    Annotation {
        path: PathBuf,
        line: Option<usize>,
        message: String,
    },
    #[error("topic {topic}: not in the bag (expected {schema}; the bag has {present})")]
    MissingTopic {
        topic: String,
        schema: &'static str,
        present: String,
    },
    #[error("topic {topic}: schema {found:?}, expected {expected}")]
    WrongSchema {
        topic: String,
        found: String,
        expected: &'static str,
    },
    #[error("topic {topic}: message encoding {found:?}, expected \"cdr\"")]
    Encoding { topic: String, found: String },
    #[error("topic {topic}, message {index} (log time {log_time}): cannot decode: {detail}")]
    Decode {
        topic: String,
        index: usize,
        log_time: Stamp,
        detail: String,
    },
    #[error(
        "topic {topic}, {time}: joint {name:?} is neither an arm joint of the robot ({arm}) nor the gripper joint"
    )]
    UnknownJoint {
        topic: String,
        time: Stamp,
        name: String,
        arm: String,
    },
    #[error("topic {topic}, {time}: joint {joint:?} is missing")]
    MissingJoint {
        topic: String,
        time: Stamp,
        joint: String,
    },
    #[error("topic {topic}, {time}: {names} names but {positions} positions")]
    LengthMismatch {
        topic: String,
        time: Stamp,
        names: usize,
        positions: usize,
    },
    #[error("topic {topic}, {time}: {field} = {value}")]
    NonFinite {
        topic: String,
        time: Stamp,
        field: String,
        value: f64,
    },
    #[error(
        "topic {topic}, {time}: gripper joint {joint:?} = {value}, outside open {open} … closed {closed}"
    )]
    Gripper {
        topic: String,
        time: Stamp,
        joint: String,
        value: f64,
        open: f64,
        closed: f64,
    },
    #[error("topic {topic}, {time}: the stamp does not increase (previous {previous})")]
    NonMonotonic {
        topic: String,
        time: Stamp,
        previous: Stamp,
    },
    #[error("topic {topic}: no transform {parent} → {child}")]
    NoTransform {
        topic: String,
        parent: String,
        child: String,
    },
    #[error(
        "program {program}: topic {topic} is silent from {from} to {to} ({gap:.3} s, longer than {max:.3} s)"
    )]
    Gap {
        program: String,
        topic: String,
        from: Stamp,
        to: Stamp,
        gap: f64,
        max: f64,
    },
    #[error("program {program}: span {start} … {end} s is empty or not finite")]
    Span {
        program: String,
        start: f64,
        end: f64,
    },
    #[error(
        "programs {first} and {second} overlap: {first} ends at {first_end} s, {second} starts at {second_start} s"
    )]
    Overlap {
        first: String,
        second: String,
        first_end: f64,
        second_start: f64,
    },
    #[error(
        "program {program} ({start} … {end} s) is outside what topic {topic} recorded ({first} … {last} s)"
    )]
    OutsideRecording {
        program: String,
        topic: String,
        start: f64,
        end: f64,
        first: f64,
        last: f64,
    },
    #[error("program id {0:?} appears twice")]
    DuplicateProgram(String),
    #[error("the bag has no joint states on {0}")]
    Empty(String),
}

/// A header stamp, printed as seconds after the bag's first joint state and as the stamp.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Stamp {
    /// Nanoseconds since the epoch.
    pub ns: i64,
    /// The first joint state's, ns.
    pub origin: i64,
}

impl std::fmt::Display for Stamp {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "t = {:.3} s (stamp {}.{:09})",
            (self.ns - self.origin) as f64 * 1e-9,
            self.ns.div_euclid(1_000_000_000),
            self.ns.rem_euclid(1_000_000_000)
        )
    }
}

/// Reads the annotation file (YAML, or JSON for `.json`).
pub fn read_annotation(path: &Path) -> Result<Annotation, BagError> {
    let text = std::fs::read_to_string(path).map_err(|source| BagError::Read {
        path: path.to_path_buf(),
        source,
    })?;
    let bad = |line: Option<usize>, message: String| BagError::Annotation {
        path: path.to_path_buf(),
        line,
        message,
    };
    if path.extension().is_some_and(|e| e == "json") {
        serde_json::from_str(&text).map_err(|e| bad(Some(e.line()), e.to_string()))
    } else {
        serde_norway::from_str(&text)
            .map_err(|e| bad(e.location().map(|l| l.line()), e.to_string()))
    }
}

/// Samples of one topic: stamps (ns) and values.
struct Series<const N: usize> {
    topic: String,
    t: Vec<i64>,
    v: Vec<[f64; N]>,
}

impl<const N: usize> Series<N> {
    fn new(topic: &str) -> Self {
        Series {
            topic: topic.to_string(),
            t: Vec::new(),
            v: Vec::new(),
        }
    }

    /// Appends a sample; stamps must increase.
    fn push(&mut self, t: i64, v: [f64; N], origin: i64) -> Result<(), BagError> {
        if let Some(&previous) = self.t.last()
            && t <= previous
        {
            return Err(BagError::NonMonotonic {
                topic: self.topic.clone(),
                time: Stamp { ns: t, origin },
                previous: Stamp {
                    ns: previous,
                    origin,
                },
            });
        }
        self.t.push(t);
        self.v.push(v);
        Ok(())
    }

    /// Checks that `[start, end]` (ns) is recorded without a gap longer than `max` ns.
    fn covers(
        &self,
        p: &Program,
        start: i64,
        end: i64,
        max: i64,
        origin: i64,
    ) -> Result<(), BagError> {
        let s = |ns: i64| (ns - origin) as f64 * 1e-9;
        let (first, last) = (self.t[0], self.t[self.t.len() - 1]);
        if start < first || end > last {
            return Err(BagError::OutsideRecording {
                program: p.id.clone(),
                topic: self.topic.clone(),
                start: p.start,
                end: p.end,
                first: s(first),
                last: s(last),
            });
        }
        let from = self.t.partition_point(|&t| t <= start).saturating_sub(1);
        let to = self.t.partition_point(|&t| t < end).min(self.t.len() - 1);
        for i in from..to {
            let gap = self.t[i + 1] - self.t[i];
            if gap > max {
                return Err(BagError::Gap {
                    program: p.id.clone(),
                    topic: self.topic.clone(),
                    from: Stamp {
                        ns: self.t[i],
                        origin,
                    },
                    to: Stamp {
                        ns: self.t[i + 1],
                        origin,
                    },
                    gap: gap as f64 * 1e-9,
                    max: max as f64 * 1e-9,
                });
            }
        }
        Ok(())
    }

    /// The value at `t` (ns, within the recording), linear between the samples around it.
    fn at(&self, t: i64) -> [f64; N] {
        let i = self.t.partition_point(|&s| s <= t);
        if i >= self.t.len() {
            return self.v[self.t.len() - 1];
        }
        let i = i.max(1);
        let (t0, t1) = (self.t[i - 1], self.t[i]);
        let w = ((t - t0) as f64 / (t1 - t0) as f64).clamp(0.0, 1.0);
        let (a, b) = (&self.v[i - 1], &self.v[i]);
        core::array::from_fn(|k| a[k] + w * (b[k] - a[k]))
    }
}

/// The messages of one topic, decoded, with their log times.
fn decode_topic<T: for<'de> Deserialize<'de>>(
    bag: &[u8],
    path: &Path,
    topic: &str,
    schema: &'static str,
    mut each: impl FnMut(T) -> Result<(), BagError>,
) -> Result<usize, BagError> {
    let mcap_err = |source| BagError::Mcap {
        path: path.to_path_buf(),
        source,
    };
    let mut present = BTreeSet::new();
    let mut n = 0;
    for m in mcap::MessageStream::new(bag).map_err(mcap_err)? {
        let m = m.map_err(mcap_err)?;
        if m.channel.topic != topic {
            present.insert(m.channel.topic.clone());
            continue;
        }
        let found = m
            .channel
            .schema
            .as_ref()
            .map(|s| s.name.clone())
            .unwrap_or_default();
        if found != schema {
            return Err(BagError::WrongSchema {
                topic: topic.into(),
                found,
                expected: schema,
            });
        }
        if m.channel.message_encoding != "cdr" {
            return Err(BagError::Encoding {
                topic: topic.into(),
                found: m.channel.message_encoding.clone(),
            });
        }
        let log_time = Stamp {
            ns: m.log_time as i64,
            origin: 0,
        };
        let fail = |detail: String| BagError::Decode {
            topic: topic.into(),
            index: n,
            log_time,
            detail,
        };
        let msg: T = decode_cdr(&m.data).map_err(fail)?;
        each(msg)?;
        n += 1;
    }
    if n == 0 {
        return Err(BagError::MissingTopic {
            topic: topic.into(),
            schema,
            present: if present.is_empty() {
                "no messages".into()
            } else {
                present.into_iter().collect::<Vec<_>>().join(", ")
            },
        });
    }
    Ok(n)
}

/// A CDR message with its 4-byte encapsulation header (CDR_LE or CDR_BE).
fn decode_cdr<T: for<'de> Deserialize<'de>>(data: &[u8]) -> Result<T, String> {
    let (header, body) = data
        .split_at_checked(4)
        .ok_or_else(|| format!("{} bytes, shorter than the CDR header", data.len()))?;
    let decoded = match header[..2] {
        [0, 1] => cdr_encoding::from_bytes::<T, LittleEndian>(body),
        [0, 0] => cdr_encoding::from_bytes::<T, BigEndian>(body),
        _ => {
            return Err(format!(
                "encapsulation {:02x?}, expected CDR_LE or CDR_BE",
                &header[..2]
            ));
        }
    };
    decoded.map(|(v, _)| v).map_err(|e| e.to_string())
}

/// Arm joints and gripper (0 open … 1 closed) from the joint states.
fn joint_series(
    bag: &[u8],
    path: &Path,
    cfg: &BagConfig,
    arm: &[String],
    gripper: &GripperJoint,
) -> Result<(Series<{ NA + 1 }>, i64), BagError> {
    let topic = cfg.joint_topic.as_str();
    let mut series = Series::new(topic);
    let mut origin = None;
    decode_topic::<JointState>(bag, path, topic, JOINT_STATE, |js| {
        let t = js.header.stamp.ns();
        let origin = *origin.get_or_insert(t);
        let time = Stamp { ns: t, origin };
        if js.name.len() != js.position.len() {
            return Err(BagError::LengthMismatch {
                topic: topic.into(),
                time,
                names: js.name.len(),
                positions: js.position.len(),
            });
        }
        let mut v = [f64::NAN; NA + 1];
        for (name, &value) in js.name.iter().zip(&js.position) {
            let slot = if *name == gripper.joint {
                NA
            } else {
                arm.iter()
                    .position(|a| a == name)
                    .ok_or_else(|| BagError::UnknownJoint {
                        topic: topic.into(),
                        time,
                        name: name.clone(),
                        arm: arm.join(", "),
                    })?
            };
            if !value.is_finite() {
                return Err(BagError::NonFinite {
                    topic: topic.into(),
                    time,
                    field: format!("position of {name}"),
                    value,
                });
            }
            v[slot] = value;
        }
        if let Some(j) = v.iter().position(|x| x.is_nan()) {
            return Err(BagError::MissingJoint {
                topic: topic.into(),
                time,
                joint: arm.get(j).unwrap_or(&gripper.joint).clone(),
            });
        }
        let g = (v[NA] - gripper.open) / (gripper.closed - gripper.open);
        if !(-GRIPPER_SLACK..=1.0 + GRIPPER_SLACK).contains(&g) {
            return Err(BagError::Gripper {
                topic: topic.into(),
                time,
                joint: gripper.joint.clone(),
                value: v[NA],
                open: gripper.open,
                closed: gripper.closed,
            });
        }
        v[NA] = g.clamp(0.0, 1.0);
        series.push(t, v, origin)
    })?;
    let origin = series
        .t
        .first()
        .copied()
        .ok_or_else(|| BagError::Empty(topic.into()))?;
    Ok((series, origin))
}

/// Platform [x, y, yaw] (yaw unwrapped) from odometry or a transform.
fn platform_series(
    bag: &[u8],
    path: &Path,
    source: &PlatformSource,
    origin: i64,
) -> Result<Series<3>, BagError> {
    let topic = source.topic();
    let mut series = Series::new(topic);
    let add = |series: &mut Series<3>, t: i64, x: f64, y: f64, yaw: f64| {
        let time = Stamp { ns: t, origin };
        for (field, value) in [("x", x), ("y", y), ("yaw", yaw)] {
            if !value.is_finite() {
                return Err(BagError::NonFinite {
                    topic: topic.into(),
                    time,
                    field: field.into(),
                    value,
                });
            }
        }
        let yaw = match series.v.last() {
            Some(p) => p[2] + prf_shared::se3::wrap(yaw - p[2]),
            None => yaw,
        };
        series.push(t, [x, y, yaw], origin)
    };
    match source {
        PlatformSource::Odometry { .. } => {
            decode_topic::<Odometry>(bag, path, topic, ODOMETRY, |o| {
                let p = o.pose.pose;
                add(
                    &mut series,
                    o.header.stamp.ns(),
                    p.position.x,
                    p.position.y,
                    p.orientation.yaw(),
                )
            })?;
        }
        PlatformSource::Tf { parent, child, .. } => {
            decode_topic::<TfMessage>(bag, path, topic, TF_MESSAGE, |m| {
                for tr in m.transforms.iter().filter(|tr| {
                    tr.header.frame_id.trim_start_matches('/') == parent.trim_start_matches('/')
                        && tr.child_frame_id.trim_start_matches('/')
                            == child.trim_start_matches('/')
                }) {
                    let (p, q) = (tr.transform.translation, tr.transform.rotation);
                    add(&mut series, tr.header.stamp.ns(), p.x, p.y, q.yaw())?;
                }
                Ok(())
            })?;
            if series.t.is_empty() {
                return Err(BagError::NoTransform {
                    topic: topic.into(),
                    parent: parent.clone(),
                    child: child.clone(),
                });
            }
        }
    }
    Ok(series)
}

/// The programs' spans, checked: finite, non-empty, unique ids, no overlap.
fn check_programs(programs: &[Program]) -> Result<(), BagError> {
    let mut order: Vec<&Program> = programs.iter().collect();
    for p in &order {
        if !(p.start.is_finite() && p.end.is_finite() && p.start < p.end) {
            return Err(BagError::Span {
                program: p.id.clone(),
                start: p.start,
                end: p.end,
            });
        }
    }
    let mut ids = BTreeSet::new();
    for p in &order {
        if !ids.insert(p.id.as_str()) {
            return Err(BagError::DuplicateProgram(p.id.clone()));
        }
    }
    order.sort_by(|a, b| a.start.total_cmp(&b.start));
    for w in order.windows(2) {
        if w[1].start < w[0].end {
            return Err(BagError::Overlap {
                first: w[0].id.clone(),
                second: w[1].id.clone(),
                first_end: w[0].end,
                second_start: w[1].start,
            });
        }
    }
    Ok(())
}

/// Reads bag `path` with its annotation into a dataset (arm joint names `arm`, A1 … A7, from
/// the robot file). The dataset is not yet validated against the robot's limits: write it and
/// read it back ([`Dataset::read`]) for that.
pub fn import(
    path: &Path,
    annotation: &Annotation,
    arm: &[String],
    cfg: &BagConfig,
) -> Result<Dataset, BagError> {
    check_programs(&annotation.programs)?;
    let bag = std::fs::read(path).map_err(|source| BagError::Read {
        path: path.to_path_buf(),
        source,
    })?;
    let (joints, origin) = joint_series(&bag, path, cfg, arm, &annotation.gripper)?;
    let platform = platform_series(&bag, path, &cfg.platform, origin)?;
    let ns = |s: f64| origin + (s * 1e9).round() as i64;
    let max_gap = (cfg.max_gap_s * 1e9).round() as i64;
    let mut demonstrations = Vec::new();
    for p in &annotation.programs {
        let (start, end) = (ns(p.start), ns(p.end));
        joints.covers(p, start, end, max_gap, origin)?;
        platform.covers(p, start, end, max_gap, origin)?;
        let n = ((p.end - p.start) * cfg.rate_hz + 1e-9).floor() as usize;
        let samples = (0..=n)
            .map(|k| {
                let t = k as f64 / cfg.rate_hz;
                let at = start + (t * 1e9).round() as i64;
                let (j, b) = (joints.at(at), platform.at(at));
                Sample {
                    t,
                    base: b,
                    arm: core::array::from_fn(|i| j[i]),
                    gripper: j[NA],
                }
            })
            .collect();
        demonstrations.push(Demonstration {
            id: p.id.clone(),
            task: p.task.clone(),
            samples,
        });
    }
    Ok(Dataset {
        robot: annotation.robot.clone(),
        description: Some(
            annotation
                .description
                .clone()
                .unwrap_or_else(|| format!("imported by prf import-bag from {}", path.display())),
        ),
        rate_hz: cfg.rate_hz,
        clearance_demo: Some(annotation.clearance_demo_m),
        parts: annotation.parts.clone(),
        locations: annotation.locations.clone(),
        demonstrations,
    })
}
