//! ROS 2 bags (issue 19), against an independent encoder and decoder (Foxglove's Python
//! `mcap` and `mcap-ros2-support`, run by `scripts/bag-fixture.sh`): a bag written from a
//! generated dataset imports (`prf import-bag`) into that dataset and learns the same
//! knowledge; every bad bag or annotation gives an error naming the topic, the time and the
//! value; the bags `prf plan --mcap` and `prf export-mcap` write decode, message by message,
//! from their own schemas.

mod common;

use byteorder::LittleEndian;
use common::{TempDir, prf_stdout, run_prf};
use prf_files::bag::messages::{self, Header, JointState, Odometry, Time};
use prf_files::bag::{self, Annotation, BagConfig, GripperJoint, PlatformSource, Program};
use prf_files::dataset::{Dataset, Instance, Placed, TaskRecord};
use prf_shared::NA;
use prf_shared::limits::MotionLimits;
use prf_shared::robot::RobotModel;
use prf_shared::se3::wrap;
use std::collections::BTreeMap;
use std::path::Path;
use std::process::Command;

fn quiet(_: prf_files::Progress) {}

/// Runs `scripts/bag-fixture.sh` with `args`; its standard output.
fn fixture_script(args: &[&std::ffi::OsStr]) -> String {
    let out = Command::new("bash")
        .arg(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../scripts/bag-fixture.sh"
        ))
        .args(args)
        .output()
        .expect("run scripts/bag-fixture.sh");
    assert!(
        out.status.success(),
        "scripts/bag-fixture.sh {args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).expect("UTF-8")
}

/// The largest difference of two datasets' samples: [t, arm, gripper, base x/y, yaw (wrapped)].
fn differences(a: &Dataset, b: &Dataset) -> [f64; 5] {
    assert_eq!(a.demonstrations.len(), b.demonstrations.len());
    let mut d = [0.0f64; 5];
    for (da, db) in a.demonstrations.iter().zip(&b.demonstrations) {
        assert_eq!(da.id, db.id);
        assert_eq!(da.task, db.task, "{}", da.id);
        assert_eq!(da.samples.len(), db.samples.len(), "{}", da.id);
        for (x, y) in da.samples.iter().zip(&db.samples) {
            d[0] = d[0].max((x.t - y.t).abs());
            for j in 0..NA {
                d[1] = d[1].max((x.arm[j] - y.arm[j]).abs());
            }
            d[2] = d[2].max((x.gripper - y.gripper).abs());
            d[3] = d[3].max((x.base[0] - y.base[0]).hypot(x.base[1] - y.base[1]));
            d[4] = d[4].max(wrap(x.base[2] - y.base[2]).abs());
        }
    }
    d
}

