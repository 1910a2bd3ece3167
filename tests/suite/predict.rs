//! The noise model of method.md §12 (`Renderer::predict_variance`) against a case whose answer
//! is known: BDD=0 in the sphere furnace (method.md §10). There the merges at x₀ are the only
//! noise besides the jitter of x₀, every photon carries exactly Φ/N_F (Lambert k = 0.5 with
//! survival q = k), and a gather's variance is α·(k/π)²·E_ind with α = Φ/(N_F·S), E_ind the
//! uniform indirect irradiance: T0 has a closed form, and the measured V must agree with it.

use bdpm_integrator::{RenderSettings, Renderer, Stage, prepare::model_cache_settings};
use bdpm_suite::{Furnace, block_map, load, with_mode};
use glam::DVec3;

/// Image-mean measured per-pass variance (luminance) and its standard error, from the spread
/// of the per-pass image means of the squared deviations: pixels share photons, so their
/// variance estimates are correlated and a per-pixel formula would understate the error.
fn measured_mean_variance(renderer: &Renderer<'_>) -> (f64, f64) {
    let pixels = renderer.settings().width as usize * renderer.settings().height as usize;
    measured_group_variances(renderer, &vec![0; pixels], 1)[0]
}

/// [`measured_mean_variance`] over each group of pixels: `group[i]` is pixel i's, of `groups`.
pub(crate) fn measured_group_variances(
    renderer: &Renderer<'_>,
    group: &[usize],
    groups: usize,
) -> Vec<(f64, f64)> {
    let s = renderer.settings();
    let passes: Vec<Vec<f64>> = (0..s.passes)
        .map(|p| {
            let out = renderer.render_pass(p, &|_| {});
            out.estimates.iter().map(|c| lum(*c)).collect()
        })
        .collect();
    let k = passes.len() as f64;
    let n = passes[0].len();
    assert_eq!(group.len(), n);
    let mean: Vec<f64> = (0..n)
        .map(|i| passes.iter().map(|p| p[i]).sum::<f64>() / k)
        .collect();
    (0..groups)
        .map(|g| {
            let count = group.iter().filter(|&&x| x == g).count() as f64;
            // m_k: the group mean of pass k's squared deviation, scaled so that mean_k m_k is
            // the group mean of the unbiased per-pixel variances.
            let m: Vec<f64> = passes
                .iter()
                .map(|p| {
                    (0..n)
                        .filter(|&i| group[i] == g)
                        .map(|i| (p[i] - mean[i]).powi(2))
                        .sum::<f64>()
                        / count
                        * k
                        / (k - 1.0)
                })
                .collect();
            let v = m.iter().sum::<f64>() / k;
            let var_m = m.iter().map(|x| (x - v).powi(2)).sum::<f64>() / (k - 1.0);
            (v, (var_m / k).sqrt())
        })
        .collect()
}

/// The noise model against the measurement per 8 × 8-pixel block of a `side` × `side` render:
/// the median, least and largest of the blocks' predicted/measured image-mean V and the
/// correlation of ln V over blocks (the bars of issues 45 and 46: median in 0.8–1.25,
/// correlation ≥ 0.8). Pixels predicted non-finite are left out of their block's mean.
pub(crate) struct BlockAgreement {
    pub(crate) median: f64,
    pub(crate) min: f64,
    pub(crate) max: f64,
    pub(crate) correlation: f64,
}

impl BlockAgreement {
    /// Prints the four numbers for `what` (scene and mode) and asserts the issues' bars.
    pub(crate) fn report_and_assert_bars(&self, what: &str) {
        let Self {
            median,
            min,
            max,
            correlation,
        } = self;
        eprintln!(
            "{what}: 8x8 blocks predicted/measured median {median:.3} [min {min:.3}, max \
             {max:.3}], correlation of ln V {correlation:.3}"
        );
        assert!(
            (0.8..=1.25).contains(median),
            "{what}: block median {median}"
        );
        assert!(*correlation >= 0.8, "{what}: correlation {correlation}");
    }
}

