//! The knowledge base: a [`crate::learn::Learner`]'s whole state in one file, so that
//! `prf learn --add DEMO --into KB` folds new demonstrations into what was learned without
//! learning the rest again (issue 17): the new demonstrations' lessons are computed, merged,
//! and only the fields of the location types they touch are rebuilt, continuing from the
//! kept sweeps and splats.
//!
//! The blob is not the container for this: it holds the encoded fields, not the swept
//! spheres they were built from, nor the demonstrated paths that tell equal skills apart.
//!
//! File layout: `PRF-KB` magic, format version (u32 LE), the base's length after the header
//! (u64 LE), the core's length (u64 LE) and CRC-32 (the blob's, [`prf_shared::blob::crc32`];
//! u32 LE), then the base: the core, `LearnerState` in postcard, followed by one section per
//! location type holding its sweep (its length, u64 LE, CRC-32, u32 LE, and a `SweepState` in
//! postcard). The sweeps are 97 % of the file (55.2 of 56.7 MB for the example cell) and each
//! is checked and decoded only when read, so `prf learn --add` reads only the types its
//! programs touch ([`crate::learn::Learner::open`]). Additions may follow the base, one per
//! `prf learn --add`, each its length (u64 LE), CRC-32 (u32 LE) and an `AdditionState` in
//! postcard: the file grows by appending instead of being rewritten whole, and loading replays
//! the additions.

use crate::capsule::Capsule;
use crate::workspace::{SeenKey, SphereSample, SweptPath};
use nalgebra::{Isometry3, Quaternion, Translation3, Unit, UnitQuaternion, Vector3};
use prf_shared::NA;
use prf_shared::dmp::{DmpParams, MAX_BASES};
use prf_shared::rdmp::Rdmp;
use prf_shared::robot::{Joint, PlatformBox, RobotModel, Sphere};
use prf_shared::se3::Pose;
use serde::{Deserialize, Serialize};
use std::marker::PhantomData;
use std::ops::Range;
use std::sync::Arc;

/// The file's first bytes.
pub const MAGIC: [u8; 6] = *b"PRF-KB";
/// The layout this build writes and reads (2: the swept spheres, their keys and the splat as
/// byte strings of `Record`s; 3: additions may follow the base; 4: each location type's sweep
/// in a section of its own, after the core; 5: a program's fingerprint covers its task, not
/// only its trajectory, [`crate::learn::fingerprint`]; 6: each swept sphere names the piece
/// of its path it lies on, [`crate::capsule`]).
pub const VERSION: u32 = 6;
/// Magic, version, base length, core length, core CRC-32.
pub const HEADER: usize = 6 + 4 + 8 + 8 + 4;
/// A sweep section's or an addition's length (u64 LE) and CRC-32 (u32 LE).
const FRAME: usize = 8 + 4;

/// The [`FRAME`] of a payload of `len` bytes whose CRC-32 is `crc`.
fn frame_of(len: usize, crc: u32) -> [u8; FRAME] {
    let mut frame = [0; FRAME];
    frame[..8].copy_from_slice(&(len as u64).to_le_bytes());
    frame[8..].copy_from_slice(&crc.to_le_bytes());
    frame
}

/// Why a knowledge-base file cannot be read.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum KbError {
    #[error(
        "not a knowledge base (no PRF-KB header): write one with `prf learn DATASET --kb FILE`"
    )]
    Magic,
    #[error(
        "knowledge base format version {found}, this build reads version {VERSION}: learn it again"
    )]
    Version { found: u32 },
    #[error("the knowledge base is cut short: {len} bytes, its header says {expected}")]
    Truncated { len: usize, expected: usize },
    #[error("the knowledge base is corrupt: CRC-32 {found:08x}, its header says {expected:08x}")]
    Crc { found: u32, expected: u32 },
    #[error("the knowledge base does not decode: {0}")]
    Decode(String),
    #[error("the knowledge base's sweep of location type {location_type} (at byte {at}) {why}")]
    Sweep {
        location_type: String,
        at: usize,
        why: String,
    },
    #[error(
        "addition {n} of the knowledge base (at byte {at}) is cut short: {len} bytes of {expected} \
         (an interrupted `prf learn --add`?); its first {at} bytes are the knowledge base before it"
    )]
    CutAddition {
        n: usize,
        at: usize,
        len: usize,
        expected: usize,
    },
    #[error("addition {n} of the knowledge base (at byte {at}) is corrupt: {why}")]
    Addition { n: usize, at: usize, why: String },
    #[error("the knowledge base names a motion class this build does not have: {0:?}")]
    Class(String),
    #[error("the knowledge base's robot model is invalid: {0}")]
    Robot(String),
}

/// A learner as plain data (see [`crate::learn::Learner`] for the meaning of each field).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub(crate) struct LearnerState {
    pub robot: RobotState,
    pub description: String,
    pub config: crate::learn::LearnConfig,
    pub clearance_demo: f64,
    pub location_kinds: Vec<String>,
    pub part_kinds: Vec<String>,
    /// Per location type: stances, field, instances.
    pub location_types: Vec<(
        AffordanceState,
        Option<crate::workspace::LearnedField>,
        usize,
    )>,
    /// Per part type: grasps.
    pub part_types: Vec<AffordanceState>,
    /// Per location type, the swept spheres not yet in its field: (centre, sphere index).
    pub pending: Vec<Vec<Vec<PathSphereState>>>,
    pub arms: Vec<ArmState>,
    pub skills: Vec<SkillState>,
    pub instances: Vec<(String, usize)>,
    pub demonstrations: usize,
    /// The demonstrations added, in order: id and fingerprint.
    pub ids: Vec<(String, u32)>,
}

