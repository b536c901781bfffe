//! The shim against the `ruckig` crate (an independent build of the same core through cxx),
//! the generator's relocation, limits and typed errors.

use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};
use std::boxed::Box;

use crate::baseline;
use crate::ffi;
use crate::online::{Code, DT, Online};

#[test]
#[allow(unsafe_code)]
fn io_layout_and_storage_match_the_shim() {
    // SAFETY: pure functions of the shim returning sizeof.
    let (io3, io7, g3, g7) = unsafe {
        (
            ffi::prf_ruckig3_io_size(),
            ffi::prf_ruckig7_io_size(),
            ffi::prf_ruckig3_size(),
            ffi::prf_ruckig7_size(),
        )
    };
    assert_eq!(io3, core::mem::size_of::<ffi::Io<3>>());
    assert_eq!(io7, core::mem::size_of::<ffi::Io<7>>());
    assert!(g3 <= crate::storage::STORAGE_BYTES && g7 <= crate::storage::STORAGE_BYTES);
}

/// Random limits and states within them.
struct Case<const N: usize> {
    p: [f64; N],
    v: [f64; N],
    a: [f64; N],
    target: [f64; N],
    target_v: [f64; N],
    lim: ([f64; N], [f64; N], [f64; N]),
}

fn case<const N: usize>(rng: &mut StdRng) -> Case<N> {
    let vmax: [f64; N] = core::array::from_fn(|_| rng.random_range(0.5..3.0));
    let amax: [f64; N] = core::array::from_fn(|j| vmax[j] * rng.random_range(1.0..4.0));
    let jmax: [f64; N] = core::array::from_fn(|j| amax[j] * rng.random_range(10.0..100.0));
    Case {
        p: core::array::from_fn(|_| rng.random_range(-2.0..2.0)),
        v: core::array::from_fn(|j| vmax[j] * rng.random_range(-0.8..0.8)),
        a: core::array::from_fn(|j| amax[j] * rng.random_range(-0.8..0.8)),
        target: core::array::from_fn(|_| rng.random_range(-2.0..2.0)),
        target_v: core::array::from_fn(|j| vmax[j] * rng.random_range(-0.9..0.9)),
        lim: (vmax, amax, jmax),
    }
}

/// Steps both generators until both finish (or `max` cycles), asserting equal samples.
fn same_run<const N: usize>(
    shim: &mut Online<N>,
    reference: &mut baseline::Online<N>,
    max: usize,
) -> usize {
    for k in 0..max {
        let (a, b) = (shim.step().unwrap(), reference.step().unwrap());
        for j in 0..N {
            for (x, y, what) in [
                (shim.position()[j], reference.position()[j], "position"),
                (shim.velocity()[j], reference.velocity()[j], "velocity"),
                (
                    shim.acceleration()[j],
                    reference.acceleration()[j],
                    "acceleration",
                ),
            ] {
                assert!(
                    (x - y).abs() <= 1e-9,
                    "cycle {k}, axis {j}: {what} {x} (shim) vs {y} (crate)"
                );
            }
        }
        assert_eq!(a, b, "cycle {k}: finished differs");
        if a {
            return k;
        }
    }
    max
}

fn pair<const N: usize>(c: &Case<N>) -> (Online<N>, baseline::Online<N>) {
    let mut s = Online::new(&c.p, &c.lim.0, &c.lim.1, &c.lim.2);
    let mut r = baseline::Online::new(&c.p, &c.lim.0, &c.lim.1, &c.lim.2);
    s.set_state(&c.p, &c.v, &c.a);
    r.set_state(&c.p, &c.v, &c.a);
    (s, r)
}

/// Position interface, time and phase synchronised, from a moving state: the same
/// trajectory as the crate's, cycle by cycle, to 1e-9.
#[test]
fn position_interface_equals_the_crate() {
    let mut rng = StdRng::seed_from_u64(16);
    for i in 0..60 {
        let c = case::<7>(&mut rng);
        let (mut s, mut r) = pair(&c);
        if i % 2 == 1 {
            s.set_phase_synchronised();
            r.set_phase_synchronised();
        }
        s.go_to(&c.target);
        r.go_to(&c.target);
        assert!(
            same_run(&mut s, &mut r, 20_000) < 20_000,
            "case {i} never finished"
        );
        let c3 = case::<3>(&mut rng);
        let (mut s, mut r) = pair(&c3);
        s.go_to(&c3.target);
        r.go_to(&c3.target);
        same_run(&mut s, &mut r, 20_000);
    }
}

