//! Statistics the crate's Monte Carlo tests share.

/// Mean and standard error of the mean of `n` values of `f`.
pub(crate) fn mean_se(n: usize, mut f: impl FnMut() -> f64) -> (f64, f64) {
    let (mut sum, mut sum2) = (0.0f64, 0.0f64);
    for _ in 0..n {
        let x = f();
        sum += x;
        sum2 += x * x;
    }
    let mean = sum / n as f64;
    (mean, ((sum2 / n as f64 - mean * mean) / n as f64).sqrt())
}
