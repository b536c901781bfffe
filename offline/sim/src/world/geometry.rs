//! Ground-truth clearance of the robot in a world: sphere-vs-box distances for the arm and
//! gripper, prism-vs-prism distances for the platform, the floor, and self-collision.
//!
//! Location boxes and the platform are vertical prisms rotated about z only (floor-standing
//! machines, a platform driving on the floor), so box-vs-box distance reduces exactly to a 2-D
//! rectangle distance combined with the gap of the z intervals.

use super::World;
use nalgebra::{Vector2, Vector3};
use prf_shared::kinematics::{ArmKinematics, arm_base_pose};
use prf_shared::robot::{N_FRAMES, RobotModel};
use prf_shared::se3::Pose;
use prf_shared::{JointVector, NA};

/// Signed distance from `p` to the axis-aligned box of half extents `half` centred at the
/// origin: negative inside.
pub fn box_signed_distance(p: &Vector3<f64>, half: &Vector3<f64>) -> f64 {
    let d = p.abs() - half;
    let outside = d.sup(&Vector3::zeros()).norm();
    let inside = d.max().min(0.0);
    outside + inside
}

/// An obstacle box of a location, in the world: centre, yaw about z, half extents.
#[derive(Clone, Debug)]
pub struct Obstacle {
    /// Index of the location it belongs to.
    pub location: usize,
    /// `CNC1/front_sill`, for messages.
    pub name: String,
    centre: Vector3<f64>,
    cos: f64,
    sin: f64,
    half: Vector3<f64>,
}

impl Obstacle {
    /// A box given by its centre, yaw and half extents in the world.
    pub fn new(
        location: usize,
        name: String,
        centre: Vector3<f64>,
        yaw: f64,
        half: Vector3<f64>,
    ) -> Self {
        Obstacle {
            location,
            name,
            centre,
            cos: yaw.cos(),
            sin: yaw.sin(),
            half,
        }
    }

    fn to_local(&self, p: &Vector3<f64>) -> Vector3<f64> {
        let d = p - self.centre;
        Vector3::new(
            self.cos * d.x + self.sin * d.y,
            -self.sin * d.x + self.cos * d.y,
            d.z,
        )
    }

    /// Signed distance from a world point to the box.
    pub fn signed_distance(&self, p: &Vector3<f64>) -> f64 {
        box_signed_distance(&self.to_local(p), &self.half)
    }

    /// Radius of the sphere about the centre that contains the box (for culling).
    fn bounding_radius(&self) -> f64 {
        self.half.norm()
    }

    /// Corners of the box's footprint on the floor (counter-clockwise).
    pub fn footprint(&self) -> [Vector2<f64>; 4] {
        rectangle(self.centre.xy(), self.cos, self.sin, self.half.xy())
    }

    fn z_range(&self) -> (f64, f64) {
        (self.centre.z - self.half.z, self.centre.z + self.half.z)
    }
}

fn rectangle(c: Vector2<f64>, cos: f64, sin: f64, h: Vector2<f64>) -> [Vector2<f64>; 4] {
    let ex = Vector2::new(cos, sin) * h.x;
    let ey = Vector2::new(-sin, cos) * h.y;
    [c + ex + ey, c - ex + ey, c - ex - ey, c + ex - ey]
}

/// Distance between two convex quadrilaterals (0 if they overlap).
fn polygon_distance(a: &[Vector2<f64>; 4], b: &[Vector2<f64>; 4]) -> f64 {
    if convex_overlap(a, b) {
        return 0.0;
    }
    let mut best = f64::INFINITY;
    for (p, q) in [(a, b), (b, a)] {
        for v in p {
            for k in 0..4 {
                best = best.min(point_segment_distance(v, &q[k], &q[(k + 1) % 4]));
            }
        }
    }
    best
}

fn point_segment_distance(p: &Vector2<f64>, a: &Vector2<f64>, b: &Vector2<f64>) -> f64 {
    let ab = b - a;
    let t = ((p - a).dot(&ab) / ab.norm_squared()).clamp(0.0, 1.0);
    (a + ab * t - p).norm()
}

/// Separating-axis test for two convex quadrilaterals.
fn convex_overlap(a: &[Vector2<f64>; 4], b: &[Vector2<f64>; 4]) -> bool {
    for poly in [a, b] {
        for k in 0..4 {
            let e = poly[(k + 1) % 4] - poly[k];
            let n = Vector2::new(-e.y, e.x);
            let (amin, amax) = project(a, &n);
            let (bmin, bmax) = project(b, &n);
            if amax < bmin || bmax < amin {
                return false;
            }
        }
    }
    true
}

fn project(p: &[Vector2<f64>; 4], n: &Vector2<f64>) -> (f64, f64) {
    p.iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
            let s = v.dot(n);
            (lo.min(s), hi.max(s))
        })
}