/// One `prf learn --add`: the lessons of the programs it added, in order, and, per location
/// type whose field it rebuilt, that field and the splat it left.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub(crate) struct AdditionState {
    pub lessons: Vec<LessonsState>,
    pub rebuilt: Vec<Rebuilt>,
}

/// A location type rebuilt by an addition: its index, field and splat.
pub(crate) type Rebuilt = (
    usize,
    Option<crate::workspace::LearnedField>,
    Option<SplatState>,
);

/// Bytes enough for most encodings of these lessons but for their swept spheres (pieces of
/// their own, [`Pieces`]): their arm paths' and weights' bytes (postcard writes an f64 as its
/// 8 bytes) and 64 KiB for the rest (a capacity reserved, not touched: its unused pages cost
/// nothing).
fn lessons_bound(lessons: &[LessonsState]) -> usize {
    let long = lessons.iter().flat_map(|l| &l.lessons).map(|l| {
        l.arm.as_ref().map_or(0, |a| {
            (a.path.len() * 7 + a.rdmp.weights.len()) * size_of::<f64>()
        })
    });
    long.sum::<usize>() + (64 << 10)
}

/// [`lessons_bound`] for rebuilt fields and their splats.
fn rebuilt_bound(rebuilt: &[Rebuilt]) -> usize {
    let long = rebuilt.iter().map(|(_, field, splat)| {
        field.as_ref().map_or(0, |f| f.bytes())
            + splat.as_ref().map_or(0, |s| {
                s.value.len() * <f64 as Record>::SIZE + s.feature.len() * <u32 as Record>::SIZE
            })
    });
    long.sum::<usize>() + (64 << 10)
}

/// A [`crate::learn::Lessons`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub(crate) struct LessonsState {
    pub demonstration: String,
    pub fingerprint: u32,
    pub lessons: Vec<LessonState>,
}

/// A [`crate::learn::Lesson`], its class by name.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub(crate) struct LessonState {
    pub class: String,
    pub location_type: Option<usize>,
    pub part_type: usize,
    /// The affordance: its frame f_a ([`FRAMES`] index) and the pose ([`pose_state`]).
    pub affordance: Option<(u8, [f64; 7])>,
    pub sweep: Option<PathSpheres>,
    pub arm: Option<ArmState>,
}

/// The frames an affordance is learned in, by index in the file.
pub(crate) const FRAMES: [prf_shared::motion::Frame; 5] = {
    use prf_shared::motion::Frame::*;
    [World, Base, Tcp, Part, Location]
};

/// Swept spheres of one instance, in order: a lesson's path, written straight from it as
/// [`Record`]s and read back into a [`crate::workspace::SweptPath`].
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct PathSpheres(pub std::sync::Arc<crate::workspace::SweptPath>);

impl Serialize for PathSpheres {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        self.0.records().serialize(s)
    }
}

impl<'de> Deserialize<'de> for PathSpheres {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let read = RecordBytes::<crate::workspace::PathSphere>::deserialize(d)?;
        let spheres = RecordBytes::new(std::borrow::Cow::Owned(read.0.into_owned()));
        Ok(PathSpheres(std::sync::Arc::new(
            crate::workspace::SweptPath::of_records(spheres),
        )))
    }
}

/// A pose exactly as held: [x, y, z, qw, qx, qy, qz] (no normalisation, no sign flip).
pub(crate) fn pose_state(p: &Pose) -> [f64; 7] {
    let (t, q) = (p.translation.vector, p.rotation.quaternion());
    [t.x, t.y, t.z, q.w, q.i, q.j, q.k]
}

/// The pose [`pose_state`] gave; a non-finite one is refused.
pub(crate) fn pose_of(a: [f64; 7]) -> Result<Pose, KbError> {
    if a.iter().any(|v| !v.is_finite()) {
        return Err(KbError::Decode(format!("a pose is not finite: {a:?}")));
    }
    Ok(Isometry3::from_parts(
        Translation3::new(a[0], a[1], a[2]),
        UnitQuaternion::new_unchecked(Quaternion::new(a[3], a[4], a[5], a[6])),
    ))
}

/// A swept sphere: centre, index in the robot model.
pub(crate) type PathSphereState = ([f64; 3], u8);

/// A joint: origin, axis, lower, upper, max speed.
type JointState = ([f64; 7], [f64; 3], f64, f64, f64);

/// A robot model exactly (the blob's record normalises its quaternions).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub(crate) struct RobotState {
    mount: [f64; 7],
    /// Per joint: origin, axis, lower, upper, max speed.
    joints: Vec<JointState>,
    flange: [f64; 7],
    tcp: [f64; 7],
    spheres: Vec<(u8, [f64; 3], f64)>,
    platform: ([f64; 3], [f64; 3]),
    home: [f64; NA],
    sphere_margin: f64,
}

impl RobotState {
    /// Number of collision spheres.
    pub fn spheres(&self) -> usize {
        self.spheres.len()
    }

