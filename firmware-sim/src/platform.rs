//! The simulated platform. Without a floor map it drives a straight line to each goal with
//! Ruckig. With the world file's boxes as its map (a KMR has one from its scanners) it
//! navigates: a path for the robot as it is (arm, and while the gripper is closed every part it
//! might hold) is planned on a helper thread (`prf_sim::navigation`), then followed one straight
//! segment at a time; a goal without a path is a fault the joint state reports.

use prf_ruckig::{Online, RuckigError};
use prf_shared::NA;
use prf_shared::limits::MotionLimits;
use prf_shared::se3::wrap;
use prf_sim::navigation::{Drive, NavError, Navigator, any_held_part};
use prf_sim::world::World;
use prf_sim::world::geometry::{Cell, HeldPart};
use std::sync::Arc;
use std::thread::JoinHandle;

/// The map and the robot's possible loads, shared with the planning threads.
struct Map {
    cell: Cell,
    loads: Vec<HeldPart>,
    clearance: f64,
}

impl Map {
    fn body(&self, arm: &[f64; NA], holding: bool) -> prf_sim::world::geometry::DriveBody {
        let loads: Vec<&HeldPart> = if holding {
            self.loads.iter().collect()
        } else {
            Vec::new()
        };
        self.cell.drive_body(arm, &loads)
    }
}

/// A platform that navigates on a floor map.
pub struct Navigating {
    map: Arc<Map>,
    /// The robot as it drives now (set with each goal: the arm holds while the platform drives).
    body: prf_sim::world::geometry::DriveBody,
    drive: Drive,
    planning: Option<JoinHandle<Result<Vec<[f64; 3]>, NavError>>>,
    no_path: Option<NavError>,
}

/// The simulated platform.
// Both variants hold a Ruckig generator (20 KB); they differ by a few hundred bytes.
#[allow(clippy::large_enum_variant)]
pub enum Platform {
    /// Straight lines with Ruckig (no floor map).
    Straight(Online<3>),
    /// Paths on the world's floor map.
    Navigating(Navigating),
}

impl Platform {
    /// At rest at `pose`; navigating on `world` if given (drives keep its acceptable
    /// clearance).
    pub fn new(pose: [f64; 3], limits: &MotionLimits, world: Option<&World>) -> Self {
        match world {
            None => Platform::Straight(Online::new(
                &pose,
                &limits.base_speed,
                &limits.base_acceleration,
                &limits.base_jerk,
            )),
            Some(w) => {
                let model = prf_shared::robot::RobotModel::kmr_iiwa14();
                let map = Arc::new(Map {
                    cell: Cell::new(w, &model),
                    loads: any_held_part(w),
                    clearance: w.clearance.acceptable,
                });
                Platform::Navigating(Navigating {
                    body: map.body(&model.home, false),
                    map,
                    drive: Drive::new(pose, limits),
                    planning: None,
                    no_path: None,
                })
            }
        }
    }

    /// Heads for `goal`; `arm` and `holding` describe the robot as it drives.
    pub fn go_to(&mut self, goal: [f64; 3], arm: &[f64; NA], holding: bool) {
        match self {
            Platform::Straight(o) => {
                let yaw = o.current().0[2];
                o.go_to(&[goal[0], goal[1], yaw + wrap(goal[2] - yaw)]);
            }
            Platform::Navigating(n) => {
                n.drive.brake();
                n.no_path = None;
                n.body = n.map.body(arm, holding);
                let (map, start, body) = (n.map.clone(), n.drive.pose(), n.body.clone());
                n.planning = Some(std::thread::spawn(move || {
                    Navigator::new(&map.cell, body, map.clearance).plan(start, goal)
                }));
            }
        }
    }

    /// Brakes to standstill where it is.
    pub fn brake(&mut self) {
        match self {
            Platform::Straight(o) => o.brake(),
            Platform::Navigating(n) => {
                n.planning = None;
                n.drive.brake();
            }
        }
    }

    /// One 1 ms cycle.
    pub fn step(&mut self) -> Result<(), RuckigError> {
        match self {
            Platform::Straight(o) => o.step().map(|_| ()),
            Platform::Navigating(n) => {
                if n.planning.as_ref().is_some_and(|h| h.is_finished())
                    && let Some(h) = n.planning.take()
                {
                    match h.join() {
                        Ok(Ok(path)) => n.drive.follow(&path),
                        Ok(Err(e)) => n.no_path = Some(e),
                        Err(_) => {}
                    }
                }
                n.drive.step().map(|_| ())
            }
        }
    }

    /// The pose [x, y, yaw], yaw in (−π, π].
    pub fn pose(&self) -> [f64; 3] {
        let p = match self {
            Platform::Straight(o) => {
                let c = o.current().0;
                [c[0], c[1], c[2]]
            }
            Platform::Navigating(n) => n.drive.pose(),
        };
        [p[0], p[1], wrap(p[2])]
    }

    /// While navigating and moving: the clearance of the robot as it set off for its goal to
    /// the nearest box, m (NaN otherwise).
    pub fn clearance(&self) -> f64 {
        match self {
            Platform::Navigating(n) if !n.drive.arrived() => {
                n.map.cell.drive_clearance(&n.body, n.drive.pose()).min()
            }
            _ => f64::NAN,
        }
    }

    /// Why the last goal has no path, if it has none.
    pub fn no_path(&self) -> Option<&NavError> {
        match self {
            Platform::Navigating(n) => n.no_path.as_ref(),
            Platform::Straight(_) => None,
        }
    }

    /// Whether this platform navigates on a map.
    pub fn navigates(&self) -> bool {
        matches!(self, Platform::Navigating(_))
    }
}