/// [`BlockAgreement`] of `renderer`'s prediction `predicted` (per pixel) against its measured
/// per-pass variance ([`measured_group_variances`]).
pub(crate) fn block_agreement(
    renderer: &Renderer<'_>,
    predicted: &[f64],
    side: u32,
) -> BlockAgreement {
    let blocks_per_row = side.div_ceil(8) as usize;
    let group: Vec<usize> = (0..(side * side) as usize)
        .map(|i| (i / side as usize / 8) * blocks_per_row + (i % side as usize) / 8)
        .collect();
    let groups = blocks_per_row * blocks_per_row;
    let measured = measured_group_variances(renderer, &group, groups);
    let mut sums = vec![(0.0, 0usize); groups];
    for (i, v) in predicted.iter().enumerate() {
        if v.is_finite() {
            sums[group[i]].0 += v;
            sums[group[i]].1 += 1;
        }
    }
    let (mut ratios, mut lp, mut lm) = (Vec::new(), Vec::new(), Vec::new());
    for (g, (sum, count)) in sums.iter().enumerate() {
        let pred = sum / *count as f64;
        let meas = measured[g].0;
        ratios.push(pred / meas);
        lp.push(pred.ln());
        lm.push(meas.ln());
    }
    ratios.sort_by(f64::total_cmp);
    BlockAgreement {
        median: ratios[ratios.len() / 2],
        min: ratios[0],
        max: ratios[ratios.len() - 1],
        correlation: pearson(&lp, &lm),
    }
}

/// Pearson correlation of two equally long samples.
fn pearson(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len() as f64;
    let (ma, mb) = (a.iter().sum::<f64>() / n, b.iter().sum::<f64>() / n);
    let cov: f64 = a.iter().zip(b).map(|(x, y)| (x - ma) * (y - mb)).sum();
    let va: f64 = a.iter().map(|x| (x - ma).powi(2)).sum();
    let vb: f64 = b.iter().map(|y| (y - mb).powi(2)).sum();
    cov / (va * vb).sqrt()
}

/// Photons of the noise model's cache in these tests (`bdpm predict` takes
/// `MODEL_CACHE_PHOTONS`, made for 256² renders of the Cornell box): enough for the furnace's
/// closed form within its 3 % and for the small images here, in a fraction of the time.
pub(crate) const MODEL_PHOTONS: u64 = 1_000_000;

fn lum(c: DVec3) -> f64 {
    0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z
}

/// Image means of the prediction's total and of its T0.
fn predicted_means(renderer: &Renderer<'_>) -> (f64, f64, f64) {
    let p = renderer.predict_variance().expect("bdd0 has a noise model");
    let mean = |v: &[f64]| {
        assert!(
            v.iter().all(|x| x.is_finite()),
            "the closed sphere fills every pixel"
        );
        v.iter().sum::<f64>() / v.len() as f64
    };
    assert!(
        p.t1.iter().chain(&p.t2).all(|t| *t == 0.0),
        "bdd0 has no x1 part"
    );
    (mean(&p.total), mean(&p.t0), mean(&p.t_jitter))
}

fn furnace_settings(spp: u32, jitter: bool) -> (bdpm_scene::Scene, RenderSettings) {
    let (scene, settings) = load("sphere-furnace.toml", 32, 32);
    let mut s = with_mode(&settings, "bdd0", 24, spp, 40_000);
    s.radius = Some(0.05);
    s.pixel_jitter = jitter;
    (scene, s)
}

