//! The weight map of the preprint's Fig. 5 (`Renderer::weight_map`) with a radius per block of
//! pixels: x₀ is seen through a known pixel, so the map is that pixel's weights, with its
//! radius. A map whose blocks are all at ½ r must be the map of a render at r/2.

use bdpm_integrator::{Renderer, WeightTarget};
use bdpm_suite::{block_map, load, with_mode};

#[test]
fn a_weight_map_takes_its_pixels_radius() {
    let (scene, settings) = load("preprint/cornell-lambert.toml", 16, 16);
    // BDD=1 under 30 % of every block: all of them at ½ r.
    let halves = block_map(16, &[0.1; 4]);
    for mode in ["optimal", "algebraic"] {
        let mut s = with_mode(&settings, mode, 1, 4, 20_000);
        s.radius = Some(0.02);
        let target = WeightTarget::Pixel(8, 12);
        let map = |r: &Renderer<'_>| r.weight_map(target).expect("a weight map").w0;
        let at_r = map(&Renderer::new(&scene, &s).expect("valid settings"));
        let per_block = map(&Renderer::new(&scene, &s)
            .expect("valid settings")
            .with_radius_map(halves.clone()));
        // 0.02 × 0.5 is 0.01 exactly in f32.
        s.radius = Some(0.01);
        let at_half = map(&Renderer::new(&scene, &s).expect("valid settings"));
        let largest_gap = |a: &[f64], b: &[f64]| {
            a.iter()
                .zip(b)
                .filter(|(x, y)| x.is_finite() && y.is_finite())
                .map(|(x, y)| (x - y).abs())
                .fold(0.0, f64::max)
        };
        let same = largest_gap(&per_block, &at_half);
        let apart = largest_gap(&at_r, &at_half);
        eprintln!("{mode}: |per block − r/2| ≤ {same:.2e}, |r − r/2| up to {apart:.3}");
        assert!(
            same < 1e-9,
            "{mode}: the per-block map is not r/2's: {same}"
        );
        assert!(apart > 0.01, "{mode}: the radius does not move w0: {apart}");
    }
}
