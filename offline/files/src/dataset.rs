//! The historical dataset D = {(q(t), T)} (Sec. 3.4): a directory with `manifest.json` and,
//! per demonstration, a task file (JSON) and a trajectory (CSV). Documented in
//! `docs/formats.md`. The reader validates everything and names the file, line and value at
//! fault; the writer produces exactly what the reader accepts.

use crate::line_of;
use prf_shared::NA;
use prf_shared::robot::RobotModel;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::fmt;
use std::path::{Path, PathBuf};

pub const MANIFEST: &str = "manifest.json";
pub const FORMAT: &str = "prf-dataset";
pub const VERSION: u32 = 1;
/// The trajectory CSV header.
pub const CSV_HEADER: [&str; 4 + NA + 1] = [
    "t", "base_x", "base_y", "base_yaw", "a1", "a2", "a3", "a4", "a5", "a6", "a7", "gripper",
];
/// Quaternions in task files must have unit norm within this tolerance.
const QUATERNION_NORM_TOL: f64 = 1e-6;

/// An id with its type (a part or location instance).
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Instance {
    pub id: String,
    #[serde(rename = "type")]
    pub kind: String,
}

/// One manifest entry: file names relative to the dataset directory.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Entry {
    pub id: String,
    pub task: String,
    pub trajectory: String,
}

#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Manifest {
    pub format: String,
    pub version: u32,
    /// Robot the programs were recorded on (informative).
    pub robot: String,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub description: Option<String>,
    /// Nominal sample rate of the trajectories, Hz (informative; `t` is authoritative).
    pub rate_hz: f64,
    /// r_d, m: the clearance every program keeps from every obstacle and the floor (Sec. 4.1),
    /// a fact about the cell that learning needs and never guesses.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub clearance_demo_m: Option<f64>,
    pub parts: Vec<Instance>,
    pub locations: Vec<Instance>,
    pub demonstrations: Vec<Entry>,
}

/// An object of a task with its pose [x, y, z, qw, qx, qy, qz] in the world.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Placed {
    pub id: String,
    #[serde(rename = "type")]
    pub kind: String,
    pub pose: [f64; 7],
}

/// The task T of a demonstration: part p at its initial pose, locations ℓ1, ℓ2, and the part's
/// goal pose.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct TaskRecord {
    pub part: Placed,
    pub from: Placed,
    pub to: Placed,
    /// Goal pose of the part, [x, y, z, qw, qx, qy, qz].
    pub goal: [f64; 7],
    /// Free text for people (e.g. how it was made); never read by learning.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub note: Option<String>,
}

/// One row of a trajectory (the shared program sample).
pub use prf_shared::motion::Sample;

#[derive(Clone, Debug, PartialEq)]
pub struct Demonstration {
    pub id: String,
    pub task: TaskRecord,
    pub samples: Vec<Sample>,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Dataset {
    pub robot: String,
    pub description: Option<String>,
    pub rate_hz: f64,
    /// r_d, m, as the manifest states it (`clearance_demo_m`); None when it does not.
    pub clearance_demo: Option<f64>,
    pub parts: Vec<Instance>,
    pub locations: Vec<Instance>,
    pub demonstrations: Vec<Demonstration>,
}

/// A dataset directory whose manifest is read and checked, its demonstrations read when
/// asked for, a range at a time: what learning a plant's archive streams through, holding
/// only the programs it is learning from at once.
pub struct DatasetDir {
    dir: PathBuf,
    manifest: Manifest,
}

impl DatasetDir {
    /// The dataset in `dir`, its manifest read and checked ([`parse_manifest`]).
    pub fn open(dir: &Path) -> Result<Self, DatasetError> {
        let mpath = dir.join(MANIFEST);
        let manifest = parse_manifest(&mpath, &read_text(&mpath)?)?;
        Ok(DatasetDir {
            dir: dir.to_path_buf(),
            manifest,
        })
    }

