//! Programs, datasets and a blob's knowledge as a ROS 2 bag (MCAP, CDR) that Foxglove and
//! rerun open without configuration (`prf plan --mcap`, `prf export-mcap`):
//!
//! | topic | type | what |
//! |---|---|---|
//! | `/robot_description` | `std_msgs/msg/String` | the URDF |
//! | `/joint_states` | `sensor_msgs/msg/JointState` | arm joints A1 … A7 by the URDF's names |
//! | `/tf` | `tf2_msgs/msg/TFMessage` | `map` → the URDF's root link (the platform) |
//! | `/tf_static` | `tf2_msgs/msg/TFMessage` | `map` → each location (frame = its id) |
//! | `/prf/gripper` | `std_msgs/msg/Float64` | 0 open … 1 closed |
//! | `/prf/risk` | `std_msgs/msg/Float64` | Eq. 16 of the configuration in its Ω+, m (at stances) |
//! | `/prf/workspace/<type>` | `sensor_msgs/msg/PointCloud2` | Ω+ nodes inside, with `distance` |
//! | `/prf/obstacles`, `/prf/parts`, `/prf/stances`, `/prf/grasps` | `visualization_msgs/msg/MarkerArray` | boxes, the part, stances, grasps |

use prf_files::bag::messages::{
    self, ColorRgba, CompressedImage, Float64, Header, JointState, Marker, MarkerArray, MeshFile,
    PointCloud2, PointField, Quaternion, RosDuration, StringMsg, TfMessage, Time, Transform,
    TransformStamped, Xyz,
};
use prf_files::bag::write::{BagWriter, WriteError};
use prf_files::dataset::Sample;
use prf_files::robot::ChainNames;
use prf_shared::field::{DistanceField, Field};
use prf_shared::kinematics::platform_pose;
use prf_shared::se3::Pose;
use std::path::Path;

/// Time of the first message, ns (1 s after the epoch: some viewers treat 0 as unset).
pub const T0: i64 = 1_000_000_000;

fn time(ns: i64) -> Time {
    Time {
        sec: ns.div_euclid(1_000_000_000) as i32,
        nanosec: ns.rem_euclid(1_000_000_000) as u32,
    }
}

fn header(ns: i64, frame: &str) -> Header {
    Header {
        stamp: time(ns),
        frame_id: frame.into(),
    }
}

fn ros_pose(p: &Pose) -> messages::Pose {
    let (t, q) = (p.translation.vector, p.rotation.quaternion());
    messages::Pose {
        position: Xyz {
            x: t.x,
            y: t.y,
            z: t.z,
        },
        orientation: Quaternion {
            x: q.i,
            y: q.j,
            z: q.k,
            w: q.w,
        },
    }
}

fn transform(ns: i64, parent: &str, child: &str, p: &Pose) -> TransformStamped {
    let q = ros_pose(p);
    TransformStamped {
        header: header(ns, parent),
        child_frame_id: child.into(),
        transform: Transform {
            translation: q.position,
            rotation: q.orientation,
        },
    }
}

/// A colour, components 0 … 1.
pub fn rgba(r: f32, g: f32, b: f32, a: f32) -> ColorRgba {
    ColorRgba { r, g, b, a }
}

/// A marker of `kind` (`messages::CUBE`, …) at `pose` in `frame`, of size `scale`.
pub fn marker(
    ns: &str,
    id: i32,
    kind: i32,
    frame: &str,
    pose: &Pose,
    scale: [f64; 3],
    color: ColorRgba,
) -> Marker {
    Marker {
        header: header(T0, frame),
        ns: ns.into(),
        id,
        kind,
        action: messages::ADD,
        pose: ros_pose(pose),
        scale: Xyz {
            x: scale[0],
            y: scale[1],
            z: scale[2],
        },
        color,
        lifetime: RosDuration::default(),
        frame_locked: false,
        points: vec![],
        colors: vec![],
        texture_resource: String::new(),
        texture: CompressedImage {
            header: header(0, ""),
            format: String::new(),
            data: vec![],
        },
        uv_coordinates: vec![],
        text: String::new(),
        mesh_resource: String::new(),
        mesh_file: MeshFile {
            filename: String::new(),
            data: vec![],
        },
        mesh_use_embedded_materials: false,
    }
}

/// A bag being exported.
pub struct Exporter {
    w: BagWriter,
    names: ChainNames,
}

impl Exporter {
    /// Creates `path` and writes the robot description `urdf` (whose names are `names`).
    pub fn create(path: &Path, urdf: &str, names: ChainNames) -> Result<Self, WriteError> {
        let mut w = BagWriter::create(path)?;
        w.write(
            "/robot_description",
            messages::STRING,
            T0,
            &StringMsg { data: urdf.into() },
        )?;
        Ok(Exporter { w, names })
    }

    /// The frames `map` → each (id, pose), on `/tf_static`.
    pub fn locations(&mut self, frames: &[(String, Pose)]) -> Result<(), WriteError> {
        let transforms = frames
            .iter()
            .map(|(id, p)| transform(T0, "map", id, p))
            .collect();
        self.w.write(
            "/tf_static",
            messages::TF_MESSAGE,
            T0,
            &TfMessage { transforms },
        )
    }

