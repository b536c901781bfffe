//! Dataset format: round trip, and one rejection test per malformed case, each checking the
//! error kind, the file and the line named.

mod common;

use common::TempDir;
use prf_files::dataset::{Dataset, Demonstration, ErrorKind, Instance, Placed, Sample, TaskRecord};
use prf_shared::robot::RobotModel;
use std::path::Path;

fn placed(id: &str, kind: &str, x: f64) -> Placed {
    Placed {
        id: id.into(),
        kind: kind.into(),
        pose: [x, 0.5, 0.0, 1.0, 0.0, 0.0, 0.0],
    }
}

/// A small valid dataset: two demonstrations of 5 samples each.
fn small() -> Dataset {
    let model = RobotModel::kmr_iiwa14();
    let inst = |id: &str, kind: &str| Instance {
        id: id.into(),
        kind: kind.into(),
    };
    let demo = |k: usize| Demonstration {
        id: format!("d{k:03}"),
        task: TaskRecord {
            part: placed("Part1", "Part1", 0.1),
            from: placed("CNC1", "CNC", 0.0),
            to: placed("Table1", "Table", 3.0),
            goal: [3.1, 0.5, 0.75, 0.0, 0.0, 0.0, 1.0],
            note: Some("hand-made".into()),
        },
        samples: (0..5)
            .map(|i| Sample {
                t: i as f64 * 0.01,
                base: [1.0 + 0.001 * i as f64, -0.25, 0.123456789],
                arm: std::array::from_fn(|j| {
                    model.home[j] + 0.01 * (i * j) as f64 + 1e-9 * k as f64
                }),
                gripper: if i >= 3 { 1.0 } else { 0.0 },
            })
            .collect(),
    };
    Dataset {
        robot: "kmr-iiwa14".into(),
        description: Some("test".into()),
        rate_hz: 100.0,
        clearance_demo: Some(0.05),
        parts: vec![inst("Part1", "Part1"), inst("Part2", "Part2")],
        locations: vec![inst("CNC1", "CNC"), inst("Table1", "Table")],
        demonstrations: vec![demo(0), demo(1)],
    }
}

fn written(name: &str) -> TempDir {
    let dir = TempDir::new(name);
    small().write(dir.path()).expect("write");
    dir
}

/// Replaces line `line` (1-based) of `file` with `text`.
fn edit_line(file: &Path, line: usize, text: &str) {
    let content = std::fs::read_to_string(file).expect("read");
    let mut lines: Vec<String> = content.lines().map(String::from).collect();
    lines[line - 1] = text.to_string();
    std::fs::write(file, lines.join("\n") + "\n").expect("write");
}

fn line(file: &Path, line: usize) -> String {
    std::fs::read_to_string(file)
        .expect("read")
        .lines()
        .nth(line - 1)
        .expect("line")
        .to_string()
}

/// Reads and expects an error in `file` at `line`; returns its kind. Parsing first and
/// checking against the model after (`prf learn --add`'s way) gives the same error.
fn rejected(dir: &Path, file: &str, line: Option<usize>) -> ErrorKind {
    let model = RobotModel::kmr_iiwa14();
    let e = Dataset::read(dir, &model).expect_err("must be rejected");
    let parsed = Dataset::parse(dir).and_then(|p| p.check(&model));
    assert_eq!(parsed.err().as_ref(), Some(&e));
    assert_eq!(e.file, dir.join(file), "{e}");
    assert_eq!(e.line, line, "{e}");
    let msg = e.to_string();
    assert!(msg.contains(file), "message names the file: {msg}");
    if let Some(l) = line {
        assert!(
            msg.contains(&format!(":{l}:")),
            "message names the line: {msg}"
        );
    }
    e.kind
}

#[test]
fn round_trip_preserves_everything() {
    let dir = written("round-trip");
    let back = Dataset::read(dir.path(), &RobotModel::kmr_iiwa14()).expect("valid dataset");
    let parsed = Dataset::parse(dir.path()).expect("parsed");
    assert_eq!(parsed.check(&RobotModel::kmr_iiwa14()).as_ref(), Ok(&back));
    let orig = small();
    assert_eq!(back.parts, orig.parts);
    assert_eq!(back.locations, orig.locations);
    assert_eq!(back.robot, orig.robot);
    for (a, b) in back.demonstrations.iter().zip(&orig.demonstrations) {
        assert_eq!(a.id, b.id);
        assert_eq!(a.task, b.task);
        assert_eq!(a.samples.len(), b.samples.len());
        for (x, y) in a.samples.iter().zip(&b.samples) {
            assert!((x.t - y.t).abs() < 1e-9);
            assert_eq!(x.gripper, y.gripper);
            for k in 0..3 {
                assert!((x.base[k] - y.base[k]).abs() <= 5e-10, "base {k}");
            }
            for j in 0..7 {
                assert!((x.arm[j] - y.arm[j]).abs() <= 5e-10, "a{}", j + 1);
            }
        }
    }
    // Writing what was read gives byte-identical files.
    let again = TempDir::new("round-trip-again");
    back.write(again.path()).expect("write");
    for f in ["manifest.json", "d000.task.json", "d000.csv", "d001.csv"] {
        assert_eq!(
            std::fs::read(dir.path().join(f)).expect("a"),
            std::fs::read(again.path().join(f)).expect("b"),
            "{f}"
        );
    }
}

