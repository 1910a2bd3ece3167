//! The unidirectional reference: path tracing with next-event estimation to point lights
//! (exact) and area lights (one light sample per vertex, MIS with BDF sampling).
use bdpm_bdf::Transport;
use bdpm_geometry::Rng;
use bdpm_scene::Scene;
use glam::Vec3;

/// Hard cap on path length; Russian roulette ends paths long before it (it guards against a
/// non-absorbing scene whose roulette probability is pinned at its ceiling).
const MAX_DEPTH: u32 = 1024;
/// Ceiling of the roulette survival probability, so that non-absorbing scenes terminate.
const MAX_SURVIVAL: f32 = 0.95;

/// One path-traced radiance sample along the camera ray `(origin, dir)` (unit `dir`):
/// an unbiased estimate of the radiance arriving at `origin` from `-dir`, W·m⁻²·sr⁻¹.
///
/// Russian roulette starts after `roulette_depth` scatterings, with survival probability
/// min(max throughput channel, 0.95).
pub fn trace_path(
    scene: &Scene,
    origin: Vec3,
    dir: Vec3,
    rng: &mut Rng,
    roulette_depth: u32,
) -> Vec3 {
    trace_path_with_first(scene, (origin, dir), rng, roulette_depth, None)
}

/// [`trace_path`] whose first BDF sample takes the numbers `first` (a sampler's stratified
/// numbers) instead of the stream's; the stream's three are drawn either way, so the rest of
/// the path reads the same numbers.
pub(crate) fn trace_path_with_first(
    scene: &Scene,
    (mut origin, mut dir): (Vec3, Vec3),
    rng: &mut Rng,
    roulette_depth: u32,
    mut first: Option<[f32; 3]>,
) -> Vec3 {
    let mut radiance = Vec3::ZERO;
    let mut beta = Vec3::ONE;
    // The radiance scaling of the refractions so far (Π 1/η²), which the roulette leaves out.
    let mut eta_scale = 1.0f32;
    let emission = scene.has_emission();
    // Where the last non-delta vertex sampled the BDF (its position and the direction's
    // density, sr⁻¹): an emitter hit after it is weighted against its light sample. None for
    // the camera ray and after delta vertices, which no light sample can reach.
    let mut bdf_from: Option<(Vec3, f32)> = None;
    for depth in 0..MAX_DEPTH {
        let Some(hit) = scene.geometry().intersect(origin, dir, f32::INFINITY) else {
            break;
        };
        let wo = -dir;
        let sh = scene.shade(&hit, wo);
        if emission {
            radiance += beta * emitted_along(scene, bdf_from.take(), &hit, wo);
        }
        if scene.is_delta(sh.material) {
            // No direct light at a mirror or glass (a point light is never on its delta):
            // follow its step; the sampler's numbers wait for the first non-delta vertex.
            let Some(step) = scene.delta_step(&sh, wo, rng.uniform(), Transport::Radiance) else {
                break;
            };
            beta *= step.weight;
            eta_scale *= step.eta_scale;
            if !survives(&mut beta, eta_scale, depth, roulette_depth, rng) {
                break;
            }
            origin = scene.spawn(&sh, step.direction);
            dir = step.direction;
            continue;
        }
        radiance += beta * scene.direct(&sh, wo);
        if emission {
            radiance += beta * scene.direct_area(&sh, wo, rng.uniform3(), true);
        }
        let wo_local = sh.frame.to_local(wo);
        if wo_local.z <= 0.0 {
            break;
        }
        let u = rng.uniform3();
        let u = first.take().unwrap_or(u);
        let Some(s) = scene.bdf_at(&sh).sample(wo_local, u) else {
            break;
        };
        let wi = sh.frame.to_world(s.wi);
        if sh.ng.dot(wi) <= 0.0 {
            break;
        }
        bdf_from = Some((sh.p, s.pdf));
        beta *= s.weight;
        if !survives(&mut beta, eta_scale, depth, roulette_depth, rng) {
            break;
        }
        origin = scene.spawn(&sh, wi);
        dir = wi;
    }
    radiance
}

/// The radiance an emitter at `hit` sends back along the ray (towards `wo`): all of it seen
/// from the camera or through delta vertices (`from` None), else weighted against the light
/// sample taken at the vertex `from` = (position, the BDF sample's density) the ray left.
pub(crate) fn emitted_along(
    scene: &Scene,
    from: Option<(Vec3, f32)>,
    hit: &bdpm_geometry::Hit,
    wo: Vec3,
) -> Vec3 {
    match from {
        None => scene.emitted(hit.prim, hit.uv, wo),
        Some((p, pdf)) => scene.emitted_mis(p, pdf, hit.prim, hit.p, hit.uv),
    }
}

/// Russian roulette after scattering `depth` (from 0): from `roulette_depth` scatterings on,
/// the path goes on with probability min(max channel of `beta`/`eta_scale`, 0.95), `beta`
/// divided by it (`eta_scale`: the refractions' radiance scaling, 1 without glass).
#[inline]
fn survives(
    beta: &mut Vec3,
    eta_scale: f32,
    depth: u32,
    roulette_depth: u32,
    rng: &mut Rng,
) -> bool {
    if depth + 1 >= roulette_depth {
        let q = (*beta / eta_scale).max_element().min(MAX_SURVIVAL);
        if q <= 0.0 || rng.uniform() >= q {
            return false;
        }
        *beta /= q;
    }
    true
}