/// Velocity interface: tracking a moving reference (a new target every cycle, as the output
/// stage does) and braking.
#[test]
fn velocity_interface_equals_the_crate() {
    let mut rng = StdRng::seed_from_u64(17);
    for _ in 0..40 {
        let c = case::<7>(&mut rng);
        let (mut s, mut r) = pair(&c);
        for k in 0..300 {
            let t = k as f64 * DT;
            let p: [f64; 7] = core::array::from_fn(|j| c.target[j] + c.target_v[j] * t);
            s.track(&p, &c.target_v, crate::TRACKING_GAIN);
            r.track(&p, &c.target_v, crate::TRACKING_GAIN);
            same_run(&mut s, &mut r, 1);
        }
        s.brake();
        r.brake();
        assert!(same_run(&mut s, &mut r, 20_000) < 20_000);
        assert!(s.velocity().iter().all(|v| v.abs() < 1e-9));
    }
}

/// The generator lives inside its value: moved (bytewise) mid-trajectory it continues exactly
/// like one that stayed put, without re-planning.
#[test]
fn a_moved_generator_continues_its_trajectory() {
    let mut rng = StdRng::seed_from_u64(18);
    let c = case::<7>(&mut rng);
    let mut stay = Online::new(&c.p, &c.lim.0, &c.lim.1, &c.lim.2);
    let mut moving = Online::new(&c.p, &c.lim.0, &c.lim.1, &c.lim.2);
    stay.go_to(&c.target);
    moving.go_to(&c.target);
    for _ in 0..50 {
        stay.step().unwrap();
        moving.step().unwrap();
    }
    let mut boxed = Box::new(moving);
    for _ in 0..50 {
        stay.step().unwrap();
        boxed.step().unwrap();
        assert!(!boxed.new_calculation(), "the move made Ruckig re-plan");
        assert_eq!(stay.position(), boxed.position());
    }
}

/// A platform-like move: reaches the goal exactly, at rest, within every limit, and a brake
/// from full speed stops within the limits.
#[test]
fn go_to_and_brake_stay_within_limits() {
    let lim = ([0.5; 3], [0.5; 3], [1.0; 3]);
    let mut m = Online::new(&[0.0; 3], &lim.0, &lim.1, &lim.2);
    m.go_to(&[2.0, -1.0, 0.5]);
    let (mut v0, mut a0) = ([0.0; 3], [0.0; 3]);
    let mut steps = 0;
    while !m.step().unwrap() {
        steps += 1;
        for k in 0..3 {
            assert!(m.velocity()[k].abs() <= 0.5 + 1e-9);
            assert!(m.acceleration()[k].abs() <= 0.5 + 1e-9);
            assert!((m.acceleration()[k] - a0[k]).abs() / DT <= 1.0 + 1e-6);
            assert!(((m.velocity()[k] - v0[k]) / DT).abs() <= 0.5 + 1e-3);
        }
        v0 = *m.velocity();
        a0 = *m.acceleration();
        assert!(steps < 20_000);
    }
    for (p, g) in m.position().iter().zip([2.0, -1.0, 0.5]) {
        assert!((p - g).abs() < 1e-9);
    }
    m.set_state(&[0.0; 3], &[0.5, -0.5, 0.2], &[0.0; 3]);
    m.brake();
    let mut n = 0;
    while !m.step().unwrap() {
        n += 1;
        assert!(n < 5000);
    }
    assert!(m.velocity().iter().all(|v| v.abs() < 1e-9));
}

/// A NaN state or a zero limit is a typed error that names the position, not garbage.
#[test]
fn bad_input_is_a_typed_error() {
    let lim = ([1.0; 7], [2.0; 7], [100.0; 7]);
    let mut m = Online::new(&[0.0; 7], &lim.0, &lim.1, &lim.2);
    let mut p = [0.0; 7];
    p[3] = f64::NAN;
    m.set_state(&p, &[0.0; 7], &[0.0; 7]);
    m.go_to(&[0.1; 7]);
    let e = m.step().unwrap_err();
    assert_eq!(e.code, Code::InvalidInput);
    let text = std::format!("{e}");
    assert!(
        text.contains("invalid input") && text.contains("NaN"),
        "{text}"
    );
    let mut z = Online::new(&[0.0; 7], &[0.0; 7], &lim.1, &lim.2);
    z.go_to(&[0.1; 7]);
    assert!(z.step().is_err());
}
