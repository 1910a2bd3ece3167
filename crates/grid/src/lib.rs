//! A hashed uniform grid for fixed-radius range queries over plain points (SmallVCM's
//! `hashgrid.hxx` design): cells of edge 2r hashed into a power-of-two table, points sorted
//! into buckets by a counting sort, each bucket a contiguous range of the sorted points.
//!
//! This module needs nothing from a scene: any renderer with its own points (photons, light
//! vertices, particles) can use it alone. [`PointGrid`] is the simple form (build from
//! `&[Vec3]` and a radius, call back the indices of the points within the radius);
//! [`HashGrid`] is the staged form the photon map's gathers use, which reports candidate
//! ranges of the sorted points and lets a caller overlap memory fetches of many queries.
//!
//! Invariant: a query reports every point within the build radius exactly once (and
//! possibly farther points of cells sharing a bucket, which [`PointGrid`] filters out), in an
//! order that depends only on the points and the radius, never on the thread count.
//!
//! ```
//! use bdpm_grid::PointGrid;
//! use glam::Vec3;
//!
//! let points = [Vec3::ZERO, Vec3::new(0.05, 0.0, 0.0), Vec3::new(1.0, 0.0, 0.0)];
//! let grid = PointGrid::new(&points, 0.1);
//! let mut near = Vec::new();
//! grid.for_each_near(Vec3::new(0.02, 0.0, 0.0), |i| near.push(i));
//! near.sort();
//! assert_eq!(near, [0, 1]);
//! ```

use glam::Vec3;
use rayon::prelude::*;

/// Bucket table over points sorted by bucket. Cells that hash to the same bucket share it; the
/// caller's distance test removes the points of the other cells. The grid keeps no points:
/// [`HashGrid::build`] returns the sorting permutation and the caller keeps the points in that
/// order ([`PointGrid`] does this for you).
///
/// A query is staged so that many can be in flight at once: [`HashGrid::start`], any number
/// of [`HashGrid::advance`] (each hints the CPU to fetch what the next reads), then
/// [`HashGrid::visit`], which reports the candidate ranges of the sorted points.
///
/// Each bucket's entry holds, beside where its points start, an occupancy filter: 32 tag bits,
/// bit t set when a point of a cell whose hash has tag t (its top five bits) lies in the
/// bucket. Most cells a query touches are empty (photons lie on surfaces, and a gather finds
/// well under one photon at the preprint's radius), and the tag spares reading the points of
/// the other cells sharing the bucket. Start and filter share one 8-byte entry, so a query
/// waits for one random read per bucket before it knows which points to fetch. The filter has
/// no false negatives, so skipping a bucket whose touched cells it calls empty never loses a
/// point, and the order in which points are reported does not depend on it.
#[derive(Clone, Debug, Default)]
pub struct HashGrid {
    /// 1 / cell edge, m⁻¹.
    inv_cell: f32,
    /// Entry b: low 32 bits the first sorted point of bucket b (its points are
    /// `start(b)..start(b + 1)`), high 32 bits its tag filter. Length = buckets + 1.
    table: Vec<u64>,
    /// `buckets − 1` (the table size is a power of two).
    mask: u64,
}

/// How far a [`GridQuery`] has got.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
enum Stage {
    /// Cells and buckets known; their table entries requested.
    #[default]
    Entries,
    /// Live buckets and their bounds read; ready to visit.
    Bounds,
}

/// A range query in flight (see [`HashGrid::start`]): the ≤ 8 cells a sphere of radius r
/// touches in a grid of cell 2r, their distinct buckets in visiting order, and what the stages
/// so far have read.
#[derive(Clone, Copy, Debug, Default)]
pub struct GridQuery {
    /// Distinct buckets, in visiting order: `buckets[..n]`.
    buckets: [u32; 8],
    /// Tag bits of the touched cells of each bucket.
    tags: [u32; 8],
    /// Bucket bounds `start(b)..start(b + 1)`, read in [`Stage::Entries`] for live buckets.
    ranges: [(u32, u32); 8],
    n: u8,
    /// Bit k set: some touched cell of bucket k may hold a point.
    live: u8,
    stage: Stage,
    /// A query spanning 3 cells on an axis (rounding at huge coordinates) takes the general
    /// path: its point and radius.
    general: Option<(Vec3, f32)>,
}

