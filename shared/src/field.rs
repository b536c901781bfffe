//! The learned safe workspace Ω+ of a location type as a conservative signed distance field
//! (Sec. 4.1), read in place from blob bytes.
//!
//! Layout: a grid of nodes with spacing h in the location frame, cut into bricks of
//! [`BRICK`]³ nodes. A brick is either stored (4 bytes per node) or uniform (one bound for all
//! its nodes, far outside Ω+). A stored node holds either
//! - a **feature ball** B(b, R) ⊆ Ω+: the dilated robot sphere that is deepest at the node
//!   (centre as an offset from the node in [`OFFSET_UNIT`] steps, radius in mm), or
//! - a **scalar** upper bound of the signed distance at the node (mm, rounded up).
//!
//! A few **certificates** per cell (sorted by cell, each naming one of the field's capsules)
//! add the demonstrated spheres that the node features alone would not certify, so every
//! demonstrated configuration is inside. A capsule is the set within R of a segment [a, b]:
//! the swept path of one robot sphere, straight within a fraction of a millimetre, dilated by
//! ε less that deviation (a ball when a = b). One capsule stands for the dozens of
//! demonstrated balls along it, and the cells its spheres reach share it.
//!
//! Lookup at x takes the minimum over the 8 corner nodes of the cell containing x (a feature
//! ball contributes its own signed distance |x − b| − R; a scalar s at node v contributes the
//! 1-Lipschitz bound s + |x − v|) and over the cell's certificate capsules (dist(x, [a, b]) −
//! R). Every term is an upper bound of the true signed distance of Ω+ (each ball and capsule
//! lies inside Ω+), so the field is **conservative**: it never reports a point deeper inside
//! Ω+ than it is. Quantization keeps this: offsets round to the nearest step and radii are
//! shrunk by the rounding error.
//!
//! Points outside the grid get d(p) + |x − p| with p the nearest point of the grid box.

use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

/// Nodes per brick edge.
pub const BRICK: usize = 2;
/// Nodes per brick.
pub const BRICK_NODES: usize = BRICK * BRICK * BRICK;
/// Bytes per stored node.
pub const NODE_BYTES: usize = 4;
/// Feature-ball centre offsets are stored in steps of this size, m (range ±127 steps).
pub const OFFSET_UNIT: f64 = 0.002;
/// Radii and scalar values are stored in mm.
pub const MM: f64 = 0.001;
/// Certificate-capsule coordinates and radii are stored in steps of this size, m (a quarter
/// millimetre: a capsule's rounding costs the reuse margin about half a millimetre; the
/// coordinates span ±8.19 m of the location frame).
pub const CERT_UNIT: f64 = 0.000_25;
/// Brick map entries at or above this are uniform bricks with value (entry − UNIFORM) mm.
pub const UNIFORM: u16 = 0x8000;
/// Margin kept from a cell's faces by the anchored lookup's first test, m: far above the
/// rounding of a point's cell coordinates (≈ 1e-15 m in a grid of metres).
pub const FACE_MARGIN: f64 = 1e-9;
/// Bytes per certificate: cell u32, capsule index u16.
pub const CERT_BYTES: usize = 6;
/// Bytes per capsule: end a i16×3, end b i16×3 (location frame) and radius u16, each in
/// [`CERT_UNIT`] steps.
pub const CAPSULE_BYTES: usize = 14;
/// Most capsules a field holds (the certificates' u16 index).
pub const MAX_CAPSULES: usize = u16::MAX as usize + 1;

/// A conservative signed distance field: never below the true signed distance (negative
/// inside the set).
pub trait DistanceField {
    /// Signed distance of `p`, m, never below the true one.
    fn distance(&self, p: &Vector3<f64>) -> f64;

