//! A bounding-volume hierarchy for ray and box queries.
//!
//! Binned surface-area-heuristic build (Wald 2007, 16 bins per axis), nodes of 32
//! bytes in single precision with the two children of a node stored next to each
//! other, and an ordered front-to-back traversal with a small fixed stack. The
//! hierarchy is generic: it stores primitive indices, and queries take a closure
//! that tests one primitive, so the same code serves triangles ([`crate::Scene`])
//! and points within ε of a ray ([`crate::PointCloudWorld`]).
//!
//! Single precision is deliberate: half the memory traffic of `f64` boxes for
//! distances of a few metres, where `f32` still resolves a tenth of a micrometre;
//! callers that need more refine the hit in `f64`.

use geom::{Aabb, InvariantViolation};
use std::ops::ControlFlow;

/// An axis-aligned box in single precision.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb32 {
    /// Lowest corner.
    pub min: [f32; 3],
    /// Highest corner.
    pub max: [f32; 3],
}

impl Aabb32 {
    /// The empty box.
    pub const EMPTY: Self = Self {
        min: [f32::INFINITY; 3],
        max: [f32::NEG_INFINITY; 3],
    };

    /// Grow to include `p`.
    #[inline]
    pub fn grow_point(&mut self, p: [f32; 3]) {
        for ((lo, hi), v) in self.min.iter_mut().zip(&mut self.max).zip(p) {
            *lo = lo.min(v);
            *hi = hi.max(v);
        }
    }

    /// Grow to include `b`.
    #[inline]
    pub fn grow(&mut self, b: &Self) {
        for i in 0..3 {
            self.min[i] = self.min[i].min(b.min[i]);
            self.max[i] = self.max[i].max(b.max[i]);
        }
    }

    /// Half the surface area (0 for an empty box); the SAH only needs ratios.
    #[inline]
    pub fn half_area(&self) -> f32 {
        let e = [
            self.max[0] - self.min[0],
            self.max[1] - self.min[1],
            self.max[2] - self.min[2],
        ];
        if e[0] < 0.0 || e[1] < 0.0 || e[2] < 0.0 {
            return 0.0;
        }
        e[0] * e[1] + e[1] * e[2] + e[2] * e[0]
    }

    /// The box in double precision, rounded outwards so it contains the original.
    pub fn to_f64(&self) -> Aabb {
        let lo = |v: f32| f64::from(v) - f64::from(v.abs()) * 1e-7 - 1e-12;
        let hi = |v: f32| f64::from(v) + f64::from(v.abs()) * 1e-7 + 1e-12;
        Aabb {
            min: geom::Point3::new(lo(self.min[0]), lo(self.min[1]), lo(self.min[2])),
            max: geom::Point3::new(hi(self.max[0]), hi(self.max[1]), hi(self.max[2])),
        }
    }

    /// A single-precision box containing `b` (rounded outwards).
    pub fn from_f64(b: &Aabb) -> Self {
        let down = |v: f64| {
            let f = v as f32;
            if f64::from(f) > v { f.next_down() } else { f }
        };
        let up = |v: f64| {
            let f = v as f32;
            if f64::from(f) < v { f.next_up() } else { f }
        };
        Self {
            min: [down(b.min.x), down(b.min.y), down(b.min.z)],
            max: [up(b.max.x), up(b.max.y), up(b.max.z)],
        }
    }

    /// `true` when the boxes share a point.
    #[inline]
    pub fn intersects(&self, o: &Self) -> bool {
        (0..3).all(|i| self.min[i] <= o.max[i] && o.min[i] <= self.max[i])
    }

    /// `true` when `o` lies inside this box.
    pub fn contains(&self, o: &Self) -> bool {
        (0..3).all(|i| self.min[i] <= o.min[i] && o.max[i] <= self.max[i])
    }
}

