//! The square root, rounding and e^{−x} both platforms compute alike, at the speed of each.
//!
//! IEEE 754 requires the square root to be correctly rounded, so every conforming
//! implementation gives the same bits for a non-NaN result. `libm::sqrt` uses the x86-64
//! instruction (in an encoding of its own: see [`sqrt`]), but on 32-bit ARM it is a software
//! routine even where the FPU has one: the Cortex-M7's double-precision unit computes it in
//! one `vsqrt.f64`, which is used there (rustc reports that unit as `target_feature = "vfp2"`:
//! with `target-cpu=cortex-m7`, not for the single-precision Cortex-M4). Rounding to an
//! integer is exact, so the FPU's `vrinta.f64` (FPv5) gives `libm::round`'s bits too.

use nalgebra::Vector3;

/// √x, correctly rounded (the FPU's instruction on a Cortex-M7, through `core`'s unstable
/// `core_float_math`, which the firmware's toolchain enables; SSE2's on x86-64;
/// `libm::sqrt` elsewhere). NaN for x < 0 (its payload may differ between platforms).
///
/// On x86-64 `libm::sqrt` is inline assembly of the legacy (non-VEX) `sqrtsd`: in a build
/// for a CPU with AVX (`-C target-cpu=native`) each call beside the AVX code around it stalls
/// on the SSE/AVX transition, and the RDMP step took 2.1 × as long (its QR takes six square
/// roots). The intrinsic lets the compiler pick the encoding.
#[inline(always)]
pub fn sqrt(x: f64) -> f64 {
    #[cfg(all(target_arch = "arm", target_feature = "vfp2"))]
    {
        // LLVM's sqrt intrinsic: one `vsqrt.f64` with a double-precision FPU.
        core::f64::math::sqrt(x)
    }
    #[cfg(target_arch = "x86_64")]
    {
        // SSE2's `sqrtsd`, encoded by the compiler (with VEX where AVX is enabled).
        use core::arch::x86_64::{_mm_cvtsd_f64, _mm_set_sd, _mm_sqrt_pd};
        // SAFETY: SSE2 is part of every x86-64 CPU (the target's baseline); the intrinsics
        // only compute on registers.
        #[allow(unsafe_code)]
        unsafe {
            _mm_cvtsd_f64(_mm_sqrt_pd(_mm_set_sd(x)))
        }
    }
    #[cfg(not(any(
        all(target_arch = "arm", target_feature = "vfp2"),
        target_arch = "x86_64"
    )))]
    {
        libm::sqrt(x)
    }
}

/// x rounded to the nearest integer, halves away from zero (`libm::round`'s result, which is
/// exact: the FPU's `vrinta.f64` on a Cortex-M7, the software routine elsewhere).
#[inline(always)]
pub fn round(x: f64) -> f64 {
    #[cfg(all(target_arch = "arm", target_feature = "vfp2"))]
    {
        core::f64::math::round(x)
    }
    #[cfg(not(all(target_arch = "arm", target_feature = "vfp2")))]
    {
        libm::round(x)
    }
}

/// `round(x) as i32` (halves away from zero; saturating; NaN → 0) without a call to the
/// software [`round`]: the remainder of the truncation decides. It is exact: below 2^52,
/// x − trunc(x) is (Sterbenz), and from 2^52 on every f64 is an integer. Without branches:
/// the remainder's comparisons are unpredictable (a swept sphere's key rounds its centre's
/// coordinates, and branches on them cost `prf learn --add` more than the divisions did).
#[inline(always)]
pub fn round_i32(x: f64) -> i32 {
    const LOW: i64 = i32::MIN as i64;
    const HIGH: i64 = i32::MAX as i64;
    // Truncated toward zero, saturating at i64's ends, NaN → 0; then held one beyond i32's
    // ends, where the remainder's step of one away from zero still saturates.
    let t = x as i64;
    let r = x - t as f64;
    let n = t.clamp(LOW - 1, HIGH + 1) + i64::from(r >= 0.5) - i64::from(r <= -0.5);
    n.clamp(LOW, HIGH) as i32
}

/// |v|: nalgebra's `norm` (the square root of the same sum of squares) through [`sqrt`].
#[inline(always)]
pub fn norm(v: &Vector3<f64>) -> f64 {
    sqrt(v.norm_squared())
}