    /// The distance at `p` if it is above `stop`; otherwise any upper bound of it that is at
    /// most `stop` (the lookup may stop at the first term that settles the comparison).
    /// `hint` carries what settled the previous lookup of the same moving point.
    fn distance_upto(&self, p: &Vector3<f64>, stop: f64, hint: &mut Hint) -> f64 {
        let _ = (stop, hint);
        self.distance(p)
    }

    /// How far a point may move from `p` while every later lookup of it with a stop ≥ `stop`
    /// is settled by `hint` without reading the field, returning [`Hint::settled`] and leaving
    /// `hint` as it is; 0 if that is not known. Call it after the lookup at `p` that
    /// left `hint`.
    fn settled_within(&self, p: &Vector3<f64>, stop: f64, hint: &Hint) -> f64 {
        let _ = (p, stop, hint);
        0.0
    }

    /// Whether [`DistanceField::settled_within`] may give any room at all (if not, callers
    /// need not bound how far their points move).
    fn settles_by_travel(&self) -> bool {
        false
    }
}

/// How lookups may be settled without reading the field.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Lookups {
    /// Every lookup reads the field (the benchmarks' first baseline).
    Full,
    /// A lookup may be settled by its hint's anchor ([`Hint`]).
    Anchored,
    /// As [`Lookups::Anchored`], and a caller that bounds how far a point moved may skip its
    /// lookup altogether while the anchor would settle it
    /// ([`DistanceField::settled_within`]; the default).
    Travelled,
}

/// Kept below the room [`DistanceField::settled_within`] gives, m: far above the rounding of
/// the centres and of the travel bounds (about 1e-13 m), far below any slack that matters.
pub const TRAVEL_MARGIN: f64 = 1e-9;

/// The lookup term that settled the last lookup of a point (a sphere centre along a
/// trajectory): its cell and term (1–8: a corner; 9 + i: certificate i; 0: none). The next
/// lookup tries it first if the point is still in that cell.
///
/// It also anchors that lookup: the term's exact value v at the point x_a and the `stop` s_a
/// it was settled against. Each term is 1-Lipschitz, so while the point stays in the cell and
/// within s_a − v of x_a the field there is still ≤ s_a, and a lookup with a stop ≥ s_a is
/// settled without reading the field. "In the cell" is first tested on the cell's box, kept
/// [`FACE_MARGIN`] inside its faces, before the cell is even computed. A hint belongs to one
/// field.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Hint {
    cell: u32,
    term: u32,
    /// x_a, the point of the anchoring lookup (location frame).
    anchor: Vector3<f64>,
    /// (s_a − v)², or 0 (no anchor).
    slack2: f64,
    /// The anchor cell's lowest node plus [`FACE_MARGIN`] on each axis: a point x with
    /// 0 < x − corner < h − 2 · [`FACE_MARGIN`] on every axis is in that cell.
    corner: Vector3<f64>,
    /// s_a.
    stop: f64,
}

impl Hint {
    /// What a lookup settled by the anchor returns: s_a.
    pub fn settled(&self) -> f64 {
        self.stop
    }
}

/// Serialized form of a field (postcard); the byte arrays are borrowed from the blob.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FieldData<'a> {
    /// Location-frame position of node (0, 0, 0), m.
    pub origin: [f32; 3],
    /// Node spacing h, m.
    pub voxel: f32,
    /// Nodes per axis, each a multiple of [`BRICK`].
    pub dims: [u16; 3],
    /// One u16 (little endian) per brick, x-major: stored brick index or uniform value.
    #[serde(borrow)]
    pub bricks: &'a [u8],
    /// Stored bricks, [`BRICK_NODES`] nodes of [`NODE_BYTES`] each, x-major inside a brick.
    #[serde(borrow)]
    pub nodes: &'a [u8],
    /// Certificates, [`CERT_BYTES`] each, sorted by cell index.
    #[serde(borrow)]
    pub certificates: &'a [u8],
    /// The capsules the certificates name, [`CAPSULE_BYTES`] each.
    #[serde(borrow)]
    pub capsules: &'a [u8],
}

