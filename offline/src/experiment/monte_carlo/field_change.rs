//! Which cells of a field may look up a larger distance after the field was rebuilt: what
//! a kept witness must avoid ([`raised_cells`]).

use prf_learn::certify::cells_with_changed_corners;
use prf_learn::workspace::LearnedField;
use prf_shared::field::{CAPSULE_BYTES, CERT_BYTES};
use std::collections::{HashMap, HashSet};

/// The capsules (their records) a field's certificates name, by cell.
fn certificates_by_cell(f: &LearnedField) -> HashMap<u32, Vec<&[u8]>> {
    let mut out: HashMap<u32, Vec<&[u8]>> = HashMap::new();
    for rec in f.certificates.chunks_exact(CERT_BYTES) {
        let cell = u32::from_le_bytes([rec[0], rec[1], rec[2], rec[3]]);
        let at = u16::from_le_bytes([rec[4], rec[5]]) as usize * CAPSULE_BYTES;
        out.entry(cell)
            .or_default()
            .push(&f.capsules[at..at + CAPSULE_BYTES]);
    }
    out
}

/// The cells (lookup cell indices) where the field `new` may look up a larger distance than
/// `old`: a cell whose eight corner nodes are encoded alike in both and whose certificates in
/// `old` are all in `new` has a superset of `old`'s terms there, so its lookup (their
/// minimum) cannot rise. None when the grids differ.
pub fn raised_cells(old: &LearnedField, new: &LearnedField) -> Option<HashSet<u32>> {
    if old.grid() != new.grid() {
        return None;
    }
    let corners = cells_with_changed_corners(new.dims, &old.node_tokens(), &new.node_tokens());
    let (before, after) = (certificates_by_cell(old), certificates_by_cell(new));
    let lost = |cell: u32| {
        before.get(&cell).is_some_and(|old| {
            let new = after.get(&cell);
            old.iter().any(|r| !new.is_some_and(|n| n.contains(r)))
        })
    };
    Some(
        (0..corners.len() as u32)
            .filter(|&cell| corners[cell as usize] || lost(cell))
            .collect(),
    )
}