    /// How many demonstrations the manifest lists.
    pub fn len(&self) -> usize {
        self.manifest.demonstrations.len()
    }

    /// Whether the manifest lists no demonstration.
    pub fn is_empty(&self) -> bool {
        self.manifest.demonstrations.is_empty()
    }

    /// The dataset without its demonstrations: robot, r_d, parts and locations.
    pub fn header(&self) -> Dataset {
        let mut manifest = self.manifest.clone();
        manifest.demonstrations = Vec::new();
        Dataset::of(manifest, Vec::new())
    }

    /// Demonstrations `range` of the manifest, read and checked against `model`'s joint
    /// limits on all cores; the first fault in manifest order is the one reported.
    pub fn read(
        &self,
        range: std::ops::Range<usize>,
        model: &RobotModel,
    ) -> Result<Vec<Demonstration>, DatasetError> {
        self.manifest.demonstrations[range]
            .par_iter()
            .map(|entry| {
                let (tpath, cpath) = (self.dir.join(&entry.task), self.dir.join(&entry.trajectory));
                let task = parse_task(&tpath, &read_text(&tpath)?, &self.manifest)?;
                let samples = parse_trajectory(&cpath, &read_text(&cpath)?, model)?;
                Ok(Demonstration {
                    id: entry.id.clone(),
                    task,
                    samples,
                })
            })
            .collect::<Vec<_>>()
            .into_iter()
            .collect()
    }
}

/// A dataset read, its numbers parsed, not yet checked against a robot ([`Dataset::parse`]).
/// What failed to read or parse is kept, in file order, for [`ParsedDataset::check`].
pub struct ParsedDataset {
    manifest: Manifest,
    /// Per demonstration: its id, its task, and its trajectory's file and rows.
    #[allow(clippy::type_complexity)]
    demonstrations: Vec<(
        String,
        Result<TaskRecord, DatasetError>,
        Result<(PathBuf, Rows), DatasetError>,
    )>,
}

impl ParsedDataset {
    /// The dataset checked against `model`'s joint limits: what [`Dataset::read`] gives with
    /// `model`, its first error included.
    pub fn check(self, model: &RobotModel) -> Result<Dataset, DatasetError> {
        let mut demonstrations = Vec::with_capacity(self.demonstrations.len());
        for (id, task, rows) in self.demonstrations {
            let task = task?;
            let (cpath, rows) = rows?;
            demonstrations.push(Demonstration {
                id,
                task,
                samples: rows.samples(&cpath, model)?,
            });
        }
        Ok(Dataset::of(self.manifest, demonstrations))
    }
}

/// What is wrong with a dataset.
#[derive(Clone, Debug, PartialEq)]
pub enum ErrorKind {
    MissingFile,
    Io(String),
    /// Malformed JSON or a missing/unknown field.
    Json(String),
    BadFormat(String),
    /// `clearance_demo_m` is not a positive number of metres.
    BadClearance(f64),
    Duplicate(String),
    UnknownPart(String),
    UnknownLocation(String),
    /// The type given in a task disagrees with the manifest.
    TypeMismatch {
        id: String,
        manifest: String,
        task: String,
    },
    BadPose {
        field: String,
    },
    BadHeader {
        found: String,
    },
    ColumnCount {
        expected: usize,
        found: usize,
    },
    BadNumber {
        column: String,
        value: String,
    },
    NonFinite {
        column: String,
        value: String,
    },
    NonMonotonicTime {
        previous: f64,
        value: f64,
    },
    JointLimit {
        joint: usize,
        value: f64,
        lower: f64,
        upper: f64,
    },
    Gripper {
        value: f64,
    },
    TooShort {
        rows: usize,
    },
}

/// An error with the file and (1-based) line at fault.
#[derive(Clone, Debug, PartialEq)]
pub struct DatasetError {
    pub file: PathBuf,
    pub line: Option<usize>,
    pub kind: ErrorKind,
}

impl fmt::Display for DatasetError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.file.display())?;
        if let Some(l) = self.line {
            write!(f, ":{l}")?;
        }
        write!(f, ": ")?;
        match &self.kind {
            ErrorKind::MissingFile => write!(f, "file is missing"),
            ErrorKind::Io(e) => write!(f, "cannot read: {e}"),
            ErrorKind::Json(e) => write!(f, "invalid JSON: {e}"),
            ErrorKind::BadFormat(e) => write!(f, "{e}"),
            ErrorKind::BadClearance(v) => write!(
                f,
                "clearance_demo_m = {v} is not a clearance: r_d is a positive number of metres"
            ),
            ErrorKind::Duplicate(id) => write!(f, "duplicate id {id:?}"),
            ErrorKind::UnknownPart(id) => write!(f, "unknown part id {id:?} (not in the manifest)"),
            ErrorKind::UnknownLocation(id) => {
                write!(f, "unknown location id {id:?} (not in the manifest)")
            }
            ErrorKind::TypeMismatch { id, manifest, task } => write!(
                f,
                "{id} has type {task:?} here but {manifest:?} in the manifest"
            ),
            ErrorKind::BadPose { field } => write!(
                f,
                "{field}: pose must be 7 finite numbers [x, y, z, qw, qx, qy, qz] with a unit quaternion"
            ),
            ErrorKind::BadHeader { found } => {
                write!(f, "header {found:?}, expected {:?}", CSV_HEADER.join(","))
            }
            ErrorKind::ColumnCount { expected, found } => {
                write!(f, "{found} columns, expected {expected}")
            }
            ErrorKind::BadNumber { column, value } => {
                write!(f, "{column}: not a number: {value:?}")
            }
            ErrorKind::NonFinite { column, value } => {
                write!(f, "{column}: non-finite value {value}")
            }
            ErrorKind::NonMonotonicTime { previous, value } => write!(
                f,
                "t = {value} does not increase (previous row t = {previous})"
            ),
            ErrorKind::JointLimit {
                joint,
                value,
                lower,
                upper,
            } => write!(
                f,
                "a{joint} = {value:.6} rad ({:.3} deg) outside its limits [{lower:.6}, {upper:.6}] rad",
                value.to_degrees()
            ),
            ErrorKind::Gripper { value } => {
                write!(f, "gripper = {value}, expected 0 (open) .. 1 (closed)")
            }
            ErrorKind::TooShort { rows } => write!(f, "{rows} samples, need at least 2"),
        }
    }
}

