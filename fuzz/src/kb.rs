//! Target `kb`: the knowledge-base reader (`prf learn --add … --into KB`) and what learning
//! does with what it accepts.
//!
//! Input: a knowledge-base file, tried as it is (header, length and CRC-32 checks, and the
//! additions after the base with theirs) and once more sealed (`prf_learn::kb::seal`: the whole
//! input made the base, its lengths and CRC-32s rewritten), so that mutations reach the
//! decoders and the state checks.
//! An accepted learner must rebuild its fields and compile (or refuse to compile) without a
//! panic, and what compiles must load in the runtime. A file read whole is also opened with
//! its sweeps left in it (`Learner::open`): that learner must give the same blob and save a
//! file that reads back as the same learner.

use prf_learn::compile;
use prf_learn::kb::seal;
use prf_learn::learn::Learner;
use std::sync::Arc;

pub fn run(data: &[u8]) {
    learn(data);
    learn(&seal(data));
}

fn learn(bytes: &[u8]) {
    let Ok(mut learner) = Learner::load(bytes) else {
        return;
    };
    let Ok(mut opened) = Learner::open(Arc::new(bytes.to_vec())) else {
        panic!("a file read whole is refused when opened");
    };
    let (Ok(k), Ok(lazy)) = (learner.knowledge(&|_| {}), opened.knowledge(&|_| {})) else {
        panic!("a file read whole is refused when its sweeps are read as needed");
    };
    let blob = compile(&k).map_err(|e| e.to_string());
    assert!(
        blob == compile(&lazy).map_err(|e| e.to_string()),
        "opened and read whole, the file gives two blobs"
    );
    // Sweeps never read are saved as their bytes (a hostile file's unsorted keys or non-shortest
    // numbers stay as they were): read whole again, they are the same learner.
    let (Ok(whole), Ok(lazy)) = (learner.save(), opened.save()) else {
        panic!("a learner read from a file is refused when saved");
    };
    let again = Learner::load(&lazy).and_then(|mut l| l.save());
    assert!(
        again.as_ref().ok() == Some(&whole),
        "opened and read whole, the file saves as two learners"
    );
    if let Ok(blob) = blob {
        // A learner the file holds compiles to a blob the runtime reads, or is refused there
        // with a typed error (never a panic).
        let _ = prf_runtime::Runtime::load(&blob);
    }
}
