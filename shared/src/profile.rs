//! Time-scaling profiles shared by trajectory generators.

/// Minimum-jerk blend s(u) = 10u³ − 15u⁴ + 6u⁵ for u ∈ [0, 1] (clamped outside): zero velocity
/// and acceleration at both ends.
pub fn min_jerk(u: f64) -> f64 {
    let u = u.clamp(0.0, 1.0);
    u * u * u * (10.0 - 15.0 * u + 6.0 * u * u)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ends_at_rest() {
        let h = 1e-6;
        assert_eq!(min_jerk(0.0), 0.0);
        assert_eq!(min_jerk(1.0), 1.0);
        assert!((min_jerk(0.5) - 0.5).abs() < 1e-15);
        assert!(min_jerk(h) / h < 1e-9 && (1.0 - min_jerk(1.0 - h)) / h < 1e-9);
    }
}