/// Tolerance: the measured image mean has a standard error σ_m of about 2 % here (24 passes,
/// 1024 correlated pixels); the prediction's own error is bounded by the closed-form check
/// (T0 within 3 % of α(k/π)²E_ind: 64 rays per pixel and the cache's L_d noise). Agreement is
/// required within 4σ_m plus that 3 %, so the test fails if the model is off by more than
/// about 11 %, and a correct model fails it with a probability below 10⁻⁴.
fn check(spp: u32, jitter: bool) {
    let (scene, settings) = furnace_settings(spp, jitter);
    let renderer = Renderer::new(&scene, &settings)
        .expect("valid settings")
        .with_model_cache(MODEL_PHOTONS);
    let (total, t0, t_jitter) = predicted_means(&renderer);

    let furnace = Furnace::of(&scene);
    let k = furnace.albedo;
    let s_area = std::f64::consts::PI * 0.05f64.powi(2);
    // Φ is the luminance of the flux (1 W per channel: 1 W).
    let alpha = furnace.flux / (settings.photons as f64 * s_area);
    let exact_t0 = alpha * (k / std::f64::consts::PI).powi(2) * furnace.indirect_irradiance();
    // N_eff/N_B = 1 in both layouts: ρ = 1 when every sample goes through the centre, and
    // N_eff = N_B = 1 with one sample per pixel.
    let expected_t0 = exact_t0;

    let (measured, se) = measured_mean_variance(&renderer);
    eprintln!(
        "furnace bdd0 spp {spp} jitter {jitter}: T0 {t0:.4e} (closed form {expected_t0:.4e}), \
         T_jitter {t_jitter:.3e}, predicted {total:.4e}, measured {measured:.4e} ± {se:.2e} \
         (ratio {:.3})",
        total / measured
    );
    assert!(
        (t0 / expected_t0 - 1.0).abs() < 0.03,
        "T0 {t0} against the closed form {expected_t0}"
    );
    assert!(
        se < 0.03 * measured,
        "the measurement is too noisy to test: {se} of {measured}"
    );
    assert!(
        (total - measured).abs() < 4.0 * se + 0.03 * total,
        "predicted {total} against measured {measured} ± {se}"
    );
}

/// Every sample through the pixel centre: the N_B gathers of a pass are one gather (ρ = 1),
/// and x₀ does not move, so V = T0 exactly.
#[test]
fn bdd0_furnace_prediction_matches_without_jitter() {
    check(4, false);
}

/// One jittered sample per pixel: N_eff = 1 whatever ρ is, so the model is exact again, now
/// with the jitter of x₀ over the pixel (T_jitter) added.
#[test]
fn bdd0_furnace_prediction_matches_with_one_jittered_sample() {
    check(1, true);
}

/// A radius per block of pixels (`adaptive_radius`; here a fixed map with blocks at ½ r, r and
/// 1.4 r): each pixel's T0 is the closed form with its own S, α/scale², and the measured V of
/// each group of blocks agrees with it. Same tolerance as [`check`]; a model that ignored the
/// map would be off by 4× on the ½ r blocks and 2× on the 1.4 r ones.
#[test]
fn bdd0_furnace_prediction_follows_a_radius_per_block() {
    let (scene, settings) = furnace_settings(4, false);
    // 32 × 32: 4 × 4 blocks, BDD=1 shares giving each scale on several blocks.
    let shares = [
        0.1, 0.45, 0.9, 0.1, //
        0.9, 0.1, 0.45, 0.9, //
        0.45, 0.9, 0.1, 0.45, //
        0.1, 0.45, 0.9, 0.1,
    ];
    let map = block_map(32, &shares);
    assert_eq!(map.blocks(), [6, 5, 5]);
    let scales: Vec<f32> = (0..32 * 32).map(|i| map.scale(i % 32, i / 32)).collect();
    let renderer = Renderer::new(&scene, &settings)
        .expect("valid settings")
        .with_radius_map(map)
        .with_model_cache(MODEL_PHOTONS);
    let p = renderer.predict_variance().expect("bdd0 has a noise model");

    let furnace = Furnace::of(&scene);
    let k = furnace.albedo;
    let s_area = std::f64::consts::PI * 0.05f64.powi(2);
    let alpha = furnace.flux / (settings.photons as f64 * s_area);
    let exact_t0 = alpha * (k / std::f64::consts::PI).powi(2) * furnace.indirect_irradiance();
    let group: Vec<usize> = scales
        .iter()
        .map(|&s| {
            [0.5, 1.0, 1.4]
                .iter()
                .position(|&c| c == s)
                .expect("a class scale")
        })
        .collect();
    let measured = measured_group_variances(&renderer, &group, 3);
    for (g, scale) in [0.5f64, 1.0, 1.4].into_iter().enumerate() {
        let mean = |v: &[f64]| {
            let (sum, n) = v
                .iter()
                .zip(&group)
                .filter(|(_, gi)| **gi == g)
                .fold((0.0, 0.0), |(s, n), (x, _)| (s + x, n + 1.0));
            sum / n
        };
        let (t0, total) = (mean(&p.t0), mean(&p.total));
        let expected = exact_t0 / (scale * scale);
        let (v, se) = measured[g];
        eprintln!(
            "furnace bdd0, blocks at {scale} r: T0 {t0:.4e} (closed form {expected:.4e}), \
             predicted {total:.4e}, measured {v:.4e} ± {se:.2e} (ratio {:.3})",
            total / v
        );
        assert!(
            (t0 / expected - 1.0).abs() < 0.03,
            "{scale} r: T0 {t0} against the closed form {expected}"
        );
        assert!(se < 0.05 * v, "{scale} r: too noisy to test: {se} of {v}");
        assert!(
            (total - v).abs() < 4.0 * se + 0.03 * total,
            "{scale} r: predicted {total} against measured {v} ± {se}"
        );
    }
}