/// e^{−x}, within 2 ulp of the correctly rounded value (test `exp_neg_is_within_two_ulp_of_libm`)
/// for |x| ≤ 700 (x is clamped to ±700; NaN stays NaN). x = k ln 2 + r with |r| ≤ ln 2/2, and
/// e^{−x} = 2^{−k} e^{−r}, e^{−r} from a polynomial of our own (a Chebyshev fit).
/// Only +, −, × and bit moves, inlined: the Gaussian bases' exponentials (8 per RDMP step)
/// without `libm::exp`'s call and division, which must serve every argument and rounding.
#[inline(always)]
pub fn exp_neg(x: f64) -> f64 {
    let x = x.clamp(-EXP_RANGE, EXP_RANGE);
    // Adding 1.5 · 2⁵² rounds x/ln 2 to the integer k (ties to even), which then sits in the
    // low bits of the sum's representation.
    let t = x * core::f64::consts::LOG2_E + ROUNDER;
    let k = t - ROUNDER;
    let k_bits = t.to_bits().wrapping_sub(ROUNDER.to_bits()) as i64;
    let r = (x - k * LN2[0]) - k * LN2[1];
    let mut p = EXP[0];
    for c in &EXP[1..] {
        p = p * r + c;
    }
    let e = 1.0 + (r * r * p - r);
    e * f64::from_bits((1023i64.wrapping_sub(k_bits) as u64) << 52)
}

/// 1.5 · 2⁵² (see [`exp_neg`]).
const ROUNDER: f64 = 6_755_399_441_055_744.0;

/// ln 2 = L1 + L2, L1 with 42 significant bits (k·L1 exact for |k| < 2¹¹).
const LN2: [f64; 2] = [0.693_147_180_559_890_3, 5.497_923_018_708_371e-14];

/// (e^{−r} − 1 + r)/r² as a polynomial in r on [−ln 2/2, ln 2/2], highest degree first: a
/// Chebyshev interpolant of degree 10, 2e-19 from the function (mpmath's `chebyfit`).
const EXP: [f64; 11] = [
    2.091_467_937_658_393_5e-9,
    -2.510_520_637_395_701e-8,
    2.755_727_366_134_863_7e-7,
    -2.755_725_542_574_643_5e-6,
    2.480_158_732_553_336_3e-5,
    -1.984_126_987_480_049_3e-4,
    1.388_888_888_888_375_2e-3,
    -8.333_333_333_326_141e-3,
    4.166_666_666_666_667e-2,
    -0.166_666_666_666_666_7,
    0.5,
];

/// [`exp_neg`] clamps x to ±this, so that 2^{−k} stays a normal number.
const EXP_RANGE: f64 = 700.0;

mod sincos_table;

/// sin x and cos x within an ulp of 1 (2.2e-16, absolute) of libm's for |x| ≤
/// [`SINCOS_RANGE`] (1.1e-16 at most where tested: `sincos_is_within_an_ulp_of_one`), libm's
/// `sincos` beyond (and for NaN). x = k/32 + d with k = round(32x), d exact (Sterbenz) and
/// |d| ≤ 1/64; then sin x = s_k + (s_k (cos d − 1) + c_k sin d) and
/// cos x = c_k + (c_k (cos d − 1) − s_k sin d), s_k and c_k correctly rounded from a table of
/// 257 pairs, sin d and cos d − 1 from their Taylor series to d⁷ and d⁶ (the next terms are
/// below 1e-19). Only +, −, ×, a table read and bit moves, inlined: FK's seven joint angles per
/// RDMP step without libm's argument reduction and its two polynomials of degree 13, which
/// must serve every argument.
#[inline(always)]
pub fn sincos(x: f64) -> (f64, f64) {
    if !(f64::abs(x) <= SINCOS_RANGE) {
        return libm::sincos(x);
    }
    // As in `exp_neg`: adding 1.5 · 2⁵² rounds 32x (exact) to the integer k.
    let t = x * 32.0 + ROUNDER;
    let k = t - ROUNDER;
    let index = t.to_bits().wrapping_sub(ROUNDER.to_bits()) as i64 + SINCOS_HALF;
    let [s_k, c_k] = sincos_table::SINCOS[index.clamp(0, 2 * SINCOS_HALF) as usize];
    let d = x - k * (1.0 / 32.0);
    let d2 = d * d;
    let sin_d = d + d * d2 * (-1.0 / 6.0 + d2 * (1.0 / 120.0 + d2 * (-1.0 / 5040.0)));
    let cos_d_1 = d2 * (-0.5 + d2 * (1.0 / 24.0 + d2 * (-1.0 / 720.0)));
    (
        s_k + (s_k * cos_d_1 + c_k * sin_d),
        c_k + (c_k * cos_d_1 - s_k * sin_d),
    )
}

/// atan2(y, x), libm's bits for every input. For 0 ≤ y < x (the first octant, where a
/// rotation's log takes it for θ/2 < 45°) libm's `atan2` comes to `atan(y / x)` after its
/// special cases, which such a pair either cannot be (NaN, x = 0, x = ∞, |y/x| > 2⁶⁴) or
/// answers alike (x = 1: atan(y); y = 0: y): that is taken directly, without the function
/// call and the checks. Elsewhere (and for NaN) libm's `atan2` itself.
#[inline(always)]
pub fn atan2(y: f64, x: f64) -> f64 {
    if y >= 0.0 && y < x {
        libm::atan(y / x)
    } else {
        libm::atan2(y, x)
    }
}

