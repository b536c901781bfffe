//! A knowledge base's additions ([`crate::kb`]): `prf learn --add` appends the lessons of the
//! programs it added and the fields it rebuilt, instead of rewriting the whole file; loading
//! replays them, so the learner loaded is the learner that appended.

use super::{Learner, Lesson, Lessons, within_100_m};
use crate::kb::{
    AdditionRecord, AdditionState, ArmState, FRAMES, KbError, LessonState, LessonsState,
    PathSpheres, RdmpState, Rebuilt, encode_addition, encode_lessons, pose_of, pose_state,
};
use crate::workspace::{PathSphere, SweptPath};
use prf_shared::motion::CLASSES;
use std::sync::{Arc, Weak};

/// The paths a field build grew a location type's sweep by, and which of their spheres were
/// new to it: of a lesson's path an addition records only those, since replaying the others
/// would add nothing (d063: 3,347 of its 108 k swept spheres). The paths are held weakly, to
/// find a lesson's among them by address without keeping them (a batch learn's are all of
/// its programs' paths).
#[derive(Clone, Debug, Default)]
pub(super) struct Grown {
    /// Each path, and the index its spheres start at across the paths.
    paths: Vec<(Weak<SweptPath>, u32)>,
    /// The new spheres' indices across the paths, ascending ([`crate::workspace::Sweep::grow`]).
    fresh: Vec<u32>,
}

impl Grown {
    /// A build's `paths`, in the order they grew the sweep, and its `fresh` spheres.
    pub(super) fn new(paths: &[Arc<SweptPath>], fresh: Vec<u32>) -> Self {
        let mut start = 0;
        let paths = paths
            .iter()
            .map(|p| {
                let at = start;
                start += p.len() as u32;
                (Arc::downgrade(p), at)
            })
            .collect();
        Grown { paths, fresh }
    }

    /// The spheres `path` added to the sweep, in order, as a path of their own; `None` if it
    /// is not one of this build's paths.
    fn added_by(&self, path: &Arc<SweptPath>) -> Option<SweptPath> {
        let &(_, start) = self
            .paths
            .iter()
            .find(|(p, _)| std::ptr::eq(p.as_ptr(), Arc::as_ptr(path)))?;
        let end = start + path.len() as u32;
        let run =
            self.fresh.partition_point(|&i| i < start)..self.fresh.partition_point(|&i| i < end);
        let own: Vec<u32> = self.fresh[run].iter().map(|i| i - start).collect();
        Some(path.only(&own))
    }
}

impl Learner {
    /// The addition record of `lessons`, each already [`Learner::add`]ed, to append to the
    /// knowledge base this learner was loaded from or saved to. It holds the lessons and,
    /// for every location type they swept whose queue [`Learner::knowledge`] has since
    /// emptied, the field and splat of that build; a type still queued is rebuilt after
    /// loading, as it would be here. Of a lesson's swept spheres whose type was rebuilt it
    /// holds those new to the sweep (`Grown`): replayed, they grow it as the whole path did.
    pub fn addition(&self, lessons: &[Lessons]) -> AdditionRecord {
        let mut touched: Vec<usize> = lessons.iter().flat_map(Lessons::swept_types).collect();
        touched.sort_unstable();
        touched.dedup();
        let rebuilt: Vec<Rebuilt> = touched
            .into_iter()
            .filter(|&t| self.pending[t].is_empty())
            .map(|t| {
                let field = self.location_types[t].field.clone();
                // A sweep left in the file has not been rebuilt since: no splat (a cache).
                let splat = self.sweeps[t].ready().and_then(|s| s.splat_state());
                (t, field, splat)
            })
            .collect();
        let recorded = |t: usize, path: &Arc<SweptPath>| {
            rebuilt
                .iter()
                .any(|r| r.0 == t)
                .then(|| self.grown[t].added_by(path))
                .flatten()
                .map_or_else(|| path.clone(), Arc::new)
        };
        let states: Vec<LessonsState> = lessons
            .iter()
            .map(|l| lessons_state(l, &recorded))
            .collect();
        encode_addition(encode_lessons(&states), &rebuilt)
    }

    /// Replays an addition: its lessons added in order, then each rebuilt type's queue moved
    /// into its sweep and the field and splat of the build installed.
    pub(super) fn replay(&mut self, a: AdditionState) -> Result<(), KbError> {
        for l in a.lessons {
            let lessons = self.lessons_of(l)?;
            self.add(&lessons);
        }
        for (t, field, splat) in a.rebuilt {
            if t >= self.sweeps.len() {
                return Err(KbError::Decode(format!(
                    "an addition rebuilt location type {t} of {}",
                    self.sweeps.len()
                )));
            }
            let paths = std::mem::take(&mut self.pending[t]);
            self.sweeps[t].replay(&self.robot, &paths, splat);
            self.location_types[t].field = field;
        }
        Ok(())
    }

