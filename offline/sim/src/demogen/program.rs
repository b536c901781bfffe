//! A complete robot program for an afforded task, the way the cell's programmer made it
//! (Sec. 4.3.1, Sec. 7): drive to the first stance, reach from home to the grasp (PTP path
//! planned by RRT-Connect to a pre-grasp 10 cm back along the tool axis, then a straight
//! approach), close the gripper, the reverse arm motion, drive to the second stance, the same to
//! place the part with the gripper opening, and drive home.

use super::ik::{self, IkConfig, IkError};
use super::rrt::{self, RrtConfig, RrtError, Space};
use super::timing::{Limits, Motion};
use crate::navigation::{PartTracker, part_size};
use crate::validate::{self, MotionLimits};
use crate::world::geometry::{Cell, Obstacle};
use crate::world::{AffordedTask, Planar, World, planar};
use nalgebra::{Isometry3, Translation3};
use prf_files::dataset::{Placed, Sample, TaskRecord};
use prf_shared::kinematics::ArmKinematics;
use prf_shared::nullspace::kernel;
use prf_shared::se3::{Pose, pose_to_array, wrap};
use prf_shared::{JointVector, NA};
use rand::{SeedableRng, rngs::StdRng};

/// Settings of the generator.
#[derive(Clone, Debug)]
pub struct GenConfig {
    /// Sample rate of the written trajectories, Hz.
    pub rate_hz: f64,
    /// Programmed arm speed as a fraction of the joint speed limits (PTP motions).
    pub arm_speed: f64,
    /// Programmed speed of the straight final approach, fraction of the speed limits.
    pub approach_speed: f64,
    /// Pre-grasp distance back along the tool axis, m.
    pub approach_distance: f64,
    /// Time the gripper takes to open or close, s.
    pub grip_time: f64,
    /// Pause between motions, s.
    pub dwell: f64,
    /// Extra clearance the planner keeps beyond r_d at checked configurations, m.
    pub planning_margin: f64,
    /// Smallest step (bound on sphere motion) of the planner's edge check, m: an edge's
    /// clearance may dip at most this far below the planner's requirement between checks.
    pub edge_resolution: f64,
    /// Smallest manipulability sqrt(det JJᵀ) of a planned configuration: programmers keep away
    /// from singularities (Sec. 4.2.1), and RDMPs cannot be trained through them.
    pub min_manipulability: f64,
    /// Re-sampling resolution of the final check, m.
    pub check_resolution: f64,
    /// Acceleration ramp of the programmed arm motions, s: the jerk filter's window (the
    /// programs ramp acceleration up and down over this time, well inside the hardware jerk
    /// limit, as smooth programs on a real cell do; the RDMPs learned from them can follow).
    pub arm_ramp: f64,
    pub limits: MotionLimits,
    pub ik: IkConfig,
    pub rrt: RrtConfig,
    /// Whether each program is taught its own way, as an archive holds the same task taught
    /// again on another day (other speeds, pre-grasp distance, a via point): off, every
    /// program of a task is the same motion (the example cell's dataset).
    pub vary: bool,
}

impl GenConfig {
    pub fn new(limits: MotionLimits) -> Self {
        GenConfig {
            rate_hz: 100.0,
            arm_speed: 0.5,
            approach_speed: 0.15,
            approach_distance: 0.10,
            grip_time: 0.5,
            dwell: 0.2,
            planning_margin: 0.005,
            edge_resolution: 0.001,
            min_manipulability: 0.03,
            check_resolution: 0.002,
            arm_ramp: 0.2,
            limits,
            ik: IkConfig::default(),
            rrt: RrtConfig::default(),
            vary: false,
        }
    }
}

/// How one program's reaches are taught: speeds, pre-grasp distance and whether the PTP
/// path passes a via point of the programmer's choosing.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Style {
    /// Fraction of the joint speed limits of the PTP motion.
    arm_speed: f64,
    /// Fraction of the joint speed limits of the straight approach.
    approach_speed: f64,
    /// Pre-grasp distance back along the tool axis, m.
    approach_distance: f64,
    /// A via point at this fraction of the way home → pre-grasp, moved by this many rad per
    /// joint (each of [−1, 1]).
    via: Option<(f64, [f64; NA])>,
}

/// Most drawn styles a program is tried in before the programmer falls back to the plain
/// one (a via point may leave no collision-free blend, or bring the held part too close).
const STYLE_ATTEMPTS: usize = 4;