impl std::error::Error for DatasetError {}

fn err(file: &Path, line: Option<usize>, kind: ErrorKind) -> DatasetError {
    DatasetError {
        file: file.to_path_buf(),
        line,
        kind,
    }
}

fn read_text(path: &Path) -> Result<String, DatasetError> {
    std::fs::read_to_string(path).map_err(|e| {
        let kind = if e.kind() == std::io::ErrorKind::NotFound {
            ErrorKind::MissingFile
        } else {
            ErrorKind::Io(e.to_string())
        };
        err(path, None, kind)
    })
}

fn parse_json<T: for<'de> Deserialize<'de>>(path: &Path, text: &str) -> Result<T, DatasetError> {
    serde_json::from_str(text)
        .map_err(|e| err(path, Some(e.line()), ErrorKind::Json(e.to_string())))
}

fn valid_pose(p: &[f64; 7]) -> bool {
    let qn = (p[3] * p[3] + p[4] * p[4] + p[5] * p[5] + p[6] * p[6]).sqrt();
    p.iter().all(|v| v.is_finite()) && (qn - 1.0).abs() < QUATERNION_NORM_TOL
}

impl Dataset {
    /// Reads and validates the dataset in `dir` against the robot's joint limits.
    pub fn read(dir: &Path, model: &RobotModel) -> Result<Dataset, DatasetError> {
        let opened = DatasetDir::open(dir)?;
        let demonstrations = opened.read(0..opened.len(), model)?;
        let mut ds = opened.header();
        ds.demonstrations = demonstrations;
        Ok(ds)
    }

