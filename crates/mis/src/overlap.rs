//! The jittered-pixel noise model of method.md §12: how much two camera samples of one pixel
//! share photons at x₀, and the effective number of independent gathers that follows.
//!
//! The preprint's weights assume that the N_B samples of a pixel share one x₀, so their N_B
//! gathers at x₀ are one gather. With samples jittered over the pixel, two gathers share only
//! the photons in the lens where their merge disks overlap. The overlap factor
//! ρ = E_{x,x′ ∈ F}[|D_r(x) ∩ D_r(x′)|]/S (F the pixel's footprint on the surface, S = πr²)
//! turns N_B into N_eff = 1 + (N_B − 1)·ρ wherever the weights weigh BDD=0 against BDD=1;
//! a renderer passes N_eff as [`crate::Budget::camera_samples`] of that pixel.

use std::fmt;

/// Which noise model the model-based weights (`algebraic-direct`, `algebraic`, `optimal`) use
/// for the sharing of photons among the camera samples of one pixel (method.md §12).
///
/// Non-exhaustive: other noise models are expected, so a match outside this crate needs a
/// `_ =>` arm.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[non_exhaustive]
pub enum NoiseModel {
    /// The preprint's: every sample of a pixel shares x₀, N_eff = N_B.
    Pinhole,
    /// Samples spread over the pixel's footprint: N_eff = 1 + (N_B − 1)·ρ per pixel.
    #[default]
    Footprint,
}

impl NoiseModel {
    /// Every name [`NoiseModel::parse`] accepts.
    pub const ALL_NAMES: &'static [&'static str] = &["pinhole", "footprint"];

    /// The model's name as used in settings and reports.
    pub fn name(&self) -> &'static str {
        match self {
            NoiseModel::Pinhole => "pinhole",
            NoiseModel::Footprint => "footprint",
        }
    }

    /// The inverse of [`NoiseModel::name`]; unknown names give `None`.
    pub fn parse(name: &str) -> Option<NoiseModel> {
        match name {
            "pinhole" => Some(NoiseModel::Pinhole),
            "footprint" => Some(NoiseModel::Footprint),
            _ => None,
        }
    }
}