#[test]
fn a_bag_from_an_independent_writer_imports_into_the_dataset_and_learns_the_same() {
    let dir = TempDir::new("import-bag");
    let (original, fixture) = (dir.path().join("original"), dir.path().join("bag"));
    run_prf(&["gen", "--only", "0-1", "--quiet"], &original);
    fixture_script(&["make".as_ref(), original.as_os_str(), fixture.as_os_str()]);
    let (bag, tasks) = (fixture.join("bag.mcap"), fixture.join("tasks.yaml"));
    let import = |name: &str, extra: &[&str]| {
        let out = dir.path().join(name);
        let mut args = vec!["import-bag", bag.to_str().unwrap(), "--tasks"];
        args.push(tasks.to_str().unwrap());
        args.extend_from_slice(extra);
        run_prf(&args, &out);
        out
    };
    let (odom, tf) = (
        import("odom", &[]),
        import("tf", &["--tf", "map,base_footprint"]),
    );
    let model = RobotModel::kmr_iiwa14();
    let read = |d: &Path| Dataset::read(d, &model).expect("read dataset");
    let (ds, from_odom, from_tf) = (read(&original), read(&odom), read(&tf));
    assert_eq!(from_odom.clearance_demo, ds.clearance_demo);
    assert_eq!(
        (&from_odom.parts, &from_odom.locations),
        (&ds.parts, &ds.locations)
    );

    // Joint states and /tf come at every row: resampling at the rows' times reproduces them
    // (up to the CSV's 1 nrad and float rounding of the stamps).
    let d = differences(&ds, &from_tf);
    println!("tf: {d:?}");
    assert!(d.iter().all(|x| *x <= 1e-9), "tf import differs by {d:?}");
    // Odometry comes at 50 Hz: linear interpolation between samples 20 ms apart is off by at
    // most |p̈|·h²/8, with |p̈| ≤ the platform's acceleration plus the centripetal ω·v.
    let l = MotionLimits::kmr_iiwa(&model);
    let h: f64 = 0.02;
    let accel = l.base_acceleration[0].hypot(l.base_acceleration[1])
        + l.base_speed[2] * l.base_speed[0].hypot(l.base_speed[1]);
    let (bound_xy, bound_yaw) = (accel * h * h / 8.0, l.base_acceleration[2] * h * h / 8.0);
    let d = differences(&ds, &from_odom);
    println!("odom: {d:?}, bounds {bound_xy:.2e} m, {bound_yaw:.2e} rad");
    assert!(d[..3].iter().all(|x| *x <= 1e-9), "odom import: {d:?}");
    assert!(d[3] <= bound_xy && d[4] <= bound_yaw, "odom import: {d:?}");

    // Learned from the imports: the same affordances (to the interpolation error) and skills.
    let learn = |ds: &Dataset| {
        prf_learn::learn(ds, &model, &prf_learn::LearnConfig::default(), &quiet).expect("learn")
    };
    let k = learn(&ds);
    for imported in [&from_tf, &from_odom] {
        let ki = learn(imported);
        assert_eq!(ki.skills.len(), k.skills.len());
        assert_eq!(ki.arms.len(), k.arms.len());
        let sets = |k: &prf_learn::Knowledge| {
            let mut v: Vec<_> = k.location_types.iter().map(|l| l.stances.clone()).collect();
            v.extend(k.part_types.iter().map(|p| p.grasps.clone()));
            v
        };
        for (a, b) in sets(&k).iter().zip(&sets(&ki)) {
            assert_eq!(a.counts, b.counts);
            for (p, q) in a.poses.iter().zip(&b.poses) {
                let dp = (p.translation.vector - q.translation.vector).norm();
                let da = p.rotation.angle_to(&q.rotation);
                assert!(
                    dp <= 1e-4 && da <= 1e-4,
                    "affordance differs by {dp} m, {da} rad"
                );
            }
        }
    }
}

// ---- hostile bags, written with the mcap crate's writer and CDR from cdr-encoding ----

const ARM: [&str; NA] = [
    "iiwa_joint_1",
    "iiwa_joint_2",
    "iiwa_joint_3",
    "iiwa_joint_4",
    "iiwa_joint_5",
    "iiwa_joint_6",
    "iiwa_joint_7",
];
const GRIPPER: &str = "finger";
/// Stamps of the k-th message: 10 ms apart from 1.7e9 s.
const ORIGIN: i64 = 1_700_000_000_000_000_000;

fn stamp(k: usize) -> i64 {
    ORIGIN + k as i64 * 10_000_000
}

fn header(t: i64) -> Header {
    Header {
        stamp: Time {
            sec: (t / 1_000_000_000) as i32,
            nanosec: (t % 1_000_000_000) as u32,
        },
        frame_id: "map".into(),
    }
}

fn cdr<T: serde::Serialize>(m: &T) -> Vec<u8> {
    let mut v = vec![0, 1, 0, 0];
    v.extend(cdr_encoding::to_vec::<T, LittleEndian>(m).expect("CDR"));
    v
}

/// 3 s at 100 Hz: joint states of the home configuration, gripper open, and odometry.
fn joint_states(model: &RobotModel) -> Vec<JointState> {
    (0..300)
        .map(|k| {
            let mut name: Vec<String> = ARM.iter().map(|s| s.to_string()).collect();
            name.push(GRIPPER.into());
            let mut position = model.home.to_vec();
            position.push(0.04);
            JointState {
                header: header(stamp(k)),
                name,
                position,
                velocity: vec![],
                effort: vec![],
            }
        })
        .collect()
}

