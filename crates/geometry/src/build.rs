//! The BVH build: a top-down binned-SAH binary BVH, collapsed into a 4-wide BVH (`crate::wide`,
//! the default) or into obvhs's compressed wide BVH (`Kernel::Cwbvh`).
//!
//! Why not obvhs's own builder (PLOC): PLOC merges mutual nearest neighbours, and among
//! coincident or nearly coincident triangles every neighbour is (nearly) as near as every other,
//! so few pairs are mutual and each pass merges only a handful of clusters: the build became
//! quadratic (20 000 identical quads: 97 s) and the tree a chain thousands of levels deep. A
//! top-down build is O(n log n) whatever the input: each level costs O(n), binned SAH splits
//! are taken only while the depth stays small, and beyond that (or where all centroids
//! coincide) the split is at the median, which halves the count. The depth bound also keeps a
//! branching wide tree within the 32 entries of obvhs's traversal stack, which overwrites its
//! top entry when full.

use glam::{Vec3, Vec3A};
use obvhs::aabb::Aabb;
use obvhs::bvh2::Bvh2;
use obvhs::bvh2::node::Bvh2Node;
use obvhs::cwbvh::CwBvh;
use obvhs::cwbvh::bvh2_to_cwbvh::bvh2_to_cwbvh;

/// Number of SAH bins per axis.
const BINS: usize = 16;

/// Depth of obvhs's CWBVH traversal stack (`TRAVERSAL_STACK_SIZE`, private in obvhs 0.4): a
/// wide BVH deeper than this could lose nodes during traversal.
pub(crate) const MAX_WIDE_DEPTH: usize = 32;

/// Largest number of triangles per wide-BVH leaf (obvhs supports up to 3).
const MAX_LEAF: u32 = 3;

/// Builds the wide BVH over `tris`; its `primitive_indices` index `tris`.
///
/// The binary tree uses SAH splits down to a depth of `64 − ⌈log₂ n⌉`, then median splits, so
/// it is at most 64 levels deep. If the wide tree made from it is deeper than the traversal
/// stack (possible only for very unbalanced SAH splits), the build is redone with median splits
/// only, whose depth ⌈log₂ n⌉ ≤ 32 bounds the wide tree's.
pub(crate) fn build(tris: &[[Vec3; 3]]) -> CwBvh {
    let n = tris.len().max(1);
    let log2 = usize::BITS - (n - 1).leading_zeros();
    let sah_depth = 64usize.saturating_sub(log2 as usize);
    let bvh = collapse(&binary(tris, sah_depth));
    if wide_depth(&bvh) <= MAX_WIDE_DEPTH {
        bvh
    } else {
        collapse(&binary(tris, 0))
    }
}

/// Builds the 4-wide BVH over `tris` from the same binary tree as [`build`]; its `order`
/// indexes `tris`. As there, a tree deeper than the traversal accepts is rebuilt with median
/// splits, whose binary depth ⌈log₂ n⌉ ≤ 32 bounds the wide tree's.
pub(crate) fn build4(tris: &[[Vec3; 3]]) -> crate::wide::Bvh4 {
    let n = tris.len().max(1);
    let log2 = usize::BITS - (n - 1).leading_zeros();
    let sah_depth = 64usize.saturating_sub(log2 as usize);
    let bvh = crate::wide::collapse(&binary(tris, sah_depth), tris);
    if bvh.depth() <= crate::wide::MAX_DEPTH {
        bvh
    } else {
        crate::wide::collapse(&binary(tris, 0), tris)
    }
}

fn collapse(bvh2: &Bvh2) -> CwBvh {
    bvh2_to_cwbvh(bvh2, MAX_LEAF, true, false)
}

/// Number of levels of wide nodes (1 for a root alone).
pub(crate) fn wide_depth(bvh: &CwBvh) -> usize {
    if bvh.nodes.is_empty() {
        return 0;
    }
    let mut depth = vec![0usize; bvh.nodes.len()];
    depth[0] = 1;
    let mut max = 1;
    // Children are stored after their parent, so one forward sweep sees every parent first.
    for i in 0..bvh.nodes.len() {
        let node = &bvh.nodes[i];
        let base = node.child_base_idx as usize;
        let child_depth = depth[i] + 1;
        for k in 0..node.imask.count_ones() as usize {
            if let Some(d) = depth.get_mut(base + k) {
                *d = child_depth;
                max = max.max(child_depth);
            }
        }
    }
    max
}

/// A pending binary node: its index and its range of `order`.
struct Task {
    node: usize,
    start: usize,
    end: usize,
    depth: usize,
}