/// Why field data was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FieldError {
    /// Non-finite origin, non-positive voxel, or dimensions not a multiple of the brick.
    Geometry,
    /// Byte array of the wrong length.
    Length,
    /// A brick map entry points past the stored bricks.
    BrickIndex {
        /// Index of the brick map entry.
        brick: usize,
    },
    /// Certificates not sorted by cell, a cell outside the grid, or a missing capsule.
    Certificates,
}

impl core::fmt::Display for FieldError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            FieldError::Geometry => write!(
                f,
                "workspace field geometry is invalid (non-finite origin, voxel not positive, or dimensions not whole bricks)"
            ),
            FieldError::Length => write!(f, "workspace field data has the wrong length"),
            FieldError::BrickIndex { brick } => write!(
                f,
                "workspace field brick map entry {brick} points past the stored bricks"
            ),
            FieldError::Certificates => write!(
                f,
                "workspace field certificates are not sorted by cell, lie outside the grid or name a capsule that is not there"
            ),
        }
    }
}

impl core::error::Error for FieldError {}

/// A validated field, reading its arrays in place.
#[derive(Clone, Copy, Debug)]
pub struct Field<'a> {
    origin: Vector3<f64>,
    h: f64,
    inv_h: f64,
    /// Location-frame position of the last node.
    top: Vector3<f64>,
    /// h − 2 · [`FACE_MARGIN`]: a cell's box as [`Hint`] tests it.
    span: f64,
    dims: [usize; 3],
    bricks_per_axis: [usize; 3],
    bricks: &'a [u8],
    nodes: &'a [u8],
    certificates: &'a [u8],
    capsules: &'a [u8],
    /// Whether lookups may be settled by their hint's anchor (see [`Hint`]).
    anchored: bool,
    /// Whether [`DistanceField::settled_within`] gives any room.
    travelled: bool,
}

/// |x − b| − r, or `stop` when that is at most `stop` (decided on squared distances, without
/// a square root).
#[inline]
fn ball_bound(x: &Vector3<f64>, b: &Vector3<f64>, r: f64, stop: f64) -> f64 {
    let reach = stop + r;
    let d2 = (x - b).norm_squared();
    if reach >= 0.0 && d2 <= reach * reach {
        stop
    } else {
        crate::float::sqrt(d2) - r
    }
}

/// The point of segment [a, b] nearest to x (a when a = b).
#[inline]
pub fn nearest_on_segment(x: &Vector3<f64>, a: &Vector3<f64>, b: &Vector3<f64>) -> Vector3<f64> {
    let e = b - a;
    let ee = e.norm_squared();
    let t = (x - a).dot(&e);
    if t <= 0.0 || ee == 0.0 {
        *a
    } else if t >= ee {
        *b
    } else {
        a + e * (t / ee)
    }
}

enum Node {
    Ball(Vector3<f64>, f64),
    Scalar(f64),
}