    /// The dataset in `dir` read and its numbers parsed, to be checked against a robot's
    /// joint limits once the model is known ([`ParsedDataset::check`]): the part of
    /// [`Dataset::read`] that needs no model, so it may run beside what gives the model
    /// (`prf learn --add` reads its knowledge base meanwhile).
    pub fn parse(dir: &Path) -> Result<ParsedDataset, DatasetError> {
        let mpath = dir.join(MANIFEST);
        let manifest = parse_manifest(&mpath, &read_text(&mpath)?)?;
        let demonstrations = manifest
            .demonstrations
            .iter()
            .map(|entry| {
                let (tpath, cpath) = (dir.join(&entry.task), dir.join(&entry.trajectory));
                let task = read_text(&tpath).and_then(|t| parse_task(&tpath, &t, &manifest));
                let rows = read_text(&cpath).and_then(|t| Rows::parse(&cpath, &t));
                (entry.id.clone(), task, rows.map(|r| (cpath, r)))
            })
            .collect();
        Ok(ParsedDataset {
            manifest,
            demonstrations,
        })
    }

    fn of(manifest: Manifest, demonstrations: Vec<Demonstration>) -> Dataset {
        Dataset {
            robot: manifest.robot,
            description: manifest.description,
            rate_hz: manifest.rate_hz,
            clearance_demo: manifest.clearance_demo_m,
            parts: manifest.parts,
            locations: manifest.locations,
            demonstrations,
        }
    }

    /// Writes the dataset to `dir` whole or not at all: `manifest.json`, and per demonstration
    /// `<id>.task.json` and `<id>.csv`, filled into a new directory that then takes the place
    /// of `dir` ([`crate::atomic::replace_dir`]; a killed run or a full disk leaves the
    /// previous dataset as it was). A `dir` holding files that are not a dataset's is refused:
    /// replacing it would delete them.
    pub fn write(&self, dir: &Path) -> std::io::Result<()> {
        if let Some(other) = foreign_entry(dir)? {
            return Err(std::io::Error::other(format!(
                "{} holds {other:?}, which is not part of a dataset: writing a dataset replaces the whole directory (choose another one, or move it away)",
                dir.display()
            )));
        }
        crate::atomic::replace_dir(dir, |t| self.write_into(t))
    }

    /// The dataset's files, into the empty directory `dir`.
    fn write_into(&self, dir: &Path) -> std::io::Result<()> {
        let mut entries = Vec::new();
        for d in &self.demonstrations {
            let task = format!("{}.task.json", d.id);
            let trajectory = format!("{}.csv", d.id);
            let json = serde_json::to_string_pretty(&d.task).map_err(std::io::Error::other)?;
            std::fs::write(dir.join(&task), json + "\n")?;
            std::fs::write(dir.join(&trajectory), trajectory_csv(&d.samples))?;
            entries.push(Entry {
                id: d.id.clone(),
                task,
                trajectory,
            });
        }
        let manifest = Manifest {
            format: FORMAT.into(),
            version: VERSION,
            robot: self.robot.clone(),
            description: self.description.clone(),
            rate_hz: self.rate_hz,
            clearance_demo_m: self.clearance_demo,
            parts: self.parts.clone(),
            locations: self.locations.clone(),
            demonstrations: entries,
        };
        let json = serde_json::to_string_pretty(&manifest).map_err(std::io::Error::other)?;
        std::fs::write(dir.join(MANIFEST), json + "\n")
    }
}

/// The first entry of `dir` that a dataset directory does not hold (its manifest, task and
/// trajectory files, `prf gen`'s floor plan and `prf demo`'s completion marker); None when
/// `dir` is missing.
fn foreign_entry(dir: &Path) -> std::io::Result<Option<String>> {
    let entries = match std::fs::read_dir(dir) {
        Ok(e) => e,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        Err(e) => return Err(e),
    };
    for e in entries {
        let e = e?;
        let name = e.file_name().to_string_lossy().into_owned();
        let ours = name == MANIFEST
            || name == "floorplan.svg"
            || name == ".complete"
            || ((name.ends_with(".task.json") || name.ends_with(".csv"))
                && e.file_type()?.is_file());
        if !ours {
            return Ok(Some(name));
        }
    }
    Ok(None)
}

