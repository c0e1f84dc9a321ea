//! The safety guard (our addition to P§3.3; Pudney's eq. 3–5 and App. B stay
//! the rule of motion): before a step's actuator change is returned, every
//! link's motion is checked against everything the robot knows of the
//! surface, and a change that would bring a link shape within a margin of it
//! is scaled down, replaced by a retreat, or dropped.
//!
//! What the robot knows, each a lower bound of where surface is:
//! * the surface model;
//! * the segments the model deleted as redundant (P§2.9): a small polygon
//!   deleted beside a larger one still stood for surface, so it is kept here
//!   as it was when deleted;
//! * the initial segments as they were given (P§4.3): the model moves
//!   their vertices when it forms shared edges in their perimeters;
//! * the raw readings of the last few sensor sets (every range finder: the
//!   control point's and the links'), which are surface even before the
//!   model holds them;
//! * past the edges of the model's polygons: a strip of
//!   [`FollowConfig::guard_edge_extension_m`] beyond each unshared edge (the
//!   true face goes on past the outermost points sensed on it), and a brim
//!   of [`FollowConfig::guard_initial_extension_m`] beyond every unshared edge
//!   of an initial segment (a table: no link passes round its edge to behind it),
//!   except the object's own faces given a priori
//!   ([`crate::Follower::mark_object_faces`]);
//! * at a convex fold of the model (a shared edge whose neighbour lies behind
//!   the polygon's plane), optionally [`FollowConfig::guard_convex_edge_margin_m`]
//!   more clearance (off by default): the fold is where two fitted planes
//!   meet, and under range noise a plane tilted by 0.5–2.6° put it 5–23 mm
//!   inside the true edge (arm4 on noisy block2, where the last link's tip
//!   came within 15–19 mm of the true vertical edges beside the −x face).
//!
//! Links are checked as the robot describes them: capsules, and collision
//! meshes triangle by triangle, never a bound around a mesh (a
//! URDF arm's shoulder stands a few centimetres above the table it is
//! mounted on, closer than any capsule around it).
//!
//! A motion is checked along the straight joint path at sub-steps short
//! enough that no point of a link moves more than [`SUB_STEP_M`] between
//! two of them; a link's clearance at each sub-step must exceed the margin
//! by the most it can dip between two sub-steps (a surface point at least
//! D from the axis at both ends of a straight path of length h stays at
//! least √(D² − (h/2)²) from it: under a millimetre for these lengths), so
//! the margin also holds between sub-steps.
//! A link far enough from everything known that its whole travel cannot
//! bring it within the margin is not sampled at all.

use crate::actuator::ceiling_scale;
use crate::body::{LinkBody, Placed};
use crate::config::FollowConfig;
use geom::{Isometry3, Point3, Real, Segment3, Vector3};
use nalgebra::{DVector, Matrix3, Matrix6xX};
pub use record::follow::GuardCounts;
use robot::Robot;
use serde::Serialize;
use std::collections::VecDeque;
use surface::{Polygon, SegmentId, SegmentKind, SurfaceModel};

/// Longest travel of any link point between two checked sub-steps, metres.
pub const SUB_STEP_M: Real = 0.01;

/// How many halvings of a change the guard tries before it retreats.
const HALVINGS: u32 = 4;

/// What the guard did with a step's actuator change.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum GuardAction {
    /// The guard is off, or there was no motion to check.
    #[default]
    None,
    /// The change keeps every link clear: taken as it is.
    Taken,
    /// The change was scaled down (halved until it kept every link clear).
    Scaled,
    /// No scaled change was clear; the robot moved back along the last
    /// change it took.
    Retreated,
    /// Neither the change, a scaled one nor a retreat was clear: the robot
    /// holds still.
    Held,
}

/// Surface the model no longer holds as it was: a deleted segment, or an
/// initial segment as given.
#[derive(Clone, Debug)]
struct Ghost {
    polygon: Option<Polygon>,
    centre: Point3,
    radius: Real,
}

impl Ghost {
    fn of_polygon(g: &Polygon) -> Self {
        let centre = g.centroid();
        let radius = g
            .vertices()
            .map(|v| (v - centre).norm())
            .fold(0.0, Real::max);
        Self {
            polygon: Some(g.clone()),
            centre,
            radius,
        }
    }
}

/// The guard's memory and counters.
#[derive(Clone, Debug)]
pub(crate) struct Guard {
    margin: Real,
    extension: Real,
    initial_extension: Real,
    convex_edge: Real,
    /// Initial segments that are the object's own faces (given a priori),
    /// which get no brim: sorted.
    object_faces: Vec<SegmentId>,
    keep_sets: usize,
    /// The initial segments as given.
    given: Vec<Ghost>,
    ghosts: Vec<Ghost>,
    recent: VecDeque<Vec<Point3>>,
    last_dq: Vec<Real>,
    counts: GuardCounts,
}

impl Guard {
    pub(crate) fn new(config: &FollowConfig) -> Self {
        Self {
            margin: config.guard_margin_m,
            extension: config.guard_edge_extension_m,
            initial_extension: config.guard_initial_extension_m,
            convex_edge: config.guard_convex_edge_margin_m,
            object_faces: Vec::new(),
            keep_sets: config.guard_recent_sets as usize,
            given: Vec::new(),
            ghosts: Vec::new(),
            recent: VecDeque::new(),
            last_dq: Vec::new(),
            counts: GuardCounts::default(),
        }
    }

    pub(crate) fn counts(&self) -> GuardCounts {
        self.counts
    }

    /// Mark initial segments as the object's own faces given a priori: the
    /// guard gives them no brim ([`FollowConfig::guard_initial_extension_m`]).
    pub(crate) fn set_object_faces(&mut self, ids: &[SegmentId]) {
        self.object_faces = ids.to_vec();
        self.object_faces.sort_unstable();
        self.object_faces.dedup();
    }

