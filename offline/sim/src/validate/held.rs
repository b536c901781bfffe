//! The held part in the ground truth: while the gripper holds it, the part's geometry at its
//! grasp against the true boxes, reported apart from the robot's clearance.
//!
//! A part is picked from a surface and put down on one, so it touches those boxes (its
//! supports: the boxes within [`SUPPORT_GAP`] of the part's base centre where it was picked or
//! put down). Against its supports the part's own surface (points on its faces,
//! at most 20 mm apart) must not sink in; against every other box, and the floor, its
//! covering spheres ([`HeldPart`], at most 15 mm beyond a face) keep a clearance.

use crate::navigation::{PartTracker, tcp_world};
use crate::world::geometry::{Cell, HeldPart, Obstacle};
use nalgebra::Vector3;
use prf_files::dataset::Sample;
use prf_shared::NA;
use prf_shared::se3::{Pose, wrap};

/// A box is a support of a rest pose when the part's base centre is within this distance of
/// its surface (resting on its top face, or sunk into it), m.
pub const SUPPORT_GAP: f64 = 0.01;

/// How far the part's surface may sink into a support before it counts, m (numerical
/// rounding of poses read from files).
pub const SINK_TOLERANCE: f64 = 1e-6;

/// Points on the part's faces are at most this far apart, m.
const SURFACE_STEP: f64 = 0.02;

/// The held part's clearances along a program.
#[derive(Clone, Debug, PartialEq)]
pub struct PartReport {
    /// Smallest clearance of the part's spheres to a box other than its supports, or to the
    /// floor, m (∞ if never held); when, and against what.
    pub min: f64,
    pub min_t: f64,
    pub obstacle: String,
    /// Smallest signed distance of the part's surface to a support, m: 0 where it rests on it,
    /// negative where it sinks in; when, and which support.
    pub support: f64,
    pub support_t: f64,
    pub support_name: String,
    /// Configurations evaluated with the part held.
    pub configurations: usize,
}

/// The boxes the part rests on at `pose` (frame at the centre of its base).
fn supports<'c>(cell: &'c Cell, pose: &Pose) -> Vec<&'c Obstacle> {
    let base = pose.translation.vector;
    cell.obstacles
        .iter()
        .filter(|o| o.signed_distance(&base).abs() <= SUPPORT_GAP)
        .collect()
}

/// Points on the faces of a box of `size` (frame at its base centre).
fn surface_points(size: [f64; 3]) -> Vec<Vector3<f64>> {
    let n = size.map(|s| (s / SURFACE_STEP).ceil().max(1.0) as usize);
    let at = |axis: usize, i: usize| {
        let u = i as f64 / n[axis] as f64;
        if axis == 2 {
            u * size[2]
        } else {
            (u - 0.5) * size[axis]
        }
    };
    let mut pts = Vec::new();
    for i in 0..=n[0] {
        for j in 0..=n[1] {
            for k in 0..=n[2] {
                let on_face = i == 0 || i == n[0] || j == 0 || j == n[1] || k == 0 || k == n[2];
                if on_face {
                    pts.push(Vector3::new(at(0, i), at(1, j), at(2, k)));
                }
            }
        }
    }
    pts
}

/// One holding interval: the samples it spans, its part geometry and supports.
struct Holding<'c> {
    samples: core::ops::Range<usize>,
    part: HeldPart,
    grasp: Pose,
    supports: Vec<&'c Obstacle>,
}