impl GridQuery {
    /// True once the bucket bounds have been read: [`HashGrid::visit`] reads nothing more of
    /// the grid.
    #[inline]
    pub fn ready(&self) -> bool {
        self.stage == Stage::Bounds
    }

    /// True if the query is known to touch no point (no live bucket, normal path).
    #[inline]
    pub fn empty(&self) -> bool {
        self.ready() && self.live == 0 && self.general.is_none()
    }
}

/// The tag bit of a cell hash: its top five bits, which the bucket index (the low bits) does
/// not use, so that two cells sharing a bucket share a tag one time in 32.
#[inline]
fn tag_bit(h: u64) -> u32 {
    1 << (h >> 59)
}

/// Super-buckets of the parallel sort (see [`sort_into_buckets`]): groups of consecutive
/// buckets sorted independently, small enough that a group's counters stay in L1.
const SUPER_BITS: u32 = 8;

/// Points per chunk of the first pass of [`sort_into_buckets`].
const SORT_CHUNK: usize = 1 << 15;

/// Stable counting sort of the point indices by bucket `hashes[i] & (buckets − 1)`, with each
/// bucket's tag filter: returns the table of [`HashGrid`] and the permutation (`order[k]` =
/// index of the k-th sorted point). `buckets` is a power of two.
///
/// A one-thread counting sort of a million points scatters into a 4 MB table and was a serial
/// stretch of every photon pass (docs/performance.md). With more than one thread and at least
/// [`PARALLEL_SORT_MIN`] points it runs in two stable parallel passes: each chunk of the input
/// sorts its indices by super-bucket (the bucket's high bits); then each super-bucket takes its
/// runs from the chunks, in input order, and sorts them by the low bits into its own slice of
/// the table and of the permutation. Both passes keep input order within a bucket, so the
/// result is the one-thread sort's, on any thread count (unit test).
fn sort_into_buckets(hashes: &[u64], buckets: usize) -> (Vec<u64>, Vec<u32>) {
    debug_assert!(buckets.is_power_of_two());
    if hashes.len() < PARALLEL_SORT_MIN || rayon::current_num_threads() == 1 {
        sort_serial(hashes, buckets)
    } else {
        sort_parallel(hashes, buckets)
    }
}

/// Points below which [`sort_into_buckets`] sorts on one thread. Measured (`measure_sort_paths`
/// below, medians): on two threads the two-pass sort took 1.35 ms against 0.79 ms at 128,000
/// points and 8.7 ms against 11.4 ms at 640,000; on one thread it is always slower (15.3 ms
/// against 9.3 ms at 640,000).
const PARALLEL_SORT_MIN: usize = 1 << 18;

/// [`sort_into_buckets`] on one thread: one counting pass, then one scatter. Faster than the
/// two-pass sort on one thread, and below [`PARALLEL_SORT_MIN`] points on two.
fn sort_serial(hashes: &[u64], buckets: usize) -> (Vec<u64>, Vec<u32>) {
    let mask = buckets as u64 - 1;
    // Each entry counts its points in the low half (fewer than 2³² points) and collects its
    // tags in the high half, then the counts become starts.
    let mut table = vec![0u64; buckets + 1];
    for &h in hashes {
        let e = &mut table[(h & mask) as usize];
        *e = (*e + 1) | u64::from(tag_bit(h)) << 32;
    }
    let mut next = Vec::with_capacity(buckets);
    let mut at = 0u32;
    for e in &mut table[..buckets] {
        let count = *e as u32;
        *e = (*e & !u64::from(u32::MAX)) | u64::from(at);
        next.push(at);
        at += count;
    }
    table[buckets] = u64::from(at);
    let mut order = vec![0u32; hashes.len()];
    for (i, &h) in hashes.iter().enumerate() {
        let slot = &mut next[(h & mask) as usize];
        order[*slot as usize] = i as u32;
        *slot += 1;
    }
    (table, order)
}

