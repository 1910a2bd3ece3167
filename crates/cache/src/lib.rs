//! The directional radiance cache of method.md §5 (preprint §6.1): per surface cell and per
//! outgoing-direction bin, the secondary radiance L_d and the quantity b = ∫ f² J dv' that the
//! optimal weights need at a camera path's second vertex.
//!
//! - **Cells** subdivide every triangle into n² congruent sub-triangles (n from a target cell
//!   size), so each cell's area is exactly the triangle's area / n²; each side of a surface
//!   has its own cells (surfaces are two-sided).
//! - **Bins** are K equal-solid-angle bins over the hemisphere: the equal-area concentric map
//!   takes a direction to the unit square, which is split into a √K × √K grid
//!   (so K is rounded to a square; each bin spans 2π/K sr).
//! - **Bin values** are cosine-weighted averages over the bin: the luminance of the energy
//!   scattered into the bin divided by (cell area × the bin's projected solid angle ∫cos dω).
//!   method.md §5 divides each photon by its cos and the bin by its solid angle ω instead,
//!   which estimates the plain average but has infinite variance (E[1/cos²] diverges under
//!   cosine-weighted scattering): one grazing scatter could double a cell. Both converge to
//!   L_d as the bins shrink, and a Lambert cell's single bin is exact either way.
//! - **Filling** uses a photon pass of its own random stream (`Domain::CachePhoton`), frozen
//!   before rendering, so the weights never depend on the photons they weight
//!   ([`RadianceCache::build`]); or arrivals the caller traced ([`RadianceCache::from_arrivals`]).
//! - **Scenes** are seen through two small traits: [`CacheSurfaces`] (triangles and Lambert
//!   albedos) and, to trace the cache's own photons, [`PhotonScene`]. bdpm's `Scene`
//!   implements both; another renderer implements them for its own scene type.
//! - **Lambert-only scenes** get one bin per cell and no b (b = (kd/π)·L_d there, method.md §7).
//! - **Storage** is sparse where that is smaller: cell sides that no photon reached (about half
//!   of them in a closed box: the outer faces) share one block of zero bins instead of a block
//!   each, and read the zeros they read in a dense table. A glossy Cornell box at paper
//!   settings (100 bins, L_d and b) takes 21 MB instead of 43 MB.
//!
//! Values are luminances (the weights use luminance): L_d in W·m⁻²·sr⁻¹, b in W·m⁻²·sr⁻².
//!
//! Architecture invariant: knows nothing of weights, pixels or films; it reads photons and
//! geometry and answers lookups by (triangle, point, direction).

use std::f32::consts::PI;

use bdpm_core::{Domain, Frame, luminance};
use bdpm_photon::{PhotonScene, TraceOptions, trace_photons_until};
use glam::{Vec2, Vec3};

/// How to build a cache.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CacheSettings {
    /// Requested bins per hemisphere K (rounded to the nearest square ≥ 1); ignored (1 bin) for
    /// Lambert-only scenes.
    pub bins: u32,
    /// Target cell edge length, metres (cells are at most this long along a triangle edge).
    pub cell_size: f32,
    /// Photons emitted for the cache pass.
    pub photons: u64,
    /// Master seed (the cache uses its own stream domain).
    pub seed: u64,
}

/// What the cache needs to know about the surfaces it covers: triangles (the cells subdivide
/// each) and, for scenes whose materials are all Lambert, each triangle's albedo (b is then
/// (k_d/π)·L_d and is not stored). A renderer with its own mesh implements this and fills a
/// cache with [`RadianceCache::from_arrivals`]; one that also implements
/// [`PhotonScene`] can let [`RadianceCache::build`] trace the cache's photons.
///
/// Triangle indices are the `prim` of lookups and arrivals: 0..[`Self::triangle_count`].
pub trait CacheSurfaces: Sync {
    /// Number of triangles.
    fn triangle_count(&self) -> usize;
    /// The vertices of triangle `prim`, m; their winding defines the side called front.
    fn triangle(&self, prim: u32) -> [Vec3; 3];
    /// The unit geometric normal of triangle `prim` on its front side.
    fn normal(&self, prim: u32) -> Vec3;
    /// The area of triangle `prim`, m²; a triangle of area 0 gets one cell and no values.
    fn area(&self, prim: u32) -> f32;
    /// True when every material is pure Lambert: the cache then keeps one bin per cell side
    /// and derives b from [`Self::lambert_albedo`].
    fn lambert_only(&self) -> bool;
    /// Luminance of the Lambert albedo k_d of triangle `prim`'s material (dimensionless, in
    /// [0, 1]); read only when [`Self::lambert_only`].
    fn lambert_albedo(&self, prim: u32) -> f32;
}

