//! The simulated platform's navigation, as a KMR drives itself between stances with its own
//! map: a path for the robot in its drive configuration (platform, arm at q_a,H, gripper and
//! held part) on the world's obstacle boxes, found by A* (the `pathfinding` crate) on a lattice
//! of poses (5 cm, 32 headings), shortened by straight-line shortcuts, and followed with Ruckig
//! within the platform's limits, one straight segment at a time (phase-synchronised, from rest
//! to rest), ending exactly at the commanded pose.
//!
//! Every straight segment, between lattice poses or a shortcut, is checked densely: no point of
//! the body moves more than [`CHECK_STEP`] between checks, and every check keeps the stated
//! clearance. The runtime and the blob never see the obstacles: only the simulated platform
//! (firmware-sim, the ideal cell of `prf plan --export`) and the checks do.

use crate::world::geometry::{Cell, DriveBody, DriveClearance, HeldPart};
use pathfinding::prelude::astar;
use prf_ruckig::{Online, RuckigError};
use prf_shared::kinematics::{ArmKinematics, arm_base_pose};
use prf_shared::limits::MotionLimits;
use prf_shared::motion::Sample;
use prf_shared::se3::Pose;
use prf_shared::se3::wrap;
use prf_shared::{JointVector, NA};
use std::cell::RefCell;
use std::collections::HashMap;

/// Lattice spacing, m.
pub const GRID: f64 = 0.05;
/// Headings of the lattice.
pub const HEADINGS: i32 = 32;
/// Largest motion of any body point between two clearance checks along a segment, m.
pub const CHECK_STEP: f64 = 0.01;
/// Cost of turning, m per rad (A*'s edge cost and heuristic).
const TURN_COST: f64 = 0.5;
/// Weight of A*'s heuristic (> 1: weighted A*).
const HEURISTIC_WEIGHT: u64 = 2;
/// A* gives up after this many lattice poses.
const MAX_POSES: usize = 400_000;

/// Why no path was found.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum NavError {
    #[error(
        "the {end} pose ({:.3} m, {:.3} m, {:.1}°) keeps only {clearance:.3} m from the nearest obstacle (needs {needed:.3} m)",
        pose[0], pose[1], pose[2].to_degrees()
    )]
    Blocked {
        /// "start" or "goal".
        end: &'static str,
        pose: [f64; 3],
        clearance: f64,
        needed: f64,
    },
    #[error(
        "no collision-free path from ({:.3} m, {:.3} m) to ({:.3} m, {:.3} m) keeping {needed:.3} m ({searched} poses searched)",
        from[0], from[1], to[0], to[1]
    )]
    NoPath {
        from: [f64; 3],
        to: [f64; 3],
        needed: f64,
        searched: usize,
    },
}

/// A* node: the start, a lattice pose (ix, iy, heading), or the goal.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
enum Node {
    Start,
    Lattice(i32, i32, i32),
    Goal,
}

/// A floor map of one cell for one drive body, with the clearance every drive keeps.
pub struct Navigator<'c> {
    cell: &'c Cell,
    body: DriveBody,
    /// Clearance every pose of a path keeps, m.
    pub clearance: f64,
    /// Lattice poses already checked.
    valid: RefCell<HashMap<(i32, i32, i32), bool>>,
}

impl<'c> Navigator<'c> {
    /// Paths for `body` in `cell` keeping `clearance` (m) from every box.
    pub fn new(cell: &'c Cell, body: DriveBody, clearance: f64) -> Self {
        Navigator {
            cell,
            body,
            clearance,
            valid: RefCell::new(HashMap::new()),
        }
    }

    /// The clearance of the body at `q` (platform pose x, y, yaw).
    pub fn clearance_at(&self, q: [f64; 3]) -> f64 {
        self.cell.drive_clearance(&self.body, q).min()
    }

    fn pose(ix: i32, iy: i32, ih: i32) -> [f64; 3] {
        let yaw = ih as f64 * std::f64::consts::TAU / HEADINGS as f64;
        [ix as f64 * GRID, iy as f64 * GRID, wrap(yaw)]
    }

