//! The configuration-space roadmap (A§3.2.1.3, §3.2.3, §4.3): `n_Q` nodes
//! sampled uniformly within the joint limits, joined to their nearest
//! neighbours in the joint-weighted distance `Σ wᵢ |Δqᵢ|`, A* between poses
//! with every motion checked lazily against the map of the moment, and the
//! node usage likelihood `L(cᵢ)` from shortest paths between all pairs of
//! nodes (Fig. 4.7).

use crate::{PlanConfig, PlanError};
use geom::Real;
use petgraph::algo::{astar, dijkstra};
use petgraph::graph::{NodeIndex, UnGraph};
use petgraph::visit::{EdgeFiltered, EdgeRef};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use robot::{JointKind, Robot};
use rustc_hash::{FxHashMap as HashMap, FxHashSet as HashSet};
use serde::{Deserialize, Serialize};
use std::cell::RefCell;

/// Lazy searches of [`Roadmap::plan`] before it checks edges as A* meets them.
const LAZY_ROUNDS: usize = 32;

/// Decides whether configurations and straight joint-space motions are safe.
/// [`crate::SafetyChecker`] implements it against an occupancy grid; tests use
/// their own.
pub trait MotionChecker {
    /// `true` when the arm may stand at `q`.
    fn pose_ok(&mut self, q: &[Real]) -> bool;
    /// `true` when every configuration of the straight joint-space motion from
    /// `a` to `b` (both ends included) is safe.
    fn motion_ok(&mut self, a: &[Real], b: &[Real]) -> bool;
    /// `false` only when [`MotionChecker::motion_ok`] would be: a cheaper
    /// test, where the checker has one, that a search may run on many
    /// motions and confirm with `motion_ok` on the few of the path found.
    fn motion_may_be_ok(&mut self, a: &[Real], b: &[Real]) -> bool {
        self.motion_ok(a, b)
    }
    /// [`MotionChecker::pose_ok`] of each of `qs`, in order. The default
    /// asks one at a time; a checker whose answers depend on the
    /// configuration alone may answer them in parallel.
    fn poses_ok(&mut self, qs: &[&[Real]]) -> Vec<bool> {
        qs.iter().map(|q| self.pose_ok(q)).collect()
    }
    /// [`MotionChecker::motion_may_be_ok`] of each motion of `motions`, in
    /// order (as [`MotionChecker::poses_ok`]).
    fn motions_may_be_ok(&mut self, motions: &[(&[Real], &[Real])]) -> Vec<bool> {
        motions
            .iter()
            .map(|(a, b)| self.motion_may_be_ok(a, b))
            .collect()
    }
    /// `pose_ok` of each of `qs` will be asked soon: a checker that
    /// remembers its answers ([`MemoChecker`]) may find them now, together.
    /// The default does nothing.
    fn prefetch_poses(&mut self, qs: &[&[Real]]) {
        let _ = qs;
    }
    /// `motion_may_be_ok` of each motion of `motions` will be asked soon (as
    /// [`MotionChecker::prefetch_poses`]).
    fn prefetch_motions_may_be(&mut self, motions: &[(&[Real], &[Real])]) {
        let _ = motions;
    }
}

/// A [`MotionChecker`] that remembers every answer of the one it wraps, for
/// many queries against one unchanged map: a failed A* search checks every
/// edge it can reach, and the next query then finds them known. A motion
/// `a → b` is remembered for `b → a` too (the checks are symmetric).
#[derive(Debug)]
pub struct MemoChecker<C> {
    inner: C,
    poses: HashMap<Vec<u64>, bool>,
    motions: HashMap<(Vec<u64>, Vec<u64>), bool>,
    may_be: HashMap<(Vec<u64>, Vec<u64>), bool>,
}

impl<C: MotionChecker> MemoChecker<C> {
    /// Remember the answers of `inner`.
    pub fn new(inner: C) -> Self {
        Self {
            inner,
            poses: HashMap::default(),
            motions: HashMap::default(),
            may_be: HashMap::default(),
        }
    }

    /// The wrapped checker.
    pub fn inner(&self) -> &C {
        &self.inner
    }
}

fn bits(q: &[Real]) -> Vec<u64> {
    q.iter().map(|v| v.to_bits()).collect()
}

impl<C: MotionChecker> MotionChecker for MemoChecker<C> {
    fn pose_ok(&mut self, q: &[Real]) -> bool {
        let key = bits(q);
        if let Some(&ok) = self.poses.get(&key) {
            return ok;
        }
        let ok = self.inner.pose_ok(q);
        self.poses.insert(key, ok);
        ok
    }

    fn motion_ok(&mut self, a: &[Real], b: &[Real]) -> bool {
        let key = motion_key(a, b);
        if let Some(&ok) = self.motions.get(&key) {
            return ok;
        }
        let ok = self.inner.motion_ok(a, b);
        self.motions.insert(key, ok);
        ok
    }

    fn motion_may_be_ok(&mut self, a: &[Real], b: &[Real]) -> bool {
        let key = motion_key(a, b);
        if let Some(&ok) = self.motions.get(&key) {
            return ok;
        }
        if let Some(&ok) = self.may_be.get(&key) {
            return ok;
        }
        let ok = self.inner.motion_may_be_ok(a, b);
        self.may_be.insert(key, ok);
        ok
    }

