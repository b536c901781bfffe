//! Learn (Alg. 3) and the blob on the example cell's 64 demonstrations, against independent
//! references: the generator's ground-truth stances and grasps, brute-force distances to the
//! demonstrated spheres, and the demonstrations themselves.

mod common;

use common::TempDir;
use nalgebra::{Translation3, Vector3};
use prf_files::dataset::{Dataset, Demonstration};
use prf_learn::compile;
use prf_learn::workspace::Sweep;
use prf_learn::{Knowledge, LearnConfig, LearnError, affordance, learn};
use prf_shared::JointVector;
use prf_shared::blob::{Blob, BlobError, HEADER_LEN, VERSION, crc32};
use prf_shared::field::{DistanceField, Field};
use prf_shared::kinematics::{ArmKinematics, arm_base_pose};
use prf_shared::motion::{CLASSES, TaskLocation};
use prf_shared::risk::RiskAccumulator;
use prf_shared::robot::RobotModel;
use prf_shared::se3::{Pose, pose_from_array};
use prf_sim::demogen::generate_dataset;
use prf_sim::world::World;
use rand::{RngExt, SeedableRng, rngs::StdRng};
use std::sync::OnceLock;

struct Fixture {
    world: World,
    model: RobotModel,
    dataset: Dataset,
    knowledge: Knowledge,
}

/// The 64 demonstrations, written and read back, and what Learn makes of them (once).
fn fixture() -> &'static Fixture {
    static F: OnceLock<Fixture> = OnceLock::new();
    F.get_or_init(|| {
        let world = World::example();
        let model = RobotModel::kmr_iiwa14();
        let all = world.afforded_tasks();
        let generated = generate_dataset(&world, &all, 1, 100.0, &prf_files::progress::quiet)
            .expect("generation");
        let dir = TempDir::new("learn");
        generated.write(dir.path()).expect("write");
        let dataset = Dataset::read(dir.path(), &model).expect("read");
        let knowledge = learn(
            &dataset,
            &model,
            &LearnConfig::default(),
            &prf_files::progress::quiet,
        )
        .expect("learn");
        Fixture {
            world,
            model,
            dataset,
            knowledge,
        }
    })
}

#[test]
fn learning_recovers_the_generators_stances_and_grasps() {
    let f = fixture();
    for t in &f.knowledge.location_types {
        let truth: Vec<Pose> = f.world.location_types
            [f.world.location_type_index(&t.name).unwrap()]
        .approaches
        .iter()
        .map(|a| a.stance.pose())
        .collect();
        assert_eq!(t.stances.len(), truth.len(), "{}: stances", t.name);
        for p in &truth {
            let i = t
                .stances
                .find(p)
                .unwrap_or_else(|| panic!("{}: stance {p:?} not learned", t.name));
            let d = t.stances.poses[i].inverse() * p;
            assert!(d.translation.vector.norm() < 1e-6 && d.rotation.angle() < 1e-6);
        }
    }
    for t in &f.knowledge.part_types {
        let truth: Vec<Pose> = f.world.part_types[f.world.part_type_index(&t.name).unwrap()]
            .grasps
            .iter()
            .map(|g| g.tcp.pose())
            .collect();
        assert_eq!(t.grasps.len(), truth.len(), "{}: grasps", t.name);
        for g in &truth {
            let i = t
                .grasps
                .find(g)
                .unwrap_or_else(|| panic!("{}: grasp not learned", t.name));
            let d = t.grasps.poses[i].inverse() * g;
            assert!(d.translation.vector.norm() < 1e-6 && d.rotation.angle() < 1e-6);
        }
    }
    // Every program is Move, Pick, Move, Place, Move.
    let counts: Vec<usize> = f.knowledge.instances.iter().map(|c| c.1).collect();
    assert_eq!(counts, vec![64, 64, 192]);
    // share(): every Pick skill serves Place and vice versa, each RDMP once per class.
    for (a, b) in [("Pick", "Place"), ("Place", "Pick")] {
        for s in f.knowledge.skills.iter().filter(|s| s.class == a) {
            assert!(
                f.knowledge
                    .skills
                    .iter()
                    .any(|k| k.class == b && k.rdmp == s.rdmp)
            );
        }
    }
    assert!(affordance::same(
        &Pose::identity(),
        &Pose::translation(5e-4, 0.0, 0.0)
    ));
    assert!(!affordance::same(
        &Pose::identity(),
        &Pose::translation(2e-3, 0.0, 0.0)
    ));
}

