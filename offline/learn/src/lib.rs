//! `prf-learn`: Learn (Alg. 3) on a dataset of robot programs, and the blob compiler.
//!
//! - [`learn`](mod@learn): the pass over the dataset, driven by the motion classes of
//!   [`prf_shared::motion::CLASSES`];
//! - [`kb`]: the knowledge base, a learner's whole state on disk, for `prf learn --add`;
//! - [`affordance`]: stances and grasps with tolerance;
//! - [`workspace`] (+ [`edt`], [`capsule`], [`certify`], [`in_file`]): Ω+ per location type as a conservative distance field;
//! - [`exact`]: the reference Ω+ (its dilated balls, searched exhaustively) the field is measured against;
//! - [`skills`]: TrainRDMP on arm motions, the skill sets and share();
//! - [`compile`](mod@compile): Learn's output → the blob ([`prf_shared::blob`]);
//! - [`report`](mod@report): a blob's contents and sizes, as `prf learn` and `prf inspect` print them.
//!
//! It knows neither the ground-truth cell nor any IPC: `cargo tree -p prf-learn` shows no
//! simulator, iceoryx2, Ruckig or terminal crate.
//!
//! # Example
//!
//! Learn a dataset (a directory as `prf gen` or `prf import-bag` writes it) and compile the
//! blob the runtime loads (compiled, not run: it needs a dataset on disk):
//!
//! ```no_run
//! use prf_files::dataset::Dataset;
//! use prf_learn::{LearnConfig, compile, learn, report};
//!
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! let robot = prf_files::robot::example()?; // or robot::load(urdf, spheres)
//! let dataset = Dataset::read("dataset".as_ref(), &robot)?;
//! let config = LearnConfig {
//!     clearance_acceptable: 0.03, // r; r_d comes with the dataset, ε = r_d − r
//!     ..LearnConfig::default()
//! };
//! let knowledge = learn(&dataset, &robot, &config, &|_progress| {})?;
//! let blob = compile(&knowledge)?;
//! print!("{}", report(&blob)?); // what `prf learn` and `prf inspect` print
//! std::fs::write("cell.blob", &blob)?;
//! # Ok(())
//! # }
//! ```

pub mod affordance;
pub mod capsule;
pub mod certify;
pub mod compile;
pub mod edt;
pub mod exact;
pub mod in_file;
pub mod kb;
pub mod learn;
pub mod report;
pub mod skills;
pub mod workspace;

pub use compile::{CompileError, compile};
pub use learn::{Knowledge, LearnConfig, LearnError, learn};
pub use report::{ReportError, report};
