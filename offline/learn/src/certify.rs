//! Step 5 of [`crate::workspace`]: certificate balls for the demonstrated spheres the encoded
//! field does not certify, continued across field builds of a growing sweep.
//!
//! Within one cell the lookup is a minimum of 1-Lipschitz terms (its 8 corner nodes), so a
//! sphere whose centre c satisfies (terms of cell C at c) + r ≤ −m is certified for every
//! centre within m of c in C. Each cell the margin ball around c touches is checked; where
//! it fails, the capsule of the piece of path the sphere lies on ([`crate::capsule`]; radius
//! r + ε less the piece's deviation) becomes a certificate of that cell, and if even that
//! leaves the sphere uncertified, its own ball B(c, r + ε). One capsule certifies the
//! dozens of spheres along its piece, so a wide margin costs few certificates.
//!
//! A cell's certificates depend only on its corner nodes and on the spheres touching it, in
//! order. So the next build of a sweep ([`Certified`]) re-decides only the cells one of whose
//! corners is encoded differently, and the spheres added since: the result is the same bytes
//! a build from nothing gives. The cells are decided in parallel. A loaded knowledge base's
//! sweep recovers these decisions from its field ([`Certified::recover`]); which of its
//! spheres touch a cell is found when the cell is decided anew.

use crate::capsule::Capsule;
use crate::in_file::Spheres;
use crate::workspace::{LearnedField, SphereSample, WorkspaceConfig};
use nalgebra::Vector3;
use prf_shared::field::{
    BRICK, BRICK_NODES, CAPSULE_BYTES, CERT_BYTES, CERT_UNIT, Field, Hint, MAX_CAPSULES,
    NODE_BYTES, UNIFORM, nearest_on_segment,
};
use rayon::prelude::*;
use std::collections::HashMap;

/// How a node is encoded: its brick's uniform value (true), or its own bytes (false).
pub type NodeToken = (bool, [u8; NODE_BYTES]);

impl LearnedField {
    /// Every node's encoding, in node order ((i · ny + j) · nz + k).
    pub fn node_tokens(&self) -> Vec<NodeToken> {
        let [nx, ny, nz] = self.dims.map(|d| d as usize);
        let (by, bz) = (ny / BRICK, nz / BRICK);
        let mut out = Vec::with_capacity(nx * ny * nz);
        for i in 0..nx {
            for j in 0..ny {
                for k in 0..nz {
                    let b = ((i / BRICK) * by + j / BRICK) * bz + k / BRICK;
                    let v = u16::from_le_bytes([self.bricks[2 * b], self.bricks[2 * b + 1]]);
                    out.push(if v >= UNIFORM {
                        let [a, c] = v.to_le_bytes();
                        (true, [a, c, 0, 0])
                    } else {
                        let local = ((i % BRICK) * BRICK + j % BRICK) * BRICK + k % BRICK;
                        let at = (v as usize * BRICK_NODES + local) * NODE_BYTES;
                        (false, core::array::from_fn(|n| self.nodes[at + n]))
                    });
                }
            }
        }
        out
    }

    /// The grid: origin, voxel and node counts.
    pub fn grid(&self) -> ([f32; 3], f32, [u16; 3]) {
        (self.origin, self.voxel, self.dims)
    }
}

/// Per lookup cell of a grid with node counts `dims`, whether one of its 8 corners is encoded
/// differently in `old` and `new` (node tokens of the same grid).
pub fn cells_with_changed_corners(
    dims: [u16; 3],
    old: &[NodeToken],
    new: &[NodeToken],
) -> Vec<bool> {
    let [nx, ny, nz] = dims.map(|d| d as usize);
    let node = |i: usize, j: usize, k: usize| (i * ny + j) * nz + k;
    let changed: Vec<bool> = old.iter().zip(new).map(|(a, b)| a != b).collect();
    let mut out = Vec::with_capacity((nx - 1) * (ny - 1) * (nz - 1));
    for i in 0..nx - 1 {
        for j in 0..ny - 1 {
            for k in 0..nz - 1 {
                out.push(
                    (0..8).any(|d| changed[node(i + (d >> 2 & 1), j + (d >> 1 & 1), k + (d & 1))]),
                );
            }
        }
    }
    out
}

