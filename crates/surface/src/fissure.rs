//! Filling fissures (P§2.5, Fig. 15–16).
//!
//! Three consecutive vertices `v₁ v₂ v₃` whose edges are not shared may form
//! fissures of type I–III; four, `v₁ v₂ v₃ v₄` with `|v₂v₃| < λ`, of type IV–VI.
//! The external angle at a vertex is measured outside the perimeter (on the right
//! of an anticlockwise perimeter), so "external angle < 180°" is a right turn and
//! "< 90°" a right turn sharper than 90°:
//!
//! | type | condition | filled by |
//! |---|---|---|
//! | I | ext(v₂) < 180°, `|v₁v₃| < λ` | edge `v₁v₃`, `v₂` removed |
//! | II | ext(v₂) < 90°, `d(v₁, v₂v₃) < λ` | `v₅` on `v₂v₃` closest to `v₁`, edge `v₁v₅` |
//! | III | ext(v₂) < 90°, `d(v₃, v₁v₂) < λ` | `v₅` on `v₁v₂` closest to `v₃`, edge `v₅v₃` |
//! | IV | ext(v₁v₂, v₃v₄) < 180° (total turn over `v₂ v₃` to the right), `|v₁v₄| < λ` | edge `v₁v₄`, `v₂ v₃` removed |
//! | V | type II on `v₁ v₃ v₄` | `v₅` on `v₃v₄` closest to `v₁`, edge `v₁v₅` |
//! | VI | type III on `v₁ v₂ v₄` | `v₅` on `v₁v₂` closest to `v₄`, edge `v₅v₄` |
//!
//! Each window of the perimeter is checked in the order IV, V, VI, I, II, III;
//! the new edge's end points must sight each other. Filling one fissure may form
//! another, so after a fill the scan steps back three vertices and continues
//! (cascading, Fig. 16). The cascade terminates: a full pass without a fill ends
//! it, and the number of fills is capped at `2n + 8` for a perimeter of `n`
//! vertices (types I, IV, V and VI remove at least one vertex; II and III replace
//! one, so the cap bounds the rare chains of those).
//!
//! After the thesis' types, pockets behind a mouth narrower than λ are closed
//! when they would collapse as a hole (`close_pockets`, our addition), and
//! the cascade runs again.
//!
//! To collapse a hole's perimeter (P§2.4.3) the restrictions on shared edges and
//! sight are lifted, and filling continues until fewer than three vertices
//! remain.

use crate::perimeter::{PerimPoint, Poly2, SightGrid, cross2, param_on_segment, turn};
use crate::segment::{Edge, EdgeKey};
use geom::polygon2::distance_point_segment;
use geom::{Point2, Real, Vector2};
use std::f64::consts::FRAC_PI_2;

/// The six fissure types of P§2.5 (Fig. 15).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum FissureType {
    /// Fig. 15(a).
    I,
    /// Fig. 15(b).
    II,
    /// Fig. 15(c).
    III,
    /// Fig. 15(d).
    IV,
    /// Fig. 15(e).
    V,
    /// Fig. 15(f).
    VI,
}

/// Whether the restrictions of ordinary fissure filling apply.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum FissureMode {
    /// Edges of the fissure may not be shared, the new edge's ends must sight
    /// each other, and at least three vertices remain.
    Restricted,
    /// Collapsing a hole's perimeter: no restrictions.
    Collapse,
}

/// Turns sharper than this count as turns (not collinear vertices).
const MIN_TURN: Real = 1e-9;

/// `turn(a, b) < -MIN_TURN` (a right turn), deciding by the signs of the
/// cross and dot products where they decide it and calling the `atan2` of
/// [`turn`] only near the thresholds and for zeros (whose signs `atan2` reads).
fn turns_right(a: &Vector2, b: &Vector2) -> bool {
    let c = cross2(a, b);
    let d = a.dot(b);
    if c > 0.0 {
        // atan2 in (0, π].
        return false;
    }
    if c < 0.0 {
        if d < 0.0 {
            // atan2 in (−π, −π/2].
            return true;
        }
        if d > 0.0 {
            // atan2 = −atan(|c|/d): beyond 10⁻⁶ rad, or within 10⁻¹².
            if -c > 1e-6 * d {
                return true;
            }
            if -c < 1e-12 * d {
                return false;
            }
        }
    }
    turn(a, b) < -MIN_TURN
}

/// `turn(a, b) < -FRAC_PI_2` (a right turn sharper than 90°), as
/// [`turns_right`] does it: the signs decide it unless the angle lies within
/// about 10⁻¹² rad of −90° or a product is zero.
fn turns_right_sharply(a: &Vector2, b: &Vector2) -> bool {
    let c = cross2(a, b);
    let d = a.dot(b);
    if c > 0.0 || d > 0.0 {
        // atan2 in (0, π], or in (−π/2, 0].
        return false;
    }
    if c < 0.0 && d < 0.0 && -d > 1e-12 * -c {
        // atan2 = −π/2 − atan(|d|/|c|), more than 10⁻¹² below −π/2.
        return true;
    }
    turn(a, b) < -FRAC_PI_2
}

/// The threshold `t` for which `x.sqrt() < lambda` exactly when `x < t`
/// (for every `x ≥ 0`, and NaN: a squared length): the smallest float whose rounded root
/// reaches `lambda`. The rounded square root is monotone, so comparing
/// squared lengths with it gives the answers of comparing the lengths
/// (`Vector2::norm` is the root of `norm_squared`) without taking a root.
fn sqrt_below(lambda: Real) -> Real {
    // Comparisons with a NaN λ are all false, as with a NaN threshold; no root
    // is below a non-positive λ; every finite one is below +∞.
    if lambda.is_nan() {
        return Real::NAN;
    }
    if lambda <= 0.0 {
        return Real::NEG_INFINITY;
    }
    if lambda == Real::INFINITY {
        return Real::INFINITY;
    }
    // λ² rounded is within an ulp or two of the threshold.
    let mut t = lambda * lambda;
    while t.sqrt() >= lambda {
        t = t.next_down();
    }
    while t.sqrt() < lambda {
        t = t.next_up();
    }
    t
}