    /// The lessons an addition holds, checked against this learner: a known class, its
    /// location and part types, finite poses, swept spheres finite within 100 m of robot
    /// spheres that exist, a whole RDMP.
    fn lessons_of(&self, st: LessonsState) -> Result<Lessons, KbError> {
        let bad = |what: &str| {
            KbError::Decode(format!(
                "{what} out of range in the lessons of {}",
                st.demonstration
            ))
        };
        let mut lessons = Vec::with_capacity(st.lessons.len());
        for l in &st.lessons {
            let class = CLASSES
                .iter()
                .map(|c| c.name())
                .find(|n| *n == l.class)
                .ok_or_else(|| KbError::Class(l.class.clone()))?;
            if l.location_type
                .is_some_and(|t| t >= self.location_types.len())
                || l.part_type >= self.part_types.len()
            {
                return Err(bad("a location or part type"));
            }
            let affordance = match l.affordance {
                Some((f, p)) => {
                    let frame = *FRAMES.get(f as usize).ok_or_else(|| bad("a frame"))?;
                    Some((frame, pose_of(p)?))
                }
                None => None,
            };
            let n_spheres = self.robot.spheres.len();
            let sweep = match &l.sweep {
                Some(PathSpheres(path)) => {
                    let c = |s: &PathSphere| [s.centre.x, s.centre.y, s.centre.z];
                    if !path
                        .spheres()
                        .all(|s| within_100_m(&c(&s)) && (s.sphere as usize) < n_spheres)
                    {
                        return Err(bad("a swept sphere"));
                    }
                    Some(path.clone())
                }
                None => None,
            };
            let arm = match &l.arm {
                Some(a) => Some((
                    a.path.clone(),
                    a.dt,
                    a.rdmp.rdmp().ok_or_else(|| bad("an RDMP's weights"))?,
                )),
                None => None,
            };
            lessons.push(Lesson {
                class,
                location_type: l.location_type,
                part_type: l.part_type,
                affordance,
                sweep,
                arm,
            });
        }
        Ok(Lessons {
            demonstration: st.demonstration,
            fingerprint: st.fingerprint,
            lessons,
        })
    }
}

/// `l` as plain data, each swept path as `recorded` gives it for its location type.
fn lessons_state(
    l: &Lessons,
    recorded: &impl Fn(usize, &Arc<SweptPath>) -> Arc<SweptPath>,
) -> LessonsState {
    LessonsState {
        demonstration: l.demonstration.clone(),
        fingerprint: l.fingerprint,
        lessons: l
            .lessons
            .iter()
            .map(|l| LessonState {
                class: l.class.to_string(),
                location_type: l.location_type,
                part_type: l.part_type,
                affordance: l.affordance.map(|(f, p)| {
                    // Every frame is one of FRAMES.
                    let frame = FRAMES.iter().position(|g| *g == f).unwrap_or_default();
                    (frame as u8, pose_state(&p))
                }),
                sweep: l.sweep.as_ref().map(|p| {
                    PathSpheres(match l.location_type {
                        Some(t) => recorded(t, p),
                        None => p.clone(),
                    })
                }),
                arm: l.arm.as_ref().map(|(path, dt, rdmp)| ArmState {
                    rdmp: RdmpState::of(rdmp),
                    path: path.clone(),
                    dt: *dt,
                }),
            })
            .collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::Grown;
    use crate::workspace::{PathSphere, Sweep, SweptPath, WorkspaceConfig};
    use nalgebra::Vector3;
    use prf_shared::robot::RobotModel;
    use rand::{RngExt, SeedableRng, rngs::StdRng};
    use std::sync::Arc;

    /// Of two paths that grow a sweep (each repeating spheres of the sweep, of the other and
    /// of itself), an addition records the spheres each added; replayed on the sweep as it
    /// was, they grow it to what the whole paths grew it to: the same spheres, keys, feature
    /// balls and order.
    #[test]
    fn the_spheres_a_path_added_grow_the_sweep_as_the_path_did() {
        let model = RobotModel::kmr_iiwa14();
        let cfg = WorkspaceConfig::default();
        let mut rng = StdRng::seed_from_u64(17);
        // 6³ centres 1 mm apart × 3 robot spheres: 648 keys, so the paths repeat each other.
        let mut path = |len: usize| {
            let spheres: Vec<PathSphere> = (0..len)
                .map(|_| {
                    let [x, y, z] = [(); 3].map(|_| rng.random_range(0..6) as f64 * 1e-3);
                    PathSphere {
                        centre: Vector3::new(x, y, z),
                        sphere: rng.random_range(0..3),
                    }
                })
                .collect();
            Arc::new(SweptPath::new(&spheres))
        };
        let (kept, b, c, other) = (path(300), path(400), path(400), path(50));
        let mut whole = Sweep::new(cfg.feature_spacing);
        whole.add_spheres(&model, &[&kept]);
        let mut replayed = whole.clone();
        let before = whole.spheres.len();
        let fresh = whole.grow(&model, &[&b, &c], None, &cfg);
        let grown = Grown::new(&[b.clone(), c.clone()], fresh);
        let (own_b, own_c) = (grown.added_by(&b).unwrap(), grown.added_by(&c).unwrap());
        assert!(grown.added_by(&other).is_none(), "not one of the paths");
        assert_eq!(own_b.len() + own_c.len(), whole.spheres.len() - before);
        assert!(
            !own_c.is_empty() && own_c.len() < own_b.len() && own_b.len() < b.len(),
            "{} of {} and {} of {} spheres new",
            own_b.len(),
            b.len(),
            own_c.len(),
            c.len()
        );
        replayed.add_spheres(&model, &[&own_b, &own_c]);
        assert_eq!(replayed.to_state(), whole.to_state());
    }
}
