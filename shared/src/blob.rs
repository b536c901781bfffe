//! The compiled knowledge base ("blob"): header + postcard payload, read in place.
//!
//! Header (24 bytes, little endian): magic `PRFBLOB\0`, format version u32, payload length
//! u32, CRC-32 (IEEE) of the payload u32, reserved u32 (0). The payload is one postcard
//! [`Payload`]; its lists are [`Table`]s of individually encoded records with an offset
//! index, and large arrays (field nodes, RDMP weights, poses) are borrowed byte slices, so
//! a blob in flash is used where it lies: only the record being read is decoded.

use crate::NA;
use crate::dmp::{DmpParams, MAX_BASES};
use crate::field::{Field, FieldData, FieldError};
use crate::motion::ActionTemplate;
use crate::rdmp::Rdmp;
use crate::robot::{Joint, MAX_SPHERES, ModelError, PlatformBox, RobotModel, Sphere};
use crate::se3::{Pose, pose_from_array};
use nalgebra::{Unit, Vector3};
use serde::{Deserialize, Serialize};

/// Magic at the start of every blob.
pub const MAGIC: [u8; 8] = *b"PRFBLOB\0";
/// Format version this build reads and writes.
pub const VERSION: u32 = 4;
/// Header bytes: magic (8), version (4), payload length (4), CRC-32 (4), reserved (4).
pub const HEADER_LEN: usize = 24;
/// Maximum affordances (stances of a location type, grasps of a part type).
pub const MAX_AFFORDANCES: usize = 16;
/// DMP coordinates of an RDMP: position 3, rotation 3, γ 1.
pub const RDMP_COORDS: usize = 7;

/// Why a blob was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BlobError {
    /// Fewer bytes than the header, or than the header says.
    Truncated {
        /// Bytes the header needs.
        needed: usize,
        /// Bytes there are.
        got: usize,
    },
    /// The blob does not start with [`MAGIC`].
    BadMagic,
    /// Written by a newer (or unknown) format version.
    Version {
        /// Format version in the header.
        found: u32,
        /// The version this build reads.
        supported: u32,
    },
    /// More bytes than the header says.
    TrailingBytes {
        /// Payload length in the header.
        declared: usize,
        /// Payload bytes present.
        got: usize,
    },
    /// The payload's CRC-32 differs from the header's.
    Checksum {
        /// CRC-32 in the header.
        expected: u32,
        /// CRC-32 of the payload.
        found: u32,
    },
    /// The payload or a record does not decode.
    Decode {
        /// The section of the record.
        section: Section,
        /// Index of the record in its section.
        index: usize,
    },
    /// The robot model is invalid.
    Model(ModelError),
    /// A workspace field is malformed.
    Field {
        /// Index of the location type.
        location_type: usize,
        /// What is wrong with its workspace.
        error: FieldError,
    },
    /// A skill names a class, RDMP, location or part type that does not exist, or an
    /// affordance pose is not a unit-quaternion pose.
    Reference {
        /// The section of the record.
        section: Section,
        /// Index of the record in its section.
        index: usize,
    },
}

impl core::fmt::Display for BlobError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            BlobError::Truncated { needed, got } => {
                write!(f, "truncated: {got} bytes, the header needs {needed}")
            }
            BlobError::BadMagic => write!(f, "not a PRF blob (bad magic)"),
            BlobError::Version { found, supported } => write!(
                f,
                "format version {found}, this build reads version {supported}"
            ),
            BlobError::TrailingBytes { declared, got } => {
                write!(f, "{got} bytes, the header declares {declared}")
            }
            BlobError::Checksum { expected, found } => write!(
                f,
                "corrupt: payload CRC-32 {found:08x}, header says {expected:08x}"
            ),
            BlobError::Decode { section, index } => {
                write!(f, "{section:?} record {index} does not decode")
            }
            BlobError::Model(e) => write!(f, "invalid robot model: {e}"),
            BlobError::Field {
                location_type,
                error,
            } => write!(f, "workspace of location type {location_type}: {error}"),
            BlobError::Reference { section, index } => {
                write!(f, "{section:?} record {index} refers to something missing")
            }
        }
    }
}