    /// The poses of `qs` not yet known, each once, through the wrapped
    /// checker's [`MotionChecker::poses_ok`].
    fn prefetch_poses(&mut self, qs: &[&[Real]]) {
        let mut todo: Vec<(Vec<u64>, &[Real])> = qs
            .iter()
            .map(|q| (bits(q), *q))
            .filter(|(k, _)| !self.poses.contains_key(k))
            .collect();
        todo.sort_by(|a, b| a.0.cmp(&b.0));
        todo.dedup_by(|a, b| a.0 == b.0);
        let ask: Vec<&[Real]> = todo.iter().map(|(_, q)| *q).collect();
        let answers = self.inner.poses_ok(&ask);
        for ((key, _), ok) in todo.into_iter().zip(answers) {
            self.poses.insert(key, ok);
        }
    }

    /// The motions of `motions` whose answer (or full check) is not yet
    /// known, each once, through the wrapped checker's
    /// [`MotionChecker::motions_may_be_ok`].
    fn prefetch_motions_may_be(&mut self, motions: &[(&[Real], &[Real])]) {
        let mut todo: Vec<(MotionKey, Motion<'_>)> = motions
            .iter()
            .map(|&(a, b)| (motion_key(a, b), (a, b)))
            .filter(|(k, _)| !self.motions.contains_key(k) && !self.may_be.contains_key(k))
            .collect();
        todo.sort_by(|a, b| a.0.cmp(&b.0));
        todo.dedup_by(|a, b| a.0 == b.0);
        let ask: Vec<Motion<'_>> = todo.iter().map(|(_, m)| *m).collect();
        let answers = self.inner.motions_may_be_ok(&ask);
        for ((key, _), ok) in todo.into_iter().zip(answers) {
            self.may_be.insert(key, ok);
        }
    }
}

/// Tell `checker` what A* is about to ask about the edges of `u` in
/// `graph`: the poses of the neighbours not known unusable and, with
/// `motions`, the coarse check of the motions to those that are safe
/// (`node_ok` and `edge_ok`: the search's answers so far, by node and edge
/// index; `config`: a node's configuration). Nothing when `u` itself is
/// unsafe: A* asks nothing more about its edges.
fn announce_edges<'c>(
    graph: &UnGraph<(), Real>,
    u: NodeIndex,
    motions: bool,
    node_ok: &mut HashMap<usize, bool>,
    edge_ok: &HashMap<usize, bool>,
    checker: &mut dyn MotionChecker,
    config: impl Fn(NodeIndex) -> &'c [Real],
) {
    let ok_u = *node_ok
        .entry(u.index())
        .or_insert_with(|| checker.pose_ok(config(u)));
    if !ok_u {
        return;
    }
    let open: Vec<_> = graph
        .edges(u)
        .filter(|e| edge_ok.get(&e.id().index()) != Some(&false))
        .collect();
    let poses: Vec<&[Real]> = open
        .iter()
        .map(EdgeRef::target)
        .filter(|v| !node_ok.contains_key(&v.index()))
        .map(&config)
        .collect();
    checker.prefetch_poses(&poses);
    if !motions {
        return;
    }
    let motions: Vec<Motion<'_>> = open
        .iter()
        .filter(|e| !edge_ok.contains_key(&e.id().index()))
        .filter(|e| {
            *node_ok
                .entry(e.target().index())
                .or_insert_with(|| checker.pose_ok(config(e.target())))
        })
        .map(|e| (config(u), config(e.target())))
        .collect();
    checker.prefetch_motions_may_be(&motions);
}

/// A straight joint-space motion, from the first configuration to the second.
type Motion<'a> = (&'a [Real], &'a [Real]);

/// A motion's key in [`MemoChecker`] ([`motion_key`]).
type MotionKey = (Vec<u64>, Vec<u64>);

/// The key of the motion `a → b`, the same as `b → a`'s.
fn motion_key(a: &[Real], b: &[Real]) -> MotionKey {
    let (ka, kb) = (bits(a), bits(b));
    if ka <= kb { (ka, kb) } else { (kb, ka) }
}

/// A roadmap node: its index in the roadmap's node order (stored as a bare
/// number, so the cache file holds plain indices).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(transparent)]
pub struct NodeId(pub u32);

impl NodeId {
    /// The node's position in the roadmap's node order.
    pub fn index(self) -> usize {
        self.0 as usize
    }

    fn of(i: usize) -> Self {
        // A roadmap holds at most `PlanConfig`'s n_Q ceiling of nodes.
        Self(u32::try_from(i).unwrap_or(u32::MAX))
    }
}

impl std::fmt::Display for NodeId {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        self.0.fmt(f)
    }
}

/// One roadmap edge: nodes `a < b` and the joint-weighted distance.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Edge {
    /// Lower node.
    pub a: NodeId,
    /// Higher node.
    pub b: NodeId,
    /// Joint-weighted distance between the two nodes.
    pub cost: Real,
}

/// A planned motion: waypoints from the start to the goal (both included);
/// the arm moves in straight joint-space lines between consecutive waypoints.
#[derive(Clone, Debug, PartialEq)]
pub struct Path {
    /// The configurations passed, start first, goal last.
    pub waypoints: Vec<Vec<Real>>,
    /// Roadmap nodes used, in order (empty for a direct motion).
    pub nodes: Vec<NodeId>,
    /// Joint-weighted length.
    pub cost: Real,
}

