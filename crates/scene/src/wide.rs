//! A four-wide bounding-volume hierarchy for closest-hit ray casting.
//!
//! Collapsed from the binary SAH tree of [`crate::bvh`] (Wald et al. 2008, "Getting
//! rid of packets"): each node holds the boxes of up to four children side by side
//! (structure of arrays), so one ray meets all four with a single set of
//! four-lane slab tests ([`wide::f32x4`], safe SIMD). The near and far planes of
//! each axis are picked once per ray from the sign of its direction, hit children
//! are visited nearest first, and farther ones wait on an explicit stack with their
//! entry distances, dropped when a closer hit has been found meanwhile.
//!
//! Incoherent rays make the walk memory-bound (most node visits miss the cache),
//! so batches ([`Bvh4::closest_hits`]) walk [`INTERLEAVE`] rays in turn, one node
//! each, each ray prefetching the node or leaf it will visit next: the misses of
//! independent rays overlap instead of following one another (in the manner of
//! asynchronous memory-access chaining, Kocberber et al. 2015).
//!
//! The leaves are the binary tree's leaves; what a leaf holds is the caller's
//! business: [`Bvh4::from_binary`] asks the caller for a 31-bit payload per leaf and
//! [`Bvh4::closest_hit`] hands that payload back when a ray reaches the leaf.

use crate::bvh::{Aabb32, Bvh, MAX_DEPTH, RayF32};
use geom::InvariantViolation;
use wide::{CmpLe, f32x4};

/// Set in a child reference that names a leaf (the other 31 bits are its payload).
pub const LEAF: u32 = 1 << 31;
/// The reference of an unused child slot; its box is empty, so no ray enters it.
pub const NO_CHILD: u32 = u32::MAX;

/// A box grown by about eight units in the last place of its coordinates
/// (relative 2⁻²⁰, plus 10⁻⁹ m near zero). A ray running exactly along a face of
/// a tight box (a zero direction component, as on an axis-aligned structure)
/// would otherwise leave the face's slab at `t = 0` and miss the triangles lying
/// on that face, and rounding in the slab products could drop grazing hits; the
/// triangle test, not the box, decides a hit. Monotone, so children stay inside
/// their parents.
fn padded(b: &Aabb32) -> Aabb32 {
    const REL: f32 = 1.0 / (1u32 << 20) as f32;
    const ABS: f32 = 1e-9;
    let pad = |v: f32| {
        if v.is_finite() {
            v.abs() * REL + ABS
        } else {
            0.0
        }
    };
    Aabb32 {
        min: b.min.map(|v| v - pad(v)),
        max: b.max.map(|v| v + pad(v)),
    }
}

/// Up to four children: their boxes lane by lane, and what they are.
/// 112 bytes padded to two whole cache lines, so a visit never touches a third.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
pub struct Node4 {
    /// Lowest x, y, z then highest x, y, z of the four child boxes (lane k is
    /// child k). Unused lanes hold the empty box (+∞ lows, −∞ highs).
    planes: [f32x4; 6],
    /// Node index, `LEAF | payload`, or [`NO_CHILD`], per lane.
    child: [u32; 4],
}

impl Node4 {
    const EMPTY: Self = Self {
        planes: [
            f32x4::new([f32::INFINITY; 4]),
            f32x4::new([f32::INFINITY; 4]),
            f32x4::new([f32::INFINITY; 4]),
            f32x4::new([f32::NEG_INFINITY; 4]),
            f32x4::new([f32::NEG_INFINITY; 4]),
            f32x4::new([f32::NEG_INFINITY; 4]),
        ],
        child: [NO_CHILD; 4],
    };

    /// The box of lane `k` (`k < 4`).
    pub fn child_box(&self, k: usize) -> Aabb32 {
        let p = self.planes.map(|v| v.to_array()[k & 3]);
        Aabb32 {
            min: [p[0], p[1], p[2]],
            max: [p[3], p[4], p[5]],
        }
    }

    /// The reference of lane `k` (`k < 4`).
    pub fn child(&self, k: usize) -> u32 {
        self.child[k & 3]
    }

    fn set(&mut self, lane: usize, b: &Aabb32, child: u32) {
        for axis in 0..3 {
            let mut lo = self.planes[axis].to_array();
            let mut hi = self.planes[axis + 3].to_array();
            lo[lane] = b.min[axis];
            hi[lane] = b.max[axis];
            self.planes[axis] = f32x4::from(lo);
            self.planes[axis + 3] = f32x4::from(hi);
        }
        self.child[lane] = child;
    }
}

