//! `Bdf::sample` against `Bdf::pdf` (chi-square goodness of fit) and against
//! `Bdf::albedo` (Monte Carlo estimate of the directional albedo).

use crate::common::{MirrorFrame, chi2_p_value, close, direction, gauss_legendre, rng, u3};
use bdpm_bdf::Bdf;
use glam::Vec3;

const LOBE_WIDTHS_DEG: [f32; 6] = [0.05, 0.5, 1.5, 5.0, 30.0, 90.0];
const VIEW_ANGLES_DEG: [f64; 4] = [0.0, 45.0, 85.0, 89.0];

/// Every configuration tested: a name, the model, and the outgoing direction.
fn configurations() -> Vec<(String, Bdf, Vec3)> {
    let mut out = Vec::new();
    for &theta in &VIEW_ANGLES_DEG {
        let wo = direction(theta);
        let lambert = Bdf::lambert(Vec3::new(0.5, 0.4, 0.3)).unwrap();
        out.push((format!("lambert θo={theta}°"), lambert, wo));
        for &deg in &LOBE_WIDTHS_DEG {
            let delta = deg.to_radians();
            let lobe = Bdf::new(Vec3::ZERO, Vec3::new(0.8, 0.6, 0.4), delta).unwrap();
            out.push((format!("lobe Δ={deg}° θo={theta}°"), lobe, wo));
            let mix = Bdf::new(Vec3::new(0.5, 0.2, 0.1), Vec3::new(0.3, 0.6, 0.5), delta).unwrap();
            out.push((format!("mix Δ={deg}° θo={theta}°"), mix, wo));
        }
    }
    out
}

/// Binning coordinate x ∈ [0, 1] of t = 1 − cos ϑ around the mirror direction: half the
/// lobe's own CDF (so narrow lobes are resolved) plus half a uniform-in-solid-angle CDF
/// (so the Lambert part far from the lobe is resolved too, with a bounded Jacobian).
struct RadialMap {
    delta2: f64,
    mass: f64,
}

impl RadialMap {
    fn new(delta: f32) -> Self {
        let delta2 = f64::from(delta).powi(2);
        Self {
            delta2,
            mass: -(-2.0 / delta2).exp_m1(),
        }
    }

    fn x(&self, t: f64) -> f64 {
        0.5 * -(-t / self.delta2).exp_m1() / self.mass + 0.25 * t
    }

    fn t(&self, x: f64) -> f64 {
        let (mut lo, mut hi) = (0.0, 2.0);
        for _ in 0..80 {
            let mid = 0.5 * (lo + hi);
            if self.x(mid) < x { lo = mid } else { hi = mid }
        }
        0.5 * (lo + hi)
    }
}

const X_BINS: usize = 20;
const PHI_BINS: usize = 20;
const SAMPLES: usize = 100_000;

