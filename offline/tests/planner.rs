//! The generator's building blocks: IK, LSPB timing and RRT-Connect, each against an
//! independent check (forward kinematics, finite differences, dense edge re-checks).

use prf_shared::JointVector;
use prf_shared::kinematics::ArmKinematics;
use prf_shared::robot::RobotModel;
use prf_shared::se3::pose_error;
use prf_sim::demogen::ik::{self, IkConfig, IkError};
use prf_sim::demogen::rrt::{self, RrtConfig, RrtError, Space};
use prf_sim::demogen::timing::{Limits, Motion};
use rand::{RngExt, SeedableRng, rngs::StdRng};

#[test]
fn ik_reaches_poses_generated_by_fk() {
    let model = RobotModel::kmr_iiwa14();
    let home = JointVector::from(model.home);
    let mut rng = StdRng::seed_from_u64(11);
    let cfg = IkConfig::default();
    for _ in 0..25 {
        // A random configuration on the working elbow branch (joint 4 < 0), away from limits.
        let q: JointVector = JointVector::from_fn(|i, _| {
            let lim = model.joints[i].upper * 0.8;
            if i == 3 {
                rng.random_range(-lim..-0.3)
            } else {
                rng.random_range(-lim..lim)
            }
        });
        let target = ArmKinematics::new(&model, &q).tcp;
        let sol = ik::solve(&model, &target, &home, &cfg, |_| Ok(())).expect("reachable");
        let (dp, dr) = pose_error(&target, &ArmKinematics::new(&model, &sol).tcp);
        assert!(dp.norm() < 1e-6 && dr.norm() < 1e-6, "{dp:?} {dr:?}");
        assert!(model.limit_violation(&sol.into()).is_none());
    }
}

#[test]
fn ik_prefers_the_solution_closest_to_home() {
    let model = RobotModel::kmr_iiwa14();
    let home = JointVector::from(model.home);
    // The home TCP pose: the closest solution is home itself.
    let target = ArmKinematics::new(&model, &home).tcp;
    let sol = ik::solve(&model, &target, &home, &IkConfig::default(), |_| Ok(())).expect("home");
    assert!((sol - home).norm() < 1e-5, "{sol:?}");
    // Every other solution found is farther from home, and the order is stable.
    let all = ik::solutions(&model, &target, &home, &IkConfig::default()).expect("solutions");
    for w in all.windows(2) {
        assert!((w[0] - home).norm() <= (w[1] - home).norm());
    }
    // Rejecting the first solution yields the next one, and the reason is reported when all
    // are rejected.
    let second = ik::solve(&model, &target, &home, &IkConfig::default(), |q| {
        if (q - home).norm() < 1e-3 {
            Err("taken".into())
        } else {
            Ok(())
        }
    });
    if all.len() > 1 {
        assert!((second.expect("second") - all[1]).norm() < 1e-9);
    }
    let none = ik::solve(&model, &target, &home, &IkConfig::default(), |_| {
        Err("blocked".into())
    });
    assert!(matches!(none, Err(IkError::Rejected { ref reason, .. }) if reason == "blocked"));
}

#[test]
fn ik_reports_unreachable_goals() {
    let model = RobotModel::kmr_iiwa14();
    let home = JointVector::from(model.home);
    let mut target = ArmKinematics::new(&model, &home).tcp;
    target.translation.vector.x += 2.0;
    match ik::solve(&model, &target, &home, &IkConfig::default(), |_| Ok(())) {
        Err(IkError::Unreachable { position_error, .. }) => assert!(position_error > 0.5),
        other => panic!("{other:?}"),
    }
}

/// Samples a motion at `dt` and returns (max |v|/vmax, max |a|/amax) over all axes.
fn limit_ratios<const N: usize>(m: &Motion<N>, l: &Limits<N>, dt: f64) -> (f64, f64) {
    let n = (m.duration() / dt).ceil() as usize;
    let q: Vec<[f64; N]> = (0..=n + 1).map(|k| m.at(k as f64 * dt)).collect();
    let (mut v, mut a) = (0.0f64, 0.0f64);
    for k in 1..q.len() - 1 {
        for j in 0..N {
            v = v.max(((q[k + 1][j] - q[k][j]) / dt).abs() / l.speed[j]);
            a = a.max(
                ((q[k + 1][j] - 2.0 * q[k][j] + q[k - 1][j]) / (dt * dt)).abs() / l.acceleration[j],
            );
        }
    }
    (v, a)
}

