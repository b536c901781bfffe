//! The blob compiler: Learn's output → header + postcard payload ([`prf_shared::blob`]).

use crate::learn::Knowledge;
use anyhow::{Context, bail};
use prf_shared::JointVector;
use prf_shared::blob::{
    self, ClassData, LocationTypeData, MAX_AFFORDANCES, PartTypeData, Payload, RDMP_COORDS,
    RdmpData, RobotData, SkillData, Table,
};
use prf_shared::kinematics::ArmKinematics;
use prf_shared::motion::CLASSES;
use prf_shared::se3::{Pose, pose_to_array};
use serde::Serialize;

/// Offsets and data of a [`Table`] of records.
#[derive(Default)]
struct OwnedTable {
    offsets: Vec<u8>,
    data: Vec<u8>,
}

impl OwnedTable {
    fn of<T: Serialize>(records: &[T]) -> anyhow::Result<Self> {
        let mut t = OwnedTable::default();
        for r in records {
            t.offsets
                .extend_from_slice(&(t.data.len() as u32).to_le_bytes());
            t.data
                .extend(postcard::to_allocvec(r).context("encoding a blob record")?);
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

fn poses(p: &[Pose], what: &str) -> anyhow::Result<heapless::Vec<[f64; 7], MAX_AFFORDANCES>> {
    if p.len() > MAX_AFFORDANCES {
        bail!(
            "{} {what} learned, the blob holds at most {MAX_AFFORDANCES}",
            p.len()
        );
    }
    Ok(p.iter().map(pose_to_array).collect())
}

/// Compiles learned knowledge into blob bytes.
pub fn compile(k: &Knowledge) -> anyhow::Result<Vec<u8>> {
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
                stances: poses(&l.stances.poses, &format!("stances of {}", l.name))?,
                workspace: l.field.as_ref().map(|f| f.data()),
            })
        })
        .collect::<anyhow::Result<Vec<_>>>()?;
    let part_types = k
        .part_types
        .iter()
        .map(|p| {
            Ok(PartTypeData {
                name: &p.name,
                grasps: poses(&p.grasps.poses, &format!("grasps of {}", p.name))?,
            })
        })
        .collect::<anyhow::Result<Vec<_>>>()?;
    let mut weights: Vec<Vec<u8>> = k
        .arms
        .iter()
        .map(|a| vec![0u8; RDMP_COORDS * a.rdmp.position.params.n_basis * 4])
        .collect();
    let rdmps = k
        .arms
        .iter()
        .zip(weights.iter_mut())
        .map(|(a, w)| {
            let end = a.path.last().copied().unwrap_or(k.robot.home);
            let goal = ArmKinematics::new(&k.robot, &JointVector::from(end)).tcp;
            RdmpData::encode(&a.rdmp, &goal, w).context("RDMP encoding")
        })
        .collect::<anyhow::Result<Vec<_>>>()?;
    let skills = k
        .skills
        .iter()
        .map(|s| {
            let small = |v: Option<usize>, max: usize| -> anyhow::Result<Option<_>> {
                v.map(|i| {
                    if i < max {
                        Ok(i)
                    } else {
                        bail!("index {i} too large for the blob")
                    }
                })
                .transpose()
            };
            Ok(SkillData {
                class: CLASSES
                    .iter()
                    .position(|c| c.name() == s.class)
                    .context("skill of an unknown class")? as u8,
                rdmp: small(s.rdmp, u16::MAX as usize)?.map(|i| i as u16),
                location_type: small(s.location_type, 255)?.map(|i| i as u8),
                part_type: small(s.part_type, 255)?.map(|i| i as u8),
                demo: &s.demo,
                shared: s.shared,
            })
        })
        .collect::<anyhow::Result<Vec<_>>>()?;
    let tables = [
        OwnedTable::of(&classes)?,
        OwnedTable::of(&location_types)?,
        OwnedTable::of(&part_types)?,
        OwnedTable::of(&rdmps)?,
        OwnedTable::of(&skills)?,
    ];
    let payload = Payload {
        description: &k.description,
        clearance_demo: k.config.clearance_demo,
        clearance_acceptable: k.config.clearance_acceptable,
        robot: RobotData::from_model(&k.robot),
        classes: tables[0].table(),
        location_types: tables[1].table(),
        part_types: tables[2].table(),
        rdmps: tables[3].table(),
        skills: tables[4].table(),
    };
    let body = postcard::to_allocvec(&payload).context("encoding the blob payload")?;
    let mut bytes = blob::header(&body).to_vec();
    bytes.extend(body);
    Ok(bytes)
}