/// The binary tree: SAH splits above `sah_depth`, median splits below; one triangle per leaf.
fn binary(tris: &[[Vec3; 3]], sah_depth: usize) -> Bvh2 {
    let boxes: Vec<Aabb> = tris
        .iter()
        .map(|t| {
            let (a, b, c) = (Vec3A::from(t[0]), Vec3A::from(t[1]), Vec3A::from(t[2]));
            Aabb::new(a.min(b).min(c), a.max(b).max(c))
        })
        .collect();
    let centres: Vec<Vec3A> = boxes.iter().map(|b| (b.min + b.max) * 0.5).collect();
    let mut order: Vec<u32> = (0..tris.len() as u32).collect();
    let mut nodes = Vec::with_capacity((2 * tris.len()).saturating_sub(1));
    nodes.push(Bvh2Node::default());
    let mut stack = vec![Task {
        node: 0,
        start: 0,
        end: tris.len(),
        depth: 0,
    }];
    while let Some(task) = stack.pop() {
        let range = &mut order[task.start..task.end];
        let mut bounds = Aabb::empty();
        let mut cbounds = Aabb::empty();
        for &i in range.iter() {
            bounds = bounds.union(&boxes[i as usize]);
            cbounds.extend(centres[i as usize]);
        }
        if range.len() == 1 {
            nodes[task.node] = Bvh2Node::new(bounds, 1, task.start as u32);
            continue;
        }
        let split = if task.depth < sah_depth {
            sah_split(range, &boxes, &centres, &cbounds)
        } else {
            None
        };
        let mid = split.unwrap_or_else(|| median_split(range, &centres, &cbounds));
        let first = nodes.len();
        nodes.push(Bvh2Node::default());
        nodes.push(Bvh2Node::default());
        nodes[task.node] = Bvh2Node::new(bounds, 0, first as u32);
        stack.push(Task {
            node: first + 1,
            start: task.start + mid,
            end: task.end,
            depth: task.depth + 1,
        });
        stack.push(Task {
            node: first,
            start: task.start,
            end: task.start + mid,
            depth: task.depth + 1,
        });
    }
    Bvh2 {
        nodes,
        primitive_indices: order,
        children_are_ordered_after_parents: true,
        ..Bvh2::default()
    }
}

/// The best binned-SAH split of `range` (partitioned in place): the size of the left part,
/// in 1..len, or `None` where every centroid coincides.
fn sah_split(range: &mut [u32], boxes: &[Aabb], centres: &[Vec3A], cb: &Aabb) -> Option<usize> {
    let extent = cb.max - cb.min;
    let mut best: Option<(f32, usize, usize)> = None; // (cost, axis, bins on the left)
    for axis in 0..3 {
        if extent[axis] <= 0.0 {
            continue;
        }
        let scale = BINS as f32 / extent[axis];
        let bin_of =
            |i: u32| (((centres[i as usize][axis] - cb.min[axis]) * scale) as usize).min(BINS - 1);
        let mut bin_box = [Aabb::empty(); BINS];
        let mut bin_count = [0usize; BINS];
        for &i in range.iter() {
            let b = bin_of(i);
            bin_box[b] = bin_box[b].union(&boxes[i as usize]);
            bin_count[b] += 1;
        }
        // Right-to-left sweep: area·count of bins k.. for every k.
        let mut right_cost = [0.0f32; BINS];
        let (mut acc, mut count) = (Aabb::empty(), 0usize);
        for k in (1..BINS).rev() {
            acc = acc.union(&bin_box[k]);
            count += bin_count[k];
            right_cost[k] = if count == 0 {
                0.0
            } else {
                acc.half_area() * count as f32
            };
        }
        let (mut acc, mut count) = (Aabb::empty(), 0usize);
        for k in 1..BINS {
            acc = acc.union(&bin_box[k - 1]);
            count += bin_count[k - 1];
            if count == 0 || count == range.len() {
                continue;
            }
            let cost = acc.half_area() * count as f32 + right_cost[k];
            if best.is_none_or(|b| cost < b.0) {
                best = Some((cost, axis, k));
            }
        }
    }
    let (_, axis, k) = best?;
    let scale = BINS as f32 / extent[axis];
    let left = |i: u32| {
        ((((centres[i as usize][axis] - cb.min[axis]) * scale) as usize).min(BINS - 1)) < k
    };
    // In-place two-pointer partition (deterministic: depends only on the input order).
    let (mut lo, mut hi) = (0, range.len());
    while lo < hi {
        if left(range[lo]) {
            lo += 1;
        } else {
            hi -= 1;
            range.swap(lo, hi);
        }
    }
    // Both sides are non-empty by construction (the split was chosen with count in 1..len).
    Some(lo)
}

/// A split of `range` at its middle: by centroid along the widest centroid axis, or, where all
/// centroids coincide, in the given order (any split of coincident boxes is as good).
fn median_split(range: &mut [u32], centres: &[Vec3A], cb: &Aabb) -> usize {
    let mid = range.len() / 2;
    let extent = cb.max - cb.min;
    if extent.max_element() > 0.0 {
        let axis = if extent.x >= extent.y && extent.x >= extent.z {
            0
        } else if extent.y >= extent.z {
            1
        } else {
            2
        };
        range.select_nth_unstable_by(mid, |&a, &b| {
            centres[a as usize][axis]
                .total_cmp(&centres[b as usize][axis])
                .then(a.cmp(&b))
        });
    }
    mid
}