impl<'a> Field<'a> {
    /// Validates sizes and indices once, so lookups need no checks that could fail.
    pub fn new(d: &FieldData<'a>) -> Result<Self, FieldError> {
        let origin = Vector3::new(d.origin[0] as f64, d.origin[1] as f64, d.origin[2] as f64);
        let h = d.voxel as f64;
        let dims = d.dims.map(|n| n as usize);
        if !(origin.iter().all(|v| v.is_finite()) && h > 0.0 && h.is_finite())
            || dims.iter().any(|&n| n < BRICK || !n.is_multiple_of(BRICK))
        {
            return Err(FieldError::Geometry);
        }
        let bricks_per_axis = dims.map(|n| n / BRICK);
        let n_bricks: usize = bricks_per_axis.iter().product();
        if d.bricks.len() != 2 * n_bricks
            || !d.nodes.len().is_multiple_of(BRICK_NODES * NODE_BYTES)
            || !d.certificates.len().is_multiple_of(CERT_BYTES)
            || !d.capsules.len().is_multiple_of(CAPSULE_BYTES)
            || d.capsules.len() > MAX_CAPSULES * CAPSULE_BYTES
        {
            return Err(FieldError::Length);
        }
        let stored = d.nodes.len() / (BRICK_NODES * NODE_BYTES);
        for b in 0..n_bricks {
            let e = u16::from_le_bytes([d.bricks[2 * b], d.bricks[2 * b + 1]]);
            if e < UNIFORM && e as usize >= stored {
                return Err(FieldError::BrickIndex { brick: b });
            }
        }
        let cells: usize = dims.iter().map(|n| n - 1).product();
        let capsules = d.capsules.len() / CAPSULE_BYTES;
        let mut last = 0u32;
        for c in d.certificates.chunks_exact(CERT_BYTES) {
            let cell = u32::from_le_bytes([c[0], c[1], c[2], c[3]]);
            let capsule = u16::from_le_bytes([c[4], c[5]]) as usize;
            if cell < last || cell as usize >= cells || capsule >= capsules {
                return Err(FieldError::Certificates);
            }
            last = cell;
        }
        let top = origin
            + Vector3::new(
                (dims[0] - 1) as f64,
                (dims[1] - 1) as f64,
                (dims[2] - 1) as f64,
            ) * h;
        Ok(Field {
            origin,
            h,
            inv_h: 1.0 / h,
            top,
            span: h - 2.0 * FACE_MARGIN,
            dims,
            bricks_per_axis,
            bricks: d.bricks,
            nodes: d.nodes,
            certificates: d.certificates,
            capsules: d.capsules,
            anchored: true,
            travelled: true,
        })
    }

    /// The same field with other [`Lookups`] (the default is [`Lookups::Travelled`]); the
    /// values that decide a risk are the same with each.
    pub fn lookups(self, lookups: Lookups) -> Self {
        Field {
            anchored: lookups != Lookups::Full,
            travelled: lookups == Lookups::Travelled,
            ..self
        }
    }

    /// Node spacing h, m.
    pub fn voxel(&self) -> f64 {
        self.h
    }

    /// Nodes per axis.
    pub fn dims(&self) -> [usize; 3] {
        self.dims
    }

    /// Number of stored bricks, of certificates and of capsules.
    pub fn counts(&self) -> (usize, usize, usize) {
        (
            self.nodes.len() / (BRICK_NODES * NODE_BYTES),
            self.certificates.len() / CERT_BYTES,
            self.capsules.len() / CAPSULE_BYTES,
        )
    }

    /// Location-frame position of node (i, j, k).
    pub fn node_position(&self, i: usize, j: usize, k: usize) -> Vector3<f64> {
        self.origin + Vector3::new(i as f64, j as f64, k as f64) * self.h
    }

    fn node(&self, i: usize, j: usize, k: usize) -> Node {
        let (bi, bj, bk) = (i / BRICK, j / BRICK, k / BRICK);
        let b = (bi * self.bricks_per_axis[1] + bj) * self.bricks_per_axis[2] + bk;
        let e = u16::from_le_bytes([self.bricks[2 * b], self.bricks[2 * b + 1]]);
        if e >= UNIFORM {
            return Node::Scalar((e - UNIFORM) as f64 * MM);
        }
        let local = ((i % BRICK) * BRICK + j % BRICK) * BRICK + k % BRICK;
        let at = (e as usize * BRICK_NODES + local) * NODE_BYTES;
        let n = &self.nodes[at..at + NODE_BYTES];
        if n[3] == 0 {
            Node::Scalar(i16::from_le_bytes([n[0], n[1]]) as f64 * MM)
        } else {
            let off = Vector3::new(n[0] as i8 as f64, n[1] as i8 as f64, n[2] as i8 as f64);
            Node::Ball(
                self.node_position(i, j, k) + off * OFFSET_UNIT,
                n[3] as f64 * MM,
            )
        }
    }