/// One scattering of secondary light at a surface, as the cache accumulates it: a photon
/// that has already scattered at least once arrives at `position` and leaves along
/// `direction` carrying `energy`. [`RadianceCache::build`] makes these from its own photon
/// pass; [`RadianceCache::from_arrivals`] takes them from the caller.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CacheArrival {
    /// Triangle hit ([`CacheSurfaces`] index).
    pub prim: u32,
    /// Hit point on the triangle, m.
    pub position: Vec3,
    /// Unit geometric normal on the side the light arrived from (and leaves to): it picks the
    /// cell side.
    pub normal: Vec3,
    /// Unit world direction the light leaves along (an unbiased sample of the scattering, e.g.
    /// a BDF sample); arrivals leaving below `normal` are skipped.
    pub direction: Vec3,
    /// Luminance of the scattered power, W: arriving power × f·cos/pdf, with the pass's
    /// 1/N_F already included (the cache divides only by cell area and bin solid angle).
    pub energy: f32,
    /// Luminance of the BDF value f(incoming, `direction`), sr⁻¹ (b's integrand is f·L_d;
    /// unused by Lambert-only caches).
    pub f: f32,
}

/// Size and cost facts about a built cache, for the run report.
#[derive(Clone, Debug, PartialEq)]
pub struct CacheStats {
    /// Number of cells per side (total cells = 2 × this).
    pub cells: usize,
    /// Bins per cell side.
    pub bins: u32,
    /// Whether b is stored.
    pub stores_b: bool,
    /// Photon arrivals accumulated.
    pub arrivals: u64,
    /// Fraction of cell sides that received at least one arrival.
    pub filled_fraction: f64,
    /// Memory of the tables, bytes.
    pub bytes: u64,
}

/// The frozen cache.
#[derive(Clone, Debug)]
pub struct RadianceCache {
    /// First cell index of each triangle.
    first_cell: Vec<u32>,
    /// Subdivision n of each triangle (n² cells).
    subdivision: Vec<u16>,
    /// Triangle vertices and normals for barycentric lookup.
    tri: Vec<CellTriangle>,
    side_bins: usize,
    grid: u32,
    /// The block of `values` holding each (cell, side)'s bins (they start at bin
    /// block × `side_bins`), in the sparse layout; empty in the dense layout, where every
    /// (cell, side) has a block and it is the (cell, side) index itself.
    ///
    /// About half the cell sides never receive a photon (the outer faces of a closed box, for
    /// one); in the sparse layout they all share block 0, whose bins are zero, as an empty
    /// cell's bins are in the dense layout, so a lookup reads the same numbers either way and
    /// needs no branch. The sparse layout is used when it is smaller (it costs 4 bytes per
    /// cell side, so a cache with one L_d per side stays dense).
    side_block: Vec<u32>,
    /// Bin values, W·m⁻²·sr⁻¹ (L_d) and W·m⁻²·sr⁻² (b): `[L_d, b]` pairs per bin, interleaved
    /// so that a lookup touches one cache line, or L_d alone when b is not stored (`stride` 1);
    /// bins of block after block (see `side_block`).
    values: Vec<f32>,
    /// Floats per bin in `values`: 2 with b, 1 without.
    stride: usize,
    /// Photon arrivals per (cell, side).
    arrivals: Vec<u32>,
    stats: CacheStats,
}

/// A bin of a [`RadianceCache`], as [`RadianceCache::slot`] finds it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CacheSlot {
    index: usize,
    /// b/L_d of the bin's triangle where b is not stored (see [`CellTriangle::b_per_ld`]).
    b_per_ld: f32,
}

/// A triangle as the cell lookup needs it: vertices, normal, and the per-triangle parts of the
/// barycentric solve (edges, their Gram matrix and its determinant), computed once.
#[derive(Clone, Copy, Debug)]
struct CellTriangle {
    v: [Vec3; 3],
    ng: Vec3,
    e1: Vec3,
    e2: Vec3,
    d11: f32,
    d12: f32,
    d22: f32,
    det: f32,
    /// b / L_d = luminance(k_d)/π, sr⁻¹, for a Lambert triangle of a cache that does not store
    /// b (method.md §7: b = ∫f·L_d = (k_d/π)·L_d there); 0 where b is stored.
    b_per_ld: f32,
}

impl CellTriangle {
    fn new(v: [Vec3; 3], ng: Vec3, b_per_ld: f32) -> CellTriangle {
        let e1 = v[1] - v[0];
        let e2 = v[2] - v[0];
        let (d11, d12, d22) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
        CellTriangle {
            v,
            ng,
            e1,
            e2,
            d11,
            d12,
            d22,
            det: d11 * d22 - d12 * d12,
            b_per_ld,
        }
    }
}