/// The Pick and Place instances of a demonstration: (location type index, arm base in the
/// location frame, arm samples).
fn arm_instances(f: &Fixture, d: &Demonstration) -> Vec<(usize, Pose, Vec<[f64; 7]>)> {
    let mut out = Vec::new();
    for m in CLASSES.iter().filter(|m| m.learns_workspace()) {
        m.segment(&d.samples, &mut |i| {
            let placed = match i.location {
                Some(TaskLocation::From) => &d.task.from,
                Some(TaskLocation::To) => &d.task.to,
                None => return,
            };
            let t = f
                .knowledge
                .location_types
                .iter()
                .position(|l| l.name == placed.kind)
                .unwrap();
            let base = pose_from_array(placed.pose).unwrap().inverse()
                * arm_base_pose(&f.model, d.samples[i.at].base);
            out.push((t, base, d.samples[i.range].iter().map(|s| s.arm).collect()));
        });
    }
    out
}

/// The learned field of location type `t`.
fn workspace(f: &Fixture, t: usize) -> Field<'_> {
    f.knowledge.location_types[t]
        .field
        .as_ref()
        .unwrap()
        .field()
}

/// Risk (Eq. 16) of a configuration path, evaluated at the samples and linearly in between
/// (8 evaluations per sample interval).
fn path_risk(model: &RobotModel, field: &Field, base: &Pose, path: &[[f64; 7]]) -> f64 {
    let mut acc = RiskAccumulator::default();
    for w in path.windows(2) {
        let (a, b) = (JointVector::from(w[0]), JointVector::from(w[1]));
        let n = 8;
        for s in 0..n {
            let q = a.lerp(&b, s as f64 / n as f64);
            acc.add(model, field, base, &ArmKinematics::new(model, &q));
        }
    }
    acc.add(
        model,
        field,
        base,
        &ArmKinematics::new(model, &JointVector::from(*path.last().unwrap())),
    );
    acc.risk()
}

#[test]
fn every_demonstration_segment_has_risk_zero() {
    let f = fixture();
    for d in &f.dataset.demonstrations {
        for (t, base, path) in arm_instances(f, d) {
            let field = workspace(f, t);
            let r = path_risk(&f.model, &field, &base, &path);
            assert_eq!(
                r, 0.0,
                "{}: risk {r} at {}",
                d.id, f.knowledge.location_types[t].name
            );
        }
    }
}

/// Brute-force signed distance to the union of the balls B(c, r + ε) of a sweep: exact
/// outside, the deepest single ball inside.
fn brute(sweep: &Sweep, eps: f64, x: &Vector3<f64>) -> f64 {
    sweep
        .spheres
        .iter()
        .map(|s| (x - s.centre).norm() - (s.radius + eps))
        .fold(f64::INFINITY, f64::min)
}

/// The sweep Learn builds for a location type, rebuilt from the dataset.
fn sweep_of(f: &Fixture, t: usize) -> Sweep {
    let mut sweep = Sweep::default();
    for d in &f.dataset.demonstrations {
        for (ti, base, path) in arm_instances(f, d) {
            if ti == t {
                sweep.add_path(
                    &f.model,
                    &base,
                    &path,
                    f.knowledge.config.workspace.resample,
                );
            }
        }
    }
    sweep
}