/// Expected counts per (x, φ) bin: N ∫∫ pdf dω over the bin, with dω = dt dφ. The t-axis is
/// cut into panels at the bin edges, at every unit of the lobe's exponent t/Δ² (so that
/// Gauss–Legendre integrates the lobe's exponential accurately), where the lobe starts to
/// cross the horizon, and every 0.02 beyond. At each t, the φ-integral runs over the part
/// of the φ-bin above the horizon, which resolves the horizon cut exactly. Cells that lie
/// entirely below the horizon are `None`; as the range of φ above the horizon shrinks
/// with t, a cell is below the horizon iff it is so at its smallest t.
fn expected_counts(bdf: &Bdf, wo: Vec3, map: &RadialMap, frame: &MirrorFrame) -> Vec<Option<f64>> {
    let gl_t = gauss_legendre(8);
    let gl_phi = gauss_legendre(6);
    let tau = std::f64::consts::TAU;
    let phi_edge = |j: usize| (-0.5 + j as f64 / PHI_BINS as f64) * tau;
    let mut expected = vec![None; X_BINS * PHI_BINS];
    for i in 0..X_BINS {
        let (t0, t1) = (
            map.t(i as f64 / X_BINS as f64),
            map.t((i + 1) as f64 / X_BINS as f64),
        );
        let reach = frame.phi_max(t0);
        for j in 0..PHI_BINS {
            if phi_edge(j).max(-reach) < phi_edge(j + 1).min(reach) {
                expected[i * PHI_BINS + j] = Some(0.0);
            }
        }
        let onset = 1.0 - frame.sin_sigma();
        let mut cuts: Vec<f64> = (0..=40)
            .map(|k| k as f64 * map.delta2)
            .chain((0..=100).map(|k| k as f64 * 0.02))
            .chain([t0, t1, onset])
            .filter(|&t| t >= t0 && t <= t1)
            .collect();
        cuts.sort_by(f64::total_cmp);
        cuts.dedup();
        for panel in cuts.windows(2) {
            let (a, b) = (panel[0], panel[1]);
            for &(gt, wt) in &gl_t {
                let t = 0.5 * (a + b) + 0.5 * (b - a) * gt;
                let dt = 0.5 * (b - a) * wt;
                let phi_max = frame.phi_max(t);
                for j in 0..PHI_BINS {
                    let (p0, p1) = (phi_edge(j).max(-phi_max), phi_edge(j + 1).min(phi_max));
                    if p1 <= p0 {
                        continue;
                    }
                    let inner: f64 = gl_phi
                        .iter()
                        .map(|&(gp, wp)| {
                            let phi = 0.5 * (p0 + p1) + 0.5 * (p1 - p0) * gp;
                            wp * f64::from(bdf.pdf(wo, frame.direction(t, phi)))
                        })
                        .sum::<f64>()
                        * 0.5
                        * (p1 - p0);
                    let cell = expected[i * PHI_BINS + j].as_mut().expect("reachable cell");
                    *cell += SAMPLES as f64 * dt * inner;
                }
            }
        }
    }
    expected
}

/// Pearson's statistic after pooling cells with expected count < 5; returns (χ², dof).
/// A sample in a cell below the horizon (`None`) fails at once.
fn pooled_chi2(cells: &[(Option<f64>, u64)], name: &str) -> (f64, usize) {
    let mut sorted: Vec<(f64, u64)> = cells
        .iter()
        .map(|&(e, o)| {
            assert!(
                e.is_some() || o == 0,
                "{name}: {o} samples below the horizon"
            );
            (e.unwrap_or(0.0), o)
        })
        .collect();
    sorted.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut pooled: Vec<(f64, u64)> = Vec::new();
    let mut acc = (0.0, 0u64);
    for &(e, o) in &sorted {
        acc = (acc.0 + e, acc.1 + o);
        if acc.0 >= 5.0 {
            pooled.push(acc);
            acc = (0.0, 0);
        }
    }
    match pooled.last_mut() {
        Some(last) => *last = (last.0 + acc.0, last.1 + acc.1),
        None => pooled.push(acc),
    }
    let chi2 = pooled
        .iter()
        .map(|&(e, o)| (o as f64 - e).powi(2) / e)
        .sum();
    (chi2, pooled.len() - 1)
}

#[test]
fn samples_follow_pdf_chi_square() {
    let configs = configurations();
    // Šidák correction: the whole family fails by chance with probability 1e-3.
    let alpha = 1.0 - (1.0 - 1e-3f64).powf(1.0 / configs.len() as f64);
    let mut failures = Vec::new();
    for (k, (name, bdf, wo)) in configs.iter().enumerate() {
        let wo = *wo;
        let map = RadialMap::new(bdf.delta().unwrap_or(30f32.to_radians()));
        let frame = MirrorFrame::new(wo);
        let mut observed = vec![0u64; X_BINS * PHI_BINS];
        let mut failed = 0u64;
        let mut rng = rng(1000 + k as u64);
        for _ in 0..SAMPLES {
            let Some(s) = bdf.sample(wo, u3(&mut rng)) else {
                failed += 1;
                continue;
            };
            assert!(
                s.wi.z > 0.0 && (s.wi.length() - 1.0).abs() < 1e-5,
                "{name}: {s:?}"
            );
            assert_eq!(s.pdf, bdf.pdf(wo, s.wi), "{name}");
            assert_eq!(s.f, bdf.eval(wo, s.wi), "{name}");
            assert!(close(s.weight, s.f * s.wi.z / s.pdf, 1e-6), "{name}: {s:?}");
            let (t, phi) = frame.coords(s.wi);
            let i = ((map.x(t) * X_BINS as f64) as usize).min(X_BINS - 1);
            let j = (((phi / std::f64::consts::TAU + 0.5) * PHI_BINS as f64) as usize)
                .min(PHI_BINS - 1);
            observed[i * PHI_BINS + j] += 1;
        }
        let expected = expected_counts(bdf, wo, &map, &frame);
        let total: f64 = expected.iter().flatten().sum();
        // The pdf must not integrate to more than 1 (beyond the quadrature's error).
        assert!(
            total < SAMPLES as f64 * (1.0 + 1e-4),
            "{name}: ∫ pdf = {}",
            total / SAMPLES as f64
        );
        // Failed samples (lobe directions below the horizon) are a cell of their own, so
        // the test also checks that the pdf integrates to the success probability.
        let mut cells: Vec<(Option<f64>, u64)> = expected.into_iter().zip(observed).collect();
        cells.push((Some((SAMPLES as f64 - total).max(0.0)), failed));
        let (chi2, dof) = pooled_chi2(&cells, name);
        let p = chi2_p_value(chi2, dof);
        if p < alpha {
            failures.push(format!(
                "{name}: χ² = {chi2:.1}, dof = {dof}, p = {p:.2e}; {failed} failed samples, {:.1} expected",
                SAMPLES as f64 - total
            ));
        }
    }
    assert!(
        failures.is_empty(),
        "α = {alpha:.2e}:\n{}",
        failures.join("\n")
    );
}

