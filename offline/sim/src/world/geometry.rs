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

    /// The box as (centre, yaw about z, half extents), world frame.
    pub fn cuboid(&self) -> (Vector3<f64>, f64, Vector3<f64>) {
        (self.centre, self.sin.atan2(self.cos), self.half)
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
        for o in &self.obstacles {
            let d = self.platform_distance(&platform, o);
            if d < r.world {
                r.world = d;
                r.world_contact = Contact::Platform {
                    obstacle: o.name.clone(),
                };
            }
        }
        r
    }

    /// Distance between the platform prism (footprint `platform`) and box `o`: the footprints'
    /// distance combined with the gap of the z intervals; overlapping prisms give a tiny
    /// negative number (a penetration whose depth is not computed).
    fn platform_distance(&self, platform: &[Vector2<f64>; 4], o: &Obstacle) -> f64 {
        let (pz0, pz1) = platform_z(&self.model);
        let (oz0, oz1) = o.z_range();
        let dz = (oz0 - pz1).max(pz0 - oz1).max(0.0);
        let dxy = polygon_distance(platform, &o.footprint());
        if dz == 0.0 && dxy == 0.0 {
            -f64::MIN_POSITIVE
        } else {
            dxy.hypot(dz)
        }
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

/// A part held in the gripper, as spheres in the TCP frame that together contain its box
/// (each cell of a grid of at most 40 mm over the box, by its circumscribed sphere: at most
/// 15 mm conservative at a face).
#[derive(Clone, Debug)]
pub struct HeldPart {
    /// (centre in the TCP frame, radius).
    pub spheres: Vec<(Vector3<f64>, f64)>,
}

impl HeldPart {
    /// The part of type `part_type` (box `size`, frame at the centre of its base) held with
    /// `grasp` (the TCP pose in the part frame).
    pub fn new(size: [f64; 3], grasp: &Pose) -> Self {
        let cells = size.map(|s| (s / 0.04).ceil().max(1.0) as usize);
        let cell = Vector3::new(
            size[0] / cells[0] as f64,
            size[1] / cells[1] as f64,
            size[2] / cells[2] as f64,
        );
        let radius = cell.norm() / 2.0;
        let to_tcp = grasp.inverse();
        let mut spheres = Vec::new();
        for i in 0..cells[0] {
            for j in 0..cells[1] {
                for k in 0..cells[2] {
                    let c = Vector3::new(
                        -size[0] / 2.0 + (i as f64 + 0.5) * cell.x,
                        -size[1] / 2.0 + (j as f64 + 0.5) * cell.y,
                        (k as f64 + 0.5) * cell.z,
                    );
                    spheres.push((to_tcp.transform_point(&c.into()).coords, radius));
                }
            }
        }
        HeldPart { spheres }
    }
}

/// The robot as it drives: the arm still at one configuration, so every sphere (arm, gripper,
/// held part) is fixed in the platform frame q_m.
#[derive(Clone, Debug)]
pub struct DriveBody {
    /// (centre in the q_m frame, radius, belongs to the held part).
    spheres: Vec<(Vector3<f64>, f64, bool)>,
    /// Largest horizontal distance of any point of the body from the q_m origin, m.
    pub radius: f64,
}

/// Clearances of the driving robot.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DriveClearance {
    /// Platform, arm and gripper to the boxes and the floor, m.
    pub robot: f64,
    /// The held part to the boxes (∞ without one), m.
    pub part: f64,
}

impl DriveClearance {
    /// The smaller of the two.
    pub fn min(&self) -> f64 {
        self.robot.min(self.part)
    }
}

impl Cell {
    /// The robot with the arm at `q_a`, holding `parts` (none, the one held, or every part it
    /// might hold), in the platform frame.
    pub fn drive_body(&self, q_a: &[f64; NA], parts: &[&HeldPart]) -> DriveBody {
        let model = &self.model;
        let kin = ArmKinematics::new(model, &JointVector::from(*q_a));
        let mut local = [Vector3::zeros(); prf_shared::robot::MAX_SPHERES];
        kin.sphere_centres(model, &mut local);
        let mount = arm_base_pose(model, [0.0; 3]);
        let mut spheres: Vec<_> = (0..model.spheres.len())
            .map(|k| {
                let c = mount.transform_point(&local[k].into()).coords;
                (c, model.spheres[k].radius, false)
            })
            .collect();
        let tcp = mount * kin.tcp;
        for p in parts {
            for (c, r) in &p.spheres {
                spheres.push((tcp.transform_point(&(*c).into()).coords, *r, true));
            }
        }
        let p = &model.platform;
        let platform = (p.centre.xy().abs() + p.half_extents.xy()).norm();
        let radius = spheres
            .iter()
            .map(|(c, r, _)| c.xy().norm() + r)
            .fold(platform, f64::max);
        DriveBody { spheres, radius }
    }

    /// Clearance of the driving robot `body` with the platform at q_m: its spheres against
    /// the boxes (and the floor), the platform prism against the boxes.
    pub fn drive_clearance(&self, body: &DriveBody, q_m: [f64; 3]) -> DriveClearance {
        let (s, c) = q_m[2].sin_cos();
        let origin = Vector2::new(q_m[0], q_m[1]);
        let mut out = DriveClearance {
            robot: f64::INFINITY,
            part: f64::INFINITY,
        };
        let platform = self.platform_footprint(q_m);
        for o in &self.obstacles {
            // Cull boxes out of reach of the body by more than the current minimum.
            let gap = (o.centre.xy() - origin).norm() - o.half.xy().norm() - body.radius;
            if gap > out.min() {
                continue;
            }
            for (p, r, held) in &body.spheres {
                let w = Vector3::new(q_m[0] + c * p.x - s * p.y, q_m[1] + s * p.x + c * p.y, p.z);
                let d = o.signed_distance(&w) - r;
                let slot = if *held { &mut out.part } else { &mut out.robot };
                *slot = slot.min(d);
            }
            out.robot = out.robot.min(self.platform_distance(&platform, o));
        }
        for (p, r, held) in &body.spheres {
            let floor = p.z - r;
            let slot = if *held { &mut out.part } else { &mut out.robot };
            *slot = slot.min(floor);
        }
        out
    }
}
