//! The paper's evaluation on the example cell (`prf experiment`):
//!
//! - [`rdmp_vs_dmp`]: Sec. 4.3, Fig. 3 and 4 — risk of RDMP and DMP trajectories generalised
//!   to a grid of new goals around one demonstration;
//! - [`monte_carlo`]: Sec. 6.3, Fig. 5 — feasible tasks as demonstrations are learned one at a
//!   time in random orders, with incremental learning and an exact cache across steps.

pub mod monte_carlo;
pub mod rdmp_vs_dmp;
