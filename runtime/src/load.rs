//! Loading a blob: validate it once and index it in place (no copy of fields or weights).

use prf_shared::blob::{Blob, BlobError};
use prf_shared::field::{Field, Lookups};
use prf_shared::kinematics::Chain;
use prf_shared::limits::MotionLimits;
use prf_shared::motion::{self, MotionClass};
use prf_shared::rdmp::{Rdmp, RdmpConfig};
use prf_shared::robot::RobotModel;

/// Maximum motion classes a blob may declare.
pub const MAX_CLASSES: usize = 8;

/// Why a blob could not be loaded.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LoadError {
    /// The blob itself is malformed (header, checksum, a record, a reference).
    Blob(BlobError),
    /// The blob declares more motion classes than the runtime has room for.
    TooManyClasses {
        /// Classes the blob declares.
        count: usize,
    },
}

impl From<BlobError> for LoadError {
    fn from(e: BlobError) -> Self {
        LoadError::Blob(e)
    }
}

impl core::fmt::Display for LoadError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            LoadError::Blob(e) => write!(f, "invalid blob: {e}"),
            LoadError::TooManyClasses { count } => write!(
                f,
                "the blob declares {count} motion classes, the runtime supports {MAX_CLASSES}"
            ),
        }
    }
}

impl core::error::Error for LoadError {}

/// Settings the planner and the executor share, so the planned trajectory is the executed one.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RuntimeConfig {
    /// RDMP integration (Δt = the executor's tick, 1 ms).
    pub rdmp: RdmpConfig,
    /// A task is physically feasible when J* ≤ this risk, m (Sec. 6.1; default 0).
    pub risk_threshold: f64,
    /// The work skill planning may do per task (default: unlimited; the firmware sets one).
    pub plan_budget: crate::skill_plan::PlanBudget,
    /// How skill planning searches (default [`crate::skill_plan::Search::DecideFirst`]).
    pub search: crate::skill_plan::Search,
    /// How risk lookups may be settled without reading the field (default
    /// [`Lookups::Travelled`]; the others are the benchmark's baselines). Risks are the same
    /// with each.
    pub lookups: Lookups,
}

impl Default for RuntimeConfig {
    fn default() -> Self {
        RuntimeConfig {
            rdmp: RdmpConfig::default(),
            risk_threshold: 0.0,
            plan_budget: crate::skill_plan::PlanBudget::UNLIMITED,
            search: crate::skill_plan::Search::DecideFirst,
            lookups: Lookups::Travelled,
        }
    }
}

/// A loaded knowledge base: the validated blob, its robot model and the code of each of its
/// motion classes (looked up once by name).
pub struct Runtime<'a> {
    /// The validated blob.
    pub blob: Blob<'a>,
    /// Its robot model.
    pub model: RobotModel,
    /// Settings of planning and execution.
    pub config: RuntimeConfig,
    /// The robot's motion limits: every planned arm stream stays within them.
    pub limits: MotionLimits,
    /// How FK composes the model, read once at load (a run starts on it without reading it
    /// again in the tick that starts it).
    chain: Chain,
    classes: heapless::Vec<&'static dyn MotionClass, MAX_CLASSES>,
}

impl<'a> Runtime<'a> {
    /// Validates header, version, CRC and every record, and indexes the sections in place.
    pub fn load(bytes: &'a [u8]) -> Result<Self, LoadError> {
        Self::load_with(bytes, RuntimeConfig::default())
    }

    /// [`Runtime::load`] with explicit settings.
    pub fn load_with(bytes: &'a [u8], config: RuntimeConfig) -> Result<Self, LoadError> {
        let blob = Blob::parse(bytes)?;
        let model = blob.robot()?;
        let n = blob.payload.classes.len();
        let mut classes = heapless::Vec::new();
        for i in 0..n {
            // Blob::parse already checked every class name resolves.
            let c = blob.class(i)?;
            let code = motion::class(c.name).ok_or(BlobError::Reference {
                section: prf_shared::blob::Section::Classes,
                index: i,
            })?;
            classes
                .push(code)
                .map_err(|_| LoadError::TooManyClasses { count: n })?;
        }
        Ok(Runtime {
            blob,
            limits: MotionLimits::kmr_iiwa(&model),
            chain: Chain::new(&model),
            model,
            config,
            classes,
        })
    }

    /// How FK composes [`Runtime::model`] ([`Chain`]), read at load.
    pub fn chain(&self) -> &Chain {
        &self.chain
    }

    /// Number of motion classes in the blob.
    pub fn class_count(&self) -> usize {
        self.classes.len()
    }

    /// The code of blob class `i`.
    pub fn class_code(&self, i: usize) -> Option<&'static dyn MotionClass> {
        self.classes.get(i).copied()
    }

    /// Blob index of the class called `name`.
    pub fn class_index(&self, name: &str) -> Option<usize> {
        self.classes.iter().position(|c| c.name() == name)
    }

    /// Indices of the skills of blob class `class`, in blob order.
    pub fn skills_of(&self, class: usize) -> impl Iterator<Item = usize> + '_ {
        (0..self.blob.payload.skills.len())
            .filter(move |&k| self.blob.skill(k).is_ok_and(|s| s.class as usize == class))
    }

    /// Workspace Ω+ of location type `t`, if one was learned.
    pub fn workspace(&self, t: usize) -> Result<Option<Field<'a>>, LoadError> {
        let l = self.blob.location_type(t)?;
        match l.workspace {
            Some(d) => Ok(Some(
                Field::new(&d)
                    .map_err(|error| BlobError::Field {
                        location_type: t,
                        error,
                    })?
                    .lookups(self.config.lookups),
            )),
            None => Ok(None),
        }
    }

    /// The working (f64) RDMP of skill `k`, if the skill has one.
    pub fn skill_rdmp(&self, k: usize) -> Result<Option<Rdmp>, LoadError> {
        match self.blob.skill(k)?.rdmp {
            Some(r) => Ok(Some(self.blob.rdmp(r as usize)?)),
            None => Ok(None),
        }
    }

    /// [`Runtime::skill_rdmp`] into `out`, without moving the RDMP; false if the skill has
    /// none.
    pub fn skill_rdmp_into(&self, k: usize, out: &mut Rdmp) -> Result<bool, LoadError> {
        match self.blob.skill(k)?.rdmp {
            Some(r) => {
                self.blob.rdmp_into(r as usize, out)?;
                Ok(true)
            }
            None => Ok(false),
        }
    }
}