    /// The collision spheres' radii.
    pub fn radii(&self) -> impl Iterator<Item = f64> + '_ {
        self.spheres.iter().map(|s| s.2)
    }

    pub fn of(m: &RobotModel) -> Self {
        let v = |x: &Vector3<f64>| [x.x, x.y, x.z];
        RobotState {
            mount: pose_state(&m.mount),
            joints: m
                .joints
                .iter()
                .map(|j| {
                    let a = j.axis.into_inner();
                    (pose_state(&j.origin), v(&a), j.lower, j.upper, j.max_speed)
                })
                .collect(),
            flange: pose_state(&m.flange),
            tcp: pose_state(&m.tcp),
            spheres: m
                .spheres
                .iter()
                .map(|s| (s.link, v(&s.centre), s.radius))
                .collect(),
            platform: (v(&m.platform.centre), v(&m.platform.half_extents)),
            home: m.home,
            sphere_margin: m.sphere_margin,
        }
    }

    /// The model, validated ([`RobotModel::validate`]).
    pub fn model(&self) -> Result<RobotModel, KbError> {
        let v = |a: [f64; 3]| Vector3::new(a[0], a[1], a[2]);
        if self.joints.len() != NA {
            return Err(KbError::Robot(format!(
                "{} joints, not {NA}",
                self.joints.len()
            )));
        }
        let mut joints = [Joint::unset(); NA];
        for (j, &(origin, axis, lower, upper, max_speed)) in joints.iter_mut().zip(&self.joints) {
            *j = Joint {
                origin: pose_of(origin)?,
                axis: Unit::new_unchecked(v(axis)),
                lower,
                upper,
                max_speed,
            };
        }
        let mut spheres = heapless::Vec::new();
        for &(link, centre, radius) in &self.spheres {
            spheres
                .push(Sphere {
                    link,
                    centre: v(centre),
                    radius,
                })
                .map_err(|_| KbError::Robot("too many spheres".into()))?;
        }
        let m = RobotModel {
            mount: pose_of(self.mount)?,
            joints,
            flange: pose_of(self.flange)?,
            tcp: pose_of(self.tcp)?,
            spheres,
            platform: PlatformBox {
                centre: v(self.platform.0),
                half_extents: v(self.platform.1),
            },
            home: self.home,
            sphere_margin: self.sphere_margin,
        };
        m.validate().map_err(|e| KbError::Robot(format!("{e:?}")))?;
        Ok(m)
    }
}

/// An affordance set: poses ([`pose_state`]) and their counts.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub(crate) struct AffordanceState {
    pub poses: Vec<[f64; 7]>,
    pub counts: Vec<usize>,
}

/// A [`crate::workspace::Sweep`], in a section of its own ([`section`]). Read, its spheres
/// and keys stay in the bytes read ([`RecordBytes`]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub(crate) struct SweepState<'a> {
    #[serde(borrow)]
    pub spheres: RecordBytes<'a, SphereSample>,
    /// The pieces of path the spheres lie on ([`crate::capsule`]).
    #[serde(borrow)]
    pub capsules: RecordBytes<'a, Capsule>,
    #[serde(borrow)]
    pub seen: RecordBytes<'a, SeenKey>,
    pub feature_spacing: f64,
    pub features: Vec<([f64; 3], f64)>,
    pub splat: Option<SplatState>,
}

/// An array of [`Record`]s as the file holds it, one byte string: borrowed from the bytes
/// read (a sweep's spheres and keys stay there, [`crate::in_file`]), or made to be written.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct RecordBytes<'a, T>(pub std::borrow::Cow<'a, [u8]>, PhantomData<T>);

impl<'a, T: Record> RecordBytes<'a, T> {
    pub fn new(bytes: std::borrow::Cow<'a, [u8]>) -> Self {
        RecordBytes(bytes, PhantomData)
    }

    /// Number of records.
    pub fn len(&self) -> usize {
        self.0.len() / T::SIZE
    }

    /// Record `i` (< [`RecordBytes::len`]).
    pub fn get(&self, i: usize) -> T {
        T::get(&self.0[i * T::SIZE..(i + 1) * T::SIZE])
    }
}

impl<T: Record + Sync> RecordBytes<'static, T> {
    /// The records of `prefix` (whole records, as a file holds them) followed by `items`,
    /// written on every core.
    pub fn written(prefix: &[u8], items: &[T]) -> Self {
        use rayon::prelude::*;
        let mut out = Vec::with_capacity(prefix.len() + items.len() * T::SIZE);
        out.extend_from_slice(prefix);
        let at = out.len();
        out.resize(at + items.len() * T::SIZE, 0);
        out[at..]
            .par_chunks_exact_mut(T::SIZE)
            .zip(items)
            .for_each(|(b, r)| r.put(b));
        RecordBytes::new(std::borrow::Cow::Owned(out))
    }
}

impl<T: Record + Sync> RecordBytes<'_, T> {
    /// The records, decoded on every core.
    pub fn decoded(&self) -> Vec<T>
    where
        T: Send,
    {
        use rayon::prelude::*;
        self.0.par_chunks_exact(T::SIZE).map(T::get).collect()
    }

    /// Whether every record passes `test` (decoded on every core: the example cell's Table
    /// holds 338 k spheres).
    pub fn all(&self, test: impl Fn(&T) -> bool + Sync) -> bool {
        use rayon::prelude::*;
        let records = self.0.par_chunks_exact(T::SIZE);
        records.all(|b| test(&T::get(b)))
    }

    /// Whether the records ascend strictly (on every core).
    pub fn ascending(&self) -> bool
    where
        T: PartialOrd,
    {
        use rayon::prelude::*;
        (1..self.len())
            .into_par_iter()
            .all(|i| self.get(i - 1) < self.get(i))
    }
}