    fn lattice_ok(&self, k: (i32, i32, i32)) -> bool {
        if let Some(&v) = self.valid.borrow().get(&k) {
            return v;
        }
        let v = self.clearance_at(Self::pose(k.0, k.1, k.2)) >= self.clearance;
        self.valid.borrow_mut().insert(k, v);
        v
    }

    /// Whether the straight segment a → b (yaw along the shorter turn) keeps the clearance,
    /// checked so that no body point moves more than [`CHECK_STEP`] between checks (the end
    /// poses themselves are checked by the caller).
    pub fn segment_ok(&self, a: [f64; 3], b: [f64; 3]) -> bool {
        let dyaw = wrap(b[2] - a[2]);
        let travel = (b[0] - a[0]).hypot(b[1] - a[1]) + self.body.radius * dyaw.abs();
        let n = (travel / CHECK_STEP).ceil() as usize;
        (1..n).all(|k| {
            let u = k as f64 / n as f64;
            let q = [
                a[0] + (b[0] - a[0]) * u,
                a[1] + (b[1] - a[1]) * u,
                a[2] + dyaw * u,
            ];
            self.clearance_at(q) >= self.clearance
        })
    }

    fn cost(a: [f64; 3], b: [f64; 3]) -> u64 {
        let d = (b[0] - a[0]).hypot(b[1] - a[1]) + TURN_COST * wrap(b[2] - a[2]).abs();
        (d * 1e4).round() as u64
    }

    /// The nearest lattice poses around `q` (2 × 2 positions × 2 headings).
    fn around(q: [f64; 3]) -> Vec<(i32, i32, i32)> {
        let (fx, fy) = ((q[0] / GRID).floor() as i32, (q[1] / GRID).floor() as i32);
        let h = (q[2].rem_euclid(std::f64::consts::TAU) / std::f64::consts::TAU * HEADINGS as f64)
            .floor() as i32;
        let mut out = Vec::with_capacity(8);
        for ix in [fx, fx + 1] {
            for iy in [fy, fy + 1] {
                for ih in [h, h + 1] {
                    out.push((ix, iy, ih.rem_euclid(HEADINGS)));
                }
            }
        }
        out
    }

    /// A collision-free path from `start` to `goal` (platform poses), as the corners of
    /// straight segments: `start` first, `goal` last.
    pub fn plan(&self, start: [f64; 3], goal: [f64; 3]) -> Result<Vec<[f64; 3]>, NavError> {
        let needed = self.clearance;
        for (end, pose) in [("start", start), ("goal", goal)] {
            let clearance = self.clearance_at(pose);
            if clearance < needed {
                return Err(NavError::Blocked {
                    end,
                    pose,
                    clearance,
                    needed,
                });
            }
        }
        if self.segment_ok(start, goal) {
            return Ok(vec![start, goal]);
        }
        let goal_links = Self::around(goal);
        let searched = RefCell::new(0usize);
        let point = |n: &Node| match n {
            Node::Start => start,
            Node::Goal => goal,
            Node::Lattice(x, y, h) => Self::pose(*x, *y, *h),
        };
        let successors = |n: &Node| -> Vec<(Node, u64)> {
            *searched.borrow_mut() += 1;
            if *searched.borrow() > MAX_POSES {
                return Vec::new();
            }
            let here = point(n);
            let mut next: Vec<Node> = Vec::new();
            match *n {
                Node::Start => next.extend(
                    Self::around(start)
                        .into_iter()
                        .map(|(x, y, h)| Node::Lattice(x, y, h)),
                ),
                Node::Lattice(x, y, h) => {
                    for (dx, dy) in [
                        (1, 0),
                        (-1, 0),
                        (0, 1),
                        (0, -1),
                        (1, 1),
                        (1, -1),
                        (-1, 1),
                        (-1, -1),
                    ] {
                        next.push(Node::Lattice(x + dx, y + dy, h));
                    }
                    next.push(Node::Lattice(x, y, (h + 1).rem_euclid(HEADINGS)));
                    next.push(Node::Lattice(x, y, (h - 1).rem_euclid(HEADINGS)));
                    if goal_links.contains(&(x, y, h)) {
                        next.push(Node::Goal);
                    }
                }
                Node::Goal => {}
            }
            next.into_iter()
                .filter(|m| match m {
                    Node::Lattice(x, y, h) => self.lattice_ok((*x, *y, *h)),
                    _ => true,
                })
                .filter(|m| self.segment_ok(here, point(m)))
                .map(|m| (m, Self::cost(here, point(&m))))
                .collect()
        };
        // Weighted A*: the heuristic counts double, trading optimality (a path at most twice
        // the shortest) for far fewer poses searched.
        let heuristic = |n: &Node| HEURISTIC_WEIGHT * Self::cost(point(n), goal);
        let found = astar(&Node::Start, successors, heuristic, |n| *n == Node::Goal);
        let Some((nodes, _)) = found else {
            return Err(NavError::NoPath {
                from: start,
                to: goal,
                needed,
                searched: searched.into_inner(),
            });
        };
        let path: Vec<[f64; 3]> = nodes.iter().map(point).collect();
        Ok(self.shortcut(&path))
    }