/// `turn(a, b) + turn(b, c) < -MIN_TURN` (type IV's total turn), deciding by
/// signs where they decide it: two left turns (positive cross products, so
/// both `atan2` values are at least zero) never sum below zero, and two right
/// turns (both values at most zero) of which one passes [`turns_right`] sum
/// to at most that one, which is below `-MIN_TURN` (rounding is monotone).
/// Only mixed or zero cross products call `atan2` twice.
fn turns_right_over_two(a: &Vector2, b: &Vector2, c: &Vector2) -> bool {
    let (c1, c2) = (cross2(a, b), cross2(b, c));
    if c1 > 0.0 && c2 > 0.0 {
        return false;
    }
    if c1 < 0.0 && c2 < 0.0 && (turns_right(a, b) || turns_right(b, c)) {
        return true;
    }
    turn(a, b) + turn(b, c) < -MIN_TURN
}

/// Fill fissures in `poly` (see the [module docs](self)); returns the types
/// filled, in order.
pub(crate) fn fill_fissures(
    poly: &mut Poly2,
    mode: FissureMode,
    lambda: Real,
    eps: Real,
    fresh: &mut dyn FnMut() -> EdgeKey,
) -> Vec<FissureType> {
    let mut filled = Vec::new();
    let mut next = Poly2 {
        nodes: Vec::with_capacity(poly.len() + 2),
    };
    cascade(poly, mode, lambda, eps, fresh, &mut next, &mut |kind| {
        filled.push(kind);
    });
    filled
}

/// The cascade of [`fill_fissures`], reporting each fill to `on_fill`; the
/// windows' candidate perimeters are built in `next` (any content) and
/// swapped in when kept.
fn cascade(
    poly: &mut Poly2,
    mode: FissureMode,
    lambda: Real,
    eps: Real,
    fresh: &mut dyn FnMut() -> EdgeKey,
    next: &mut Poly2,
    on_fill: &mut dyn FnMut(FissureType),
) {
    let cap = 2 * poly.len() + 8;
    let mut fills = 0usize;
    let mut i = 0usize;
    let mut without_fill = 0usize;
    // The area of `poly` once computed, kept from window to window (and taken
    // over from a filled perimeter that had its area computed).
    let mut area: Option<Real> = None;
    let below_lambda_sq = sqrt_below(lambda);
    while fills < cap {
        let n = poly.len();
        if n < 3 || without_fill >= n {
            break;
        }
        let at = i % n;
        if let Some(kind) = fill_window(
            poly,
            at,
            mode,
            (lambda, below_lambda_sq),
            eps,
            fresh,
            next,
            &mut area,
        ) {
            std::mem::swap(poly, next);
            fills += 1;
            on_fill(kind);
            without_fill = 0;
            let m = poly.len().max(1);
            i = (at + 3 * m - 3) % m;
        } else {
            i = at + 1;
            without_fill += 1;
        }
    }
}

/// Remove vertices that lie within `eps` of the straight edge joining their
/// neighbours (between two non-shared edges, not corner vertices). Extending a
/// perimeter to points that lie along an edge leaves such vertices behind; they
/// carry no shape, and every perimeter query costs time per vertex. (Our
/// addition to P§2.5: the limit of a type I fissure whose external angle tends
/// to 180°.) Returns the number removed.
pub(crate) fn remove_collinear(
    poly: &mut Poly2,
    eps: Real,
    fresh: &mut dyn FnMut() -> EdgeKey,
) -> usize {
    let mut removed = 0;
    let mut i = 0;
    // Each removal shortens the perimeter by one vertex; a pass without removal ends.
    let mut without = 0;
    while poly.len() > 3 && without < poly.len() {
        let n = poly.len();
        let k = i % n;
        let (a, v, b) = (poly.pt(k + n - 1), poly.pt(k), poly.pt(k + 1));
        let ok = !poly.is_shared(k)
            && !poly.is_shared(k + n - 1)
            && poly.nodes[k].corner.is_none()
            && distance_point_segment(&v, &a, &b) <= eps
            && (b - a).dot(&(v - a)) > 0.0
            && (a - b).dot(&(v - b)) > 0.0;
        if ok {
            let prev = (k + n - 1) % n;
            poly.nodes[prev].edge = Edge {
                key: fresh(),
                share: None,
            };
            poly.nodes.remove(k);
            removed += 1;
            without = 0;
            i = k.saturating_sub(1);
        } else {
            i = k + 1;
            without += 1;
        }
    }
    removed
}