impl<T> Serialize for RecordBytes<'_, T> {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_bytes(&self.0)
    }
}

impl<'de: 'a, 'a, T: Record> Deserialize<'de> for RecordBytes<'a, T> {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let b = <&'de [u8]>::deserialize(d)?;
        records::whole::<D::Error>(b.len(), T::SIZE)?;
        Ok(RecordBytes::new(std::borrow::Cow::Borrowed(b)))
    }
}

/// The last field build's splat of a sweep.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub(crate) struct SplatState {
    pub origin: [f64; 3],
    pub dims: [usize; 3],
    pub grid: [f64; 3],
    #[serde(with = "records")]
    pub value: Vec<f64>,
    #[serde(with = "records")]
    pub feature: Vec<u32>,
    pub done: usize,
}

/// A [`crate::skills::ArmSkill`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub(crate) struct ArmState {
    pub rdmp: RdmpState,
    pub path: Vec<[f64; 7]>,
    pub dt: f64,
}

/// A [`crate::skills::Skill`], its class by name.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub(crate) struct SkillState {
    pub class: String,
    pub rdmp: Option<usize>,
    pub location_type: Option<usize>,
    pub part_type: Option<usize>,
    pub demo: String,
    pub shared: bool,
}

/// An [`Rdmp`] exactly: its three DMPs' parameters, durations and forcing terms, the
/// rotation's travel and γ's goal.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub(crate) struct RdmpState {
    /// Position, rotation, γ.
    pub params: [DmpParams; 3],
    pub tau: [f64; 3],
    /// Weights of position (3 rows), rotation (3 rows), γ (1 row), [`MAX_BASES`] each.
    pub weights: Vec<f64>,
    pub scaled: [bool; 7],
    pub travel: [f64; 3],
    pub gamma_goal: f64,
}

impl RdmpState {
    pub fn of(r: &Rdmp) -> Self {
        let (p, o, g) = (&r.position, &r.rotation, &r.gamma);
        let rows = p
            .forcing
            .weights
            .iter()
            .chain(&o.forcing.weights)
            .chain(&g.forcing.weights);
        let s = |a: &[bool]| a.to_vec();
        let scaled: Vec<bool> = [
            s(&p.forcing.scaled),
            s(&o.forcing.scaled),
            s(&g.forcing.scaled),
        ]
        .concat();
        RdmpState {
            params: [p.params, o.params, g.params],
            tau: [p.tau, o.tau, g.tau],
            weights: rows.flat_map(|w| w.iter().copied()).collect(),
            scaled: core::array::from_fn(|i| scaled[i]),
            travel: [o.travel.x, o.travel.y, o.travel.z],
            gamma_goal: r.gamma_goal,
        }
    }

    /// The RDMP, or None when the weights do not fill exactly seven rows.
    pub fn rdmp(&self) -> Option<Rdmp> {
        if self.weights.len() != 7 * MAX_BASES {
            return None;
        }
        let row = |i: usize| -> [f64; MAX_BASES] {
            core::array::from_fn(|k| self.weights[i * MAX_BASES + k])
        };
        let mut r = Rdmp::empty();
        r.position.params = self.params[0];
        r.rotation.params = self.params[1];
        r.gamma.params = self.params[2];
        r.position.tau = self.tau[0];
        r.rotation.tau = self.tau[1];
        r.gamma.tau = self.tau[2];
        r.position.forcing.weights = [row(0), row(1), row(2)];
        r.rotation.forcing.weights = [row(3), row(4), row(5)];
        r.gamma.forcing.weights = [row(6)];
        r.position.forcing.scaled = [self.scaled[0], self.scaled[1], self.scaled[2]];
        r.rotation.forcing.scaled = [self.scaled[3], self.scaled[4], self.scaled[5]];
        r.gamma.forcing.scaled = [self.scaled[6]];
        r.rotation.travel = nalgebra::Vector3::new(self.travel[0], self.travel[1], self.travel[2]);
        r.gamma_goal = self.gamma_goal;
        Some(r)
    }
}

/// A fixed-size record of the knowledge base's long arrays, little-endian. Such an array is
/// written as one byte string ([`records`]), not element by element: the example cell's
/// 1.2 M swept spheres encode and decode in milliseconds instead of a tenth of a second.
pub(crate) trait Record: Sized {
    const SIZE: usize;
    /// Writes the record into `out`, `SIZE` bytes.
    fn put(&self, out: &mut [u8]);
    /// The record of `SIZE` bytes.
    fn get(b: &[u8]) -> Self;
}

/// The first `N` words of `b` as little-endian numbers (`from` of each `W`-byte word; zeros
/// if `b` is shorter), tested once for length: a record's fields then decode as plain loads,
/// without a bounds check per byte.
fn words<const N: usize, const W: usize, T: Default + Copy>(
    b: &[u8],
    from: fn([u8; W]) -> T,
) -> [T; N] {
    match b.as_chunks::<W>().0.first_chunk::<N>() {
        Some(w) => w.map(from),
        None => [T::default(); N],
    }
}