    /// How many deleted segments the guard keeps.
    pub(crate) fn ghosts(&self) -> usize {
        self.ghosts.len()
    }

    /// Keep the model's initial segments (P§4.3) as they were given: the
    /// model moves their vertices when it forms shared edges and corner
    /// vertices in their perimeters, but the surface they stand for is known
    /// whatever their outline becomes (in a trial run arm4's a-priori +x
    /// face of the cube lost a notch below its top edge to a shared edge
    /// with the top polygon, and the last link came within millimetres of
    /// the true edge there).
    pub(crate) fn keep_given(&mut self, model: &SurfaceModel) {
        for seg in model.segments().filter(|s| s.is_initial()) {
            if let Some(g) = seg.as_polygon() {
                self.given.push(Ghost::of_polygon(g));
            }
        }
    }

    /// Remember what the update just made of the set `points`: the points
    /// themselves and the segments the update deleted.
    pub(crate) fn remember(&mut self, model: &SurfaceModel, points: &[Point3]) {
        for seg in model.deleted_by_last_update() {
            self.ghosts.push(match seg.kind() {
                SegmentKind::Point(p) => Ghost {
                    polygon: None,
                    centre: p.centroid(),
                    radius: 0.0,
                },
                SegmentKind::Polygon(g) => Ghost::of_polygon(g),
            });
        }
        if self.keep_sets > 0 {
            if self.recent.len() == self.keep_sets {
                self.recent.pop_front();
            }
            self.recent.push_back(points.to_vec());
        }
    }

    /// Distance from `axis` to known surface, minus `radius`; `cap` when
    /// nothing known is within `cap` of the link's surface. With it, the
    /// closest points (on the axis, on the surface) when within `cap`.
    fn nearest(
        &self,
        model: &SurfaceModel,
        link: &Placed,
        cap: Real,
    ) -> (Real, Option<(Point3, Point3)>) {
        let reach = cap + link.radius();
        let mut d = reach;
        let mut pair = None;
        model_nearest(
            model,
            Extensions {
                model: self.extension,
                initial: self.initial_extension,
                object_faces: &self.object_faces,
                convex_edge: self.convex_edge,
            },
            link,
            &mut d,
            &mut pair,
        );
        for g in self.given.iter().chain(&self.ghosts) {
            if link.lower_bound_to_point(&g.centre) - g.radius >= d {
                continue;
            }
            let (dg, on_link, on_ghost) = if let Some(p) = &g.polygon {
                link.to_polygon(p, d)
            } else {
                let (dc, c) = link.to_point(&g.centre, d);
                (dc, c, g.centre)
            };
            if dg < d {
                d = dg;
                pair = Some((on_link, on_ghost));
            }
        }
        for p in self.recent.iter().flatten() {
            let (dp, c) = link.to_point(p, d);
            if dp < d {
                d = dp;
                pair = Some((c, *p));
            }
        }
        match pair {
            Some(_) => (d - link.radius(), pair),
            // Nothing within reach: exactly `cap`, not `cap` rounded.
            None => (cap, None),
        }
    }

    fn clearance(&self, model: &SurfaceModel, link: &Placed, cap: Real) -> Real {
        self.nearest(model, link, cap).0
    }

    /// The actuator change to take instead of `dq` at joints `q`: `dq`
    /// itself when every link stays clear, else the largest of `dq / 2^k`
    /// (k ≤ [`HALVINGS`]) that does, else a retreat along the last change
    /// taken, else no motion. A link already within the margin (surface
    /// sensed close only now) is clear when it comes no closer along the
    /// way, and the control point's link only when it also ends
    /// [`ESCAPE_GAIN_M`] farther off (or at the margin); when
    /// nothing else is clear, it retreats straight away from the closest
    /// known surface point.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn check(
        &mut self,
        robot: &Robot,
        world_from_base: &Isometry3,
        bodies: &[LinkBody],
        model: &SurfaceModel,
        config: &FollowConfig,
        q: &[Real],
        dq: Vec<Real>,
    ) -> (Vec<Real>, GuardAction) {
        if dq.iter().all(|d| *d == 0.0) {
            return (dq, GuardAction::None);
        }
        let mut motion = Motion {
            guard: self,
            robot,
            world_from_base,
            bodies,
            model,
            frames: Vec::new(),
            start: Vec::new(),
            start_clearance: Vec::new(),
        };
        if motion.set_start(q).is_none() {
            return (vec![0.0; dq.len()], GuardAction::Held);
        }
        let mut scaled = dq.clone();
        let mut chosen = None;
        for k in 0..=HALVINGS {
            if motion.is_clear(q, &scaled) {
                chosen = Some(k);
                break;
            }
            for d in &mut scaled {
                *d *= 0.5;
            }
        }
        let (out, action) = match chosen {
            Some(0) => (dq, GuardAction::Taken),
            Some(k) => {
                let s = 0.5_f64.powi(k as i32);
                (dq.iter().map(|d| d * s).collect(), GuardAction::Scaled)
            }
            None => {
                let mut motion = motion;
                let back: Vec<Real> = self.last_dq.iter().map(|d| -d).collect();
                if let Some(away) = motion.escape(q, config) {
                    (away, GuardAction::Retreated)
                } else if back.len() == dq.len()
                    && back.iter().any(|d| *d != 0.0)
                    && motion.is_clear(q, &back)
                {
                    (back, GuardAction::Retreated)
                } else {
                    (vec![0.0; dq.len()], GuardAction::Held)
                }
            }
        };
        match action {
            GuardAction::Taken => self.counts.taken += 1,
            GuardAction::Scaled => self.counts.scaled += 1,
            GuardAction::Retreated => self.counts.retreated += 1,
            GuardAction::Held => self.counts.held += 1,
            GuardAction::None => {}
        }
        if matches!(action, GuardAction::Taken | GuardAction::Scaled) {
            self.last_dq.clone_from(&out);
        }
        (out, action)
    }
}