impl Path {
    /// Sum of `|Δqᵢ|` over the whole path, radians (A eq. 3.3's travel).
    pub fn joint_travel(&self) -> Real {
        self.waypoints
            .windows(2)
            .map(|w| {
                w[0].iter()
                    .zip(&w[1])
                    .map(|(a, b)| (a - b).abs())
                    .sum::<Real>()
            })
            .sum()
    }
}

/// The roadmap: sampled nodes, joint weights and edges.
#[derive(Clone, Debug)]
pub struct Roadmap {
    dof: usize,
    nodes: Vec<Real>,
    weights: Vec<Real>,
    edges: Vec<Edge>,
    graph: UnGraph<(), Real>,
}

/// What a roadmap is made of, as stored in the cache file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RoadmapParts {
    /// Joints per node.
    pub dof: usize,
    /// Node configurations, one row of `dof` values per node.
    pub nodes: Vec<Vec<Real>>,
    /// Joint weights of the distance.
    pub weights: Vec<Real>,
    /// Edges, `a < b`, sorted.
    pub edges: Vec<Edge>,
}

impl Roadmap {
    /// Sample `config.n_q` nodes uniformly within `robot`'s joint limits
    /// (seeded), derive the joint weights unless given, and join each node to
    /// its `config.neighbours` nearest nodes plus a minimum spanning tree.
    pub fn build(robot: &Robot, config: &PlanConfig) -> Result<Self, PlanError> {
        let dof = robot.dof();
        config.validate(dof)?;
        let ranges = joint_ranges(robot)?;
        let mut rng = ChaCha8Rng::seed_from_u64(config.seed);
        let mut nodes = Vec::with_capacity(config.n_q * dof);
        for _ in 0..config.n_q {
            for &(lo, hi) in &ranges {
                nodes.push(if hi > lo {
                    rng.random_range(lo..hi)
                } else {
                    lo
                });
            }
        }
        let weights = if config.joint_weights.is_empty() {
            derived_weights(robot, &nodes)?
        } else {
            config.joint_weights.clone()
        };
        let edges = connect(&nodes, &weights, config.neighbours);
        Ok(Self::assemble(dof, nodes, weights, edges))
    }

    /// Rebuild a roadmap from stored parts, checking their consistency.
    pub fn from_parts(parts: RoadmapParts) -> Result<Self, String> {
        let RoadmapParts {
            dof,
            nodes,
            weights,
            edges,
        } = parts;
        if weights.len() != dof || weights.iter().any(|w| !(w.is_finite() && *w > 0.0)) {
            return Err(format!("weights: expected {dof} positive values"));
        }
        if let Some(i) = nodes
            .iter()
            .position(|n| n.len() != dof || n.iter().any(|v| !v.is_finite()))
        {
            return Err(format!("node {i}: expected {dof} finite joint values"));
        }
        let n = nodes.len();
        if let Some(e) = edges
            .iter()
            .find(|e| e.a >= e.b || e.b.index() >= n || !(e.cost.is_finite() && e.cost >= 0.0))
        {
            return Err(format!(
                "edge {}–{}: expected a < b < {n} and a finite cost",
                e.a, e.b
            ));
        }
        Ok(Self::assemble(dof, nodes.concat(), weights, edges))
    }

    /// The parts to store.
    pub fn to_parts(&self) -> RoadmapParts {
        RoadmapParts {
            dof: self.dof,
            nodes: self.nodes.chunks(self.dof).map(<[Real]>::to_vec).collect(),
            weights: self.weights.clone(),
            edges: self.edges.clone(),
        }
    }

    fn assemble(dof: usize, nodes: Vec<Real>, weights: Vec<Real>, edges: Vec<Edge>) -> Self {
        let n = nodes.len() / dof.max(1);
        let mut graph = UnGraph::with_capacity(n, edges.len());
        for _ in 0..n {
            graph.add_node(());
        }
        for e in &edges {
            graph.add_edge(
                NodeIndex::new(e.a.index()),
                NodeIndex::new(e.b.index()),
                e.cost,
            );
        }
        Self {
            dof,
            nodes,
            weights,
            edges,
            graph,
        }
    }

    /// Number of nodes `n_Q`.
    pub fn len(&self) -> usize {
        self.nodes.len() / self.dof.max(1)
    }