/// Writes `values` into `out` as little-endian f64s.
fn put_f64s<'a>(out: &mut [u8], values: impl IntoIterator<Item = &'a f64>) {
    for (b, v) in out.chunks_exact_mut(8).zip(values) {
        b.copy_from_slice(&v.to_le_bytes());
    }
}

/// Centre x, y, z and radius: decoded straight into the sweep's own type (no second copy of
/// the example cell's 38 MB of swept spheres).
impl Record for SphereSample {
    const SIZE: usize = 36;
    fn put(&self, out: &mut [u8]) {
        put_f64s(out, self.centre.iter().chain([&self.radius]));
        out[32..36].copy_from_slice(&self.capsule.to_le_bytes());
    }
    fn get(b: &[u8]) -> Self {
        let [x, y, z, radius] = words(&b[..32], f64::from_le_bytes);
        SphereSample {
            centre: Vector3::new(x, y, z),
            radius,
            capsule: u32::from_le_bytes([b[32], b[33], b[34], b[35]]),
        }
    }
}

impl Record for Capsule {
    const SIZE: usize = 56;
    fn put(&self, out: &mut [u8]) {
        put_f64s(out, self.a.iter().chain(self.b.iter()).chain([&self.loss]));
    }
    fn get(b: &[u8]) -> Self {
        let [ax, ay, az, bx, by, bz, loss] = words(b, f64::from_le_bytes);
        Capsule {
            a: Vector3::new(ax, ay, az),
            b: Vector3::new(bx, by, bz),
            loss,
        }
    }
}

impl Record for crate::workspace::PathSphere {
    const SIZE: usize = 25;
    fn put(&self, out: &mut [u8]) {
        put_f64s(out, self.centre.iter());
        out[24] = self.sphere;
    }
    fn get(b: &[u8]) -> Self {
        let [x, y, z] = words(b, f64::from_le_bytes);
        crate::workspace::PathSphere {
            centre: Vector3::new(x, y, z),
            sphere: b.get(24).copied().unwrap_or_default(),
        }
    }
}

impl Record for (i32, i32, i32, u8) {
    const SIZE: usize = 13;
    fn put(&self, out: &mut [u8]) {
        for (b, v) in out.chunks_exact_mut(4).zip([self.0, self.1, self.2]) {
            b.copy_from_slice(&v.to_le_bytes());
        }
        out[12] = self.3;
    }
    fn get(b: &[u8]) -> Self {
        let [x, y, z] = words(b, i32::from_le_bytes);
        (x, y, z, b.get(12).copied().unwrap_or_default())
    }
}

impl Record for f64 {
    const SIZE: usize = 8;
    fn put(&self, out: &mut [u8]) {
        out.copy_from_slice(&self.to_le_bytes());
    }
    fn get(b: &[u8]) -> Self {
        let [v] = words(b, f64::from_le_bytes);
        v
    }
}

impl Record for u32 {
    const SIZE: usize = 4;
    fn put(&self, out: &mut [u8]) {
        out.copy_from_slice(&self.to_le_bytes());
    }
    fn get(b: &[u8]) -> Self {
        let [v] = words(b, u32::from_le_bytes);
        v
    }
}

/// `#[serde(with = "records")]`: a `Vec` of [`Record`]s as one byte string.
mod records {
    use super::{Record, RecordBytes};
    use serde::de::Error;
    use serde::{Deserialize, Deserializer, Serializer};

    pub fn serialize<S: Serializer, T: Record + Sync>(
        items: &[T],
        s: S,
    ) -> Result<S::Ok, S::Error> {
        s.serialize_bytes(&RecordBytes::written(&[], items).0)
    }

    pub fn deserialize<'de, D: Deserializer<'de>, T: Record + Send + Sync>(
        d: D,
    ) -> Result<Vec<T>, D::Error> {
        Ok(RecordBytes::<T>::deserialize(d)?.decoded())
    }

    /// Refuses an array of `len` bytes that is not whole `size`-byte records.
    pub fn whole<E: Error>(len: usize, size: usize) -> Result<(), E> {
        if !len.is_multiple_of(size) {
            return Err(E::custom(format!(
                "an array of {len} bytes is not made of {size}-byte records"
            )));
        }
        Ok(())
    }
}

/// The file of a learner's state: the header, `state` (the core), then the location types'
/// sweep `sections` ([`section`], or the bytes of one read from a file), in type order.
pub(crate) fn encode(state: &LearnerState, sections: &[&[u8]]) -> Vec<u8> {
    // Straight after the header, the lengths and CRC-32 filled in after: no second copy.
    let mut out = Vec::from([0; HEADER]);
    out[..6].copy_from_slice(&MAGIC);
    out[6..10].copy_from_slice(&VERSION.to_le_bytes());
    // Plain data of Vecs and numbers: postcard cannot fail on it (nor on a Vec's Extend).
    out = postcard::to_extend(state, out).unwrap_or_default();
    let core = out.len().saturating_sub(HEADER);
    let crc = crc32(out.get(HEADER..).unwrap_or_default());
    for s in sections {
        out.extend_from_slice(s);
    }
    let base = out.len().saturating_sub(HEADER);
    if let Some(h) = out.get_mut(10..HEADER) {
        h[..8].copy_from_slice(&(base as u64).to_le_bytes());
        h[8..16].copy_from_slice(&(core as u64).to_le_bytes());
        h[16..].copy_from_slice(&crc.to_le_bytes());
    }
    out
}