impl core::error::Error for BlobError {}

/// Sections of the payload, for error reports.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Section {
    /// The payload as a whole.
    Payload,
    /// The motion classes.
    Classes,
    /// The location types (stances, workspaces).
    LocationTypes,
    /// The part types (grasps).
    PartTypes,
    /// The RDMP skills.
    Rdmps,
    /// The skill table.
    Skills,
}

/// CRC-32/ISO-HDLC (IEEE 802.3: reflected, init and final xor 0xFFFFFFFF), the checksum of
/// blobs, task blocks and setpoint streams. A stream is checksummed piece by piece with
/// `CRC32.digest()`, `update`, `finalize`.
pub static CRC32: crc::Crc<u32> = crc::Crc::<u32>::new(&crc::CRC_32_ISO_HDLC);

/// The CRC-32 of `data`.
pub fn crc32(data: &[u8]) -> u32 {
    CRC32.checksum(data)
}

/// The header for a payload.
pub fn header(payload: &[u8]) -> [u8; HEADER_LEN] {
    let mut h = [0u8; HEADER_LEN];
    h[..8].copy_from_slice(&MAGIC);
    h[8..12].copy_from_slice(&VERSION.to_le_bytes());
    h[12..16].copy_from_slice(&(payload.len() as u32).to_le_bytes());
    h[16..20].copy_from_slice(&crc32(payload).to_le_bytes());
    h
}

/// A list of postcard records: `offsets` holds one u32 (LE) start per record into `data`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Table<'a> {
    /// Little-endian u32 offset of each record in `data`.
    #[serde(borrow)]
    pub offsets: &'a [u8],
    /// The records, postcard-encoded, back to back.
    #[serde(borrow)]
    pub data: &'a [u8],
}

impl<'a> Table<'a> {
    /// Number of records.
    pub fn len(&self) -> usize {
        self.offsets.len() / 4
    }

    /// True when the table has no record.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    fn range(&self, i: usize) -> Option<(usize, usize)> {
        let at = |k: usize| {
            let o = self.offsets.get(4 * k..4 * k + 4)?;
            Some(u32::from_le_bytes([o[0], o[1], o[2], o[3]]) as usize)
        };
        let start = at(i)?;
        let end = if i + 1 < self.len() {
            at(i + 1)?
        } else {
            self.data.len()
        };
        (start <= end && end <= self.data.len()).then_some((start, end))
    }

    /// Decodes record `i`.
    pub fn get<T: Deserialize<'a>>(&self, i: usize, section: Section) -> Result<T, BlobError> {
        let err = BlobError::Decode { section, index: i };
        let (s, e) = self.range(i).ok_or(err)?;
        postcard::from_bytes(&self.data[s..e]).map_err(|_| err)
    }
}

/// A revolute joint: origin pose [x, y, z, qw, qx, qy, qz], axis, limits (rad, rad/s).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct JointData {
    /// Joint frame in the parent link frame, [x, y, z, qw, qx, qy, qz].
    pub origin: [f64; 7],
    /// Rotation axis in the joint frame.
    pub axis: [f64; 3],
    /// Lower position limit, rad.
    pub lower: f64,
    /// Upper position limit, rad.
    pub upper: f64,
    /// Speed limit, rad/s.
    pub max_speed: f64,
}

/// A collision sphere as stored.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct SphereData {
    /// Frame index: 0 arm base, 1–7 links, 8 flange.
    pub link: u8,
    /// Centre in the link frame, m.
    pub centre: [f64; 3],
    /// Radius, m.
    pub radius: f64,
}