/// The noise model's cache does not change what a render computes (the mix reads the
/// weights' cache, and only when its mode needs one): the same image bits with and without
/// it, for modes without a cache and for the glossy file's `optimal-path`, whose weights read
/// a one-bin cache while the model gets its own of `MODEL_CACHE_BINS` bins. A renderer whose
/// settings are `model_cache_settings` weighs with the model's cache and builds no second one.
#[test]
fn model_inputs_keep_the_image_bits() {
    let stages = |r: &Renderer<'_>| -> Vec<String> {
        r.stages()
            .iter()
            .filter(|st| st.stage == Stage::RadianceCache)
            .map(|st| st.detail.clone())
            .collect()
    };
    let lambert = load("preprint/cornell-lambert.toml", 16, 16);
    let glossy = load("cornell-glossy.toml", 16, 16);
    let cases = [
        (&lambert, "bdd0"),
        (&lambert, "bdd1"),
        (&lambert, "balance"),
        (&glossy, "optimal-path"),
    ];
    for ((scene, settings), mode) in cases {
        let mut s = with_mode(settings, mode, 1, 2, 5_000);
        s.adaptive_radius = false;
        let plain = Renderer::new(scene, &s).expect("valid settings");
        let with_cache = Renderer::new(scene, &s)
            .expect("valid settings")
            .with_model_cache(MODEL_PHOTONS);
        let built = stages(&with_cache);
        let model = built
            .iter()
            .find(|d| d.starts_with("noise model's"))
            .unwrap_or_else(|| panic!("{mode}: no model cache in {built:?}"));
        assert!(
            model.contains(&format!("{MODEL_PHOTONS} photons")),
            "{model}"
        );
        if mode == "optimal-path" {
            assert_eq!(s.cache_bins, 1, "the glossy file's weights read one bin");
            assert_eq!(built.len(), 2, "{built:?}");
            assert!(model.contains("100 bin(s)"), "{model}");
        }
        let a = plain.render_pass(0, &|_| {}).estimates;
        let b = with_cache.render_pass(0, &|_| {}).estimates;
        assert_eq!(a, b, "{mode}");

        let own = Renderer::new(scene, &model_cache_settings(&s, MODEL_PHOTONS))
            .expect("valid settings")
            .with_model_cache(MODEL_PHOTONS);
        let built = stages(&own);
        if mode == "optimal-path" {
            assert_eq!(built.len(), 1, "{mode}: {built:?}");
            assert!(!built[0].starts_with("noise model's"), "{built:?}");
        }
    }
}