/// A location type's sweep section: its length, CRC-32 and `sweep` in postcard.
pub(crate) fn section(sweep: &SweepState<'_>) -> Vec<u8> {
    framed(sweep)
}

/// The lessons of an addition (`AdditionState::lessons`) in postcard: the record's first
/// field, encoded on its own ([`AdditionRecord`]), in pieces (`Pieces`): the swept paths'
/// sphere records, most of an addition's bytes, stay where the paths keep them.
pub struct LessonsPart(Vec<Piece>);

/// A piece of a [`LessonsPart`]: bytes encoded for it, or a swept path's sphere records.
enum Piece {
    Encoded(Vec<u8>),
    Spheres(Arc<SweptPath>),
}

impl Piece {
    fn bytes(&self) -> &[u8] {
        match self {
            Piece::Encoded(b) => b,
            Piece::Spheres(p) => &p.records().0,
        }
    }
}

/// A postcard flavor that writes an encoding as [`Piece`]s: a byte string that is the sphere
/// records of one of `paths` (the same address and length) becomes a piece that refers to
/// its path, instead of a copy (for one demonstration 2.7 MB, a sixth of the page faults of
/// `prf learn --add`).
struct Pieces<'a> {
    paths: &'a [Arc<SweptPath>],
    pieces: Vec<Piece>,
    /// The bytes encoded since the last path's records.
    open: Vec<u8>,
}

impl Pieces<'_> {
    /// The path whose sphere records `data` is.
    fn path_of(&self, data: &[u8]) -> Option<&Arc<SweptPath>> {
        // Only a byte string can be a path's records; postcard writes the others by field.
        if data.len() < crate::workspace::PathSphere::SIZE {
            return None;
        }
        self.paths
            .iter()
            .find(|p| std::ptr::eq(p.records().0.as_ref(), data))
    }
}

impl postcard::ser_flavors::Flavor for Pieces<'_> {
    type Output = Vec<Piece>;

    fn try_push(&mut self, data: u8) -> postcard::Result<()> {
        self.open.push(data);
        Ok(())
    }

    fn try_extend(&mut self, data: &[u8]) -> postcard::Result<()> {
        match self.path_of(data).cloned() {
            Some(path) => {
                let encoded = std::mem::take(&mut self.open);
                self.pieces.push(Piece::Encoded(encoded));
                self.pieces.push(Piece::Spheres(path));
            }
            None => self.open.extend_from_slice(data),
        }
        Ok(())
    }

    fn finalize(mut self) -> postcard::Result<Vec<Piece>> {
        self.pieces.push(Piece::Encoded(self.open));
        Ok(self.pieces)
    }
}

/// [`LessonsPart`] of `lessons`.
pub(crate) fn encode_lessons(lessons: &[LessonsState]) -> LessonsPart {
    let paths: Vec<Arc<SweptPath>> = lessons
        .iter()
        .flat_map(|l| &l.lessons)
        .filter_map(|l| Some(l.sweep.as_ref()?.0.clone()))
        .collect();
    let pieces = Pieces {
        paths: &paths,
        pieces: Vec::new(),
        open: Vec::with_capacity(lessons_bound(lessons)),
    };
    LessonsPart(postcard::serialize_with_flavor(lessons, pieces).unwrap_or_default())
}

/// An addition's record, to append to a knowledge base: the frame (length and CRC-32 of the
/// rest), the lessons ([`LessonsPart`]) and the rebuilt types in postcard. Postcard encodes a
/// struct as its fields in order, so the last two are the `AdditionState`'s encoding (test
/// `an_addition_in_parts_is_the_additions_encoding`); kept apart, neither is copied into the
/// other.
pub struct AdditionRecord {
    frame: [u8; FRAME],
    lessons: LessonsPart,
    rebuilt: Vec<u8>,
}

impl AdditionRecord {
    /// Bytes in all.
    pub fn len(&self) -> usize {
        self.parts().iter().map(|p| p.len()).sum()
    }

    /// Never: a record has at least its frame.
    pub fn is_empty(&self) -> bool {
        false
    }

    /// The parts, in file order.
    pub fn parts(&self) -> Vec<&[u8]> {
        let lessons = self.lessons.0.iter().map(Piece::bytes);
        std::iter::once(&self.frame[..])
            .chain(lessons)
            .chain([&self.rebuilt[..]])
            .collect()
    }

    /// The record in one buffer.
    pub fn to_vec(&self) -> Vec<u8> {
        self.parts().concat()
    }
}

/// The addition record of `lessons` and the types `rebuilt`.
pub(crate) fn encode_addition(lessons: LessonsPart, rebuilt: &[Rebuilt]) -> AdditionRecord {
    let out = Vec::with_capacity(rebuilt_bound(rebuilt));
    let rebuilt = postcard::to_extend(rebuilt, out).unwrap_or_default();
    let mut crc = crc32fast::Hasher::new();
    let mut len = rebuilt.len();
    for piece in &lessons.0 {
        crc.update(piece.bytes());
        len += piece.bytes().len();
    }
    crc.update(&rebuilt);
    AdditionRecord {
        frame: frame_of(len, crc.finalize()),
        lessons,
        rebuilt,
    }
}