fn odometry() -> Vec<Odometry> {
    let zero = messages::Xyz {
        x: 0.0,
        y: 0.0,
        z: 0.0,
    };
    (0..300)
        .map(|k| Odometry {
            header: header(stamp(k)),
            child_frame_id: "base_footprint".into(),
            pose: messages::PoseWithCovariance {
                pose: messages::Pose {
                    position: messages::Xyz {
                        x: 2.5,
                        y: 0.001 * k as f64,
                        z: 0.0,
                    },
                    orientation: messages::Quaternion {
                        x: 0.0,
                        y: 0.0,
                        z: 0.0,
                        w: 1.0,
                    },
                },
                covariance: [[0.0; 6]; 6],
            },
            twist: messages::TwistWithCovariance {
                twist: messages::Twist {
                    linear: zero,
                    angular: zero,
                },
                covariance: [[0.0; 6]; 6],
            },
        })
        .collect()
}

fn write_bag(path: &Path, js: &[JointState], odom: &[Odometry]) {
    let file = std::io::BufWriter::new(std::fs::File::create(path).expect("create bag"));
    let mut w = mcap::Writer::new(file).expect("writer");
    let channel = |w: &mut mcap::Writer<_>, topic: &str, schema: &str| {
        let s = w.add_schema(schema, "ros2msg", b"").expect("schema");
        w.add_channel(s, topic, "cdr", &BTreeMap::new())
            .expect("channel")
    };
    let (cj, co) = (
        channel(&mut w, "/joint_states", messages::JOINT_STATE),
        channel(&mut w, "/odom", messages::ODOMETRY),
    );
    let put = |w: &mut mcap::Writer<_>, c: u16, t: &Time, data: Vec<u8>| {
        let ns = t.ns() as u64;
        let h = mcap::records::MessageHeader {
            channel_id: c,
            sequence: 0,
            log_time: ns,
            publish_time: ns,
        };
        w.write_to_known_channel(&h, &data).expect("message");
    };
    for m in js {
        put(&mut w, cj, &m.header.stamp, cdr(m));
    }
    for m in odom {
        put(&mut w, co, &m.header.stamp, cdr(m));
    }
    w.finish().expect("finish");
}

fn placed(id: &str, kind: &str) -> Placed {
    Placed {
        id: id.into(),
        kind: kind.into(),
        pose: [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0],
    }
}

fn program(id: &str, start: f64, end: f64) -> Program {
    Program {
        id: id.into(),
        start,
        end,
        task: TaskRecord {
            part: placed("Part1", "Part1"),
            from: placed("CNC1", "CNC"),
            to: placed("Table1", "Table"),
            goal: [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0],
            note: None,
        },
    }
}

fn annotation(programs: Vec<Program>) -> Annotation {
    let inst = |id: &str, kind: &str| Instance {
        id: id.into(),
        kind: kind.into(),
    };
    Annotation {
        robot: "kmr-iiwa14".into(),
        description: None,
        clearance_demo_m: 0.05,
        gripper: GripperJoint {
            joint: GRIPPER.into(),
            open: 0.04,
            closed: 0.0,
        },
        parts: vec![inst("Part1", "Part1")],
        locations: vec![inst("CNC1", "CNC"), inst("Table1", "Table")],
        programs,
    }
}