/// [`sincos`] reads its table for |x| up to this (every joint's range with room to spare).
pub const SINCOS_RANGE: f64 = 4.0;

/// The table's k runs over ±this: 32 · [`SINCOS_RANGE`].
const SINCOS_HALF: i64 = 128;

#[cfg(test)]
mod tests {
    /// The same bits as libm's routine (both are IEEE 754's correctly rounded square root):
    /// the streams stay those of the other platforms.
    #[test]
    fn sqrt_is_libms_bit_for_bit() {
        let mut x: u64 = 0x9e37_79b9_7f4a_7c15;
        let special = [
            0.0,
            -0.0,
            f64::MIN_POSITIVE,
            f64::MIN_POSITIVE / 3.0,
            f64::MAX,
            f64::INFINITY,
            1.0,
            2.0,
            0.25,
        ];
        let random = (0..200_000).map(|_| {
            // xorshift64: every exponent and mantissa, positive.
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            f64::from_bits(x >> 1)
        });
        for v in special.into_iter().chain(random).filter(|v| !v.is_nan()) {
            assert_eq!(
                super::sqrt(v).to_bits(),
                libm::sqrt(v).to_bits(),
                "sqrt({v:e})"
            );
        }
        assert!(super::sqrt(-1.0).is_nan() && super::sqrt(f64::NAN).is_nan());
    }