    /// Upper bound of the signed distance at x contributed by node (i, j, k).
    ///
    /// When the bound is at most `stop`, `stop` itself may be returned (decided on squared
    /// distances, without a square root).
    fn node_bound(&self, i: usize, j: usize, k: usize, x: &Vector3<f64>, stop: f64) -> f64 {
        match self.node(i, j, k) {
            Node::Ball(b, r) => ball_bound(x, &b, r, stop),
            Node::Scalar(s) => s + crate::float::norm(&(x - self.node_position(i, j, k))),
        }
    }

    /// Number of certificates.
    fn certificate_count(&self) -> usize {
        self.certificates.len() / CERT_BYTES
    }

    /// Cell of certificate `i` (< count).
    fn certificate_cell(&self, i: usize) -> u32 {
        let c = &self.certificates[i * CERT_BYTES..];
        u32::from_le_bytes([c[0], c[1], c[2], c[3]])
    }

    /// First certificate of cell `cell` or later (binary search in the sorted list).
    fn first_certificate(&self, cell: u32) -> usize {
        let (mut lo, mut hi) = (0, self.certificate_count());
        while lo < hi {
            let mid = (lo + hi) / 2;
            if self.certificate_cell(mid) < cell {
                lo = mid + 1;
            } else {
                hi = mid;
            }
        }
        lo
    }

    /// Term of certificate `i` at `x`, dist(x, [a, b]) − R of its capsule (`stop` as in
    /// [`Field::node_bound`]).
    fn certificate_bound(&self, i: usize, x: &Vector3<f64>, stop: f64) -> f64 {
        let c = &self.certificates[i * CERT_BYTES..(i + 1) * CERT_BYTES];
        let (a, b, r) = self.capsule(u16::from_le_bytes([c[4], c[5]]) as usize);
        ball_bound(x, &nearest_on_segment(x, &a, &b), r, stop)
    }

    /// Capsule `i` (< count): its ends a and b and its radius, m.
    pub fn capsule(&self, i: usize) -> (Vector3<f64>, Vector3<f64>, f64) {
        let c = &self.capsules[i * CAPSULE_BYTES..(i + 1) * CAPSULE_BYTES];
        let v = |o: usize| i16::from_le_bytes([c[o], c[o + 1]]) as f64 * CERT_UNIT;
        (
            Vector3::new(v(0), v(2), v(4)),
            Vector3::new(v(6), v(8), v(10)),
            u16::from_le_bytes([c[12], c[13]]) as f64 * CERT_UNIT,
        )
    }

    /// Cell containing the grid-box point with grid coordinates `g`.
    fn cell_of(&self, g: &Vector3<f64>) -> [usize; 3] {
        // Truncation is floor for g ≥ 0; below 0 (and NaN) clamps to cell 0, above to the last
        // cell. Clamped before the conversion, which is then one instruction (a saturating
        // float-to-usize conversion is a branchy sequence on x86-64).
        core::array::from_fn(|a| {
            let last = self.dims[a] - 2;
            if g[a] > 0.0 {
                g[a].min(last as f64) as u32 as usize
            } else {
                0
            }
        })
    }

    /// The lookup terms of cell `c` (its 8 corner nodes and its certificates) evaluated at
    /// `x`: an upper bound of the signed distance at any `x`, the field's value for `x` in
    /// the cell. `c` must be a cell of the grid (from [`Field::cell_at`]).
    pub fn distance_in_cell(&self, c: [usize; 3], x: &Vector3<f64>) -> f64 {
        self.distance_in_cell_upto(c, x, f64::NEG_INFINITY, &mut Hint::default())
    }