#[test]
fn a_trajectory_pushed_10_cm_out_has_the_exact_risk_within_one_voxel() {
    let f = fixture();
    let t = f
        .knowledge
        .location_types
        .iter()
        .position(|l| l.name == "Table")
        .unwrap();
    let field = workspace(f, t);
    let sweep = sweep_of(f, t);
    let eps = f.knowledge.config.workspace.epsilon;
    let d = f
        .dataset
        .demonstrations
        .iter()
        .find(|d| d.task.to.kind == "Table")
        .unwrap();
    let (_, base, path) = arm_instances(f, d)
        .into_iter()
        .find(|(ti, ..)| *ti == t)
        .unwrap();
    // Up 10 cm: the top of every sweep at the table is free space.
    let pushed = Pose::translation(0.0, 0.0, 0.10) * base;
    let (mut exact, mut looked_up) = (f64::NEG_INFINITY, f64::NEG_INFINITY);
    for q in path.iter().step_by(5) {
        let kin = ArmKinematics::new(&f.model, &JointVector::from(*q));
        let mut c = [Vector3::zeros(); 48];
        kin.sphere_centres(&f.model, &mut c);
        for (s, c) in f.model.spheres.iter().zip(&c) {
            let x = pushed.transform_point(&(*c).into()).coords;
            exact = exact.max(brute(&sweep, eps, &x) + s.radius);
            looked_up = looked_up.max(field.distance(&x) + s.radius);
        }
    }
    let h = field.voxel();
    assert!(exact > 0.05, "the push leaves Ω+: exact risk {exact}");
    assert!(
        looked_up >= exact - 1e-12 && looked_up - exact <= h,
        "risk {looked_up} vs exact {exact}, voxel {h}"
    );
}

#[test]
fn the_field_is_conservative_and_at_most_one_voxel_diagonal_shallow() {
    let f = fixture();
    let t = f
        .knowledge
        .location_types
        .iter()
        .position(|l| l.name == "Printer")
        .unwrap();
    let learned = f.knowledge.location_types[t].field.as_ref().unwrap();
    let field = learned.field();
    let sweep = sweep_of(f, t);
    let eps = f.knowledge.config.workspace.epsilon;
    let h = field.voxel();
    let far = f.knowledge.config.workspace.far;
    let dims = field.dims();
    let lo = field.node_position(0, 0, 0);
    let hi = field.node_position(dims[0] - 1, dims[1] - 1, dims[2] - 1);
    let mut rng = StdRng::seed_from_u64(3);
    let (mut inside, mut outside, mut worst) = (0, 0, 0.0f64);
    // Half the points near demonstrated spheres (where it matters), half anywhere in the box.
    for k in 0..1500 {
        let x = if k % 2 == 0 {
            let s = &sweep.spheres.get(rng.random_range(0..sweep.spheres.len()));
            s.centre + Vector3::from_fn(|_, _| rng.random_range(-0.15..0.15))
        } else {
            Vector3::from_fn(|i, _| rng.random_range(lo[i]..hi[i]))
        };
        let reference = brute(&sweep, eps, &x);
        let d = field.distance(&x);
        // Never deeper than the deepest single ball, hence never deeper than Ω+ itself.
        assert!(d >= reference - 1e-9, "deeper at {x:?}: {d} < {reference}");
        // Within the stored bricks: every corner of its cell is closer than `far` to Ω+.
        if reference < far - h * 3f64.sqrt() / 2.0 {
            worst = worst.max(d - reference);
            assert!(
                d - reference <= h * 3f64.sqrt(),
                "too shallow at {x:?}: {d} vs {reference}"
            );
            if reference < 0.0 {
                inside += 1
            } else {
                outside += 1
            }
        }
    }
    assert!(
        inside > 100 && outside > 100,
        "{inside} inside, {outside} outside"
    );
    println!(
        "worst shallowness {worst:.4} m (voxel diagonal {:.4} m)",
        h * 3f64.sqrt()
    );
}