#[test]
fn every_import_error_names_the_topic_the_time_and_the_value() {
    let dir = TempDir::new("bad-bags");
    let model = RobotModel::kmr_iiwa14();
    let arm: Vec<String> = ARM.iter().map(|s| s.to_string()).collect();
    let cfg = BagConfig::default();
    let one = annotation(vec![program("p0", 0.5, 2.5)]);
    let path = dir.path().join("bag.mcap");
    let import = |js: &[JointState], odom: &[Odometry], ann: &Annotation, cfg: &BagConfig| {
        write_bag(&path, js, odom);
        bag::import(&path, ann, &arm, cfg)
    };
    let (js, odom) = (joint_states(&model), odometry());
    // The clean bag imports: 201 samples at 100 Hz over 0.5 … 2.5 s.
    let ds = import(&js, &odom, &one, &cfg).expect("clean bag");
    assert_eq!(ds.demonstrations[0].samples.len(), 201);
    let s = &ds.demonstrations[0].samples[100];
    assert!(
        (s.base[1] - 0.15).abs() < 1e-12 && s.gripper == 0.0,
        "{s:?}"
    );

    let expect = |result: Result<Dataset, bag::BagError>, parts: &[&str]| {
        let e = result.expect_err("refused").to_string();
        for p in parts {
            assert!(e.contains(p), "{e:?} does not name {p:?}");
        }
        println!("{e}");
    };
    let mut bad = js.clone();
    bad[150].name[3] = "iiwa_joint_44".into();
    expect(
        import(&bad, &odom, &one, &cfg),
        &[
            "/joint_states",
            "t = 1.500 s",
            "\"iiwa_joint_44\"",
            "stamp 1700000001.500000000",
        ],
    );
    let mut bad = js.clone();
    bad[120].name.remove(1);
    bad[120].position.remove(1);
    expect(
        import(&bad, &odom, &one, &cfg),
        &[
            "/joint_states",
            "t = 1.200 s",
            "\"iiwa_joint_2\" is missing",
        ],
    );
    let mut bad = js.clone();
    bad[50].position[4] = f64::NAN;
    expect(
        import(&bad, &odom, &one, &cfg),
        &["/joint_states", "t = 0.500 s", "iiwa_joint_5", "NaN"],
    );
    let mut bad = js.clone();
    bad[60].position[NA] = 0.2;
    expect(
        import(&bad, &odom, &one, &cfg),
        &["/joint_states", "t = 0.600 s", "\"finger\" = 0.2"],
    );
    let mut bad = js.clone();
    bad.drain(100..130);
    expect(
        import(&bad, &odom, &one, &cfg),
        &[
            "program p0",
            "/joint_states",
            "t = 0.990 s",
            "t = 1.300 s",
            "0.310 s",
        ],
    );
    let mut bad = js.clone();
    bad.swap(200, 201);
    expect(
        import(&bad, &odom, &one, &cfg),
        &["/joint_states", "t = 2.000 s", "previous t = 2.010 s"],
    );
    let mut bad = odom.clone();
    bad[70].pose.pose.position.x = f64::INFINITY;
    expect(
        import(&js, &bad, &one, &cfg),
        &["/odom", "t = 0.700 s", "x = inf"],
    );
    expect(
        import(&js, &odom, &annotation(vec![program("p0", 2.0, 3.5)]), &cfg),
        &["program p0", "/joint_states", "2 … 3.5 s", "0 … 2.99 s"],
    );
    expect(
        import(
            &js,
            &odom,
            &annotation(vec![program("a", 0.5, 1.5), program("b", 1.4, 2.0)]),
            &cfg,
        ),
        &[
            "programs a and b overlap",
            "ends at 1.5 s",
            "starts at 1.4 s",
        ],
    );
    expect(
        import(&js, &odom, &annotation(vec![program("p0", 1.5, 1.5)]), &cfg),
        &["program p0", "1.5 … 1.5 s"],
    );
    let no_odom = BagConfig {
        platform: PlatformSource::Odometry {
            topic: "/odometry".into(),
        },
        ..cfg.clone()
    };
    expect(
        import(&js, &odom, &one, &no_odom),
        &[
            "/odometry: not in the bag",
            "nav_msgs/msg/Odometry",
            "/joint_states, /odom",
        ],
    );
    let swapped = BagConfig {
        joint_topic: "/odom".into(),
        ..cfg.clone()
    };
    expect(
        import(&js, &odom, &one, &swapped),
        &[
            "/odom",
            "nav_msgs/msg/Odometry",
            "expected sensor_msgs/msg/JointState",
        ],
    );
    let tf = BagConfig {
        platform: PlatformSource::Tf {
            topic: "/odom".into(),
            parent: "map".into(),
            child: "base".into(),
        },
        ..cfg.clone()
    };
    expect(
        import(&js, &odom, &one, &tf),
        &["/odom", "expected tf2_msgs/msg/TFMessage"],
    );
    // A truncated file and a bad annotation name the file.
    write_bag(&path, &js, &odom);
    let bytes = std::fs::read(&path).unwrap();
    std::fs::write(&path, &bytes[..bytes.len() / 2]).unwrap();
    let e = bag::import(&path, &one, &arm, &cfg)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("bag.mcap") && e.contains("not a valid MCAP"),
        "{e}"
    );
    let ann = dir.path().join("tasks.yaml");
    std::fs::write(
        &ann,
        "robot: kmr-iiwa14\nclearance_demo_m: 0.05\ngripper: 3\n",
    )
    .unwrap();
    let e = bag::read_annotation(&ann).unwrap_err().to_string();
    assert!(e.contains("tasks.yaml:3") && e.contains("gripper"), "{e}");
}