/// The robot model as compiled from URDF + sphere file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RobotData {
    /// Arm base in the platform frame, [x, y, z, qw, qx, qy, qz].
    pub mount: [f64; 7],
    /// The seven arm joints.
    pub joints: [JointData; NA],
    /// Flange in the frame of link 7.
    pub flange: [f64; 7],
    /// TCP in the flange frame.
    pub tcp: [f64; 7],
    /// Collision spheres.
    pub spheres: heapless::Vec<SphereData, MAX_SPHERES>,
    /// Platform box centre in the base frame, m.
    pub platform_centre: [f64; 3],
    /// Platform box half extents, m.
    pub platform_half: [f64; 3],
    /// Home configuration q_a,H, rad.
    pub home: [f64; NA],
    /// How far at least every sphere reaches beyond its link's surface, m.
    pub sphere_margin: f64,
}

impl RobotData {
    /// The record of a robot model.
    pub fn from_model(m: &RobotModel) -> Self {
        use crate::se3::pose_to_array as arr;
        RobotData {
            mount: arr(&m.mount),
            joints: m.joints.map(|j| JointData {
                origin: arr(&j.origin),
                axis: j.axis.into_inner().into(),
                lower: j.lower,
                upper: j.upper,
                max_speed: j.max_speed,
            }),
            flange: arr(&m.flange),
            tcp: arr(&m.tcp),
            spheres: m
                .spheres
                .iter()
                .map(|s| SphereData {
                    link: s.link,
                    centre: s.centre.into(),
                    radius: s.radius,
                })
                .collect(),
            platform_centre: m.platform.centre.into(),
            platform_half: m.platform.half_extents.into(),
            home: m.home,
            sphere_margin: m.sphere_margin,
        }
    }

    /// The model, validated.
    pub fn to_model(&self) -> Result<RobotModel, BlobError> {
        let pose = |a: [f64; 7]| pose_from_array(a).ok_or(BlobError::Model(ModelError::Transform));
        let mut joints = [Joint::unset(); NA];
        for (i, (j, d)) in joints.iter_mut().zip(&self.joints).enumerate() {
            let bad = BlobError::Model(ModelError::Joint { joint: i });
            let axis = Vector3::from(d.axis);
            if !(axis.norm() > 0.5 && axis.iter().all(|v| v.is_finite())) {
                return Err(bad);
            }
            *j = Joint {
                origin: pose_from_array(d.origin).ok_or(bad)?,
                axis: Unit::new_normalize(axis),
                lower: d.lower,
                upper: d.upper,
                max_speed: d.max_speed,
            };
        }
        let m = RobotModel {
            mount: pose(self.mount)?,
            joints,
            flange: pose(self.flange)?,
            tcp: pose(self.tcp)?,
            spheres: self
                .spheres
                .iter()
                .map(|s| Sphere {
                    link: s.link,
                    centre: Vector3::from(s.centre),
                    radius: s.radius,
                })
                .collect(),
            platform: PlatformBox {
                centre: Vector3::from(self.platform_centre),
                half_extents: Vector3::from(self.platform_half),
            },
            home: self.home,
            sphere_margin: self.sphere_margin,
        };
        m.validate().map_err(BlobError::Model)?;
        Ok(m)
    }
}

/// A motion class as stored: its name (the code's [`crate::motion::CLASSES`] entry that
/// provides segment, π, Y, G, Φ_x) and its action template.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ClassData<'a> {
    /// Class name (Pick, Place, Move).
    pub name: &'a str,
    /// Its action template α (head, parameters, pre, eff).
    pub action: ActionTemplate,
}

/// A location type: its stances T_b^ℓ and its workspace Ω+ (if any was learned).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct LocationTypeData<'a> {
    /// Location type name.
    pub name: &'a str,
    /// Learned stances T_b^ℓ, location frame, [x, y, z, qw, qx, qy, qz].
    pub stances: heapless::Vec<[f64; 7], MAX_AFFORDANCES>,
    /// The workspace Ω+ as a distance field (None: never demonstrated).
    #[serde(borrow)]
    pub workspace: Option<FieldData<'a>>,
}