/// Largest move of a via point off the straight path, rad per joint.
const VIA_SPREAD: f64 = 0.35;

impl Style {
    /// The configured speeds and distance, no via point: every program the same.
    fn plain(cfg: &GenConfig) -> Self {
        Style {
            arm_speed: cfg.arm_speed,
            approach_speed: cfg.approach_speed,
            approach_distance: cfg.approach_distance,
            via: None,
        }
    }

    /// A style drawn from `rng` around the plain one: PTP speed × [0.6, 1.2], approach speed
    /// × [0.6, 1.3], pre-grasp distance × [0.8, 1.3], and a via point on three of four.
    fn drawn(cfg: &GenConfig, rng: &mut StdRng) -> Self {
        use rand::RngExt;
        let arm_speed = cfg.arm_speed * rng.random_range(0.6..1.2);
        let approach_speed = cfg.approach_speed * rng.random_range(0.6..1.3);
        let approach_distance = cfg.approach_distance * rng.random_range(0.8..1.3);
        let via = rng.random_bool(0.75).then(|| {
            let at = rng.random_range(0.3..0.7);
            let off: [f64; NA] = std::array::from_fn(|_| rng.random_range(-1.0..1.0));
            (at, off)
        });
        Style {
            arm_speed,
            approach_speed,
            approach_distance,
            via,
        }
    }
}

/// Why a demonstration could not be generated.
#[derive(Clone, Debug)]
pub enum GenError {
    Ik {
        location: String,
        what: &'static str,
        error: IkError,
    },
    Plan {
        location: String,
        error: RrtError,
    },
    /// The timed motion failed the final check (should not happen: reported, not hidden).
    Check {
        what: String,
        detail: String,
    },
}

impl std::fmt::Display for GenError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            GenError::Ik {
                location,
                what,
                error,
            } => write!(f, "{location}: IK of the {what}: {error}"),
            GenError::Plan { location, error } => write!(f, "{location}: path planning: {error}"),
            GenError::Check { what, detail } => {
                write!(f, "{what}: failed the clearance check: {detail}")
            }
        }
    }
}

impl std::error::Error for GenError {}

/// The arm at a fixed base pose, for the planner: valid = within limits, clearance ≥ r_d +
/// margin to the environment and ≥ self clearance to itself.
struct ArmSpace<'a> {
    cell: &'a Cell,
    base: Pose,
    obstacles: Vec<&'a Obstacle>,
    world_clearance: f64,
    self_clearance: f64,
    levers: [f64; NA],
    resolution: f64,
    min_manipulability: f64,
}

/// Largest step of the edge check (bound on sphere motion), m: keeps the manipulability,
/// which has no slack bound, sampled densely enough.
const MAX_EDGE_STEP: f64 = 0.05;

impl ArmSpace<'_> {
    /// The planner's one validity test: within limits, manipulability ≥ the floor, clearance
    /// ≥ r_d + margin and self clearance ≥ its minimum. Returns the slack (how far every
    /// sphere centre may move before the requirement can break), or why `q` is invalid.
    fn check(&self, q: &[f64; NA]) -> Result<f64, String> {
        let model = &self.cell.model;
        let at = || format!("at q = {:.1?} deg", q.map(f64::to_degrees));
        if let Some((j, v)) = model.limit_violation(q) {
            return Err(format!(
                "a{} = {:.1} deg beyond its limit",
                j + 1,
                v.to_degrees()
            ));
        }
        let kin = ArmKinematics::new(model, &JointVector::from(*q));
        let w = kernel(&kin.jacobian(model)).manipulability;
        if w < self.min_manipulability {
            return Err(format!(
                "near a singularity: manipulability {w:.4} {}",
                at()
            ));
        }
        let c = self.cell.arm_clearance(&self.base, &kin, &self.obstacles);
        if c.world < self.world_clearance {
            return Err(format!(
                "clearance {:.1} mm < {:.1} mm to {:?} {}",
                c.world * 1e3,
                self.world_clearance * 1e3,
                c.world_contact,
                at()
            ));
        }
        if c.self_ < self.self_clearance {
            return Err(format!(
                "self clearance {:.1} mm < {:.1} mm: {:?} {}",
                c.self_ * 1e3,
                self.self_clearance * 1e3,
                c.self_contact,
                at()
            ));
        }
        Ok((c.world - self.world_clearance)
            .min((c.self_ - self.self_clearance) / 2.0)
            .min(MAX_EDGE_STEP))
    }
}

