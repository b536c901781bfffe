//! Motion classes: the symbolic templates are well formed, Φ_x and G chain a Pick, a Move and
//! a Place so the part lands exactly on its goal, and segment() finds the instances of a
//! synthetic program.

use prf_shared::JointVector;
use prf_shared::motion::{
    CLASSES, Goal, GoalContext, MotionClass, PhysicalState, Sample, TaskLocation, Value, class,
};
use prf_shared::robot::RobotModel;
use prf_shared::se3::{Pose, pose_bits, pose_from_xyz_rpy};

#[test]
fn templates_are_well_formed() {
    for c in CLASSES.iter() {
        let a = c.action();
        assert_eq!(a.head.as_str(), c.name());
        for atom in a.pre.iter().chain(&a.eff) {
            assert!(
                atom.args.iter().all(|&i| (i as usize) < a.params.len()),
                "{}",
                c.name()
            );
            if let Value::Param(i) = atom.value {
                assert!((i as usize) < a.params.len());
            }
        }
        if let Some(other) = c.shares_with() {
            assert_eq!(class(other).and_then(|o| o.shares_with()), Some(c.name()));
        }
    }
}

/// Pick, Move and Place.
fn ptt_classes() -> (
    &'static dyn MotionClass,
    &'static dyn MotionClass,
    &'static dyn MotionClass,
) {
    let c = |name| class(name).unwrap();
    (c("Pick"), c("Move"), c("Place"))
}

#[test]
fn pick_move_place_put_the_part_on_its_goal() {
    let model = RobotModel::kmr_iiwa14();
    let (pick, mv, place) = ptt_classes();
    let part = pose_from_xyz_rpy([1.0, -1.2, 0.9], [0.0, 0.0, 0.4]);
    let grasp = pose_from_xyz_rpy([0.0, 0.0, 0.05], [std::f64::consts::PI, 0.0, 0.0]);
    let goal = pose_from_xyz_rpy([3.0, 1.5, 0.8], [0.0, 0.0, -1.0]);
    let x0 = PhysicalState {
        base: pose_from_xyz_rpy([1.0, -0.4, 0.0], [0.0, 0.0, -1.5]),
        arm: JointVector::from(model.home),
        gripper: 0.0,
        part,
        grasp: None,
    };
    fn cx<'a>(
        model: &'a RobotModel,
        goal: Pose,
        grasp: &'a Pose,
        location: Pose,
        stances: &'a [Pose],
    ) -> GoalContext<'a> {
        GoalContext {
            model,
            part_goal: goal,
            location,
            stances,
            grasps: std::slice::from_ref(grasp),
        }
    }
    let mut goals = Vec::new();
    pick.goals(
        &x0,
        &cx(&model, goal, &grasp, Pose::identity(), &[]),
        &mut |g| goals.push(g),
    );
    let [g] = goals[..] else {
        panic!("one grasp, one goal")
    };
    let x1 = pick.transition(&model, &x0, &g);
    assert_eq!(x1.gripper, 1.0);
    assert_eq!(x1.grasp, Some(grasp), "the grasp is held");
    // Held: the TCP sits on the grasp of the part.
    let rel = x1.part.inverse() * x1.tcp(&model);
    assert!((rel.inverse() * grasp).translation.vector.norm() < 1e-12);
    let stance = [pose_from_xyz_rpy(
        [0.0, -0.9, 0.0],
        [0.0, 0.0, std::f64::consts::FRAC_PI_2],
    )];
    let location = pose_from_xyz_rpy([3.1, 2.3, 0.0], [0.0, 0.0, -1.0]);
    let mut goals = Vec::new();
    mv.goals(
        &x1,
        &cx(&model, goal, &grasp, location, &stance),
        &mut |g| goals.push(g),
    );
    let [Goal::Base(b)] = goals[..] else {
        panic!("one stance, one goal")
    };
    assert!(
        ((location * stance[0]).inverse() * b)
            .translation
            .vector
            .norm()
            < 1e-12
    );
    let x2 = mv.transition(&model, &x1, &Goal::Base(b));
    let rel2 = x2.part.inverse() * x2.tcp(&model);
    assert!(
        (rel2.inverse() * rel).translation.vector.norm() < 1e-12,
        "the part rides along"
    );
    let mut goals = Vec::new();
    place.goals(&x2, &cx(&model, goal, &grasp, location, &[]), &mut |g| {
        goals.push(g)
    });
    let x3 = place.transition(&model, &x2, &goals[0]);
    assert_eq!(x3.gripper, 0.0);
    assert_eq!(x3.grasp, None, "nothing is held");
    let d = x3.part.inverse() * goal;
    assert!(
        d.translation.vector.norm() < 1e-12 && d.rotation.angle() < 1e-12,
        "{d:?}"
    );
    // An empty-handed Move leaves the part where it is.
    let x4 = mv.transition(&model, &x3, &Goal::Base(Pose::identity()));
    assert_eq!(x4.part, x3.part);
}