/// The certificate decisions of a sweep's last field build, continued by the next one.
#[derive(Clone, Debug)]
pub struct Certified {
    /// The grid the decisions were made on and every node's encoding there.
    grid: ([f32; 3], f32, [u16; 3]),
    tokens: Vec<NodeToken>,
    /// Per cell: the spheres (indices, ascending) whose margin ball touches it, and its
    /// certificate capsules (as quantized).
    spheres: Vec<Vec<u32>>,
    balls: Vec<Vec<Cert>>,
    /// Spheres decided (a prefix of the sweep's, which only grows).
    done: usize,
    /// Spheres left out of the lists by a recovery, if any.
    unlisted: Option<Box<Unlisted>>,
    /// Margin and ε the decisions were made with.
    settings: (f64, f64),
}

impl Certified {
    /// The decisions the build of `learned` from the sweep's first `spheres` spheres left,
    /// recovered from what a knowledge base keeps, without deciding anything: every cell's
    /// balls from the field's certificate records (whose mm steps are the balls' own), the
    /// node encodings from the field. The cells' lists of these spheres are left to the build
    /// that decides a cell anew ([`certificates`]); most builds decide none. None for a field
    /// that is not valid, or with a ball at the end of a record's range (clamped there, so not
    /// the ball decided).
    pub fn recover(
        learned: &LearnedField,
        spheres: usize,
        cfg: &WorkspaceConfig,
    ) -> Option<Certified> {
        let field = Field::new(&learned.data()).ok()?;
        let [nx, ny, nz] = field.dims();
        let n_cells = (nx - 1) * (ny - 1) * (nz - 1);
        let mut balls = vec![Vec::new(); n_cells];
        for r in learned.certificates.chunks_exact(CERT_BYTES) {
            let cell = u32::from_le_bytes([r[0], r[1], r[2], r[3]]) as usize;
            let (a, b, r) = field.capsule(u16::from_le_bytes([r[4], r[5]]) as usize);
            // An end at the edge of the records' range may have been clamped there.
            let edge = (i16::MAX - 1) as f64 * CERT_UNIT;
            if a.iter().chain(b.iter()).any(|v| v.abs() > edge) {
                return None;
            }
            balls.get_mut(cell)?.push(Cert { a, b, r });
        }
        Some(Certified {
            grid: learned.grid(),
            tokens: learned.node_tokens(),
            spheres: vec![Vec::new(); n_cells],
            balls,
            done: spheres,
            unlisted: Some(Box::new(Unlisted {
                before: spheres,
                listed: vec![false; n_cells],
            })),
            settings: (cfg.certify_margin, cfg.epsilon),
        })
    }

    /// Completes the lists of the cells in `redo` that lack the spheres a recovery left out,
    /// from one pass over those spheres (the lists stay ascending: they held only later ones).
    fn list_before_unlisted(&mut self, decide: &Decide, redo: &[bool], spheres: &Spheres) {
        let Some(u) = self.unlisted.as_mut() else {
            return;
        };
        let missing: Vec<bool> = (0..redo.len())
            .map(|cell| redo[cell] && !u.listed[cell])
            .collect();
        if !missing.contains(&true) {
            return;
        }
        let mut before: Vec<Vec<u32>> = vec![Vec::new(); redo.len()];
        for (i, s) in spheres.iter().take(u.before).enumerate() {
            decide.cells_touched(&s, |cell| {
                if missing[cell] {
                    before[cell].push(i as u32);
                }
            });
        }
        for (cell, mut list) in before.into_iter().enumerate() {
            if missing[cell] {
                list.append(&mut self.spheres[cell]);
                self.spheres[cell] = list;
                u.listed[cell] = true;
            }
        }
    }
}

/// The spheres a recovery did not list ([`Certified::recover`]): those before `before` are in
/// the lists of the `listed` cells only (a cell's list is needed only when the cell is decided
/// anew).
#[derive(Clone, Debug)]
struct Unlisted {
    before: usize,
    listed: Vec<bool>,
}

