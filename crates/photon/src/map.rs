//! The photon map: stored photons, the light-path vertices they refer to, and the grid.

use glam::Vec3;
use rayon::prelude::*;

use crate::scene::PhotonScene;
use crate::trace::{PathVertex, PhotonArrival, TraceOptions, never, trace_chunks};
use bdpm_grid::{GridQuery, HashGrid};

/// A stored photon: an arrival at a surface after ≥ 1 scattering (method.md §1). The first
/// arrival from a light is direct light, which the integrators compute exactly, so it is not
/// stored. Its position is kept apart, in the map's [`PhotonMap::positions`] (the range test
/// reads only those), at the same index.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Photon {
    /// Unit direction from the photon's position back towards where the light came from (the previous
    /// vertex): the arrival direction of the ray that stored it, as its previous vertex's
    /// successor would record it. Stored rather than recomputed from the positions so that a
    /// merge at the camera's x₁ and a merge at x₀ through this vertex read the same number
    /// (their weights must agree bit for bit, method.md §2).
    pub incoming: Vec3,
    /// Power E_p, W per channel; already includes Φ/N_F.
    pub power: Vec3,
    /// Index into [`PhotonMap::vertices()`] of the previous vertex y_p (where it was scattered
    /// from); this photon's depth is that vertex's depth + 1, and its incoming direction points
    /// from its position to that vertex. No two photons share a previous vertex (a path goes on
    /// from a vertex once), so `prev` also identifies the photon within its pass.
    pub prev: u32,
}

// Photons are the bulk of a pass's memory: keep them small.
const _: () = assert!(size_of::<Photon>() <= 28);

/// The concatenation of `parts`, each element passed through `adjust(part index, element)`,
/// copied in parallel: a pass's photon map is a hundred megabytes, and copying (and
/// page-faulting) it on one thread was a third of the photon stage.
fn concat_parallel<T: Copy + Send + Sync>(
    parts: &[&[T]],
    adjust: impl Fn(usize, T) -> T + Sync,
) -> Vec<T> {
    let n: usize = parts.iter().map(|p| p.len()).sum();
    let mut out = Vec::with_capacity(n);
    let mut rest = &mut out.spare_capacity_mut()[..n];
    let mut slices = Vec::with_capacity(parts.len());
    for p in parts {
        let (head, tail) = rest.split_at_mut(p.len());
        slices.push(head);
        rest = tail;
    }
    slices
        .into_par_iter()
        .zip(parts.par_iter())
        .enumerate()
        .for_each(|(i, (dst, src))| {
            for (d, s) in dst.iter_mut().zip(src.iter()) {
                d.write(adjust(i, *s));
            }
        });
    // SAFETY: the slices partition the first n spare elements and the loop above wrote every
    // element of every slice (each has the length of its part), so all n are initialised.
    unsafe { out.set_len(n) };
    out
}

/// A range query of a [`PhotonMap`] in flight: see [`PhotonMap::start_query`]. The default
/// value is an empty query to be filled by [`PhotonMap::restart_query`].
#[derive(Clone, Copy, Debug, Default)]
pub struct PhotonQuery {
    x: Vec3,
    grid: GridQuery,
    /// Indices (grid order) of the photons found, in the order they are reported, once the
    /// query has been scanned: `found[..n_found]`.
    found: [u32; FOUND_CAPACITY],
    n_found: u8,
    scan: Scan,
    /// Squared gather radius of this query, m².
    r2: f32,
}

/// Photons a query remembers after its scan; more are found again when it is finished.
const FOUND_CAPACITY: usize = 8;

/// How far a [`PhotonQuery`] got past its grid stages.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
enum Scan {
    /// Not scanned yet.
    #[default]
    No,
    /// Scanned; every photon found is in `found` (and was asked for).
    Listed,
    /// Scanned, and their previous vertices were asked for too.
    Fetched,
    /// Scanned, but more photons were found than `found` holds.
    Overflow,
}

/// The photons of one pass in a hashed uniform grid for fixed-radius gathers.
///
/// [`Self::photons`] are kept in grid (bucket) order; [`Self::vertices`] in path order (each
/// path's kept vertices consecutive, paths in photon-index order), so `Photon::prev` stays
/// valid. Every field is a pure function of the scene, [`TraceOptions`] and the radius.
#[derive(Clone, Debug)]
pub struct PhotonMap {
    /// Stored photons (depth ≥ 1 arrivals), sorted by grid bucket. Private with `positions`
    /// and `grid`: they are derived together, and editing one alone would make queries wrong
    /// without any error.
    photons: Vec<Photon>,
    /// The position of `photons[i]` for every i, packed densely: the range test of a gather reads
    /// only these 12 bytes per candidate, so the candidates of a query share fewer cache lines
    /// and the array stays in the last-level cache for a million photons.
    positions: Vec<Vec3>,
    /// The light-path vertices the paths went on from (depth 0 included), in path order.
    vertices: Vec<PathVertex>,
    grid: HashGrid,
    radius: f32,
    emitted: u64,
}