/// The manifest in `text` (read from `path`), checked: format and version, r_d, unique ids.
pub fn parse_manifest(path: &Path, text: &str) -> Result<Manifest, DatasetError> {
    let manifest: Manifest = parse_json(path, text)?;
    if manifest.format != FORMAT || manifest.version != VERSION {
        return Err(err(
            path,
            line_of(text, "\"format\""),
            ErrorKind::BadFormat(format!(
                "format {:?} version {}, this build reads {FORMAT:?} version {VERSION}",
                manifest.format, manifest.version
            )),
        ));
    }
    if let Some(r_d) = manifest.clearance_demo_m
        && !(r_d > 0.0 && r_d.is_finite())
    {
        return Err(err(
            path,
            line_of(text, "\"clearance_demo_m\""),
            ErrorKind::BadClearance(r_d),
        ));
    }
    let ids = manifest
        .parts
        .iter()
        .map(|p| &p.id)
        .chain(manifest.locations.iter().map(|l| &l.id))
        .chain(manifest.demonstrations.iter().map(|d| &d.id));
    let mut seen = std::collections::HashSet::new();
    for id in ids {
        if !seen.insert(id) {
            let line = line_of(text, &format!("\"{id}\""));
            return Err(err(path, line, ErrorKind::Duplicate(id.clone())));
        }
    }
    Ok(manifest)
}

/// The task record in `text` (read from `path`), checked against `manifest`: known ids of the
/// right types, unit quaternions.
pub fn parse_task(
    path: &Path,
    text: &str,
    manifest: &Manifest,
) -> Result<TaskRecord, DatasetError> {
    let task: TaskRecord = parse_json(path, text)?;
    let check = |placed: &Placed, known: &[Instance], field: &str, part: bool| {
        let line = line_of(text, &format!("\"{}\"", placed.id));
        let Some(m) = known.iter().find(|i| i.id == placed.id) else {
            let kind = if part {
                ErrorKind::UnknownPart(placed.id.clone())
            } else {
                ErrorKind::UnknownLocation(placed.id.clone())
            };
            return Err(err(path, line, kind));
        };
        if m.kind != placed.kind {
            return Err(err(
                path,
                line,
                ErrorKind::TypeMismatch {
                    id: placed.id.clone(),
                    manifest: m.kind.clone(),
                    task: placed.kind.clone(),
                },
            ));
        }
        if !valid_pose(&placed.pose) {
            let line = line_of(text, &format!("\"{field}\""));
            return Err(err(
                path,
                line,
                ErrorKind::BadPose {
                    field: format!("{field}.pose"),
                },
            ));
        }
        Ok(())
    };
    check(&task.part, &manifest.parts, "part", true)?;
    check(&task.from, &manifest.locations, "from", false)?;
    check(&task.to, &manifest.locations, "to", false)?;
    if !valid_pose(&task.goal) {
        let line = line_of(text, "\"goal\"");
        return Err(err(
            path,
            line,
            ErrorKind::BadPose {
                field: "goal".into(),
            },
        ));
    }
    Ok(task)
}

/// The trajectory CSV in `text` (read from `path`), checked: header, numbers, time strictly
/// increasing, joint limits, gripper in [0, 1], at least two samples. The rows' numbers are
/// parsed on all cores, then checked in order: the first fault by line is the one reported.
pub fn parse_trajectory(
    path: &Path,
    text: &str,
    model: &RobotModel,
) -> Result<Vec<Sample>, DatasetError> {
    Rows::parse(path, text)?.samples(path, model)
}

/// A trajectory's rows parsed into numbers (in parallel), each with its line, not yet
/// checked: the part of [`parse_trajectory`] that needs no robot model.
struct Rows(Vec<(usize, Result<[f64; 12], ErrorKind>)>);