/// Fill shallow dents: remove reflex vertices (the polygon grows) that lie
/// within `delta` of the straight edge joining their neighbours (between two
/// non-shared edges, not corner vertices), such that every vertex removed in
/// this call stays within `delta` of the edge that replaces it, and the new
/// edge crosses no other edge (within `eps`). Returns the number removed.
///
/// Our addition to P§2.5, in its spirit (gaps narrower than λ are filled), with
/// `delta` the collinearity length of P§2.2 (`collinear_fraction·λ`). Under
/// range noise every extension of a perimeter (P§2.4.2) leaves a vertex a few
/// millimetres off the straight boundary, which [`remove_collinear`] keeps;
/// ragged perimeters of a hundred vertices made every perimeter operation, and
/// so the update, several times slower. Only dents are filled: cutting off
/// bulges as well moved boundaries away from the lines where shared edges form,
/// and noisy faces lost shared edges.
pub(crate) fn remove_nearly_collinear(
    poly: &mut Poly2,
    delta: Real,
    eps: Real,
    fresh: &mut dyn FnMut() -> EdgeKey,
) -> usize {
    // The removed vertices each edge stands for.
    let mut ghosts: Vec<Vec<Point2>> = vec![Vec::new(); poly.len()];
    let mut removed = 0;
    let mut i = 0;
    // Each removal shortens the perimeter by one vertex; a pass without removal ends.
    let mut without = 0;
    while poly.len() > 3 && without < poly.len() {
        let n = poly.len();
        let k = i % n;
        let prev = (k + n - 1) % n;
        let (a, v, b) = (poly.pt(k + n - 1), poly.pt(k), poly.pt(k + 1));
        let ok = !poly.is_shared(k)
            && !poly.is_shared(prev)
            && poly.nodes[k].corner.is_none()
            && distance_point_segment(&v, &a, &b) <= delta
            && (b - a).dot(&(v - a)) > 0.0
            && (a - b).dot(&(v - b)) > 0.0
            && cross2(&(b - a), &(v - a)) > 0.0
            && ghosts[prev]
                .iter()
                .chain(&ghosts[k])
                .all(|g| distance_point_segment(g, &a, &b) <= delta)
            && poly.sight(&a, &b, eps, |e| e == prev || e == k);
        if ok {
            let mut merged = std::mem::take(&mut ghosts[prev]);
            merged.append(&mut ghosts[k]);
            merged.push(v);
            ghosts[prev] = merged;
            ghosts.remove(k);
            poly.nodes[prev].edge = Edge {
                key: fresh(),
                share: None,
            };
            poly.nodes.remove(k);
            removed += 1;
            without = 0;
            i = k.saturating_sub(1);
        } else {
            i = k + 1;
            without += 1;
        }
    }
    removed
}

/// Close pockets: a section `v_i … v_j` of five or more vertices whose end
/// vertices are less than λ apart, whose edges are not shared, and which runs
/// clockwise around the region between it and the chord `v_j v_i` (a pocket
/// outside the polygon, entered through a mouth narrower than λ) is replaced
/// by the chord when the chord's ends sight each other and the pocket's
/// perimeter, taken as a hole's (P§2.4.3), collapses under fissure filling.
/// Larger pockets are tried first. Returns the number closed.
///
/// Our addition to P§2.5, the thesis' own step from three to four vertices
/// (types I–III to IV–VI) taken to any number: a notch that the perimeter
/// extensions of P§2.4.2 leave between two spikes usually has several
/// vertices on each wall, and filling it needs a window longer than four
/// vertices. The collapse test is the thesis' test for discarding a hole, so
/// a pocket is filled exactly when it would be as a hole: a narrow notch of any
/// depth (the morphological closing of P§2.5 with a structuring element of
/// diameter λ), never a wide cavity behind a narrow mouth.
pub(crate) fn close_pockets(
    poly: &mut Poly2,
    lambda: Real,
    eps: Real,
    fresh: &mut dyn FnMut() -> EdgeKey,
) -> usize {
    let mut closed = 0;
    let mut free: Vec<usize> = Vec::new();
    let mut pocket: Vec<Point2> = Vec::new();
    // The perimeter's points taken twice (and one more), so that sections
    // index them without reducing indices modulo n: the section scan below
    // tests O(n²) chords per call.
    let mut twice: Vec<Point2> = Vec::new();
    let mut collapser = Collapser::default();
    // `|v| >= λ` as `|v|² >= below_lambda_sq` (see `sqrt_below`).
    let below_lambda_sq = sqrt_below(lambda);
    // Each closure removes at least three vertices.
    'outer: loop {
        let n = poly.len();
        if n < 8 {
            return closed;
        }
        // Twice the signed area of a pocket from prefix sums of the edges'
        // cross products (over the perimeter taken twice).
        twice.clear();
        twice.extend((0..=2 * n).map(|m| poly.pt(m)));
        let mut prefix = Vec::with_capacity(2 * n + 1);
        prefix.push(0.0);
        for m in 0..2 * n {
            let (a, b) = (twice[m], twice[m + 1]);
            let last = prefix.last().copied().unwrap_or(0.0);
            prefix.push(last + (a.x * b.y - a.y * b.x));
        }
        // Sight tests against the unchanged perimeter go through an index.
        let mut grid: Option<SightGrid> = None;
        let mut area: Option<Real> = None;
        // free[m]: how many edges from edge m on (over the perimeter taken
        // twice) are not shared.
        free.clear();
        free.resize(2 * n + 1, 0);
        for m in (0..2 * n).rev() {
            free[m] = if poly.is_shared(m) {
                0
            } else {
                free[m + 1] + 1
            };
        }
        // Sections start at each vertex and run over non-shared edges only.
        for i in 0..n {
            let vi = twice[i];
            // Section v_i … v_{i+k}: k edges, k − 1 removed vertices, and at
            // least three vertices left.
            let k_max = free[i].min(n - 3);
            if k_max < 4 {
                continue;
            }
            // v_i … v_{i+k_max} (i + k_max < 2n).
            let section = &twice[i..=i + k_max];
            for k in (4..=k_max).rev() {
                let vj = section[k];
                if (vj - vi).norm_squared() >= below_lambda_sq {
                    continue;
                }
                let twice_area = prefix[i + k] - prefix[i] + (vj.x * vi.y - vj.y * vi.x);
                if twice_area >= 0.0 {
                    continue;
                }
                let grid = grid.get_or_insert_with(|| SightGrid::new(poly));
                if !grid.sight(poly, &vi, &vj, eps, |_| false) {
                    continue;
                }
                pocket.clear();
                pocket.extend_from_slice(&section[..=k]);
                if !collapser.collapses(&pocket, lambda, eps) {
                    continue;
                }
                let edge = Edge {
                    key: fresh(),
                    share: None,
                };
                let Ok(next) = poly.replace_section(
                    PerimPoint::vertex(i),
                    PerimPoint::vertex(i + k),
                    edge,
                    &[],
                    fresh,
                ) else {
                    continue;
                };
                if next.area() > *area.get_or_insert_with(|| poly.area()) && next.is_valid(eps) {
                    *poly = next;
                    closed += 1;
                    continue 'outer;
                }
            }
        }
        return closed;
    }
}