// ---- exported bags, decoded by the independent reader ----

/// The bag's messages as the Python reader decoded them.
fn read_back(bag: &Path) -> serde_json::Value {
    let text = fixture_script(&["read".as_ref(), bag.as_os_str()]);
    serde_json::from_str(&text).expect("reader JSON")
}

/// Rows of a trajectory CSV: [t, base x, y, yaw, a1 … a7, gripper].
fn csv_rows(path: &Path) -> Vec<Vec<f64>> {
    std::fs::read_to_string(path)
        .expect("CSV")
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(|v| v.parse().expect("number")).collect())
        .collect()
}

fn positions(state: &serde_json::Value) -> Vec<f64> {
    state["position"]
        .as_array()
        .expect("positions")
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect()
}

fn assert_arm(state: &serde_json::Value, row: &[f64], names: &[String]) {
    let expected_names: Vec<&str> = names.iter().map(|s| s.as_str()).collect();
    let got: Vec<&str> = state["name"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_str().unwrap())
        .collect();
    assert_eq!(got, expected_names);
    for (a, b) in positions(state).iter().zip(&row[4..4 + NA]) {
        assert!((a - b).abs() <= 1e-9, "{a} vs {b}");
    }
    let stamp = state["stamp"].as_i64().unwrap();
    assert_eq!(
        stamp,
        prf_offline::export_mcap::T0 + (row[0] * 1e9).round() as i64
    );
}

