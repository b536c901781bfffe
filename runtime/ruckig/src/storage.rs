/// Bytes reserved for one generator (Ruckig with its input and output parameters; 7 DoF:
/// 19,848 B on x86-64). Included by `build.rs` too, which passes it to the shim's size check.
pub const STORAGE_BYTES: usize = 20 * 1024;
