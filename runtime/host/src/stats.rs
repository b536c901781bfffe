//! Percentiles of timing samples (collected into pre-sized buffers inside the loop, sorted
//! once afterwards).

/// p50, p99, p99.9 and max of `v` (sorted in place); zeros when empty.
pub fn percentiles(v: &mut [f64]) -> [f64; 4] {
    if v.is_empty() {
        return [0.0; 4];
    }
    v.sort_by(f64::total_cmp);
    let at = |p: f64| v[((v.len() - 1) as f64 * p).round() as usize];
    [at(0.5), at(0.99), at(0.999), v[v.len() - 1]]
}