#[test]
fn exported_bags_decode_with_an_independent_reader() {
    let dir = TempDir::new("export-mcap");
    let (ds_dir, blob) = (dir.path().join("dataset"), dir.path().join("cell.blob"));
    run_prf(&["gen", "--only", "0-1", "--quiet"], &ds_dir);
    run_prf(&["learn", ds_dir.to_str().unwrap(), "--quiet"], &blob);
    let model = RobotModel::kmr_iiwa14();
    let ds = Dataset::read(&ds_dir, &model).expect("dataset");
    let names = prf_files::robot::chain_names(prf_files::robot::EXAMPLE_URDF, "urdf")
        .expect("names")
        .arm_joints;
    let world = prf_sim::world::World::example();
    let obstacles = prf_sim::world::geometry::Cell::new(&world, &model)
        .obstacles
        .len() as u64;

    // A planned program: the bag holds exactly the executed samples, decimated to 100 Hz.
    let task = &ds.demonstrations[0].task;
    let (csv, bag) = (
        dir.path().join("program.csv"),
        dir.path().join("program.mcap"),
    );
    let out = prf_stdout(&[
        "plan".as_ref(),
        blob.as_os_str(),
        "--part".as_ref(),
        task.part.id.as_ref(),
        "--from".as_ref(),
        task.from.id.as_ref(),
        "--to".as_ref(),
        task.to.id.as_ref(),
        "--export".as_ref(),
        csv.as_os_str(),
        "--mcap".as_ref(),
        bag.as_os_str(),
    ]);
    assert!(out.contains("J* = 0.0 mm"), "{out}");
    let rows = csv_rows(&csv);
    let n = rows.len().div_ceil(10) as u64;
    let r = read_back(&bag);
    let topic = |t: &str| {
        (
            r["topics"][t]["schema"].as_str(),
            r["topics"][t]["count"].as_u64(),
        )
    };
    let from = format!("/prf/workspace/{}", task.from.id.to_lowercase());
    let to = format!("/prf/workspace/{}", task.to.id.to_lowercase());
    for (t, schema, count) in [
        ("/robot_description", "std_msgs/msg/String", Some(1)),
        ("/tf_static", "tf2_msgs/msg/TFMessage", Some(1)),
        ("/joint_states", "sensor_msgs/msg/JointState", Some(n)),
        ("/tf", "tf2_msgs/msg/TFMessage", Some(n)),
        ("/prf/gripper", "std_msgs/msg/Float64", Some(n)),
        ("/prf/risk", "std_msgs/msg/Float64", None),
        (
            "/prf/obstacles",
            "visualization_msgs/msg/MarkerArray",
            Some(1),
        ),
        ("/prf/parts", "visualization_msgs/msg/MarkerArray", Some(1)),
        (from.as_str(), "sensor_msgs/msg/PointCloud2", Some(1)),
        (to.as_str(), "sensor_msgs/msg/PointCloud2", Some(1)),
    ] {
        let (s, c) = topic(t);
        assert_eq!(s, Some(schema), "{t}");
        if count.is_some() {
            assert_eq!(c, count, "{t}");
        }
    }
    assert_eq!(
        r["topics"].as_object().unwrap().len(),
        10,
        "{}",
        r["topics"]
    );
    assert_eq!(r["robot_description"], prf_files::robot::EXAMPLE_URDF);
    assert_arm(&r["first_joint_state"], &rows[0], &names);
    assert_arm(&r["last_joint_state"], &rows[(n as usize - 1) * 10], &names);
    // J* = 0: every configuration at a stance is inside its Ω+.
    assert_eq!(r["risk"], serde_json::json!([0.0, 0.0]));
    for t in [&from, &to] {
        let c = &r["clouds"][t.as_str()];
        let points = c["points"].as_u64().unwrap();
        assert!(points > 100, "{t}: {c}");
        assert_eq!(c["bytes"].as_u64(), Some(16 * points));
        assert_eq!(c["fields"], serde_json::json!(["x", "y", "z", "distance"]));
    }
    assert_eq!(r["markers"]["/prf/obstacles"].as_u64(), Some(obstacles));
    assert_eq!(r["markers"]["/prf/parts"].as_u64(), Some(2));

    // The same program as pictures.
    let view = dir.path().join("view");
    run_prf(
        &[
            "view",
            blob.to_str().unwrap(),
            "--part",
            &task.part.id,
            "--from",
            &task.from.id,
            "--to",
            &task.to.id,
        ],
        &view,
    );
    common::assert_charts(&view, &["top".into(), "side".into()]);

    // The dataset: both programs at 100 Hz, 1 s apart.
    let bag = dir.path().join("dataset.mcap");
    run_prf(
        &["export-mcap", "--dataset", ds_dir.to_str().unwrap()],
        &bag,
    );
    let r = read_back(&bag);
    let total: usize = ds.demonstrations.iter().map(|d| d.samples.len()).sum();
    assert_eq!(
        r["topics"]["/joint_states"]["count"].as_u64(),
        Some(total as u64)
    );
    let row = |s: &prf_files::dataset::Sample, offset: f64| {
        let mut v = vec![s.t + offset, s.base[0], s.base[1], s.base[2]];
        v.extend(s.arm);
        v
    };
    let first = &ds.demonstrations[0].samples;
    let last = &ds.demonstrations[1].samples;
    assert_arm(&r["first_joint_state"], &row(&first[0], 0.0), &names);
    let offset = first.last().unwrap().t + 1.0;
    assert_arm(
        &r["last_joint_state"],
        &row(last.last().unwrap(), offset),
        &names,
    );

    // The blob's knowledge: a cloud and the stances at every location of a learned type.
    let bag = dir.path().join("knowledge.mcap");
    run_prf(&["export-mcap", "--blob", blob.to_str().unwrap()], &bag);
    let r = read_back(&bag);
    let bytes = std::fs::read(&blob).unwrap();
    let rt = prf_runtime::Runtime::load(&bytes).expect("blob");
    let (mut clouds, mut stances) = (0, 0);
    for t in 0..rt.blob.payload.location_types.len() {
        let lt = rt.blob.location_type(t).unwrap();
        for l in world.locations.iter().filter(|l| l.kind == lt.name) {
            stances += lt.stances.len() as u64;
            if lt.workspace.is_some() {
                clouds += 1;
                let c = &r["clouds"][format!("/prf/workspace/{}", l.id.to_lowercase())];
                assert_eq!(c["frame"].as_str(), Some(l.id.as_str()));
                assert!(c["points"].as_u64().unwrap() > 100, "{c}");
            }
        }
    }
    assert!(clouds >= 2, "{clouds} workspaces");
    assert_eq!(r["clouds"].as_object().unwrap().len(), clouds);
    assert_eq!(r["markers"]["/prf/stances"].as_u64(), Some(stances));
    let grasps: usize = (0..rt.blob.payload.part_types.len())
        .map(|t| rt.blob.part_type(t).unwrap().grasps.len())
        .sum();
    assert!(grasps > 0);
    assert_eq!(
        r["markers"]["/prf/grasps"].as_u64(),
        Some((grasps * world.locations.len()) as u64)
    );
}