    /// Every `every`-th sample of a program from `t0` (ns): joint states, the platform and
    /// the gripper, and with `risk` (one per sample, NaN where none applies) the largest risk
    /// of each window of `every` samples.
    pub fn samples(
        &mut self,
        t0: i64,
        samples: &[Sample],
        every: usize,
        risk: Option<&[f64]>,
    ) -> Result<(), WriteError> {
        let every = every.max(1);
        for (k, s) in samples.iter().enumerate().step_by(every) {
            let t = t0 + (s.t * 1e9).round() as i64;
            let js = JointState {
                header: header(t, ""),
                name: self.names.arm_joints.clone(),
                position: s.arm.to_vec(),
                velocity: vec![],
                effort: vec![],
            };
            self.w
                .write("/joint_states", messages::JOINT_STATE, t, &js)?;
            let base = transform(t, "map", &self.names.root_link, &platform_pose(s.base));
            self.w.write(
                "/tf",
                messages::TF_MESSAGE,
                t,
                &TfMessage {
                    transforms: vec![base],
                },
            )?;
            self.w.write(
                "/prf/gripper",
                messages::FLOAT64,
                t,
                &Float64 { data: s.gripper },
            )?;
            if let Some(r) = risk {
                let window = &r[k..(k + every).min(r.len())];
                let worst = window
                    .iter()
                    .filter(|x| !x.is_nan())
                    .fold(f64::NAN, |a, &b| a.max(b));
                if !worst.is_nan() {
                    self.w
                        .write("/prf/risk", messages::FLOAT64, t, &Float64 { data: worst })?;
                }
            }
        }
        Ok(())
    }

    /// Ω+ of location type `name` in `frame`: every node of its field with distance ≤ 0, with
    /// the distance as the `distance` field (m).
    pub fn workspace(
        &mut self,
        name: &str,
        frame: &str,
        field: &Field<'_>,
    ) -> Result<(), WriteError> {
        let [nx, ny, nz] = field.dims();
        let mut data = Vec::new();
        let mut n = 0u32;
        for i in 0..nx {
            for j in 0..ny {
                for k in 0..nz {
                    let p = field.node_position(i, j, k);
                    let d = field.distance(&p);
                    if d <= 0.0 {
                        for v in [p.x as f32, p.y as f32, p.z as f32, d as f32] {
                            data.extend(v.to_le_bytes());
                        }
                        n += 1;
                    }
                }
            }
        }
        let field = |name: &str, offset: u32| PointField {
            name: name.into(),
            offset,
            datatype: messages::FLOAT32,
            count: 1,
        };
        let cloud = PointCloud2 {
            header: header(T0, frame),
            height: 1,
            width: n,
            fields: vec![
                field("x", 0),
                field("y", 4),
                field("z", 8),
                field("distance", 12),
            ],
            is_bigendian: false,
            point_step: 16,
            row_step: 16 * n,
            data,
            is_dense: true,
        };
        let topic = format!("/prf/workspace/{}", name.to_lowercase());
        self.w.write(&topic, messages::POINT_CLOUD2, T0, &cloud)
    }

    /// Markers on `topic` (latched at the start).
    pub fn markers(&mut self, topic: &str, markers: Vec<Marker>) -> Result<(), WriteError> {
        self.w
            .write(topic, messages::MARKER_ARRAY, T0, &MarkerArray { markers })
    }

    /// Closes the bag; the messages written per topic.
    pub fn finish(self) -> Result<Vec<(String, &'static str, u64)>, WriteError> {
        let counts = self.w.counts();
        self.w.finish()?;
        Ok(counts)
    }
}

/// The risk (Eq. 16) of each sample's configuration in the Ω+ of the location it stands at
/// (the platform within 1 mm and 1 mrad of the plan's stance at ℓ1 or ℓ2); NaN elsewhere.
pub fn program_risk(
    rt: &prf_runtime::Runtime<'_>,
    plan: &prf_runtime::plan::Plan,
    from: &Pose,
    to: &Pose,
    samples: &[Sample],
) -> Result<Vec<f64>, prf_runtime::LoadError> {
    let Some((at_from, at_to)) = plan.stances else {
        return Ok(vec![f64::NAN; samples.len()]);
    };
    let (from_field, to_field) = (
        rt.workspace(plan.resolved.from_type)?,
        rt.workspace(plan.resolved.to_type)?,
    );
    let sides = [(at_from, from, from_field), (at_to, to, to_field)];
    let at = |stance: &Pose, p: &Pose| {
        (stance.translation.vector - p.translation.vector).norm() < 1e-3
            && stance.rotation.angle_to(&p.rotation) < 1e-3
    };
    Ok(samples
        .iter()
        .map(|s| {
            let platform = platform_pose(s.base);
            sides
                .iter()
                .find(|(stance, _, _)| at(stance, &platform))
                .and_then(|(_, location, field)| {
                    let field = field.as_ref()?;
                    let arm_base = location.inverse() * platform * rt.model.mount;
                    let kin = prf_shared::kinematics::ArmKinematics::new(&rt.model, &s.arm.into());
                    let mut acc = prf_shared::risk::RiskAccumulator::default();
                    Some(acc.add(&rt.model, field, &arm_base, &kin))
                })
                .unwrap_or(f64::NAN)
        })
        .collect())
}