/// One side of one cell, as [`RadianceCache::cells`] reports it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CellSummary {
    /// Triangle the cell lies on.
    pub prim: u32,
    /// Which side (0 = the winding's front, 1 = the back).
    pub side: u8,
    /// Cell area, m².
    pub area: f64,
    /// Photon arrivals accumulated into it.
    pub arrivals: u32,
    /// L_d averaged over its bins (luminance), W·m⁻²·sr⁻¹.
    pub mean_ld: f64,
}

/// Inverse of the equal-area concentric square → hemisphere map: a unit direction with z ≥ 0
/// to a point of [0, 1)².
fn hemisphere_to_square(d: Vec3) -> Vec2 {
    // The disk radius r with r² = 1 − z makes the map equal-area.
    let r = (1.0 - d.z.clamp(0.0, 1.0)).max(0.0).sqrt();
    let phi = d.y.atan2(d.x); // (−π, π]
    let (a, b);
    // Invert Shirley–Chiu by octant of the disk.
    let phi = if phi < -PI / 4.0 { phi + 2.0 * PI } else { phi };
    if phi < PI / 4.0 {
        a = r;
        b = phi * a / (PI / 4.0);
    } else if phi < 3.0 * PI / 4.0 {
        b = r;
        a = -(phi - PI / 2.0) * b / (PI / 4.0);
    } else if phi < 5.0 * PI / 4.0 {
        a = -r;
        b = (phi - PI) * a / (PI / 4.0);
    } else {
        b = -r;
        a = -(phi - 3.0 * PI / 2.0) * b / (PI / 4.0);
    }
    Vec2::new((a + 1.0) * 0.5, (b + 1.0) * 0.5).clamp(Vec2::ZERO, Vec2::splat(1.0 - 1e-7))
}

/// ∫ cos θ dω over each bin of a `grid` × `grid` split of the equal-area square: the bin's
/// projected solid angle, sr (they sum to π).
///
/// In the concentric map's coordinates (a, b) ∈ [−1, 1]² the disk radius is max(|a|, |b|) and
/// the equal-area hemisphere has cos θ = 1 − r², so the integral over b is done in closed form
/// and the one over a by a fine midpoint rule.
fn projected_solid_angles(grid: u32) -> Vec<f64> {
    const Q: u32 = 512;
    // ∫_{b0}^{b1} max(a², b²) db for a fixed a.
    let inner = |a: f64, b0: f64, b1: f64| -> f64 {
        let (lo, hi) = ((-a.abs()).max(b0), a.abs().min(b1));
        let flat = if hi > lo { a * a * (hi - lo) } else { 0.0 };
        let cube = |x: f64| x * x * x / 3.0;
        // The parts of [b0, b1] outside [−|a|, |a|], where max = b².
        let below = if b0 < -a.abs() {
            cube(b1.min(-a.abs())) - cube(b0)
        } else {
            0.0
        };
        let above = if b1 > a.abs() {
            cube(b1) - cube(b0.max(a.abs()))
        } else {
            0.0
        };
        flat + below + above
    };
    let g = grid as f64;
    let mut out = Vec::with_capacity((grid * grid) as usize);
    for by in 0..grid {
        for bx in 0..grid {
            let (a0, a1) = (2.0 * bx as f64 / g - 1.0, 2.0 * (bx + 1) as f64 / g - 1.0);
            let (b0, b1) = (2.0 * by as f64 / g - 1.0, 2.0 * (by + 1) as f64 / g - 1.0);
            let h = (a1 - a0) / Q as f64;
            let r2: f64 = (0..Q)
                .map(|i| inner(a0 + (i as f64 + 0.5) * h, b0, b1) * h)
                .sum();
            let area = (a1 - a0) * (b1 - b0);
            // The [−1, 1]² square (area 4) maps to 2π sr: dω = (π/2)·da·db.
            out.push(std::f64::consts::FRAC_PI_2 * (area - r2));
        }
    }
    out
}

impl RadianceCache {
    /// Traces the cache's photon pass on `scene` and accumulates L_d (and b unless the scene
    /// is Lambert-only) per cell and bin.
    pub fn build<S: PhotonScene + CacheSurfaces + ?Sized>(
        scene: &S,
        settings: &CacheSettings,
    ) -> RadianceCache {
        Self::build_until(scene, settings, &|| false)
            .expect("a build that is never stopped is complete")
    }