/// The two-pass parallel form of [`sort_into_buckets`].
fn sort_parallel(hashes: &[u64], buckets: usize) -> (Vec<u64>, Vec<u32>) {
    let mask = buckets as u64 - 1;
    let bucket_bits = buckets.trailing_zeros();
    let super_bits = SUPER_BITS.min(bucket_bits);
    let low_bits = bucket_bits - super_bits;
    let supers = 1usize << super_bits;
    let per_super = 1usize << low_bits;
    let super_of = |h: u64| ((h & mask) >> low_bits) as usize;

    // Pass 1: per chunk, its indices grouped by super-bucket, and where each group starts.
    let runs: Vec<(Vec<u32>, Vec<u32>)> = hashes
        .par_chunks(SORT_CHUNK)
        .enumerate()
        .map(|(c, chunk)| {
            let base = (c * SORT_CHUNK) as u32;
            let mut first = vec![0u32; supers + 1];
            for &h in chunk {
                first[super_of(h) + 1] += 1;
            }
            for s in 0..supers {
                first[s + 1] += first[s];
            }
            let mut next = first.clone();
            let mut sorted = vec![0u32; chunk.len()];
            for (i, &h) in chunk.iter().enumerate() {
                let s = super_of(h);
                sorted[next[s] as usize] = base + i as u32;
                next[s] += 1;
            }
            (sorted, first)
        })
        .collect();

    // Where each super-bucket's points start in the sorted order.
    let mut group_start = vec![0usize; supers + 1];
    for s in 0..supers {
        let size: usize = runs
            .iter()
            .map(|(_, first)| (first[s + 1] - first[s]) as usize)
            .sum();
        group_start[s + 1] = group_start[s] + size;
    }

    // Pass 2: each super-bucket fills its buckets' entries and its part of the permutation.
    let n = hashes.len();
    let mut table = vec![0u64; buckets + 1];
    let mut order = vec![0u32; n];
    let mut parts = Vec::with_capacity(supers);
    let mut rest = order.as_mut_slice();
    for s in 0..supers {
        let (head, tail) = rest.split_at_mut(group_start[s + 1] - group_start[s]);
        parts.push(head);
        rest = tail;
    }
    let low_mask = per_super - 1;
    table[..buckets]
        .par_chunks_mut(per_super)
        .zip(parts)
        .enumerate()
        .for_each(|(s, (entries, out))| {
            let group = || {
                runs.iter().flat_map(move |(sorted, first)| {
                    &sorted[first[s] as usize..first[s + 1] as usize]
                })
            };
            let mut counts = vec![0u32; per_super];
            let mut tags = vec![0u32; per_super];
            for &i in group() {
                let h = hashes[i as usize];
                let b = (h & mask) as usize & low_mask;
                counts[b] += 1;
                tags[b] |= tag_bit(h);
            }
            let mut at = 0u32;
            for b in 0..per_super {
                entries[b] = u64::from(group_start[s] as u32 + at) | u64::from(tags[b]) << 32;
                let size = counts[b];
                counts[b] = at;
                at += size;
            }
            for &i in group() {
                let b = (hashes[i as usize] & mask) as usize & low_mask;
                out[counts[b] as usize] = i;
                counts[b] += 1;
            }
        });
    table[buckets] = n as u64;
    (table, order)
}

/// Integer cell coordinates of `p`. `as` saturates, so absurd radii only merge cells.
#[inline]
fn cell_of(p: Vec3, inv_cell: f32) -> [i64; 3] {
    let c = p * inv_cell;
    [floor_i64(c.x), floor_i64(c.y), floor_i64(c.z)]
}

/// `x.floor() as i64` (saturating, NaN → 0) without a call: x86-64's baseline has no rounding
/// instruction, so `floor` is a call into libm, about 1 % of a Lambert render's samples.
#[inline]
fn floor_i64(x: f32) -> i64 {
    // `as` truncates towards zero (and saturates); one less below zero unless x is integral.
    // Above 2²⁴ every f32 is integral and `t as f32` is x again.
    let t = x as i64;
    if (t as f32) > x {
        t.saturating_sub(1)
    } else {
        t
    }
}

/// The hash of a cell that picks its bucket (low bits) and tag (top five bits). The 2×2×2
/// block of cells around an even corner shares one hash of the block's coordinates and takes
/// the cells' parities as its three lowest bits, so a block's eight cells have eight
/// consecutive buckets: the ≤ 8 cells of a query, a 2×2×2 box at any offset, fall in one to
/// eight blocks (3.4 on average), and their table entries and points in as many runs of the
/// table and of the sorted points, instead of eight of each.
#[inline]
fn cell_hash(c: [i64; 3]) -> u64 {
    let parity = ((c[0] & 1) << 2 | (c[1] & 1) << 1 | (c[2] & 1)) as u64;
    (hash([c[0] >> 1, c[1] >> 1, c[2] >> 1]) & !7) | parity
}