impl PhotonMap {
    /// Traces the pass `options` in parallel (see [`crate::trace_photons`] for the stream and
    /// determinism guarantees) and builds the grid for merge radius `radius` (m).
    ///
    /// # Panics
    /// If `radius` is not positive and finite, or the pass stores ≥ 2³² − 1 photons or vertices.
    pub fn trace<S: PhotonScene + ?Sized>(
        scene: &S,
        options: &TraceOptions,
        radius: f32,
    ) -> PhotonMap {
        Self::trace_visiting(scene, options, radius, |_| (), |_, _, _| {}).0
    }

    /// [`Self::trace`] that also shows every arrival to `visit`, with the light-path vertices
    /// the arrival's own chunk has kept before it (in path order, so a stored photon's
    /// previous vertex y_p is the slice's last element and y_p's predecessors, while their
    /// depths count down, are the elements before it). `new(chunk)` makes each chunk's
    /// accumulator; they come back in chunk order, so anything `visit` records in them is, in
    /// that order, a pure function of (scene, options), whatever the thread count.
    ///
    /// # Panics
    /// As [`Self::trace`].
    pub fn trace_visiting<A: Send, S: PhotonScene + ?Sized>(
        scene: &S,
        options: &TraceOptions,
        radius: f32,
        new: impl Fn(u64) -> A + Sync,
        visit: impl Fn(&mut A, &PhotonArrival, &[PathVertex]) + Sync,
    ) -> (PhotonMap, Vec<A>) {
        Self::trace_visiting_until(scene, options, radius, new, visit, &never)
            .expect("a trace that is never stopped is complete")
    }

    /// [`Self::trace_visiting`] that gives up when `stop()` returns true, asked before each
    /// chunk of photons ([`crate::trace_photons_until`]): `None` then.
    ///
    /// # Panics
    /// As [`Self::trace`].
    pub fn trace_visiting_until<A: Send, S: PhotonScene + ?Sized>(
        scene: &S,
        options: &TraceOptions,
        radius: f32,
        new: impl Fn(u64) -> A + Sync,
        visit: impl Fn(&mut A, &PhotonArrival, &[PathVertex]) + Sync,
        stop: &(dyn Fn() -> bool + Sync),
    ) -> Option<(PhotonMap, Vec<A>)> {
        // Only the vertices a path goes on from are kept: they are the previous vertices y_p
        // the weights read. A path's last vertex (where it was absorbed, and every depth-0
        // vertex of a path that ended there) is nobody's y_p; keeping those too held 2.6 times
        // as many vertices on the Lambert Cornell box (docs/performance.md, memory).
        let chunks = trace_chunks(
            scene,
            options,
            |c| {
                let vertices = Vec::<PathVertex>::new();
                (vertices, Vec::<Vec3>::new(), Vec::<Photon>::new(), new(c))
            },
            |(vertices, positions, photons, acc), a| {
                visit(acc, a, vertices);
                if a.vertex.depth >= 1 && !a.delta {
                    // The path went on from its previous arrival, which was therefore the last
                    // vertex pushed.
                    positions.push(a.vertex.at.p);
                    photons.push(Photon {
                        incoming: a.vertex.incoming,
                        power: a.power,
                        prev: vertices.len() as u32 - 1,
                    });
                }
                if a.continued {
                    vertices.push(a.vertex);
                }
            },
            stop,
        )?;
        let n_vertices: usize = chunks.iter().map(|c| c.0.len()).sum();
        let n_photons: usize = chunks.iter().map(|c| c.2.len()).sum();
        assert!(
            n_vertices < u32::MAX as usize,
            "too many path vertices for u32 indices"
        );
        debug_assert!(n_photons <= n_vertices);
        // Each chunk's vertex indices start at the vertices of the chunks before it.
        let offsets: Vec<u32> = chunks
            .iter()
            .scan(0u32, |acc, c| {
                let first = *acc;
                *acc += c.0.len() as u32;
                Some(first)
            })
            .collect();
        let vertex_parts: Vec<&[PathVertex]> = chunks.iter().map(|c| c.0.as_slice()).collect();
        let position_parts: Vec<&[Vec3]> = chunks.iter().map(|c| c.1.as_slice()).collect();
        let photon_parts: Vec<&[Photon]> = chunks.iter().map(|c| c.2.as_slice()).collect();
        let vertices = concat_parallel(&vertex_parts, |_, v| v);
        let positions = concat_parallel(&position_parts, |_, p| p);
        let photons = concat_parallel(&photon_parts, |chunk, p| Photon {
            prev: p.prev + offsets[chunk],
            ..p
        });
        // The parts are freed before the grid's sort arrays are allocated: holding both was
        // the photon stage's memory peak.
        let visited = chunks.into_iter().map(|c| c.3).collect();
        let map = PhotonMap::from_parts(positions, photons, vertices, options.photons, radius);
        Some((map, visited))
    }