#[test]
fn missing_manifest() {
    let dir = TempDir::new("no-manifest");
    assert_eq!(
        rejected(dir.path(), "manifest.json", None),
        ErrorKind::MissingFile
    );
}

#[test]
fn missing_trajectory_file() {
    let dir = written("missing-csv");
    std::fs::remove_file(dir.path().join("d001.csv")).expect("rm");
    assert_eq!(
        rejected(dir.path(), "d001.csv", None),
        ErrorKind::MissingFile
    );
}

#[test]
fn missing_task_file() {
    let dir = written("missing-task");
    std::fs::remove_file(dir.path().join("d000.task.json")).expect("rm");
    assert_eq!(
        rejected(dir.path(), "d000.task.json", None),
        ErrorKind::MissingFile
    );
}

#[test]
fn non_monotonic_time() {
    let dir = written("time");
    let csv = dir.path().join("d000.csv");
    // Row 4 (line 5) gets the time of row 2.
    let l = line(&csv, 5).replacen("0.030000", "0.010000", 1);
    edit_line(&csv, 5, &l);
    let kind = rejected(dir.path(), "d000.csv", Some(5));
    assert_eq!(
        kind,
        ErrorKind::NonMonotonicTime {
            previous: 0.02,
            value: 0.01
        }
    );
}

#[test]
fn nan_value() {
    let dir = written("nan");
    let csv = dir.path().join("d001.csv");
    let mut fields: Vec<String> = line(&csv, 3).split(',').map(String::from).collect();
    fields[6] = "NaN".into();
    edit_line(&csv, 3, &fields.join(","));
    let kind = rejected(dir.path(), "d001.csv", Some(3));
    assert_eq!(
        kind,
        ErrorKind::NonFinite {
            column: "a3".into(),
            value: "NaN".into()
        }
    );
}