    /// [`Self::build`] that gives up when `stop()` returns true, asked before each chunk of
    /// the cache's photons ([`bdpm_photon::trace_photons_until`]): `None` then. A `stop` that
    /// never fires builds the same cache.
    pub fn build_until<S: PhotonScene + CacheSurfaces + ?Sized>(
        scene: &S,
        settings: &CacheSettings,
        stop: &(dyn Fn() -> bool + Sync),
    ) -> Option<RadianceCache> {
        Self::build_of_until(scene, settings, &|_| true, stop)
    }

    /// [`Self::build_until`] of the part of the secondary light whose arrivals `keep` accepts
    /// (asked only for arrivals the cache would record): e.g. only caustic light
    /// ([`bdpm_photon::PhotonArrival::caustic`]), the light that reaches a surface through
    /// mirrors and glass alone. L_d and b then hold that part's radiance and b.
    pub fn build_of_until<S: PhotonScene + CacheSurfaces + ?Sized>(
        scene: &S,
        settings: &CacheSettings,
        keep: &(dyn Fn(&bdpm_photon::PhotonArrival) -> bool + Sync),
        stop: &(dyn Fn() -> bool + Sync),
    ) -> Option<RadianceCache> {
        let mut cache = RadianceCache::empty(scene, settings.bins, settings.cell_size);
        let options = TraceOptions {
            photons: settings.photons.max(1),
            seed: settings.seed,
            domain: Domain::CachePhoton,
            pass: 0,
            light_visibility: false,
            max_depth: bdpm_photon::MAX_DEPTH,
        };
        // Records are made in parallel and come back in photon order, so the sequential
        // accumulation in `fill` is bit-identical whatever the thread count.
        let this = &cache;
        let records: Vec<(u32, f32, f32)> = trace_photons_until(
            scene,
            &options,
            |arrival, out| {
                // Only light that has scattered at least once is secondary (L_d, method.md §5).
                // A delta vertex (mirror, glass) has no radiance of its own to cache.
                if arrival.vertex.depth == 0 || arrival.delta || !keep(arrival) {
                    return;
                }
                let Some(sc) = arrival.scatter else { return };
                let vx = &arrival.vertex;
                let record = this.record(&CacheArrival {
                    prim: vx.at.prim,
                    position: vx.at.p,
                    normal: vx.at.n,
                    direction: sc.direction,
                    energy: luminance(arrival.power * sc.weight),
                    f: luminance(sc.f),
                });
                out.extend(record);
            },
            stop,
        )?;
        if stop() {
            return None;
        }
        cache.fill(&records);
        Some(cache)
    }

    /// A cache over `surfaces` filled from arrivals the caller traced itself (e.g. with its
    /// own photon tracer), accumulated in the order given. `bins` and `cell_size` (m) are as in
    /// [`CacheSettings`]. Each arrival is one scattering of secondary light (light that has
    /// already scattered at least once, method.md §5); arrivals that leave below their normal
    /// or name an unknown or degenerate triangle are skipped.
    pub fn from_arrivals<S: CacheSurfaces + ?Sized>(
        surfaces: &S,
        bins: u32,
        cell_size: f32,
        arrivals: impl IntoIterator<Item = CacheArrival>,
    ) -> RadianceCache {
        let mut cache = RadianceCache::empty(surfaces, bins, cell_size);
        let records: Vec<(u32, f32, f32)> = arrivals
            .into_iter()
            .filter_map(|a| cache.record(&a))
            .collect();
        cache.fill(&records);
        cache
    }

    /// The cells of `surfaces`, without bins yet (`fill` lays them out).
    fn empty<S: CacheSurfaces + ?Sized>(surfaces: &S, bins: u32, cell_size: f32) -> RadianceCache {
        let lambert = surfaces.lambert_only();
        let grid = if lambert {
            1
        } else {
            (bins.max(1) as f32).sqrt().round().max(1.0) as u32
        };
        let side_bins = (grid * grid) as usize;
        let n_tris = surfaces.triangle_count();
        let mut first_cell = Vec::with_capacity(n_tris);
        let mut subdivision = Vec::with_capacity(n_tris);
        let mut tri = Vec::with_capacity(n_tris);
        let mut cells = 0u32;
        for prim in 0..n_tris as u32 {
            let v = surfaces.triangle(prim);
            let longest = (v[1] - v[0])
                .length()
                .max((v[2] - v[1]).length())
                .max((v[0] - v[2]).length());
            let n = if surfaces.area(prim) > 0.0 {
                ((longest / cell_size.max(1e-9)).ceil() as u32).clamp(1, 256)
            } else {
                1
            };
            first_cell.push(cells);
            subdivision.push(n as u16);
            // The one place the Lambert b is derived: L_d's cells hold the rest.
            let b_per_ld = if lambert {
                surfaces.lambert_albedo(prim) / PI
            } else {
                0.0
            };
            tri.push(CellTriangle::new(v, surfaces.normal(prim), b_per_ld));
            cells += n * n;
        }
        RadianceCache {
            first_cell,
            subdivision,
            tri,
            side_bins,
            grid,
            side_block: Vec::new(),
            // Laid out by `fill`, which knows which cell sides hold values.
            values: Vec::new(),
            stride: if lambert { 1 } else { 2 },
            arrivals: vec![0; cells as usize * 2],
            stats: CacheStats {
                cells: cells as usize,
                bins: side_bins as u32,
                stores_b: !lambert,
                arrivals: 0,
                filled_fraction: 0.0,
                bytes: 0,
            },
        }
    }

