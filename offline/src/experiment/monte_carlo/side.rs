//! One side of a task at one stance and grasp: is there a candidate at risk ≤ the
//! threshold? Decided with the episode's cache ([`SideState`]) and what all episodes share
//! ([`Shared`]); see the parent module for why every shortcut is exact.

use super::TypeState;
use anyhow::{Result, anyhow};
use prf_runtime::Runtime;
use prf_runtime::skill_plan::{Evaluation, Side, evaluate_arm_motion_observed};
use prf_shared::field::Field;
use prf_shared::kinematics::ArmKinematics;
use prf_shared::rdmp::Rdmp;
use prf_shared::risk::RiskAccumulator;
use prf_shared::robot::MAX_SPHERES;
use prf_shared::se3::{Pose, pose_bits};
use std::collections::{HashMap, HashSet};
use std::sync::{Arc, Mutex};

/// Why a candidate is not a witness, and how to re-check that under another field.
#[derive(Clone, Debug)]
enum Rejection {
    /// It failed, missed its goal or is too fast: its stream does not depend on the field.
    Always,
    /// A configuration of its stream whose own risk exceeded the threshold in the field it was
    /// found in: while it still does, so does the stream's risk (a maximum over it).
    Above(Box<ArmKinematics>),
}

/// A stream at risk ≤ the threshold, with the cells its spheres visit.
#[derive(Clone, Debug)]
struct Witness {
    rdmp: u16,
    stream: Arc<Vec<ArmKinematics>>,
    /// Sorted cell indices (in the grid it was rated on) of every sphere of the stream.
    cells: Vec<u32>,
}

/// What is known about a side (one stance and grasp).
#[derive(Clone, Debug, Default)]
pub struct SideState {
    /// The field version the answers below hold in.
    version: u64,
    /// An RDMP (blob index) whose stream has risk ≤ the threshold, and that stream.
    witness: Option<Witness>,
    /// RDMPs that are not witnesses, with what showed it.
    rejected: HashMap<u16, Rejection>,
    /// Rejections confirmed in the current version.
    confirmed: HashSet<u16>,
}

impl SideState {
    /// The RDMP (blob index) of the side's witness, if it has one.
    pub(super) fn witness_rdmp(&self) -> Option<u16> {
        self.witness.as_ref().map(|w| w.rdmp)
    }
}

/// What is known about a candidate (an RDMP to a goal from an arm base) whatever the field:
/// its stream does not depend on it, so all episodes share this.
#[derive(Default)]
struct Known {
    /// It failed, missed its goal or is too fast.
    always: bool,
    /// Configurations of its stream that exceeded the threshold in some field: in a field
    /// where one still does, the candidate is rejected without integrating.
    probes: Vec<ArmKinematics>,
    /// Its whole stream, when some episode found it a witness (memory permitting).
    stream: Option<Arc<Vec<ArmKinematics>>>,
}

/// A candidate: the RDMP (its exact value, printed) and the goal and arm base (bits).
type CandidateKey = (String, [u64; 7], [u64; 7]);

/// Candidates known across episodes, with the bytes of streams kept.
#[derive(Default)]
pub struct Shared {
    known: Mutex<HashMap<CandidateKey, Known>>,
    stream_bytes: Mutex<usize>,
}

/// A set of lookup cells of one field, as bits.
struct CellSet(Vec<u64>);

impl CellSet {
    /// The empty set over the cells of `field`.
    fn new(field: &Field<'_>) -> Self {
        let [nx, ny, nz] = field.dims();
        CellSet(vec![0; ((nx - 1) * (ny - 1) * (nz - 1)).div_ceil(64)])
    }

    /// Adds the cells of the points `centres` (field frame).
    fn insert(&mut self, field: &Field<'_>, centres: &[nalgebra::Vector3<f64>]) {
        for c in centres {
            let i = field.cell_index(field.cell_at(c)) as usize;
            self.0[i / 64] |= 1 << (i % 64);
        }
    }

    /// The cells, ascending.
    fn sorted(&self) -> Vec<u32> {
        let mut out = Vec::new();
        for (w, &bits) in self.0.iter().enumerate() {
            let mut b = bits;
            while b != 0 {
                out.push((w * 64) as u32 + b.trailing_zeros());
                b &= b - 1;
            }
        }
        out
    }
}

/// At most this many probes per candidate.
const MAX_PROBES: usize = 8;
/// At most this many bytes of streams are kept across episodes.
const MAX_STREAM_BYTES: usize = 768 << 20;

/// One side, stance and grasp of a task on a blob: what a candidate needs.
pub struct At<'s, 'a> {
    pub rt: &'s Runtime<'a>,
    pub side: &'s Side<'a>,
    pub s: usize,
    pub g: usize,
}