    /// Replaces runs of the path by straight segments where those keep the clearance.
    fn shortcut(&self, path: &[[f64; 3]]) -> Vec<[f64; 3]> {
        let mut out = vec![path[0]];
        let mut i = 0;
        while i + 1 < path.len() {
            let mut j = path.len() - 1;
            while j > i + 1 && !self.segment_ok(path[i], path[j]) {
                j -= 1;
            }
            out.push(path[j]);
            i = j;
        }
        out
    }
}

/// Follows a path with Ruckig within the platform's limits: one straight segment at a time,
/// phase-synchronised from rest to rest, so the platform stays on the checked segments.
pub struct Drive {
    online: Online<3>,
    /// Corners still to reach, next first.
    corners: std::collections::VecDeque<[f64; 3]>,
    pose: [f64; 3],
    /// Driving towards a corner (else at rest: Ruckig is not stepped).
    active: bool,
}

impl Drive {
    /// At rest at `pose`.
    pub fn new(pose: [f64; 3], limits: &MotionLimits) -> Self {
        let mut online = Online::new(
            &pose,
            &limits.base_speed,
            &limits.base_acceleration,
            &limits.base_jerk,
        );
        online.set_phase_synchronised();
        Drive {
            online,
            corners: Default::default(),
            pose,
            active: false,
        }
    }

    /// Drives along `path` (its first corner is where the platform is).
    pub fn follow(&mut self, path: &[[f64; 3]]) {
        self.corners = path.iter().skip(1).copied().collect();
        self.next_corner();
    }

    fn next_corner(&mut self) {
        self.active = false;
        if let Some(c) = self.corners.pop_front() {
            // Yaw along the shorter turn from where the platform heads now.
            let yaw = self.pose[2] + wrap(c[2] - self.pose[2]);
            self.online.go_to(&[c[0], c[1], yaw]);
            self.active = true;
        }
    }

    /// One 1 ms cycle; the platform pose afterwards (unchanged at rest).
    pub fn step(&mut self) -> Result<[f64; 3], RuckigError> {
        if !self.active {
            return Ok(self.pose);
        }
        let reached = self.online.step()?;
        let p = self.online.position();
        self.pose = [p[0], p[1], p[2]];
        if reached {
            self.next_corner();
        }
        Ok(self.pose)
    }

    /// True once the last corner is reached (or a brake has stopped).
    pub fn arrived(&self) -> bool {
        !self.active
    }

    /// The platform pose now.
    pub fn pose(&self) -> [f64; 3] {
        self.pose
    }

    /// Stops following the path: brakes to standstill within the limits where it is.
    pub fn brake(&mut self) {
        self.corners.clear();
        self.online.brake();
        self.active = true;
    }
}