    /// The (slot, L_d energy, b energy) record of one arrival, or None if it adds nothing; the
    /// slot is (cell, side) × bins per side + bin, its index in the dense layout.
    fn record(&self, a: &CacheArrival) -> Option<(u32, f32, f32)> {
        if a.direction.dot(a.normal) <= 0.0 {
            return None;
        }
        let cell_side = self.cell_side(a.prim, a.position, a.normal)?;
        let local = Frame::from_normal(a.normal).to_local(a.direction);
        let slot = (cell_side * self.side_bins + self.bin(local)) as u32;
        Some((slot, a.energy, a.energy * a.f))
    }

    /// Accumulates `records` (slots of the dense layout, see [`Self::record`]) into the bins,
    /// choosing the dense or the sparse layout (see `side_block`).
    fn fill(&mut self, records: &[(u32, f32, f32)]) {
        let sides = self.arrivals.len();
        for &(slot, _, _) in records {
            self.arrivals[slot as usize / self.side_bins] += 1;
        }
        self.stats.arrivals = records.len() as u64;
        // Cell area per (cell, side); 0 for a degenerate triangle, whose bins stay zero.
        let mut side_area = vec![0f64; sides];
        for (prim, &n) in self.subdivision.iter().enumerate() {
            let cell_area = self.triangle_area(prim) / (n as f64 * n as f64);
            let first = self.first_cell[prim] as usize * 2;
            side_area[first..first + 2 * n as usize * n as usize].fill(cell_area);
        }
        // Only a (cell, side) with an arrival and an area can hold a value other than 0.
        let holds = |cs: usize| self.arrivals[cs] > 0 && side_area[cs] > 0.0;
        let filled = (0..sides).filter(|&cs| holds(cs)).count();
        let block_floats = self.side_bins * self.stride;
        let dense_bytes = sides * block_floats * 4;
        let sparse_bytes = sides * 4 + (filled + 1) * block_floats * 4;
        let side_block: Vec<u32> = if sparse_bytes < dense_bytes {
            let mut next = 0u32;
            (0..sides)
                .map(|cs| {
                    if holds(cs) {
                        next += 1;
                        next
                    } else {
                        0
                    }
                })
                .collect()
        } else {
            Vec::new()
        };
        let blocks = if side_block.is_empty() {
            sides
        } else {
            filled + 1
        };
        let block_of = |cs: usize| {
            if side_block.is_empty() {
                cs
            } else {
                side_block[cs] as usize
            }
        };
        // Sums in f64, per bin in record order (the same order in either layout, so the same
        // sums); block 0 of the sparse layout takes none.
        let bins = blocks * self.side_bins;
        let mut ld = vec![0f64; bins];
        let mut b = vec![0f64; if self.stride == 2 { bins } else { 0 }];
        for &(slot, l, bb) in records {
            let cs = slot as usize / self.side_bins;
            if !holds(cs) {
                continue;
            }
            let k = block_of(cs) * self.side_bins + slot as usize % self.side_bins;
            ld[k] += l as f64;
            if !b.is_empty() {
                b[k] += bb as f64;
            }
        }
        // Divide by cell area s and the bin's projected solid angle ∫_bin cos dω (see the crate
        // doc for why not by ω with a 1/cos per photon).
        let projected = projected_solid_angles(self.grid);
        self.values = vec![0.0; bins * self.stride];
        for cs in (0..sides).filter(|&cs| holds(cs)) {
            let cell_area = side_area[cs];
            let base = block_of(cs) * self.side_bins;
            for (k, omega_cos) in (base..base + self.side_bins).zip(&projected) {
                self.values[k * self.stride] = (ld[k] / (cell_area * omega_cos)) as f32;
                if !b.is_empty() {
                    self.values[k * self.stride + 1] = (b[k] / (cell_area * omega_cos)) as f32;
                }
            }
        }
        self.side_block = side_block;
        self.stats.filled_fraction = self.arrivals.iter().filter(|a| **a > 0).count() as f64
            / self.arrivals.len().max(1) as f64;
        self.stats.bytes = (self.values.len() * 4
            + self.side_block.len() * 4
            + self.arrivals.len() * 4
            + self.first_cell.len() * 4
            + self.subdivision.len() * 2
            + self.tri.len() * std::mem::size_of::<CellTriangle>())
            as u64;
    }