    /// Builds a map from photons, their positions (m, `positions[i]` is `photons[i]`'s) and
    /// vertices made elsewhere (e.g. tests, or a rebuild with a new radius): reorders both
    /// into grid order for merge radius `radius` (m). `emitted` is N_F. `prev`/`vertex`
    /// indices are not checked here; [`PhotonMap::vertex`] panics on a bad one.
    ///
    /// # Panics
    /// If `radius` is not positive and finite, or `positions` and `photons` differ in length.
    pub fn from_parts(
        positions: Vec<Vec3>,
        photons: Vec<Photon>,
        vertices: Vec<PathVertex>,
        emitted: u64,
        radius: f32,
    ) -> PhotonMap {
        assert!(
            radius > 0.0 && radius.is_finite(),
            "merge radius must be positive and finite, got {radius}"
        );
        assert_eq!(positions.len(), photons.len(), "one position per photon");
        let (grid, order) = HashGrid::build(&positions, radius);
        let photons = order.par_iter().map(|&i| photons[i as usize]).collect();
        let positions = order.par_iter().map(|&i| positions[i as usize]).collect();
        PhotonMap {
            photons,
            positions,
            vertices,
            grid,
            radius,
            emitted,
        }
    }

    /// The same photons in a grid for another radius (m), e.g. for a shrinking radius.
    pub fn with_radius(self, radius: f32) -> PhotonMap {
        PhotonMap::from_parts(
            self.positions,
            self.photons,
            self.vertices,
            self.emitted,
            radius,
        )
    }

    /// The merge radius r the grid was built for, m.
    pub fn radius(&self) -> f32 {
        self.radius
    }

    /// Calls `f` for every photon whose position p has |x − p| ≤ radius (compared as squared
    /// distances in f32). The order is deterministic (grid order); nothing is allocated. At
    /// most 8 grid cells are visited, so the cost is the photons in a (4r)³ box.
    #[inline]
    pub fn for_each_near(&self, x: Vec3, f: impl FnMut(&Photon)) {
        self.finish_query(&self.start_query(x), f);
    }

    /// Starts the query of [`Self::for_each_near`] at `x` without waiting for memory: it works
    /// out which grid cells to read and asks the CPU to fetch the first of them. Do other work
    /// (e.g. other queries' [`Self::advance_query`]) before advancing or finishing it, and the
    /// fetches overlap that work. The photons reported do not depend on how far a query was
    /// advanced.
    #[inline]
    pub fn start_query(&self, x: Vec3) -> PhotonQuery {
        let mut q = PhotonQuery::default();
        self.restart_query(&mut q, x);
        q
    }

    /// [`Self::start_query`] into an existing query, overwriting it in place.
    #[inline]
    pub fn restart_query(&self, q: &mut PhotonQuery, x: Vec3) {
        self.restart_query_within(q, x, self.radius);
    }

    /// [`Self::restart_query`] with a gather radius of its own, at most the grid's: build the
    /// map for the largest radius a query will use (a larger one is cut to the grid's, which
    /// would bias a kernel normalised for it).
    #[inline]
    pub fn restart_query_within(&self, q: &mut PhotonQuery, x: Vec3, radius: f32) {
        debug_assert!(
            radius <= self.radius,
            "gather radius {radius} beyond the grid's"
        );
        let radius = radius.min(self.radius);
        q.x = x;
        q.n_found = 0;
        q.scan = Scan::No;
        q.r2 = radius * radius;
        self.grid.start(&mut q.grid, x, radius);
    }