#[test]
fn blob_round_trip() {
    let f = fixture();
    let bytes = compile(&f.knowledge).expect("compile");
    assert!(bytes.len() < 1 << 20);
    let blob = Blob::parse(&bytes).expect("parse");
    assert_eq!(blob.robot().unwrap(), f.model);
    for (i, t) in f.knowledge.location_types.iter().enumerate() {
        let lt = blob.location_type(i).unwrap();
        assert_eq!(lt.name, t.name);
        assert_eq!(lt.stances.len(), t.stances.len());
        for (a, b) in lt.stances.iter().zip(&t.stances.poses) {
            let d = pose_from_array(*a).unwrap().inverse() * b;
            assert!(d.translation.vector.norm() < 1e-12 && d.rotation.angle() < 1e-9);
        }
        // The blob's field answers exactly as the learned one.
        let (a, b) = (
            Field::new(lt.workspace.as_ref().unwrap()).unwrap(),
            t.field.as_ref().unwrap().field(),
        );
        let mut rng = StdRng::seed_from_u64(i as u64);
        for _ in 0..200 {
            let x = Vector3::from_fn(|_, _| rng.random_range(-1.0..2.0));
            assert_eq!(a.distance(&x), b.distance(&x));
        }
    }
    for (i, arm) in f.knowledge.arms.iter().enumerate() {
        let r = blob.rdmp(i).unwrap();
        assert_eq!(r.duration(), arm.rdmp.duration());
        for c in 0..3 {
            for (w, v) in r.position.forcing.weights[c]
                .iter()
                .zip(&arm.rdmp.position.forcing.weights[c])
            {
                assert!((w - v).abs() <= 1e-6 * v.abs().max(1.0), "{w} vs {v}");
            }
        }
    }
    assert_eq!(blob.payload.skills.len(), f.knowledge.skills.len());
}

#[test]
fn corrupt_blobs_are_refused_with_their_own_error() {
    let f = fixture();
    let bytes = compile(&f.knowledge).expect("compile");
    // Truncated anywhere: header or payload.
    for cut in [0, 10, HEADER_LEN, bytes.len() / 2, bytes.len() - 1] {
        assert!(
            matches!(Blob::parse(&bytes[..cut]), Err(BlobError::Truncated { .. })),
            "cut {cut}"
        );
    }
    // A flipped bit anywhere in the payload.
    let mut rng = StdRng::seed_from_u64(9);
    for _ in 0..50 {
        let mut b = bytes.clone();
        let i = rng.random_range(HEADER_LEN..b.len());
        b[i] ^= 1 << rng.random_range(0..8);
        assert!(matches!(Blob::parse(&b), Err(BlobError::Checksum { .. })));
    }
    let mut b = bytes.clone();
    b[0] = b'X';
    assert_eq!(Blob::parse(&b).unwrap_err(), BlobError::BadMagic);
    let mut b = bytes.clone();
    b[8..12].copy_from_slice(&(VERSION + 1).to_le_bytes());
    assert_eq!(
        Blob::parse(&b).unwrap_err(),
        BlobError::Version {
            found: VERSION + 1,
            supported: VERSION
        }
    );
    let mut b = bytes.clone();
    b.push(0);
    assert!(matches!(
        Blob::parse(&b),
        Err(BlobError::TrailingBytes { .. })
    ));
    // Corruption behind a valid checksum (a buggy writer): refused by decoding or
    // validation, never a panic.
    for _ in 0..300 {
        let mut b = bytes.clone();
        for _ in 0..rng.random_range(1..4) {
            let i = rng.random_range(HEADER_LEN..b.len());
            b[i] = rng.random();
        }
        let crc = crc32(&b[HEADER_LEN..]);
        b[16..20].copy_from_slice(&crc.to_le_bytes());
        if let Ok(blob) = Blob::parse(&b) {
            // Accepted: every record still decodes (the change hit a value, not structure).
            for i in 0..blob.payload.rdmps.len() {
                blob.rdmp(i).unwrap();
            }
        }
    }
}

