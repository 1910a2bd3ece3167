//! The error measures of the lab, over per-pixel luminance against a reference: RMSE, the
//! relative measures with the literature's ε (relMSE, relV), and means. `study`, `compare`,
//! `predict` and `figure` share them, so that a number means the same in every report.

/// Root-mean-square difference of two equally long images.
pub(crate) fn rmse(a: &[f64], b: &[f64]) -> f64 {
    assert_eq!(a.len(), b.len(), "images differ in size");
    if a.is_empty() {
        return 0.0;
    }
    let sum: f64 = a.iter().zip(b).map(|(x, y)| (x - y) * (x - y)).sum();
    (sum / a.len() as f64).sqrt()
}

/// ε of the relative metrics: 0.01 × the squared image-mean luminance of the reference, so
/// that black pixels neither divide by zero nor dominate (the convention of the rendering
/// literature's relMSE).
pub(crate) fn rel_epsilon(reference: &[f64]) -> f64 {
    0.01 * mean(reference).powi(2)
}

/// relMSE of `image` against `reference`: the mean over pixels of (I − R)²/(R² + ε), ε from
/// [`rel_epsilon`]. Dimensionless. The same with per-pixel variances V in place of (I − R)² is
/// relV ([`rel_mean`]).
pub(crate) fn rel_mse(image: &[f64], reference: &[f64]) -> f64 {
    let sq: Vec<f64> = image
        .iter()
        .zip(reference)
        .map(|(i, r)| (i - r).powi(2))
        .collect();
    rel_mean(&sq, reference)
}

/// The mean over pixels of q/(R² + ε) for a per-pixel squared quantity q (W²·m⁻⁴·sr⁻²).
pub(crate) fn rel_mean(q: &[f64], reference: &[f64]) -> f64 {
    assert_eq!(q.len(), reference.len(), "images differ in size");
    let eps = rel_epsilon(reference);
    mean(
        &q.iter()
            .zip(reference)
            .map(|(q, r)| q / (r * r + eps))
            .collect::<Vec<_>>(),
    )
}

/// Mean of a slice (0 for an empty one).
pub(crate) fn mean(v: &[f64]) -> f64 {
    if v.is_empty() {
        0.0
    } else {
        v.iter().sum::<f64>() / v.len() as f64
    }
}
