//! Which cells of a field may look up a larger distance after the field was rebuilt: what
//! a kept witness must avoid ([`raised_cells`]).

use prf_learn::workspace::LearnedField;
use prf_shared::field::{BRICK, BRICK_NODES, CERT_BYTES, NODE_BYTES, UNIFORM};
use std::collections::{HashMap, HashSet};

/// The encoding of node (i, j, k) of a field: its brick's uniform value (true), or its 4
/// bytes (false).
fn node_token(f: &LearnedField, i: usize, j: usize, k: usize) -> (bool, [u8; NODE_BYTES]) {
    let [_, ny, nz] = f.dims.map(|d| d as usize);
    let (by, bz) = (ny / BRICK, nz / BRICK);
    let b = ((i / BRICK) * by + j / BRICK) * bz + k / BRICK;
    let v = u16::from_le_bytes([f.bricks[2 * b], f.bricks[2 * b + 1]]);
    if v >= UNIFORM {
        let [a, c] = v.to_le_bytes();
        return (true, [a, c, 0, 0]);
    }
    let local = ((i % BRICK) * BRICK + j % BRICK) * BRICK + k % BRICK;
    let at = (v as usize * BRICK_NODES + local) * NODE_BYTES;
    (false, core::array::from_fn(|n| f.nodes[at + n]))
}

/// Certificate records of a field by cell.
fn certificates_by_cell(f: &LearnedField) -> HashMap<u32, Vec<&[u8]>> {
    let mut out: HashMap<u32, Vec<&[u8]>> = HashMap::new();
    for rec in f.certificates.chunks_exact(CERT_BYTES) {
        let cell = u32::from_le_bytes([rec[0], rec[1], rec[2], rec[3]]);
        out.entry(cell).or_default().push(rec);
    }
    out
}

/// The cells (lookup cell indices) where the field `new` may look up a larger distance than
/// `old`: a cell whose eight corner nodes are encoded alike in both and whose certificates in
/// `old` are all in `new` has a superset of `old`'s terms there, so its lookup (their
/// minimum) cannot rise. None when the grids differ.
pub fn raised_cells(old: &LearnedField, new: &LearnedField) -> Option<HashSet<u32>> {
    if (old.origin, old.voxel, old.dims) != (new.origin, new.voxel, new.dims) {
        return None;
    }
    let [nx, ny, nz] = new.dims.map(|d| d as usize);
    let node = |i: usize, j: usize, k: usize| (i * ny + j) * nz + k;
    let mut changed = vec![false; nx * ny * nz];
    for i in 0..nx {
        for j in 0..ny {
            for k in 0..nz {
                changed[node(i, j, k)] = node_token(old, i, j, k) != node_token(new, i, j, k);
            }
        }
    }
    let (before, after) = (certificates_by_cell(old), certificates_by_cell(new));
    let mut raised = HashSet::new();
    for i in 0..nx - 1 {
        for j in 0..ny - 1 {
            for k in 0..nz - 1 {
                let cell = ((i * (ny - 1) + j) * (nz - 1) + k) as u32;
                let corners =
                    (0..8).any(|d| changed[node(i + (d >> 2 & 1), j + (d >> 1 & 1), k + (d & 1))]);
                let lost = before.get(&cell).is_some_and(|old| {
                    let new = after.get(&cell);
                    old.iter().any(|r| !new.is_some_and(|n| n.contains(r)))
                });
                if corners || lost {
                    raised.insert(cell);
                }
            }
        }
    }
    Some(raised)
}