    /// The first bin of (cell, side) `cs` in `values` (in units of bins, not floats).
    #[inline]
    fn block_start(&self, cs: usize) -> usize {
        let block = if self.side_block.is_empty() {
            cs
        } else {
            self.side_block[cs] as usize
        };
        block * self.side_bins
    }

    fn triangle_area(&self, prim: usize) -> f64 {
        let v = self.tri[prim].v;
        0.5 * (v[1] - v[0])
            .as_dvec3()
            .cross((v[2] - v[0]).as_dvec3())
            .length()
    }

    /// Index of (cell, side) for a point `p` on triangle `prim`, seen from the side of `n`.
    fn cell_side(&self, prim: u32, p: Vec3, n: Vec3) -> Option<usize> {
        let t = self.tri.get(prim as usize)?;
        if t.det <= 0.0 {
            return None;
        }
        // Barycentrics by least squares in the triangle's plane.
        let d = p - t.v[0];
        let (p1, p2) = (d.dot(t.e1), d.dot(t.e2));
        let b1 = ((t.d22 * p1 - t.d12 * p2) / t.det).clamp(0.0, 1.0);
        let b2 = ((t.d11 * p2 - t.d12 * p1) / t.det).clamp(0.0, 1.0 - b1);
        let sub = self.subdivision[prim as usize] as u32;
        let (fu, fv) = (b1 * sub as f32, b2 * sub as f32);
        let i = (fu as u32).min(sub - 1);
        let j = (fv as u32).min(sub - 1 - i.min(sub - 1));
        // Row j of the subdivided triangle holds 2(n − j) − 1 cells: "up" then "down" ones.
        let upper = (fu - i as f32) + (fv - j as f32) > 1.0 && i + j + 1 < sub;
        let row_start = j * (2 * sub - j);
        let local = row_start + 2 * i + upper as u32;
        let cell = self.first_cell[prim as usize] + local.min(sub * sub - 1);
        let side = (t.ng.dot(n) < 0.0) as usize;
        Some(cell as usize * 2 + side)
    }

    fn bin(&self, local_dir: Vec3) -> usize {
        if self.grid == 1 {
            return 0;
        }
        let s = hemisphere_to_square(local_dir);
        let g = self.grid as f32;
        let (x, y) = ((s.x * g) as u32, (s.y * g) as u32);
        (y.min(self.grid - 1) * self.grid + x.min(self.grid - 1)) as usize
    }

    /// L_d (W·m⁻²·sr⁻¹) and b (W·m⁻²·sr⁻²), luminances, leaving triangle `prim` at point `p`
    /// towards the unit world direction `wo`, on the side of `wo`. Where b is not stored
    /// (Lambert-only scenes) it is (k_d/π)·L_d, exactly.
    pub fn lookup(&self, prim: u32, p: Vec3, wo: Vec3) -> (f32, f32) {
        self.slot(prim, p, wo).map_or((0.0, 0.0), |s| self.at(s))
    }

    /// Where [`Self::lookup`] of the same arguments reads, or None where it returns zeros (an
    /// unknown or degenerate triangle). Splitting the lookup lets a caller [`Self::prefetch`]
    /// the bin and do other work before reading it with [`Self::at`].
    pub fn slot(&self, prim: u32, p: Vec3, wo: Vec3) -> Option<CacheSlot> {
        let t = self.tri.get(prim as usize)?;
        let ng = t.ng;
        let n = if ng.dot(wo) < 0.0 { -ng } else { ng };
        let cell_side = self.cell_side(prim, p, n)?;
        let start = self.block_start(cell_side);
        // One bin (Lambert-only scenes) needs no direction, nor does the shared zero block of
        // the sparse layout (start 0 there), whose bins are all 0.
        let bin = if self.grid == 1 || (start == 0 && !self.side_block.is_empty()) {
            0
        } else {
            self.bin(Frame::from_normal(n).to_local(wo))
        };
        Some(CacheSlot {
            index: start + bin,
            b_per_ld: t.b_per_ld,
        })
    }

    /// Whether [`Self::slot`] of triangle `prim` reads the same side of its cells for the
    /// directions `a` and `b` (true for an unknown triangle, where it reads nothing). With
    /// [`Self::is_isotropic`], the side is all a direction changes about the slot.
    pub fn same_side(&self, prim: u32, a: Vec3, b: Vec3) -> bool {
        self.tri
            .get(prim as usize)
            .is_none_or(|t| (t.ng.dot(a) < 0.0) == (t.ng.dot(b) < 0.0))
    }

