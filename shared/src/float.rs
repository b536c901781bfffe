//! The square root and rounding both platforms compute alike, at the speed of each.
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

/// |v|: nalgebra's `norm` (the square root of the same sum of squares) through [`sqrt`].
#[inline(always)]
pub fn norm(v: &Vector3<f64>) -> f64 {
    sqrt(v.norm_squared())
}

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
}