/// Place's goal comes from the grasp held, so the same stance, grasp and part goal give the
/// same bits whichever location and platform pose the part was picked at (what lets a
/// planner recall a place evaluation across tasks). It agrees with the route through the
/// part's pose, T_B⁻¹ T_p,g T_p⁻¹ T_B F_a(q_a), within rounding, and puts the part on its goal.
#[test]
fn place_goals_are_the_same_bits_whichever_location_the_part_came_from() {
    let model = RobotModel::kmr_iiwa14();
    let (pick, mv, place) = ptt_classes();
    let grasps = [pose_from_xyz_rpy(
        [0.01, -0.02, 0.05],
        [std::f64::consts::PI, 0.1, 0.3],
    )];
    let part_goal = pose_from_xyz_rpy([3.0, 1.5, 0.8], [0.0, 0.0, -1.0]);
    let location = pose_from_xyz_rpy([3.1, 2.3, 0.0], [0.0, 0.0, -1.0]);
    let stances = [pose_from_xyz_rpy([0.0, -0.9, 0.0], [0.0, 0.0, 1.5])];
    let cx = |location: Pose, stances| GoalContext {
        model: &model,
        part_goal,
        location,
        stances,
        grasps: &grasps,
    };
    let mut first: Option<[u64; 7]> = None;
    for (i, (part, base)) in [
        ([1.0, -1.2, 0.9, 0.4], [1.0, -0.4, -1.5]),
        ([-2.3, 0.7, 1.1, 2.9], [-2.2, 0.1, 1.2]),
        ([0.31, 4.9, 0.62, -1.7], [0.9, 4.1, 0.3]),
    ]
    .into_iter()
    .enumerate()
    {
        let x0 = PhysicalState {
            base: pose_from_xyz_rpy([base[0], base[1], 0.0], [0.0, 0.0, base[2]]),
            arm: JointVector::from(model.home),
            gripper: 0.0,
            part: pose_from_xyz_rpy([part[0], part[1], part[2]], [0.0, 0.0, part[3]]),
            grasp: None,
        };
        let mut goals = Vec::new();
        pick.goals(&x0, &cx(Pose::identity(), &[]), &mut |g| goals.push(g));
        let x1 = pick.transition(&model, &x0, &goals[0]);
        let mut goals = Vec::new();
        mv.goals(&x1, &cx(location, &stances), &mut |g| goals.push(g));
        let x2 = mv.transition(&model, &x1, &goals[0]);
        let mut goals = Vec::new();
        place.goals(&x2, &cx(location, &stances), &mut |g| goals.push(g));
        let [Goal::Tcp { pose, grasp }] = goals[..] else {
            panic!("one TCP goal")
        };
        assert_eq!(grasp, grasps[0]);
        assert_eq!(
            *first.get_or_insert(pose_bits(&pose)),
            pose_bits(&pose),
            "pick {i}"
        );
        let arm_base = x2.base * model.mount;
        let through_part = arm_base.inverse() * part_goal * x2.part.inverse() * x2.tcp(&model);
        let d = through_part.inverse() * pose;
        assert!(
            d.translation.vector.norm() < 1e-12 && d.rotation.angle() < 1e-12,
            "pick {i}: {d:?}"
        );
        let x3 = place.transition(&model, &x2, &goals[0]);
        let d = x3.part.inverse() * part_goal;
        assert!(
            d.translation.vector.norm() < 1e-12 && d.rotation.angle() < 1e-12,
            "pick {i}: {d:?}"
        );
    }
}

#[test]
fn segment_finds_pick_place_and_moves() {
    let home = RobotModel::kmr_iiwa14().home;
    let mut q1 = home;
    q1[1] += 0.5;
    let mut p = Vec::new();
    let mut push = |base: [f64; 3], arm: [f64; 7], gripper: f64| {
        p.push(Sample {
            t: p.len() as f64 * 0.01,
            base,
            arm,
            gripper,
        })
    };
    let lerp =
        |a: &[f64; 7], b: &[f64; 7], u: f64| core::array::from_fn(|i| a[i] + (b[i] - a[i]) * u);
    let arm_motion = |push: &mut dyn FnMut([f64; 3], [f64; 7], f64), base, g0: f64, g1: f64| {
        for k in 0..=10 {
            push(base, lerp(&home, &q1, k as f64 / 10.0), g0);
        }
        for _ in 0..5 {
            push(base, q1, g1);
        }
        for k in 0..=10 {
            push(base, lerp(&q1, &home, k as f64 / 10.0), g1);
        }
    };
    for k in 0..=10 {
        push([k as f64 * 0.1, 0.0, 0.0], home, 0.0);
    }
    arm_motion(&mut push, [1.0, 0.0, 0.0], 0.0, 1.0);
    for k in 0..=10 {
        push([1.0 + k as f64 * 0.1, 0.0, 0.0], home, 1.0);
    }
    arm_motion(&mut push, [2.0, 0.0, 0.0], 1.0, 0.0);
    for k in 0..=10 {
        push([2.0 - k as f64 * 0.2, 0.0, 0.0], home, 0.0);
    }
    let found = |name: &str| {
        let mut v = Vec::new();
        class(name).unwrap().segment(&p, &mut |i| v.push(i));
        v
    };
    let (picks, places, moves) = (found("Pick"), found("Place"), found("Move"));
    assert_eq!((picks.len(), places.len(), moves.len()), (1, 1, 3));
    let pick = &picks[0];
    let fwd = pick.arm.clone().unwrap().forward;
    assert_eq!((p[fwd.start].arm, p[fwd.end - 1].arm), (home, q1));
    assert_eq!(p[pick.range.end - 1].arm, home);
    assert_eq!(pick.location, Some(TaskLocation::From));
    assert_eq!(places[0].location, Some(TaskLocation::To));
    let arrivals: Vec<_> = moves.iter().map(|m| m.location).collect();
    assert_eq!(
        arrivals,
        vec![Some(TaskLocation::From), Some(TaskLocation::To), None]
    );
}