/// The certificate records ([`prf_shared::field::CERT_BYTES`]) of `learned`, whose
/// certificates must still be empty, for the demonstrated `spheres` and the pieces of path
/// `capsules` they name; `last` is what the previous build of the same sweep decided (its
/// spheres a prefix of these), or None. Returns the records and what this build decided, for
/// the next.
pub fn certificates(
    learned: &LearnedField,
    spheres: &Spheres,
    capsules: &[Capsule],
    last: Option<Certified>,
    cfg: &WorkspaceConfig,
) -> ((Vec<u8>, Vec<u8>, usize), Certified) {
    debug_assert!(learned.certificates.is_empty());
    let field = learned.field();
    let [nx, ny, nz] = field.dims();
    let n_cells = (nx - 1) * (ny - 1) * (nz - 1);
    let tokens = learned.node_tokens();
    let settings = (cfg.certify_margin, cfg.epsilon);
    let mut c = match last {
        Some(c)
            if c.grid == learned.grid() && c.settings == settings && c.done <= spheres.len() =>
        {
            c
        }
        _ => Certified {
            grid: learned.grid(),
            tokens: Vec::new(),
            spheres: vec![Vec::new(); n_cells],
            balls: vec![Vec::new(); n_cells],
            done: 0,
            unlisted: None,
            settings,
        },
    };
    // The cells one of whose corners changed have every sphere touching them decided anew;
    // the spheres added since are decided in every cell they touch. A cell's decisions
    // depend only on its own list, in order: the cells are decided in parallel.
    let redo = if c.done > 0 {
        cells_with_changed_corners(learned.dims, &c.tokens, &tokens)
    } else {
        vec![false; n_cells]
    };
    let decide = Decide::new(field, capsules, cfg);
    c.list_before_unlisted(&decide, &redo, spheres);
    let old: Vec<usize> = c.spheres.iter().map(Vec::len).collect();
    decide.list(&mut c.spheres, spheres, c.done);
    c.spheres
        .par_iter()
        .zip(c.balls.par_iter_mut())
        .enumerate()
        .for_each_init(
            || decide,
            |decide, (cell, (list, balls))| {
                let from = if redo[cell] {
                    balls.clear();
                    0
                } else {
                    old[cell]
                };
                for &i in &list[from..] {
                    decide.sphere_in_cell(&spheres.get(i as usize), cell, balls);
                }
            },
        );
    c.done = spheres.len();
    c.tokens = tokens;
    (records(&c.balls), c)
}

/// The certificates (cell, capsule index) of the cells' capsules `balls`, and the capsules,
/// each stored once, in the order of first use, and how many certificates were left out:
/// beyond [`MAX_CAPSULES`] a capsule is not stored and the certificates naming it are left
/// out, so the field stays conservative and the spheres they certified rate a risk (a
/// location type that needs more capsules than the u16 index holds learns with a smaller
/// margin; `prf learn` says so).
fn records(balls: &[Vec<Cert>]) -> (Vec<u8>, Vec<u8>, usize) {
    let (mut certificates, mut capsules, mut left_out) = (Vec::new(), Vec::new(), 0);
    let mut index: HashMap<[i64; 7], u16> = HashMap::new();
    for (cell, list) in balls.iter().enumerate() {
        for k in list {
            let key = k.steps();
            let next = index.len();
            let i = match index.get(&key) {
                Some(i) => *i,
                None if next < MAX_CAPSULES => {
                    for v in &key[..6] {
                        capsules.extend_from_slice(&(*v as i16).to_le_bytes());
                    }
                    capsules.extend_from_slice(&(key[6] as u16).to_le_bytes());
                    index.insert(key, next as u16);
                    next as u16
                }
                None => {
                    left_out += 1;
                    continue;
                }
            };
            certificates.extend_from_slice(&(cell as u32).to_le_bytes());
            certificates.extend_from_slice(&i.to_le_bytes());
        }
    }
    debug_assert_eq!(certificates.len() % CERT_BYTES, 0);
    debug_assert_eq!(capsules.len() % CAPSULE_BYTES, 0);
    (certificates, capsules, left_out)
}

/// A certificate capsule as the field stores it: ends and radius on the [`CERT_UNIT`] grid.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Cert {
    a: Vector3<f64>,
    b: Vector3<f64>,
    r: f64,
}