    /// True if every cell side has one bin (a Lambert-only scene): a lookup depends on the
    /// direction only through the side it faces.
    pub fn is_isotropic(&self) -> bool {
        self.grid == 1
    }

    /// Hints the CPU to fetch the bin at `slot` (no effect on results).
    #[inline]
    pub fn prefetch(&self, slot: CacheSlot) {
        if let Some(v) = self.values.get(slot.index * self.stride) {
            bdpm_core::prefetch(v);
        }
    }

    /// L_d and b at `slot` (see [`Self::lookup`]).
    pub fn at(&self, slot: CacheSlot) -> (f32, f32) {
        let k = slot.index * self.stride;
        if self.stride == 2 {
            (self.values[k], self.values[k + 1])
        } else {
            let ld = self.values[k];
            (ld, slot.b_per_ld * ld)
        }
    }

    /// Every (cell, side) with its area, arrivals and bin-averaged L_d (for checks and tools).
    pub fn cells(&self) -> Vec<CellSummary> {
        let mut out = Vec::with_capacity(self.arrivals.len());
        for (prim, &n) in self.subdivision.iter().enumerate() {
            let area = self.triangle_area(prim) / (n as f64 * n as f64);
            let first = self.first_cell[prim] as usize;
            for cell in first..first + n as usize * n as usize {
                for side in 0..2 {
                    let cs = cell * 2 + side;
                    let start = self.block_start(cs);
                    let bins =
                        (start..start + self.side_bins).map(|k| self.values[k * self.stride]);
                    out.push(CellSummary {
                        prim: prim as u32,
                        side: side as u8,
                        area,
                        arrivals: self.arrivals[cs],
                        mean_ld: bins.map(f64::from).sum::<f64>() / self.side_bins as f64,
                    });
                }
            }
        }
        out
    }