/// One node: a box, and either two children (`count == 0`, children at
/// `first` and `first + 1`) or a leaf of `count` primitives starting at `first`
/// in [`Bvh::prim_indices`].
#[derive(Clone, Copy, Debug)]
#[repr(C)]
pub struct BvhNode {
    /// Lowest corner.
    pub min: [f32; 3],
    /// First child (inner node) or first primitive slot (leaf).
    pub first: u32,
    /// Highest corner.
    pub max: [f32; 3],
    /// Number of primitives (0 for an inner node).
    pub count: u32,
}

/// A ray prepared for box tests in single precision.
#[derive(Clone, Copy, Debug)]
pub struct RayF32 {
    /// Origin.
    pub origin: [f32; 3],
    /// Unit direction.
    pub dir: [f32; 3],
    /// Component-wise reciprocal of the direction, with zero components
    /// replaced by ±1e-20 so the reciprocal stays finite (no `0 · ∞` NaNs in the
    /// slab test).
    pub inv_dir: [f32; 3],
}

impl RayF32 {
    /// Prepare a ray.
    #[inline]
    pub fn new(origin: [f32; 3], dir: [f32; 3]) -> Self {
        let safe = |d: f32| {
            if d.abs() < 1e-20 {
                1e-20f32.copysign(d)
            } else {
                d
            }
        };
        let inv_dir = [1.0 / safe(dir[0]), 1.0 / safe(dir[1]), 1.0 / safe(dir[2])];
        Self {
            origin,
            dir,
            inv_dir,
        }
    }

    /// From a double-precision ray.
    #[inline]
    pub fn from_ray(ray: &geom::Ray) -> Self {
        Self::new(
            [
                ray.origin.x as f32,
                ray.origin.y as f32,
                ray.origin.z as f32,
            ],
            [ray.dir.x as f32, ray.dir.y as f32, ray.dir.z as f32],
        )
    }

    /// Entry distance into the node's box if the ray meets it before `t_max`,
    /// else `f32::INFINITY`.
    #[inline]
    fn enter(&self, n: &BvhNode, t_max: f32) -> f32 {
        let tx0 = (n.min[0] - self.origin[0]) * self.inv_dir[0];
        let tx1 = (n.max[0] - self.origin[0]) * self.inv_dir[0];
        let ty0 = (n.min[1] - self.origin[1]) * self.inv_dir[1];
        let ty1 = (n.max[1] - self.origin[1]) * self.inv_dir[1];
        let tz0 = (n.min[2] - self.origin[2]) * self.inv_dir[2];
        let tz1 = (n.max[2] - self.origin[2]) * self.inv_dir[2];
        let tmin = tx0.min(tx1).max(ty0.min(ty1)).max(tz0.min(tz1)).max(0.0);
        let tmax = tx0.max(tx1).min(ty0.max(ty1)).min(tz0.max(tz1)).min(t_max);
        if tmin <= tmax { tmin } else { f32::INFINITY }
    }
}

/// The hierarchy: nodes plus the primitive order the leaves refer to.
#[derive(Clone, Debug, Default)]
pub struct Bvh {
    /// Nodes; node 0 is the root.
    pub nodes: Vec<BvhNode>,
    /// Primitive indices in leaf order.
    pub prim_indices: Vec<u32>,
}

/// Parameters of the binned-SAH build.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BuildParams {
    /// Bins per axis (at least 2).
    pub bins: usize,
    /// Largest leaf: larger sets are always split (by position, or by order when
    /// every centroid coincides).
    pub max_leaf: usize,
    /// Cost of a node visit relative to one primitive test, for the SAH.
    pub traversal_cost: f32,
    /// Primitives tested together in one step (SIMD lanes): the SAH counts a
    /// set of `n` primitives as `⌈n / block⌉` tests.
    pub block: usize,
}

impl Default for BuildParams {
    /// 16 bins, leaves of at most 8, a node visit as dear as a primitive test:
    /// the setting for scalar primitive tests ([`Bvh::closest_hit`]).
    fn default() -> Self {
        Self {
            bins: 16,
            max_leaf: 8,
            traversal_cost: 1.0,
            block: 1,
        }
    }
}