/// Why the navigating cell stopped.
#[derive(Debug, thiserror::Error)]
pub enum NavCellError {
    #[error("the platform cannot reach its goal: {0}")]
    Nav(#[from] NavError),
    #[error(transparent)]
    Ruckig(#[from] RuckigError),
}

/// One drive of the platform: where to, along which corners.
#[derive(Clone, Debug)]
pub struct DriveRecord {
    /// The commanded goal pose.
    pub goal: [f64; 3],
    /// The path's corners, start first.
    pub path: Vec<[f64; 3]>,
    /// A part was held.
    pub holding: bool,
}

/// Gripper opening at and above which the part counts as held.
pub const HOLDING: f64 = 0.95;

/// Where the part is: picked up when the gripper closes (its grasp is where the TCP is
/// relative to the part then), put down where it is when the gripper opens.
#[derive(Clone, Debug)]
pub struct PartTracker {
    size: [f64; 3],
    /// The part's world pose while not held.
    pose: Pose,
    /// The part in the TCP frame while held, and its grasp (TCP in the part frame).
    held: Option<(HeldPart, Pose)>,
}

impl PartTracker {
    /// The part (box `size`, frame at its base centre) at `pose`, not held.
    pub fn new(size: [f64; 3], pose: Pose) -> Self {
        PartTracker {
            size,
            pose,
            held: None,
        }
    }

    /// Follows the gripper at opening `gripper` (0…1); `tcp` gives the TCP's world pose, asked
    /// only when the part is picked up or put down.
    pub fn update(&mut self, gripper: f64, tcp: impl FnOnce() -> Pose) {
        let closed = gripper >= HOLDING;
        match (&self.held, closed) {
            (None, true) => {
                let grasp = self.pose.inverse() * tcp();
                self.held = Some((HeldPart::new(self.size, &grasp), grasp));
            }
            (Some((_, grasp)), false) => {
                self.pose = tcp() * grasp.inverse();
                self.held = None;
            }
            _ => {}
        }
    }

    /// The held part, if the gripper holds it.
    pub fn held(&self) -> Option<&HeldPart> {
        self.held.as_ref().map(|(p, _)| p)
    }

    /// Whether the gripper holds the part.
    pub fn holding(&self) -> bool {
        self.held.is_some()
    }

    /// The part's world pose where it was last put down (or its start pose).
    pub fn rest_pose(&self) -> &Pose {
        &self.pose
    }

    /// The held part's grasp (TCP in the part frame).
    pub fn grasp(&self) -> Option<&Pose> {
        self.held.as_ref().map(|(_, g)| g)
    }

    /// The part's box size, m.
    pub fn size(&self) -> [f64; 3] {
        self.size
    }
}

/// The TCP's world pose with the platform at `base` and the arm at `arm`.
pub fn tcp_world(model: &prf_shared::robot::RobotModel, base: [f64; 3], arm: &[f64; NA]) -> Pose {
    let kin = ArmKinematics::new(model, &JointVector::from(*arm));
    arm_base_pose(model, base) * kin.tcp
}

/// The runtime's ideal cell (arm follows exactly, gripper at its fixed rate) with a platform
/// that navigates: each new base goal is reached along a path of [`Navigator`] for the robot
/// as it is then (arm configuration, held part), followed by [`Drive`]. The part is picked up
/// when the gripper closes (its grasp is where the TCP is relative to the part then) and put
/// down when it opens.
pub struct NavigatingCell<'c> {
    ideal: prf_runtime::ideal::IdealCell,
    cell: &'c Cell,
    clearance: f64,
    drive: Drive,
    goal: [f64; 3],
    part: PartTracker,
    /// Every drive so far.
    pub drives: Vec<DriveRecord>,
}

impl<'c> NavigatingCell<'c> {
    /// At rest with the arm at `arm`, the platform at `home` and the gripper open, ticked every
    /// `dt` s, with `part` where it lies; drives keep `clearance`.
    pub fn new(
        cell: &'c Cell,
        arm: [f64; NA],
        home: &Pose,
        dt: f64,
        part: PartTracker,
        clearance: f64,
    ) -> Self {
        let ideal = prf_runtime::ideal::IdealCell::new(arm, home, dt);
        let base = ideal.measured.base;
        NavigatingCell {
            ideal,
            cell,
            clearance,
            drive: Drive::new(base, &MotionLimits::kmr_iiwa(&cell.model)),
            goal: base,
            part,
            drives: Vec::new(),
        }
    }
}

impl prf_runtime::executor::Plant for NavigatingCell<'_> {
    type Error = NavCellError;

    fn measured(&self) -> prf_runtime::executor::Measured {
        self.ideal.measured
    }