/// Collapse a hole's perimeter (clockwise, the polygon on its left) by filling
/// fissures without restrictions. `true` when it collapsed.
pub(crate) fn collapse_hole(hole: &[Point2], lambda: Real, eps: Real) -> bool {
    Collapser::default().collapses(hole, lambda, eps)
}

/// [`collapse_hole`] with its perimeters kept between calls, for callers that
/// test many holes.
#[derive(Default)]
struct Collapser {
    poly: Poly2,
    next: Poly2,
}

impl Collapser {
    fn collapses(&mut self, hole: &[Point2], lambda: Real, eps: Real) -> bool {
        let mut key = 0u32;
        let mut fresh = || {
            key += 1;
            EdgeKey(key)
        };
        self.poly.nodes.clear();
        self.poly.nodes.extend(
            hole.iter()
                .map(|p| crate::perimeter::Node2::plain(*p, EdgeKey(0))),
        );
        cascade(
            &mut self.poly,
            FissureMode::Collapse,
            lambda,
            eps,
            &mut fresh,
            &mut self.next,
            &mut |_| {},
        );
        self.poly.len() < 3
    }
}

/// The fissures found at one window, in the order they are tried: at most
/// one of each type.
struct Candidates {
    items: [(FissureType, PerimPoint, PerimPoint); 6],
    len: usize,
}

impl Default for Candidates {
    fn default() -> Self {
        let none = (FissureType::I, PerimPoint::vertex(0), PerimPoint::vertex(0));
        Self {
            items: [none; 6],
            len: 0,
        }
    }
}

impl Candidates {
    fn push(&mut self, item: (FissureType, PerimPoint, PerimPoint)) {
        self.items[self.len] = item;
        self.len += 1;
    }

    fn as_slice(&self) -> &[(FissureType, PerimPoint, PerimPoint)] {
        &self.items[..self.len]
    }
}