/// A ray prepared for four-lane box tests.
#[derive(Clone, Copy, Debug)]
struct Ray4 {
    origin: [f32x4; 3],
    inv_dir: [f32x4; 3],
    /// Index in [`Node4::planes`] of the plane each axis enters by.
    near: [usize; 3],
    /// Index of the plane each axis leaves by.
    far: [usize; 3],
}

impl Ray4 {
    #[inline]
    fn new(ray: &RayF32) -> Self {
        let mut near = [0, 1, 2];
        let mut far = [3, 4, 5];
        for axis in 0..3 {
            if ray.inv_dir[axis] < 0.0 {
                near[axis] += 3;
                far[axis] -= 3;
            }
        }
        Self {
            origin: ray.origin.map(f32x4::splat),
            inv_dir: ray.inv_dir.map(f32x4::splat),
            near,
            far,
        }
    }

    /// Entry distances of the four child boxes, and the mask (bit k = lane k) of
    /// those entered before `t_max`.
    #[inline]
    fn enter(&self, n: &Node4, t_max: f32x4) -> (f32x4, i32) {
        let p = &n.planes;
        let slab = |plane: usize, axis: usize| (p[plane] - self.origin[axis]) * self.inv_dir[axis];
        let t_near = slab(self.near[0], 0)
            .fast_max(slab(self.near[1], 1))
            .fast_max(slab(self.near[2], 2))
            .fast_max(f32x4::ZERO);
        let t_far = slab(self.far[0], 0)
            .fast_min(slab(self.far[1], 1))
            .fast_min(slab(self.far[2], 2))
            .fast_min(t_max);
        (t_near, t_near.cmp_le(t_far).move_mask())
    }
}

/// The four-wide hierarchy. Node 0 is the root; a tree over no primitives has
/// no nodes.
#[derive(Clone, Debug, Default)]
pub struct Bvh4 {
    nodes: Vec<Node4>,
}

/// What [`Bvh4::closest_hit`] does at the leaves.
pub trait LeafTest {
    /// The closest primitive hit of leaf `payload` along `ray` no farther than
    /// `t_best`: `(id, t)`.
    fn test(&mut self, ray: &RayF32, payload: u32, t_best: f32) -> Option<(u32, f32)>;

    /// Ask the cache for the leaf's data, which will be tested soon.
    fn prefetch(&self, _payload: u32) {}
}

/// Ask the cache for the line holding `x` (a no-op where not supported).
#[inline]
pub fn prefetch<T>(x: &T) {
    #[cfg(target_arch = "x86_64")]
    safe_arch::prefetch_t0(x);
    #[cfg(not(target_arch = "x86_64"))]
    let _ = x;
}

/// Rays walked in turn by [`Bvh4::closest_hits`].
pub const INTERLEAVE: usize = 16;

/// The state of one ray's walk down the tree.
#[derive(Clone, Debug)]
struct Walk {
    ray: RayF32,
    r4: Ray4,
    /// The reference to visit next.
    cur: u32,
    best_t: f32,
    best: Option<u32>,
    stack: Stack,
}

impl Walk {
    #[inline]
    fn new(ray: RayF32, t_max: f32, mut stack: Stack) -> Self {
        stack.clear();
        Self {
            r4: Ray4::new(&ray),
            ray,
            cur: 0,
            best_t: t_max,
            best: None,
            stack,
        }
    }

    #[inline]
    fn result(&self) -> Option<(u32, f32)> {
        self.best.map(|id| (id, self.best_t))
    }
}

/// A traversal stack: (child reference, entry distance). Reuse one across rays
/// to keep allocation out of the loop.
pub type Stack = Vec<(u32, f32)>;