    /// `true` without nodes.
    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }

    /// Joints per node.
    pub fn dof(&self) -> usize {
        self.dof
    }

    /// The configuration of node `id` (of this roadmap).
    pub fn node(&self, id: NodeId) -> &[Real] {
        let i = id.index();
        &self.nodes[i * self.dof..(i + 1) * self.dof]
    }

    /// Every node, in index order.
    pub fn node_ids(&self) -> impl ExactSizeIterator<Item = NodeId> + use<> {
        (0..self.len()).map(NodeId::of)
    }

    /// Every node's configuration, in index order.
    pub fn nodes(&self) -> impl ExactSizeIterator<Item = &[Real]> + '_ {
        self.nodes.chunks_exact(self.dof)
    }

    /// The joint weights `wᵢ`.
    pub fn weights(&self) -> &[Real] {
        &self.weights
    }

    /// The edges.
    pub fn edges(&self) -> &[Edge] {
        &self.edges
    }

    /// The joint-weighted distance `Σ wᵢ |aᵢ − bᵢ|`.
    pub fn distance(&self, a: &[Real], b: &[Real]) -> Real {
        weighted_distance(&self.weights, a, b)
    }

    /// The `k` nodes nearest to `q` (ties by index), nearest first.
    pub fn nearest(&self, q: &[Real], k: usize) -> Vec<(NodeId, Real)> {
        let mut all: Vec<(NodeId, Real)> = self
            .nodes()
            .enumerate()
            .map(|(i, n)| (NodeId::of(i), self.distance(q, n)))
            .collect();
        let k = k.min(all.len());
        if k == 0 {
            return Vec::new();
        }
        all.select_nth_unstable_by(k - 1, |a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)));
        all.truncate(k);
        all.sort_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)));
        all
    }

    /// Number of connected components of the roadmap (1 when built here).
    pub fn components(&self) -> usize {
        petgraph::algo::connected_components(&self.graph)
    }

    /// Plan a motion from `from` to `to` (A§3.2.1.3: A* on the joint-weighted
    /// distance). A direct straight motion is taken when it is safe; otherwise
    /// both ends are joined to their `link_k` nearest nodes and A* searches
    /// the roadmap, checking each node and edge it relaxes with `checker`
    /// (lazily, each at most once per query). `None` when no safe path exists.
    pub fn plan(
        &self,
        from: &[Real],
        to: &[Real],
        link_k: usize,
        checker: &mut dyn MotionChecker,
    ) -> Option<Path> {
        if from.len() != self.dof || to.len() != self.dof {
            return None;
        }
        if !checker.pose_ok(from) || !checker.pose_ok(to) {
            return None;
        }
        if checker.motion_ok(from, to) {
            return Some(Path {
                waypoints: vec![from.to_vec(), to.to_vec()],
                nodes: Vec::new(),
                cost: self.distance(from, to),
            });
        }
        let n = self.len();
        let mut graph = self.graph.clone();
        let start = graph.add_node(());
        let goal = graph.add_node(());
        for (i, d) in self.nearest(from, link_k) {
            graph.add_edge(start, NodeIndex::new(i.index()), d);
        }
        for (i, d) in self.nearest(to, link_k) {
            graph.add_edge(goal, NodeIndex::new(i.index()), d);
        }
        let config = |v: NodeIndex| -> &[Real] {
            match v.index() {
                i if i < n => self.node(NodeId::of(i)),
                i if i == n => from,
                _ => to,
            }
        };
        // An edge is usable when both its nodes and the motion along it are
        // safe. The search is lazy first (Lazy PRM): A* over the edges
        // between safe nodes whose motion is not yet found unsafe, then the
        // path's motions checked from the start, and at the first unusable
        // one the search is made again
        // without it. A path whose every edge checks out is a shortest one
        // among the usable edges, found checking only the edges of the
        // paths tried. After `LAZY_ROUNDS` searches (a goal no safe path
        // reaches keeps failing them) it turns eager: A* sees only the
        // edges that may be usable, checked when A* first meets them, in
        // the order it would expand with every edge and the unusable ones
        // at an infinite cost, so a search that finds no path stops without
        // checking the edges of nodes no safe path reaches. Every answer is
        // kept for the next round.
        let checks = RefCell::new((
            HashMap::<usize, bool>::default(),
            HashMap::<usize, bool>::default(),
            checker,
        ));
        // A* asks about every edge of a node it expands, one after another
        // with nothing checked in between: the first time it asks about one
        // of `u`'s, the checker is told what comes (the poses of `u`'s
        // neighbours and, in the eager rounds, the motions to them), so that
        // a checker that remembers ([`MemoChecker`]) answers them together,
        // in parallel. The answers are the same as one by one.
        let (lazy_told, eager_told) = (
            RefCell::new(HashSet::default()),
            RefCell::new(HashSet::default()),
        );
        let tell = |u: NodeIndex, motions: bool| {
            let told = if motions { &eager_told } else { &lazy_told };
            if told.borrow_mut().insert(u.index()) {
                let mut guard = checks.borrow_mut();
                let (node_ok, edge_ok, checker) = &mut *guard;
                announce_edges(&graph, u, motions, node_ok, edge_ok, &mut **checker, config);
            }
        };
        let check_edge = |e: petgraph::graph::EdgeReference<'_, Real>| -> bool {
            let mut guard = checks.borrow_mut();
            let (node_ok, edge_ok, checker) = &mut *guard;
            if let Some(&ok) = edge_ok.get(&e.id().index()) {
                return ok;
            }
            let (u, v) = (e.source(), e.target());
            let ok = [u, v].iter().all(|w| {
                *node_ok
                    .entry(w.index())
                    .or_insert_with(|| checker.pose_ok(config(*w)))
            }) && checker.motion_ok(config(u), config(v));
            edge_ok.insert(e.id().index(), ok);
            ok
        };
        let may_be_usable = |e: petgraph::graph::EdgeReference<'_, Real>| -> bool {
            tell(e.source(), true);
            let mut guard = checks.borrow_mut();
            let (node_ok, edge_ok, checker) = &mut *guard;
            if let Some(&ok) = edge_ok.get(&e.id().index()) {
                return ok;
            }
            let (u, v) = (e.source(), e.target());
            [u, v].iter().all(|w| {
                *node_ok
                    .entry(w.index())
                    .or_insert_with(|| checker.pose_ok(config(*w)))
            }) && checker.motion_may_be_ok(config(u), config(v))
        };
        // The lazy rounds check the nodes A* meets (one configuration each)
        // and leave the motions (many) to the paths found.
        let not_known_bad = |e: petgraph::graph::EdgeReference<'_, Real>| -> bool {
            tell(e.source(), false);
            let mut guard = checks.borrow_mut();
            let (node_ok, edge_ok, checker) = &mut *guard;
            edge_ok.get(&e.id().index()) != Some(&false)
                && [e.source(), e.target()].iter().all(|w| {
                    *node_ok
                        .entry(w.index())
                        .or_insert_with(|| checker.pose_ok(config(*w)))
                })
        };
        let mut found = None;
        for _ in 0..LAZY_ROUNDS {
            let (total, route) = astar(
                &EdgeFiltered::from_fn(&graph, not_known_bad),
                start,
                |v| v == goal,
                |e| *e.weight(),
                |v| self.distance(config(v), to),
            )?;
            let all_usable = route.windows(2).all(|w| {
                // Every edge between the two nodes is checked until one is
                // usable, so the edge A* took is known after a failure.
                graph.edges_connecting(w[0], w[1]).any(check_edge)
            });
            if all_usable {
                found = Some((total, route));
                break;
            }
        }
        let (total, route) = match found {
            Some(f) => f,
            // Eager: A* through the edges whose motion may be safe (the
            // checker's cheaper test, checked as A* meets them), the path
            // found confirmed edge by edge, and A* again without an edge
            // that fails; every round knows one more unusable edge.
            None => loop {
                let (total, route) = astar(
                    &EdgeFiltered::from_fn(&graph, may_be_usable),
                    start,
                    |v| v == goal,
                    |e| *e.weight(),
                    |v| self.distance(config(v), to),
                )?;
                if route.windows(2).all(|w| {
                    // Every edge between the two nodes is checked until one is
                    // usable, so the edge A* took is known after a failure.
                    graph.edges_connecting(w[0], w[1]).any(check_edge)
                }) {
                    break (total, route);
                }
            },
        };
        if !total.is_finite() {
            return None;
        }
        Some(Path {
            waypoints: route.iter().map(|&v| config(v).to_vec()).collect(),
            nodes: route
                .iter()
                .map(|v| v.index())
                .filter(|&i| i < n)
                .map(NodeId::of)
                .collect(),
            cost: total,
        })
    }

    /// The usage likelihood `L(cᵢ)` of every node (A§4.3, Fig. 4.7): shortest
    /// paths are planned between every ordered pair of connected nodes of the
    /// obstacle-free roadmap, and `L(cᵢ)` is the fraction of those paths that
    /// pass through node `i` (ends included). Ties between equally short paths
    /// go to the lower node index, so the result is deterministic.
    pub fn usage_likelihood(&self) -> Vec<Real> {
        let n = self.len();
        let (counts, pairs) = (0..n)
            .into_par_iter()
            .fold(
                || (vec![0u64; n], 0u64),
                |(mut counts, mut pairs), s| {
                    pairs += self.count_paths_from(s, &mut counts);
                    (counts, pairs)
                },
            )
            .reduce(
                || (vec![0u64; n], 0u64),
                |(mut a, pa), (b, pb)| {
                    for (x, y) in a.iter_mut().zip(&b) {
                        *x += y;
                    }
                    (a, pa + pb)
                },
            );
        if pairs == 0 {
            return vec![0.0; n];
        }
        counts.iter().map(|&c| c as Real / pairs as Real).collect()
    }

    /// Add to `counts[v]` the number of targets whose shortest path from `s`
    /// passes `v`; return the number of targets reached (s excluded).
    fn count_paths_from(&self, s: usize, counts: &mut [u64]) -> u64 {
        let dist = dijkstra(&self.graph, NodeIndex::new(s), None, |e| *e.weight());
        // The shortest-path tree: each reached node's parent is its
        // lowest-index neighbour on a shortest path. In the weighted L1
        // distance many paths tie (any node inside the box between two
        // others lies on a shortest path), and their sums differ only by
        // rounding: a relative tolerance makes the rule see them as ties.
        let mut order: Vec<(usize, Real)> = dist.iter().map(|(v, d)| (v.index(), *d)).collect();
        order.sort_by(|a, b| b.1.total_cmp(&a.1).then(b.0.cmp(&a.0)));
        let mut subtree: HashMap<usize, u64> = order.iter().map(|&(v, _)| (v, 1)).collect();
        for &(v, dv) in &order {
            let below = subtree[&v];
            counts[v] += below;
            if v == s {
                counts[v] -= 1;
                continue;
            }
            let parent = self
                .graph
                .edges(NodeIndex::new(v))
                .filter_map(|e| {
                    let u = if e.source().index() == v {
                        e.target()
                    } else {
                        e.source()
                    };
                    let du = dist.get(&u)?;
                    (du + e.weight() <= dv + TIE * (1.0 + dv)).then_some(u.index())
                })
                .min();
            if let Some(p) = parent {
                *subtree.entry(p).or_insert(1) += below;
            }
        }
        order.len() as u64 - 1
    }
}