impl Rows {
    /// The rows of the trajectory `text` (read from `path`) after its header.
    fn parse(path: &Path, text: &str) -> Result<Rows, DatasetError> {
        let mut lines = text
            .lines()
            .enumerate()
            .map(|(i, l)| (i + 1, l.trim_end_matches('\r')));
        let header = lines.next().map(|(_, l)| l).unwrap_or("");
        let columns: Vec<&str> = header.split(',').map(str::trim).collect();
        if columns != CSV_HEADER {
            return Err(err(
                path,
                Some(1),
                ErrorKind::BadHeader {
                    found: header.to_string(),
                },
            ));
        }
        let rows: Vec<(usize, &str)> = lines.filter(|(_, l)| !l.trim().is_empty()).collect();
        Ok(Rows(
            rows.par_iter()
                .map(|(line_no, line)| (*line_no, parse_row(line)))
                .collect(),
        ))
    }

    /// The samples, checked in row order: numbers, times rising, within `model`'s joint
    /// limits, gripper in [0, 1]; the first failure with its line of `path`.
    fn samples(self, path: &Path, model: &RobotModel) -> Result<Vec<Sample>, DatasetError> {
        let mut samples: Vec<Sample> = Vec::with_capacity(self.0.len());
        for (line_no, v) in self.0 {
            let at = |kind| err(path, Some(line_no), kind);
            let v = v.map_err(at)?;
            let s = Sample {
                t: v[0],
                base: [v[1], v[2], v[3]],
                arm: std::array::from_fn(|j| v[4 + j]),
                gripper: v[11],
            };
            if let Some(prev) = samples.last()
                && !(s.t > prev.t)
            {
                return Err(at(ErrorKind::NonMonotonicTime {
                    previous: prev.t,
                    value: s.t,
                }));
            }
            if let Some((joint, value)) = model.limit_violation(&s.arm) {
                let j = &model.joints[joint];
                return Err(at(ErrorKind::JointLimit {
                    joint: joint + 1,
                    value,
                    lower: j.lower,
                    upper: j.upper,
                }));
            }
            if !(0.0..=1.0).contains(&s.gripper) {
                return Err(at(ErrorKind::Gripper { value: s.gripper }));
            }
            samples.push(s);
        }
        if samples.len() < 2 {
            return Err(err(
                path,
                None,
                ErrorKind::TooShort {
                    rows: samples.len(),
                },
            ));
        }
        Ok(samples)
    }
}

/// The comma-separated fields of `line`, as `line.split(',')` gives them, found byte by byte:
/// a row's fields are a few bytes long, shorter than pays for a `memchr` per field (the
/// split took 11.5 M of the 28 M instructions of parsing d063's 5,080 rows).
fn fields(line: &str) -> impl Iterator<Item = &str> {
    let mut rest = Some(line);
    std::iter::from_fn(move || {
        let r = rest?;
        match r.bytes().position(|b| b == b',') {
            Some(i) => {
                rest = Some(&r[i + 1..]);
                Some(&r[..i])
            }
            None => {
                rest = None;
                Some(r)
            }
        }
    })
}

/// The 12 numbers of one trajectory row, each finite; a row with another number of columns
/// is refused first (nothing is allocated unless the row is refused). One pass over the row:
/// its columns are counted again only when it is refused.
fn parse_row(line: &str) -> Result<[f64; 12], ErrorKind> {
    let mut v = [0.0; 12];
    let mut fields = fields(line);
    let (mut parsed, mut first_error) = (0, None);
    for ((x, column), f) in v.iter_mut().zip(CSV_HEADER).zip(fields.by_ref()) {
        parsed += 1;
        let f = f.trim();
        match f.parse::<f64>() {
            Ok(number) if number.is_finite() => *x = number,
            Ok(_) => {
                first_error = Some(ErrorKind::NonFinite {
                    column: column.to_string(),
                    value: f.to_string(),
                });
                break;
            }
            Err(_) => {
                first_error = Some(ErrorKind::BadNumber {
                    column: column.to_string(),
                    value: f.to_string(),
                });
                break;
            }
        }
    }
    if first_error.is_none() && parsed == v.len() && fields.next().is_none() {
        return Ok(v);
    }
    let found = line.split(',').count();
    if found != CSV_HEADER.len() {
        return Err(ErrorKind::ColumnCount {
            expected: CSV_HEADER.len(),
            found,
        });
    }
    first_error.map_or(Ok(v), Err)
}