impl At<'_, '_> {
    /// RDMP `r` of the blob and the side's goal.
    fn rdmp_and_goal(&self, r: u16) -> Result<(Rdmp, &Pose)> {
        let rdmp = self
            .rt
            .blob
            .rdmp(r as usize)
            .map_err(|e| anyhow!("RDMP {r}: {e}"))?;
        let goal = self
            .side
            .goal(self.s, self.g)
            .ok_or_else(|| anyhow!("no goal for stance {}, grasp {}", self.s, self.g))?;
        Ok((rdmp, goal))
    }

    /// Risk of one configuration in the side's field.
    fn risk_at(&self, kin: &ArmKinematics) -> f64 {
        let base = &self.side.arm_bases[self.s];
        RiskAccumulator::default().add(&self.rt.model, &self.side.field, base, kin)
    }

    /// Calls `f` with each configuration of `stream` and its sphere centres in the side's
    /// field frame, while it returns true.
    fn each_centres(
        &self,
        stream: &[ArmKinematics],
        mut f: impl FnMut(&ArmKinematics, &[nalgebra::Vector3<f64>]) -> bool,
    ) {
        let model = &self.rt.model;
        let base = &self.side.arm_bases[self.s];
        let mut centres = [nalgebra::Vector3::zeros(); MAX_SPHERES];
        for kin in stream {
            kin.sphere_centres_in(model, base, &mut centres);
            if !f(kin, &centres[..model.spheres.len()]) {
                return;
            }
        }
    }

    /// Risk of a stream in the side's field, stopping once it exceeds `threshold` (then the
    /// first configuration that did is returned); within it, the sorted cells its spheres are
    /// looked up in ([`At::cells`]), from the same centres.
    fn rate(
        &self,
        stream: &[ArmKinematics],
        threshold: f64,
    ) -> Result<Vec<u32>, Box<ArmKinematics>> {
        let (model, field) = (&self.rt.model, &self.side.field);
        let mut acc = RiskAccumulator::default();
        let mut cells = CellSet::new(field);
        let mut above = None;
        self.each_centres(stream, |kin, centres| {
            if acc.add_centres(model, field, centres) > threshold {
                above = Some(Box::new(*kin));
                return false;
            }
            cells.insert(field, centres);
            true
        });
        above.map_or_else(|| Ok(cells.sorted()), Err)
    }

    /// The sorted cells the spheres of `stream` are looked up in.
    fn cells(&self, stream: &[ArmKinematics]) -> Vec<u32> {
        let field = &self.side.field;
        let mut cells = CellSet::new(field);
        self.each_centres(stream, |_, centres| {
            cells.insert(field, centres);
            true
        });
        cells.sorted()
    }

    /// Whether RDMP `r` is a witness, using and extending what `shared` knows of it; Ok(stream)
    /// for a witness, otherwise why not.
    fn candidate(
        &self,
        r: u16,
        threshold: f64,
        shared: &Shared,
        integrations: &mut u64,
    ) -> Result<Result<Arc<Vec<ArmKinematics>>, Rejection>> {
        let (rdmp, goal) = self.rdmp_and_goal(r)?;
        let key: CandidateKey = (
            format!("{rdmp:?}"),
            pose_bits(goal),
            pose_bits(&self.side.arm_bases[self.s]),
        );
        let lock = || {
            shared
                .known
                .lock()
                .map_err(|_| anyhow!("the shared cache is poisoned"))
        };
        let (probes, stream) = match lock()?.get(&key) {
            Some(k) if k.always => return Ok(Err(Rejection::Always)),
            Some(k) => (k.probes.clone(), k.stream.clone()),
            None => (Vec::new(), None),
        };
        if let Some(p) = probes.iter().find(|p| self.risk_at(p) > threshold) {
            return Ok(Err(Rejection::Above(Box::new(*p))));
        }
        if let Some(stream) = stream {
            return Ok(match self.rate(&stream, threshold) {
                Ok(_) => Ok(stream),
                Err(kin) => {
                    if let Some(k) = lock()?.get_mut(&key)
                        && k.probes.len() < MAX_PROBES
                    {
                        k.probes.push(*kin);
                    }
                    Err(Rejection::Above(kin))
                }
            });
        }
        let outcome = self.evaluate(r, threshold, integrations)?;
        let mut known = lock()?;
        let k = known.entry(key).or_default();
        Ok(match outcome {
            Ok(stream) => {
                let stream = Arc::new(stream);
                let bytes = stream.len() * std::mem::size_of::<ArmKinematics>();
                let mut kept = shared
                    .stream_bytes
                    .lock()
                    .map_err(|_| anyhow!("the shared cache is poisoned"))?;
                if k.stream.is_none() && *kept + bytes <= MAX_STREAM_BYTES {
                    *kept += bytes;
                    k.stream = Some(stream.clone());
                }
                Ok(stream)
            }
            Err(Rejection::Always) => {
                k.always = true;
                Err(Rejection::Always)
            }
            Err(Rejection::Above(kin)) => {
                if k.probes.len() < MAX_PROBES {
                    k.probes.push(*kin);
                }
                Err(Rejection::Above(kin))
            }
        })
    }