/// Issue 23: r_d is a fact of the dataset. Without it learning is refused, with a larger one
/// than stated too; with its own r_d = 0.04 m it learns ε = r_d − r = 10 mm (the workspace is
/// 10 mm shallower than with r_d = 0.05 m), and the blob says so.
#[test]
fn learning_takes_r_d_from_the_dataset_and_refuses_to_guess() {
    let f = fixture();
    let mut ds = f.dataset.clone();
    ds.demonstrations.truncate(8);
    let learn_with =
        |ds: &Dataset, cfg: LearnConfig| learn(ds, &f.model, &cfg, &prf_files::progress::quiet);
    let mut unstated = ds.clone();
    unstated.clearance_demo = None;
    let e = learn_with(&unstated, LearnConfig::default()).expect_err("no r_d");
    assert!(matches!(e, LearnError::NoClearance));
    assert!(e.to_string().contains("clearance_demo_m"), "{e}");
    let mut stated = ds.clone();
    stated.clearance_demo = Some(0.04);
    let old_default = LearnConfig {
        clearance_demo: Some(0.05),
        ..LearnConfig::default()
    };
    let e = learn_with(&stated, old_default).expect_err("r_d above the stated one");
    assert!(
        matches!(e, LearnError::ClearanceAboveStated { requested, stated } if requested == 0.05 && stated == 0.04)
    );
    let own = learn_with(&stated, LearnConfig::default()).expect("learns with its own r_d");
    assert_eq!(own.clearance_demo, 0.04);
    let wider = learn_with(&ds, LearnConfig::default()).expect("learns with r_d = 0.05");
    assert_eq!(wider.clearance_demo, 0.05);
    // The workspace own learned is Ω+ dilated by 10 mm: never deeper than the brute-force
    // distance to the demonstrated spheres grown by 10 mm, where the r_d = 0.05 one (20 mm) is.
    let t = own
        .location_types
        .iter()
        .position(|l| l.field.is_some())
        .expect("a workspace");
    let name = &own.location_types[t].name;
    let mut sweep = Sweep::default();
    for d in &ds.demonstrations {
        for (ti, base, path) in arm_instances(f, d) {
            if f.knowledge.location_types[ti].name == *name {
                sweep.add_path(&f.model, &base, &path, own.config.workspace.resample);
            }
        }
    }
    let own_field = own.location_types[t].field.as_ref().unwrap().field();
    let wider_field = wider.location_types[t].field.as_ref().unwrap().field();
    let mut rng = StdRng::seed_from_u64(23);
    let mut deeper = 0.0f64;
    for _ in 0..1000 {
        let s = &sweep.spheres.get(rng.random_range(0..sweep.spheres.len()));
        let x = s.centre + Vector3::from_fn(|_, _| rng.random_range(-0.15..0.15));
        let reference = brute(&sweep, 0.010, &x);
        assert!(
            own_field.distance(&x) >= reference - 1e-9,
            "deeper than a 10 mm dilation at {x:?}"
        );
        deeper = deeper.max(reference - wider_field.distance(&x));
    }
    assert!(deeper > 0.005, "the 20 mm workspace is deeper by {deeper}");
    let report = prf_learn::report(&compile(&own).expect("compile")).expect("report");
    assert!(
        report.contains("r_d = 40 mm, r = 30 mm (ε = 10 mm)"),
        "{report}"
    );
}