/// CSV text of a trajectory: time to 1 µs, positions to 1 nm and angles to 1 nrad (fine enough
/// that second differences at 100 Hz resolve accelerations to 1e-4 m/s²).
pub fn trajectory_csv(samples: &[Sample]) -> String {
    use std::fmt::Write;
    let mut out = CSV_HEADER.join(",");
    out.push('\n');
    for s in samples {
        let _ = write!(
            out,
            "{:.6},{:.9},{:.9},{:.9}",
            s.t, s.base[0], s.base[1], s.base[2]
        );
        for a in s.arm {
            let _ = write!(out, ",{a:.9}");
        }
        let _ = writeln!(out, ",{}", s.gripper);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `fields` splits as `str::split(',')`: empty lines and fields, commas at either end,
    /// multi-byte characters beside commas, and random lines over a small alphabet.
    #[test]
    fn fields_split_as_str_split() {
        let same = |line: &str| {
            let got: Vec<&str> = fields(line).collect();
            let want: Vec<&str> = line.split(',').collect();
            assert_eq!(got, want, "{line:?}");
        };
        for line in [
            "",
            ",",
            ",,",
            "a",
            "a,",
            ",a",
            "1.5,-2,,x",
            "é,ü€,,😀",
            " , ,",
        ] {
            same(line);
        }
        let alphabet = [",", "1", ".", "-", " ", "é", "€"];
        let mut s: u64 = 0x9e37_79b9_7f4a_7c15;
        for _ in 0..2_000 {
            let mut line = String::new();
            for _ in 0..(s % 17) {
                s ^= s << 13;
                s ^= s >> 7;
                s ^= s << 17;
                line.push_str(alphabet[(s % alphabet.len() as u64) as usize]);
            }
            s = s.wrapping_add(1);
            same(&line);
        }
    }

    /// A row's column count is judged before its numbers, in one pass or two.
    #[test]
    fn a_row_is_refused_for_its_columns_before_its_numbers() {
        let good = "0.5,2.5,0,0,0,-1,0,-1.9,0,1.5,0,1";
        let v = parse_row(good).expect("a good row");
        assert_eq!((v[0], v[1], v[7], v[11]), (0.5, 2.5, -1.9, 1.0));
        assert_eq!(parse_row(" 0.5 , 2.5,0,0,0,-1,0,-1.9,0,1.5,0, 1 "), Ok(v));
        let columns = |found| {
            Err(ErrorKind::ColumnCount {
                expected: 12,
                found,
            })
        };
        assert_eq!(parse_row("0.5,2.5,0,0,0,-1,0,-1.9,0,1.5,0"), columns(11));
        assert_eq!(parse_row(&format!("{good},7")), columns(13));
        assert_eq!(parse_row(&format!("x,{good}")), columns(13));
        assert_eq!(parse_row("x,2.5,0,0,0,-1,0,-1.9,0,1.5,0"), columns(11));
        assert_eq!(parse_row(""), columns(1));
        assert_eq!(
            parse_row("0.5,2.5,0,0,0,-1,inf,-1.9,0,1.5,0,1"),
            Err(ErrorKind::NonFinite {
                column: "a3".into(),
                value: "inf".into()
            })
        );
        assert_eq!(
            parse_row("0.5,2.5,0,0,0,-1,0,-1.9,0,1.5,0,one"),
            Err(ErrorKind::BadNumber {
                column: "gripper".into(),
                value: "one".into()
            })
        );
    }
}
