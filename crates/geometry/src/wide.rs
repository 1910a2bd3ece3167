//! A 4-wide BVH with uncompressed f32 boxes in SoA layout, and its ordered traversal.
//!
//! Why not obvhs's CWBVH: its 8-wide nodes store child boxes quantised to 8 bits, and about
//! 45 % of a ray's time went into decoding them. Here a node holds its four children's boxes as
//! six `Vec4`s (min x, max x, min y, …), so the slab test of all four children is a handful of
//! 4-lane operations that the x86_64 baseline (SSE2) executes directly: nothing depends on the
//! CPU the renderer runs on, so neither do the images. The tree is made from the same binned
//! SAH binary tree as the CWBVH (`build::binary`), by pulling the largest grandchildren up until
//! a node has four children.

use std::mem::MaybeUninit;

use glam::{Vec3A, Vec4};
use obvhs::bvh2::Bvh2;

/// Children of a node that are leaves carry this bit in their reference: `LEAF_BIT | packet`.
const LEAF_BIT: u32 = 1 << 31;
/// Largest number of triangles per leaf (one [`Tri4`] packet); a subtree with at most this
/// many becomes a leaf.
const MAX_LEAF: u32 = 4;
/// The slot of a packet lane that holds no triangle.
pub(crate) const PADDING: u32 = u32::MAX;
/// The reference of an unused child slot (its box is empty, so it is never entered).
const EMPTY: u32 = u32::MAX;

/// Entries of the traversal stack. A node pushes at most three children and descends into the
/// fourth, so a tree of depth `d` needs at most 3·(d − 1) entries; [`MAX_DEPTH`] keeps that
/// within the stack.
const STACK: usize = 96;
/// Largest depth (levels of nodes) of a tree the traversal accepts.
pub(crate) const MAX_DEPTH: usize = 32;

/// Every slab distance `(plane − o)·(1/d)` is three correctly rounded operations, so it is
/// within a relative 3·2⁻²⁴ of the exact one, with the exact sign. Comparing the nearest exit
/// scaled up by 1 + 4·2⁻²³ with the farthest entry therefore never culls a box that the exact
/// ray touches (a ray through a face of a flat box included).
const GROW: f32 = 1.0 + 4.0 * f32::EPSILON;

/// Four children: their boxes as planes (min x, max x, min y, max y, min z, max z), one lane
/// per child, and their references (a node index, a leaf, or [`EMPTY`]).
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
pub(crate) struct Node4 {
    planes: [Vec4; 6],
    child: [u32; 4],
}

impl Node4 {
    const UNUSED: Node4 = Node4 {
        planes: [
            Vec4::INFINITY,
            Vec4::NEG_INFINITY,
            Vec4::INFINITY,
            Vec4::NEG_INFINITY,
            Vec4::INFINITY,
            Vec4::NEG_INFINITY,
        ],
        child: [EMPTY; 4],
    };
}

/// Up to four triangles of a leaf, laid out for the 4-lane ray test: per lane one vertex and two
/// edges (metres), each as x, y, z vectors. Unused lanes have zero edges, which no ray hits.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Tri4 {
    v0: [Vec4; 3],
    e1: [Vec4; 3],
    e2: [Vec4; 3],
}

