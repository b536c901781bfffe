//! The square root and rounding both platforms compute alike, at the speed of each.
//!
//! IEEE 754 requires the square root to be correctly rounded, so every conforming
//! implementation gives the same bits for a non-NaN result. `libm::sqrt` uses the x86-64
//! instruction, but on 32-bit ARM it is a software routine even where the FPU has one: the
//! Cortex-M7's double-precision unit computes it in one `vsqrt.f64`, which is used there
//! (rustc reports that unit as `target_feature = "vfp2"`: with `target-cpu=cortex-m7`, not
//! for the single-precision Cortex-M4). Rounding to an integer is exact, so the FPU's
//! `vrinta.f64` (FPv5) gives `libm::round`'s bits too.

use nalgebra::Vector3;

/// √x, correctly rounded (the FPU's instruction on a Cortex-M7, through `core`'s unstable
/// `core_float_math`, which the firmware's toolchain enables; `libm::sqrt` elsewhere).
/// NaN for x < 0 (its payload may differ between platforms).
#[inline(always)]
pub fn sqrt(x: f64) -> f64 {
    #[cfg(all(target_arch = "arm", target_feature = "vfp2"))]
    {
        // LLVM's sqrt intrinsic: one `vsqrt.f64` with a double-precision FPU.
        core::f64::math::sqrt(x)
    }
    #[cfg(not(all(target_arch = "arm", target_feature = "vfp2")))]
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