/// One motion check: the links at the start pose and their clearances.
struct Motion<'a> {
    guard: &'a Guard,
    robot: &'a Robot,
    world_from_base: &'a Isometry3,
    bodies: &'a [LinkBody],
    model: &'a SurfaceModel,
    frames: Vec<Isometry3>,
    start: Vec<Placed>,
    /// Each link's clearance at the start, known exactly up to the margin
    /// plus [`START_CAP_M`].
    start_clearance: Vec<Real>,
}

/// How much farther from known surface the control point's link, already
/// within the margin, must end each step (or at the margin): it may back
/// off, not slide along.
const ESCAPE_GAIN_M: Real = 0.002;

/// How far beyond the margin a start clearance is measured: more than any
/// link travels in one step under Pudney's ceilings (γ_p = 0.05 m, γ_r =
/// 3.8° at a metre's reach); a longer travel is sampled all along.
const START_CAP_M: Real = 0.1;

impl Motion<'_> {
    fn place(&mut self, q: &[Real]) -> Option<Vec<Placed>> {
        let all: Vec<usize> = (0..self.bodies.len()).collect();
        self.place_some(q, &all)
    }

    /// Bodies `which` (indices into the bodies) placed at joints `q`, in
    /// that order: a mesh is placed triangle by triangle, so only the
    /// bodies a check needs are.
    fn place_some(&mut self, q: &[Real], which: &[usize]) -> Option<Vec<Placed>> {
        self.robot.fk_into(q, &mut self.frames).ok()?;
        let mut out = Vec::with_capacity(which.len());
        for &i in which {
            let b = self.bodies.get(i)?;
            let f = self.world_from_base * self.frames.get(b.link.0)?;
            out.push(Placed::new(&b.shape, &f));
        }
        Some(out)
    }

    fn set_start(&mut self, q: &[Real]) -> Option<()> {
        self.start = self.place(q)?;
        let cap = self.guard.margin + START_CAP_M;
        self.start_clearance = self
            .start
            .iter()
            .map(|l| self.guard.clearance(self.model, l, cap))
            .collect();
        Some(())
    }

    /// A change moving the link closest to known surface straight away from
    /// it, when a link is within the margin: the link point's position
    /// Jacobian, damped least squares, under the ceilings and limits, halved
    /// until the motion is clear.
    fn escape(&mut self, q: &[Real], config: &FollowConfig) -> Option<Vec<Real>> {
        let margin = self.guard.margin;
        let (i, &c0) = self
            .start_clearance
            .iter()
            .enumerate()
            .min_by(|a, b| a.1.total_cmp(b.1))?;
        if c0 >= margin {
            return None;
        }
        let (_, pair) = self.guard.nearest(self.model, &self.start[i], margin);
        let (on_link, on_surface) = pair?;
        let away = (on_link - on_surface).try_normalize(1e-12)?;
        let link = self.bodies[i].link;
        self.robot.fk_into(q, &mut self.frames).ok()?;
        for f in &mut self.frames {
            *f = self.world_from_base * *f;
        }
        let in_link = self.frames.get(link.0)?.inverse_transform_point(&on_link);
        let mut jac = Matrix6xX::zeros(self.robot.dof());
        self.robot
            .jacobian_into(&self.frames, link, &in_link, &mut jac);
        let j = jac.fixed_rows::<3>(0).into_owned();
        let v = away * (margin - c0 + 0.5 * SUB_STEP_M).min(2.0 * SUB_STEP_M);
        let damping = 1e-4;
        let jjt = &j * j.transpose() + Matrix3::identity() * damping;
        let w = jjt.try_inverse()? * v;
        let mut dq: DVector<Real> = j.transpose() * w;
        dq *= ceiling_scale(self.robot, q, &dq, config);
        if dq.iter().all(|d| *d == 0.0) {
            return None;
        }
        for _ in 0..=HALVINGS {
            let step: Vec<Real> = dq.iter().copied().collect();
            if self.is_clear(q, &step) {
                return Some(step);
            }
            dq *= 0.5;
        }
        None
    }

    /// Whether the straight joint motion `q → q + dq` keeps every link clear.
    fn is_clear(&mut self, q: &[Real], dq: &[Real]) -> bool {
        let margin = self.guard.margin;
        let end_q: Vec<Real> = q.iter().zip(dq).map(|(a, d)| a + d).collect();
        // A retreat along the last change can leave the limits the change
        // kept (the joints moved since).
        if !self.robot.within_limits(&end_q) {
            return false;
        }
        let Some(end) = self.place(&end_q) else {
            return false;
        };
        // Each link's travel: a rigid motion moves the points of a segment
        // at most as far as its farther end point.
        let travel: Vec<Real> = self
            .start
            .iter()
            .zip(&end)
            .map(|(a, b)| a.travel_to(b))
            .collect();
        // Links that must be sampled: those whose travel could bring them
        // within the margin, and those already within it.
        let watched: Vec<usize> = (0..self.start.len())
            .filter(|&i| {
                let c0 = self.start_clearance[i];
                c0 < margin || c0 - travel[i] < margin
            })
            .collect();
        if watched.is_empty() {
            return true;
        }
        let longest = watched.iter().map(|&i| travel[i]).fold(0.0, Real::max);
        // A few per cent more sub-steps than the chord length asks, for the
        // arcs revolute joints sweep between them.
        let n = ((longest * 1.05 / SUB_STEP_M).ceil() as usize).clamp(1, 1000);
        let mut sub_q = q.to_vec();
        for k in 1..=n {
            let s = k as Real / n as Real;
            for ((x, a), d) in sub_q.iter_mut().zip(q).zip(dq) {
                *x = a + d * s;
            }
            let Some(placed) = self.place_some(&sub_q, &watched) else {
                return false;
            };
            for (&i, placed) in watched.iter().zip(&placed) {
                let c0 = self.start_clearance[i];
                let need = if c0 < margin {
                    // Already within the margin: it may not come closer
                    // (and must end farther off, below).
                    c0 - 1e-9
                } else {
                    // Between two sub-steps a surface point at least D from
                    // the axis at both ends of a straight path of length h
                    // stays at least √(D² − (h/2)²) from it.
                    let d = self.start[i].radius() + margin;
                    let h = travel[i] * 1.05 / n as Real;
                    margin + (d - (d * d - 0.25 * h * h).max(0.0).sqrt()) + 1e-4
                };
                // Within the margin, the control point's link must also
                // end the step farther off: the control point's motion drags
                // it along the surface, and let slide along known surface at
                // its depth it met the true surface beyond the model (arm4 on
                // noisy block1 with a 0.03 m margin, 509 contact steps at
                // block1's lower edge). Other links are moved by the
                // reconfiguration, which moves them away; a link the robot's
                // description puts within the margin of the table it stands
                // on (the UR5's shoulder) can never gain, and may still move.
                let need = if k == n && c0 < margin && self.bodies[i].link == self.robot.tool.0 {
                    need.max((c0 + ESCAPE_GAIN_M).min(margin))
                } else {
                    need
                };
                let c = self.guard.clearance(self.model, placed, need);
                if c < need {
                    return false;
                }
            }
        }
        true
    }
}