    fn command(&mut self, sp: &prf_runtime::executor::Setpoint) -> Result<(), NavCellError> {
        let base = self.ideal.measured.base;
        self.ideal.apply(sp);
        self.ideal.measured.base = base;
        let m = self.ideal.measured;
        self.part
            .update(m.gripper, || tcp_world(&self.cell.model, m.base, &m.arm));
        if sp.base_goal != self.goal {
            self.goal = sp.base_goal;
            let body = self.cell.drive_body(&m.arm, self.part.held().as_slice());
            let nav = Navigator::new(self.cell, body, self.clearance);
            let path = nav.plan(m.base, sp.base_goal)?;
            self.drive.follow(&path);
            self.drives.push(DriveRecord {
                goal: sp.base_goal,
                path,
                holding: self.part.holding(),
            });
        }
        self.ideal.measured.base = self.drive.step()?;
        Ok(())
    }
}

/// One drive of a recorded program: the ticks where the platform moves, whether a part was
/// held, and the smallest clearances on the way.
#[derive(Clone, Copy, Debug)]
pub struct DrivePhase {
    /// First and last sample time, s.
    pub t: (f64, f64),
    pub holding: bool,
    /// Smallest clearance of platform + arm + gripper, and of the held part.
    pub min: DriveClearance,
}

/// The drives of a program recorded at 1 kHz (`samples`, e.g. `prf plan --export`), checked
/// against the world's boxes like arm motions are: every sample where the platform moves, the
/// robot as it is (arm configuration, held part tracked from the gripper) in `cell`.
pub fn drive_phases(cell: &Cell, samples: &[Sample], mut part: PartTracker) -> Vec<DrivePhase> {
    let mut out: Vec<DrivePhase> = Vec::new();
    let mut moving = false;
    for (k, s) in samples.iter().enumerate() {
        part.update(s.gripper, || tcp_world(&cell.model, s.base, &s.arm));
        let next = samples.get(k + 1).map_or(s.base, |n| n.base);
        let moves = next != s.base
            || samples
                .get(k.wrapping_sub(1))
                .is_some_and(|p| p.base != s.base);
        if !moves {
            moving = false;
            continue;
        }
        let c = cell.drive_clearance(&cell.drive_body(&s.arm, part.held().as_slice()), s.base);
        if !moving {
            out.push(DrivePhase {
                t: (s.t, s.t),
                holding: part.holding(),
                min: c,
            });
            moving = true;
        }
        if let Some(p) = out.last_mut() {
            p.t.1 = s.t;
            p.min.robot = p.min.robot.min(c.robot);
            p.min.part = p.min.part.min(c.part);
        }
    }
    out
}

/// Runs `program` on a [`NavigatingCell`] of `world` for floor task `task` (drives keep the
/// world's acceptable clearance r): the execution and the drives.
pub fn execute_navigating(
    world: &crate::world::World,
    rt: &prf_runtime::Runtime<'_>,
    program: &prf_runtime::program::Program,
    task: &crate::tasks::FloorTask,
    max_ticks: usize,
) -> Result<(prf_host::ideal::Execution, Vec<DriveRecord>), NavCellError> {
    let cell = Cell::new(world, &rt.model);
    let part = PartTracker::new(part_size(world, &task.part.1), task.part_pose);
    let mut plant = NavigatingCell::new(
        &cell,
        rt.model.home,
        &task.home,
        rt.config.rdmp.dt,
        part,
        world.clearance.acceptable,
    );
    let run = prf_host::ideal::execute_on(
        rt,
        program,
        &task.home,
        prf_runtime::executor::ExecutorConfig::default(),
        max_ticks,
        &mut plant,
    )?;
    Ok((run, plant.drives))
}

/// The box size of part type `name` (zero if the world lacks it).
pub fn part_size(world: &crate::world::World, name: &str) -> [f64; 3] {
    world
        .part_type_index(name)
        .map_or([0.0; 3], |i| world.part_types[i].size)
}

/// Every part a cell's gripper could hold, at each of its grasps: the conservative footprint of
/// a platform that does not know which part it carries.
pub fn any_held_part(world: &crate::world::World) -> Vec<HeldPart> {
    world
        .part_types
        .iter()
        .flat_map(|t| {
            t.grasps
                .iter()
                .map(|g| HeldPart::new(t.size, &g.tcp.pose()))
        })
        .collect()
}