/// Largest number of bins [`BuildParams::bins`] may ask for.
pub const MAX_BINS: usize = 64;
/// Deepest tree [`Bvh::check_invariants`] accepts.
pub const MAX_DEPTH: usize = 64;
const STACK_SIZE: usize = MAX_DEPTH;

impl Bvh {
    /// Build over primitives with the given boxes and centroids (same length),
    /// with [`BuildParams::default`].
    pub fn build(bounds: &[Aabb32], centroids: &[[f32; 3]]) -> Self {
        Self::build_with(bounds, centroids, &BuildParams::default())
    }

    /// Build over primitives with the given boxes and centroids (same length).
    /// `params.bins` is clamped to `2..=MAX_BINS` and `params.max_leaf` to at least 1.
    pub fn build_with(bounds: &[Aabb32], centroids: &[[f32; 3]], params: &BuildParams) -> Self {
        debug_assert_eq!(bounds.len(), centroids.len());
        let params = BuildParams {
            bins: params.bins.clamp(2, MAX_BINS),
            max_leaf: params.max_leaf.max(1),
            traversal_cost: params.traversal_cost,
            block: params.block.max(1),
        };
        let n = bounds.len();
        let mut prim_indices: Vec<u32> = (0..n as u32).collect();
        if n == 0 {
            return Self {
                nodes: vec![BvhNode {
                    min: Aabb32::EMPTY.min,
                    first: 0,
                    max: Aabb32::EMPTY.max,
                    count: 0,
                }],
                prim_indices,
            };
        }
        let mut nodes: Vec<BvhNode> = Vec::with_capacity(2 * n);
        nodes.push(BvhNode {
            min: [0.0; 3],
            first: 0,
            max: [0.0; 3],
            count: 0,
        });
        // Work list of (node index, first prim slot, prim count).
        let mut work: Vec<(usize, usize, usize)> = vec![(0, 0, n)];
        while let Some((node, first, count)) = work.pop() {
            let slice = &mut prim_indices[first..first + count];
            let mut bbox = Aabb32::EMPTY;
            let mut cbox = Aabb32::EMPTY;
            for &p in slice.iter() {
                bbox.grow(&bounds[p as usize]);
                cbox.grow_point(centroids[p as usize]);
            }
            nodes[node].min = bbox.min;
            nodes[node].max = bbox.max;
            let split = if count <= 1 {
                None
            } else {
                best_split(slice, bounds, centroids, &cbox, bbox.half_area(), &params)
            };
            let mid = match split {
                Some((axis, pos)) => {
                    let mid = partition(slice, |p| centroids[p as usize][axis] < pos);
                    (mid != 0 && mid != count).then_some(mid)
                }
                None => None,
            };
            // A set too large for a leaf that the SAH cannot part (identical
            // centroids, or a threshold that rounds to one side) is split by order.
            let mid = mid.or((count > params.max_leaf).then_some(count / 2));
            if let Some(mid) = mid {
                let left = nodes.len();
                nodes[node].first = left as u32;
                nodes[node].count = 0;
                for _ in 0..2 {
                    nodes.push(BvhNode {
                        min: [0.0; 3],
                        first: 0,
                        max: [0.0; 3],
                        count: 0,
                    });
                }
                work.push((left + 1, first + mid, count - mid));
                work.push((left, first, mid));
            } else {
                nodes[node].first = first as u32;
                nodes[node].count = count as u32;
            }
        }
        Self {
            nodes,
            prim_indices,
        }
    }

    /// Number of primitives.
    pub fn len(&self) -> usize {
        self.prim_indices.len()
    }

    /// `true` when there are no primitives.
    pub fn is_empty(&self) -> bool {
        self.prim_indices.is_empty()
    }

    /// The root box (empty box when there are no primitives).
    pub fn bounds(&self) -> Aabb32 {
        let r = &self.nodes[0];
        Aabb32 {
            min: r.min,
            max: r.max,
        }
    }

