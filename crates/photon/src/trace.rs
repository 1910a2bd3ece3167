//! Emission from point lights and the random walk of photons (method.md §1).

use bdpm_core::sampling::uniform_sphere;
use bdpm_core::{Domain, Rng, Shading, WeightVertex};

use crate::scene::{AREA_LIGHT, PhotonScene, Scatter};
use glam::Vec3;
use rayon::prelude::*;

/// Photons per parallel work item. Fixed (not derived from the thread count) so that the
/// chunking, and therefore every output, is the same on any number of threads.
pub(crate) const CHUNK: u64 = 4096;

/// One surface vertex of a light path: every surface hit, including the first hit from the
/// light (which is direct light and not itself stored as a [`Photon`](crate::Photon)).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PathVertex {
    /// Position, normal (flipped to the side the light arrived from: surfaces are two-sided),
    /// material, triangle and light visibility, as the MIS weights read them. The visibility
    /// bits are filled only with [`TraceOptions::light_visibility`] and only at vertices the
    /// path continued from (each is the previous vertex y_p of the next stored photon, where
    /// the weights read it); 0 elsewhere.
    pub at: WeightVertex,
    /// Unit direction from this vertex back towards where the light came from (the previous
    /// vertex, or the light for depth 0).
    pub incoming: Vec3,
    /// Index of the point light that emitted this path, or [`AREA_LIGHT`] for an area light.
    pub light: u16,
    /// Number of scatterings before this arrival: 0 = reached directly from the light.
    pub depth: u16,
    /// Russian-roulette survival probability q used when scattering at this vertex
    /// (dimensionless): the scene's survival probability of the material for `incoming`
    /// (bdpm's: `bdpm_bdf::survival_probability`). Recorded even where the path ended (absorbed, failed BDF sample or the depth cap), because the weights
    /// need the density with which the walk *would* continue.
    pub survival: f32,
}

/// Parameters of one photon pass.
#[derive(Clone, Copy, Debug)]
pub struct TraceOptions {
    /// N_F: photons emitted in this pass (all lights together).
    pub photons: u64,
    /// Master seed of the render.
    pub seed: u64,
    /// Random-stream domain: `Domain::Photon` for render passes, `Domain::CachePhoton` for the
    /// radiance-cache pre-pass (independent streams).
    pub domain: Domain,
    /// Pass index (stream key): photon `i` of pass `pass` uses `Rng::new(seed, domain, [pass, i, 0])`.
    pub pass: u32,
    /// Fill the visibility bits of [`PathVertex::at`] (one shadow ray per light, up to 32, per vertex the
    /// path continues from).
    pub light_visibility: bool,
    /// Hard cap on scatterings per path (arrivals have depth ≤ `max_depth`), a guard for
    /// scenes that barely absorb; e.g. [`MAX_DEPTH`].
    pub max_depth: u32,
}

/// The cap on scatterings per light path that every tracer of bdpm uses (render passes, the
/// radiance cache, the memory estimate's pilot): Russian roulette ends paths long before it;
/// it guards against a scene that barely absorbs.
pub const MAX_DEPTH: u32 = 1024;

impl TraceOptions {
    /// Options for `photons` photons of render pass `pass` with the defaults: photon domain,
    /// no light visibility, `max_depth` [`MAX_DEPTH`].
    pub fn new(photons: u64, seed: u64, pass: u32) -> TraceOptions {
        TraceOptions {
            photons,
            seed,
            domain: Domain::Photon,
            pass,
            light_visibility: false,
            max_depth: MAX_DEPTH,
        }
    }
}

/// A photon leaving a light: which light, from where, where to, with what power.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Emission {
    /// Index of the chosen light.
    pub(crate) light: usize,
    /// Probability p_l with which that light was chosen.
    pub(crate) light_probability: f32,
    /// Ray origin (the light's position), m.
    pub(crate) origin: Vec3,
    /// Unit direction: uniform on the sphere from a point light (density 1/(4π) sr⁻¹), as
    /// the scene's [`PhotonScene::emit_area`] chose from an area light.
    pub(crate) direction: Vec3,
    /// Power Φ_l / (p_l · N_F), W per channel.
    pub(crate) power: Vec3,
    /// Emitted by an area light ([`PhotonScene::is_area_light`]).
    pub(crate) area: bool,
}