#[test]
fn joint_outside_limits() {
    let dir = written("limits");
    let csv = dir.path().join("d000.csv");
    let mut fields: Vec<String> = line(&csv, 4).split(',').map(String::from).collect();
    fields[7] = "2.2".into(); // a4, limit ±120° = ±2.094 rad
    edit_line(&csv, 4, &fields.join(","));
    match rejected(dir.path(), "d000.csv", Some(4)) {
        ErrorKind::JointLimit {
            joint: 4,
            value,
            upper,
            ..
        } => {
            assert_eq!(value, 2.2);
            assert!((upper - 120f64.to_radians()).abs() < 1e-12);
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn wrong_column_count() {
    let dir = written("columns");
    let csv = dir.path().join("d001.csv");
    let l = line(&csv, 6);
    edit_line(&csv, 6, &l[..l.rfind(',').expect("comma")]);
    let kind = rejected(dir.path(), "d001.csv", Some(6));
    assert_eq!(
        kind,
        ErrorKind::ColumnCount {
            expected: 12,
            found: 11
        }
    );
}

#[test]
fn bad_header() {
    let dir = written("header");
    let csv = dir.path().join("d000.csv");
    edit_line(&csv, 1, "t,x,y,yaw,a1,a2,a3,a4,a5,a6,a7,gripper");
    assert!(matches!(
        rejected(dir.path(), "d000.csv", Some(1)),
        ErrorKind::BadHeader { .. }
    ));
}

#[test]
fn not_a_number() {
    let dir = written("number");
    let csv = dir.path().join("d000.csv");
    let l = line(&csv, 2).replacen("0.000000", "zero", 1);
    edit_line(&csv, 2, &l);
    let kind = rejected(dir.path(), "d000.csv", Some(2));
    assert_eq!(
        kind,
        ErrorKind::BadNumber {
            column: "t".into(),
            value: "zero".into()
        }
    );
}

#[test]
fn unknown_location_id() {
    let dir = written("location");
    let task = dir.path().join("d001.task.json");
    let text = std::fs::read_to_string(&task)
        .expect("read")
        .replace("\"Table1\"", "\"Table9\"");
    std::fs::write(&task, &text).expect("write");
    let expected_line = text.lines().position(|l| l.contains("Table9")).expect("id") + 1;
    let kind = rejected(dir.path(), "d001.task.json", Some(expected_line));
    assert_eq!(kind, ErrorKind::UnknownLocation("Table9".into()));
}

#[test]
fn unknown_part_id() {
    let dir = written("part");
    let task = dir.path().join("d000.task.json");
    let text = std::fs::read_to_string(&task)
        .expect("read")
        .replacen("\"Part1\"", "\"Part7\"", 1);
    std::fs::write(&task, &text).expect("write");
    let expected_line = text.lines().position(|l| l.contains("Part7")).expect("id") + 1;
    let kind = rejected(dir.path(), "d000.task.json", Some(expected_line));
    assert_eq!(kind, ErrorKind::UnknownPart("Part7".into()));
}

#[test]
fn location_type_disagrees_with_manifest() {
    let dir = written("type");
    let task = dir.path().join("d000.task.json");
    let text = std::fs::read_to_string(&task)
        .expect("read")
        .replace("\"CNC\"", "\"Printer\"");
    std::fs::write(&task, &text).expect("write");
    let expected_line = text
        .lines()
        .position(|l| l.contains("\"CNC1\""))
        .expect("id")
        + 1;
    let kind = rejected(dir.path(), "d000.task.json", Some(expected_line));
    assert_eq!(
        kind,
        ErrorKind::TypeMismatch {
            id: "CNC1".into(),
            manifest: "CNC".into(),
            task: "Printer".into()
        }
    );
}

/// r_d in the manifest: kept by a round trip (above), refused when not a positive length, with
/// its line.
#[test]
fn clearance_must_be_a_positive_length() {
    for bad in ["0", "-0.05"] {
        let dir = written("clearance");
        let manifest = dir.path().join("manifest.json");
        let text = std::fs::read_to_string(&manifest).expect("manifest");
        let l = text
            .lines()
            .position(|l| l.contains("\"clearance_demo_m\""))
            .expect("the writer states r_d")
            + 1;
        edit_line(&manifest, l, &format!("  \"clearance_demo_m\": {bad},"));
        let kind = rejected(dir.path(), "manifest.json", Some(l));
        assert!(matches!(kind, ErrorKind::BadClearance(v) if v == bad.parse::<f64>().unwrap()));
    }
}

#[test]
fn malformed_json_names_the_line() {
    let dir = written("json");
    let manifest = dir.path().join("manifest.json");
    edit_line(&manifest, 3, "  \"version\": ,");
    assert!(matches!(
        rejected(dir.path(), "manifest.json", Some(3)),
        ErrorKind::Json(_)
    ));
}

#[test]
fn non_unit_quaternion() {
    let dir = written("quaternion");
    let task = dir.path().join("d000.task.json");
    let mut t: TaskRecord =
        serde_json::from_str(&std::fs::read_to_string(&task).expect("read")).expect("json");
    t.goal = [3.1, 0.5, 0.75, 0.5, 0.0, 0.0, 0.5];
    let text = serde_json::to_string_pretty(&t).expect("json");
    std::fs::write(&task, &text).expect("write");
    let expected_line = text
        .lines()
        .position(|l| l.contains("\"goal\""))
        .expect("goal")
        + 1;
    let kind = rejected(dir.path(), "d000.task.json", Some(expected_line));
    assert_eq!(
        kind,
        ErrorKind::BadPose {
            field: "goal".into()
        }
    );
}

#[test]
fn gripper_outside_zero_one() {
    let dir = written("gripper");
    let csv = dir.path().join("d001.csv");
    let l = line(&csv, 2);
    let l = format!("{},2", &l[..l.rfind(',').expect("comma")]);
    edit_line(&csv, 2, &l);
    assert_eq!(
        rejected(dir.path(), "d001.csv", Some(2)),
        ErrorKind::Gripper { value: 2.0 }
    );
}

#[test]
fn too_short_trajectory() {
    let dir = written("short");
    let csv = dir.path().join("d000.csv");
    let content = std::fs::read_to_string(&csv).expect("read");
    let first_two: Vec<&str> = content.lines().take(2).collect();
    std::fs::write(&csv, first_two.join("\n") + "\n").expect("write");
    assert_eq!(
        rejected(dir.path(), "d000.csv", None),
        ErrorKind::TooShort { rows: 1 }
    );
}