    /// Closest hit along a ray: calls `hit(slot, t_best)` for candidate leaf slots
    /// (positions in [`Bvh::prim_indices`], in front-to-back box order); `hit`
    /// returns the hit distance when the primitive is hit no farther than
    /// `t_best`. The first hit found is kept even at exactly `t_max` (so closed
    /// intervals `[0, t_max]` work), later ones only when strictly closer.
    /// Returns the winning slot and distance.
    #[inline]
    pub fn closest_hit<F>(&self, ray: &RayF32, t_max: f32, mut hit: F) -> Option<(u32, f32)>
    where
        F: FnMut(u32, f32) -> Option<f32>,
    {
        if self.prim_indices.is_empty() {
            return None;
        }
        let mut best_t = t_max;
        let mut best: Option<u32> = None;
        let mut stack = [(0u32, 0.0f32); STACK_SIZE];
        let mut sp = 0usize;
        let root = &self.nodes[0];
        if ray.enter(root, best_t) == f32::INFINITY {
            return None;
        }
        let mut node = root;
        loop {
            if node.count > 0 {
                let start = node.first;
                for slot in start..start + node.count {
                    if let Some(t) = hit(slot, best_t)
                        && (t < best_t || (best.is_none() && t <= best_t))
                    {
                        best_t = t;
                        best = Some(slot);
                    }
                }
            } else {
                let c = node.first as usize;
                let (n0, n1) = (&self.nodes[c], &self.nodes[c + 1]);
                let mut d0 = ray.enter(n0, best_t);
                let mut d1 = ray.enter(n1, best_t);
                let (mut i0, mut i1) = (c as u32, c as u32 + 1);
                if d1 < d0 {
                    std::mem::swap(&mut d0, &mut d1);
                    std::mem::swap(&mut i0, &mut i1);
                }
                if d0 != f32::INFINITY {
                    if d1 != f32::INFINITY && sp < STACK_SIZE {
                        stack[sp] = (i1, d1);
                        sp += 1;
                    }
                    node = &self.nodes[i0 as usize];
                    continue;
                }
            }
            // Pop the next node still worth visiting.
            loop {
                if sp == 0 {
                    return best.map(|s| (s, best_t));
                }
                sp -= 1;
                let (i, d) = stack[sp];
                if d <= best_t {
                    node = &self.nodes[i as usize];
                    break;
                }
            }
        }
    }

    /// Visit every leaf slot whose primitive box may overlap `query` (leaf boxes
    /// are tested, primitive boxes are not). Stop early by returning
    /// `ControlFlow::Break`.
    pub fn query_aabb<B>(
        &self,
        query: &Aabb32,
        mut visit: impl FnMut(u32) -> ControlFlow<B>,
    ) -> Option<B> {
        if self.prim_indices.is_empty() {
            return None;
        }
        let mut stack = Vec::with_capacity(STACK_SIZE);
        stack.push(0usize);
        while let Some(i) = stack.pop() {
            let n = &self.nodes[i];
            let b = Aabb32 {
                min: n.min,
                max: n.max,
            };
            if !b.intersects(query) {
                continue;
            }
            if n.count > 0 {
                for slot in n.first..n.first + n.count {
                    if let ControlFlow::Break(v) = visit(slot) {
                        return Some(v);
                    }
                }
            } else {
                stack.push(n.first as usize + 1);
                stack.push(n.first as usize);
            }
        }
        None
    }

    /// Check the structure: every primitive appears in exactly one leaf, every
    /// child box lies inside its parent's, every leaf box contains its
    /// primitives' boxes, the tree depth fits the traversal stack.
    pub fn check_invariants(&self, bounds: &[Aabb32]) -> Result<(), InvariantViolation> {
        self.invariant_detail(bounds)
            .map_err(|d| InvariantViolation::new("BVH", d))
    }