/// `value` in postcard after its length (u64 LE) and CRC-32 (u32 LE).
fn framed<T: Serialize>(value: &T) -> Vec<u8> {
    let mut out = Vec::from([0; FRAME]);
    out = postcard::to_extend(value, out).unwrap_or_default();
    let payload = out.len().saturating_sub(FRAME);
    let crc = crc32(out.get(FRAME..).unwrap_or_default());
    if let Some(h) = out.get_mut(..FRAME) {
        h.copy_from_slice(&frame_of(payload, crc));
    }
    out
}

/// The length of a knowledge base's base (header, core and sweep sections, without the
/// additions after it), or None when `bytes` do not start with a knowledge-base header.
pub fn base_len(bytes: &[u8]) -> Option<usize> {
    if bytes.len() < HEADER || bytes[..6] != MAGIC {
        return None;
    }
    Some(HEADER.saturating_add(u64_at(bytes, 10).min(usize::MAX as u64) as usize))
}

/// Why an addition of `addition` bytes should not be appended to the knowledge base `read`
/// but the whole state rewritten as a new base, or None when it may be appended: the
/// additions, this one included, must stay within half the base (beyond, replaying them would
/// slow every load more than one rewrite).
pub fn rewrite_instead(read: &[u8], addition: usize) -> Option<String> {
    let base = base_len(read)?;
    let additions = read.len().saturating_sub(base).saturating_add(addition);
    (additions > base / 2).then(|| {
        format!(
            "its additions would have been {:.1} MB, over half its {:.1} MB base",
            additions as f64 / 1e6,
            base as f64 / 1e6
        )
    })
}

/// `bytes` made to pass the header's, the sweep sections' and the additions' length and CRC
/// checks wherever their lengths fit: the whole input after the header is the base, the core
/// as long as the header says (at most what there is). For the fuzzer, so that mutations
/// reach the decoders and the state checks.
pub fn seal(bytes: &[u8]) -> Vec<u8> {
    let mut out = bytes.to_vec();
    if out.len() < HEADER {
        return out;
    }
    let base = out.len() - HEADER;
    out[10..18].copy_from_slice(&(base as u64).to_le_bytes());
    let core = (u64_at(&out, 18).min(base as u64)) as usize;
    out[18..26].copy_from_slice(&(core as u64).to_le_bytes());
    let crc = crc32(&out[HEADER..HEADER + core]);
    out[26..30].copy_from_slice(&crc.to_le_bytes());
    let mut at = HEADER + core;
    while out.len() - at >= FRAME {
        let len = (u64_at(&out, at).min((out.len() - at - FRAME) as u64)) as usize;
        let crc = crc32(&out[at + FRAME..at + FRAME + len]);
        out[at..at + FRAME].copy_from_slice(&frame_of(len, crc));
        at += FRAME + len;
    }
    out
}

fn u64_at(b: &[u8], i: usize) -> u64 {
    u64::from_le_bytes(core::array::from_fn(|k| b[i + k]))
}

fn u32_at(b: &[u8], i: usize) -> u32 {
    u32::from_le_bytes(core::array::from_fn(|k| b[i + k]))
}

/// A knowledge-base file as read: the core, where each location type's sweep section is
/// (header included, unchecked: [`read_section`] checks it), and the additions, in order.
pub(crate) struct Decoded {
    pub base: LearnerState,
    pub sweeps: Vec<Range<usize>>,
    pub additions: Vec<AdditionState>,
}

/// The file `bytes`: the header, the core and its CRC-32, the sweep sections' lengths (one
/// per location type, filling the base), and every addition with its CRC-32.
pub(crate) fn decode(bytes: &[u8]) -> Result<Decoded, KbError> {
    if bytes.len() < HEADER || bytes[..6] != MAGIC {
        return Err(KbError::Magic);
    }
    let version = u32_at(bytes, 6);
    if version != VERSION {
        return Err(KbError::Version { found: version });
    }
    let expected = base_len(bytes).unwrap_or(usize::MAX);
    let core = HEADER.saturating_add(u64_at(bytes, 18).min(usize::MAX as u64) as usize);
    if bytes.len() < expected || core > expected {
        return Err(KbError::Truncated {
            len: bytes.len(),
            expected: expected.max(core),
        });
    }
    let payload = &bytes[HEADER..core];
    let (found, stated) = (crc32(payload), u32_at(bytes, 26));
    if found != stated {
        return Err(KbError::Crc {
            found,
            expected: stated,
        });
    }
    let base: LearnerState =
        postcard::from_bytes(payload).map_err(|e| KbError::Decode(e.to_string()))?;
    let mut sweeps = Vec::with_capacity(base.location_kinds.len());
    let mut at = core;
    for name in &base.location_kinds {
        let cut = || KbError::Sweep {
            location_type: name.clone(),
            at,
            why: format!("does not fit in the base's {expected} bytes"),
        };
        if expected - at < FRAME {
            return Err(cut());
        }
        let len = u64_at(bytes, at).min(usize::MAX as u64) as usize;
        if len > expected - at - FRAME {
            return Err(cut());
        }
        sweeps.push(at..at + FRAME + len);
        at += FRAME + len;
    }
    if at != expected {
        return Err(KbError::Decode(format!(
            "{} bytes after the last sweep section, within the base",
            expected - at
        )));
    }
    let mut additions = Vec::new();
    while at < bytes.len() {
        let n = additions.len() + 1;
        let rest = &bytes[at..];
        let len = rest.len();
        let cut = |expected: usize| KbError::CutAddition {
            n,
            at,
            len,
            expected,
        };
        if len < FRAME {
            return Err(cut(FRAME));
        }
        let size = FRAME.saturating_add(u64_at(rest, 0).min(usize::MAX as u64) as usize);
        if len < size {
            return Err(cut(size));
        }
        let payload = &rest[FRAME..size];
        let (found, stated) = (crc32(payload), u32_at(rest, 8));
        let corrupt = |why: String| KbError::Addition { n, at, why };
        if found != stated {
            return Err(corrupt(format!(
                "CRC-32 {found:08x}, its header says {stated:08x}"
            )));
        }
        additions.push(postcard::from_bytes(payload).map_err(|e| corrupt(e.to_string()))?);
        at += size;
    }
    Ok(Decoded {
        base,
        sweeps,
        additions,
    })
}