    /// Facts for the run report.
    pub fn stats(&self) -> &CacheStats {
        &self.stats
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use bdpm_core::Rng;
    use bdpm_core::sampling::uniform_sphere;

    /// A unit square in z = 0 of two triangles, Lambert-only or not.
    struct Square {
        lambert: bool,
    }

    impl CacheSurfaces for Square {
        fn triangle_count(&self) -> usize {
            2
        }
        fn triangle(&self, prim: u32) -> [Vec3; 3] {
            let (a, b, c, d) = (Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y);
            if prim == 0 { [a, b, c] } else { [a, c, d] }
        }
        fn normal(&self, _: u32) -> Vec3 {
            Vec3::Z
        }
        fn area(&self, _: u32) -> f32 {
            0.5
        }
        fn lambert_only(&self) -> bool {
            self.lambert
        }
        fn lambert_albedo(&self, _: u32) -> f32 {
            0.7
        }
    }

    /// A random point of the square and the triangle it lies on.
    fn square_point(rng: &mut Rng, x_max: f32) -> (u32, Vec3) {
        let [u, v] = rng.uniform2();
        let p = Vec3::new(u * x_max, v, 0.0);
        ((p.y > p.x) as u32, p)
    }

    /// The sparse layout reads, bit for bit, what the dense layout (every (cell, side) its own
    /// bins, the layout before it) reads: the sums of the arrivals of each bin over cell area
    /// and projected solid angle in the filled cells, and zeros in the empty ones.
    #[test]
    fn sparse_layout_reads_what_the_dense_layout_reads() {
        for lambert in [false, true] {
            let square = Square { lambert };
            let mut rng = Rng::new(7, Domain::Other, [0; 3]);
            // Arrivals on the front side of the left 40 % only: most cell sides stay empty.
            let arrivals: Vec<CacheArrival> = (0..20_000)
                .map(|_| {
                    let (prim, position) = square_point(&mut rng, 0.4);
                    let mut direction = uniform_sphere(rng.uniform2());
                    direction.z = direction.z.abs();
                    let [e, f] = rng.uniform2();
                    CacheArrival {
                        prim,
                        position,
                        normal: Vec3::Z,
                        direction,
                        energy: e * 1e-3,
                        f: 3.0 * f,
                    }
                })
                .collect();
            let cache = RadianceCache::from_arrivals(&square, 16, 0.1, arrivals.iter().copied());
            // Sparse exactly where it is smaller: with bins and b, not with one L_d per side.
            assert_eq!(cache.side_block.is_empty(), lambert);
            assert!(cache.stats().filled_fraction > 0.1 && cache.stats().filled_fraction < 0.4);
            // The dense reference, accumulated as the cache did before it had layouts.
            let sides = cache.arrivals.len();
            let mut ld = vec![0f64; sides * cache.side_bins];
            let mut b = ld.clone();
            for a in &arrivals {
                let (slot, l, bb) = cache.record(a).unwrap();
                ld[slot as usize] += l as f64;
                b[slot as usize] += bb as f64;
            }
            let projected = projected_solid_angles(cache.grid);
            let cell_area = 0.5 / (cache.subdivision[0] as f64).powi(2);
            let reference = |k: usize| {
                let d = cell_area * projected[k % cache.side_bins];
                let ld = (ld[k] / d) as f32;
                if lambert {
                    (ld, 0.7 / PI * ld)
                } else {
                    (ld, (b[k] / d) as f32)
                }
            };
            let (mut empty, mut filled) = (0, 0);
            for _ in 0..20_000 {
                let (prim, p) = square_point(&mut rng, 1.0);
                let wo = uniform_sphere(rng.uniform2());
                let n = if wo.z < 0.0 { -Vec3::Z } else { Vec3::Z };
                let cs = cache.cell_side(prim, p, n).unwrap();
                let k = cs * cache.side_bins + cache.bin(Frame::from_normal(n).to_local(wo));
                let want = reference(k);
                let got = cache.lookup(prim, p, wo);
                assert_eq!(
                    (got.0.to_bits(), got.1.to_bits()),
                    (want.0.to_bits(), want.1.to_bits()),
                    "{prim} {p} {wo}"
                );
                if cache.arrivals[cs] == 0 {
                    assert_eq!(got, (0.0, 0.0));
                    empty += 1;
                } else {
                    filled += (got.0 > 0.0) as u32;
                }
            }
            assert!(empty > 5_000 && filled > 2_000, "{empty} {filled}");
            // The per-cell summaries agree too.
            for (cs, c) in cache.cells().iter().enumerate() {
                let bins = cs * cache.side_bins..(cs + 1) * cache.side_bins;
                let mean =
                    bins.map(|k| reference(k).0 as f64).sum::<f64>() / cache.side_bins as f64;
                assert_eq!(c.mean_ld.to_bits(), mean.to_bits());
            }
        }
    }

    #[test]
    fn projected_solid_angles_sum_to_pi() {
        for grid in [1, 3, 10] {
            let p = projected_solid_angles(grid);
            let sum: f64 = p.iter().sum();
            assert!(
                (sum - std::f64::consts::PI).abs() < 1e-4,
                "grid {grid}: {sum}"
            );
        }
        assert!((projected_solid_angles(1)[0] - std::f64::consts::PI).abs() < 1e-4);
    }

    #[test]
    fn square_map_is_equal_area_and_in_range() {
        // Uniform directions on the hemisphere must fill a 4×4 grid of the square evenly.
        let mut rng = Rng::new(1, Domain::Other, [0; 3]);
        let mut counts = [0u32; 16];
        let n = 160_000;
        for _ in 0..n {
            let mut d = uniform_sphere(rng.uniform2());
            d.z = d.z.abs();
            let s = hemisphere_to_square(d);
            assert!(
                (0.0..1.0).contains(&s.x) && (0.0..1.0).contains(&s.y),
                "{s}"
            );
            counts[(s.y * 4.0) as usize * 4 + (s.x * 4.0) as usize] += 1;
        }
        // Each cell expects 10000 with binomial SE ≈ 97; allow 5 SE.
        for c in counts {
            assert!((c as f64 - 10_000.0).abs() < 5.0 * 97.0, "{counts:?}");
        }
    }

    #[test]
    fn square_map_inverts_the_concentric_hemisphere_warp() {
        let mut rng = Rng::new(2, Domain::Other, [0; 3]);
        for _ in 0..10_000 {
            let u = rng.uniform2();
            let d = bdpm_core::sampling::concentric_disk(u);
            let z = (1.0 - d.length_squared()).max(0.0);
            // Equal-area concentric hemisphere: disk point (r, φ) ↦ z = 1 − r².
            let r = d.length();
            let dir = if r > 0.0 {
                let s = (1.0 - z * z).max(0.0).sqrt();
                Vec3::new(d.x / r * s, d.y / r * s, z)
            } else {
                Vec3::Z
            };
            let back = hemisphere_to_square(dir);
            assert!(
                (back - Vec2::from(u)).abs().max_element() < 2e-3,
                "{u:?} -> {back}"
            );
        }
    }
}

// The README (the crate's page on crates.io) as a hidden item, so that `cargo test --doc`
// compiles and runs its example; the crate documentation above stays as it is.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;