    /// [`Bvh::check_invariants`], the failure as text.
    pub(crate) fn invariant_detail(&self, bounds: &[Aabb32]) -> Result<(), String> {
        if bounds.is_empty() && self.prim_indices.is_empty() {
            return Ok(());
        }
        if self.prim_indices.len() != bounds.len() {
            return Err(format!(
                "{} primitive slots for {} primitives",
                self.prim_indices.len(),
                bounds.len()
            ));
        }
        let mut seen = vec![false; bounds.len()];
        let mut stack = vec![(0usize, 0usize)];
        while let Some((i, depth)) = stack.pop() {
            if depth >= STACK_SIZE {
                return Err(format!("depth {depth} exceeds the traversal stack"));
            }
            let n = self.nodes.get(i).ok_or(format!("node {i} missing"))?;
            let nb = Aabb32 {
                min: n.min,
                max: n.max,
            };
            if n.count > 0 {
                for slot in n.first..n.first + n.count {
                    let p = *self
                        .prim_indices
                        .get(slot as usize)
                        .ok_or(format!("leaf {i} slot {slot} out of range"))?
                        as usize;
                    if std::mem::replace(&mut seen[p], true) {
                        return Err(format!("primitive {p} in two leaves"));
                    }
                    if !nb.contains(&bounds[p]) {
                        return Err(format!("leaf {i} box does not contain primitive {p}"));
                    }
                }
            } else {
                for c in [n.first as usize, n.first as usize + 1] {
                    let cn = self.nodes.get(c).ok_or(format!("child {c} missing"))?;
                    let cb = Aabb32 {
                        min: cn.min,
                        max: cn.max,
                    };
                    if !nb.contains(&cb) {
                        return Err(format!("node {c} sticks out of its parent {i}"));
                    }
                    stack.push((c, depth + 1));
                }
            }
        }
        match seen.iter().position(|s| !s) {
            Some(p) if !bounds.is_empty() => Err(format!("primitive {p} in no leaf")),
            _ => Ok(()),
        }
    }
}

/// Best SAH split `(axis, centroid threshold)`, or `None` when a leaf is cheaper
/// (and small enough) or the centroids coincide.
fn best_split(
    slice: &[u32],
    bounds: &[Aabb32],
    centroids: &[[f32; 3]],
    cbox: &Aabb32,
    parent_half_area: f32,
    params: &BuildParams,
) -> Option<(usize, f32)> {
    let count = slice.len();
    let bins = params.bins;
    let blocks = |n: u32| n.div_ceil(params.block as u32) as f32;
    let mut best_cost = f32::INFINITY;
    let mut best: Option<(usize, f32)> = None;
    #[allow(clippy::needless_range_loop)] // `axis` indexes boxes and centroids alike
    for axis in 0..3 {
        let lo = cbox.min[axis];
        let extent = cbox.max[axis] - lo;
        if extent <= 0.0 || !extent.is_finite() {
            continue;
        }
        let scale = bins as f32 / extent;
        let mut bin_box = [Aabb32::EMPTY; MAX_BINS];
        let mut bin_count = [0u32; MAX_BINS];
        for &p in slice {
            let b = (((centroids[p as usize][axis] - lo) * scale) as usize).min(bins - 1);
            bin_count[b] += 1;
            bin_box[b].grow(&bounds[p as usize]);
        }
        // Sweep from the left and from the right.
        let mut left_area = [0.0f32; MAX_BINS];
        let mut left_count = [0u32; MAX_BINS];
        let mut acc = Aabb32::EMPTY;
        let mut cnt = 0;
        for i in 0..bins - 1 {
            acc.grow(&bin_box[i]);
            cnt += bin_count[i];
            left_area[i] = acc.half_area();
            left_count[i] = cnt;
        }
        let mut acc = Aabb32::EMPTY;
        let mut cnt = 0;
        for i in (1..bins).rev() {
            acc.grow(&bin_box[i]);
            cnt += bin_count[i];
            let l = i - 1;
            if left_count[l] == 0 || cnt == 0 {
                continue;
            }
            let cost = blocks(left_count[l]) * left_area[l] + blocks(cnt) * acc.half_area();
            if cost < best_cost {
                best_cost = cost;
                best = Some((axis, lo + i as f32 / scale));
            }
        }
    }
    let leaf_cost = blocks(count as u32);
    let split_cost = if parent_half_area > 0.0 {
        params.traversal_cost + best_cost / parent_half_area
    } else {
        f32::INFINITY
    };
    if best.is_none() || (split_cost >= leaf_cost && count <= params.max_leaf) {
        return None;
    }
    best
}

