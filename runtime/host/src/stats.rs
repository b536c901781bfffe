//! Percentiles of timing samples (collected into pre-sized buffers inside the loop, sorted
//! once afterwards).

/// The `q` quantile (0 ≤ q ≤ 1) of sorted samples, the nearest rank; 0 when empty.
pub fn quantile(sorted: &[f64], q: f64) -> f64 {
    if sorted.is_empty() {
        return 0.0;
    }
    sorted[((sorted.len() - 1) as f64 * q.clamp(0.0, 1.0)).round() as usize]
}

/// p50, p99, p99.9 and max of `v` (sorted in place); zeros when empty.
pub fn percentiles(v: &mut [f64]) -> [f64; 4] {
    v.sort_by(f64::total_cmp);
    [0.5, 0.99, 0.999, 1.0].map(|q| quantile(v, q))
}