    /// [`super::atan2`] gives libm's bits: random pairs in every quadrant and of every
    /// magnitude ratio, and the special values (zeros of both signs, x = 1, ∞, NaN, y = x).
    #[test]
    fn atan2_is_libms_bit_for_bit() {
        let mut seed: u64 = 0x2545_f491_4f6c_dd1d;
        let mut next = || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            seed
        };
        let special = [
            0.0,
            -0.0,
            1.0,
            -1.0,
            f64::MIN_POSITIVE / 3.0,
            1e-300,
            0.5,
            1e300,
            f64::MAX,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
        ];
        let same = |y: f64, x: f64| {
            let (a, b) = (super::atan2(y, x), libm::atan2(y, x));
            assert!(
                a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan()),
                "atan2({y:e}, {x:e}): {a:e} against libm's {b:e}"
            );
        };
        for &y in &special {
            for &x in &special {
                same(y, x);
            }
            same(y, y);
        }
        for _ in 0..1_000_000 {
            let (a, b) = (next(), next());
            // Mantissas and signs at random, exponents within ±80 of each other's and of 0.
            let at = |bits: u64, e: u64| f64::from_bits((bits & 0x800f_ffff_ffff_ffff) | (e << 52));
            let (ey, ex) = (943 + (a >> 52) % 160, 943 + (b >> 52) % 160);
            let (y, x) = (at(a, ey), at(b, ex));
            same(y, x);
            same(y.abs(), x.abs());
            same(y.abs().min(x.abs()), y.abs().max(x.abs()));
        }
    }

    /// Within an ulp of 1 (absolute) of libm's sin and cos (itself within an ulp of the
    /// true values) over the table's range: at the table's points, at the midpoints between
    /// them (the largest d), near the zeros of sin and cos and at a million random points;
    /// libm's own bits beyond the range and for NaN.
    #[test]
    fn sincos_is_within_an_ulp_of_one() {
        use super::{SINCOS_RANGE, sincos};
        let mut worst = (0.0f64, 0.0f64);
        let mut check = |x: f64| {
            let (s, c) = sincos(x);
            let (s_ref, c_ref) = libm::sincos(x);
            let err = f64::max(f64::abs(s - s_ref), f64::abs(c - c_ref));
            if err > worst.0 {
                worst = (err, x);
            }
        };
        let mut seed = 0x2545_f491_4f6c_dd1d_u64;
        let random = (0..1_000_000).map(|_| {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            ((seed >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0) * SINCOS_RANGE
        });
        let grid = (-128..=128).flat_map(|k| {
            let x = f64::from(k) / 32.0;
            [x, x + 1.0 / 64.0, x - 1.0 / 64.0, x + 1e-9]
        });
        let half_pi = core::f64::consts::FRAC_PI_2;
        let zeros = [-2, -1, 1, 2].into_iter().flat_map(|k| {
            let x = f64::from(k) * half_pi;
            [
                x,
                f64::from_bits(x.to_bits() + 1),
                f64::from_bits(x.to_bits() - 1),
            ]
        });
        let special = [0.0, -0.0, 1e-300, -1e-300, SINCOS_RANGE, -SINCOS_RANGE];
        random
            .chain(grid)
            .chain(zeros)
            .chain(special)
            .for_each(&mut check);
        assert!(
            worst.0 <= f64::EPSILON,
            "{:e} off libm at x = {:e}",
            worst.0,
            worst.1
        );
        for x in [
            SINCOS_RANGE * (1.0 + f64::EPSILON),
            -5.0,
            1e6,
            f64::INFINITY,
        ] {
            let ((s, c), (s_ref, c_ref)) = (sincos(x), libm::sincos(x));
            assert_eq!(
                (s.to_bits(), c.to_bits()),
                (s_ref.to_bits(), c_ref.to_bits()),
                "{x:e}"
            );
        }
        let (s, c) = sincos(f64::NAN);
        assert!(s.is_nan() && c.is_nan());
        // The table itself: each entry within an ulp of libm's value (of the same sign).
        for (i, [s_k, c_k]) in super::sincos_table::SINCOS.iter().enumerate() {
            let x = (i as f64 - 128.0) / 32.0;
            let (s_ref, c_ref) = libm::sincos(x);
            for (v, r) in [(*s_k, s_ref), (*c_k, c_ref)] {
                assert!(
                    v == r || (v * r > 0.0 && ulps(v.abs(), r.abs()) <= 1),
                    "{x}: {v} {r}"
                );
            }
        }
    }

    /// The distance in ulps between `a` and `b`, both positive.
    fn ulps(a: f64, b: f64) -> u64 {
        a.to_bits().abs_diff(b.to_bits())
    }

    /// The same integer as `round(x) as i32` on halves, values just below them, the ends of
    /// i32, i64 and f64, NaN, infinities and 3 million random values.
    #[test]
    fn round_i32_is_round_then_cast() {
        use super::{round, round_i32};
        let same = |x: f64| assert_eq!(round_i32(x), round(x) as i32, "{x:e}");
        let below_half = 0.5 - f64::EPSILON / 4.0;
        for k in [
            0.0,
            1.0,
            2.0,
            3.0,
            1e6,
            4503599627370495.0,
            4503599627370496.0,
        ] {
            for x in [k + 0.5, k + below_half, k - 0.5, k + 0.25, k] {
                same(x);
                same(-x);
            }
        }
        for x in [
            f64::NAN,
            f64::INFINITY,
            f64::NEG_INFINITY,
            2147483647.4,
            2147483647.5,
            -2147483648.5,
            -2147483648.6,
            9.3e18,
            -9.3e18,
            i64::MAX as f64,
            (i64::MAX as f64).next_down(),
            i64::MIN as f64,
            (i64::MIN as f64).next_up(),
            f64::MAX,
            f64::MIN,
            f64::MIN_POSITIVE,
            -0.0,
        ] {
            same(x);
        }
        let mut s: u64 = 0x9e37_79b9_7f4a_7c15;
        for i in 0..3_000_000 {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            same(match i % 3 {
                // Any bit pattern; centres on the 0.2 mm grid of a cell; halves.
                0 => f64::from_bits(s),
                1 => (s as i64 as f64) / 9.3e15,
                _ => (s % 2_000_001) as f64 / 2.0 - 500_000.0,
            });
        }
    }

    /// Within 2 ulp of libm's exp (itself within 1 ulp of e^x) over the range, in the
    /// Gaussian bases' [0, 36] most densely; NaN stays NaN; beyond ±700 clamped.
    #[test]
    fn exp_neg_is_within_two_ulp_of_libm() {
        use super::{EXP_RANGE, exp_neg};
        let mut s: u64 = 0x2545_f491_4f6c_dd1d;
        let mut uniform = |lo: f64, hi: f64| {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            lo + (hi - lo) * ((s >> 11) as f64 / (1u64 << 53) as f64)
        };
        let mut worst = 0;
        for i in 0..1_000_000 {
            let x = match i % 4 {
                0 | 1 => uniform(0.0, 36.0),
                2 => uniform(-EXP_RANGE, EXP_RANGE),
                _ => uniform(-1e-3, 1e-3),
            };
            let (got, want) = (exp_neg(x), libm::exp(-x));
            let e = ulps(got, want);
            assert!(e <= 2, "e^-{x:e} = {got:e}, libm {want:e}");
            worst = worst.max(e);
        }
        for x in [
            0.0,
            -0.0,
            36.0,
            core::f64::consts::LN_2 / 2.0,
            EXP_RANGE,
            -EXP_RANGE,
        ] {
            assert!(ulps(exp_neg(x), libm::exp(-x)) <= 2, "e^-{x:e}");
        }
        assert!(worst >= 1, "the test compares something");
        assert!(exp_neg(f64::NAN).is_nan());
        assert_eq!(exp_neg(1e4), exp_neg(EXP_RANGE));
        assert_eq!(exp_neg(-1e4), exp_neg(-EXP_RANGE));
    }
}