/// The sweep of a section [`decode`] found (`framed`: its header and payload), its CRC-32
/// checked; the error says what is wrong with it. The CRC is computed beside the decoding
/// (on another core; 1.9 ms for the example cell's 15 MB Table), whose result is dropped
/// unless the CRC matches; decoding any bytes is safe (the fuzzer decodes sealed ones).
pub(crate) fn read_section(framed: &[u8]) -> Result<SweepState<'_>, String> {
    if framed.len() < FRAME {
        return Err("is cut short".into());
    }
    let payload = framed.get(FRAME..).unwrap_or_default();
    let (found, decoded) = rayon::join(|| crc32(payload), || postcard::from_bytes(payload));
    let stated = u32_at(framed, 8);
    if found != stated {
        return Err(format!(
            "is corrupt: CRC-32 {found:08x}, its header says {stated:08x}"
        ));
    }
    decoded.map_err(|e| format!("does not decode: {e}"))
}

/// The CRC-32 of the blob ([`prf_shared::blob::CRC32`], the same values), computed with
/// carry-less multiplication where the CPU has it (`crc32fast`): the example cell's 57 MB
/// knowledge base takes about 3 ms instead of 12 ms with 16-byte tables, and is read on every
/// `prf learn --add`. The firmware keeps the blob's byte-wise table.
fn crc32(data: &[u8]) -> u32 {
    crc32fast::hash(data)
}

#[cfg(test)]
mod tests {
    /// The file format states the blob's CRC-32: the 16-byte-a-step table gives its values.
    #[test]
    fn the_knowledge_base_crc_is_the_blobs() {
        let bytes: Vec<u8> = (0..100_003u32)
            .map(|i| (i.wrapping_mul(2_654_435_761) >> 13) as u8)
            .collect();
        for n in [0, 1, 15, 16, 17, 1000, bytes.len()] {
            assert_eq!(
                super::crc32(&bytes[..n]),
                prf_shared::blob::crc32(&bytes[..n]),
                "{n} bytes"
            );
        }
        // The check value of CRC-32/ISO-HDLC.
        assert_eq!(super::crc32(b"123456789"), 0xcbf4_3926);
    }

    /// The record `prf learn --add` appends in parts is the framed encoding of the addition
    /// that loading decodes.
    #[test]
    fn an_addition_in_parts_is_the_additions_encoding() {
        use super::*;
        use crate::workspace::PathSphere;
        let spheres = (0..1000)
            .map(|i| PathSphere {
                centre: Vector3::new(i as f64 * 1e-3, -0.5, 1.0 / (1.0 + i as f64)),
                sphere: (i % 7) as u8,
            })
            .collect::<Vec<_>>();
        let lesson = LessonState {
            class: "reach".into(),
            location_type: Some(1),
            part_type: 0,
            affordance: Some((2, [0.1, 0.2, 0.3, 1.0, 0.0, 0.0, 0.0])),
            sweep: Some(PathSpheres(std::sync::Arc::new(SweptPath::new(&spheres)))),
            arm: None,
        };
        let state = AdditionState {
            lessons: vec![LessonsState {
                demonstration: "d063".into(),
                fingerprint: 0x1234_5678,
                lessons: vec![lesson.clone(), lesson],
            }],
            rebuilt: vec![(
                1,
                None,
                Some(SplatState {
                    origin: [0.0, -1.0, 0.5],
                    dims: [4, 4, 4],
                    grid: [0.05; 3],
                    value: (0..64).map(|i| i as f64 * 0.01).collect(),
                    feature: (0..64)
                        .map(|i| if i % 3 == 0 { u32::MAX } else { i })
                        .collect(),
                    done: 64,
                }),
            )],
        };
        let parts = encode_addition(encode_lessons(&state.lessons), &state.rebuilt);
        // Both lessons' spheres are written from their path, not copied.
        let kept = parts.lessons.0.iter();
        assert_eq!(kept.filter(|p| matches!(p, Piece::Spheres(_))).count(), 2);
        assert_eq!(parts.to_vec(), framed(&state));
        assert_eq!(parts.len(), framed(&state).len());
        let payload = &parts.to_vec()[FRAME..];
        assert_eq!(postcard::from_bytes::<AdditionState>(payload), Ok(state));
    }
}