/// A part type and its grasps T_e^p.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PartTypeData<'a> {
    /// Part type name.
    pub name: &'a str,
    /// Learned grasps T_e^p, part frame, [x, y, z, qw, qx, qy, qz].
    pub grasps: heapless::Vec<[f64; 7], MAX_AFFORDANCES>,
}

/// A trained RDMP: shared DMP parameters, durations and goal data as f64, forcing weights
/// as f32 (little endian, [`RDMP_COORDS`] × n_basis: position x y z, rotation x y z, γ).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RdmpData<'a> {
    /// Number of Gaussian bases n_g.
    pub n_basis: u8,
    /// Spring gain α_z (Eq. 4).
    pub alpha_z: f64,
    /// Damper gain β_z (Eq. 4).
    pub beta_z: f64,
    /// Phase decay α_ζ (Eq. 5).
    pub alpha_zeta: f64,
    /// Smallest amplitude the forcing term is scaled by.
    pub min_amplitude: f64,
    /// Duration τ of the demonstration, s.
    pub tau: f64,
    /// Bit c set: coordinate c's forcing term is scaled by its amplitude (Eq. 3).
    pub scaled: u8,
    /// Demonstrated travel of the position DMP (goal − start), m.
    pub travel: [f64; 3],
    /// γ at the goal (the null-space coordinate, Alg. 1).
    pub gamma_goal: f64,
    /// The demonstrated TCP goal (arm base frame, [x, y, z, qw, qx, qy, qz]): the planner
    /// tries skills whose demonstrated goal is nearest a new goal first.
    pub goal: [f64; 7],
    /// Forcing weights, f32 little-endian, coordinate by coordinate.
    #[serde(borrow)]
    pub weights: &'a [u8],
}

impl<'a> RdmpData<'a> {
    /// Compact form of a trained RDMP demonstrated towards `goal`; `weights` receives the
    /// f32 bytes to borrow.
    pub fn encode(r: &Rdmp, goal: &Pose, weights: &'a mut [u8]) -> Option<Self> {
        let p = r.position.params;
        let n = p.n_basis;
        if weights.len() != RDMP_COORDS * n * 4 {
            return None;
        }
        let mut scaled = 0u8;
        let mut put = |c: usize, w: &[f64; MAX_BASES], s: bool| {
            for i in 0..n {
                let at = (c * n + i) * 4;
                weights[at..at + 4].copy_from_slice(&(w[i] as f32).to_le_bytes());
            }
            if s {
                scaled |= 1 << c;
            }
        };
        for c in 0..3 {
            put(
                c,
                &r.position.forcing.weights[c],
                r.position.forcing.scaled[c],
            );
            put(
                3 + c,
                &r.rotation.forcing.weights[c],
                r.rotation.forcing.scaled[c],
            );
        }
        put(6, &r.gamma.forcing.weights[0], r.gamma.forcing.scaled[0]);
        Some(RdmpData {
            n_basis: n as u8,
            alpha_z: p.alpha_z,
            beta_z: p.beta_z,
            alpha_zeta: p.alpha_zeta,
            min_amplitude: p.min_amplitude,
            tau: r.position.tau,
            scaled,
            travel: r.rotation.travel.into(),
            gamma_goal: r.gamma_goal,
            goal: crate::se3::pose_to_array(goal),
            weights: &weights[..],
        })
    }

    /// The working RDMP (one skill's weights widened to f64 while it is used).
    pub fn decode(&self) -> Option<Rdmp> {
        let mut r = Rdmp::empty();
        self.decode_into(&mut r).then_some(r)
    }

