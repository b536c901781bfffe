//! The one contract between the host cell (`prf-host`) and the joint controller
//! (`prf-firmware-sim`), which both depend on: the fixed-size messages ([`messages`]), the
//! iceoryx2 services and ports of a cell ([`link`]), and the clock both stamp messages with
//! ([`clock`]).

pub mod clock;
pub mod link;
pub mod messages;
pub mod recycled;

pub use clock::now_ns;
pub use messages::{JointStateMsg, SetpointMsg, flags, mode, status};