/// Image sum of a prediction's total over the pixels where both are finite.
fn total_over(p: &bdpm_integrator::Prediction, q: &bdpm_integrator::Prediction) -> (f64, f64) {
    p.total
        .iter()
        .zip(&q.total)
        .filter(|(a, b)| a.is_finite() && b.is_finite())
        .fold((0.0, 0.0), |(sa, sb), (a, b)| (sa + a, sb + b))
}

/// The floor of `bdpm predict --headroom`: the unclamped `optimal-split` minimises the §12
/// functional over weights per (x₀, x₁) and path kind, so no mode evaluated in that family
/// predicts less V (the floor's A and B come from other rays than the prediction's, so it is
/// a minimiser only up to their sampling error: 1 % is allowed). The pure strategies sit far
/// above it. And the headroom responds to what the model says creates it: the correlation of
/// a pixel's samples. Through the pixel centre (ρ = 1) `balance` leaves a clear gap; with
/// jittered samples (N_eff ≈ 1) the weights it leaves on the table are small.
#[test]
fn no_mode_predicts_less_than_the_floor() {
    let (scene, settings) = load("preprint/cornell-lambert.toml", 24, 24);
    let floor_h = bdpm_mis::Heuristic::OptimalSplit {
        clamp_weights: false,
    };
    let mut gaps = Vec::new();
    for jitter in [true, false] {
        // The floor weighs with the cache the model reads (as `bdpm predict --headroom`'s).
        let mut base = model_cache_settings(
            &with_mode(&settings, "optimal-split", 1, 8, 50_000),
            MODEL_PHOTONS,
        );
        base.pixel_jitter = jitter;
        let floor_r = Renderer::new(&scene, &base)
            .expect("valid settings")
            .with_model_cache(MODEL_PHOTONS);
        let floor = floor_r.predict_variance_for(floor_h).expect("floor");
        for mode in ["bdd0", "bdd1", "optimal", "balance", "optimal-path"] {
            let mut s = with_mode(&settings, mode, 1, 8, 50_000);
            s.pixel_jitter = jitter;
            let r = Renderer::new(&scene, &s)
                .expect("valid settings")
                .with_model_cache(MODEL_PHOTONS);
            let p = r.predict_variance().expect("a BDPM mode");
            let (v, f) = total_over(&p, &floor);
            let ratio = v / f;
            eprintln!("jitter {jitter} {mode}: predicted V / floor {ratio:.4}");
            assert!(
                ratio > 0.99,
                "{mode} (jitter {jitter}) below the floor: {ratio}"
            );
            if mode.starts_with("bdd") {
                assert!(
                    ratio > 1.1,
                    "{mode} (jitter {jitter}) near the floor: {ratio}"
                );
            }
            if mode == "balance" {
                gaps.push(ratio - 1.0);
            }
        }
    }
    // gaps = [jittered, centred].
    assert!(
        gaps[1] > 0.05 && gaps[1] > 4.0 * gaps[0].max(0.0),
        "balance's headroom jittered {} against centred {}",
        gaps[0],
        gaps[1]
    );
}