#[test]
fn lspb_stays_within_limits_and_hits_its_ends() {
    // No jerk filter: the bare LSPB.
    let limits = Limits {
        speed: [1.0, 0.5, 2.0],
        acceleration: [2.0, 1.0, 4.0],
        jerk: [f64::INFINITY; 3],
    };
    let path = [
        [0.0, 0.0, 0.0],
        [1.0, 0.2, -0.5],
        [1.5, -0.8, 0.5],
        [0.2, -0.3, 1.5],
        [0.25, -0.3, 1.5],
    ];
    for blend in [true, false] {
        let m = Motion::new(&path, &limits, blend);
        assert_eq!(m.start(), path[0]);
        let end = m.end();
        for j in 0..3 {
            assert!((end[j] - path[4][j]).abs() < 1e-12);
        }
        let (v, a) = limit_ratios(&m, &limits, 1e-3);
        assert!(v <= 1.0 + 1e-9, "speed ratio {v}");
        assert!(a <= 1.0 + 1e-6, "acceleration ratio {a}");
        // Some axis actually uses its limits (time-optimal within the scheme).
        assert!(v > 0.99, "speed ratio {v}");
        // At rest at both ends.
        let d = m.duration();
        for j in 0..3 {
            assert!((m.at(1e-6)[j] - path[0][j]).abs() < 1e-9);
            assert!((m.at(d - 1e-6)[j] - path[4][j]).abs() < 1e-9);
        }
    }
    // Exact stops pass through every via point; blends are faster.
    let stops = Motion::new(&path, &limits, false);
    let blended = Motion::new(&path, &limits, true);
    assert!(blended.duration() < stops.duration());
    // Near a rest point q moves as ½ a t², so a 1e-4 s grid comes within 2e-8 of each via.
    let grid: Vec<[f64; 3]> = (0..=(stops.duration() / 1e-4) as usize)
        .map(|k| stops.at(k as f64 * 1e-4))
        .collect();
    let hit = path
        .iter()
        .filter(|w| {
            grid.iter()
                .any(|q| (0..3).all(|j| (w[j] - q[j]).abs() < 1e-6))
        })
        .count();
    assert_eq!(
        hit,
        path.len(),
        "the exact-stop motion rests at every via point"
    );
}

/// The jerk filter: the smoothed motion keeps speed, acceleration and jerk (third differences
/// at 1 ms) within the limits, starts and ends at rest on the path's ends, and takes the
/// filter window longer than the bare LSPB.
#[test]
fn the_jerk_filter_keeps_every_limit() {
    let bare = Limits {
        speed: [1.0, 0.5, 2.0],
        acceleration: [2.0, 1.0, 4.0],
        jerk: [f64::INFINITY; 3],
    };
    let limits = Limits {
        jerk: [20.0, 10.0, 40.0],
        ..bare
    };
    let path = [[0.0, 0.0, 0.0], [1.0, 0.2, -0.5], [1.5, -0.8, 0.5]];
    for blend in [true, false] {
        let m = Motion::new(&path, &limits, blend);
        let raw = Motion::new(&path, &bare, blend);
        // Window 2·a/j = 0.2 s on every axis.
        assert!((m.duration() - raw.duration() - 0.2).abs() < 1e-12);
        let dt = 1e-3;
        let n = (m.duration() / dt).ceil() as usize + 3;
        let q: Vec<[f64; 3]> = (0..=n).map(|k| m.at(k as f64 * dt - 2.0 * dt)).collect();
        let (mut rv, mut ra, mut rj) = (0.0f64, 0.0f64, 0.0f64);
        for k in 3..q.len() {
            for j in 0..3 {
                let d1 = q[k][j] - q[k - 1][j];
                let d2 = q[k][j] - 2.0 * q[k - 1][j] + q[k - 2][j];
                let d3 = q[k][j] - 3.0 * q[k - 1][j] + 3.0 * q[k - 2][j] - q[k - 3][j];
                rv = rv.max(d1.abs() / dt / limits.speed[j]);
                ra = ra.max(d2.abs() / (dt * dt) / limits.acceleration[j]);
                rj = rj.max(d3.abs() / (dt * dt * dt) / limits.jerk[j]);
            }
        }
        assert!(
            rv <= 1.0 + 1e-9 && ra <= 1.0 + 1e-6,
            "speed {rv}, acceleration {ra}"
        );
        assert!(rj <= 1.0 + 1e-6, "jerk ratio {rj}");
        // Without the filter the same path steps its acceleration: far above the jerk limit.
        let qr: Vec<[f64; 3]> = (0..=n).map(|k| raw.at(k as f64 * dt - 2.0 * dt)).collect();
        let jerk = (3..qr.len())
            .map(|k| {
                let d3 = qr[k][0] - 3.0 * qr[k - 1][0] + 3.0 * qr[k - 2][0] - qr[k - 3][0];
                d3.abs() / (dt * dt * dt) / limits.jerk[0]
            })
            .fold(0.0, f64::max);
        assert!(jerk > 10.0, "unfiltered jerk ratio {jerk}");
        for j in 0..3 {
            assert!((m.start()[j] - path[0][j]).abs() < 1e-12);
            assert!((m.end()[j] - path[2][j]).abs() < 1e-12);
        }
    }
}