/// The intervals in which `tracker`'s part is held along `samples`, with the boxes it rests on
/// where it is picked up and where it is put down.
fn holdings<'c>(cell: &'c Cell, samples: &[Sample], mut tracker: PartTracker) -> Vec<Holding<'c>> {
    let mut out = Vec::new();
    let mut start: Option<(usize, Pose)> = None;
    for (i, s) in samples.iter().enumerate() {
        let was = tracker.holding();
        let from = *tracker.rest_pose();
        tracker.update(s.gripper, || tcp_world(&cell.model, s.base, &s.arm));
        match (was, tracker.holding()) {
            (false, true) => start = Some((i, from)),
            (true, false) => {
                if let Some((first, picked)) = start.take() {
                    out.push((first..i, picked, Some(*tracker.rest_pose())));
                }
            }
            _ => {}
        }
    }
    if let Some((first, picked)) = start {
        out.push((first..samples.len(), picked, None));
    }
    out.into_iter()
        .map(|(range, picked, placed)| {
            let s = &samples[range.start];
            let grasp = picked.inverse() * tcp_world(&cell.model, s.base, &s.arm);
            let mut sup = supports(cell, &picked);
            if let Some(p) = placed {
                sup.extend(supports(cell, &p));
            }
            sup.dedup_by(|a, b| std::ptr::eq(*a, *b));
            Holding {
                samples: range,
                part: HeldPart::new(tracker.size(), &grasp),
                grasp,
                supports: sup,
            }
        })
        .collect()
}

/// Checks the part `tracker` follows (from its start pose, picked up when the gripper closes)
/// along `samples`, re-sampling between samples so that no part sphere moves more than
/// `resolution` (m) between checks.
pub fn check_held_part(
    cell: &Cell,
    samples: &[Sample],
    tracker: PartTracker,
    resolution: f64,
) -> PartReport {
    let size = tracker.size();
    let surface = surface_points(size);
    let mut r = PartReport {
        min: f64::INFINITY,
        min_t: 0.0,
        obstacle: String::new(),
        support: f64::INFINITY,
        support_t: 0.0,
        support_name: String::new(),
        configurations: 0,
    };
    for h in holdings(cell, samples, tracker) {
        let to_part = h.grasp.inverse();
        // The part's spheres (world) with the TCP at `tcp`.
        let spheres_at = |tcp: &Pose| {
            h.part
                .spheres
                .iter()
                .map(|(c, rad)| (tcp.transform_point(&(*c).into()).coords, *rad))
                .collect::<Vec<_>>()
        };
        let eval = |t: f64, base: [f64; 3], arm: &[f64; NA], r: &mut PartReport| {
            r.configurations += 1;
            let tcp = tcp_world(&cell.model, base, arm);
            let spheres = spheres_at(&tcp);
            for (c, rad) in &spheres {
                if c.z - rad < r.min {
                    (r.min, r.min_t, r.obstacle) = (c.z - rad, t, "floor".into());
                }
            }
            let part_pose = tcp * to_part;
            for o in cell.obstacles_near(base) {
                if h.supports.iter().any(|s| std::ptr::eq(*s, o)) {
                    for p in &surface {
                        let d = o.signed_distance(&part_pose.transform_point(&(*p).into()).coords);
                        if d < r.support {
                            (r.support, r.support_t, r.support_name) = (d, t, o.name.clone());
                        }
                    }
                } else {
                    for (c, rad) in &spheres {
                        let d = o.signed_distance(c) - rad;
                        if d < r.min {
                            (r.min, r.min_t, r.obstacle) = (d, t, o.name.clone());
                        }
                    }
                }
            }
        };
        for i in h.samples.clone() {
            let s = &samples[i];
            let Some(next) = samples.get(i + 1).filter(|_| i + 1 < h.samples.end) else {
                eval(s.t, s.base, &s.arm, &mut r);
                continue;
            };
            let tcp = |x: &Sample| tcp_world(&cell.model, x.base, &x.arm);
            let (a, b) = (spheres_at(&tcp(s)), spheres_at(&tcp(next)));
            let moved = a
                .iter()
                .zip(&b)
                .map(|((p, _), (q, _))| (p - q).norm())
                .fold(0.0, f64::max);
            // Joint-space interpolation bends the Cartesian path: half the resolution.
            let n = ((2.0 * moved / resolution).ceil() as usize).max(1);
            for k in 0..n {
                let u = k as f64 / n as f64;
                let lerp = |x: f64, y: f64| x + (y - x) * u;
                let mut base: [f64; 3] = std::array::from_fn(|m| lerp(s.base[m], next.base[m]));
                base[2] = s.base[2] + wrap(next.base[2] - s.base[2]) * u;
                let arm = std::array::from_fn(|m| lerp(s.arm[m], next.arm[m]));
                eval(lerp(s.t, next.t), base, &arm, &mut r);
            }
        }
    }
    r
}