    /// Evaluates RDMP `r` as the planner does, pruned just above `threshold`: Ok(stream) when
    /// its risk is within it, otherwise why not.
    fn evaluate(
        &self,
        r: u16,
        threshold: f64,
        integrations: &mut u64,
    ) -> Result<Result<Vec<ArmKinematics>, Rejection>> {
        let (rdmp, goal) = self.rdmp_and_goal(r)?;
        *integrations += 1;
        // Per run: its stream and the first configuration that took the risk above.
        let (e, (stream, above)) = evaluate_arm_motion_observed(
            self.rt,
            &rdmp,
            goal,
            &self.side.field,
            &self.side.arm_bases[self.s],
            threshold.next_up(),
            usize::MAX,
            || (Vec::new(), None),
            |(stream, above): &mut (Vec<ArmKinematics>, Option<ArmKinematics>), kin, risk| {
                if above.is_none() {
                    stream.push(*kin);
                    if risk > threshold {
                        *above = Some(*kin);
                    }
                }
            },
        );
        Ok(match (e, above) {
            (Evaluation::Risk { risk, .. }, None) if risk <= threshold => Ok(stream),
            (Evaluation::Risk { .. } | Evaluation::Pruned { .. }, Some(kin)) => {
                Err(Rejection::Above(Box::new(kin)))
            }
            (
                Evaluation::Failed { .. } | Evaluation::Missed { .. } | Evaluation::TooFast { .. },
                _,
            ) => Err(Rejection::Always),
            (e, _) => return Err(anyhow!("RDMP {r}: unexpected evaluation {e:?}")),
        })
    }
}

/// Whether a side has a candidate at risk ≤ the threshold for its stance and grasp, deciding
/// anew only what the cache cannot answer (see the module). Counts integrations.
pub fn side_feasible(
    at: &At<'_, '_>,
    state: &mut SideState,
    field: &TypeState,
    shared: &Shared,
    integrations: &mut u64,
) -> Result<bool> {
    let threshold = at.rt.config.risk_threshold;
    if at.side.bound(at.s, at.g) > threshold {
        return Ok(false);
    }
    if state.version != field.version {
        // One version on (the cache sees every step), only some cells may have risen: a
        // witness none of whose spheres is in them still holds.
        let next = state.version + 1 == field.version;
        state.version = field.version;
        state.confirmed.clear();
        if let Some(w) = state.witness.take() {
            let kept = next
                && field
                    .raised
                    .as_ref()
                    .is_some_and(|raised| !w.cells.iter().any(|c| raised.contains(c)));
            if kept {
                state.witness = Some(w);
            } else {
                match at.rate(&w.stream, threshold) {
                    Ok(cells) => {
                        state.witness = Some(Witness { cells, ..w });
                    }
                    Err(kin) => {
                        state.rejected.insert(w.rdmp, Rejection::Above(kin));
                        state.confirmed.insert(w.rdmp);
                    }
                }
            }
        }
    }
    if state.witness.is_some() {
        return Ok(true);
    }
    let mut result = Ok(());
    at.side.candidates(at.rt, at.g, |stance, k| {
        if stance as usize != at.s {
            return true;
        }
        let r = match at.rt.blob.skill(k as usize) {
            Ok(skill) => skill.rdmp,
            Err(e) => {
                result = Err(anyhow!("skill {k}: {e}"));
                return false;
            }
        };
        let Some(r) = r else { return true };
        match state.rejected.get(&r) {
            Some(Rejection::Always) => return true,
            Some(Rejection::Above(_)) if state.confirmed.contains(&r) => return true,
            Some(Rejection::Above(kin)) if at.risk_at(kin) > threshold => {
                state.confirmed.insert(r);
                return true;
            }
            _ => {}
        }
        match at.candidate(r, threshold, shared, integrations) {
            Ok(Ok(stream)) => {
                let cells = at.cells(&stream);
                state.witness = Some(Witness {
                    rdmp: r,
                    stream,
                    cells,
                });
                false
            }
            Ok(Err(why)) => {
                state.rejected.insert(r, why);
                state.confirmed.insert(r);
                true
            }
            Err(e) => {
                result = Err(e);
                false
            }
        }
    })?;
    result?;
    Ok(state.witness.is_some())
}
