//! The blob compiler: Learn's output → header + postcard payload ([`prf_shared::blob`]).

use crate::learn::Knowledge;
use prf_shared::JointVector;
use prf_shared::blob::{
    self, ClassData, LocationTypeData, MAX_AFFORDANCES, PartTypeData, Payload, RDMP_COORDS,
    RdmpData, RobotData, SkillData, Table,
};
use prf_shared::kinematics::ArmKinematics;
use prf_shared::motion::CLASSES;
use prf_shared::se3::{Pose, pose_to_array};
use serde::Serialize;

/// Why learned knowledge does not fit the blob.
#[derive(Debug, thiserror::Error)]
pub enum CompileError {
    #[error("encoding {what} for the blob")]
    Encode {
        what: &'static str,
        #[source]
        source: postcard::Error,
    },
    #[error("arm skill {index}: its RDMP does not fit the blob's RDMP record")]
    Rdmp { index: usize },
    #[error("{count} {what} learned, the blob holds at most {max}")]
    TooMany {
        what: String,
        count: usize,
        max: usize,
    },
    #[error("skill {skill} of class {class}: an index ({index}) too large for the blob")]
    Index {
        skill: usize,
        class: &'static str,
        index: usize,
    },
    #[error("skill {skill} has class {class}, which the runtime does not know")]
    UnknownClass { skill: usize, class: &'static str },
}

/// Offsets and data of a [`Table`] of records.
#[derive(Default)]
struct OwnedTable {
    offsets: Vec<u8>,
    data: Vec<u8>,
}

impl OwnedTable {
    fn of<T: Serialize>(records: &[T]) -> Result<Self, CompileError> {
        let mut t = OwnedTable::default();
        for r in records {
            t.offsets
                .extend_from_slice(&(t.data.len() as u32).to_le_bytes());
            t.data.extend(
                postcard::to_allocvec(r).map_err(|source| CompileError::Encode {
                    what: "a record",
                    source,
                })?,
            );
        }
        Ok(t)
    }

    fn table(&self) -> Table<'_> {
        Table {
            offsets: &self.offsets,
            data: &self.data,
        }
    }
}

fn poses(
    p: &[Pose],
    what: String,
) -> Result<heapless::Vec<[f64; 7], MAX_AFFORDANCES>, CompileError> {
    if p.len() > MAX_AFFORDANCES {
        return Err(CompileError::TooMany {
            what,
            count: p.len(),
            max: MAX_AFFORDANCES,
        });
    }
    Ok(p.iter().map(pose_to_array).collect())
}

/// Compiles learned knowledge into blob bytes.
pub fn compile(k: &Knowledge) -> Result<Vec<u8>, CompileError> {
    let classes: Vec<ClassData> = CLASSES
        .iter()
        .map(|c| ClassData {
            name: c.name(),
            action: c.action(),
        })
        .collect();
    let location_types = k
        .location_types
        .iter()
        .map(|l| {
            Ok(LocationTypeData {
                name: &l.name,
                stances: poses(&l.stances.poses, format!("stances of {}", l.name))?,
                workspace: l.field.as_ref().map(|f| f.data()),
            })
        })
        .collect::<Result<Vec<_>, CompileError>>()?;
    let part_types = k
        .part_types
        .iter()
        .map(|p| {
            Ok(PartTypeData {
                name: &p.name,
                grasps: poses(&p.grasps.poses, format!("grasps of {}", p.name))?,
            })
        })
        .collect::<Result<Vec<_>, CompileError>>()?;
    let mut weights: Vec<Vec<u8>> = k
        .arms
        .iter()
        .map(|a| vec![0u8; RDMP_COORDS * a.rdmp.position.params.n_basis * 4])
        .collect();
    let rdmps = k
        .arms
        .iter()
        .zip(weights.iter_mut())
        .enumerate()
        .map(|(index, (a, w))| {
            let end = a.path.last().copied().unwrap_or(k.robot.home);
            let goal = ArmKinematics::new(&k.robot, &JointVector::from(end)).tcp;
            RdmpData::encode(&a.rdmp, &goal, w).ok_or(CompileError::Rdmp { index })
        })
        .collect::<Result<Vec<_>, CompileError>>()?;
    let skills = k
        .skills
        .iter()
        .enumerate()
        .map(|(skill, s)| {
            let small = |v: Option<usize>, max: usize| -> Result<Option<_>, CompileError> {
                v.map(|index| {
                    if index < max {
                        Ok(index)
                    } else {
                        Err(CompileError::Index {
                            skill,
                            class: s.class,
                            index,
                        })
                    }
                })
                .transpose()
            };
            Ok(SkillData {
                class: CLASSES.iter().position(|c| c.name() == s.class).ok_or(
                    CompileError::UnknownClass {
                        skill,
                        class: s.class,
                    },
                )? as u8,
                rdmp: small(s.rdmp, u16::MAX as usize)?.map(|i| i as u16),
                location_type: small(s.location_type, 255)?.map(|i| i as u8),
                part_type: small(s.part_type, 255)?.map(|i| i as u8),
                demo: &s.demo,
                shared: s.shared,
            })
        })
        .collect::<Result<Vec<_>, CompileError>>()?;
    let tables = [
        OwnedTable::of(&classes)?,
        OwnedTable::of(&location_types)?,
        OwnedTable::of(&part_types)?,
        OwnedTable::of(&rdmps)?,
        OwnedTable::of(&skills)?,
    ];
    let payload = Payload {
        description: &k.description,
        clearance_demo: k.clearance_demo,
        clearance_acceptable: k.config.clearance_acceptable,
        robot: RobotData::from_model(&k.robot),
        classes: tables[0].table(),
        location_types: tables[1].table(),
        part_types: tables[2].table(),
        rdmps: tables[3].table(),
        skills: tables[4].table(),
    };
    let body = postcard::to_allocvec(&payload).map_err(|source| CompileError::Encode {
        what: "the payload",
        source,
    })?;
    let mut bytes = blob::header(&body).to_vec();
    bytes.extend(body);
    Ok(bytes)
}