impl fmt::Display for NoiseModel {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// N_eff = 1 + (N_B − 1)·ρ, the number of camera samples of one pixel whose gathers at x₀
/// count as independent (method.md §12). `overlap` is clamped to [0, 1]; ρ = 1 returns
/// `camera_samples` exactly (the preprint's layout), and N_B < 1 is taken as 1.
pub fn effective_samples(camera_samples: f64, overlap: f64) -> f64 {
    let n = if camera_samples >= 1.0 {
        camera_samples
    } else {
        1.0
    };
    let rho = if overlap >= 1.0 {
        return n;
    } else if overlap > 0.0 {
        overlap
    } else {
        0.0
    };
    1.0 + (n - 1.0) * rho
}

/// |D_r(x) ∩ D_r(x′)|/S for two disks of radius r whose centres are `distance` apart, from
/// the lens area 2r²·acos(d/2r) − (d/2)·√(4r² − d²). Dimensionless, in [0, 1].
pub fn lens_fraction(distance: f64, radius: f64) -> f64 {
    if radius.is_nan() || radius <= 0.0 {
        return 0.0;
    }
    let u = (distance.abs() / (2.0 * radius)).min(1.0);
    if u >= 1.0 {
        return 0.0;
    }
    (2.0 / std::f64::consts::PI) * (u.acos() - u * (1.0 - u * u).sqrt())
}

/// 8-point Gauss–Legendre nodes and weights on [0, 1] (digits to double precision).
#[allow(clippy::excessive_precision)]
const GAUSS8: [(f64, f64); 8] = [
    (0.019_855_071_751_231_856, 0.050_614_268_145_188_13),
    (0.101_666_761_293_186_63, 0.111_190_517_226_687_24),
    (0.237_233_795_041_835_5, 0.156_853_322_938_943_64),
    (0.408_282_678_752_175_1, 0.181_341_891_689_180_99),
    (0.591_717_321_247_824_9, 0.181_341_891_689_180_99),
    (0.762_766_204_958_164_5, 0.156_853_322_938_943_64),
    (0.898_333_238_706_813_4, 0.111_190_517_226_687_24),
    (0.980_144_928_248_768_1, 0.050_614_268_145_188_13),
];

/// Angular steps of the polar rule over the lens disk (midpoint rule, exact for the
/// trigonometric polynomials of low order that a smooth footprint density gives).
const ANGLES: usize = 24;

/// The overlap factor ρ of method.md §12 for a pixel whose footprint on x₀'s tangent plane is
/// the parallelogram spanned by `edge_x` and `edge_y` (m: where the image point moves by one
/// pixel right and one pixel down), for merge disks of radius `radius` (m). Samples are
/// uniform over the footprint (the box filter), so the displacement between two of them is
/// s·edge_x + t·edge_y with s, t independent and triangular on [−1, 1].
///
/// ρ ∈ [0, 1]: 1 for a footprint that is a point, ≈ S/|F| for a footprint much larger than
/// the disk. Computed by quadrature over the smaller of the two supports (the displacement
/// parallelogram, or the disk of radius 2r where the lens is not empty); accurate to about
/// 1 % of ρ. Non-finite edges (a footprint that runs off to the horizon) give 0; r ≤ 0
/// gives 0.
pub fn overlap_factor(edge_x: [f64; 3], edge_y: [f64; 3], radius: f64) -> f64 {
    if !(radius > 0.0 && radius.is_finite()) {
        return 0.0;
    }
    if !edge_x.iter().chain(edge_y.iter()).all(|c| c.is_finite()) {
        return 0.0;
    }
    let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let (xx, xy, yy) = (
        dot(edge_x, edge_x),
        dot(edge_x, edge_y),
        dot(edge_y, edge_y),
    );
    let area = (xx * yy - xy * xy).max(0.0).sqrt();
    let disk = std::f64::consts::PI * radius * radius;
    // The displacement parallelogram has area 4|F|, the disk of non-empty lenses 4S.
    if area <= disk {
        // Over (s, t): both signs of (s, t) together give |δ| twice, so two quadrants suffice.
        let mut sum = 0.0;
        for &(s, ws) in &GAUSS8 {
            for &(t, wt) in &GAUSS8 {
                let w = ws * wt * (1.0 - s) * (1.0 - t);
                let plus = (xx * s * s + 2.0 * xy * s * t + yy * t * t).max(0.0).sqrt();
                let minus = (xx * s * s - 2.0 * xy * s * t + yy * t * t).max(0.0).sqrt();
                sum += w * (lens_fraction(plus, radius) + lens_fraction(minus, radius));
            }
        }
        (2.0 * sum).clamp(0.0, 1.0)
    } else {
        // Over the disk |δ| < 2r in polar coordinates, with the footprint density
        // p(δ) = (1 − |s|)(1 − |t|)/|F|, (s, t) the footprint coordinates of δ. In a 2-D
        // basis of the plane: edge_x = (a, 0), edge_y = (b, c).
        let a = xx.sqrt();
        let (b, c) = (xy / a, area / a);
        // The ring's directions are the same for every radius of the rule (this function runs
        // once per pixel: the trigonometry was most of its time).
        let directions: [(f64, f64); ANGLES] = std::array::from_fn(|k| {
            let theta = (k as f64 + 0.5) * (std::f64::consts::TAU / ANGLES as f64);
            (theta.cos(), theta.sin())
        });
        let mut sum = 0.0;
        for &(q, wq) in &GAUSS8 {
            let d = 2.0 * radius * q;
            let mut ring = 0.0;
            for &(cos, sin) in &directions {
                let (dx, dy) = (d * cos, d * sin);
                // δ = s·(a, 0) + t·(b, c).
                let t = dy / c;
                let s = (dx - t * b) / a;
                ring += (1.0 - s.abs()).max(0.0) * (1.0 - t.abs()).max(0.0);
            }
            ring *= std::f64::consts::TAU / ANGLES as f64;
            sum += wq * 2.0 * radius * d * lens_fraction(d, radius) * ring;
        }
        (sum / area).clamp(0.0, 1.0)
    }
}

/// The overlap factor ρ for N = n_x·n_y camera samples stratified over the pixel: one
/// uniformly jittered sample in each cell of an n_x × n_y grid (`strata`), the footprint and
/// radius as in [`overlap_factor`]. ρ is the mean over pairs of *distinct* samples.
///
/// Over all N² ordered pairs of cells, a displacement has the density of two independent
/// uniform points of the pixel; the N pairs of a cell with itself have that of two uniform
/// points of one cell, whose footprint is spanned by edge_x/n_x and edge_y/n_y. So the
/// N(N − 1) pairs of distinct cells give ρ_strat = (N·ρ(F) − ρ(F_cell))/(N − 1), exactly.
/// Samples in different cells lie further apart than independent ones, so ρ_strat ≤ ρ(F)
/// (clamped to [0, 1] against the quadrature's ≈ 1 % error). With N ≤ 1 no pair exists and
/// ρ(F) is returned (N_eff = 1 either way).
pub fn overlap_factor_stratified(
    edge_x: [f64; 3],
    edge_y: [f64; 3],
    radius: f64,
    strata: (u32, u32),
) -> f64 {
    let (nx, ny) = (strata.0.max(1) as f64, strata.1.max(1) as f64);
    let n = nx * ny;
    let full = overlap_factor(edge_x, edge_y, radius);
    if n <= 1.0 {
        return full;
    }
    let cell = overlap_factor(edge_x.map(|c| c / nx), edge_y.map(|c| c / ny), radius);
    ((n * full - cell) / (n - 1.0)).clamp(0.0, 1.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    /// A brute-force ρ: the mean lens fraction over a stratified grid of point pairs in the
    /// footprint (an independent route to the same number).
    fn brute_force(edge_x: [f64; 3], edge_y: [f64; 3], radius: f64) -> f64 {
        // A fixed 2-D grid for each point of the pair: n⁴ pairs.
        let n = 40;
        let grid: Vec<(f64, f64)> = (0..n * n)
            .map(|i| {
                (
                    ((i % n) as f64 + 0.5) / n as f64,
                    ((i / n) as f64 + 0.5) / n as f64,
                )
            })
            .collect();
        let mut sum = 0.0;
        for &(s0, t0) in &grid {
            for &(s1, t1) in &grid {
                let (s, t) = (s0 - s1, t0 - t1);
                let d = [0, 1, 2].map(|k| s * edge_x[k] + t * edge_y[k]);
                let len = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
                sum += lens_fraction(len, radius);
            }
        }
        sum / (grid.len() * grid.len()) as f64
    }

    #[test]
    fn gauss_rule_integrates_polynomials_exactly() {
        let total: f64 = GAUSS8.iter().map(|&(_, w)| w).sum();
        assert!((total - 1.0).abs() < 1e-15);
        // An 8-point rule is exact to degree 15: ∫₀¹ x¹⁵ dx = 1/16.
        let x15: f64 = GAUSS8.iter().map(|&(x, w)| w * x.powi(15)).sum();
        assert!((x15 - 1.0 / 16.0).abs() < 1e-14, "{x15}");
    }

    #[test]
    fn lens_fraction_limits() {
        assert_eq!(lens_fraction(0.0, 1.0), 1.0);
        assert_eq!(lens_fraction(2.0, 1.0), 0.0);
        assert_eq!(lens_fraction(5.0, 1.0), 0.0);
        assert_eq!(lens_fraction(0.5, 0.0), 0.0);
        // d = r: 2r²·acos(½) − (r/2)·√3·r = r²(2π/3 − √3/2).
        let expected = (2.0 * PI / 3.0 - 3f64.sqrt() / 2.0) / PI;
        assert!((lens_fraction(1.0, 1.0) - expected).abs() < 1e-15);
    }

    #[test]
    fn overlap_matches_brute_force_over_shapes_and_scales() {
        let r = 1.0;
        // Square, oblong and sheared footprints from far below to far above the disk size.
        for &(ex, ey) in &[
            ([1.0, 0.0, 0.0], [0.0, 1.0, 0.0]),
            ([1.0, 0.0, 0.0], [0.3, 0.2, 0.0]),
            ([0.6, 0.0, 0.8], [0.0, 1.7, 0.0]),
            ([1.0, 1.0, 0.0], [-0.2, 0.9, 0.4]),
        ] {
            for &scale in &[0.05, 0.5, 1.5, 3.0, 8.0, 20.0] {
                let ex = ex.map(|c: f64| c * scale);
                let ey = ey.map(|c: f64| c * scale);
                let quad = overlap_factor(ex, ey, r);
                let brute = brute_force(ex, ey, r);
                assert!(
                    (quad - brute).abs() <= 0.015 * brute + 2e-4,
                    "edges {ex:?} {ey:?}: quadrature {quad}, brute force {brute}"
                );
            }
        }
    }

    #[test]
    fn overlap_limits() {
        // A point-like footprint shares everything.
        assert!((overlap_factor([1e-9, 0.0, 0.0], [0.0, 1e-9, 0.0], 1.0) - 1.0).abs() < 1e-6);
        // A large square footprint of side a: ρ ≈ (πr²/a²)(1 − 1.15·r/a) (method.md §12).
        let a = 200.0;
        let rho = overlap_factor([a, 0.0, 0.0], [0.0, a, 0.0], 1.0);
        let approx = PI / (a * a) * (1.0 - 1.15 / a);
        assert!((rho / approx - 1.0).abs() < 0.01, "{rho} vs {approx}");
        // Degenerate inputs.
        assert_eq!(
            overlap_factor([f64::INFINITY, 0.0, 0.0], [0.0, 1.0, 0.0], 1.0),
            0.0
        );
        assert_eq!(overlap_factor([1.0, 0.0, 0.0], [0.0, 1.0, 0.0], 0.0), 0.0);
        assert_eq!(
            overlap_factor([1.0, 0.0, 0.0], [f64::NAN, 1.0, 0.0], 1.0),
            0.0
        );
        // A footprint collapsed to a segment still overlaps along it.
        let seg = overlap_factor([4.0, 0.0, 0.0], [8.0, 0.0, 0.0], 1.0);
        assert!(seg > 0.0 && seg < 1.0);
    }

    /// ρ of a stratified layout against brute force: the mean lens fraction over pairs of
    /// points of a fine grid in two *different* cells (agreement within 0.3 % on these cases;
    /// 1 % + 10⁻³ allowed).
    #[test]
    fn stratified_overlap_matches_brute_force() {
        let r = 1.0;
        let m = 10; // points per cell side
        for &(ex, ey, strata) in &[
            ([2.0, 0.0, 0.0], [0.0, 3.0, 0.0], (2u32, 3u32)),
            ([1.0, 0.0, 0.0], [0.3, 1.2, 0.0], (5, 6)),
            ([6.0, 0.0, 0.0], [0.0, 6.0, 0.0], (4, 4)),
            ([0.4, 0.0, 0.0], [0.0, 0.4, 0.0], (1, 7)),
            ([3.0, 0.0, 0.0], [0.5, 2.5, 0.0], (8, 8)),
            ([1.5, 0.0, 0.0], [0.0, 1.5, 0.0], (2, 2)),
        ] {
            let (nx, ny) = strata;
            let points: Vec<(usize, f64, f64)> = (0..nx * ny)
                .flat_map(|c| {
                    (0..m * m).map(move |p| {
                        let s = ((c % nx) as f64 + ((p % m) as f64 + 0.5) / m as f64) / nx as f64;
                        let t = ((c / nx) as f64 + ((p / m) as f64 + 0.5) / m as f64) / ny as f64;
                        (c as usize, s, t)
                    })
                })
                .collect();
            let (mut sum, mut count) = (0.0, 0.0);
            for &(c0, s0, t0) in &points {
                for &(c1, s1, t1) in &points {
                    if c0 == c1 {
                        continue;
                    }
                    let (s, t) = (s0 - s1, t0 - t1);
                    let d = [0, 1, 2].map(|k| s * ex[k] + t * ey[k]);
                    sum += lens_fraction((d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt(), r);
                    count += 1.0;
                }
            }
            let brute = sum / count;
            let formula = overlap_factor_stratified(ex, ey, r, strata);
            let independent = overlap_factor(ex, ey, r);
            assert!(
                (formula - brute).abs() <= 0.01 * brute + 1e-3,
                "strata {strata:?}: formula {formula}, brute force {brute}"
            );
            assert!(formula <= independent + 1e-12);
        }
        // One sample: no pair, the plain factor.
        let e = ([1.0, 0.0, 0.0], [0.0, 1.0, 0.0]);
        assert_eq!(
            overlap_factor_stratified(e.0, e.1, 1.0, (1, 1)),
            overlap_factor(e.0, e.1, 1.0)
        );
    }

    #[test]
    fn effective_samples_bounds() {
        assert_eq!(effective_samples(30.0, 1.0), 30.0);
        assert_eq!(effective_samples(30.0, 0.0), 1.0);
        assert_eq!(effective_samples(30.0, f64::NAN), 1.0);
        assert_eq!(effective_samples(30.0, 2.0), 30.0);
        assert!((effective_samples(30.0, 0.025) - 1.725).abs() < 1e-12);
        assert_eq!(effective_samples(0.0, 0.5), 1.0);
    }
}