/// `direct_boost`: where a pixel takes M direct-light samples per camera sample, the model
/// divides L₀'s part of T_jitter by M, and the predicted V of those pixels follows the measured
/// one down; every other pixel's prediction keeps its bits. cornell-lambert at 16², where the
/// ceiling spot above the light falls in two pixels and their V is mostly L₀'s jitter.
#[test]
fn direct_boost_lowers_the_predicted_jitter_where_it_samples_more() {
    let (scene, settings) = load("preprint/cornell-lambert.toml", 16, 16);
    let mut s = with_mode(&settings, "balance", 32, 128, 100_000);
    s.radius = Some(0.01);
    let run = |boost: u32| {
        let s = RenderSettings {
            direct_boost: boost,
            ..s.clone()
        };
        let renderer = Renderer::new(&scene, &s)
            .expect("valid settings")
            .with_model_cache(MODEL_PHOTONS);
        let p = renderer
            .predict_variance()
            .expect("balance has a noise model");
        let m: Vec<u32> = (0..256)
            .map(|i| {
                renderer
                    .direct_samples()
                    .map_or(1, |d| d.at(i % 16, i / 16))
            })
            .collect();
        let film = bdpm_suite::render_with(&renderer);
        let measured: Vec<f64> = film.pass_variance().iter().map(|c| lum(*c)).collect();
        (p, m, measured)
    };
    let (one, m_one, v_one) = run(1);
    let (many, m, v_many) = run(16);
    assert!(m_one.iter().all(|&m| m == 1));
    let boosted: Vec<usize> = (0..256).filter(|&i| m[i] > 1).collect();
    assert!(!boosted.is_empty(), "the spot takes more than one sample");
    for (i, &mi) in m.iter().enumerate() {
        if mi > 1 {
            assert!(
                many.t_jitter[i] < 0.5 * one.t_jitter[i],
                "pixel {i}, M {mi}: T_jitter {} against {}",
                many.t_jitter[i],
                one.t_jitter[i]
            );
        } else {
            assert_eq!(many.t_jitter[i], one.t_jitter[i], "pixel {i}");
            assert_eq!(many.total[i], one.total[i], "pixel {i}");
        }
    }
    let sum = |v: &[f64]| boosted.iter().map(|&i| v[i]).sum::<f64>();
    let (predicted_fall, measured_fall) = (
        sum(&one.total) / sum(&many.total),
        sum(&v_one) / sum(&v_many),
    );
    eprintln!(
        "boosted pixels {boosted:?}: predicted V falls {predicted_fall:.2}x, measured \
         {measured_fall:.2}x (32 passes each)"
    );
    // Each measured sum has ~25 % standard error (32 passes, 2 pixels): a fall within a
    // factor 1.6 of the predicted one.
    let r = predicted_fall / measured_fall;
    assert!(
        (1.0 / 1.6..1.6).contains(&r),
        "predicted over measured fall {r:.2}"
    );
}

/// κ of `photon_power_spread` in the sphere furnace, whose photons all arrive again: with a
/// grey wall every photon keeps its Φ/N (κ = 1); with kd = (0.6, 0.3, 0.15) the roulette
/// survives with q = 0.6 and multiplies the photon's colour by c = kd/q at each bounce, so a
/// photon arrives after d ≥ 1 bounces with probability q^d carrying lum(c^d)·Φ/N, and
/// κ = Σ q^d lum(c^d)² / Σ q^d lum(c^d) = 0.4738. Seeds 1–8 gave 0.4725–0.4744 (standard
/// deviation 0.13 %), so the 1 % tolerance is about 7 of them.
#[test]
fn photon_power_spread_matches_the_furnace_series() {
    use bdpm_integrator::photon_spread::photon_power_spread;
    let text = std::fs::read_to_string(bdpm_suite::scene_path("sphere-furnace.toml"))
        .expect("the scene file");
    let (grey, _) = crate::specular::load(&text);
    let kappa = photon_power_spread(&grey, 1);
    assert!((kappa - 1.0).abs() < 1e-5, "grey: {kappa}");

    let kd = DVec3::new(0.6, 0.3, 0.15);
    let text = text.replace("kd = 0.5\n", "kd = [0.6, 0.3, 0.15]\n");
    let (coloured, _) = crate::specular::load(&text);
    let q = 0.6;
    let lum = |c: DVec3| 0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z;
    let (mut num, mut den) = (0.0, 0.0);
    for d in 1..200 {
        let p = lum((kd / q).powf(f64::from(d)));
        num += q.powi(d) * p * p;
        den += q.powi(d) * p;
    }
    let expected = num / den;
    let kappa = photon_power_spread(&coloured, 1);
    eprintln!("kappa {kappa}, series {expected}");
    assert!(
        (kappa / expected - 1.0).abs() < 0.01,
        "{kappa} vs {expected}"
    );
}