#[inline(always)]
fn cross(a: &[Vec4; 3], b: &[Vec4; 3]) -> [Vec4; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

#[inline(always)]
fn dot(a: &[Vec4; 3], b: &[Vec4; 3]) -> Vec4 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

impl Tri4 {
    const EMPTY: Tri4 = Tri4 {
        v0: [Vec4::ZERO; 3],
        e1: [Vec4::ZERO; 3],
        e2: [Vec4::ZERO; 3],
    };

    /// Lane `k` becomes the triangle with vertices `v` (metres).
    fn set(&mut self, k: usize, v: [glam::Vec3; 3]) {
        let e1 = v[1] - v[0];
        let e2 = v[2] - v[0];
        for a in 0..3 {
            self.v0[a][k] = v[0][a];
            self.e1[a][k] = e1[a];
            self.e2[a][k] = e2[a];
        }
    }

    /// The four lanes of `LeafTri::intersect` (mesh.rs) at once: Möller–Trumbore with the same
    /// operations in the same order on each lane (glam's `Vec3A` cross product is
    /// `a.y·b.z − a.z·b.y, …` and its dot product `(x + y) + z`, without fused multiply-adds on
    /// the x86_64 baseline), so each lane's distance has the same bits as the scalar test's.
    /// Returns per lane `t` in units of |d| (+∞ for a miss), the barycentrics (u, v) of the
    /// point where the ray meets the lane's plane, and the lanes the barycentric test alone
    /// rejected within [`NEAR_EDGE`] of an edge: the caller decides those with the watertight
    /// edge test (`Geometry::rescue_near_edges`).
    #[inline(always)]
    pub(crate) fn intersect(&self, ray: &BoxRay, tmax: f32) -> Lanes {
        let p = cross(&ray.d, &self.e2);
        let det = dot(&self.e1, &p);
        let inv = Vec4::ONE / det;
        let s = [
            ray.o[0] - self.v0[0],
            ray.o[1] - self.v0[1],
            ray.o[2] - self.v0[2],
        ];
        let u = dot(&s, &p) * inv;
        let q = cross(&s, &self.e1);
        let v = dot(&ray.d, &q) * inv;
        let t = dot(&self.e2, &q) * inv;
        // A NaN (det = 0 gives ∞·0) fails every comparison, as it does in the scalar test.
        let in_range = det.cmpne(Vec4::ZERO) & t.cmpgt(Vec4::ZERO) & t.cmplt(Vec4::splat(tmax));
        // The least barycentric (1 − (u + v) ≥ 0 exactly when u + v ≤ 1): the ray passes
        // through the triangle where it is ≥ 0 (the scalar test's three comparisons: in range,
        // u and v are finite, never NaN) and just outside an edge where it is ≥ −NEAR_EDGE.
        let least = u.min(v).min(Vec4::ONE - (u + v));
        let hit = in_range & least.cmpge(Vec4::ZERO);
        let loose = in_range & least.cmpge(Vec4::splat(-NEAR_EDGE));
        let hits = hit.bitmask();
        Lanes {
            t: Vec4::select(hit, t, Vec4::INFINITY),
            u,
            v,
            near: loose.bitmask() & !hits,
            t_raw: t,
        }
    }
}

/// How far outside a triangle's edges (in barycentric units) a ray may pass and still be
/// handed to the watertight edge test: 2⁻¹⁰. The barycentric test rounds differently on the
/// two triangles of a shared edge, so a ray within rounding of the edge can miss both (from a
/// point 1 µm in front of a tilted quad's centre, 7 rays in 16 607 passed through its
/// diagonal: few, but each carries direct light at 1 µm). The rounding of u and v is a few
/// ulps times |o − v₀| over the triangle's height, well below this unless a triangle is
/// 10⁴ times smaller than its distance from the origin.
pub(crate) const NEAR_EDGE: f32 = 1.0 / 1024.0;

/// What [`Tri4::intersect`] found in the four lanes of a packet.
pub(crate) struct Lanes {
    /// Distance of each lane's hit in units of |d|, +∞ for a miss.
    pub(crate) t: Vec4,
    /// Barycentric u of the ray's meeting point with each lane's plane.
    pub(crate) u: Vec4,
    /// Barycentric v of the ray's meeting point with each lane's plane.
    pub(crate) v: Vec4,
    /// Bit k: lane k's plane is met within range but just outside its edges (within
    /// [`NEAR_EDGE`]).
    pub(crate) near: u32,
    /// The distance of each lane's meeting point with its plane (valid for `near` lanes).
    pub(crate) t_raw: Vec4,
}

/// The 4-wide BVH: nodes (the root first), leaf packets, and which triangle each lane holds.
pub(crate) struct Bvh4 {
    pub(crate) nodes: Vec<Node4>,
    pub(crate) tris: Vec<Tri4>,
    /// Packet lane (4·packet + lane) → index into the triangles the tree was built over, or
    /// [`PADDING`].
    pub(crate) order: Vec<u32>,
}

/// A ray prepared for the box test: origin, clamped reciprocal direction, and for each axis
/// which plane of a box it meets first.
pub(crate) struct BoxRay {
    o: [Vec4; 3],
    d: [Vec4; 3],
    inv: [Vec4; 3],
    near: [usize; 3],
    far: [usize; 3],
}

impl BoxRay {
    /// The ray `origin + t·dir` (metres; `t` in units of |dir|).
    #[inline(always)]
    pub(crate) fn new(origin: Vec3A, dir: Vec3A) -> BoxRay {
        // A reciprocal clamped to ±f32::MAX rather than ±∞: a zero component then gives
        // 0·MAX = 0 (not NaN) for a plane through the origin, and MAX·|difference| overflows
        // to the infinity of the right sign for any other plane, as 1/0 would.
        let inv = (Vec3A::ONE / dir).clamp(Vec3A::splat(-f32::MAX), Vec3A::splat(f32::MAX));
        // Planes are ordered by the reciprocal's sign, not the direction's: 1/(−0) = −∞ is
        // negative while −0 < 0 is false, and ordering by the latter swapped near and far and
        // missed every box (tests/signed_zero.rs in bdpm-geometry).
        let neg = inv.cmplt(Vec3A::ZERO).bitmask() as usize;
        let s = [neg & 1, (neg >> 1) & 1, (neg >> 2) & 1];
        BoxRay {
            o: [
                Vec4::splat(origin.x),
                Vec4::splat(origin.y),
                Vec4::splat(origin.z),
            ],
            d: [Vec4::splat(dir.x), Vec4::splat(dir.y), Vec4::splat(dir.z)],
            inv: [Vec4::splat(inv.x), Vec4::splat(inv.y), Vec4::splat(inv.z)],
            near: [s[0], 2 + s[1], 4 + s[2]],
            far: [1 - s[0], 3 - s[1], 5 - s[2]],
        }
    }

    /// Entry distances of the four children and the mask of those the segment `[0, tmax]`
    /// may touch (conservatively, see [`GROW`]).
    #[inline(always)]
    fn hits(&self, node: &Node4, tmax: f32) -> (Vec4, u32) {
        let p = &node.planes;
        let tx0 = (p[self.near[0]] - self.o[0]) * self.inv[0];
        let ty0 = (p[self.near[1]] - self.o[1]) * self.inv[1];
        let tz0 = (p[self.near[2]] - self.o[2]) * self.inv[2];
        let tx1 = (p[self.far[0]] - self.o[0]) * self.inv[0];
        let ty1 = (p[self.far[1]] - self.o[1]) * self.inv[1];
        let tz1 = (p[self.far[2]] - self.o[2]) * self.inv[2];
        let enter = tx0.max(ty0).max(tz0).max(Vec4::ZERO);
        let exit = tx1.min(ty1).min(tz1).min(Vec4::splat(tmax)) * GROW;
        (enter, enter.cmple(exit).bitmask())
    }
}

/// Children of one node taken for traversal, in order of entry distance.
#[derive(Clone, Copy)]
struct Entry {
    child: u32,
    t: f32,
}

impl Bvh4 {
    /// Bytes of the nodes, leaf triangles and leaf order: their lengths, not the capacities
    /// `collapse` reserves for the worst case (one triangle a leaf), whose pages beyond the
    /// length are never written and so never resident (shrinking them would copy).
    pub(crate) fn bytes(&self) -> u64 {
        (self.nodes.len() * size_of::<Node4>()
            + self.tris.len() * size_of::<Tri4>()
            + self.order.len() * size_of::<u32>()) as u64
    }

    /// Number of node levels (1 for a root alone).
    pub(crate) fn depth(&self) -> usize {
        fn walk(nodes: &[Node4], i: usize) -> usize {
            1 + nodes[i]
                .child
                .iter()
                .filter(|&&c| c & LEAF_BIT == 0)
                .map(|&c| walk(nodes, c as usize))
                .max()
                .unwrap_or(0)
        }
        walk(&self.nodes, 0)
    }

    /// Visits leaves the segment `[0, tmax]` may touch (nearest entry first if `ordered`),
    /// skipping those beyond the current `tmax`; `leaf(packet, &mut tmax)` tests a leaf's
    /// packet, lowers `tmax` to a hit, and returns true to stop.
    #[inline(always)]
    pub(crate) fn traverse(
        &self,
        ray: &BoxRay,
        mut tmax: f32,
        ordered: bool,
        mut leaf: impl FnMut(usize, &mut f32) -> bool,
    ) {
        // Uninitialised: clearing 768 bytes per ray would cost as much as a node test.
        let mut stack = [const { MaybeUninit::<Entry>::uninit() }; STACK];
        let mut sp = 0usize;
        let mut cur = 0u32;
        loop {
            if cur & LEAF_BIT == 0 {
                let node = &self.nodes[cur as usize];
                let (enter, mut mask) = ray.hits(node, tmax);
                if mask != 0 {
                    let enter = enter.to_array();
                    if mask & (mask - 1) == 0 {
                        cur = node.child[mask.trailing_zeros() as usize];
                        continue;
                    }
                    // Two to four children: sort them by entry distance (insertion sort on at
                    // most four), descend into the nearest and push the others far to near.
                    let mut hit = [Entry { child: 0, t: 0.0 }; 4];
                    let mut n = 0;
                    while mask != 0 {
                        let k = mask.trailing_zeros() as usize;
                        mask &= mask - 1;
                        let e = Entry {
                            child: node.child[k],
                            t: enter[k],
                        };
                        let mut j = n;
                        if ordered {
                            while j > 0 && hit[j - 1].t > e.t {
                                hit[j] = hit[j - 1];
                                j -= 1;
                            }
                        }
                        hit[j] = e;
                        n += 1;
                    }
                    for e in hit[1..n].iter().rev() {
                        stack[sp] = MaybeUninit::new(*e);
                        sp += 1;
                    }
                    cur = hit[0].child;
                    continue;
                }
            } else {
                if leaf((cur & !LEAF_BIT) as usize, &mut tmax) {
                    return;
                }
            }
            // Pop the nearest pending child that may still hold a nearer hit.
            loop {
                if sp == 0 {
                    return;
                }
                sp -= 1;
                // SAFETY: entries below `sp` were all written by the pushes above (a bounds
                // check guards every write), and `sp` only counts writes not yet popped.
                let e = unsafe { stack[sp].assume_init() };
                if e.t <= tmax * GROW {
                    cur = e.child;
                    break;
                }
            }
        }
    }
}

/// The 4-wide tree over the binary tree `bvh2` (one triangle per leaf, each node's triangles a
/// contiguous range of `bvh2.primitive_indices`, children after their parent) built over
/// `tris` (metres).
pub(crate) fn collapse(bvh2: &Bvh2, tris: &[[glam::Vec3; 3]]) -> Bvh4 {
    let b = &bvh2.nodes;
    // Triangle range (first, count) of every binary node; children come after parents, so a
    // backward sweep sees both children of a node before it.
    let mut range = vec![(0u32, 0u32); b.len()];
    for i in (0..b.len()).rev() {
        range[i] = if b[i].prim_count > 0 {
            (b[i].first_index, b[i].prim_count)
        } else {
            let l = range[b[i].first_index as usize];
            let r = range[b[i].first_index as usize + 1];
            (l.0.min(r.0), l.1 + r.1)
        };
    }
    let mut out = Bvh4 {
        nodes: Vec::with_capacity(b.len() / 4 + 1),
        tris: Vec::with_capacity(b.len() / 4 + 1),
        order: Vec::with_capacity(b.len() / 2 + 4),
    };
    emit(bvh2, tris, &range, 0, &mut out);
    assert!(
        out.tris.len() < LEAF_BIT as usize,
        "too many leaves for the 4-wide BVH"
    );
    out
}

/// Emits the wide node for binary node `i` (and its subtree); returns its index.
fn emit(
    bvh2: &Bvh2,
    tris: &[[glam::Vec3; 3]],
    range: &[(u32, u32)],
    i: usize,
    out: &mut Bvh4,
) -> u32 {
    let b = &bvh2.nodes;
    let slot = out.nodes.len();
    out.nodes.push(Node4::UNUSED);
    let mut kids: Vec<usize> = if b[i].prim_count > 0 {
        vec![i]
    } else {
        let l = b[i].first_index as usize;
        vec![l, l + 1]
    };
    // Pull up the children of the largest inner child until there are four: large boxes are
    // the ones most rays enter, so splitting them tightens the test most. A child small enough
    // to be a leaf is kept whole: splitting it leaves lanes of two packets empty, and was no
    // faster on the 130k-triangle mesh (docs/performance.md, round two).
    while kids.len() < 4 {
        let best = kids
            .iter()
            .enumerate()
            .filter(|&(_, &c)| b[c].prim_count == 0 && range[c].1 > MAX_LEAF)
            .max_by(|x, y| {
                b[*x.1]
                    .aabb
                    .half_area()
                    .total_cmp(&b[*y.1].aabb.half_area())
            })
            .map(|(k, _)| k);
        let Some(k) = best else { break };
        let l = b[kids[k]].first_index as usize;
        kids.splice(k..=k, [l, l + 1]);
    }
    let mut node = Node4::UNUSED;
    for (k, &c) in kids.iter().enumerate() {
        let bb = b[c].aabb;
        node.planes[0][k] = bb.min.x;
        node.planes[1][k] = bb.max.x;
        node.planes[2][k] = bb.min.y;
        node.planes[3][k] = bb.max.y;
        node.planes[4][k] = bb.min.z;
        node.planes[5][k] = bb.max.z;
        let (first, count) = range[c];
        node.child[k] = if count <= MAX_LEAF {
            let packet = out.tris.len();
            let mut tri4 = Tri4::EMPTY;
            for lane in 0..4u32 {
                if lane < count {
                    let j = bvh2.primitive_indices[(first + lane) as usize];
                    tri4.set(lane as usize, tris[j as usize]);
                    out.order.push(j);
                } else {
                    out.order.push(PADDING);
                }
            }
            out.tris.push(tri4);
            LEAF_BIT | packet as u32
        } else {
            emit(bvh2, tris, range, c, out)
        };
    }
    out.nodes[slot] = node;
    slot as u32
}