/// Emits one photon of a pass of `photons` (N_F) photons: `u_light` picks a light with
/// probability [`PhotonScene::pick_light`] (bdpm's scene: proportional to flux luminance),
/// `u_dir` an isotropic direction from a point light. An area light also asks `u_point` for
/// two more numbers (so point-light paths draw exactly what they drew before area lights).
/// Returns `None` only if the picked light has zero probability (cannot happen for
/// `u_light` in [0, 1)), it emits nothing or `photons` is 0.
pub(crate) fn emit<S: PhotonScene + ?Sized>(
    scene: &S,
    u_light: f32,
    u_dir: [f32; 2],
    u_point: impl FnOnce() -> [f32; 2],
    photons: u64,
) -> Option<Emission> {
    let (light, p) = scene.pick_light(u_light);
    if p.is_nan() || p <= 0.0 || photons == 0 {
        return None;
    }
    if scene.is_area_light(light) {
        let a = scene.emit_area(light, p, u_point(), u_dir)?;
        return Some(Emission {
            light,
            light_probability: p,
            origin: a.origin,
            direction: a.direction,
            power: a.flux / photons as f32,
            area: true,
        });
    }
    let l = scene.light(light);
    Some(Emission {
        light,
        light_probability: p,
        origin: l.position,
        direction: uniform_sphere(u_dir),
        power: l.flux / (p * photons as f32),
        area: false,
    })
}

/// Everything known at one arrival of a photon at a surface, as passed to the visitors of
/// [`trace_photons`].
#[derive(Clone, Copy, Debug)]
pub struct PhotonArrival {
    /// Index of the emitted photon in its pass (0..N_F).
    pub photon: u64,
    /// The vertex (its `depth` 0 is the first hit, which is direct light).
    pub vertex: PathVertex,
    /// Arriving power E_p, W per channel (includes Φ/N_F; for depth 0 the emitted power).
    pub power: Vec3,
    /// The vertex the photon was scattered from (y_p), `None` at depth 0.
    pub previous: Option<PathVertex>,
    /// The shading data of the hit, oriented to the side of `vertex.incoming`.
    pub shading: Shading,
    /// The BDF sample drawn here, before Russian roulette: present whenever sampling
    /// succeeded on the correct side of the geometric normal, whether or not the photon then
    /// survived. The photon continued along it iff `continued`. A visitor that needs an
    /// unbiased scattered-direction sample (e.g. the radiance cache, method.md §5: scattered
    /// energy `power · weight`) can use it without drawing random numbers of its own.
    pub scatter: Option<Scatter>,
    /// True iff the photon survived the roulette and the depth cap and left along `scatter`.
    pub continued: bool,
    /// True iff the vertex is a delta one ([`PhotonScene::is_delta`]): no photon is stored
    /// there and nothing connects to it; `scatter` is the delta step.
    pub delta: bool,
    /// True iff the photon has scattered only at delta vertices since it left the light (and
    /// at least once): it arrives by light → mirrors and glass → here, a caustic's path,
    /// which no technique but a merge here can sample from a point light.
    pub caustic: bool,
}

/// Traces the pass described by `options` in parallel and returns the records that `visit`
/// pushes for each arrival, in photon order and, within a photon, in path order, whatever the
/// thread count: the result is a pure function of (scene, options).
///
/// `visit` sees every arrival, depth 0 included (filter on `arrival.vertex.depth >= 1` for
/// stored photons), and may push any number of records of its own type.
pub fn trace_photons<R: Send, S: PhotonScene + ?Sized>(
    scene: &S,
    options: &TraceOptions,
    visit: impl Fn(&PhotonArrival, &mut Vec<R>) + Sync,
) -> Vec<R> {
    trace_photons_until(scene, options, visit, &never).unwrap_or_default()
}

/// [`trace_photons`] that gives up when `stop()` returns true: it is asked before each chunk
/// of 4096 photons, and the result is `None` when a chunk was skipped (it would be
/// incomplete). For long pre-passes that an interrupt must stop promptly; a `stop` that never
/// fires changes nothing, the records included.
pub fn trace_photons_until<R: Send, S: PhotonScene + ?Sized>(
    scene: &S,
    options: &TraceOptions,
    visit: impl Fn(&PhotonArrival, &mut Vec<R>) + Sync,
    stop: &(dyn Fn() -> bool + Sync),
) -> Option<Vec<R>> {
    let chunks = trace_chunks(scene, options, |_| Vec::new(), |out, a| visit(a, out), stop)?;
    let mut out = Vec::with_capacity(chunks.iter().map(Vec::len).sum());
    for c in chunks {
        out.extend(c);
    }
    Some(out)
}