#[inline]
fn hash(c: [i64; 3]) -> u64 {
    // Multiply each coordinate by a distinct odd constant, then SplitMix64's finaliser, so that
    // neighbouring cells spread over the whole table.
    let mut h = (c[0] as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15)
        ^ (c[1] as u64).wrapping_mul(0xc2b2_ae3d_27d4_eb4f)
        ^ (c[2] as u64).wrapping_mul(0x1656_67b1_9e37_79f9);
    h = (h ^ (h >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    h = (h ^ (h >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    h ^ (h >> 31)
}

impl HashGrid {
    /// Builds the grid for `points` with cell edge `2·radius` and returns it with the
    /// permutation that sorts the points by bucket (`order[k]` = index of the k-th sorted
    /// point). The sort is stable, so the result is deterministic, on any thread count.
    pub fn build(points: &[Vec3], radius: f32) -> (HashGrid, Vec<u32>) {
        assert!(
            points.len() < u32::MAX as usize,
            "a grid holds at most 2³² − 2 points"
        );
        // A subnormal radius (below ~1e-38 m) would make 1/(2r) infinite; then the touched
        // cells span the whole i64 range and the ≤ 8-cell query overflows its arrays. The
        // loader rejects such radii; this keeps the grid sound for any positive radius.
        let inv_cell = (0.5 / radius).min(f32::MAX);
        let buckets = points.len().max(1).next_power_of_two();
        let hashes: Vec<u64> = points
            .par_iter()
            .map(|&p| cell_hash(cell_of(p, inv_cell)))
            .collect();
        let (table, order) = sort_into_buckets(&hashes, buckets);
        (
            HashGrid {
                inv_cell,
                table,
                mask: buckets as u64 - 1,
            },
            order,
        )
    }

    /// First sorted point of bucket `b` (`b` ≤ buckets).
    #[inline]
    fn start_of(&self, b: usize) -> u32 {
        self.table[b] as u32
    }

    /// True if the tag filter of bucket `b` has any of `tags`.
    #[inline]
    fn has_tags(&self, b: usize, tags: u32) -> bool {
        (self.table[b] >> 32) as u32 & tags != 0
    }

    /// The distinct buckets that a sphere of radius `radius` (the build radius) around `x` can
    /// touch, in a deterministic order, with whether the filter says any of their touched
    /// cells may hold a point: `(buckets[..n], live[..n])`. This is the general path, for
    /// queries that span 3 cells on an axis (rounding at huge coordinates); [`GridQuery`]
    /// visits the same buckets in the same order for the usual ≤ 2.
    fn buckets_near(&self, x: Vec3, radius: f32) -> ([u32; 27], [bool; 27], usize) {
        let lo = cell_of(x - Vec3::splat(radius), self.inv_cell);
        let hi = cell_of(x + Vec3::splat(radius), self.inv_cell);
        let mut buckets = [u32::MAX; 27];
        let mut live = [false; 27];
        let mut n = 0;
        for cx in lo[0]..=hi[0].min(lo[0].saturating_add(2)) {
            for cy in lo[1]..=hi[1].min(lo[1].saturating_add(2)) {
                for cz in lo[2]..=hi[2].min(lo[2].saturating_add(2)) {
                    let h = cell_hash([cx, cy, cz]);
                    let b = (h & self.mask) as u32;
                    let occupied = self.has_tags(b as usize, tag_bit(h));
                    // Two touched cells may share a bucket; visit it once (or its points would
                    // be reported twice), at its first place in the order.
                    if let Some(k) = buckets[..n].iter().position(|&c| c == b) {
                        live[k] |= occupied;
                        continue;
                    }
                    buckets[n] = b;
                    live[n] = occupied;
                    n += 1;
                }
            }
        }
        (buckets, live, n)
    }

    /// Starts a range query for a sphere of radius `radius` (the build radius) around `x`:
    /// finds the touched cells and their buckets and hints the CPU to fetch their table
    /// entries. [`Self::advance`] moves it on, [`Self::visit`] finishes it.
    /// `q` is overwritten in place (a query is a few hundred bytes; callers keep theirs in
    /// fixed slots rather than moving them).
    #[inline]
    pub fn start(&self, q: &mut GridQuery, x: Vec3, radius: f32) {
        // The arrays need no reset: only their first `n` entries are read, and `ranges[k]`
        // only once bucket k is live.
        q.live = 0;
        q.n = 0;
        q.general = None;
        q.stage = Stage::Entries;
        if self.table.len() < 2 {
            q.stage = Stage::Bounds;
            return;
        }
        let lo = cell_of(x - Vec3::splat(radius), self.inv_cell);
        let hi = cell_of(x + Vec3::splat(radius), self.inv_cell);
        // Saturating: cell coordinates saturate at ±2⁶³ for absurd positions or radii, and a
        // wrapped difference would send such a query down the ≤ 8-cell path.
        if (0..3).any(|a| hi[a].saturating_sub(lo[a]) > 1) {
            q.general = Some((x, radius));
            return;
        }
        let mut n = 0;
        for cx in lo[0]..=hi[0] {
            for cy in lo[1]..=hi[1] {
                for cz in lo[2]..=hi[2] {
                    let h = cell_hash([cx, cy, cz]);
                    let b = (h & self.mask) as u32;
                    // Cells that share a bucket: the bucket is visited once, at its first place.
                    match q.buckets[..n].iter().position(|&c| c == b) {
                        Some(k) => q.tags[k] |= tag_bit(h),
                        None => {
                            let entry = &self.table[b as usize];
                            bdpm_core::prefetch(entry);
                            // The bucket's end is the next entry's start, in the next
                            // cache line when this entry is its line's last.
                            if (entry as *const u64 as usize) % 64 == 56 {
                                bdpm_core::prefetch(&self.table[b as usize + 1]);
                            }
                            q.buckets[n] = b;
                            q.tags[n] = tag_bit(h);
                            n += 1;
                        }
                    }
                }
            }
        }
        q.n = n as u8;
    }

    /// Moves `q` one stage on, hinting the CPU to fetch what the next stage reads: the table
    /// entries decide which buckets are live and give their bounds (and `hint(first point
    /// index)` is called for each non-empty live bucket, so the caller can fetch its points).
    /// Results do not depend on how often this is called.
    #[inline]
    pub fn advance(&self, q: &mut GridQuery, hint: impl Fn(usize)) {
        if q.stage == Stage::Bounds {
            return;
        }
        for k in 0..q.n as usize {
            let b = q.buckets[k] as usize;
            if self.has_tags(b, q.tags[k]) {
                q.live |= 1 << k;
                q.ranges[k] = (self.start_of(b), self.start_of(b + 1));
                if q.ranges[k].0 < q.ranges[k].1 {
                    hint(q.ranges[k].0 as usize);
                }
            }
        }
        q.stage = Stage::Bounds;
    }

    /// Finishes `q`: calls `f(range)` once for each distinct non-empty bucket the query
    /// touches, in a deterministic order (the same whatever stage `q` had reached). The ranges
    /// index the sorted points.
    #[inline]
    pub fn visit(&self, q: &GridQuery, mut f: impl FnMut(std::ops::Range<usize>)) {
        if let Some((x, radius)) = q.general {
            let (buckets, live, n) = self.buckets_near(x, radius);
            for k in 0..n {
                let b = buckets[k] as usize;
                let (s, e) = (self.start_of(b), self.start_of(b + 1));
                if live[k] && s < e {
                    f(s as usize..e as usize);
                }
            }
            return;
        }
        if q.stage != Stage::Bounds {
            let mut q = *q;
            self.advance(&mut q, |_| {});
            return self.visit(&q, f);
        }
        for k in 0..q.n as usize {
            let (s, e) = q.ranges[k];
            if q.live & (1 << k) != 0 && s < e {
                f(s as usize..e as usize);
            }
        }
    }

    /// Heap bytes held.
    pub fn memory_bytes(&self) -> u64 {
        (self.table.capacity() * size_of::<u64>()) as u64
    }
}

/// A fixed-radius point grid that owns what a query needs: the points sorted into the grid and
/// their indices in the caller's slice. Build once, query from any number of threads.
#[derive(Clone, Debug, Default)]
pub struct PointGrid {
    grid: HashGrid,
    /// The caller's points in grid order, m.
    sorted: Vec<Vec3>,
    /// `order[k]`: index in the caller's slice of `sorted[k]`.
    order: Vec<u32>,
    radius: f32,
}

impl PointGrid {
    /// Builds the grid of `points` (positions, m) for range queries of radius `radius` (m).
    /// Deterministic: the same points and radius give the same grid on any thread count.
    ///
    /// # Panics
    /// If `radius` is not positive and finite, or there are ≥ 2³² − 1 points.
    pub fn new(points: &[Vec3], radius: f32) -> PointGrid {
        assert!(
            radius > 0.0 && radius.is_finite(),
            "query radius must be positive and finite, got {radius}"
        );
        let (grid, order) = HashGrid::build(points, radius);
        let sorted = order.iter().map(|&i| points[i as usize]).collect();
        PointGrid {
            grid,
            sorted,
            order,
            radius,
        }
    }

    /// The query radius r the grid was built for, m.
    pub fn radius(&self) -> f32 {
        self.radius
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.sorted.len()
    }

    /// True if the grid holds no point.
    pub fn is_empty(&self) -> bool {
        self.sorted.is_empty()
    }

    /// Calls `f(i)` for every point `points[i]` (of the slice given to [`Self::new`]) with
    /// |x − points\[i\]|² ≤ r² (in f32), each once, in a deterministic order. Allocates
    /// nothing; at most 8 cells of edge 2r are read, so the cost is the points in a (4r)³ box.
    pub fn for_each_near(&self, x: Vec3, mut f: impl FnMut(usize)) {
        let mut q = GridQuery::default();
        self.grid.start(&mut q, x, self.radius);
        let r2 = self.radius * self.radius;
        self.grid.visit(&q, |range| {
            for k in range {
                if (self.sorted[k] - x).length_squared() <= r2 {
                    f(self.order[k] as usize);
                }
            }
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A subnormal radius used to make 1/(2r) infinite, and the query then indexed its
    /// 8-cell arrays out of bounds (issue 15). It must answer, and find the point it sits on.
    #[test]
    fn floor_i64_is_floor() {
        let mut xs = vec![
            0.0f32,
            -0.0,
            0.5,
            -0.5,
            1.0,
            -1.0,
            -1.0 + f32::EPSILON,
            -f32::MIN_POSITIVE,
            f32::MIN_POSITIVE,
            16_777_215.5,
            -16_777_215.5,
            9.223_372e18,
            -9.223_372e18,
            1e19,
            -1e19,
            f32::MAX,
            f32::MIN,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
        ];
        let mut rng = bdpm_core::Rng::new(9, bdpm_core::Domain::Other, [0; 3]);
        xs.extend(
            (0..100_000)
                .map(|_| (rng.uniform() - 0.5) * 10f32.powi((rng.uniform() * 40.0) as i32 - 20)),
        );
        for x in xs {
            assert_eq!(floor_i64(x), x.floor() as i64, "x = {x:e}");
        }
    }

    #[test]
    fn subnormal_and_tiny_radii_do_not_break_queries() {
        let points = [Vec3::ZERO, Vec3::new(1.0, -2.0, 3.0), Vec3::splat(-1e6)];
        for radius in [1e-40f32, f32::MIN_POSITIVE, 1e-30, 1e-3] {
            let (grid, order) = HashGrid::build(&points, radius);
            for (k, &x) in points.iter().enumerate() {
                let mut q = GridQuery::default();
                grid.start(&mut q, x, radius);
                let mut found = false;
                grid.visit(&q, |range| {
                    found |= order[range].contains(&(k as u32));
                });
                assert!(found, "radius {radius:e}: point {k} not found");
            }
        }
    }

    /// The parallel two-pass sort gives the one-thread sort's table and permutation, for sizes
    /// below, at and above one chunk and one super-bucket, with crowded buckets, on 1 and 3
    /// threads.
    #[test]
    fn parallel_sort_equals_the_one_thread_sort() {
        let mut rng = bdpm_core::Rng::new(7, bdpm_core::Domain::Other, [0; 3]);
        let mut random = || rng.next_u64();
        for (n, distinct) in [
            (0usize, 1u64),
            (1, 1),
            (5, 3),
            (300, 1000),
            (SORT_CHUNK - 1, 50),
            (SORT_CHUNK + 17, u64::MAX),
            (3 * SORT_CHUNK + 5, 100_000),
        ] {
            let pool: Vec<u64> = (0..distinct.min(4096)).map(|_| random()).collect();
            let hashes: Vec<u64> = (0..n)
                .map(|_| {
                    let h = random();
                    // Few distinct cells crowd their buckets; otherwise every hash is fresh.
                    if distinct < n as u64 {
                        pool[(h % pool.len() as u64) as usize]
                    } else {
                        h
                    }
                })
                .collect();
            for buckets in [1usize, 64, 256, 1024, n.max(1).next_power_of_two()] {
                let expected = sort_serial(&hashes, buckets);
                for threads in [1, 3] {
                    let got = rayon::ThreadPoolBuilder::new()
                        .num_threads(threads)
                        .build()
                        .unwrap()
                        .install(|| sort_parallel(&hashes, buckets));
                    assert!(
                        got == expected,
                        "n {n}, {buckets} buckets, {threads} threads: sorts differ"
                    );
                }
            }
        }
    }

    /// The eight cells of a 2×2×2 block at even coordinates (negative ones included) take
    /// eight consecutive buckets in a table of at least eight, so a query reads a few runs of
    /// the table instead of eight scattered entries.
    #[test]
    fn a_blocks_cells_take_consecutive_buckets() {
        let mut rng = bdpm_core::Rng::new(3, bdpm_core::Domain::Other, [0; 3]);
        for _ in 0..1000 {
            let c0 = [0; 3].map(|_| (rng.next_u64() as i64 >> 20) & !1);
            for mask in [7u64, (1 << 20) - 1] {
                let mut buckets: Vec<u64> = (0..8)
                    .map(|k| {
                        cell_hash([c0[0] + (k >> 2), c0[1] + (k >> 1 & 1), c0[2] + (k & 1)]) & mask
                    })
                    .collect();
                buckets.sort_unstable();
                assert_eq!(buckets[0] % 8, 0, "block {c0:?}");
                assert!(
                    buckets.windows(2).all(|w| w[1] == w[0] + 1),
                    "block {c0:?}: {buckets:?}"
                );
            }
        }
    }

    /// The simple API reports exactly the points brute force finds, each once.
    #[test]
    fn point_grid_matches_brute_force() {
        let mut rng = bdpm_core::Rng::new(5, bdpm_core::Domain::Other, [0; 3]);
        let points: Vec<Vec3> = (0..5_000)
            .map(|_| Vec3::from(rng.uniform3()) * 2.0 - 1.0)
            .collect();
        let radius = 0.07;
        let grid = PointGrid::new(&points, radius);
        assert_eq!(grid.len(), points.len());
        for _ in 0..500 {
            let x = Vec3::from(rng.uniform3()) * 2.2 - 1.1;
            let mut found = Vec::new();
            grid.for_each_near(x, |i| found.push(i));
            found.sort_unstable();
            let brute: Vec<usize> = (0..points.len())
                .filter(|&i| (points[i] - x).length_squared() <= radius * radius)
                .collect();
            assert_eq!(found, brute);
        }
    }
}

/// A measurement, not a test: the two sort paths timed side by side (interleaved, medians and
/// fastest of 25), which sets [`PARALLEL_SORT_MIN`] and the one-thread rule. Run it as an
/// ignored library test of this crate in release, with its output shown (the command is in
/// docs/performance.md).
#[cfg(test)]
mod measure {
    use super::*;

    mod walls {
        include!(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/benches/common/walls.rs"
        ));
    }

    #[test]
    #[ignore = "a timing for docs/performance.md, not a check"]
    fn measure_sort_paths() {
        for n in [128_000usize, 640_000] {
            let points = walls::wall_points(n);
            let hashes: Vec<u64> = points
                .iter()
                .map(|&p| cell_hash(cell_of(p, 0.5 / 0.00175)))
                .collect();
            let buckets = n.next_power_of_two();
            for threads in [1, 2] {
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .unwrap();
                let (mut ts, mut tp) = (vec![], vec![]);
                for _ in 0..25 {
                    let t = std::time::Instant::now();
                    std::hint::black_box(sort_serial(&hashes, buckets));
                    ts.push(t.elapsed().as_secs_f64() * 1e3);
                    let t = std::time::Instant::now();
                    std::hint::black_box(pool.install(|| sort_parallel(&hashes, buckets)));
                    tp.push(t.elapsed().as_secs_f64() * 1e3);
                }
                ts.sort_by(f64::total_cmp);
                tp.sort_by(f64::total_cmp);
                println!(
                    "n {n} threads {threads}: serial median {:.2} min {:.2}; parallel median {:.2} min {:.2}",
                    ts[12], ts[0], tp[12], tp[0]
                );
            }
        }
    }
}

// The README (the crate's page on crates.io) as a hidden item, so that `cargo test --doc`
// compiles and runs its example; the crate documentation above stays as it is.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;