impl Space<NA> for ArmSpace<'_> {
    fn lower(&self) -> [f64; NA] {
        std::array::from_fn(|j| self.cell.model.joints[j].lower)
    }

    fn upper(&self) -> [f64; NA] {
        std::array::from_fn(|j| self.cell.model.joints[j].upper)
    }

    fn valid(&self, q: &[f64; NA]) -> bool {
        self.check(q).is_ok()
    }

    /// Conservative advancement: at a configuration with clearance slack s (the smaller of
    /// the world slack and half the self slack), no sphere centre that moves less than s can
    /// violate the requirement, so the edge is walked in steps of the motion bound
    /// Σ lever_j |Δq_j| = max(s, `resolution`).
    fn edge_valid(&self, a: &[f64; NA], b: &[f64; NA]) -> bool {
        let total: f64 = (0..NA).map(|j| self.levers[j] * (b[j] - a[j]).abs()).sum();
        let mut u: f64 = 0.0;
        loop {
            let q: [f64; NA] = std::array::from_fn(|j| a[j] + (b[j] - a[j]) * u);
            let Ok(slack) = self.check(&q) else {
                return false;
            };
            if u >= 1.0 || total <= 0.0 {
                return true;
            }
            u = (u + slack.max(self.resolution) / total).min(1.0);
        }
    }
}

/// One piece of a program.
enum Piece {
    /// Platform motion with the arm at home.
    Base(Motion<3>),
    /// Arm motion at a fixed base; `reversed` plays it backwards.
    Arm {
        base: [f64; 3],
        motion: Motion<NA>,
        reversed: bool,
    },
    /// Everything still for `duration`; the gripper takes `gripper` at its start.
    Hold { duration: f64, gripper: f64 },
}

/// The arm's way to a grasp at one stance.
struct Reach {
    base: [f64; 3],
    /// Home → pre-grasp (PTP path), pre-grasp → grasp (straight approach).
    ptp: Motion<NA>,
    approach: Motion<NA>,
}

/// The generator for one world.
pub struct Generator<'w> {
    pub world: &'w World,
    pub cell: Cell,
    pub cfg: GenConfig,
}

impl<'w> Generator<'w> {
    pub fn new(world: &'w World, model: &prf_shared::robot::RobotModel, cfg: GenConfig) -> Self {
        Generator {
            world,
            cell: Cell::new(world, model),
            cfg,
        }
    }

    fn arm_limits(&self, scale: f64) -> Limits<NA> {
        Limits {
            speed: self.cfg.limits.arm_speed.map(|v| v * scale),
            acceleration: self.cfg.limits.arm_acceleration,
            jerk: std::array::from_fn(|j| {
                let a = self.cfg.limits.arm_acceleration[j];
                self.cfg.limits.arm_jerk[j].min(2.0 * a / self.cfg.arm_ramp)
            }),
        }
    }