/// Relative tolerance under which two path lengths tie.
const TIE: Real = 1e-9;

/// `Σ wᵢ |aᵢ − bᵢ|`.
pub fn weighted_distance(weights: &[Real], a: &[Real], b: &[Real]) -> Real {
    weights
        .iter()
        .zip(a.iter().zip(b))
        .map(|(w, (x, y))| w * (x - y).abs())
        .sum()
}

/// Each actuated joint's sampling range: its limits, or `[−π, π]` for a
/// revolute joint without limits.
fn joint_ranges(robot: &Robot) -> Result<Vec<(Real, Real)>, PlanError> {
    robot
        .actuated()
        .map(|j| match (j.limits, j.kind) {
            (Some(l), _) if l.min.is_finite() && l.max.is_finite() && l.min <= l.max => {
                Ok((l.min, l.max))
            }
            (None, JointKind::Revolute) => Ok((-std::f64::consts::PI, std::f64::consts::PI)),
            _ => Err(PlanError::Robot {
                robot: robot.name.clone(),
                message: format!(
                    "joint {} needs finite limits to sample the configuration space",
                    j.name
                ),
            }),
        })
        .collect()
}

/// Smallest derived joint weight (metres per radian): a joint that moves no
/// envelope still costs something to move.
const MIN_WEIGHT: Real = 0.01;

