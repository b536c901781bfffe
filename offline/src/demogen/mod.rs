//! The demonstration generator: the programmer of the example cell, who knows the true
//! geometry and plans collision-free programs (Sec. 4.3.1, Sec. 7).

pub mod ik;
pub mod program;
pub mod rrt;
pub mod timing;

pub use program::{GenConfig, GenError, Generator};