    /// Moves `q` one stage on, each time asking the CPU to fetch what the next stage reads.
    /// Three stages: the buckets' table entries (filter and bounds; then the candidates'
    /// positions are fetched), the range test (then the photons found), the photons (then
    /// their previous vertices, which the weights read). Further calls do nothing.
    #[inline]
    pub fn advance_query(&self, q: &mut PhotonQuery) {
        if !q.grid.ready() {
            self.grid.advance(&mut q.grid, |i| {
                bdpm_core::prefetch(&self.positions[i]);
            });
            if q.grid.empty() {
                q.n_found = 0;
                q.scan = Scan::Fetched;
            }
            return;
        }
        match q.scan {
            Scan::No => {
                let (mut n, mut overflow) = (0, false);
                let mut found = [0u32; FOUND_CAPACITY];
                self.scan(q, |i| {
                    if n < FOUND_CAPACITY {
                        found[n] = i as u32;
                        n += 1;
                    } else {
                        overflow = true;
                    }
                });
                q.found = found;
                q.n_found = n as u8;
                for &i in &q.found[..n] {
                    bdpm_core::prefetch(&self.photons[i as usize]);
                }
                q.scan = if overflow {
                    Scan::Overflow
                } else {
                    Scan::Listed
                };
            }
            Scan::Listed => {
                for &i in &q.found[..q.n_found as usize] {
                    let v = &self.vertices[self.photons[i as usize].prev as usize];
                    // A vertex may straddle two cache lines.
                    bdpm_core::prefetch(v);
                    bdpm_core::prefetch(&v.survival);
                }
                q.scan = Scan::Fetched;
            }
            Scan::Fetched | Scan::Overflow => {}
        }
    }

    /// Calls `found(i)` with the index (grid order) of every photon within the radius of the
    /// query's point, in reporting order.
    #[inline]
    fn scan(&self, q: &PhotonQuery, mut found: impl FnMut(usize)) {
        let r2 = q.r2;
        let x = q.x;
        self.grid.visit(&q.grid, |range| {
            let start = range.start;
            for (k, position) in self.positions[range].iter().enumerate() {
                if (*position - x).length_squared() <= r2 {
                    found(start + k);
                }
            }
        });
    }

    /// Finishes `q`: calls `f` for every photon within the radius of its point, exactly as
    /// [`Self::for_each_near`] would.
    #[inline]
    pub fn finish_query(&self, q: &PhotonQuery, mut f: impl FnMut(&Photon)) {
        self.finish_query_indexed(q, |_, ph| f(ph));
    }

    /// [`Self::finish_query`] that also passes each photon's index into
    /// [`PhotonMap::photons()`], so that a caller can keep per-photon data of its own in a
    /// parallel array (photons of one grid cell are stored together, so such reads stay
    /// mostly sequential).
    #[inline]
    pub fn finish_query_indexed(&self, q: &PhotonQuery, mut f: impl FnMut(usize, &Photon)) {
        match q.scan {
            Scan::Listed | Scan::Fetched => {
                for &i in &q.found[..q.n_found as usize] {
                    f(i as usize, &self.photons[i as usize]);
                }
            }
            Scan::No | Scan::Overflow => self.scan(q, |i| f(i, &self.photons[i])),
        }
    }

    /// The stored photons, in grid (bucket) order: the index a query reports
    /// ([`Self::finish_query_indexed`]) is an index into this slice.
    #[inline]
    pub fn photons(&self) -> &[Photon] {
        &self.photons
    }

    /// The position of `photons()[i]` for every i, m, packed densely (what the range test
    /// reads).
    #[inline]
    pub fn positions(&self) -> &[Vec3] {
        &self.positions
    }

    /// The light-path vertices of the pass that a path went on from (depth 0 included), in
    /// path order: the targets of [`Photon::prev`]. A path's vertices are consecutive and
    /// their depths count up from 0, so the vertices before a photon's y_p are the rest of its
    /// light path. A vertex where a path ended is not kept (it is nobody's y_p).
    #[inline]
    pub fn vertices(&self) -> &[PathVertex] {
        &self.vertices
    }

    /// The path vertex with index `i` (a [`Photon::prev`]).
    #[inline]
    pub fn vertex(&self, i: u32) -> &PathVertex {
        &self.vertices[i as usize]
    }

    /// Heap and inline bytes held by the map (photons, vertices, grid table).
    pub fn memory_bytes(&self) -> u64 {
        (size_of::<Self>()
            + self.photons.capacity() * size_of::<Photon>()
            + self.positions.capacity() * size_of::<Vec3>()
            + self.vertices.capacity() * size_of::<PathVertex>()) as u64
            + self.grid.memory_bytes()
    }

    /// N_F: photons emitted in the pass (stored or not), the divisor already in each power.
    pub fn emitted(&self) -> u64 {
        self.emitted
    }
}