    /// [`RdmpData::decode`] into `out`, in one pass over the weights and without moving the
    /// (3 KB) RDMP: what a controller tick can afford. False (with `out` unusable) if the
    /// record is invalid.
    pub fn decode_into(&self, out: &mut Rdmp) -> bool {
        let n = self.n_basis as usize;
        let finite = [
            self.alpha_z,
            self.beta_z,
            self.alpha_zeta,
            self.tau,
            self.gamma_goal,
        ]
        .iter()
        .chain(&self.travel)
        .all(|v| v.is_finite());
        if !(2..=MAX_BASES).contains(&n)
            || self.weights.len() != RDMP_COORDS * n * 4
            || !finite
            || !(self.tau > 0.0)
        {
            return false;
        }
        let params = DmpParams {
            n_basis: n,
            alpha_z: self.alpha_z,
            beta_z: self.beta_z,
            alpha_zeta: self.alpha_zeta,
            min_amplitude: self.min_amplitude,
            ridge: 0.0,
        };
        let (p, r, g) = (&mut out.position, &mut out.rotation, &mut out.gamma);
        let mut all_finite = true;
        for (c, bytes) in self.weights.chunks_exact(4 * n).enumerate() {
            let (weights, scaled) = match c {
                0..3 => (&mut p.forcing.weights[c], &mut p.forcing.scaled[c]),
                3..6 => (&mut r.forcing.weights[c - 3], &mut r.forcing.scaled[c - 3]),
                _ => (&mut g.forcing.weights[0], &mut g.forcing.scaled[0]),
            };
            for (w, b) in weights.iter_mut().zip(bytes.chunks_exact(4)) {
                *w = f32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64;
                all_finite &= w.is_finite();
            }
            weights[n..].fill(0.0);
            *scaled = self.scaled & (1 << c) != 0;
        }
        (p.params, p.tau) = (params, self.tau);
        (r.params, r.tau, r.travel) = (params, self.tau, Vector3::from(self.travel));
        (g.params, g.tau) = (params, self.tau);
        out.gamma_goal = self.gamma_goal;
        out.gamma_shift = 0.0;
        all_finite
    }
}

/// A skill κ = (m, π): its class and, for classes with a learnable generator, its RDMP.
/// `location_type`, `part_type` and `demo` say where it was learned (for reports); `shared`
/// marks a copy made by share().
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SkillData<'a> {
    /// Index of the skill's motion class.
    pub class: u8,
    /// Index of its RDMP (None: a fixed generator such as BaseMove).
    pub rdmp: Option<u16>,
    /// Location type it was learned at.
    pub location_type: Option<u8>,
    /// Part type it was learned with.
    pub part_type: Option<u8>,
    /// Id of the demonstration it came from.
    pub demo: &'a str,
    /// Added by share() from another class.
    pub shared: bool,
}

/// The payload.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Payload<'a> {
    /// Free text about the cell (from the dataset).
    pub description: &'a str,
    /// Clearances the workspaces were learned with: demonstrations r_d and acceptable r, m.
    pub clearance_demo: f64,
    /// Acceptable clearance r, m.
    pub clearance_acceptable: f64,
    /// The robot model.
    pub robot: RobotData,
    /// Motion classes ([`ClassData`]).
    #[serde(borrow)]
    pub classes: Table<'a>,
    /// Location types ([`LocationTypeData`]).
    #[serde(borrow)]
    pub location_types: Table<'a>,
    /// Part types ([`PartTypeData`]).
    #[serde(borrow)]
    pub part_types: Table<'a>,
    /// RDMP skills ([`RdmpData`]).
    #[serde(borrow)]
    pub rdmps: Table<'a>,
    /// Skill table ([`SkillData`]).
    #[serde(borrow)]
    pub skills: Table<'a>,
}

/// A validated blob: every record decodes, every reference resolves, every field is valid.
#[derive(Clone, Debug)]
pub struct Blob<'a> {
    /// The validated payload; records decode on access.
    pub payload: Payload<'a>,
}