/// Try the fissure types at the window starting at vertex `i`; the filled
/// perimeter is left in `next`. Lengths are compared with λ (`lambda`) as
/// squares with `below_lambda_sq = sqrt_below(lambda)`. `area` is `poly`'s area when known (it is
/// filled in when computed here); after a fill it is `next`'s, when known.
#[allow(
    clippy::too_many_arguments,
    reason = "the cascade's state, passed down to the one function it calls per window"
)]
fn fill_window(
    poly: &Poly2,
    i: usize,
    mode: FissureMode,
    (lambda, below_lambda_sq): (Real, Real),
    eps: Real,
    fresh: &mut dyn FnMut() -> EdgeKey,
    next: &mut Poly2,
    area: &mut Option<Real>,
) -> Option<FissureType> {
    let n = poly.len();
    if n == 0 {
        return None;
    }
    let restricted = mode == FissureMode::Restricted;
    let min_left = if restricted { 3 } else { 0 };
    // The window's node indices (as `pt` and `is_shared` reduce them), with
    // one division instead of one per access.
    let following = |k: usize| if k + 1 == n { 0 } else { k + 1 };
    let i0 = i % n;
    let (i1, i2, i3) = (
        following(i0),
        following(following(i0)),
        following(following(following(i0))),
    );
    let ns = &poly.nodes;
    let (v1, v2, v3, v4) = (ns[i0].p, ns[i1].p, ns[i2].p, ns[i3].p);
    let plain = |poly_edges_ok: bool| poly_edges_ok || !restricted;
    let shared = |k: usize| ns[k].edge.share.is_some();
    let two_free = plain(!shared(i0) && !shared(i1));
    let three_free = two_free && plain(!shared(i2));
    let d12 = v2 - v1;
    let d23 = v3 - v2;
    let d34 = v4 - v3;
    // At most one candidate per type, kept on the stack: this runs for every
    // window of every cascade, the collapse tests of `close_pockets` included.
    let mut candidates = Candidates::default();
    // `|v| < λ` as `|v|² < below_lambda_sq` (see `sqrt_below`), without a root.
    let short = |v: Vector2| v.norm_squared() < below_lambda_sq;
    if n >= 4 && three_free && short(v3 - v2) {
        // IV
        if n >= min_left + 2 && short(v4 - v1) && turns_right_over_two(&d12, &d23, &d34) {
            candidates.push((
                FissureType::IV,
                PerimPoint::vertex(i),
                PerimPoint::vertex(i + 3),
            ));
        }
        if n > min_left {
            // V: type II on v1 v3 v4.
            if turns_right_sharply(&(v3 - v1), &d34)
                && distance_point_segment(&v1, &v3, &v4) < lambda
            {
                let t = param_on_segment(&v1, &v3, &v4);
                candidates.push((
                    FissureType::V,
                    PerimPoint::vertex(i),
                    PerimPoint {
                        edge: (i + 2) % n,
                        t,
                    },
                ));
            }
            // VI: type III on v1 v2 v4.
            if turns_right_sharply(&d12, &(v4 - v2))
                && distance_point_segment(&v4, &v1, &v2) < lambda
            {
                let t = param_on_segment(&v4, &v1, &v2);
                candidates.push((
                    FissureType::VI,
                    PerimPoint { edge: i % n, t },
                    PerimPoint::vertex(i + 3),
                ));
            }
        }
    }
    // Types I–III need a right turn at v₂ (II and III a sharp one, which is a
    // right turn too), decided by signs in most windows: the turns come
    // before the distances, which most windows never need.
    if two_free && turns_right(&d12, &d23) {
        if n > min_left && short(v3 - v1) {
            candidates.push((
                FissureType::I,
                PerimPoint::vertex(i),
                PerimPoint::vertex(i + 2),
            ));
        }
        if turns_right_sharply(&d12, &d23) {
            if distance_point_segment(&v1, &v2, &v3) < lambda {
                let t = param_on_segment(&v1, &v2, &v3);
                candidates.push((
                    FissureType::II,
                    PerimPoint::vertex(i),
                    PerimPoint {
                        edge: (i + 1) % n,
                        t,
                    },
                ));
            }
            if distance_point_segment(&v3, &v1, &v2) < lambda {
                let t = param_on_segment(&v3, &v1, &v2);
                candidates.push((
                    FissureType::III,
                    PerimPoint { edge: i % n, t },
                    PerimPoint::vertex(i + 2),
                ));
            }
        }
    }
    for &(kind, from, to) in candidates.as_slice() {
        let removes = match kind {
            FissureType::IV => 2,
            FissureType::I | FissureType::V | FissureType::VI => 1,
            FissureType::II | FissureType::III => 0,
        };
        if !restricted && n < 3 + removes {
            // The hole's perimeter collapses.
            next.nodes.clear();
            *area = None;
            return Some(kind);
        }
        let from = poly.snap(from, eps);
        let to = poly.snap(to, eps);
        let (a, b) = (poly.point_at(from), poly.point_at(to));
        if restricted && (b - a).norm() <= eps {
            continue;
        }
        if restricted && !poly.sight(&a, &b, eps, |_| false) {
            continue;
        }
        let edge = Edge {
            key: fresh(),
            share: None,
        };
        if poly
            .replace_section_into(from, to, edge, &[], fresh, &mut next.nodes)
            .is_err()
        {
            continue;
        }
        if next.len() >= n && !matches!(kind, FissureType::II | FissureType::III) {
            continue;
        }
        let next_area = if restricted {
            // Cheapest first: the area before the simplicity check.
            if next.len() < 3 {
                continue;
            }
            let next_area = next.area();
            if next_area <= *area.get_or_insert_with(|| poly.area()) {
                continue;
            }
            if !next.is_valid(eps) {
                continue;
            }
            Some(next_area)
        } else if next.len() >= 3 && next.len() >= n {
            let next_area = next.area();
            if next_area.abs() >= area.get_or_insert_with(|| poly.area()).abs() {
                continue;
            }
            Some(next_area)
        } else {
            None
        };
        *area = next_area;
        return Some(kind);
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::perimeter::Node2;

    /// The sign-decided turn tests give `turn`'s answers: on random
    /// directions, on directions a hair off the thresholds (straight on, and
    /// ±90°), and on zeros of either sign.
    #[test]
    fn turn_tests_agree_with_atan2() {
        use rand::{RngExt, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        let mut cases: Vec<(Vector2, Vector2)> = Vec::new();
        let zeros = [0.0, -0.0];
        for &x in &zeros {
            for &y in &zeros {
                for &u in &zeros {
                    for &w in &zeros {
                        cases.push((Vector2::new(x, y), Vector2::new(u, w)));
                    }
                    cases.push((Vector2::new(x, y), Vector2::new(1.0, -0.5)));
                    cases.push((Vector2::new(1.0, 0.0), Vector2::new(x, y)));
                }
            }
        }
        for _ in 0..200_000 {
            let a = Vector2::new(rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0));
            let angle: Real = match rng.random_range(0..4) {
                0 => rng.random_range(-3.2..3.2),
                1 => rng.random_range(-1e-8..1e-8) * rng.random_range(0.0..1.0f64).powi(8),
                2 => {
                    -FRAC_PI_2
                        + rng.random_range(-1e-9..1e-9) * rng.random_range(0.0..1.0f64).powi(8)
                }
                _ => -MIN_TURN * rng.random_range(0.5..2.0),
            };
            let len = rng.random_range(1e-6..10.0);
            let (s, c) = angle.sin_cos();
            let b = Vector2::new(c * a.x - s * a.y, s * a.x + c * a.y) * len;
            cases.push((a, b));
        }
        for (a, b) in cases {
            assert_eq!(turns_right(&a, &b), turn(&a, &b) < -MIN_TURN, "{a:?} {b:?}");
            assert_eq!(
                turns_right_sharply(&a, &b),
                turn(&a, &b) < -FRAC_PI_2,
                "{a:?} {b:?}"
            );
        }
    }

    /// The sign-decided total turn of type IV gives the `atan2` sum's
    /// answers: on random directions, on turns a hair either side of zero
    /// and of `-MIN_TURN` (alone and split over the two vertices), and on
    /// zero vectors.
    #[test]
    fn total_turn_agrees_with_atan2() {
        use rand::{RngExt, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
        let rotate = |v: &Vector2, angle: Real, len: Real| {
            let (s, c) = angle.sin_cos();
            Vector2::new(c * v.x - s * v.y, s * v.x + c * v.y) * len
        };
        let mut cases: Vec<(Vector2, Vector2, Vector2)> = Vec::new();
        let zero = Vector2::zeros();
        let unit = Vector2::new(1.0, 0.0);
        cases.push((zero, unit, unit));
        cases.push((unit, zero, unit));
        cases.push((unit, unit, zero));
        cases.push((unit, -unit, unit));
        for _ in 0..200_000 {
            let a = Vector2::new(rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0));
            let mut angle = || -> Real {
                match rng.random_range(0..4) {
                    0 => rng.random_range(-3.2..3.2),
                    1 => rng.random_range(-1e-8..1e-8) * rng.random_range(0.0..1.0f64).powi(8),
                    2 => -MIN_TURN * rng.random_range(0.0..2.0),
                    _ => -0.5 * MIN_TURN * rng.random_range(0.9..1.1),
                }
            };
            let (t1, t2) = (angle(), angle());
            let b = rotate(&a, t1, rng.random_range(1e-6..10.0));
            let c = rotate(&b, t2, rng.random_range(1e-6..10.0));
            cases.push((a, b, c));
        }
        for (a, b, c) in cases {
            assert_eq!(
                turns_right_over_two(&a, &b, &c),
                turn(&a, &b) + turn(&b, &c) < -MIN_TURN,
                "{a:?} {b:?} {c:?}"
            );
        }
    }

    /// `sqrt_below` splits the floats exactly where the rounded root
    /// crosses λ: at and around the threshold, and for random squares.
    #[test]
    fn sqrt_below_is_the_root_threshold() {
        use rand::{RngExt, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        let mut lambdas = vec![0.05, 1.0, 1e-6, 0.3, 7.0, Real::MIN_POSITIVE, 1e300];
        lambdas.extend((0..200).map(|_| rng.random_range(1e-4..10.0)));
        for lambda in lambdas {
            let t = sqrt_below(lambda);
            let mut xs = vec![t, t.next_down(), t.next_up(), lambda * lambda, 0.0, -0.0];
            let mut x = t;
            for _ in 0..8 {
                x = x.next_down();
                xs.push(x);
            }
            xs.extend((0..200).map(|_| (lambda * rng.random_range(0.0..2.0)).powi(2)));
            xs.extend([Real::NAN, Real::INFINITY]);
            // Squared lengths: never below zero.
            for x in xs.into_iter().filter(|x| x.is_nan() || *x >= 0.0) {
                assert_eq!(x < t, x.sqrt() < lambda, "λ = {lambda}, x = {x}");
                assert_eq!(x >= t, x.sqrt() >= lambda, "λ = {lambda}, x = {x}");
            }
        }
        for lambda in [0.0, -1.0, Real::NAN, Real::INFINITY] {
            let t = sqrt_below(lambda);
            for x in [0.0, -0.0, 1.0, 1e300, Real::INFINITY, Real::NAN] {
                assert_eq!(x < t, x.sqrt() < lambda, "λ = {lambda}, x = {x}");
                assert_eq!(x >= t, x.sqrt() >= lambda, "λ = {lambda}, x = {x}");
            }
        }
    }

    fn poly(pts: &[(Real, Real)]) -> Poly2 {
        Poly2 {
            nodes: pts
                .iter()
                .enumerate()
                .map(|(i, &(x, y))| Node2::plain(Point2::new(x, y), EdgeKey(i as u32)))
                .collect(),
        }
    }

    fn fill(p: &mut Poly2) -> Vec<FissureType> {
        let mut k = 1000;
        let mut fresh = || {
            k += 1;
            EdgeKey(k)
        };
        fill_fissures(p, FissureMode::Restricted, 0.05, 1e-6, &mut fresh)
    }

    /// Shallow dents (within δ of the chord) are filled, bulges and deep dents
    /// stay, and every removed vertex lies within δ of the final perimeter.
    #[test]
    fn nearly_collinear_dents_are_filled() {
        let delta = 0.005;
        // The bottom edge of a 1 m square, jagged: dents (y > 0, inside) of
        // 3 mm, a bulge (y < 0) of 3 mm, a deep dent of 2 cm.
        let bottom = [
            (0.1, 0.003),
            (0.2, 0.0),
            (0.3, 0.003),
            (0.4, -0.003),
            (0.5, 0.0),
            (0.6, 0.02),
            (0.7, 0.0),
            (0.8, 0.002),
        ];
        let mut pts = vec![(0.0, 0.0)];
        pts.extend(bottom);
        pts.extend([(1.0, 0.0), (1.0, 1.0), (0.0, 1.0)]);
        let mut p = poly(&pts);
        let area = p.area();
        let mut k = 1000;
        let mut fresh = || {
            k += 1;
            EdgeKey(k)
        };
        let removed = remove_nearly_collinear(&mut p, delta, 1e-6, &mut fresh);
        assert!(p.is_valid(1e-6));
        assert!(p.area() >= area);
        let left: Vec<Point2> = p.points();
        let has = |x: Real, y: Real| left.iter().any(|q| (q - Point2::new(x, y)).norm() < 1e-12);
        assert!(has(0.4, -0.003), "the bulge stays");
        assert!(has(0.6, 0.02), "the deep dent stays");
        assert!(!has(0.1, 0.003) && !has(0.3, 0.003) && !has(0.8, 0.002));
        assert_eq!(removed, pts.len() - left.len());
        // Oracle: every original vertex lies within δ of the new perimeter.
        let n = left.len();
        for &(x, y) in &pts {
            let v = Point2::new(x, y);
            let d = (0..n)
                .map(|i| distance_point_segment(&v, &left[i], &left[(i + 1) % n]))
                .fold(Real::INFINITY, Real::min);
            assert!(d <= delta + 1e-12, "{v} is {d} from the perimeter");
        }
    }

    /// P Fig. 15(a): a narrow V notch, mouth narrower than λ.
    #[test]
    fn fig15a_type_i() {
        let mut p = poly(&[
            (0.0, 0.0),
            (1.0, 0.0),
            (1.0, 1.0),
            (0.52, 1.0),
            (0.5, 0.7),
            (0.48, 1.0),
            (0.0, 1.0),
        ]);
        let kinds = fill(&mut p);
        assert_eq!(kinds, vec![FissureType::I]);
        assert_eq!(p.len(), 6);
        assert!((p.area() - 1.0).abs() < 1e-12);
    }

    /// P Fig. 15(b): a slanted slot whose first wall is close to the second edge.
    #[test]
    fn fig15b_type_ii() {
        // Notch entering at (0.4, 1), bottom (0.7, 0.6), leaving at (0.75, 1.0):
        // sharp reflex turn at the bottom, v1 within λ of edge v2v3 but |v1v3| ≥ λ.
        let mut p = poly(&[
            (0.0, 0.0),
            (1.0, 0.0),
            (1.0, 1.0),
            (0.46, 0.9),
            (0.5, 0.5),
            (0.4, 1.0),
            (0.0, 1.0),
        ]);
        let kinds = fill(&mut p);
        assert_eq!(kinds.first(), Some(&FissureType::II), "{kinds:?}");
        assert!(p.is_valid(1e-9));
    }

    /// P Fig. 15(c): mirror image of (b).
    #[test]
    fn fig15c_type_iii() {
        let mut p = poly(&[
            (1.0, 1.0),
            (0.6, 1.0),
            (0.5, 0.5),
            (0.54, 0.9),
            (0.0, 1.0),
            (0.0, 0.0),
            (1.0, 0.0),
        ]);
        let kinds = fill(&mut p);
        assert_eq!(kinds.first(), Some(&FissureType::III), "{kinds:?}");
        assert!(p.is_valid(1e-9));
    }

    /// P Fig. 15(d): a square-bottomed slot narrower than λ.
    #[test]
    fn fig15d_type_iv() {
        let mut p = poly(&[
            (0.0, 0.0),
            (1.0, 0.0),
            (1.0, 1.0),
            (0.52, 1.0),
            (0.52, 0.6),
            (0.48, 0.6),
            (0.48, 1.0),
            (0.0, 1.0),
        ]);
        let kinds = fill(&mut p);
        assert_eq!(kinds, vec![FissureType::IV]);
        assert_eq!(p.len(), 6);
        assert!((p.area() - 1.0).abs() < 1e-12);
    }

    /// P Fig. 15(e): a slot with a short bottom whose far wall slants back.
    #[test]
    fn fig15e_type_v() {
        let mut p = poly(&[
            (0.0, 0.0),
            (1.0, 0.0),
            (1.0, 1.0),
            (0.46, 0.9),
            (0.51, 0.5),
            (0.49, 0.5),
            (0.4, 1.0),
            (0.0, 1.0),
        ]);
        let kinds = fill(&mut p);
        assert_eq!(kinds.first(), Some(&FissureType::V), "{kinds:?}");
        assert!(p.is_valid(1e-9));
    }

    /// P Fig. 15(f): mirror image of (e).
    #[test]
    fn fig15f_type_vi() {
        let mut p = poly(&[
            (1.0, 1.0),
            (0.6, 1.0),
            (0.51, 0.5),
            (0.49, 0.5),
            (0.54, 0.9),
            (0.0, 1.0),
            (0.0, 0.0),
            (1.0, 0.0),
        ]);
        let kinds = fill(&mut p);
        assert_eq!(kinds.first(), Some(&FissureType::VI), "{kinds:?}");
        assert!(p.is_valid(1e-9));
    }

    /// P Fig. 16: filling one fissure forms the next (a staircase notch).
    #[test]
    fn fig16_cascade() {
        // A narrow V notch with several vertices per wall: each fill exposes the
        // next fissure one step up the notch.
        let mut pts = vec![(0.0, 0.0), (1.0, 0.0), (1.0, 1.0)];
        for k in (1..=4).rev() {
            pts.push((0.5 + 0.004 * f64::from(k), 0.9 + 0.025 * f64::from(k)));
        }
        pts.push((0.5, 0.9));
        for k in 1..=4 {
            pts.push((0.5 - 0.004 * f64::from(k), 0.9 + 0.025 * f64::from(k)));
        }
        pts.push((0.0, 1.0));
        let mut p = poly(&pts);
        let kinds = fill(&mut p);
        assert!(kinds.len() >= 3, "{kinds:?}");
        assert!((p.area() - 1.0).abs() < 1e-9, "{:?}", p.points());
        assert!(p.len() <= 6);
    }

    /// Shared edges are never part of a fissure; sight blocks fills that would cross.
    #[test]
    fn shared_edges_block_fissures() {
        let mut p = poly(&[
            (0.0, 0.0),
            (1.0, 0.0),
            (1.0, 1.0),
            (0.52, 1.0),
            (0.5, 0.7),
            (0.48, 1.0),
            (0.0, 1.0),
        ]);
        p.nodes[3].edge.share = Some(crate::segment::Share {
            neighbour: crate::segment::SegmentId(9),
            pair: crate::segment::PairId(1),
        });
        assert!(fill(&mut p).is_empty());
    }

    #[test]
    fn thin_hole_collapses() {
        // Clockwise sliver triangle, width < λ.
        let hole = [
            Point2::new(0.0, 0.0),
            Point2::new(0.01, 0.3),
            Point2::new(0.02, 0.0),
        ];
        assert!(collapse_hole(&hole, 0.05, 1e-6));
        // A wide square hole does not.
        let hole = [
            Point2::new(0.0, 0.0),
            Point2::new(0.0, 0.3),
            Point2::new(0.3, 0.3),
            Point2::new(0.3, 0.0),
        ];
        assert!(!collapse_hole(&hole, 0.05, 1e-6));
    }

    /// A perimeter recorded from a surface follower's sets (cube top, point3):
    /// vertices 22, 23, 0, 1, 2 enclose a pocket whose mouth (v22–v2, 4.8 cm)
    /// is narrower than λ; its walls have five vertices, more than any
    /// fissure type looks at.
    #[allow(clippy::unreadable_literal)]
    fn follower_notch() -> Vec<(Real, Real)> {
        vec![
            (-0.013414, -0.022087),
            (-0.034847, -0.029013),
            (-0.070920, -0.013639),
            (-0.070497, -0.033080),
            (-0.066070, -0.070821),
            (-0.039749, -0.079824),
            (-0.024585, -0.082431),
            (0.014604, -0.067763),
            (0.063195, -0.079550),
            (0.073574, -0.065818),
            (0.114926, -0.065277),
            (0.114778, -0.053933),
            (0.124347, -0.046916),
            (0.096381, -0.013639),
            (0.070687, 0.029254),
            (0.096381, 0.070012),
            (0.059965, 0.071294),
            (0.012730, 0.070012),
            (-0.037266, 0.069386),
            (-0.040035, 0.071294),
            (-0.070920, 0.070012),
            (-0.058294, 0.044405),
            (-0.044165, 0.025958),
            (-0.027866, 0.022638),
        ]
    }

    fn close(p: &mut Poly2) -> usize {
        let mut k = 1000;
        let mut fresh = || {
            k += 1;
            EdgeKey(k)
        };
        close_pockets(p, 0.05, 1e-6, &mut fresh)
    }

    /// The pocket survives the thesis' fissure types and is closed by its chord:
    /// the new polygon is the old one plus the pocket (areas by the shoelace
    /// formula on the original coordinates), and every old vertex is kept or
    /// lies on the pocket's wall.
    #[test]
    fn pocket_behind_a_narrow_mouth_is_closed() {
        let pts = follower_notch();
        let mut p = poly(&pts);
        assert!(p.is_valid(1e-6));
        let mut thesis = p.clone();
        fill(&mut thesis);
        let has = |q: &Poly2, (x, y): (Real, Real)| {
            q.points()
                .iter()
                .any(|v| (v - Point2::new(x, y)).norm() < 1e-12)
        };
        assert!(
            has(&thesis, pts[0]) && has(&thesis, pts[1]) && has(&thesis, pts[23]),
            "fissure types I–VI leave the pocket"
        );
        let area = p.area();
        assert_eq!(close(&mut p), 1);
        assert!(p.is_valid(1e-6));
        let pocket: Vec<Point2> = [22, 23, 0, 1, 2]
            .iter()
            .map(|&i| Point2::new(pts[i].0, pts[i].1))
            .collect();
        let pocket_area = -geom::polygon2::signed_area(&pocket);
        assert!(pocket_area > 0.0);
        assert!((p.area() - (area + pocket_area)).abs() < 1e-12);
        assert_eq!(p.len(), pts.len() - 3);
        for i in [23, 0, 1] {
            assert!(!has(&p, pts[i]));
        }
    }

    /// A mouth of λ or more, a shared edge on the pocket, and a wide cavity
    /// behind a narrow mouth (which would not collapse as a hole) all stay.
    #[test]
    fn wide_mouths_shared_walls_and_cavities_stay() {
        // Scaled by 1.2 the mouth is 5.7 cm.
        let wide: Vec<(Real, Real)> = follower_notch()
            .iter()
            .map(|&(x, y)| (1.2 * x, 1.2 * y))
            .collect();
        let mut p = poly(&wide);
        assert_eq!(close(&mut p), 0);
        assert_eq!(p.len(), wide.len());
        // The pocket's wall v0 v1 shared with a neighbour.
        let mut p = poly(&follower_notch());
        p.nodes[0].edge.share = Some(crate::segment::Share {
            neighbour: crate::segment::SegmentId(9),
            pair: crate::segment::PairId(1),
        });
        assert_eq!(close(&mut p), 0);
        // A 1 m square with a slit 3 cm wide and 0.3 m long in its bottom edge,
        // leading into a 0.3 m square cavity.
        let bottle = [
            (0.0, 0.0),
            (0.485, 0.0),
            (0.485, 0.3),
            (0.35, 0.3),
            (0.35, 0.6),
            (0.65, 0.6),
            (0.65, 0.3),
            (0.515, 0.3),
            (0.515, 0.0),
            (1.0, 0.0),
            (1.0, 1.0),
            (0.0, 1.0),
        ];
        let mut p = poly(&bottle);
        assert!(p.is_valid(1e-6));
        assert_eq!(close(&mut p), 0);
        assert_eq!(p.len(), bottle.len());
        // The same slit without the cavity is a narrow notch: it closes (by
        // the thesis' cascade of fissures already, or as a pocket).
        let slit = [
            (0.0, 0.0),
            (0.485, 0.0),
            (0.485, 0.1),
            (0.48, 0.2),
            (0.49, 0.3),
            (0.51, 0.3),
            (0.52, 0.25),
            (0.515, 0.15),
            (0.515, 0.0),
            (1.0, 0.0),
            (1.0, 1.0),
            (0.0, 1.0),
        ];
        let mut p = poly(&slit);
        fill(&mut p);
        close(&mut p);
        assert!(p.is_valid(1e-6));
        assert!((p.area() - 1.0).abs() < 1e-9, "{}", p.area());
    }
}