/// A stop that never fires.
pub(crate) fn never() -> bool {
    false
}

/// The parallel driver: one accumulator per fixed chunk of photon indices, returned in chunk
/// order. `new(chunk)` makes a chunk's accumulator; `visit` is called for each arrival of the
/// chunk's photons, sequentially and in path order. `stop` is asked before each chunk; `None`
/// when it skipped one.
pub(crate) fn trace_chunks<A: Send, S: PhotonScene + ?Sized>(
    scene: &S,
    options: &TraceOptions,
    new: impl Fn(u64) -> A + Sync,
    visit: impl Fn(&mut A, &PhotonArrival) + Sync,
    stop: &(dyn Fn() -> bool + Sync),
) -> Option<Vec<A>> {
    let chunks = options.photons.div_ceil(CHUNK);
    let done: Vec<Option<A>> = (0..chunks)
        .into_par_iter()
        .map(|c| {
            if stop() {
                return None;
            }
            let mut acc = new(c);
            let end = ((c + 1) * CHUNK).min(options.photons);
            for i in c * CHUNK..end {
                trace_one(scene, options, i, &mut |a| visit(&mut acc, a));
            }
            Some(acc)
        })
        .collect();
    done.into_iter().collect()
}

/// The random walk of photon `index` of the pass.
fn trace_one<S: PhotonScene + ?Sized>(
    scene: &S,
    options: &TraceOptions,
    index: u64,
    visit: &mut impl FnMut(&PhotonArrival),
) {
    let mut rng = Rng::new(
        options.seed,
        options.domain,
        [u64::from(options.pass), index, 0],
    );
    let u_light = rng.uniform();
    let u_dir = rng.uniform2();
    let Some(e) = emit(scene, u_light, u_dir, || rng.uniform2(), options.photons) else {
        return;
    };
    // Lights beyond u16 cannot be named in a vertex; scenes have a handful of point lights,
    // and an area light's path records only that it is one.
    let light = if e.area {
        AREA_LIGHT
    } else {
        e.light.min(usize::from(u16::MAX - 1)) as u16
    };
    let max_depth = options.max_depth.min(u32::from(u16::MAX));
    let mut origin = e.origin;
    let mut dir = e.direction;
    let mut power = e.power;
    let mut previous: Option<PathVertex> = None;
    let mut depth: u32 = 0;
    // Every vertex so far was a delta one (vacuously at the first hit).
    let mut only_delta = true;
    while let Some(sh) = scene.intersect(origin, dir) {
        let incoming = -dir;
        // The random numbers are drawn in a fixed order whatever happens, so that a visitor's
        // view of one arrival never shifts the stream of another.
        let u_rr = rng.uniform();
        let u_bdf = rng.uniform3();
        let delta = scene.is_delta(&sh);
        let (survival, sample) = scene.scatter(&sh, incoming, u_bdf);
        let mut vertex = PathVertex {
            // The visibility bits are filled below once it is known whether the path goes on.
            at: WeightVertex::at(&sh, 0),
            incoming,
            light,
            depth: depth as u16,
            survival,
        };
        // The shading normal may disagree with the geometric one; a direction that would pass
        // through the surface carries no light (no transmission in the non-delta models). A
        // delta step has been checked by the scene and may refract through.
        let scatter = if delta {
            sample
        } else {
            sample.filter(|s| sh.ng.dot(s.direction) > 0.0)
        };
        let continued = scatter.is_some() && u_rr < survival && depth < max_depth;
        // Only a vertex the path leaves is some photon's previous vertex, the one place the
        // weights read light visibility: a path's last vertex would waste its shadow rays (and
        // a delta vertex is nobody's y_p the weights read).
        if options.light_visibility && continued && !delta {
            vertex.at.lights = if depth == 0 && !e.area {
                scene.visible_light_mask_reached(&sh, e.light)
            } else {
                scene.visible_light_mask(&sh)
            };
        }
        visit(&PhotonArrival {
            photon: index,
            vertex,
            power,
            previous,
            shading: sh,
            scatter,
            continued,
            delta,
            caustic: depth >= 1 && only_delta,
        });
        only_delta &= delta;
        let Some(s) = scatter.filter(|_| continued) else {
            break;
        };
        // Roulette with q independent of power keeps the estimator unbiased: E[w/q · 1{u<q}] = w.
        power *= s.weight / survival;
        origin = scene.spawn(&sh, s.direction);
        dir = s.direction;
        previous = Some(vertex);
        depth += 1;
    }
}