    /// Term `term` of cell `c` ([`Hint`] numbering) at `x`; ∞ for a term the cell lacks.
    fn term(&self, c: [usize; 3], cell: u32, term: u32, x: &Vector3<f64>, stop: f64) -> f64 {
        match term {
            1..=8 => {
                let d = (term - 1) as usize;
                self.node_bound(
                    c[0] + (d >> 2 & 1),
                    c[1] + (d >> 1 & 1),
                    c[2] + (d & 1),
                    x,
                    stop,
                )
            }
            9.. => {
                let i = (term - 9) as usize;
                if i < self.certificate_count() && self.certificate_cell(i) == cell {
                    self.certificate_bound(i, x, stop)
                } else {
                    f64::INFINITY
                }
            }
            0 => f64::INFINITY,
        }
    }

    /// [`Field::distance_in_cell`], stopping at the first term ≤ `stop`: the hinted term
    /// first, then the corners nearest first, then the certificates.
    pub fn distance_in_cell_upto(
        &self,
        c: [usize; 3],
        x: &Vector3<f64>,
        stop: f64,
        hint: &mut Hint,
    ) -> f64 {
        let cell = self.cell_index(c);
        if hint.cell == cell && hint.term != 0 {
            let v = self.term(c, cell, hint.term, x, stop);
            if v <= stop {
                return v;
            }
        }
        let g = (x - self.node_position(c[0], c[1], c[2])) * self.inv_h;
        let near = (usize::from(g.x >= 0.5) << 2)
            | (usize::from(g.y >= 0.5) << 1)
            | usize::from(g.z >= 0.5);
        let mut best = f64::INFINITY;
        for k in 0..8 {
            let term = ((k ^ near) + 1) as u32;
            best = best.min(self.term(c, cell, term, x, stop));
            if best <= stop {
                *hint = Hint {
                    cell,
                    term,
                    ..Hint::default()
                };
                return best;
            }
        }
        let n = self.certificate_count();
        let mut i = self.first_certificate(cell);
        while i < n && self.certificate_cell(i) == cell {
            best = best.min(self.certificate_bound(i, x, stop));
            if best <= stop {
                *hint = Hint {
                    cell,
                    term: 9 + i as u32,
                    ..Hint::default()
                };
                return best;
            }
            i += 1;
        }
        best
    }

    /// A lower bound of the field's value anywhere within `delta` of `p` (location frame): the
    /// smallest lookup term, at `p`, of every cell the lookup of such a point can use, less
    /// `delta` (every term is 1-Lipschitz; outside the grid box the lookup adds the distance to
    /// the box, and clamping to the box moves no point farther). NaN input gives NaN.
    pub fn distance_lower_within(&self, p: &Vector3<f64>, delta: f64) -> f64 {
        let q = p.sup(&self.origin).inf(&self.top);
        if !(q.iter().all(|v| v.is_finite()) && delta >= 0.0) {
            return f64::NAN;
        }
        let d = Vector3::repeat(delta);
        let lo = self.cell_of(&((q - d - self.origin) * self.inv_h));
        let hi = self.cell_of(&((q + d - self.origin) * self.inv_h));
        let mut best = f64::INFINITY;
        for i in lo[0]..=hi[0] {
            for j in lo[1]..=hi[1] {
                for k in lo[2]..=hi[2] {
                    best = best.min(self.distance_in_cell([i, j, k], p));
                }
            }
        }
        best - delta
    }

    /// Linear index of cell (i, j, k).
    pub fn cell_index(&self, c: [usize; 3]) -> u32 {
        ((c[0] * (self.dims[1] - 1) + c[1]) * (self.dims[2] - 1) + c[2]) as u32
    }

    /// Cell containing location-frame point `x` (clamped to the grid).
    pub fn cell_at(&self, x: &Vector3<f64>) -> [usize; 3] {
        self.cell_of(&((x - self.origin) * self.inv_h))
    }
}

