//! The report of a blob's contents and sizes, shared by `prf learn` and `prf inspect`.

use prf_shared::blob::{self, Blob, Table};
use prf_shared::field::Field;
use prf_shared::motion::CLASSES;
use std::fmt::Write;

/// Why a blob's report could not be made: the blob is invalid.
#[derive(Debug, thiserror::Error)]
pub enum ReportError {
    #[error("invalid blob: {0}")]
    Blob(prf_shared::blob::BlobError),
    #[error("invalid blob: workspace: {0}")]
    Field(prf_shared::field::FieldError),
    #[error("encoding the robot record")]
    Encode(#[from] postcard::Error),
    #[error("formatting the report")]
    Format(#[from] std::fmt::Error),
}

impl From<prf_shared::blob::BlobError> for ReportError {
    fn from(e: prf_shared::blob::BlobError) -> Self {
        ReportError::Blob(e)
    }
}

impl From<prf_shared::field::FieldError> for ReportError {
    fn from(e: prf_shared::field::FieldError) -> Self {
        ReportError::Field(e)
    }
}

fn kib(b: usize) -> String {
    format!("{:.1} KiB", b as f64 / 1024.0)
}

/// A validated blob's contents and sizes, as `prf inspect` prints them.
pub fn report(bytes: &[u8]) -> Result<String, ReportError> {
    let blob = Blob::parse(bytes)?;
    let p = &blob.payload;
    let robot = blob.robot()?;
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
        "robot: 7-axis arm, {} collision spheres (≥ {} mm beyond the link surfaces); clearances r_d = {} mm, r = {} mm (ε = {} mm)",
        robot.spheres.len(),
        robot.sphere_margin * 1e3,
        p.clearance_demo * 1e3,
        p.clearance_acceptable * 1e3,
        ((p.clearance_demo - p.clearance_acceptable) * 1e3).round()
    )?;
    writeln!(o, "motion classes:")?;
    for i in 0..p.classes.len() {
        let c = blob.class(i)?;
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
        let t = blob.part_type(i)?;
        writeln!(o, "  part {:<10} {} grasps", t.name, t.grasps.len())?;
    }
    let mut field_bytes = 0;
    for i in 0..p.location_types.len() {
        let t = blob.location_type(i)?;
        write!(o, "  location {:<7} {} stances", t.name, t.stances.len())?;
        match &t.workspace {
            Some(d) => {
                let f = Field::new(d)?;
                let b = d.bricks.len() + d.nodes.len() + d.certificates.len() + d.capsules.len();
                field_bytes += b;
                let dims = f.dims();
                let (stored, certs, capsules) = f.counts();
                writeln!(
                    o,
                    "; workspace {}×{}×{} nodes at {:.0} mm ({:.2}×{:.2}×{:.2} m), {} of {} \
                     bricks stored, {} certificates of {} capsules, {}",
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
                    capsules,
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
            let s = blob.skill(i)?;
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
        let r = blob.rdmp(i)?;
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