impl<'a> Blob<'a> {
    /// Checks header, version, length and CRC, decodes the payload and validates every
    /// record once, so later accesses cannot find anything malformed.
    /// The whole length (header + payload) the header at the start of `region` declares,
    /// after checking its magic and version: how much of a larger region (the flash region
    /// the blob was written to) is the blob.
    pub fn stored_len(region: &[u8]) -> Result<usize, BlobError> {
        if region.len() < HEADER_LEN {
            return Err(BlobError::Truncated {
                needed: HEADER_LEN,
                got: region.len(),
            });
        }
        if region[..8] != MAGIC {
            return Err(BlobError::BadMagic);
        }
        let u32_at =
            |i: usize| u32::from_le_bytes([region[i], region[i + 1], region[i + 2], region[i + 3]]);
        let version = u32_at(8);
        if version != VERSION {
            return Err(BlobError::Version {
                found: version,
                supported: VERSION,
            });
        }
        Ok(HEADER_LEN.saturating_add(u32_at(12) as usize))
    }

    /// Validates header, version, length, CRC-32 and every record; borrows `bytes`.
    pub fn parse(bytes: &'a [u8]) -> Result<Self, BlobError> {
        let total = Self::stored_len(bytes)?;
        let u32_at =
            |i: usize| u32::from_le_bytes([bytes[i], bytes[i + 1], bytes[i + 2], bytes[i + 3]]);
        if bytes.len() < total {
            return Err(BlobError::Truncated {
                needed: total,
                got: bytes.len(),
            });
        }
        if bytes.len() > total {
            return Err(BlobError::TrailingBytes {
                declared: total,
                got: bytes.len(),
            });
        }
        let payload = &bytes[HEADER_LEN..];
        let (expected, found) = (u32_at(16), crc32(payload));
        if expected != found {
            return Err(BlobError::Checksum { expected, found });
        }
        let payload: Payload<'a> =
            postcard::from_bytes(payload).map_err(|_| BlobError::Decode {
                section: Section::Payload,
                index: 0,
            })?;
        let blob = Blob { payload };
        blob.validate()?;
        Ok(blob)
    }

    fn validate(&self) -> Result<(), BlobError> {
        let p = &self.payload;
        p.robot.to_model()?;
        for i in 0..p.classes.len() {
            let c = self.class(i)?;
            if crate::motion::class(c.name).is_none() || !c.action.is_well_formed() {
                return Err(BlobError::Reference {
                    section: Section::Classes,
                    index: i,
                });
            }
        }
        for i in 0..p.location_types.len() {
            let l = self.location_type(i)?;
            check_poses(&l.stances, Section::LocationTypes, i)?;
            if let Some(f) = &l.workspace {
                Field::new(f).map_err(|error| BlobError::Field {
                    location_type: i,
                    error,
                })?;
            }
        }
        for i in 0..p.part_types.len() {
            check_poses(&self.part_type(i)?.grasps, Section::PartTypes, i)?;
        }
        for i in 0..p.rdmps.len() {
            self.rdmp(i)?;
            self.rdmp_goal(i)?;
        }
        for i in 0..p.skills.len() {
            let s = self.skill(i)?;
            let bad = BlobError::Reference {
                section: Section::Skills,
                index: i,
            };
            let ok = (s.class as usize) < p.classes.len()
                && s.rdmp.is_none_or(|r| (r as usize) < p.rdmps.len())
                && s.location_type
                    .is_none_or(|l| (l as usize) < p.location_types.len())
                && s.part_type
                    .is_none_or(|t| (t as usize) < p.part_types.len());
            if !ok {
                return Err(bad);
            }
        }
        Ok(())
    }

    /// The robot model.
    pub fn robot(&self) -> Result<RobotModel, BlobError> {
        self.payload.robot.to_model()
    }