/// The field's lower bound over a ball (the planner's admissible bound at a goal pose) is
/// below the field at random points of the ball, inside and outside the grid box.
#[test]
fn the_lower_bound_within_a_ball_is_below_every_lookup_in_it() {
    let f = fixture();
    let mut rng = StdRng::seed_from_u64(22);
    let mut tight = 0.0f64;
    for lt in &f.knowledge.location_types {
        let Some(learned) = lt.field.as_ref() else {
            continue;
        };
        let field = learned.field();
        let dims = field.dims();
        let lo = field.node_position(0, 0, 0);
        let hi = field.node_position(dims[0] - 1, dims[1] - 1, dims[2] - 1);
        for _ in 0..400 {
            // Some centres beyond the grid box, so balls cross its faces too.
            let p = Vector3::from_fn(|i, _| rng.random_range(lo[i] - 0.05..hi[i] + 0.05));
            let delta = rng.random_range(0.0..0.01);
            let bound = field.distance_lower_within(&p, delta);
            assert!(bound <= field.distance(&p) + 1e-12);
            for _ in 0..20 {
                let u = Vector3::from_fn(|_, _| rng.random_range(-1.0..1.0));
                let x = p + u.normalize() * delta * rng.random_range(0.0..=1.0f64).cbrt();
                let d = field.distance(&x);
                assert!(
                    d >= bound - 1e-12,
                    "{d} < bound {bound} at {x:?} (p {p:?}, δ {delta})"
                );
                tight = tight.max(d - bound);
            }
        }
    }
    println!(
        "largest gap between a lookup and the ball's bound: {:.2} mm",
        tight * 1e3
    );
}

/// Anchored lookups (a hint that settles a moving point without reading the field while it
/// stays in its cell and within its slack) against full lookups, along every demonstrated
/// sphere path and along the same paths pushed 0–15 cm off, with rising stops.
#[test]
fn anchored_lookups_agree_with_full_lookups() {
    use prf_shared::field::Hint;
    use prf_shared::robot::MAX_SPHERES;
    let f = fixture();
    let mut rng = StdRng::seed_from_u64(5);
    let (mut lookups, mut skipped) = (0usize, 0usize);
    for d in f.dataset.demonstrations.iter().step_by(4) {
        for (t, base, path) in arm_instances(f, d) {
            let field = workspace(f, t);
            let push = Vector3::new(
                rng.random_range(-0.15..0.15),
                rng.random_range(-0.15..0.15),
                rng.random_range(-0.15..0.15),
            );
            for offset in [Vector3::zeros(), push] {
                let mut hints = [Hint::default(); MAX_SPHERES];
                let mut level = rng.random_range(-0.05..0.0);
                for q in &path {
                    let kin = ArmKinematics::new(&f.model, &JointVector::from(*q));
                    let mut centres = [Vector3::zeros(); MAX_SPHERES];
                    kin.sphere_centres_in(&f.model, &base, &mut centres);
                    level += rng.random_range(0.0..0.0005);
                    for ((s, c), hint) in f.model.spheres.iter().zip(&centres).zip(&mut hints) {
                        let p = c + offset;
                        let stop = level - s.radius;
                        let full = field.distance(&p);
                        let before = *hint;
                        let v = field.distance_upto(&p, stop, hint);
                        lookups += 1;
                        skipped += usize::from(before == *hint && v <= stop);
                        if full > stop {
                            assert_eq!(v, full, "{p:?} stop {stop}");
                        } else {
                            assert!(v <= stop && v >= full, "{p:?}: {v} vs {full}, stop {stop}");
                        }
                    }
                }
            }
        }
    }
    assert!(
        skipped > lookups / 4,
        "{skipped} of {lookups} lookups settled by their anchor"
    );
}