/// What the smallest clearance was measured against.
#[derive(Clone, Debug, PartialEq)]
pub enum Contact {
    /// Collision sphere `sphere` of the arm or gripper against an obstacle box.
    Sphere {
        sphere: usize,
        obstacle: String,
    },
    /// The platform against an obstacle box.
    Platform {
        obstacle: String,
    },
    /// Collision sphere `sphere` against the floor.
    Floor {
        sphere: usize,
    },
    /// Two spheres of non-adjacent arm parts.
    SelfSpheres {
        a: usize,
        b: usize,
    },
    /// An arm sphere against the robot's own platform.
    SelfPlatform {
        sphere: usize,
    },
    None,
}

/// Smallest clearances of one configuration.
#[derive(Clone, Debug)]
pub struct ClearanceReport {
    /// Smallest distance to the environment (boxes and floor), m; negative = penetration.
    pub world: f64,
    pub world_contact: Contact,
    /// Smallest distance between non-adjacent robot parts, m.
    pub self_: f64,
    pub self_contact: Contact,
}

/// The cell's obstacles in the world and the robot model: answers clearance queries.
#[derive(Clone, Debug)]
pub struct Cell {
    pub model: RobotModel,
    pub obstacles: Vec<Obstacle>,
    /// Pairs of spheres checked for self-collision.
    self_pairs: Vec<(usize, usize)>,
    /// Spheres checked against the own platform.
    platform_spheres: Vec<usize>,
    /// Upper bound on the distance of any sphere surface from the arm base, m.
    arm_reach: f64,
}

/// Spheres on frames ≥ this are checked against the own platform.
const FIRST_FRAME_VS_PLATFORM: u8 = 3;
/// Spheres on frames ≥ this (wrist, gripper) are checked against spheres on frames ≤
/// [`LAST_FRAME_VS_WRIST`] (arm base, shoulder).
const FIRST_WRIST_FRAME: u8 = 5;
const LAST_FRAME_VS_WRIST: u8 = 2;

impl Cell {
    pub fn new(world: &World, model: &RobotModel) -> Cell {
        let mut obstacles = Vec::new();
        for (i, loc) in world.locations.iter().enumerate() {
            let pose = world.location_pose(i);
            let yaw = loc.yaw_deg.to_radians();
            for b in &world.location_type(i).boxes {
                let lo = Vector3::from(b.min);
                let hi = Vector3::from(b.max);
                let centre = pose.transform_point(&((lo + hi) / 2.0).into()).coords;
                obstacles.push(Obstacle::new(
                    i,
                    format!("{}/{}", loc.id, b.name),
                    centre,
                    yaw,
                    (hi - lo) / 2.0,
                ));
            }
        }
        let spheres = &model.spheres;
        let mut self_pairs = Vec::new();
        for (a, sa) in spheres.iter().enumerate() {
            for (b, sb) in spheres.iter().enumerate() {
                if sa.link >= FIRST_WRIST_FRAME && sb.link <= LAST_FRAME_VS_WRIST {
                    self_pairs.push((a, b));
                }
            }
        }
        let platform_spheres = (0..spheres.len())
            .filter(|&k| spheres[k].link >= FIRST_FRAME_VS_PLATFORM)
            .collect();
        Cell {
            model: model.clone(),
            obstacles,
            self_pairs,
            platform_spheres,
            arm_reach: arm_reach_bound(model),
        }
    }

    /// Clearances of the full configuration (base q_m = [x, y, yaw], arm q_a).
    pub fn clearance(&self, q_m: [f64; 3], q_a: &[f64; NA]) -> ClearanceReport {
        let base = arm_base_pose(&self.model, q_m);
        let kin = ArmKinematics::new(&self.model, &JointVector::from(*q_a));
        let mut r = self.arm_clearance(&base, &kin, &self.obstacles_near(q_m));
        let platform = self.platform_footprint(q_m);
        let (pz0, pz1) = platform_z(&self.model);
        for o in &self.obstacles {
            let (oz0, oz1) = o.z_range();
            let dz = (oz0 - pz1).max(pz0 - oz1).max(0.0);
            let dxy = polygon_distance(&platform, &o.footprint());
            let d = if dz == 0.0 && dxy == 0.0 {
                // Overlapping prisms: a penetration (its depth is not computed).
                -f64::MIN_POSITIVE
            } else {
                dxy.hypot(dz)
            };
            if d < r.world {
                r.world = d;
                r.world_contact = Contact::Platform {
                    obstacle: o.name.clone(),
                };
            }
        }
        r
    }

    /// Obstacles that can be within reach of the arm when the platform stands at q_m.
    pub fn obstacles_near(&self, q_m: [f64; 3]) -> Vec<&Obstacle> {
        let base = arm_base_pose(&self.model, q_m).translation.vector;
        self.obstacles
            .iter()
            .filter(|o| (o.centre - base).norm() - o.bounding_radius() < self.arm_reach + 1.0)
            .collect()
    }

