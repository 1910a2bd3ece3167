//! A hashed uniform grid for fixed-radius range queries (SmallVCM's `hashgrid.hxx` design):
//! cells of edge 2r hashed into a power-of-two table, points sorted into buckets by a
//! counting sort, each bucket a contiguous range of the sorted points.

use glam::Vec3;
use rayon::prelude::*;

/// Bucket table over points sorted by bucket. Cells that hash to the same bucket share it; the
/// caller's distance test removes the points of the other cells.
///
/// A bit filter of occupied cells sits in front of the table: most cells a query touches are
/// empty (photons lie on surfaces, and a gather finds well under one photon at the preprint's
/// radius), and the filter, a few bits per point, stays in the core's cache where the bucket
/// table does not. It has no false negatives, so skipping a bucket whose cells it calls empty
/// never loses a point, and the order in which points are reported is unchanged.
#[derive(Clone, Debug, Default)]
pub(crate) struct HashGrid {
    /// 1 / cell edge, m⁻¹.
    inv_cell: f32,
    /// Bucket b holds sorted points `starts[b]..starts[b + 1]`; length = buckets + 1.
    starts: Vec<u32>,
    /// `buckets − 1` (the table size is a power of two).
    mask: u64,
    /// Occupied-cell filter: bit `filter_bit(hash)` is set for the cell of every point.
    filter: Vec<u64>,
    /// Filter bits − 1 (a power of two).
    filter_mask: u64,
}

/// Filter bits per bucket: 4 gives ~1 bit set in 6 for a full table and half a megabyte for a
/// million points.
const FILTER_BITS_PER_BUCKET: usize = 4;

/// The filter bit of a cell hash: bits from the high half, so that it is nearly independent of
/// the bucket index (the low bits) and two cells sharing a bucket rarely share a bit.
#[inline]
fn filter_bit(h: u64, filter_mask: u64) -> u64 {
    h.rotate_right(32) & filter_mask
}

/// Integer cell coordinates of `p`. `as` saturates, so absurd radii only merge cells.
#[inline]
fn cell_of(p: Vec3, inv_cell: f32) -> [i64; 3] {
    let c = p * inv_cell;
    [c.x.floor() as i64, c.y.floor() as i64, c.z.floor() as i64]
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
    /// point). The sort is stable, so the result is deterministic.
    pub(crate) fn build(points: &[Vec3], radius: f32) -> (HashGrid, Vec<u32>) {
        assert!(
            points.len() < u32::MAX as usize,
            "photon map holds at most 2³² − 2 photons"
        );
        let inv_cell = 1.0 / (2.0 * radius);
        let buckets = points.len().max(1).next_power_of_two();
        let mask = buckets as u64 - 1;
        // Hashing is the only per-point arithmetic worth spreading over threads; the counting
        // passes are memory-bound and sequential keeps them stable and simple.
        let hashes: Vec<u64> = points
            .par_iter()
            .map(|&p| hash(cell_of(p, inv_cell)))
            .collect();
        let filter_bits = buckets * FILTER_BITS_PER_BUCKET;
        let filter_mask = filter_bits as u64 - 1;
        let mut filter = vec![0u64; filter_bits.div_ceil(64)];
        let mut starts = vec![0u32; buckets + 1];
        let keys: Vec<u32> = hashes.iter().map(|&h| (h & mask) as u32).collect();
        for (&k, &h) in keys.iter().zip(&hashes) {
            starts[k as usize + 1] += 1;
            let bit = filter_bit(h, filter_mask);
            filter[(bit >> 6) as usize] |= 1 << (bit & 63);
        }
        for b in 0..buckets {
            starts[b + 1] += starts[b];
        }
        let mut next = starts.clone();
        let mut order = vec![0u32; points.len()];
        for (i, &k) in keys.iter().enumerate() {
            let slot = &mut next[k as usize];
            order[*slot as usize] = i as u32;
            *slot += 1;
        }
        (
            HashGrid {
                inv_cell,
                starts,
                mask,
                filter,
                filter_mask,
            },
            order,
        )
    }

    /// The distinct buckets that a sphere of radius `radius` (the build radius) around `x` can
    /// touch, in a deterministic order, with whether the filter says any of their touched
    /// cells may hold a point: `(buckets[..n], live[..n])`. With cell edge 2r the span is ≤ 2
    /// cells per axis (8 in all); rounding at huge coordinates could make it 3, so 27 are
    /// allowed.
    #[inline]
    fn buckets_near(&self, x: Vec3, radius: f32) -> ([u32; 27], [bool; 27], usize) {
        let lo = cell_of(x - Vec3::splat(radius), self.inv_cell);
        let hi = cell_of(x + Vec3::splat(radius), self.inv_cell);
        let mut buckets = [u32::MAX; 27];
        let mut live = [false; 27];
        let mut n = 0;
        for cx in lo[0]..=hi[0].min(lo[0] + 2) {
            for cy in lo[1]..=hi[1].min(lo[1] + 2) {
                for cz in lo[2]..=hi[2].min(lo[2] + 2) {
                    let h = hash([cx, cy, cz]);
                    let b = (h & self.mask) as u32;
                    let bit = filter_bit(h, self.filter_mask);
                    let occupied = self.filter[(bit >> 6) as usize] & (1 << (bit & 63)) != 0;
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

    /// Calls `f(range)` once for each distinct non-empty bucket that a sphere of radius
    /// `radius` (the build radius) around `x` can touch, in a deterministic order. The ranges
    /// index the sorted points. Allocation-free.
    #[inline]
    pub(crate) fn for_each_bucket(
        &self,
        x: Vec3,
        radius: f32,
        mut f: impl FnMut(std::ops::Range<usize>),
    ) {
        if self.starts.len() < 2 {
            return;
        }
        let (buckets, live, n) = self.buckets_near(x, radius);
        // All bucket bounds are read before any point: the reads are independent, so their
        // cache misses overlap instead of alternating with the points' misses.
        let mut ranges = [(0u32, 0u32); 27];
        for ((r, &b), _) in ranges
            .iter_mut()
            .zip(&buckets[..n])
            .zip(&live)
            .filter(|(_, l)| **l)
        {
            *r = (self.starts[b as usize], self.starts[b as usize + 1]);
        }
        for &(s, e) in &ranges[..n] {
            if s < e {
                f(s as usize..e as usize);
            }
        }
    }

    /// Asks the CPU to fetch the bucket bounds that a query at `x` will read (a hint; no
    /// effect on results). Issued a little before the query, it hides their memory latency
    /// behind other work.
    #[inline]
    pub(crate) fn prefetch(&self, x: Vec3, radius: f32) {
        if self.starts.len() < 2 {
            return;
        }
        let (buckets, live, n) = self.buckets_near(x, radius);
        for (&b, _) in buckets[..n].iter().zip(&live).filter(|(_, l)| **l) {
            bdpm_geometry::prefetch(&self.starts[b as usize]);
        }
    }

    /// Heap bytes held.
    pub(crate) fn memory_bytes(&self) -> u64 {
        (self.starts.capacity() * size_of::<u32>() + self.filter.capacity() * size_of::<u64>())
            as u64
    }
}