impl Cert {
    /// The capsule of radius `r` around [a, b] quantized conservatively: the ends rounded to
    /// the grid (the segment moves at most as far as its farther end), the radius shrunk by
    /// that and rounded down. None when an end is outside the records' range or nothing is
    /// left of the radius.
    fn quantized(a: &Vector3<f64>, b: &Vector3<f64>, r: f64) -> Option<Self> {
        let limit = (i16::MAX - 1) as f64;
        let grid = |v: &Vector3<f64>| {
            let q = v.map(|x| (x / CERT_UNIT).round());
            q.iter().all(|x| x.abs() <= limit).then_some(q * CERT_UNIT)
        };
        let (qa, qb) = (grid(a)?, grid(b)?);
        let moved = (qa - a).norm().max((qb - b).norm());
        let r = ((r - moved) / CERT_UNIT).floor() * CERT_UNIT;
        (r > 0.0 && r / CERT_UNIT <= u16::MAX as f64).then_some(Cert { a: qa, b: qb, r })
    }

    /// Ends and radius in [`CERT_UNIT`] steps.
    fn steps(&self) -> [i64; 7] {
        let s = |v: f64| (v / CERT_UNIT).round() as i64;
        [
            s(self.a.x),
            s(self.a.y),
            s(self.a.z),
            s(self.b.x),
            s(self.b.y),
            s(self.b.z),
            s(self.r),
        ]
    }

    /// dist(x, [a, b]) − r.
    fn distance(&self, x: &Vector3<f64>) -> f64 {
        (x - nearest_on_segment(x, &self.a, &self.b)).norm() - self.r
    }
}

/// The decision for one sphere in one cell, on an encoded field without certificates.
#[derive(Clone, Copy)]
struct Decide<'a> {
    field: Field<'a>,
    capsules: &'a [Capsule],
    cfg: &'a WorkspaceConfig,
    hint: Hint,
}

impl<'a> Decide<'a> {
    fn new(field: Field<'a>, capsules: &'a [Capsule], cfg: &'a WorkspaceConfig) -> Self {
        Decide {
            field,
            capsules,
            cfg,
            hint: Hint::default(),
        }
    }

    /// Appends to each cell's list the spheres from index `from` on that touch it, in order.
    fn list(&self, lists: &mut [Vec<u32>], spheres: &Spheres, from: usize) {
        for (i, s) in (from..).zip(spheres.iter_from(from)) {
            self.cells_touched(&s, |cell| lists[cell].push(i as u32));
        }
    }

    /// Cell (i, j, k) of a cell index ([`Field::cell_index`]).
    fn cell(&self, index: usize) -> [usize; 3] {
        let [_, ny, nz] = self.field.dims().map(|n| n - 1);
        [index / (ny * nz), (index / nz) % ny, index % nz]
    }

    /// Calls `visit` with each cell (index) the margin ball of `s` touches: those of its box's
    /// corners (per axis the cell of the lowest and of the highest corner, and every cell
    /// between), at most 8. A visitor, not a returned array of them: returned, the array went
    /// through the stack and its reads waited on its writes.
    #[inline]
    fn cells_touched(&self, s: &SphereSample, mut visit: impl FnMut(usize)) {
        let m = Vector3::repeat(self.cfg.certify_margin);
        let (a, b) = (
            self.field.cell_at(&(s.centre - m)),
            self.field.cell_at(&(s.centre + m)),
        );
        let mut n = 0;
        for i in a[0]..=b[0] {
            for j in a[1]..=b[1] {
                for k in a[2]..=b[2] {
                    if n < 8 {
                        visit(self.field.cell_index([i, j, k]) as usize);
                        n += 1;
                    }
                }
            }
        }
    }

