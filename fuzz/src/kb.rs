//! Target `kb`: the knowledge-base reader (`prf learn --add … --into KB`) and what learning
//! does with what it accepts.
//!
//! Input: a knowledge-base file, tried as it is (header, length and CRC-32 checks, and the
//! additions after the base with theirs) and once more sealed — the whole input made the base,
//! its length and CRC-32 rewritten — so that mutations reach the decoder and the state checks.
//! An accepted learner must rebuild its fields and compile (or refuse to compile) without a
//! panic, and what compiles must load in the runtime.

use prf_learn::compile;
use prf_learn::learn::Learner;

/// Header bytes before the payload.
const HEADER: usize = 22;

pub fn run(data: &[u8]) {
    learn(data);
    learn(&seal(data));
}

/// `bytes` sealed: its header's length and CRC-32 made to match.
pub fn seal(bytes: &[u8]) -> Vec<u8> {
    let mut out = bytes.to_vec();
    if out.len() >= HEADER {
        let len = (out.len() - HEADER) as u64;
        let crc = prf_shared::blob::crc32(&out[HEADER..]);
        out[10..18].copy_from_slice(&len.to_le_bytes());
        out[18..22].copy_from_slice(&crc.to_le_bytes());
    }
    out
}

fn learn(bytes: &[u8]) {
    let Ok(mut learner) = Learner::load(bytes) else {
        return;
    };
    let k = learner.knowledge(&|_| {});
    if let Ok(blob) = compile(&k) {
        // A learner the file holds compiles to a blob the runtime reads, or is refused there
        // with a typed error (never a panic).
        let _ = prf_runtime::Runtime::load(&blob);
    }
}