    /// Arm-only clearance at a fixed base (for planners that keep the base still): spheres
    /// against the given obstacles and the floor, and self-collision.
    pub fn arm_clearance(
        &self,
        base: &Pose,
        kin: &ArmKinematics,
        obstacles: &[&Obstacle],
    ) -> ClearanceReport {
        let model = &self.model;
        let mut local = [Vector3::zeros(); prf_shared::robot::MAX_SPHERES];
        kin.sphere_centres(model, &mut local);
        let n = model.spheres.len();
        let mut r = ClearanceReport {
            world: f64::INFINITY,
            world_contact: Contact::None,
            self_: f64::INFINITY,
            self_contact: Contact::None,
        };
        for k in 0..n {
            let c = base.transform_point(&local[k].into()).coords;
            let radius = model.spheres[k].radius;
            let floor = c.z - radius;
            if floor < r.world {
                r.world = floor;
                r.world_contact = Contact::Floor { sphere: k };
            }
            for o in obstacles {
                let d = o.signed_distance(&c) - radius;
                if d < r.world {
                    r.world = d;
                    r.world_contact = Contact::Sphere {
                        sphere: k,
                        obstacle: o.name.clone(),
                    };
                }
            }
        }
        for &(a, b) in &self.self_pairs {
            let d =
                (local[a] - local[b]).norm() - model.spheres[a].radius - model.spheres[b].radius;
            if d < r.self_ {
                r.self_ = d;
                r.self_contact = Contact::SelfSpheres { a, b };
            }
        }
        let p = &model.platform;
        for &k in &self.platform_spheres {
            let in_b = model.mount.transform_point(&local[k].into()).coords - p.centre;
            let d = box_signed_distance(&in_b, &p.half_extents) - model.spheres[k].radius;
            if d < r.self_ {
                r.self_ = d;
                r.self_contact = Contact::SelfPlatform { sphere: k };
            }
        }
        r
    }

    /// Corners of the platform's footprint at q_m.
    pub fn platform_footprint(&self, q_m: [f64; 3]) -> [Vector2<f64>; 4] {
        let p = &self.model.platform;
        let (s, c) = q_m[2].sin_cos();
        let centre = Vector2::new(q_m[0], q_m[1])
            + Vector2::new(
                c * p.centre.x - s * p.centre.y,
                s * p.centre.x + c * p.centre.y,
            );
        rectangle(centre, c, s, p.half_extents.xy())
    }

    /// Bound on how far any sphere surface point moves per unit change of each arm joint
    /// (m/rad), and of the base (m per m of travel, m/rad of yaw): displacement ≤
    /// Σ_j lever_j |Δq_j| + |Δxy| + lever_yaw |Δyaw|.
    pub fn motion_levers(&self) -> ([f64; NA], f64) {
        let model = &self.model;
        let mut levers = [0.0; NA];
        for j in 0..NA {
            // Distance from joint j's origin to any sphere surface downstream, along the chain.
            let chain: f64 = model.joints[j + 1..]
                .iter()
                .map(|jt| jt.origin.translation.vector.norm())
                .sum();
            levers[j] = chain + tool_extent(model);
        }
        let m = model.mount.translation.vector;
        let p = &model.platform;
        let platform_corner = (p.centre.xy().abs() + p.half_extents.xy()).norm();
        let yaw_lever = (m.xy().norm() + levers[0]).max(platform_corner);
        (levers, yaw_lever)
    }
}

/// Reach of any sphere surface beyond the flange chain: flange + farthest tool sphere.
fn tool_extent(model: &RobotModel) -> f64 {
    let last = (N_FRAMES - 1) as u8;
    let tool = model
        .spheres
        .iter()
        .map(|s| {
            let d = if s.link == last {
                (model.flange.translation.vector.norm()) + s.centre.norm()
            } else if s.link as usize == NA {
                s.centre.norm()
            } else {
                0.0
            };
            d + s.radius
        })
        .fold(0.0, f64::max);
    tool.max(
        model
            .spheres
            .iter()
            .map(|s| s.centre.norm() + s.radius)
            .fold(0.0, f64::max),
    )
}

/// Upper bound on the distance of any sphere surface point from the arm base origin.
fn arm_reach_bound(model: &RobotModel) -> f64 {
    let chain: f64 = model
        .joints
        .iter()
        .map(|j| j.origin.translation.vector.norm())
        .sum();
    chain + tool_extent(model)
}

fn platform_z(model: &RobotModel) -> (f64, f64) {
    let p = &model.platform;
    (p.centre.z - p.half_extents.z, p.centre.z + p.half_extents.z)
}
