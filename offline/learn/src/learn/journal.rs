//! A knowledge base's additions ([`crate::kb`]): `prf learn --add` appends the lessons of the
//! programs it added and the fields it rebuilt, instead of rewriting the whole file; loading
//! replays them, so the learner loaded is the learner that appended.

use super::{Learner, Lesson, Lessons, within_100_m};
use crate::kb::{
    AdditionRecord, AdditionState, ArmState, FRAMES, KbError, LessonState, LessonsState,
    PathSpheres, RdmpState, Rebuilt, encode_addition, encode_lessons, pose_of, pose_state,
};
use crate::workspace::PathSphere;
use prf_shared::motion::CLASSES;

impl Learner {
    /// The addition record of `lessons`, each already [`Learner::add`]ed, to append to the
    /// knowledge base this learner was loaded from or saved to. It holds the lessons and,
    /// for every location type they swept whose queue [`Learner::knowledge`] has since
    /// emptied, the field and splat of that build; a type still queued is rebuilt after
    /// loading, as it would be here.
    pub fn addition(&self, lessons: &[Lessons]) -> AdditionRecord {
        let part = encode_lessons(&lessons.iter().map(lessons_state).collect::<Vec<_>>());
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
        encode_addition(part, &rebuilt)
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

/// `l` as plain data.
fn lessons_state(l: &Lessons) -> LessonsState {
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
                sweep: l.sweep.clone().map(PathSpheres),
                arm: l.arm.as_ref().map(|(path, dt, rdmp)| ArmState {
                    rdmp: RdmpState::of(rdmp),
                    path: path.clone(),
                    dt: *dt,
                }),
            })
            .collect(),
    }
}