/// The unit square with a wall at x = 0.5 except for a gap at y ∈ [0.45, 0.55].
struct Wall;

impl Space<2> for Wall {
    fn lower(&self) -> [f64; 2] {
        [0.0, 0.0]
    }
    fn upper(&self) -> [f64; 2] {
        [1.0, 1.0]
    }
    fn valid(&self, q: &[f64; 2]) -> bool {
        let in_square = (0.0..=1.0).contains(&q[0]) && (0.0..=1.0).contains(&q[1]);
        let off_wall = (q[0] - 0.5).abs() >= 0.02;
        let in_gap = (0.45..=0.55).contains(&q[1]);
        in_square && (off_wall || in_gap)
    }
    fn edge_valid(&self, a: &[f64; 2], b: &[f64; 2]) -> bool {
        let n = 200;
        (0..=n).all(|k| {
            let u = k as f64 / n as f64;
            self.valid(&[a[0] + (b[0] - a[0]) * u, a[1] + (b[1] - a[1]) * u])
        })
    }
}

#[test]
fn rrt_connect_finds_the_gap_and_is_deterministic() {
    let cfg = RrtConfig {
        step: 0.05,
        ..RrtConfig::default()
    };
    let (start, goal) = ([0.1, 0.1], [0.9, 0.9]);
    let plan = |seed| rrt::plan(&Wall, start, goal, &cfg, &mut StdRng::seed_from_u64(seed));
    let path = plan(5).expect("path");
    assert_eq!(path[0], start);
    assert_eq!(*path.last().expect("end"), goal);
    // Every edge re-checked at a 10× finer resolution than the planner's.
    for e in path.windows(2) {
        for k in 0..=2000 {
            let u = k as f64 / 2000.0;
            assert!(Wall.valid(&[
                e[0][0] + (e[1][0] - e[0][0]) * u,
                e[0][1] + (e[1][1] - e[0][1]) * u
            ]));
        }
    }
    // Shortcut and pruned: through the gap in few edges.
    assert!(path.len() <= 4, "{path:?}");
    assert_eq!(plan(5).expect("again"), path);
    assert_eq!(
        rrt::plan(&Wall, [0.5, 0.1], goal, &cfg, &mut StdRng::seed_from_u64(1)),
        Err(RrtError::InvalidStart)
    );
}

#[test]
fn rrt_gives_up_when_no_path_exists() {
    struct Closed;
    impl Space<2> for Closed {
        fn lower(&self) -> [f64; 2] {
            [0.0, 0.0]
        }
        fn upper(&self) -> [f64; 2] {
            [1.0, 1.0]
        }
        fn valid(&self, q: &[f64; 2]) -> bool {
            (q[0] - 0.5).abs() > 0.02
        }
        fn edge_valid(&self, a: &[f64; 2], b: &[f64; 2]) -> bool {
            (a[0] < 0.5) == (b[0] < 0.5) && self.valid(a) && self.valid(b)
        }
    }
    let cfg = RrtConfig {
        max_iterations: 500,
        attempts: 3,
        ..RrtConfig::default()
    };
    let r = rrt::plan(
        &Closed,
        [0.1, 0.1],
        [0.9, 0.9],
        &cfg,
        &mut StdRng::seed_from_u64(1),
    );
    assert_eq!(r, Err(RrtError::NoPath { iterations: 1500 }));
}
