//! Light tracing: a photon arrival connected to the pinhole camera. The `light` reference
//! splats every arrival of depth ≥ 1 unweighted; the mix with `light_tracing` on samples
//! BDD=0's paths this way instead of merging photons at x₀, with BDD=0's weight
//! 1 − w₁(x₀, y_p) (docs/method-notes.md, "Light tracing in place of the merge at x₀").
use bdpm_mis::{Pair, Weigher};
use bdpm_photon::{PathVertex, PhotonArrival};
use bdpm_scene::{Scene, Shading};
use glam::Vec3;

use crate::estimates::WeightStats;
use crate::inputs::direction_to;
use crate::mix::{FirstVertex, Mix};

/// A photon arrival connected to the camera: where it lands on the film and what it adds.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Connection {
    /// The pixel it lands in, column `x`, row `y` (from the top).
    pub(crate) x: u32,
    pub(crate) y: u32,
    /// Unit direction from the arrival towards the camera.
    pub(crate) to_camera: Vec3,
    /// Its contribution to the pixel's estimate (radiance averaged over the pixel's
    /// image-plane area), W·m⁻²·sr⁻¹ per channel.
    pub(crate) value: Vec3,
}

/// Connects the arrival at `sh` (light arriving from the unit direction `incoming` with power
/// `power`, W per channel) to the camera: None where the camera is behind the surface or
/// outside the image, the BDF is 0 towards it, or the segment is occluded.
pub(crate) fn connect(
    scene: &Scene,
    sh: &Shading,
    incoming: Vec3,
    power: Vec3,
) -> Option<Connection> {
    let cam = &scene.camera();
    let to_cam = cam.position() - sh.p;
    let d2 = to_cam.length_squared();
    if d2 <= 0.0 || sh.ng.dot(to_cam) <= 0.0 {
        return None;
    }
    let wc = to_cam / d2.sqrt();
    let (fx, fy) = cam.project(sh.p)?;
    let cos_cam = cam.forward().dot(-wc);
    let cos_x = sh.frame.n.dot(wc);
    if cos_cam <= 0.0 || cos_x <= 0.0 {
        return None;
    }
    let f = scene.eval(sh, wc, incoming);
    if f == Vec3::ZERO
        || scene
            .geometry()
            .occluded(scene.spawn(sh, wc), cam.position())
    {
        return None;
    }
    // Radiance averaged over the pixel's image-plane area: dA_plane = dω/cos³θ_c and
    // dω = cos_x dA/d², so a photon adds f·E_p·cos_x/(d²·cos³θ_c·a_pixel).
    let k = 1.0 / cam.pixel_area();
    let value = f * power * (cos_x * k / (d2 * cos_cam * cos_cam * cos_cam));
    Some(Connection {
        x: fx as u32,
        y: fy as u32,
        to_camera: wc,
        value,
    })
}

/// One light-tracing contribution of the mix to a pixel's pass estimate.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Splat {
    /// Row-major pixel index.
    pub(crate) pixel: u32,
    /// Unweighted, W·m⁻²·sr⁻¹ per channel (the pure light-tracing estimate).
    pub(crate) raw: Vec3,
    /// The weight w₁ of BDD=1 for the path; the splat adds `raw`·(1 − w₁).
    pub(crate) w1: f64,
}

/// What one chunk of photon paths splatted, in path order.
#[derive(Default)]
pub(crate) struct Splats {
    pub(crate) list: Vec<Splat>,
    pub(crate) stats: WeightStats,
}

impl Mix<'_> {
    /// The mix's light-tracing contribution of one photon arrival, or None. `vertices` are the
    /// light-path vertices its chunk kept before it (the arrival's y_p last), `weigher(x, y)`
    /// the weigher of pixel (x, y). The path …→y_p→x is weighed exactly as a merge of this
    /// photon at a camera vertex x₀ = x would be ([`Mix::photon_side_pair`]'s inputs), so BDD=1
    /// at the camera's x₁ and this splat sum to one weight per path.
    pub(crate) fn splat(
        &self,
        a: &PhotonArrival,
        vertices: &[PathVertex],
        weigher: impl Fn(u32, u32) -> Weigher,
        splats: &mut Splats,
    ) {
        // Depth 0 is direct light at x, which the camera side adds exactly. (`bdd1` has no
        // BDD=0 part and never light-traces: `Mix::light_tracing` is false for it.)
        if a.vertex.depth == 0 || a.delta {
            return;
        }
        let Some(c) = connect(self.scene, &a.shading, a.vertex.incoming, a.power) else {
            return;
        };
        let Some(x0) = self.first_vertex_shaded(a.shading, c.to_camera) else {
            return;
        };
        let w1 = if let Some(w1) = self.fixed_w1 {
            // As a merge at x₀ would, no path where y_p is x₀ itself.
            if direction_to(&x0, &vertices[vertices.len() - 1].at).is_none() {
                return;
            }
            w1
        } else {
            let Some(pair) = self.splat_pair(&x0, vertices) else {
                return;
            };
            let weigher = weigher(c.x, c.y);
            if self.two_way_splat_weights() {
                weigher.weight(&pair).w1
            } else {
                self.w1(&pair, &weigher, &mut splats.stats)
            }
        };
        let w = self.scene.camera().width();
        splats.list.push(Splat {
            pixel: c.y * w + c.x,
            raw: c.value,
            w1,
        });
    }

    /// The inputs of a splat's path …→y_p→x₀ at x₀ = the arrival (`x0`, seen from the
    /// camera), `vertices` its chunk's light-path vertices with y_p last: the photon side's
    /// function ([`Mix::light_vertex_pair`]), so the agreement test in inputs.rs covers it.
    pub(crate) fn splat_pair(&self, x0: &FirstVertex<'_>, vertices: &[PathVertex]) -> Option<Pair> {
        self.light_vertex_pair(x0, vertices, (vertices.len() - 1) as u32, None)
    }
}
