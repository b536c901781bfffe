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
//! A few **certificate balls** per cell (sorted by cell) add the demonstrated spheres that
//! the node features alone would not certify, so every demonstrated configuration is inside.
//!
//! Lookup at x takes the minimum over the 8 corner nodes of the cell containing x (a feature
//! ball contributes its own signed distance |x − b| − R; a scalar s at node v contributes the
//! 1-Lipschitz bound s + |x − v|) and over the cell's certificate balls. Every term is an
//! upper bound of the true signed distance of Ω+ (each ball lies inside Ω+), so the field is
//! **conservative**: it never reports a point deeper inside Ω+ than it is. Quantization keeps
//! this: offsets round to the nearest step and radii are shrunk by the rounding error.
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
/// Radii, scalar values and certificate-ball coordinates are stored in mm.
pub const MM: f64 = 0.001;
/// Brick map entries at or above this are uniform bricks with value (entry − UNIFORM) mm.
pub const UNIFORM: u16 = 0x8000;
/// Bytes per certificate ball: cell u32, centre i16×3 (mm, location frame), radius u16 mm.
pub const CERT_BYTES: usize = 12;

/// A conservative signed distance field: never below the true signed distance (negative
/// inside the set).
pub trait DistanceField {
    fn distance(&self, p: &Vector3<f64>) -> f64;
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
    /// Certificate balls, [`CERT_BYTES`] each, sorted by cell index.
    #[serde(borrow)]
    pub certificates: &'a [u8],
}

/// Why field data was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FieldError {
    /// Non-finite origin, non-positive voxel, or dimensions not a multiple of the brick.
    Geometry,
    /// Byte array of the wrong length.
    Length,
    /// A brick map entry points past the stored bricks.
    BrickIndex { brick: usize },
    /// Certificate balls not sorted by cell, or a cell outside the grid.
    Certificates,
}

/// A validated field, reading its arrays in place.
#[derive(Clone, Copy, Debug)]
pub struct Field<'a> {
    origin: Vector3<f64>,
    h: f64,
    dims: [usize; 3],
    bricks_per_axis: [usize; 3],
    bricks: &'a [u8],
    nodes: &'a [u8],
    certificates: &'a [u8],
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
        let mut last = 0u32;
        for c in d.certificates.chunks_exact(CERT_BYTES) {
            let cell = u32::from_le_bytes([c[0], c[1], c[2], c[3]]);
            if cell < last || cell as usize >= cells {
                return Err(FieldError::Certificates);
            }
            last = cell;
        }
        Ok(Field {
            origin,
            h,
            dims,
            bricks_per_axis,
            bricks: d.bricks,
            nodes: d.nodes,
            certificates: d.certificates,
        })
    }

    /// Node spacing h, m.
    pub fn voxel(&self) -> f64 {
        self.h
    }

    /// Nodes per axis.
    pub fn dims(&self) -> [usize; 3] {
        self.dims
    }

    /// Number of stored bricks and of certificate balls.
    pub fn counts(&self) -> (usize, usize) {
        (
            self.nodes.len() / (BRICK_NODES * NODE_BYTES),
            self.certificates.len() / CERT_BYTES,
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
    fn node_bound(&self, i: usize, j: usize, k: usize, x: &Vector3<f64>) -> f64 {
        match self.node(i, j, k) {
            Node::Ball(b, r) => (x - b).norm() - r,
            Node::Scalar(s) => s + (x - self.node_position(i, j, k)).norm(),
        }
    }

    /// The certificate balls of cell `cell` (binary search in the sorted list).
    fn certificate_bound(&self, cell: u32, x: &Vector3<f64>) -> f64 {
        let n = self.certificates.len() / CERT_BYTES;
        let key = |i: usize| {
            let c = &self.certificates[i * CERT_BYTES..];
            u32::from_le_bytes([c[0], c[1], c[2], c[3]])
        };
        let (mut lo, mut hi) = (0, n);
        while lo < hi {
            let mid = (lo + hi) / 2;
            if key(mid) < cell {
                lo = mid + 1;
            } else {
                hi = mid;
            }
        }
        let mut best = f64::INFINITY;
        let mut i = lo;
        while i < n && key(i) == cell {
            let c = &self.certificates[i * CERT_BYTES..(i + 1) * CERT_BYTES];
            let v = |o: usize| i16::from_le_bytes([c[o], c[o + 1]]) as f64 * MM;
            let centre = Vector3::new(v(4), v(6), v(8));
            let r = u16::from_le_bytes([c[10], c[11]]) as f64 * MM;
            best = best.min((x - centre).norm() - r);
            i += 1;
        }
        best
    }

    /// Cell containing the grid-box point with grid coordinates `g`.
    fn cell_of(&self, g: &Vector3<f64>) -> [usize; 3] {
        core::array::from_fn(|a| {
            let c = libm::floor(g[a]);
            (if c > 0.0 { c as usize } else { 0 }).min(self.dims[a] - 2)
        })
    }

    /// The lookup terms of cell `c` (its 8 corner nodes and its certificates) evaluated at
    /// `x`: an upper bound of the signed distance at any `x`, the field's value for `x` in
    /// the cell. `c` must be a cell of the grid (from [`Field::cell_at`]).
    pub fn distance_in_cell(&self, c: [usize; 3], x: &Vector3<f64>) -> f64 {
        let mut best = f64::INFINITY;
        for di in 0..2 {
            for dj in 0..2 {
                for dk in 0..2 {
                    best = best.min(self.node_bound(c[0] + di, c[1] + dj, c[2] + dk, x));
                }
            }
        }
        if !self.certificates.is_empty() {
            best = best.min(self.certificate_bound(self.cell_index(c), x));
        }
        best
    }

    /// Linear index of cell (i, j, k).
    pub fn cell_index(&self, c: [usize; 3]) -> u32 {
        ((c[0] * (self.dims[1] - 1) + c[1]) * (self.dims[2] - 1) + c[2]) as u32
    }

    /// Cell containing location-frame point `x` (clamped to the grid).
    pub fn cell_at(&self, x: &Vector3<f64>) -> [usize; 3] {
        self.cell_of(&((x - self.origin) / self.h))
    }
}

impl DistanceField for Field<'_> {
    /// Conservative signed distance at `p` (location frame), m. NaN input gives NaN.
    fn distance(&self, p: &Vector3<f64>) -> f64 {
        let hi = self.origin
            + Vector3::new(
                (self.dims[0] - 1) as f64,
                (self.dims[1] - 1) as f64,
                (self.dims[2] - 1) as f64,
            ) * self.h;
        let q = p.sup(&self.origin).inf(&hi);
        let outside = (p - q).norm();
        if !outside.is_finite() {
            return f64::NAN;
        }
        let c = self.cell_of(&((q - self.origin) / self.h));
        self.distance_in_cell(c, &q) + outside
    }
}