/// Lookups skipped by the travel bound (a sphere that cannot have left its anchor's room since
/// its last lookup) give the risk and the excess of lookups that place every sphere, bit for
/// bit after every configuration: along demonstrated paths, the same with the arm base pushed
/// 0–15 cm (risky: the level rises), with every other configuration dropped (jumps), and with
/// the base changed halfway (every leash untied). The hints end the same, too.
#[test]
fn lookups_skipped_by_travel_agree_with_placing_every_sphere() {
    use prf_shared::field::Lookups;
    let f = fixture();
    let mut rng = StdRng::seed_from_u64(11);
    let (mut configurations, mut risky) = (0usize, 0usize);
    let (mut total_placed, mut total_leashed) = (0u64, 0u64);
    for d in f.dataset.demonstrations.iter().step_by(3) {
        for (t, base, path) in arm_instances(f, d) {
            let travelled = workspace(f, t).lookups(Lookups::Travelled);
            let anchored = workspace(f, t).lookups(Lookups::Anchored);
            let push = Translation3::new(
                rng.random_range(-0.15..0.15),
                rng.random_range(-0.15..0.15),
                rng.random_range(-0.15..0.15),
            );
            for (pushed, stride) in [(false, 1), (true, 1), (true, 2)] {
                let base = if pushed { push * base } else { base };
                let moved = Translation3::new(0.0, 0.01, 0.0) * base;
                let (mut a, mut b) = (RiskAccumulator::default(), RiskAccumulator::default());
                for (i, q) in path.iter().enumerate().step_by(stride) {
                    let base = if i < path.len() / 2 { &base } else { &moved };
                    let kin = ArmKinematics::new(&f.model, &JointVector::from(*q));
                    let (ra, rb) = (
                        a.add(&f.model, &travelled, base, &kin),
                        b.add(&f.model, &anchored, base, &kin),
                    );
                    assert_eq!(ra.to_bits(), rb.to_bits(), "configuration {i}");
                    assert_eq!(
                        a.excess().to_bits(),
                        b.excess().to_bits(),
                        "configuration {i}"
                    );
                    configurations += 1;
                }
                let (placed, leashed) = a.counts();
                assert_eq!(b.counts().1, 0);
                (total_placed, total_leashed) = (total_placed + placed, total_leashed + leashed);
                risky += usize::from(a.risk() > 0.0);
            }
        }
    }
    assert!(
        configurations > 10_000 && risky > 10,
        "{configurations} configurations, {risky} risky paths"
    );
    assert!(
        total_leashed > total_placed,
        "{total_leashed} spheres settled by their leash, {total_placed} placed"
    );
}

/// `Field::cell_at` against floor and clamping worked out independently: random points of the
/// grid box, points on and just off node planes, and points far outside it (±1e30, ∞, NaN).
#[test]
fn cells_are_floored_and_clamped_to_the_grid() {
    let field = workspace(fixture(), 0);
    let (dims, h) = (field.dims(), field.voxel());
    let origin = field.node_position(0, 0, 0);
    let last = dims.map(|n| n - 2);
    let expected = |x: &Vector3<f64>| -> [usize; 3] {
        core::array::from_fn(|a| {
            // The grid coordinate as the field computes it (its inverse voxel, 1 / h).
            let g = (x[a] - origin[a]) * (1.0 / h);
            if g.is_nan() || g <= 0.0 {
                0
            } else {
                (g.floor().min(last[a] as f64)) as usize
            }
        })
    };
    let mut rng = StdRng::seed_from_u64(9);
    let top = field.node_position(dims[0] - 1, dims[1] - 1, dims[2] - 1);
    for _ in 0..20_000 {
        let x = Vector3::from_fn(|a, _| rng.random_range(origin[a] - 0.5..top[a] + 0.5));
        assert_eq!(field.cell_at(&x), expected(&x), "{x:?}");
    }
    // Node planes, a hair either side (the grid coordinate's rounding decides; both agree).
    for i in 0..dims[0] {
        let node = field.node_position(i, dims[1] / 2, dims[2] / 2);
        for dx in [-1e-12, 0.0, 1e-12] {
            let x = node + Vector3::new(dx, 0.25 * h, 0.25 * h);
            assert_eq!(field.cell_at(&x)[0], expected(&x)[0], "{x:?}");
        }
    }
    for v in [
        1e30,
        -1e30,
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::NAN,
        1e10,
    ] {
        let x = Vector3::repeat(v);
        let want = if v > 0.0 { last } else { [0; 3] };
        assert_eq!(field.cell_at(&x), want, "{v}");
    }
}