    /// Motion class `i`.
    pub fn class(&self, i: usize) -> Result<ClassData<'a>, BlobError> {
        self.payload.classes.get(i, Section::Classes)
    }

    /// Location type `i`.
    pub fn location_type(&self, i: usize) -> Result<LocationTypeData<'a>, BlobError> {
        self.payload.location_types.get(i, Section::LocationTypes)
    }

    /// Part type `i`.
    pub fn part_type(&self, i: usize) -> Result<PartTypeData<'a>, BlobError> {
        self.payload.part_types.get(i, Section::PartTypes)
    }

    /// The demonstrated TCP goal of RDMP `i` (arm base frame).
    pub fn rdmp_goal(&self, i: usize) -> Result<Pose, BlobError> {
        let d: RdmpData<'a> = self.payload.rdmps.get(i, Section::Rdmps)?;
        crate::se3::pose_from_array(d.goal).ok_or(BlobError::Decode {
            section: Section::Rdmps,
            index: i,
        })
    }

    /// RDMP `i`, decoded into its working form.
    pub fn rdmp(&self, i: usize) -> Result<Rdmp, BlobError> {
        let mut r = Rdmp::empty();
        self.rdmp_into(i, &mut r)?;
        Ok(r)
    }

    /// [`Blob::rdmp`] into `out` ([`RdmpData::decode_into`]).
    pub fn rdmp_into(&self, i: usize, out: &mut Rdmp) -> Result<(), BlobError> {
        let d: RdmpData<'a> = self.payload.rdmps.get(i, Section::Rdmps)?;
        if d.decode_into(out) {
            Ok(())
        } else {
            Err(BlobError::Decode {
                section: Section::Rdmps,
                index: i,
            })
        }
    }

    /// Skill `i`.
    pub fn skill(&self, i: usize) -> Result<SkillData<'a>, BlobError> {
        self.payload.skills.get(i, Section::Skills)
    }

    /// Index of the location type called `name`.
    pub fn location_type_index(&self, name: &str) -> Option<usize> {
        (0..self.payload.location_types.len())
            .find(|&i| self.location_type(i).is_ok_and(|l| l.name == name))
    }

    /// Index of the part type called `name`.
    pub fn part_type_index(&self, name: &str) -> Option<usize> {
        (0..self.payload.part_types.len())
            .find(|&i| self.part_type(i).is_ok_and(|p| p.name == name))
    }
}

fn check_poses(poses: &[[f64; 7]], section: Section, index: usize) -> Result<(), BlobError> {
    let ok = poses.iter().all(|p| {
        let q = crate::float::sqrt(p[3] * p[3] + p[4] * p[4] + p[5] * p[5] + p[6] * p[6]);
        p.iter().all(|v| v.is_finite()) && f64::abs(q - 1.0) < 1e-6
    });
    if ok {
        Ok(())
    } else {
        Err(BlobError::Reference { section, index })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crc32_matches_the_check_value_whole_and_piecewise() {
        // The check value of CRC-32/ISO-HDLC.
        assert_eq!(crc32(b"123456789"), 0xCBF4_3926);
        let mut digest = CRC32.digest();
        for piece in [&b"1234"[..], b"", b"56789"] {
            digest.update(piece);
        }
        let piecewise = digest.finalize();
        assert_eq!(piecewise, 0xCBF4_3926);
    }

    /// Against a bit-by-bit reference of the polynomial, on bytes of every value and length.
    #[test]
    fn crc32_matches_a_bitwise_reference() {
        fn bitwise(data: &[u8]) -> u32 {
            let mut c = 0xFFFF_FFFFu32;
            for &b in data {
                c ^= b as u32;
                for _ in 0..8 {
                    c = if c & 1 != 0 {
                        (c >> 1) ^ 0xEDB8_8320
                    } else {
                        c >> 1
                    };
                }
            }
            !c
        }
        let data: [u8; 600] = core::array::from_fn(|i| (i * 7 + i / 256) as u8);
        for n in [0, 1, 2, 3, 255, 256, 257, 600] {
            assert_eq!(crc32(&data[..n]), bitwise(&data[..n]), "{n} bytes");
        }
    }
}