impl DistanceField for Field<'_> {
    /// Conservative signed distance at `p` (location frame), m. NaN input gives NaN.
    fn distance(&self, p: &Vector3<f64>) -> f64 {
        self.distance_upto(p, f64::NEG_INFINITY, &mut Hint::default())
    }

    /// The two anchored tests inline (most lookups along a trajectory end there); the rest
    /// in `Field::lookup_in` (inside the grid) and `Field::lookup_outside`.
    #[inline]
    fn distance_upto(&self, p: &Vector3<f64>, stop: f64, hint: &mut Hint) -> f64 {
        if self.anchored && hint.stop <= stop && (p - hint.anchor).norm_squared() < hint.slack2 {
            // Within the anchor's slack, and in its cell's box (the test below, before the
            // cell).
            let x = p - hint.corner;
            if (0..3).all(|a| x[a] > 0.0 && x[a] < self.span) {
                return hint.stop;
            }
        }
        let inside = (0..3).all(|a| p[a] >= self.origin[a] && p[a] <= self.top[a]);
        if !inside {
            return self.lookup_outside(p, stop, hint);
        }
        let c = self.cell_at(p);
        let cell = self.cell_index(c);
        if self.anchored
            && hint.cell == cell
            && hint.stop <= stop
            && (p - hint.anchor).norm_squared() < hint.slack2
        {
            return hint.stop;
        }
        self.lookup_in(c, cell, p, stop, hint)
    }

    fn settles_by_travel(&self) -> bool {
        self.travelled
    }

    /// The room the first anchored test leaves around `p`: the anchor's slack less the
    /// distance from the anchor, and the distance to the faces of the box it tests.
    fn settled_within(&self, p: &Vector3<f64>, stop: f64, hint: &Hint) -> f64 {
        if !(self.travelled && hint.slack2 > 0.0 && hint.stop <= stop) {
            return 0.0;
        }
        let x = p - hint.corner;
        let mut room = crate::float::sqrt(hint.slack2) - crate::float::norm(&(p - hint.anchor));
        // A NaN point makes every term NaN, and the room 0.
        let lesser = |a: f64, b: f64| if a < b { a } else { b };
        for a in 0..3 {
            room = lesser(lesser(room, x[a]), self.span - x[a]);
        }
        let room = room - TRAVEL_MARGIN;
        if room > 0.0 { room } else { 0.0 }
    }
}

impl Field<'_> {
    /// [`DistanceField::distance_upto`] at `p` inside the grid, in cell `c` (index `cell`),
    /// past the anchored tests: the cell's terms, then the anchor renewed.
    #[inline(never)]
    fn lookup_in(
        &self,
        c: [usize; 3],
        cell: u32,
        p: &Vector3<f64>,
        stop: f64,
        hint: &mut Hint,
    ) -> f64 {
        let v = self.distance_in_cell_upto(c, p, stop, hint);
        if self.anchored && v <= stop && hint.cell == cell && hint.term != 0 {
            let exact = self.term(c, cell, hint.term, p, f64::NEG_INFINITY);
            let slack = stop - exact;
            (hint.anchor, hint.stop) = (*p, stop);
            hint.slack2 = if slack > 0.0 { slack * slack } else { 0.0 };
            hint.corner = self.node_position(c[0], c[1], c[2]).add_scalar(FACE_MARGIN);
        }
        v
    }

    /// [`DistanceField::distance_upto`] outside the grid box (or NaN): the nearest box
    /// point's value plus the distance to it.
    #[inline(never)]
    fn lookup_outside(&self, p: &Vector3<f64>, stop: f64, hint: &mut Hint) -> f64 {
        let q = p.sup(&self.origin).inf(&self.top);
        let outside = crate::float::norm(&(p - q));
        if !outside.is_finite() {
            return f64::NAN;
        }
        hint.slack2 = 0.0;
        self.distance_in_cell_upto(self.cell_at(&q), &q, stop - outside, hint) + outside
    }
}