#[test]
fn chi_square_detects_a_wrong_pdf() {
    // The same machinery must reject a pdf that is off by a small lobe-width error:
    // samples of Δ = 1.5° binned against the pdf of Δ = 1.6°.
    let wo = direction(45.0);
    let sampled = Bdf::new(Vec3::ZERO, Vec3::ONE, 1.5f32.to_radians()).unwrap();
    let claimed = Bdf::new(Vec3::ZERO, Vec3::ONE, 1.6f32.to_radians()).unwrap();
    let map = RadialMap::new(1.6f32.to_radians());
    let frame = MirrorFrame::new(wo);
    let mut observed = vec![0u64; X_BINS * PHI_BINS];
    let mut rng = rng(7);
    for _ in 0..SAMPLES {
        let s = sampled.sample(wo, u3(&mut rng)).unwrap();
        let (t, phi) = frame.coords(s.wi);
        let i = ((map.x(t) * X_BINS as f64) as usize).min(X_BINS - 1);
        let j =
            (((phi / std::f64::consts::TAU + 0.5) * PHI_BINS as f64) as usize).min(PHI_BINS - 1);
        observed[i * PHI_BINS + j] += 1;
    }
    let expected = expected_counts(&claimed, wo, &map, &frame);
    let cells: Vec<(Option<f64>, u64)> = expected.into_iter().zip(observed).collect();
    let (chi2, dof) = pooled_chi2(&cells, "wrong pdf");
    assert!(chi2_p_value(chi2, dof) < 1e-6, "χ² = {chi2}, dof = {dof}");
}

#[test]
fn sampled_albedo_matches_albedo() {
    const N: usize = 100_000;
    let mut failures = Vec::new();
    for (k, (name, bdf, wo)) in configurations().iter().enumerate() {
        let wo = *wo;
        let mut rng = rng(5000 + k as u64);
        let (mut sum, mut sum2) = (glam::DVec3::ZERO, glam::DVec3::ZERO);
        for _ in 0..N {
            // A failed sample is a zero-weight sample of the estimator.
            if let Some(s) = bdf.sample(wo, u3(&mut rng)) {
                let w = s.weight.as_dvec3();
                sum += w;
                sum2 += w * w;
            }
        }
        let n = N as f64;
        let mean = sum / n;
        let std_err = ((sum2 / n - mean * mean).max(glam::DVec3::ZERO) / (n - 1.0)).powf(0.5);
        let albedo = bdf.albedo(wo).as_dvec3();
        // 4 standard errors, plus 1e-4 relative for the albedo table's interpolation
        // (the weight has almost no variance for a narrow lobe at normal incidence).
        let tol = 4.0 * std_err + 1e-4 * albedo;
        if (mean - albedo).abs().cmpgt(tol).any() {
            failures.push(format!(
                "{name}: sampled {mean:.6} ± {std_err:.6}, albedo() {albedo:.6}"
            ));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