/// How far the guard takes polygons past their edges.
#[derive(Clone, Copy)]
pub(crate) struct Extensions<'a> {
    /// Unshared edges of the model's polygons.
    pub(crate) model: Real,
    /// Unshared edges of initial segments (the brim) ...
    pub(crate) initial: Real,
    /// ... except those of these (sorted): none.
    pub(crate) object_faces: &'a [SegmentId],
    /// How much nearer than it is a convex shared edge of a polygon that is
    /// not an initial segment counts (0: as near as it is).
    pub(crate) convex_edge: Real,
}

/// Lowers `best` (and sets `pair`: on the axis, on the model) to the
/// distance between `axis` and the model when that is smaller: its point
/// segments, its polygons, a strip `ext.model` wide beyond every unshared
/// edge of a polygon that is not an initial segment, and a brim
/// `ext.initial` wide beyond every unshared edge of an initial segment not
/// one of `ext.object_faces` (a width of 0: none). A polygon ends at the
/// outermost points sensed on its face, and the face may go on past them (at
/// a convex edge whose other face was not modelled yet, arm4's last link met
/// block1's true face 25 mm beyond its polygon); a strip also stands across
/// a convex edge into the free space the robot follows in, so it is only
/// λ/2 wide by default ([`FollowConfig::guard_edge_extension_m`]). A shared
/// edge whose neighbour lies behind the polygon's plane (a convex fold)
/// counts `ext.convex_edge` nearer than it is: the model's fold lies where
/// two fitted planes meet, and a tilted plane puts it inside the true edge
/// ([`FollowConfig::guard_convex_edge_margin_m`]).
pub(crate) fn model_nearest(
    model: &SurfaceModel,
    ext: Extensions<'_>,
    link: &Placed,
    best: &mut Real,
    pair: &mut Option<(Point3, Point3)>,
) {
    let (mid, half) = link.centre_reach();
    let widest = ext.model.max(ext.initial).max(ext.convex_edge);
    let mut ids = model.segments_near(&mid, half + *best + widest);
    ids.sort_unstable();
    let offer = |best: &mut Real, pair: &mut Option<_>, d: Real, on_link, on_model| {
        if d < *best {
            *best = d;
            *pair = Some((on_link, on_model));
        }
    };
    for id in ids {
        let Some(seg) = model.segment(id) else {
            continue;
        };
        match seg.kind() {
            SegmentKind::Point(pt) => {
                let c = pt.centroid();
                let (d, q) = link.to_point(&c, *best);
                offer(best, pair, d, q, c);
            }
            SegmentKind::Polygon(g) => {
                let extend = if !g.is_initial() {
                    ext.model
                } else if ext.object_faces.binary_search(&id).is_ok() {
                    0.0
                } else {
                    ext.initial
                };
                let extend = extend.max(0.0);
                let convex = if g.is_initial() {
                    0.0
                } else {
                    ext.convex_edge.max(0.0)
                };
                let wider = extend.max(convex);
                let (d, on_link, on_model) = link.to_polygon(g, *best + wider);
                offer(best, pair, d, on_link, on_model);
                if wider <= 0.0 || d - wider >= *best {
                    continue;
                }
                let n = g.normal().into_inner();
                for (i, node) in g.nodes().iter().enumerate() {
                    let Some((a, b)) = g.edge_points(i) else {
                        continue;
                    };
                    let share = node.edge.share;
                    // A strip past an unshared edge; the extra clearance at
                    // a shared one, when it proves a convex fold.
                    let strip = if share.is_none() { extend } else { 0.0 };
                    let fold = if share.is_some() { convex } else { 0.0 };
                    let wide = strip.max(fold);
                    if wide <= 0.0 {
                        continue;
                    }
                    let edge = Segment3::new(a, b);
                    let de = link.lower_bound_to_segment(&edge, *best + wide);
                    if de - wide >= *best {
                        continue;
                    }
                    if let Some(sh) = share
                        && fold > 0.0
                        && neighbour_behind(model, sh.neighbour, &a, &n)
                    {
                        let (d, on_link, on_edge) = link.to_segment(&edge, *best + fold);
                        offer(best, pair, d - fold, on_link, on_edge);
                    }
                    if strip <= 0.0 || de - strip >= *best {
                        continue;
                    }
                    let Some(out) = (b - a).cross(&n).try_normalize(1e-12) else {
                        continue;
                    };
                    let out = out * strip;
                    let (d, on_link, on_strip) = link.to_quad(&[a, b, b + out, a + out], &n, *best);
                    offer(best, pair, d, on_link, on_strip);
                }
            }
        }
    }
}