    /// Decides sphere `s` in cell `cell` after the certificates `balls` of the spheres before
    /// it: certified by the cell's terms or one of those with the margin; or the capsule of its
    /// piece of path is added, and if that does not certify it, its own ball B(c, r + ε).
    fn sphere_in_cell(&mut self, s: &SphereSample, cell: usize, balls: &mut Vec<Cert>) {
        let m = self.cfg.certify_margin;
        let certified = |d: f64| d + s.radius <= -m;
        let c = self.cell(cell);
        // The lookup may stop at the first term that certifies the sphere.
        let mut d = self
            .field
            .distance_in_cell_upto(c, &s.centre, -m - s.radius, &mut self.hint);
        if !certified(d) {
            d = self.field.distance_in_cell(c, &s.centre);
        }
        for k in balls.iter() {
            if certified(d) {
                return;
            }
            d = d.min(k.distance(&s.centre));
        }
        if certified(d) {
            return;
        }
        let dilated = s.radius + self.cfg.epsilon;
        if let Some(piece) = self.capsules.get(s.capsule as usize)
            && let Some(k) = Cert::quantized(&piece.a, &piece.b, dilated - piece.loss)
            && certified(k.distance(&s.centre))
        {
            balls.push(k);
        } else if let Some(k) = Cert::quantized(&s.centre, &s.centre, dilated) {
            balls.push(k);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::exact::BallUnion;
    use crate::workspace::{REUSE_MARGIN, Sweep, build_field};
    use prf_shared::field::DistanceField;
    use prf_shared::se3::Pose;
    use rand::rngs::StdRng;
    use rand::{RngExt, SeedableRng};

    /// Two sweeping reaches of the example robot, the second shifted in phase.
    fn two_reaches(cfg: &WorkspaceConfig) -> Sweep {
        let model = prf_files::robot::example().unwrap();
        let mut sweep = Sweep::new(cfg.feature_spacing);
        for phase in [0.0, 0.15] {
            let arm: Vec<[f64; 7]> = (0..120)
                .map(|k| {
                    let t = k as f64 / 60.0;
                    core::array::from_fn(|j| phase + 0.4 * t * (1.0 + j as f64 / 7.0))
                })
                .collect();
            sweep.add_path(&model, &Pose::identity(), &arm, cfg.resample);
        }
        sweep
    }

    /// With a narrow margin and the default, every demonstrated sphere is certified at every
    /// point within the margin of its centre (field + r ≤ 0 at the centre and at random
    /// points inside the margin's sphere), and the field stays above the exact Ω+ there.
    #[test]
    fn every_sphere_is_certified_within_the_margin() {
        let mut rng = StdRng::seed_from_u64(3);
        for margin in [0.001, REUSE_MARGIN] {
            let cfg = WorkspaceConfig {
                certify_margin: margin,
                ..WorkspaceConfig::default()
            };
            let mut sweep = two_reaches(&cfg);
            let learned = build_field(&mut sweep, &cfg).unwrap();
            let field = learned.field();
            let exact = BallUnion::dilated(&sweep.spheres, cfg.epsilon);
            for s in sweep.spheres.iter() {
                for k in 0..4 {
                    let u = Vector3::from_fn(|_, _| rng.random_range(-1.0..1.0));
                    let x = if k == 0 {
                        s.centre
                    } else {
                        s.centre + u.normalize() * margin * rng.random_range(0.0..=1.0)
                    };
                    let d = field.distance(&x);
                    assert!(d + s.radius <= 1e-12, "{:?} at {x:?}: {d}", s);
                    assert!(d >= exact.distance(&x) - 1e-12, "not conservative at {x:?}");
                }
            }
        }
    }

    #[test]
    fn capsules_beyond_the_index_range_leave_their_certificates_out_and_are_counted() {
        // MAX_CAPSULES + 10 distinct capsules in cell 0, then the first one again in cell 1:
        // the first MAX_CAPSULES are stored, the 10 beyond are counted, and a capsule already
        // stored is still named after the overflow.
        let cert = |i: usize| {
            let a = Vector3::new((i % 256) as f64, (i / 256) as f64, 0.0) * CERT_UNIT;
            Cert::quantized(&a, &(a + Vector3::x() * 0.01), 0.05).unwrap()
        };
        let cells = vec![
            (0..MAX_CAPSULES + 10).map(cert).collect::<Vec<_>>(),
            vec![cert(0)],
        ];
        let (certificates, capsules, left_out) = records(&cells);
        assert_eq!(left_out, 10);
        assert_eq!(capsules.len(), MAX_CAPSULES * CAPSULE_BYTES);
        assert_eq!(certificates.len(), (MAX_CAPSULES + 1) * CERT_BYTES);
        let last = &certificates[certificates.len() - CERT_BYTES..];
        assert_eq!(last, [1, 0, 0, 0, 0, 0], "cell 1 names capsule 0");
    }
}