/// Joint weights from the robot's envelope: for each actuated joint, the
/// farthest any point of a later link's bounding ellipsoid lies from the
/// joint's axis over the sampled nodes (prismatic joints: 1 m per metre).
fn derived_weights(robot: &Robot, nodes: &[Real]) -> Result<Vec<Real>, PlanError> {
    let dof = robot.dof();
    let joint_of: Vec<usize> = robot
        .joints
        .iter()
        .enumerate()
        .filter(|(_, j)| j.is_actuated())
        .map(|(i, _)| i)
        .collect();
    let kinds = robot.joint_kinds();
    let mut weights = vec![MIN_WEIGHT; dof];
    let mut any_ellipsoid = false;
    for q in nodes.chunks_exact(dof) {
        let frames = robot.forward_kinematics(q)?;
        let ellipsoids = robot.posed_ellipsoids(&frames);
        any_ellipsoid |= !ellipsoids.is_empty();
        for (a, &j) in joint_of.iter().enumerate() {
            if kinds[a] == JointKind::Prismatic {
                weights[a] = 1.0;
                continue;
            }
            let Some((p, axis)) = robot.joint_axis_in_base(&frames, j) else {
                continue;
            };
            for (link, e) in &ellipsoids {
                if link.index() <= j {
                    continue;
                }
                let c = geom::Point3::from(e.pose.translation.vector);
                let r = (c - p).cross(&axis).norm() + e.radii.max();
                weights[a] = weights[a].max(r);
            }
        }
    }
    if !any_ellipsoid {
        return Err(PlanError::Robot {
            robot: robot.name.clone(),
            message: "no link has a bounding ellipsoid (A§3.2.1.4)".into(),
        });
    }
    Ok(weights)
}