/// Whether polygon `neighbour` (across a shared edge through `a` of a
/// polygon with normal `n`) lies behind that polygon's plane, so that the
/// edge is convex: its centroid more than 1° below the plane as seen from
/// `a`.
fn neighbour_behind(model: &SurfaceModel, neighbour: SegmentId, a: &Point3, n: &Vector3) -> bool {
    let Some(SegmentKind::Polygon(h)) = model.segment(neighbour).map(surface::Segment::kind) else {
        return false;
    };
    let to = h.centroid() - a;
    to.dot(n) < -FOLD_SINE * to.norm()
}

/// The sine of the smallest fold a shared edge is convex by, for
/// [`Extensions::convex_edge`]: 1°.
const FOLD_SINE: Real = 0.017_452;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::body::{LinkShape, link_bodies};
    use proptest::prelude::*;
    use surface::SurfaceConfig;

    /// A model holding one initial square `half` wide at height `z`,
    /// facing up.
    fn floor(z: Real, half: Real) -> SurfaceModel {
        let mut m = SurfaceModel::new(SurfaceConfig::default()).unwrap();
        m.add_initial_segment(&[
            Point3::new(-half, -half, z),
            Point3::new(half, -half, z),
            Point3::new(half, half, z),
            Point3::new(-half, half, z),
        ])
        .unwrap();
        m
    }

    fn check(
        robot: &Robot,
        guard: &mut Guard,
        model: &SurfaceModel,
        q: &[Real],
        dq: Vec<Real>,
    ) -> (Vec<Real>, GuardAction) {
        let bodies = link_bodies(robot);
        let config = FollowConfig::default();
        guard.check(
            robot,
            &Isometry3::identity(),
            &bodies,
            model,
            &config,
            q,
            dq,
        )
    }

    /// The smallest distance of any link capsule from the plane z = `z`
    /// (all links above it), along the straight joint motion, sampled
    /// every 1/400 of it: the analytic oracle of the floor tests.
    fn floor_clearance(robot: &Robot, z: Real, q: &[Real], dq: &[Real]) -> Real {
        let bodies = link_bodies(robot);
        let mut best = Real::INFINITY;
        for k in 0..=400 {
            let s = Real::from(k) / 400.0;
            let qs: Vec<Real> = q.iter().zip(dq).map(|(a, d)| a + d * s).collect();
            let frames = robot.forward_kinematics(&qs).unwrap();
            for b in &bodies {
                let LinkShape::Capsule { axis, radius } = &b.shape else {
                    panic!("capsules only");
                };
                let f = frames[b.link.0];
                let low = (f * axis.a).z.min((f * axis.b).z);
                best = best.min(low - z - radius);
            }
        }
        best
    }

    #[test]
    fn the_brim_keeps_a_link_from_passing_round_a_table_edge() {
        // point3 0.1 outside the edge x = 0.5 of a table at z = 0, asked to
        // drop 0.15 to 0.1 below the table's plane: 0.08 from the table's
        // edge all the way, so without the brim the drop is taken whole.
        let robot = robot::builtin("point3").unwrap();
        let model = floor(0.0, 0.5);
        let q = [0.6, 0.0, 0.05];
        let drop = vec![0.0, 0.0, -0.15];
        let no_brim = FollowConfig {
            guard_initial_extension_m: 0.0,
            ..FollowConfig::default()
        };
        let (dq, action) = check(&robot, &mut Guard::new(&no_brim), &model, &q, drop.clone());
        assert_eq!((dq[2], action), (-0.15, GuardAction::Taken));
        // With the default brim (0.2 past every edge) the table's plane goes
        // on to x = 0.7: halved until the sphere keeps the margin above it
        // (the oracle: the plane z = 0 under the whole motion).
        let mut guard = Guard::new(&FollowConfig::default());
        let (dq, action) = check(&robot, &mut guard, &model, &q, drop.clone());
        assert_eq!(action, GuardAction::Scaled, "{dq:?}");
        assert!(floor_clearance(&robot, 0.0, &q, &dq) >= 0.02, "{dq:?}");
        // A face given a priori gets no brim: the robot works round the
        // object's edges.
        let table = model.segments().next().unwrap().id();
        guard.set_object_faces(&[table]);
        let (dq, action) = check(&robot, &mut guard, &model, &q, drop);
        assert_eq!((dq[2], action), (-0.15, GuardAction::Taken));
    }

    /// Two polygons (not initial segments) meeting at a fold along the line
    /// x = z = 0, with their shared edge formed there (P§2.6): a top
    /// (z = 0, x ≤ 0, facing +z) and a side (x = 0, z ≤ 0, facing +x) make
    /// a convex fold, a floor (z = 0, x ≥ 0) and a wall (x = 0, z ≥ 0) a
    /// concave one.
    fn fold(convex: bool) -> SurfaceModel {
        use surface::testing::{ModelInternals, ShareOutcome};
        let p = Point3::new;
        let mut m = SurfaceModel::new(SurfaceConfig::default()).unwrap();
        let (a, b) = if convex {
            (
                m.insert_test_polygon(
                    &[
                        p(-0.5, -0.4, 0.0),
                        p(-0.02, -0.4, 0.0),
                        p(-0.02, 0.3, 0.0),
                        p(-0.5, 0.3, 0.0),
                    ],
                    200,
                ),
                m.insert_test_polygon(
                    &[
                        p(0.0, -0.3, -0.8),
                        p(0.0, 0.4, -0.8),
                        p(0.0, 0.4, -0.03),
                        p(0.0, -0.3, -0.03),
                    ],
                    200,
                ),
            )
        } else {
            (
                m.insert_test_polygon(
                    &[
                        p(0.02, -0.3, 0.0),
                        p(0.6, -0.3, 0.0),
                        p(0.6, 0.3, 0.0),
                        p(0.02, 0.3, 0.0),
                    ],
                    200,
                ),
                m.insert_test_polygon(
                    &[
                        p(0.0, -0.3, 0.03),
                        p(0.0, 0.3, 0.03),
                        p(0.0, 0.3, 0.4),
                        p(0.0, -0.3, 0.4),
                    ],
                    200,
                ),
            )
        };
        assert_eq!(m.form_shared_edges(a, b), ShareOutcome::Formed(1));
        m
    }

    /// `guard_convex_edge_margin_m` = m: the guard keeps the margin plus m
    /// from a convex fold of the model (a shared edge), and only the margin
    /// from a concave fold or an unshared edge. The oracle is the distance
    /// from point3's centre to the line x = z = 0 (or to the unshared edge's
    /// line), by hand.
    #[test]
    fn convex_edges_are_kept_the_extra_margin_off() {
        let robot = robot::builtin("point3").unwrap();
        let rule = |m: Real| FollowConfig {
            guard_convex_edge_margin_m: m,
            ..FollowConfig::default()
        };
        let edge_distance = |q: &[Real]| q[0].hypot(q[2]);
        // Convex fold. From (0.07, 0, 0.07), 0.0990 from the edge, a move of
        // (−0.03, 0, −0.03) ends 0.0566 from it: 0.0366 clear of the sphere,
        // taken without the rule; with m = 0.025 it must end ≥ 0.02 + 0.02 +
        // 0.025 = 0.065 off, which half the move does (0.0778).
        let model = fold(true);
        let q = [0.07, 0.0, 0.07];
        let dive = vec![-0.03, 0.0, -0.03];
        let (dq, action) = check(
            &robot,
            &mut Guard::new(&rule(0.0)),
            &model,
            &q,
            dive.clone(),
        );
        assert_eq!((dq.clone(), action), (dive.clone(), GuardAction::Taken));
        let (dq, action) = check(
            &robot,
            &mut Guard::new(&rule(0.025)),
            &model,
            &q,
            dive.clone(),
        );
        assert_eq!(action, GuardAction::Scaled, "{dq:?}");
        assert!(
            (dq[0] + 0.015).abs() < 1e-12 && (dq[2] + 0.015).abs() < 1e-12,
            "{dq:?}"
        );
        let end = [q[0] + dq[0], 0.0, q[2] + dq[2]];
        assert!(edge_distance(&end) - 0.02 - 0.025 >= 0.02);
        // Over the top's inside, 0.1 m from the fold, the rule changes
        // nothing: a drop to 0.045 above the top (0.025 clear) is taken.
        let q = [-0.1, 0.0, 0.07];
        let drop = vec![0.0, 0.0, -0.025];
        let (dq, action) = check(
            &robot,
            &mut Guard::new(&rule(0.025)),
            &model,
            &q,
            drop.clone(),
        );
        assert_eq!((dq, action), (drop, GuardAction::Taken));

        // Concave fold, m = 0.05: from (0.07, 0, 0.07) to (0.05, 0, 0.05) the
        // floor and the wall end 0.05 off (0.03 clear): taken. Were the edge
        // counted (0.0707 off, less 0.05), it would be 0.0007 clear.
        let model = fold(false);
        let q = [0.07, 0.0, 0.07];
        let dive = vec![-0.02, 0.0, -0.02];
        let (dq, action) = check(
            &robot,
            &mut Guard::new(&rule(0.05)),
            &model,
            &q,
            dive.clone(),
        );
        assert_eq!((dq, action), (dive, GuardAction::Taken));

        // An unshared edge: the top alone, its edge at x = −0.02, with no
        // strip past it. From (0.05, 0, 0.08) to (0.03, 0, 0.02) the edge
        // comes to √(0.05² + 0.02²) = 0.0539 (nearest at the end): 0.0339
        // clear, taken with m = 0.025 too (counted m nearer, it would be
        // 0.0089 clear).
        let mut top = SurfaceModel::new(SurfaceConfig::default()).unwrap();
        {
            use surface::testing::ModelInternals;
            let p = Point3::new;
            top.insert_test_polygon(
                &[
                    p(-0.5, -0.4, 0.0),
                    p(-0.02, -0.4, 0.0),
                    p(-0.02, 0.3, 0.0),
                    p(-0.5, 0.3, 0.0),
                ],
                200,
            );
        }
        let no_strip = |m: Real| FollowConfig {
            guard_edge_extension_m: 0.0,
            ..rule(m)
        };
        let q = [0.05, 0.0, 0.08];
        let dive = vec![-0.02, 0.0, -0.06];
        let (dq, action) = check(
            &robot,
            &mut Guard::new(&no_strip(0.0)),
            &top,
            &q,
            dive.clone(),
        );
        assert_eq!((dq, action), (dive.clone(), GuardAction::Taken));
        let (dq, action) = check(
            &robot,
            &mut Guard::new(&no_strip(0.025)),
            &top,
            &q,
            dive.clone(),
        );
        assert_eq!((dq, action), (dive, GuardAction::Taken));
        let end = [q[0] - 0.02 + 0.02, 0.0, q[2] - 0.06];
        assert!((edge_distance(&end) - 0.02 - 0.033_852).abs() < 1e-6);
    }

    /// point3 (a sphere of radius 0.02) 0.06 above the floor asked to drop
    /// 0.05: the guard halves the drop until the margin holds (two halvings:
    /// a quarter leaves 0.0275, half would leave 0.015).
    #[test]
    fn a_dive_at_the_model_is_scaled_to_the_margin() {
        let robot = robot::builtin("point3").unwrap();
        let model = floor(0.0, 2.0);
        let mut guard = Guard::new(&FollowConfig::default());
        let q = [0.0, 0.0, 0.06];
        let (dq, action) = check(&robot, &mut guard, &model, &q, vec![0.01, 0.0, -0.05]);
        assert_eq!(action, GuardAction::Scaled);
        assert!((dq[2] + 0.0125).abs() < 1e-12, "{dq:?}");
        assert!(floor_clearance(&robot, 0.0, &q, &dq) >= 0.02);
        assert!(floor_clearance(&robot, 0.0, &q, &[0.0, 0.0, -0.025]) < 0.02);
        // Sideways the floor is no nearer: taken as it is.
        let (dq, action) = check(&robot, &mut guard, &model, &q, vec![0.05, 0.0, 0.0]);
        assert_eq!((dq[0], action), (0.05, GuardAction::Taken));
    }

    /// Raw readings are surface before the model holds them: with an empty
    /// model, the points of the last set stop the same dive.
    #[test]
    fn raw_readings_guard_before_the_model_holds_them() {
        let robot = robot::builtin("point3").unwrap();
        let empty = SurfaceModel::new(SurfaceConfig::default()).unwrap();
        let mut guard = Guard::new(&FollowConfig::default());
        let q = [0.0, 0.0, 0.06];
        let (dq, _) = check(&robot, &mut guard, &empty, &q, vec![0.0, 0.0, -0.05]);
        assert_eq!(dq[2], -0.05, "nothing known: the dive is taken");
        let grid: Vec<Point3> = (-4..=4)
            .flat_map(|i| {
                (-4..=4).map(move |j| Point3::new(0.01 * Real::from(i), 0.01 * Real::from(j), 0.0))
            })
            .collect();
        guard.remember(&empty, &grid);
        let (dq, action) = check(&robot, &mut guard, &empty, &q, vec![0.0, 0.0, -0.05]);
        assert_eq!(action, GuardAction::Scaled);
        assert!(0.06 + dq[2] - 0.02 >= 0.02, "{dq:?}");
        // Readings older than `guard_recent_sets` sets are forgotten.
        for _ in 0..FollowConfig::default().guard_recent_sets {
            guard.remember(&empty, &[]);
        }
        let (dq, _) = check(&robot, &mut guard, &empty, &q, vec![0.0, 0.0, -0.05]);
        assert_eq!(dq[2], -0.05);
    }

    /// Already within the margin (surface sensed close only now), the robot
    /// may back off but neither come closer nor slide along at its depth: a
    /// change must end [`ESCAPE_GAIN_M`] farther off (here point3's 0.02 m
    /// sphere 0.01 m above the floor, so 0.012 m), and a slide or a dive
    /// turns into a retreat straight away from the surface.
    #[test]
    fn within_the_margin_a_dive_becomes_a_retreat() {
        let robot = robot::builtin("point3").unwrap();
        let model = floor(0.0, 2.0);
        let mut guard = Guard::new(&FollowConfig::default());
        let q = [0.0, 0.0, 0.03];
        let (dq, action) = check(&robot, &mut guard, &model, &q, vec![0.05, 0.0, 0.0025]);
        assert_eq!((dq[0], action), (0.05, GuardAction::Taken));
        for slide in [
            vec![0.05, 0.0, 0.0],
            vec![0.05, 0.0, 0.0015],
            vec![0.0, 0.0, -0.02],
        ] {
            let (dq, action) = check(&robot, &mut guard, &model, &q, slide.clone());
            assert_eq!(action, GuardAction::Retreated, "{slide:?}");
            assert!(
                dq[2] > 0.0 && dq[0].abs() < 1e-9 && dq[1].abs() < 1e-9,
                "{slide:?}: {dq:?}"
            );
        }
    }

    /// The lowest point of any moving link's collision mesh over the
    /// straight joint motion, sampled every 1/400 of it: the oracle of the
    /// mesh test.
    fn lowest_mesh_point(robot: &Robot, q: &[Real], dq: &[Real]) -> Real {
        let mut low = Real::INFINITY;
        for k in 0..=400 {
            let s = Real::from(k) / 400.0;
            let qs: Vec<Real> = q.iter().zip(dq).map(|(a, d)| a + d * s).collect();
            let frames = robot.forward_kinematics(&qs).unwrap();
            for (i, link) in robot.links.iter().enumerate().skip(robot.mounted_links()) {
                for shape in &link.collision {
                    if let robot::CollisionShape::Mesh(m) = shape {
                        for v in &m.vertices {
                            low = low.min((frames[i] * v).z);
                        }
                    }
                }
            }
        }
        low
    }

    /// The UR5 of `data/` (collision meshes read) on a floor at z = 0, at
    /// `data/scenarios/ur5_cube.toml`'s start pose. The guard measures each
    /// mesh itself: its clearance from the floor is the mesh's lowest vertex
    /// (the shoulder's 24 mm, the upper arm's 30 mm; a capsule about each
    /// mesh's bounding-ellipsoid axis stood up to 105 mm into the floor, and
    /// in that scenario the arm held still in 509 of 629 steps). A turn of
    /// the shoulder lift that stays clear is taken whole, and a dive of the
    /// wrist to the floor is cut short of the margin (oracle: the lowest
    /// mesh vertex along the motion).
    #[test]
    fn meshes_are_guarded_as_they_are() {
        let path = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../data/robots/ur5/ur5_robot.urdf"
        );
        let loader = |p: &std::path::Path| {
            scene::io::load_mesh(p, 1.0)
                .map(robot::LoadedMesh::Mesh)
                .map_err(|e| e.to_string())
        };
        let ur5 =
            Robot::from_urdf_file_with(std::path::Path::new(path), Some("tool0"), &loader).unwrap();
        let model = floor(0.0, 2.0);
        let margin = FollowConfig::default().guard_margin_m;
        let q = [
            -0.276_380_182,
            -1.764_972_628,
            2.086_270_701,
            -1.892_094_395,
            -std::f64::consts::FRAC_PI_2,
            -0.276_379_906,
        ];
        let start = lowest_mesh_point(&ur5, &q, &[0.0; 6]);
        assert!((0.02..0.03).contains(&start), "{start}");
        let frames = ur5.forward_kinematics(&q).unwrap();
        let guard = Guard::new(&FollowConfig::default());
        let bodies = link_bodies(&ur5);
        let mut meshes = 0;
        for b in &bodies {
            // `ee_link`'s 1 cm box is a capsule.
            let LinkShape::Mesh(m) = &b.shape else {
                continue;
            };
            meshes += 1;
            let f = frames[b.link.0];
            let low = m
                .mesh()
                .vertices
                .iter()
                .map(|v| (f * v).z)
                .fold(Real::INFINITY, Real::min);
            let placed = Placed::new(&b.shape, &f);
            let c = guard.clearance(&model, &placed, 1.0);
            assert!(
                (c - low.min(1.0)).abs() < 1e-9,
                "link {}: {c} against {low}",
                b.link.0
            );
        }
        assert_eq!(meshes, 6, "one for each moving link");
        for lift in [0.03, -0.03] {
            let mut guard = Guard::new(&FollowConfig::default());
            let dq = vec![0.0, lift, 0.0, 0.0, 0.0, 0.0];
            assert!(lowest_mesh_point(&ur5, &q, &dq) > margin + 1e-3);
            let (out, action) = check(&ur5, &mut guard, &model, &q, dq.clone());
            assert_eq!((out, action), (dq, GuardAction::Taken), "lift {lift}");
        }
        // The elbow opened: the wrist swings down through the floor.
        let dive = vec![0.0, 0.0, 1.2, 0.0, 0.0, 0.0];
        assert!(lowest_mesh_point(&ur5, &q, &dive) < 0.0);
        let mut guard = Guard::new(&FollowConfig::default());
        let (out, action) = check(&ur5, &mut guard, &model, &q, dive);
        assert_eq!(action, GuardAction::Scaled);
        assert!(out[2] > 0.0, "{out:?}");
        let low = lowest_mesh_point(&ur5, &q, &out);
        assert!(low >= margin - 1e-4, "{low}");
    }

    /// No change the guard returns leaves the joint limits, a retreat
    /// included: point3 just outside the margin of the floor, 10 mm from its
    /// x limit, with a dive asked; the retreat along the last change taken
    /// (−x) would go 40 mm past the limit, so the robot holds instead.
    #[test]
    fn a_retreat_stays_within_the_joint_limits() {
        let robot = robot::builtin("point3").unwrap();
        let model = floor(0.0, 20.0);
        let mut guard = Guard::new(&FollowConfig::default());
        let limit = robot.limits()[0].unwrap().max;
        let (dq, action) = check(
            &robot,
            &mut guard,
            &model,
            &[limit - 0.01, 0.0, 0.1],
            vec![-0.05, 0.0, 0.0],
        );
        assert_eq!((dq[0], action), (-0.05, GuardAction::Taken));
        let q = [limit - 0.01, 0.0, 0.041];
        let (dq, action) = check(&robot, &mut guard, &model, &q, vec![0.0, 0.0, -0.05]);
        let end: Vec<Real> = q.iter().zip(&dq).map(|(a, d)| a + d).collect();
        assert!(robot.within_limits(&end), "{action:?} to {end:?}");
        assert_eq!(action, GuardAction::Held);
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(200))]
        /// arm4 above a floor at z = 0.3, any pose clear of it by the margin
        /// and any change of up to 0.07 rad a joint: the motion the guard
        /// lets through keeps every link capsule at least the margin from
        /// the floor all along (sampled 400 times), and it lets the whole
        /// change through when the oracle finds the floor far.
        #[test]
        fn arm4_never_comes_within_the_margin_of_a_known_floor(
            q in proptest::collection::vec(-2.5..2.5_f64, 6),
            dq in proptest::collection::vec(-0.07..0.07_f64, 6),
        ) {
            let robot = robot::builtin("arm4").unwrap();
            let model = floor(0.3, 10.0);
            let margin = FollowConfig::default().guard_margin_m;
            prop_assume!(floor_clearance(&robot, 0.3, &q, &[0.0; 6]) >= margin + 1e-3);
            let mut guard = Guard::new(&FollowConfig::default());
            let (taken, action) = check(&robot, &mut guard, &model, &q, dq.clone());
            let along = floor_clearance(&robot, 0.3, &q, &taken);
            prop_assert!(along >= margin - 1e-6, "{action:?}: {along}");
            if floor_clearance(&robot, 0.3, &q, &dq) >= margin + 0.01 {
                prop_assert_eq!(action, GuardAction::Taken);
            }
        }
    }
}