impl Bvh4 {
    /// Collapse a binary tree: every node takes the (up to) four descendants
    /// reached by repeatedly opening its inner child of largest surface area.
    /// `payload(first, count)` names each binary leaf (its slot range in
    /// [`Bvh::prim_indices`]) by a value below [`LEAF`]; `None` when a payload
    /// does not fit in 31 bits.
    pub fn from_binary(bvh: &Bvh, mut payload: impl FnMut(u32, u32) -> u32) -> Option<Self> {
        if bvh.is_empty() {
            return Some(Self::default());
        }
        let mut nodes = vec![Node4::EMPTY];
        // (binary node, wide node to fill)
        let mut work = vec![(0usize, 0usize)];
        while let Some((b, w)) = work.pop() {
            let bn = bvh.nodes.get(b)?;
            let mut kids = [0usize; 4];
            let mut len = 1;
            if bn.count == 0 {
                kids[0] = bn.first as usize;
                kids[1] = bn.first as usize + 1;
                len = 2;
            } else {
                kids[0] = b;
            }
            while len < 4 {
                let mut pick: Option<(usize, f32)> = None;
                for (i, &k) in kids[..len].iter().enumerate() {
                    let kn = bvh.nodes.get(k)?;
                    if kn.count == 0 {
                        let area = Aabb32 {
                            min: kn.min,
                            max: kn.max,
                        }
                        .half_area();
                        if pick.is_none_or(|(_, a)| area > a) {
                            pick = Some((i, area));
                        }
                    }
                }
                let Some((i, _)) = pick else { break };
                let first = bvh.nodes.get(kids[i])?.first as usize;
                kids[i] = first;
                kids[len] = first + 1;
                len += 1;
            }
            for (lane, &k) in kids[..len].iter().enumerate() {
                let kn = bvh.nodes.get(k)?;
                let b = padded(&Aabb32 {
                    min: kn.min,
                    max: kn.max,
                });
                let child = if kn.count > 0 {
                    let p = payload(kn.first, kn.count);
                    if p >= LEAF {
                        return None;
                    }
                    LEAF | p
                } else {
                    let idx = u32::try_from(nodes.len()).ok().filter(|&i| i < LEAF)?;
                    nodes.push(Node4::EMPTY);
                    work.push((k, idx as usize));
                    idx
                };
                nodes[w].set(lane, &b, child);
            }
        }
        Some(Self { nodes })
    }

    /// The nodes (node 0 is the root).
    pub fn nodes(&self) -> &[Node4] {
        &self.nodes
    }

    /// Closest hit along `ray` up to `t_max`: calls [`LeafTest::test`] for the
    /// leaves whose boxes the ray enters, nearest box first. The first hit found
    /// is kept even at exactly `t_max` (closed intervals work), later ones only
    /// when strictly closer. Returns the winning id and distance.
    #[inline]
    pub fn closest_hit<L: LeafTest>(
        &self,
        ray: &RayF32,
        t_max: f32,
        stack: &mut Stack,
        leaf: &mut L,
    ) -> Option<(u32, f32)> {
        if self.nodes.is_empty() {
            return None;
        }
        stack.clear();
        let mut walk = Walk::new(*ray, t_max, std::mem::take(stack));
        while self.step(&mut walk, leaf) {}
        *stack = std::mem::take(&mut walk.stack);
        walk.result()
    }

    /// [`Bvh4::closest_hit`] for many rays: `out[i]` receives ray `i`'s hit
    /// (`out` as long as `rays`). [`INTERLEAVE`] rays are walked in turn, one node
    /// each, and each prefetches the node it will visit next, so the cache misses
    /// of independent rays overlap instead of following one another (the walk is
    /// memory-bound for incoherent rays). Same results as one ray at a time.
    pub fn closest_hits<L: LeafTest>(
        &self,
        rays: &[RayF32],
        t_max: f32,
        leaf: &mut L,
        out: &mut [Option<(u32, f32)>],
    ) {
        if self.nodes.is_empty() {
            out.fill(None);
            return;
        }
        let n = rays.len().min(out.len());
        let mut lanes: Vec<(usize, Walk)> = (0..n.min(INTERLEAVE))
            .map(|i| (i, Walk::new(rays[i], t_max, Vec::with_capacity(64))))
            .collect();
        let mut next = lanes.len();
        while !lanes.is_empty() {
            let mut k = 0;
            while k < lanes.len() {
                let (id, walk) = &mut lanes[k];
                if self.step(walk, leaf) {
                    k += 1;
                    continue;
                }
                out[*id] = walk.result();
                if next < n {
                    let stack = std::mem::take(&mut walk.stack);
                    *walk = Walk::new(rays[next], t_max, stack);
                    *id = next;
                    next += 1;
                    k += 1;
                } else {
                    lanes.swap_remove(k);
                }
            }
        }
    }