/// Partition in place so that elements satisfying `left` come first; returns
/// their number.
fn partition(slice: &mut [u32], left: impl Fn(u32) -> bool) -> usize {
    let mut i = 0;
    let mut j = slice.len();
    while i < j {
        if left(slice[i]) {
            i += 1;
        } else {
            j -= 1;
            slice.swap(i, j);
        }
    }
    i
}

#[cfg(test)]
mod tests {
    use super::*;

    fn point_boxes(n: usize) -> (Vec<Aabb32>, Vec<[f32; 3]>) {
        let mut b = Vec::new();
        let mut c = Vec::new();
        for i in 0..n {
            let x = (i % 17) as f32 * 0.3;
            let y = (i % 5) as f32 * 0.7;
            let z = (i / 85) as f32 * 0.2;
            b.push(Aabb32 {
                min: [x - 0.1, y - 0.1, z - 0.1],
                max: [x + 0.1, y + 0.1, z + 0.1],
            });
            c.push([x, y, z]);
        }
        (b, c)
    }

    #[test]
    fn invariants_hold_for_various_sizes() {
        for n in [0, 1, 2, 3, 9, 100, 1000] {
            let (b, c) = point_boxes(n);
            let bvh = Bvh::build(&b, &c);
            bvh.check_invariants(&b).unwrap();
        }
        // Identical centroids force the split-by-order path.
        let b = vec![
            Aabb32 {
                min: [0.0; 3],
                max: [1.0; 3]
            };
            50
        ];
        let c = vec![[0.5; 3]; 50];
        let bvh = Bvh::build(&b, &c);
        bvh.check_invariants(&b).unwrap();
        // A primitive that moved out of its leaf's box is reported, typed.
        let (mut b, c) = point_boxes(100);
        let bvh = Bvh::build(&b, &c);
        b[37].min = [1e6; 3];
        b[37].max = [1e6 + 1.0; 3];
        let e = bvh.check_invariants(&b).unwrap_err();
        assert_eq!(e.structure, "BVH");
        assert!(e.to_string().contains("invariant violated"), "{e}");
    }

    #[test]
    fn aabb_query_finds_overlaps() {
        let (b, c) = point_boxes(500);
        let bvh = Bvh::build(&b, &c);
        let q = Aabb32 {
            min: [0.5, 0.5, 0.0],
            max: [1.5, 1.6, 0.5],
        };
        let mut found = Vec::new();
        let _: Option<()> = bvh.query_aabb(&q, |slot| {
            let p = bvh.prim_indices[slot as usize] as usize;
            if b[p].intersects(&q) {
                found.push(p);
            }
            ControlFlow::Continue(())
        });
        found.sort_unstable();
        let brute: Vec<usize> = (0..b.len()).filter(|&i| b[i].intersects(&q)).collect();
        assert_eq!(found, brute);
    }

    #[test]
    fn f64_round_trip_contains() {
        let b = Aabb {
            min: geom::Point3::new(0.1, -0.2, 1.0 / 3.0),
            max: geom::Point3::new(0.7, 0.3, 2.0 / 3.0),
        };
        let f = Aabb32::from_f64(&b);
        for i in 0..3 {
            assert!(f64::from(f.min[i]) <= b.min[i] && f64::from(f.max[i]) >= b.max[i]);
        }
    }
}
