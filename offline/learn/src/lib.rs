//! `prf-learn`: Learn (Alg. 3) on a dataset of robot programs, and the blob compiler.
//!
//! - [`learn`](mod@learn): the pass over the dataset, driven by the motion classes of
//!   [`prf_shared::motion::CLASSES`];
//! - [`kb`]: the knowledge base, a learner's whole state on disk, for `prf learn --add`;
//! - [`affordance`]: stances and grasps with tolerance;
//! - [`workspace`] (+ [`edt`], [`certify`], [`in_file`]): Ω+ per location type as a conservative distance field;
//! - [`skills`]: TrainRDMP on arm motions, the skill sets and share();
//! - [`compile`](mod@compile): Learn's output → the blob ([`prf_shared::blob`]);
//! - [`report`](mod@report): a blob's contents and sizes, as `prf learn` and `prf inspect` print them.
//!
//! It knows neither the ground-truth cell nor any IPC: `cargo tree -p prf-learn` shows no
//! simulator, iceoryx2, Ruckig or terminal crate.

pub mod affordance;
pub mod certify;
pub mod compile;
pub mod edt;
pub mod in_file;
pub mod kb;
pub mod learn;
pub mod report;
pub mod skills;
pub mod workspace;

pub use compile::{CompileError, compile};
pub use learn::{Knowledge, LearnConfig, LearnError, learn};
pub use report::{ReportError, report};
