//! The blob compiler: Learn's output → header + postcard payload ([`prf_shared::blob`]),
//! and the report of a blob's contents shared by `prf learn` and `prf inspect`.

use crate::learn::Knowledge;
use anyhow::{Context, bail};
use prf_shared::JointVector;
use prf_shared::blob::{
    self, Blob, ClassData, LocationTypeData, MAX_AFFORDANCES, PartTypeData, Payload, RDMP_COORDS,
    RdmpData, RobotData, SkillData, Table,
};
use prf_shared::field::Field;
use prf_shared::kinematics::ArmKinematics;
use prf_shared::motion::CLASSES;
use prf_shared::se3::{Pose, pose_to_array};
use serde::Serialize;
use std::fmt::Write;

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

fn kib(b: usize) -> String {
    format!("{:.1} KiB", b as f64 / 1024.0)
}

/// A validated blob's contents and sizes, as `prf inspect` prints them.
pub fn report(bytes: &[u8]) -> anyhow::Result<String> {
    let blob = Blob::parse(bytes).map_err(|e| anyhow::anyhow!("invalid blob: {e}"))?;
    let p = &blob.payload;
    let robot = blob.robot().map_err(|e| anyhow::anyhow!("{e:?}"))?;
    let mut o = String::new();
    let table_bytes = |t: &Table| t.offsets.len() + t.data.len();
    writeln!(
        o,
        "blob: format v{}, {} ({} bytes), CRC-32 ok",
        blob::VERSION,
        kib(bytes.len()),
        bytes.len()
    )?;
    if !p.description.is_empty() {
        writeln!(o, "cell: {}", p.description)?;
    }
    writeln!(
        o,
        "robot: 7-axis arm, {} collision spheres; clearances r_d = {} mm, r = {} mm (ε = {} mm)",
        robot.spheres.len(),
        p.clearance_demo * 1e3,
        p.clearance_acceptable * 1e3,
        ((p.clearance_demo - p.clearance_acceptable) * 1e3).round()
    )?;
    writeln!(o, "motion classes:")?;
    for i in 0..p.classes.len() {
        let c = blob.class(i).map_err(|e| anyhow::anyhow!("{e:?}"))?;
        let params: Vec<String> = c.action.params.iter().map(|x| format!("{x:?}")).collect();
        writeln!(
            o,
            "  {}({}): {} preconditions, {} effects",
            c.name,
            params.join(", "),
            c.action.pre.len(),
            c.action.eff.len()
        )?;
    }
    writeln!(o, "affordances:")?;
    for i in 0..p.part_types.len() {
        let t = blob.part_type(i).map_err(|e| anyhow::anyhow!("{e:?}"))?;
        writeln!(o, "  part {:<10} {} grasps", t.name, t.grasps.len())?;
    }
    let mut field_bytes = 0;
    for i in 0..p.location_types.len() {
        let t = blob
            .location_type(i)
            .map_err(|e| anyhow::anyhow!("{e:?}"))?;
        write!(o, "  location {:<7} {} stances", t.name, t.stances.len())?;
        match &t.workspace {
            Some(d) => {
                let f = Field::new(d).map_err(|e| anyhow::anyhow!("{e:?}"))?;
                let b = d.bricks.len() + d.nodes.len() + d.certificates.len();
                field_bytes += b;
                let dims = f.dims();
                let (stored, certs) = f.counts();
                writeln!(
                    o,
                    "; workspace {}×{}×{} nodes at {:.0} mm ({:.2}×{:.2}×{:.2} m), {} of {} \
                     bricks stored, {} certificate balls, {}",
                    dims[0],
                    dims[1],
                    dims[2],
                    f.voxel() * 1e3,
                    (dims[0] - 1) as f64 * f.voxel(),
                    (dims[1] - 1) as f64 * f.voxel(),
                    (dims[2] - 1) as f64 * f.voxel(),
                    stored,
                    d.bricks.len() / 2,
                    certs,
                    kib(b)
                )?;
            }
            None => writeln!(o, "; no workspace")?,
        }
    }
    writeln!(o, "skills:")?;
    for (ci, c) in CLASSES.iter().enumerate() {
        let (mut n, mut shared) = (0, 0);
        for i in 0..p.skills.len() {
            let s = blob.skill(i).map_err(|e| anyhow::anyhow!("{e:?}"))?;
            if s.class as usize == ci {
                n += 1;
                shared += s.shared as usize;
            }
        }
        writeln!(o, "  {:<6} {n} ({shared} from share())", c.name())?;
    }
    let mut durations = Vec::new();
    let mut bases = 0;
    for i in 0..p.rdmps.len() {
        let r = blob.rdmp(i).map_err(|e| anyhow::anyhow!("{e:?}"))?;
        durations.push(r.duration());
        bases = r.position.params.n_basis;
    }
    if !durations.is_empty() {
        let (lo, hi) = durations
            .iter()
            .fold((f64::MAX, 0.0f64), |(a, b), &d| (a.min(d), b.max(d)));
        writeln!(
            o,
            "  {} distinct arm RDMPs, {bases} bases, f32 weights, durations {lo:.2}–{hi:.2} s",
            p.rdmps.len()
        )?;
    }
    writeln!(o, "size by section:")?;
    let robot_bytes = postcard::to_allocvec(&p.robot)?.len();
    let loc = table_bytes(&p.location_types);
    let rows = [
        ("header".to_string(), blob::HEADER_LEN),
        ("robot model".into(), robot_bytes),
        ("action templates".into(), table_bytes(&p.classes)),
        ("workspaces (fields)".into(), field_bytes),
        (
            "location types (stances, field headers)".into(),
            loc - field_bytes,
        ),
        ("part types (grasps)".into(), table_bytes(&p.part_types)),
        ("RDMP skills (weights)".into(), table_bytes(&p.rdmps)),
        ("skill table".into(), table_bytes(&p.skills)),
    ];
    for (name, b) in rows {
        writeln!(o, "  {name:<42} {:>10}", kib(b))?;
    }
    writeln!(o, "  {:<42} {:>10}", "total", kib(bytes.len()))?;
    Ok(o)
}

/// The blob of a world from the demonstrations of `chosen`: generate them with the
/// ground-truth planner (seed 1, 100 Hz), learn with the default settings, compile.
pub fn blob_of_demonstrations(
    world: &crate::world::World,
    chosen: &[crate::world::AffordedTask],
    bar: &indicatif::ProgressBar,
) -> anyhow::Result<Vec<u8>> {
    let model = prf_shared::robot::RobotModel::kmr_iiwa14();
    let ds = crate::demogen::generate_dataset(world, chosen, 1, 100.0, bar)?;
    let k = crate::learn::learn(&ds, &model, &crate::learn::LearnConfig::default(), bar)?;
    compile(&k)
}