/// Edges: each node to its `k` nearest (ties by index), plus Prim's minimum
/// spanning tree of the complete graph so the roadmap is connected. Sorted,
/// without duplicates.
fn connect(nodes: &[Real], weights: &[Real], k: usize) -> Vec<Edge> {
    let dof = weights.len();
    let n = nodes.len() / dof;
    let node = |i: usize| &nodes[i * dof..(i + 1) * dof];
    let mut edges: Vec<Edge> = (0..n)
        .into_par_iter()
        .flat_map_iter(|i| {
            let mut d: Vec<(usize, Real)> = (0..n)
                .filter(|&j| j != i)
                .map(|j| (j, weighted_distance(weights, node(i), node(j))))
                .collect();
            let k = k.min(d.len());
            if k > 0 {
                d.select_nth_unstable_by(k - 1, |a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)));
            }
            d.truncate(k);
            d.into_iter().map(move |(j, cost)| Edge {
                a: NodeId::of(i.min(j)),
                b: NodeId::of(i.max(j)),
                cost,
            })
        })
        .collect();
    // Prim on the complete graph, O(n²).
    if n > 1 {
        let mut in_tree = vec![false; n];
        let mut best = vec![(Real::INFINITY, 0usize); n];
        in_tree[0] = true;
        for (j, b) in best.iter_mut().enumerate().skip(1) {
            *b = (weighted_distance(weights, node(0), node(j)), 0);
        }
        for _ in 1..n {
            let Some(v) = (0..n)
                .filter(|&j| !in_tree[j])
                .min_by(|&a, &b| best[a].0.total_cmp(&best[b].0).then(a.cmp(&b)))
            else {
                break;
            };
            in_tree[v] = true;
            let (cost, u) = best[v];
            edges.push(Edge {
                a: NodeId::of(u.min(v)),
                b: NodeId::of(u.max(v)),
                cost,
            });
            for j in 0..n {
                if !in_tree[j] {
                    let d = weighted_distance(weights, node(v), node(j));
                    if d < best[j].0 {
                        best[j] = (d, v);
                    }
                }
            }
        }
    }
    edges.sort_by_key(|e| (e.a, e.b));
    edges.dedup_by(|x, y| x.a == y.a && x.b == y.b);
    edges
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A checker over a 2-D joint space with a forbidden square.
    struct Square {
        lo: [Real; 2],
        hi: [Real; 2],
        step: Real,
    }

    impl Square {
        fn inside(&self, q: &[Real]) -> bool {
            (0..2).all(|i| q[i] > self.lo[i] && q[i] < self.hi[i])
        }
    }

    impl MotionChecker for Square {
        fn pose_ok(&mut self, q: &[Real]) -> bool {
            !self.inside(q)
        }
        fn motion_ok(&mut self, a: &[Real], b: &[Real]) -> bool {
            let len = ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt();
            let steps = (len / self.step).ceil().max(1.0) as usize;
            (0..=steps).all(|s| {
                let t = s as Real / steps as Real;
                let q = [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])];
                !self.inside(&q)
            })
        }
    }

    fn grid_roadmap(n: usize) -> Roadmap {
        // An n × n lattice over [−1, 1]², unit weights, 8 neighbours.
        let mut nodes = Vec::new();
        for i in 0..n {
            for j in 0..n {
                let s = |k: usize| -1.0 + 2.0 * k as Real / (n - 1) as Real;
                nodes.push(vec![s(i), s(j)]);
            }
        }
        let weights = vec![1.0, 1.0];
        let flat: Vec<Real> = nodes.concat();
        let edges = connect(&flat, &weights, 8);
        Roadmap::from_parts(RoadmapParts {
            dof: 2,
            nodes,
            weights,
            edges,
        })
        .unwrap()
    }

    #[test]
    fn a_star_goes_around_a_forbidden_square_and_is_shortest() {
        let map = grid_roadmap(21);
        assert_eq!(map.components(), 1);
        let mut checker = Square {
            lo: [-0.5, -0.5],
            hi: [0.5, 0.5],
            step: 0.01,
        };
        let from = [-0.8, 0.0];
        let to = [0.8, 0.0];
        let path = map.plan(&from, &to, 4, &mut checker).unwrap();
        assert_eq!(path.waypoints.first().unwrap(), &from.to_vec());
        assert_eq!(path.waypoints.last().unwrap(), &to.to_vec());
        for w in path.waypoints.windows(2) {
            assert!(checker.motion_ok(&w[0], &w[1]));
        }
        // L1 around the square: 0.3 to the side rows at |y| ≥ 0.5, then
        // across and back: at least 2·0.5 + 1.6 = 2.6; the lattice (0.1
        // spacing) achieves it exactly.
        assert!(path.cost >= 2.6 - 1e-9, "{}", path.cost);
        assert!(path.cost <= 2.6 + 1e-9, "{}", path.cost);
        // A free straight line is taken directly.
        let direct = map
            .plan(&[-0.8, 0.8], &[0.8, 0.8], 4, &mut checker)
            .unwrap();
        assert_eq!(direct.waypoints.len(), 2);
        assert!(direct.nodes.is_empty());
        // Into the square: no path.
        assert!(map.plan(&from, &[0.0, 0.0], 4, &mut checker).is_none());
    }

    /// Counts the calls that reach the checker it wraps.
    struct Counting<C> {
        inner: C,
        calls: usize,
    }

    impl<C: MotionChecker> MotionChecker for Counting<C> {
        fn pose_ok(&mut self, q: &[Real]) -> bool {
            self.calls += 1;
            self.inner.pose_ok(q)
        }
        fn motion_ok(&mut self, a: &[Real], b: &[Real]) -> bool {
            self.calls += 1;
            self.inner.motion_ok(a, b)
        }
    }

    #[test]
    fn memo_checker_gives_the_same_paths_and_checks_each_motion_once() {
        /// A forbidden square ring, 0.4 < |q|∞ < 0.6: the poses inside it
        /// are safe but no motion reaches them from outside.
        struct Ring(Square, Square);
        impl MotionChecker for Ring {
            fn pose_ok(&mut self, q: &[Real]) -> bool {
                !self.0.inside(q) || self.1.inside(q)
            }
            fn motion_ok(&mut self, a: &[Real], b: &[Real]) -> bool {
                let len = ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt();
                let steps = (len / 0.01).ceil().max(1.0) as usize;
                (0..=steps).all(|s| {
                    let t = s as Real / steps as Real;
                    self.pose_ok(&[a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])])
                })
            }
        }
        let ring = || {
            let sq = |h: Real| Square {
                lo: [-h, -h],
                hi: [h, h],
                step: 0.01,
            };
            Ring(sq(0.6), sq(0.4))
        };
        let map = grid_roadmap(21);
        let mut plain = Counting {
            inner: ring(),
            calls: 0,
        };
        let mut memo = MemoChecker::new(Counting {
            inner: ring(),
            calls: 0,
        });
        // Goals inside the ring fail after searching every node outside it;
        // the others are reached.
        let queries = [
            ([-0.8, 0.0], [0.8, 0.05]),
            ([-0.8, 0.0], [0.05, 0.05]),
            ([-0.8, 0.0], [-0.15, 0.25]),
            ([-0.8, 0.0], [0.8, 0.75]),
        ];
        let mut plain_calls = Vec::new();
        let mut memo_calls = Vec::new();
        for (from, to) in &queries {
            let a = map.plan(from, to, 4, &mut plain);
            let b = map.plan(from, to, 4, &mut memo);
            assert_eq!(a, b);
            let inside = to[0].abs() < 0.4 && to[1].abs() < 0.4;
            assert_eq!(a.is_none(), inside, "{to:?}");
            plain_calls.push(plain.calls);
            memo_calls.push(memo.inner().calls);
        }
        // The first query costs the memo no more (a little less: a pose
        // checked twice within one search is checked once); the later
        // failed one costs it almost nothing (its whole search was done by
        // the first failure), while the plain checker repeats it.
        assert!(memo_calls[0] <= plain_calls[0]);
        let plain_third = plain_calls[2] - plain_calls[1];
        let memo_third = memo_calls[2] - memo_calls[1];
        assert!(
            memo_third * 10 < plain_third,
            "memo {memo_third} vs plain {plain_third} checks"
        );
        assert!(memo_calls[3] < plain_calls[3]);
    }

    #[test]
    fn usage_of_a_chain_counts_paths_through_each_node() {
        // A path graph 0–1–2–3: ordered pairs 12; node 1 lies on the paths
        // of pairs with an end at 1 (6) and of 0↔2, 0↔3 (4): 10.
        let nodes = vec![vec![0.0], vec![1.0], vec![2.0], vec![3.0]];
        let edges = vec![
            Edge {
                a: NodeId(0),
                b: NodeId(1),
                cost: 1.0,
            },
            Edge {
                a: NodeId(1),
                b: NodeId(2),
                cost: 1.0,
            },
            Edge {
                a: NodeId(2),
                b: NodeId(3),
                cost: 1.0,
            },
        ];
        let map = Roadmap::from_parts(RoadmapParts {
            dof: 1,
            nodes,
            weights: vec![1.0],
            edges,
        })
        .unwrap();
        let l = map.usage_likelihood();
        let expect = [6.0 / 12.0, 10.0 / 12.0, 10.0 / 12.0, 6.0 / 12.0];
        for (a, b) in l.iter().zip(expect) {
            assert!((a - b).abs() < 1e-12, "{l:?}");
        }
    }

    #[test]
    fn usage_matches_brute_force_on_a_random_roadmap() {
        // Every pair's path from a second method: Floyd–Warshall with the
        // same lowest-index tie rule, then walk the paths.
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let n = 40;
        let nodes: Vec<Vec<Real>> = (0..n)
            .map(|_| vec![rng.random_range(0.0..1.0), rng.random_range(0.0..1.0)])
            .collect();
        let weights = vec![1.0, 0.7];
        let edges = connect(&nodes.concat(), &weights, 3);
        let map = Roadmap::from_parts(RoadmapParts {
            dof: 2,
            nodes,
            weights,
            edges: edges.clone(),
        })
        .unwrap();
        let mut d = vec![vec![Real::INFINITY; n]; n];
        for (i, row) in d.iter_mut().enumerate() {
            row[i] = 0.0;
        }
        for e in &edges {
            d[e.a.index()][e.b.index()] = e.cost;
            d[e.b.index()][e.a.index()] = e.cost;
        }
        for k in 0..n {
            for i in 0..n {
                for j in 0..n {
                    if d[i][k] + d[k][j] < d[i][j] {
                        d[i][j] = d[i][k] + d[k][j];
                    }
                }
            }
        }
        let mut counts = vec![0.0; n];
        let mut pairs = 0.0;
        #[allow(clippy::needless_range_loop)]
        for s in 0..n {
            for t in 0..n {
                if s == t {
                    continue;
                }
                pairs += 1.0;
                // Walk back from t: the predecessor is a neighbour u with
                // d[s][u] + w(u, v) ≈ d[s][v] (lowest index among ties).
                let mut v = t;
                counts[v] += 1.0;
                while v != s {
                    let u = edges
                        .iter()
                        .filter_map(|e| {
                            let (x, y) = (e.a.index(), e.b.index());
                            let u = if x == v {
                                y
                            } else if y == v {
                                x
                            } else {
                                return None;
                            };
                            (d[s][u] + e.cost <= d[s][v] + 1e-9 * (1.0 + d[s][v])).then_some(u)
                        })
                        .min()
                        .unwrap();
                    counts[u] += 1.0;
                    v = u;
                }
            }
        }
        let l = map.usage_likelihood();
        for i in 0..n {
            assert!(
                (l[i] - counts[i] / pairs).abs() < 1e-12,
                "node {i}: {} vs {}",
                l[i] * pairs,
                counts[i]
            );
        }
    }

    #[test]
    fn from_parts_rejects_inconsistent_parts() {
        let bad = RoadmapParts {
            dof: 2,
            nodes: vec![vec![0.0, 0.0], vec![1.0]],
            weights: vec![1.0, 1.0],
            edges: vec![],
        };
        assert!(Roadmap::from_parts(bad).unwrap_err().contains("node 1"));
        let bad = RoadmapParts {
            dof: 1,
            nodes: vec![vec![0.0], vec![1.0]],
            weights: vec![1.0],
            edges: vec![Edge {
                a: NodeId(1),
                b: NodeId(5),
                cost: 1.0,
            }],
        };
        assert!(Roadmap::from_parts(bad).unwrap_err().contains("edge 1–5"));
    }
}