    fn space(&self, base: [f64; 3]) -> ArmSpace<'_> {
        ArmSpace {
            cell: &self.cell,
            base: prf_shared::kinematics::arm_base_pose(&self.cell.model, base),
            obstacles: self.cell.obstacles_near(base),
            world_clearance: self.world.clearance.demonstration + self.cfg.planning_margin,
            self_clearance: self.world.clearance.self_collision + self.cfg.planning_margin,
            levers: self.cell.motion_levers().0,
            resolution: self.cfg.edge_resolution,
            min_manipulability: self.cfg.min_manipulability,
        }
    }

    /// Plans the reach to grasp `grasp` of the part at location `loc` from `approach`, taught
    /// in `style`.
    fn reach(
        &self,
        loc: usize,
        approach: usize,
        part_type: usize,
        grasp: usize,
        style: &Style,
        rng: &mut StdRng,
    ) -> Result<Reach, GenError> {
        let w = self.world;
        let model = &self.cell.model;
        let ltype = w.location_type(loc);
        let stance = ltype.approaches[approach].stance.pose();
        let base = planar(&(w.location_pose(loc) * stance));
        let name = format!(
            "{}.{}",
            w.locations[loc].id, ltype.approaches[approach].name
        );
        // TCP goal in the arm base frame: (T_b^ℓ · mount)⁻¹ · T_p^ℓ · T_e^p.
        let tcp_grasp = (stance * model.mount).inverse()
            * ltype.part_pose.pose()
            * w.part_types[part_type].grasps[grasp].tcp.pose();
        let tcp_pre = tcp_grasp
            * Isometry3::from_parts(
                Translation3::new(0.0, 0.0, -style.approach_distance),
                nalgebra::UnitQuaternion::identity(),
            );
        let space = self.space(base);
        let home = JointVector::from(model.home);
        let ik_err = |what, error| GenError::Ik {
            location: name.clone(),
            what,
            error,
        };
        let q_grasp = ik::solve(model, &tcp_grasp, &home, &self.cfg.ik, |q| {
            space.check(&(*q).into()).map(|_| ())
        })
        .map_err(|e| ik_err("grasp", e))?;
        let q_pre = ik::solve(model, &tcp_pre, &q_grasp, &self.cfg.ik, |q| {
            space.check(&(*q).into())?;
            if space.edge_valid(&(*q).into(), &q_grasp.into()) {
                Ok(())
            } else {
                Err("the straight approach to the grasp collides".into())
            }
        })
        .map_err(|e| ik_err("pre-grasp", e))?;
        let plan = |from: [f64; NA], to: [f64; NA], rng: &mut StdRng| {
            rrt::plan(&space, from, to, &self.cfg.rrt, rng).map_err(|error| GenError::Plan {
                location: name.clone(),
                error,
            })
        };
        let path = match style.via {
            None => plan(model.home, q_pre.into(), rng)?,
            Some((at, off)) => {
                let q_pre: [f64; NA] = q_pre.into();
                let via: [f64; NA] = std::array::from_fn(|j| {
                    let q = model.home[j] + (q_pre[j] - model.home[j]) * at + VIA_SPREAD * off[j];
                    q.clamp(model.joints[j].lower, model.joints[j].upper)
                });
                let mut path = plan(model.home, via, rng)?;
                path.extend(plan(via, q_pre, rng)?.into_iter().skip(1));
                path
            }
        };
        let approach_path = [q_pre.into(), q_grasp.into()];
        let approach = Motion::new(
            &approach_path,
            &self.arm_limits(style.approach_speed),
            false,
        );
        // Blended PTP path, or exact stops at the via points if the blends cut a corner too
        // close to an obstacle.
        let limits = self.arm_limits(style.arm_speed);
        let arm_ok = |m: &Motion<NA>| {
            self.piece_ok(Piece::Arm {
                base,
                motion: m.clone(),
                reversed: false,
            })
        };
        let mut ptp = Motion::new(&path, &limits, true);
        if !arm_ok(&ptp) {
            ptp = Motion::new(&path, &limits, false);
            if !arm_ok(&ptp) {
                return Err(GenError::Check {
                    what: name,
                    detail: "PTP path".into(),
                });
            }
        }
        Ok(Reach {
            base,
            ptp,
            approach,
        })
    }

    /// Does one timed piece, sampled as it will be written, pass the final check?
    fn piece_ok(&self, piece: Piece) -> bool {
        let samples = self.sample(&[piece], 0.0);
        self.check(&samples).ok(
            self.world.clearance.demonstration,
            self.world.clearance.self_collision,
            validate::LIMIT_TOLERANCE,
        )
    }

    fn check(&self, samples: &[Sample]) -> validate::Report {
        validate::check(
            &self.cell,
            &self.cfg.limits,
            samples,
            self.cfg.check_resolution,
        )
    }

    /// The part, held from the pick to the place, keeps r_d from every box but the surfaces it
    /// is picked from and put down on, and does not sink into those (the pieces were planned
    /// for the robot alone; this is the ground truth with the part).
    fn check_held_part(
        &self,
        samples: &[Sample],
        kind: &str,
        start: &Pose,
    ) -> Result<(), GenError> {
        let tracker = PartTracker::new(part_size(self.world, kind), *start);
        let r = validate::check_held_part(&self.cell, samples, tracker, self.cfg.check_resolution);
        let r_d = self.world.clearance.demonstration;
        if r.min < r_d || r.support < -validate::SINK_TOLERANCE {
            return Err(GenError::Check {
                what: format!("the held {kind}"),
                detail: format!(
                    "{:.1} mm from {} at t = {:.2} s (r_d {:.0} mm); {:.1} mm into its support {} at t = {:.2} s",
                    r.min * 1e3,
                    r.obstacle,
                    r.min_t,
                    r_d * 1e3,
                    -r.support * 1e3,
                    r.support_name,
                    r.support_t
                ),
            });
        }
        Ok(())
    }

    /// Platform path through the given planar poses (yaw in rad, unwrapped on the way).
    fn base_motion(&self, poses: &[[f64; 3]]) -> Result<Motion<3>, GenError> {
        let mut w: Vec<[f64; 3]> = Vec::new();
        for p in poses {
            let mut p = *p;
            if let Some(prev) = w.last() {
                p[2] = prev[2] + wrap(p[2] - prev[2]);
                if (0..3).all(|k| (p[k] - prev[k]).abs() < 1e-9) {
                    continue;
                }
            }
            w.push(p);
        }
        let limits = Limits {
            speed: self.cfg.limits.base_speed,
            acceleration: self.cfg.limits.base_acceleration,
            jerk: self.cfg.limits.base_jerk,
        };
        let blended = Motion::new(&w, &limits, true);
        let ok = |m: &Motion<3>| self.piece_ok(Piece::Base(m.clone()));
        if ok(&blended) {
            return Ok(blended);
        }
        let stops = Motion::new(&w, &limits, false);
        if ok(&stops) {
            return Ok(stops);
        }
        Err(GenError::Check {
            what: "platform path".into(),
            detail: format!("{poses:?}"),
        })
    }

    /// Waypoints from the stance of `approach` at `loc` out to the aisle (world, rad).
    fn exit_path(&self, loc: usize, approach: usize) -> Vec<[f64; 3]> {
        let w = self.world;
        let a = &w.location_type(loc).approaches[approach];
        let pose = w.location_pose(loc);
        std::iter::once(&a.stance)
            .chain(&a.exit)
            .map(|p: &Planar| planar(&(pose * p.pose())))
            .collect()
    }

    /// Generates the program of one afforded task; `seed` fixes the planner's random choices
    /// (and, with [`GenConfig::vary`], the style of each reach: up to four drawn ones, then
    /// the plain one, so a style that leaves no valid program is not fatal).
    pub fn generate(
        &self,
        a: &AffordedTask,
        seed: u64,
    ) -> Result<(TaskRecord, Vec<Sample>), GenError> {
        let mut rng = StdRng::seed_from_u64(seed);
        if self.cfg.vary {
            for _ in 0..STYLE_ATTEMPTS {
                let styles = [(); 2].map(|_| Style::drawn(&self.cfg, &mut rng));
                if let Ok(program) = self.generate_in(a, seed, &styles, &mut rng) {
                    return Ok(program);
                }
            }
        }
        let plain = Style::plain(&self.cfg);
        self.generate_in(a, seed, &[plain, plain], &mut rng)
    }

    /// [`Generator::generate`] with the pick and the place taught in `styles`.
    fn generate_in(
        &self,
        a: &AffordedTask,
        seed: u64,
        styles: &[Style; 2],
        rng: &mut StdRng,
    ) -> Result<(TaskRecord, Vec<Sample>), GenError> {
        let w = self.world;
        let t = a.task;
        let part_type = w.part_type_index(&w.parts[t.part].kind).unwrap_or(0);
        let [pick_style, place_style] = styles;
        let mut pick = self.reach(t.from, a.approach_from, part_type, a.grasp, pick_style, rng)?;
        let mut place = self.reach(t.to, a.approach_to, part_type, a.grasp, place_style, rng)?;
        let home = [w.home.x, w.home.y, w.home.yaw_deg.to_radians()];
        let exit1 = self.exit_path(t.from, a.approach_from);
        let exit2 = self.exit_path(t.to, a.approach_to);
        let rev = |v: &[[f64; 3]]| v.iter().rev().copied().collect::<Vec<_>>();
        // Each drive starts where the last one ended, so the yaw stays continuous.
        let to_first = self.base_motion(&[vec![home], rev(&exit1)].concat())?;
        pick.base = to_first.end();
        let between =
            self.base_motion(&[vec![pick.base], exit1[1..].to_vec(), rev(&exit2)].concat())?;
        place.base = between.end();
        let back =
            self.base_motion(&[vec![place.base], exit2[1..].to_vec(), vec![home]].concat())?;
        let dwell = Piece::Hold {
            duration: self.cfg.dwell,
            gripper: 0.0,
        };
        let arm = |r: &Reach, gripper_at_end: f64| {
            [
                Piece::Arm {
                    base: r.base,
                    motion: r.ptp.clone(),
                    reversed: false,
                },
                Piece::Arm {
                    base: r.base,
                    motion: r.approach.clone(),
                    reversed: false,
                },
                Piece::Hold {
                    duration: self.cfg.grip_time,
                    gripper: gripper_at_end,
                },
                Piece::Arm {
                    base: r.base,
                    motion: r.approach.clone(),
                    reversed: true,
                },
                Piece::Arm {
                    base: r.base,
                    motion: r.ptp.clone(),
                    reversed: true,
                },
                Piece::Hold {
                    duration: self.cfg.dwell,
                    gripper: gripper_at_end,
                },
            ]
        };
        let mut pieces = vec![
            dwell,
            Piece::Base(to_first),
            Piece::Hold {
                duration: self.cfg.dwell,
                gripper: 0.0,
            },
        ];
        pieces.extend(arm(&pick, 1.0));
        pieces.push(Piece::Base(between));
        pieces.push(Piece::Hold {
            duration: self.cfg.dwell,
            gripper: 1.0,
        });
        pieces.extend(arm(&place, 0.0));
        pieces.push(Piece::Base(back));
        pieces.push(Piece::Hold {
            duration: self.cfg.dwell,
            gripper: 0.0,
        });
        let samples = self.sample(&pieces, 0.0);
        self.check_held_part(&samples, &w.parts[t.part].kind, &w.part_pose_at(t.from))?;
        let placed = |id: &str, kind: &str, pose: &Pose| Placed {
            id: id.to_string(),
            kind: kind.to_string(),
            pose: pose_to_array(pose),
        };
        let part = &w.parts[t.part];
        let (from, to) = (&w.locations[t.from], &w.locations[t.to]);
        let task = TaskRecord {
            part: placed(&part.id, &part.kind, &w.part_pose_at(t.from)),
            from: placed(&from.id, &from.kind, &w.location_pose(t.from)),
            to: placed(&to.id, &to.kind, &w.location_pose(t.to)),
            goal: pose_to_array(&w.part_pose_at(t.to)),
            note: Some(format!("prf gen, seed {seed}: {}", w.label(a))),
        };
        Ok((task, samples))
    }

    /// Samples the pieces at the configured rate starting at time `t0`; the last sample is the
    /// end of the program.
    fn sample(&self, pieces: &[Piece], t0: f64) -> Vec<Sample> {
        let home = self.cell.model.home;
        let durations: Vec<f64> = pieces
            .iter()
            .map(|p| match p {
                Piece::Base(m) => m.duration(),
                Piece::Arm { motion, .. } => motion.duration(),
                Piece::Hold { duration, .. } => *duration,
            })
            .collect();
        let total: f64 = durations.iter().sum();
        let dt = 1.0 / self.cfg.rate_hz;
        let n = (total / dt).ceil() as usize;
        // State carried across pieces: the base, the arm and the gripper at each piece's end.
        let mut state = Sample {
            t: 0.0,
            base: [0.0; 3],
            arm: home,
            gripper: 0.0,
        };
        if let Some(first_base) = pieces.iter().find_map(|p| match p {
            Piece::Base(m) => Some(m.start()),
            Piece::Arm { base, .. } => Some(*base),
            Piece::Hold { .. } => None,
        }) {
            state.base = first_base;
        }
        let mut out = Vec::with_capacity(n + 1);
        let mut k = 0usize;
        let mut start = 0.0;
        for (p, d) in pieces.iter().zip(&durations) {
            let end = start + d;
            let at = |s: &mut Sample, tau: f64| match p {
                Piece::Base(m) => {
                    s.base = m.at(tau);
                    s.arm = home;
                }
                Piece::Arm {
                    base,
                    motion,
                    reversed,
                } => {
                    s.base = *base;
                    s.arm = motion.at(if *reversed {
                        motion.duration() - tau
                    } else {
                        tau
                    });
                }
                Piece::Hold { gripper, .. } => s.gripper = *gripper,
            };
            while k <= n && (k as f64) * dt <= end + 1e-12 {
                let mut s = state;
                s.t = t0 + k as f64 * dt;
                at(&mut s, k as f64 * dt - start);
                out.push(s);
                k += 1;
            }
            at(&mut state, *d);
            start = end;
        }
        if let Some(last) = out.last()
            && last.t < t0 + total - 1e-9
        {
            let mut s = state;
            s.t = t0 + (k as f64) * dt;
            out.push(s);
        }
        out
    }
}