    /// One visit: test the current node's children or the current leaf, choose
    /// the next reference (nearest entered child, else the stack) and prefetch it.
    /// `false` when the walk is over.
    #[inline]
    fn step<L: LeafTest>(&self, w: &mut Walk, leaf: &mut L) -> bool {
        let cur = w.cur;
        if cur & LEAF == 0 {
            if let Some(n) = self.nodes.get(cur as usize) {
                let (t_near, mask) = w.r4.enter(n, f32x4::splat(w.best_t));
                if mask != 0 {
                    if mask & (mask - 1) == 0 {
                        w.cur = n.child[mask.trailing_zeros() as usize & 3];
                        self.prefetch(w.cur, leaf);
                        return true;
                    }
                    // Several: push them farthest first, go on with the nearest.
                    let d = t_near.to_array();
                    let base = w.stack.len();
                    let mut m = mask;
                    while m != 0 {
                        let k = m.trailing_zeros() as usize & 3;
                        m &= m - 1;
                        let e = (n.child[k], d[k]);
                        w.stack.push(e);
                        let mut j = w.stack.len() - 1;
                        while j > base && w.stack[j - 1].1 < e.1 {
                            w.stack.swap(j - 1, j);
                            j -= 1;
                        }
                    }
                    if let Some((c, _)) = w.stack.pop() {
                        w.cur = c;
                        self.prefetch(c, leaf);
                        return true;
                    }
                }
            }
        } else if let Some((id, t)) = leaf.test(&w.ray, cur & !LEAF, w.best_t)
            && (t < w.best_t || (w.best.is_none() && t <= w.best_t))
        {
            w.best_t = t;
            w.best = Some(id);
        }
        // Pop the next child still worth visiting.
        while let Some((c, d)) = w.stack.pop() {
            if d <= w.best_t {
                w.cur = c;
                self.prefetch(c, leaf);
                return true;
            }
        }
        false
    }

    /// Prefetch what a child reference points to.
    #[inline]
    fn prefetch<L: LeafTest>(&self, c: u32, leaf: &L) {
        if c & LEAF != 0 {
            leaf.prefetch(c & !LEAF);
        } else if let Some(node) = self.nodes.get(c as usize) {
            prefetch(node);
            prefetch(&node.planes[4]);
        }
    }

    /// Check the structure: every node is reached once from the root, every box
    /// lies inside its parent's box, unused lanes are empty, the depth is at most
    /// [`MAX_DEPTH`]; `leaf(payload, leaf_box)` checks each leaf (it is called
    /// once per leaf reached).
    pub fn check_invariants(
        &self,
        leaf: impl FnMut(u32, &Aabb32) -> Result<(), String>,
    ) -> Result<(), InvariantViolation> {
        self.invariant_detail(leaf)
            .map_err(|d| InvariantViolation::new("four-wide BVH", d))
    }

    /// The check of [`check_invariants`](Self::check_invariants), the failure as text.
    pub(crate) fn invariant_detail(
        &self,
        mut leaf: impl FnMut(u32, &Aabb32) -> Result<(), String>,
    ) -> Result<(), String> {
        if self.nodes.is_empty() {
            return Ok(());
        }
        let mut seen = vec![false; self.nodes.len()];
        let mut stack: Vec<(usize, Option<Aabb32>, usize)> = vec![(0, None, 0)];
        while let Some((i, parent, depth)) = stack.pop() {
            if depth > MAX_DEPTH {
                return Err(format!("wide node {i} at depth {depth} > {MAX_DEPTH}"));
            }
            let n = self.nodes.get(i).ok_or(format!("wide node {i} missing"))?;
            if std::mem::replace(&mut seen[i], true) {
                return Err(format!("wide node {i} reached twice"));
            }
            for k in 0..4 {
                let b = n.child_box(k);
                let c = n.child[k];
                if c == NO_CHILD {
                    if (0..3).any(|a| b.min[a] <= b.max[a]) {
                        return Err(format!("unused lane {k} of wide node {i} has a box"));
                    }
                    continue;
                }
                if let Some(p) = parent
                    && !p.contains(&b)
                {
                    return Err(format!(
                        "lane {k} of wide node {i} sticks out of its parent"
                    ));
                }
                if c & LEAF != 0 {
                    leaf(c & !LEAF, &b)?;
                } else {
                    stack.push((c as usize, Some(b), depth + 1));
                }
            }
        }
        match seen.iter().position(|s| !s) {
            Some(i) => Err(format!("wide node {i} unreachable")),
            None => Ok(()),
        }
    }
}
