//! Sweeps left in the knowledge-base file until a field build needs them (issue 17): the
//! sweeps are 97 % of the file, and `prf learn --add` of one program touches one or two of
//! the location types. A learner [`Learner::open`]ed on a file keeps the file and reads a
//! type's section (its CRC-32 checked, decoded, its numbers checked) when the type is rebuilt
//! or saved with changes; a type it never reads is saved as the same bytes.

use super::{Learner, check_sweep};
use crate::kb::{KbError, SplatState, read_section};
use crate::workspace::{Sweep, SweptPath};
use std::ops::Range;
use std::sync::Arc;

/// The bytes of a knowledge-base file (a mapped file, or a buffer), shared by a learner
/// [`Learner::open`]ed on it with the sweeps it has not read yet.
pub type KbFile = Arc<dyn AsRef<[u8]> + Send + Sync>;

/// A location type's sweep: read, or still in the file.
#[derive(Clone, Debug)]
pub(super) enum Slot {
    Ready(Box<Sweep>),
    Stored(Stored),
}

/// A sweep section not read yet, and what the additions replayed since the base did to it.
#[derive(Clone)]
pub(super) struct Stored {
    file: KbFile,
    /// The section's bytes in `file`, header included.
    range: Range<usize>,
    /// The swept paths the additions moved into the sweep, in order.
    added: Vec<Arc<SweptPath>>,
    /// The splat of the last addition that rebuilt the type (replacing the base's).
    splat: Option<Option<SplatState>>,
}

impl std::fmt::Debug for Stored {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Stored")
            .field("range", &self.range)
            .field("added", &self.added.len())
            .field("splat", &self.splat.as_ref().map(Option::is_some))
            .finish()
    }
}

impl Slot {
    /// The section at `range` of `file`, not read.
    pub fn stored(file: KbFile, range: Range<usize>) -> Self {
        Slot::Stored(Stored {
            file,
            range,
            added: Vec::new(),
            splat: None,
        })
    }

    pub fn ready(&self) -> Option<&Sweep> {
        match self {
            Slot::Ready(s) => Some(s.as_ref()),
            Slot::Stored(_) => None,
        }
    }

    pub fn ready_mut(&mut self) -> Option<&mut Sweep> {
        match self {
            Slot::Ready(s) => Some(s.as_mut()),
            Slot::Stored(_) => None,
        }
    }

    /// The section's bytes as read, when the sweep is still in the file unchanged.
    pub fn unchanged(&self) -> Option<&[u8]> {
        match self {
            Slot::Stored(s) if s.added.is_empty() && s.splat.is_none() => {
                (*s.file).as_ref().get(s.range.clone())
            }
            _ => None,
        }
    }

    /// An addition's rebuild of this type replayed ([`Learner::replay`]): `paths` moved into
    /// the sweep, then `splat` installed; for a sweep still in the file, kept until it is read
    /// (adding paths at once adds what adding them one after another does).
    pub fn replay(
        &mut self,
        robot: &prf_shared::robot::RobotModel,
        paths: &[Arc<SweptPath>],
        splat: Option<SplatState>,
    ) {
        match self {
            Slot::Ready(sweep) => replay_into(sweep, robot, paths, splat),
            Slot::Stored(s) => {
                s.added.extend(paths.iter().cloned());
                s.splat = Some(splat);
            }
        }
    }
}

/// An addition's rebuild replayed on a read sweep: `paths` added, then `splat` installed.
fn replay_into(
    sweep: &mut Sweep,
    robot: &prf_shared::robot::RobotModel,
    paths: &[Arc<SweptPath>],
    splat: Option<SplatState>,
) {
    let paths: Vec<&SweptPath> = paths.iter().map(|p| p.as_ref()).collect();
    sweep.add_spheres(robot, &paths);
    sweep.set_splat(splat);
}

impl Learner {
    /// The learner of the knowledge-base `file`, its sweeps left in the file until needed
    /// (module doc): only the core and the additions are read here. A sweep section that is
    /// corrupt is found when its type is rebuilt or its sweep saved ([`KbError::Sweep`]);
    /// [`Learner::load`] reads everything at once.
    pub fn open(file: KbFile) -> Result<Self, KbError> {
        Self::read((*file).as_ref(), Some(&file))
    }

    /// Reads the sweep of location type `t` if it is still in the file, and checks that its
    /// next field build's grid is within bounds ([`Learner::check_grid`]).
    pub(super) fn read_sweep(&mut self, t: usize) -> Result<(), KbError> {
        match self.decode_stored(t) {
            Some(read) => self.install(t, read?),
            None => Ok(()),
        }
    }

    /// The sweep of location type `t` decoded from the file, the additions' rebuilds
    /// replayed, if it is still there (the part of [`Learner::read_sweep`] that only reads
    /// the learner: it may run beside the lessons, [`Learner::read_ahead`]).
    pub(super) fn decode_stored(&self, t: usize) -> Option<Result<Sweep, KbError>> {
        let Some(Slot::Stored(s)) = self.sweeps.get(t) else {
            return None;
        };
        let bytes = (*s.file).as_ref().get(s.range.clone()).unwrap_or_default();
        Some(
            self.sweep_of(t, bytes, s.range.start, Some(&s.file))
                .map(|mut sweep| {
                    // The additions' rebuilds kept (paths and splat are kept together by `replay`).
                    if let Some(splat) = &s.splat {
                        replay_into(&mut sweep, &self.robot, &s.added, splat.clone());
                    }
                    sweep
                }),
        )
    }

    /// Puts `sweep`, [`Learner::decode_stored`] of type `t`, in its slot once its next field
    /// build's grid is within bounds: a sweep refused by its grid stays unread, so a later
    /// build is refused again.
    pub(super) fn install(&mut self, t: usize, sweep: Sweep) -> Result<(), KbError> {
        let stored = std::mem::replace(&mut self.sweeps[t], Slot::Ready(Box::new(sweep)));
        if let Err(e) = self.check_grid(t) {
            self.sweeps[t] = stored;
            return Err(e);
        }
        Ok(())
    }

    /// The sweep of location type `t` in its section `bytes` (at byte `at` of the file), its
    /// spheres left in `file` if these bytes are its ([`Sweep::from_state`]).
    pub(super) fn sweep_of(
        &self,
        t: usize,
        bytes: &[u8],
        at: usize,
        file: Option<&KbFile>,
    ) -> Result<Sweep, KbError> {
        let name = self.location_kinds.get(t).cloned().unwrap_or_default();
        let wrong = |why: String| KbError::Sweep {
            location_type: name.clone(),
            at,
            why,
        };
        let st = read_section(bytes).map_err(wrong)?;
        check_sweep(&st, &self.config.workspace).map_err(wrong)?;
        Ok(Sweep::from_state(st, file))
    }
}
