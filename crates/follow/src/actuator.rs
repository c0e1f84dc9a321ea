//! Actuator changes (P§3.3, eq. 3–5, App. A and B): `θ̇ = J⁺ẋ + α(I − J⁺J)z`,
//! with `z = −∇H` keeping the links away from the surface model, and ceilings
//! γ_p / γ_r on the change.

use crate::body::Placed;
use crate::config::{FollowConfig, Objective};
use crate::guard::{Extensions, model_nearest};
use crate::query::closest_segment_model;
use geom::{Isometry3, Point3, Real, Segment3, Vector3};
use nalgebra::{DMatrix, DVector, Matrix6xX};
use robot::{JointKind, LinkId, Robot};
use surface::SurfaceModel;

pub use crate::body::{LinkBody, LinkMesh, LinkShape, link_bodies};

/// The part of segment `s` farther than `radius` from `c`: up to two pieces.
pub fn outside_ball(s: &Segment3, c: &Point3, radius: Real) -> Vec<Segment3> {
    let d = s.b - s.a;
    let len2 = d.norm_squared();
    if len2 <= 0.0 {
        return if (s.a - c).norm() >= radius {
            vec![*s]
        } else {
            Vec::new()
        };
    }
    // |a + t d − c|² = r² → t² |d|² + 2 t d·(a − c) + |a − c|² − r² = 0.
    let f = s.a - c;
    let b = d.dot(&f);
    let disc = b * b - len2 * (f.norm_squared() - radius * radius);
    if disc <= 0.0 {
        return vec![*s];
    }
    let root = disc.sqrt();
    let (t0, t1) = ((-b - root) / len2, (-b + root) / len2);
    let mut out = Vec::new();
    if t0 > 0.0 {
        out.push(Segment3::new(s.a, s.point_at(t0.min(1.0))));
    }
    if t1 < 1.0 {
        out.push(Segment3::new(s.point_at(t1.max(0.0)), s.b));
    }
    out.retain(|p| p.length() > 1e-9);
    out
}

/// One link's closest approach to the model (eq. 4): `lᵢ` on the link, `sᵢ`
/// on the model.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LinkProximity {
    /// The link.
    pub link: LinkId,
    /// `lᵢ`, base frame.
    pub on_link: Point3,
    /// `sᵢ`, base frame.
    pub on_model: Point3,
    /// `‖lᵢ − sᵢ‖`.
    pub distance: Real,
    /// The link's radius about its axis (a capsule's radius; 0 for a mesh,
    /// measured from its surface).
    pub radius: Real,
}

/// Each link's closest point to the model within `influence` (eq. 4), the
/// control point's own zone (radius δ) excluded from the tool link (P§3.3).
/// `frames` are the link frames in the model's frame.
pub fn link_proximities(
    model: &SurfaceModel,
    bodies: &[LinkBody],
    frames: &[Isometry3],
    control_point: &Point3,
    tool_link: LinkId,
    exclusion: Real,
    influence: Real,
) -> Vec<LinkProximity> {
    let mut out: Vec<LinkProximity> = Vec::new();
    let mut offer = |link: LinkId, d: Real, l: Point3, s: Point3, radius: Real| match out
        .iter_mut()
        .find(|p| p.link == link)
    {
        Some(p) if p.distance <= d => {}
        Some(p) => {
            *p = LinkProximity {
                link,
                on_link: l,
                on_model: s,
                distance: d,
                radius,
            };
        }
        None => out.push(LinkProximity {
            link,
            on_link: l,
            on_model: s,
            distance: d,
            radius,
        }),
    };
    for body in bodies {
        let Some(frame) = frames.get(body.link.0) else {
            continue;
        };
        match &body.shape {
            LinkShape::Capsule { axis, radius } => {
                let axis = Segment3::new(frame * axis.a, frame * axis.b);
                let pieces = if body.link == tool_link {
                    outside_ball(&axis, control_point, exclusion)
                } else {
                    vec![axis]
                };
                for piece in pieces {
                    if let Some((d, l, s, _)) = closest_segment_model(model, &piece, influence) {
                        offer(body.link, d, l, s, *radius);
                    }
                }
            }
            LinkShape::Mesh(_) => {
                let mut placed = Placed::new(&body.shape, frame);
                if body.link == tool_link {
                    placed.drop_triangles_within(control_point, exclusion);
                }
                let mut best = influence;
                let mut pair = None;
                let none = Extensions {
                    model: 0.0,
                    initial: 0.0,
                    object_faces: &[],
                    convex_edge: 0.0,
                };
                model_nearest(model, none, &placed, &mut best, &mut pair);
                if let Some((l, s)) = pair {
                    offer(body.link, best, l, s, 0.0);
                }
            }
        }
    }
    out
}

/// A proximity switch that detects an object (App. B): its position `pᵢ` and
/// the centre `cᵢ` of its sensing field, base frame, on link `link`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SwitchContact {
    /// The link carrying the switch.
    pub link: LinkId,
    /// `pᵢ`.
    pub position: Point3,
    /// `cᵢ`.
    pub field_centre: Point3,
}

/// The reconfiguration vector `z = −∇H` of eq. 5 (link distances), or of
/// App. B (switches), for the robot at link frames `frames`.
pub fn reconfiguration(
    robot: &Robot,
    frames: &[Isometry3],
    objective: Objective,
    proximities: &[LinkProximity],
    switches: &[SwitchContact],
    config: &FollowConfig,
) -> DVector<Real> {
    let dof = robot.dof();
    let mut z = DVector::zeros(dof);
    let d0 = 0.5 * config.influence_m * config.influence_m;
    let g = config.exponent as i32;
    let mut jac = Matrix6xX::zeros(dof);
    let mut add = |link: LinkId, point: &Point3, away: &Vector3, weight: Real| {
        let Some(frame) = frames.get(link.0) else {
            return;
        };
        let in_link = frame.inverse_transform_point(point);
        robot.jacobian_into(frames, link, &in_link, &mut jac);
        for k in 0..dof {
            let r = Vector3::new(jac[(0, k)], jac[(1, k)], jac[(2, k)]);
            z[k] += weight * away.dot(&r);
        }
    };
    match objective {
        Objective::LinkDistance => {
            for p in proximities {
                let d = 0.5 * p.distance * p.distance;
                if d < d0 {
                    let w = (1.0 - d / d0).powi(g - 1);
                    add(p.link, &p.on_link, &(p.on_link - p.on_model), w);
                }
            }
        }
        Objective::ProximitySwitches => {
            for s in switches {
                let d = 0.5 * (s.position - s.field_centre).norm_squared();
                if d < d0 {
                    let w = (1.0 - d / d0).powi(g - 1);
                    add(s.link, &s.position, &(s.position - s.field_centre), w);
                }
            }
        }
    }
    z
}

/// The largest weight `(1 − d/d₀)^(g−1)` that eq. 5 (or App. B's
/// switches) gives any link, `d = ½‖lᵢ − sᵢ‖²` and `d₀ = ½(√(2d₀))²` as in
/// [`reconfiguration`]: 1 at the model, 0 beyond the influence distance.
/// It scales the joint-limit term down where link avoidance needs the null
/// space ([`FollowConfig::joint_limit_yield`]).
pub fn largest_link_weight(
    objective: Objective,
    proximities: &[LinkProximity],
    switches: &[SwitchContact],
    config: &FollowConfig,
) -> Real {
    let d0 = 0.5 * config.influence_m * config.influence_m;
    let g = config.exponent as i32;
    let weight = |d: Real| {
        if d < d0 {
            (1.0 - d / d0).powi(g - 1)
        } else {
            0.0
        }
    };
    let distances: Vec<Real> = match objective {
        Objective::LinkDistance => proximities
            .iter()
            .map(|p| 0.5 * p.distance * p.distance)
            .collect(),
        Objective::ProximitySwitches => switches
            .iter()
            .map(|s| 0.5 * (s.position - s.field_centre).norm_squared())
            .collect(),
    };
    distances.into_iter().map(weight).fold(0.0, Real::max)
}

/// Exponent of the joint-limit cost of [`joint_limit_gradient`]: flat over
/// most of a joint's range, steep near its limits (at 80 % of the way from
/// the middle to a limit the gradient is 3 % of its value at the limit).
pub const JOINT_LIMIT_EXPONENT: i32 = 16;

/// The joint-limit term added to `z` (our addition to eq. 5): `−β ∇H` of
/// `H = Σ ((qₖ − mₖ)/hₖ)^p` over the joints with limits (`mₖ` the middle
/// of the range, `hₖ` half its width, `p` = [`JOINT_LIMIT_EXPONENT`], `β` =
/// [`FollowConfig::joint_limit_gain`]). Pudney's objective watches only the
/// links' distances; arm4 wound its yaw and a wrist roll onto their ±π
/// limits while following block2's +y face, the locked joints left it
/// unable to follow the face, and P§3.4.7 gave up slice after slice (the
/// face ended 47 % modelled). Taken in the null space like the rest of `z`.
/// Off by default: with a gain of 0.01 arm4 met issue 24's criteria in
/// more runs, but one of 21 touched block1 (crate README).
pub fn joint_limit_gradient(robot: &Robot, q: &[Real], config: &FollowConfig) -> DVector<Real> {
    let limits = robot.limits();
    DVector::from_fn(limits.len(), |k, _| match (limits[k], q.get(k)) {
        (Some(l), Some(&qk)) if config.joint_limit_gain > 0.0 => {
            let half = 0.5 * (l.max - l.min);
            if !(half > 0.0 && half.is_finite()) {
                return 0.0;
            }
            let x = (qk - 0.5 * (l.max + l.min)) / half;
            -config.joint_limit_gain
                * Real::from(JOINT_LIMIT_EXPONENT)
                * x.powi(JOINT_LIMIT_EXPONENT - 1)
                / half
        }
        _ => 0.0,
    })
}

/// How close to a limit a joint counts as being at it (rad or m): the limit
/// scaling below stops a joint exactly on its limit, up to rounding.
const AT_LIMIT: Real = 1e-9;

/// Eq. 3 with the ceilings of P§3.3: `θ̇ = J⁺ẋ + α(I − J⁺J)z`, where `J` is the
/// 3 × n positional Jacobian of the control point, under the ceilings γ_r
/// (revolute part) and γ_p (prismatic part) and the joint limits. Pudney
/// scales the whole vector by one factor (the control point keeps its
/// direction); on a redundant robot we grant the control-point term
/// `task_share` of the ceilings first and let the reconfiguration fill the
/// rest (see `share_ceilings`; `task_share = 0` is the thesis' rule).
///
/// `guards` are the rows `n̂ᵀ J_l` of links already closer to the model than
/// their radius plus the margin (`n̂` the unit vector from the model point to
/// the link point, `J_l` the link point's positional Jacobian): the
/// control-point term `J⁺ẋ` loses its part that would bring any of them
/// closer (see `keep_links_off`); the reconfiguration is taken as it is.
/// Pudney's objective alone does not stop a link that the control point's
/// motion drags onto an edge (arm4 brushed block1 in 22 of 1800 steps).
///
/// Joint limits (our addition; P§3.3 has none): a joint already at a limit
/// that eq. 3 would drive further is locked for the step — its column of `J`
/// and its entry of `z` are zeroed, so both terms of eq. 3 are solved by the
/// other joints — and eq. 3, the guard included, is solved again until no
/// locked joint remains pushed out. The guard is thus checked on the motion
/// actually taken. Without the lock, the limit scaling alone stops the
/// whole step for as long as eq. 3 pushes on the limit (arm4 froze with its
/// yaw at π on block1).
pub fn actuator_change(
    robot: &Robot,
    q: &[Real],
    jacobian: &Matrix6xX<Real>,
    motion: &Vector3,
    z: &DVector<Real>,
    guards: &[DVector<Real>],
    config: &FollowConfig,
) -> DVector<Real> {
    let none = DVector::zeros(robot.dof());
    actuator_change_bounded(robot, q, jacobian, motion, z, &none, guards, &[], config)
}

/// [`actuator_change`] with a second reconfiguration vector `z_bounded`
/// (the joint-limit term, [`FollowConfig::joint_limit_keeps_links_off`])
/// whose null-space motion `v = α(I − J⁺J)z_bounded` is bounded by
/// `bounds`, rows `(g, b)` with `g = n̂ᵀ J_l` as in `guards`: `g·v ≥ −b`,
/// a link may come at most `b` closer (to first order). It loses, within
/// the null space, the part that would break a bound (see
/// `keep_links_off_in_null_space`), so it still leaves the control point
/// where it is. `z` (Pudney's link distances) is taken as it is.
#[allow(clippy::too_many_arguments)]
pub fn actuator_change_bounded(
    robot: &Robot,
    q: &[Real],
    jacobian: &Matrix6xX<Real>,
    motion: &Vector3,
    z: &DVector<Real>,
    z_bounded: &DVector<Real>,
    guards: &[DVector<Real>],
    bounds: &[(DVector<Real>, Real)],
    config: &FollowConfig,
) -> DVector<Real> {
    let dof = robot.dof();
    let limits = robot.limits();
    let kinds = robot.joint_kinds();
    let mut locked = vec![false; dof];
    let mut dq = DVector::zeros(dof);
    for _ in 0..=dof {
        dq = eq3(
            &kinds, jacobian, motion, z, z_bounded, guards, bounds, &locked, config,
        );
        if !dq.iter().all(|v| v.is_finite()) {
            return DVector::zeros(dof);
        }
        let mut more = false;
        for (k, lim) in limits.iter().enumerate() {
            if let (Some(lim), Some(&qk), false) = (lim, q.get(k), locked[k])
                && ((qk >= lim.max - AT_LIMIT && dq[k] > 0.0)
                    || (qk <= lim.min + AT_LIMIT && dq[k] < 0.0))
            {
                locked[k] = true;
                more = true;
            }
        }
        if !more {
            break;
        }
    }
    let dq = &dq * ceiling_scale(robot, q, &dq, config);
    match second_order(robot, q, &dq, &locked, config) {
        // The correction is second order; scaling it back under the ceilings
        // leaves a remainder of the order of the excess times that.
        Some(fixed) => &fixed * ceiling_scale(robot, q, &fixed, config),
        None => dq,
    }
}

/// The one factor (≤ 1) that brings `dq` within the ceilings γ_r and γ_p
/// (P§3.3).
fn ceiling_factor(kinds: &[JointKind], dq: &DVector<Real>, config: &FollowConfig) -> Real {
    let (mut rev, mut pri) = (0.0, 0.0);
    for (k, kind) in kinds.iter().enumerate() {
        match kind {
            JointKind::Revolute => rev += dq[k] * dq[k],
            JointKind::Prismatic => pri += dq[k] * dq[k],
            JointKind::Fixed => {}
        }
    }
    let mut scale: Real = 1.0;
    let (rev, pri) = (rev.sqrt(), pri.sqrt());
    if rev > config.ceiling_revolute_rad() {
        scale = scale.min(config.ceiling_revolute_rad() / rev);
    }
    if pri > config.ceiling_prismatic_m {
        scale = scale.min(config.ceiling_prismatic_m / pri);
    }
    scale
}

/// The one factor (≤ 1) that brings `dq` within the ceilings γ_r and γ_p
/// (P§3.3) and keeps every joint within its limits.
pub(crate) fn ceiling_scale(
    robot: &Robot,
    q: &[Real],
    dq: &DVector<Real>,
    config: &FollowConfig,
) -> Real {
    let mut scale = ceiling_factor(&robot.joint_kinds(), dq, config);
    for (k, lim) in robot.limits().iter().enumerate() {
        if let (Some(lim), Some(&qk)) = (lim, q.get(k)) {
            let step = dq[k] * scale;
            if qk + step > lim.max && step > 0.0 {
                scale = scale.min(((lim.max - qk) / dq[k]).max(0.0));
            } else if qk + step < lim.min && step < 0.0 {
                scale = scale.min(((lim.min - qk) / dq[k]).max(0.0));
            }
        }
    }
    scale
}

/// Eq. 3 is a rate equation; taken as a finite step of up to γ_r (3.8°) its
/// control point moves by `J θ̇` only to first order. When the
/// reconfiguration fills the ceiling, the ceiling shrinks the control-point
/// term to a sliver and the second-order remainder (millimetres a step on
/// arm4) outgrows it: the control point crept into block1 while its motion
/// asked to back off. So the remainder is measured by forward kinematics and
/// cancelled by one Newton step `J⁺ r` (our gap fill, joints locked as in
/// eq. 3), which makes the step move the control point as eq. 3 says. The
/// correction (`None` when there is none to make) is dropped if it is not
/// small (a second-order term is); the caller scales the result back under
/// the ceilings and limits.
fn second_order(
    robot: &Robot,
    q: &[Real],
    dq: &DVector<Real>,
    locked: &[bool],
    config: &FollowConfig,
) -> Option<DVector<Real>> {
    let (tool_link, tool) = robot.tool;
    let tool_point = Point3::from(tool.translation.vector);
    let q1: Vec<Real> = q.iter().zip(dq.iter()).map(|(a, b)| a + b).collect();
    let (Ok(j0), Ok(j1), Ok(p0), Ok(p1)) = (
        robot.jacobian(q, tool_link, &tool_point),
        robot.jacobian(&q1, tool_link, &tool_point),
        robot.tool_pose(q),
        robot.tool_pose(&q1),
    ) else {
        return None;
    };
    let predicted = Vector3::from_fn(|r, _| (0..dq.len()).map(|c| j0[(r, c)] * dq[c]).sum());
    let residual = predicted - (p1.translation.vector - p0.translation.vector);
    if residual.norm() < 1e-12 {
        // A linear robot (point3) or a step too small to matter.
        return None;
    }
    let none = DVector::zeros(dq.len());
    let fix = eq3(
        &robot.joint_kinds(),
        &j1,
        &residual,
        &none,
        &none,
        &[],
        &[],
        locked,
        config,
    );
    if !fix.iter().all(|v| v.is_finite()) || fix.norm() > 0.5 * dq.norm() {
        return None;
    }
    Some(dq + fix)
}

/// Eq. 3 with the joints in `locked` held still (their columns of `J` and
/// entries of `z` zeroed: `J⁺` then has zero rows and `I − J⁺J` zero
/// off-diagonal entries for them), the guard applied to its control-point term
/// and to the null-space motion of `z_bounded`.
#[allow(clippy::too_many_arguments)]
fn eq3(
    kinds: &[JointKind],
    jacobian: &Matrix6xX<Real>,
    motion: &Vector3,
    z: &DVector<Real>,
    z_bounded: &DVector<Real>,
    guards: &[DVector<Real>],
    bounds: &[(DVector<Real>, Real)],
    locked: &[bool],
    config: &FollowConfig,
) -> DVector<Real> {
    let dof = locked.len();
    let j = DMatrix::from_fn(
        3,
        dof,
        |r, c| {
            if locked[c] { 0.0 } else { jacobian[(r, c)] }
        },
    );
    let j_pinv = if config.damping > 0.0 {
        robot::damped_pseudo_inverse(&j, config.damping)
    } else {
        robot::pseudo_inverse(&j, 1e-12)
    };
    let xdot = DVector::from_column_slice(motion.as_slice());
    let mut dq = &j_pinv * xdot;
    keep_links_off(&mut dq, guards, locked);
    let z = DVector::from_fn(dof, |k, _| if locked[k] { 0.0 } else { z[k] });
    let zb = DVector::from_fn(dof, |k, _| if locked[k] { 0.0 } else { z_bounded[k] });
    let bounded = zb.iter().any(|v| *v != 0.0);
    if config.alpha > 0.0 && (bounded || z.iter().any(|v| *v != 0.0)) {
        let null = robot::null_space_projector(&j, &j_pinv);
        let mut reconfiguration = (&null * z) * config.alpha;
        if bounded {
            let mut b = (&null * zb) * config.alpha;
            keep_links_off_in_null_space(&mut b, &null, bounds, locked);
            reconfiguration += b;
        }
        // Three free joints or fewer leave no null space for the
        // control point's three coordinates: (I − J⁺J)z is then damping's
        // rounding, summed as before.
        if locked.iter().filter(|l| !**l).count() > 3 {
            dq = share_ceilings(kinds, &dq, &reconfiguration, config);
        } else {
            dq += reconfiguration;
        }
    }
    for (v, l) in dq.iter_mut().zip(locked) {
        if *l {
            *v = 0.0;
        }
    }
    dq
}

/// The link guard on the control-point term: `dq` loses its components
/// along the rows `g` of `guards` (locked joints' entries zeroed) that it
/// would bring closer (`g·dq < 0`), by projection onto each violated
/// half-space in turn, a few rounds; what is left moves the control point
/// as far as the links allow. When the rounds leave a row violated the term
/// is dropped, as it was dropped whole before (arm4 then stood with its
/// control point wedged between the floor and a face, every goal given up
/// by the progress check in turn, with a third of the cube modelled).
fn keep_links_off(dq: &mut DVector<Real>, guards: &[DVector<Real>], locked: &[bool]) {
    if guards.iter().all(|g| g.dot(dq) >= 0.0) {
        return;
    }
    let rows: Vec<DVector<Real>> = guards
        .iter()
        .map(|g| DVector::from_fn(g.len(), |k, _| if locked[k] { 0.0 } else { g[k] }))
        .collect();
    for _ in 0..GUARD_ROUNDS {
        let mut moved = false;
        for g in &rows {
            let gg = g.norm_squared();
            let v = g.dot(dq);
            if v < 0.0 && gg > 1e-18 {
                dq.axpy(-v / gg, g, 1.0);
                moved = true;
            }
        }
        if !moved {
            break;
        }
    }
    if rows.iter().any(|g| g.dot(dq) < -1e-12) {
        dq.fill(0.0);
    }
}

/// The bounds on a null-space motion `v` (`null` = `I − J⁺J`): for each
/// row `(g, b)`, `g·v ≥ −b` (a link comes at most `b` closer, to first
/// order). A broken bound is met along `N g`, the row's own null-space
/// part, so what is left still leaves the control point where it is (to
/// first order), by projection onto each broken half-space in turn, a few
/// rounds; when a bound stays broken the motion is dropped (a row with no
/// null-space part, `gᵀN g` ≈ 0, cannot be met within the null space).
fn keep_links_off_in_null_space(
    v: &mut DVector<Real>,
    null: &DMatrix<Real>,
    bounds: &[(DVector<Real>, Real)],
    locked: &[bool],
) {
    if bounds.iter().all(|(g, b)| g.dot(v) >= -b) {
        return;
    }
    let rows: Vec<(DVector<Real>, DVector<Real>, Real)> = bounds
        .iter()
        .map(|(g, b)| {
            let g = DVector::from_fn(g.len(), |k, _| if locked[k] { 0.0 } else { g[k] });
            let u = null * &g;
            (g, u, *b)
        })
        .collect();
    for _ in 0..GUARD_ROUNDS {
        let mut moved = false;
        for (g, u, b) in &rows {
            let gu = g.dot(u);
            let short = -b - g.dot(v);
            if short > 0.0 && gu > 1e-18 {
                v.axpy(short / gu, u, 1.0);
                moved = true;
            }
        }
        if !moved {
            break;
        }
    }
    if rows
        .iter()
        .any(|(g, _, b)| g.dot(v) < -b - 1e-9 * v.norm().max(1e-12) * g.norm())
    {
        v.fill(0.0);
    }
}

/// Projection rounds of [`keep_links_off`].
const GUARD_ROUNDS: usize = 8;

/// The largest `t` in `[0, 1]` for which `u + t v` keeps the revolute and
/// the prismatic parts within γ_r and γ_p (0 when `u` alone does not).
fn room(kinds: &[JointKind], u: &DVector<Real>, v: &DVector<Real>, config: &FollowConfig) -> Real {
    let mut t: Real = 1.0;
    for (kind, cap) in [
        (JointKind::Revolute, config.ceiling_revolute_rad()),
        (JointKind::Prismatic, config.ceiling_prismatic_m),
    ] {
        let (mut uu, mut uv, mut vv) = (0.0, 0.0, 0.0);
        for (k, _) in kinds.iter().enumerate().filter(|(_, j)| **j == kind) {
            uu += u[k] * u[k];
            uv += u[k] * v[k];
            vv += v[k] * v[k];
        }
        let c = uu - cap * cap;
        if c > 0.0 {
            return 0.0;
        }
        if vv > 0.0 {
            // vv t² + 2 uv t + c ≤ 0, c ≤ 0: t up to the positive root.
            t = t.min(((-uv + (uv * uv - vv * c).sqrt()) / vv).max(0.0));
        }
    }
    t
}

/// Eq. 3's two terms under the ceilings with the control point first (our
/// departure from P§3.3, which scales the whole `θ̇` by one factor): the
/// control-point term `a = J⁺ẋ` is granted up to `task_share` of the
/// ceilings, the reconfiguration `b = α(I − J⁺J)z` fills what is left of
/// them, and `a` then takes any room `b` did not need. With α = 7000,
/// `b` is often hundreds of times the ceilings on arm4, and the one factor
/// left the control point millimetres a step: it idled wedged in corners
/// until P§3.4.7 gave every goal up, and arm4 ended with 61–65 % of the
/// faces it can reach modelled. A `task_share` of 0 returns `a + b` for
/// the one factor to scale.
fn share_ceilings(
    kinds: &[JointKind],
    a: &DVector<Real>,
    b: &DVector<Real>,
    config: &FollowConfig,
) -> DVector<Real> {
    if config.task_share <= 0.0 {
        return a + b;
    }
    let first = ceiling_factor(kinds, &(a / config.task_share), config);
    let granted = a * first;
    let filled = &granted + b * room(kinds, &granted, b, config);
    let rest = a * (1.0 - first);
    let more = room(kinds, &filled, &rest, config);
    filled + rest * more
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn outside_ball_by_hand() {
        let s = Segment3::new(Point3::new(0.0, 0.0, 0.0), Point3::new(0.0, 0.0, 1.0));
        // Ball at the end: one piece, ending 0.1 before it.
        let p = outside_ball(&s, &Point3::new(0.0, 0.0, 1.0), 0.1);
        assert_eq!(p.len(), 1);
        assert!((p[0].b.z - 0.9).abs() < 1e-12);
        // Ball in the middle: two pieces.
        let p = outside_ball(&s, &Point3::new(0.0, 0.0, 0.5), 0.1);
        assert_eq!(p.len(), 2);
        assert!((p[0].b.z - 0.4).abs() < 1e-12 && (p[1].a.z - 0.6).abs() < 1e-12);
        // Ball away: unchanged; ball covering: nothing.
        assert_eq!(outside_ball(&s, &Point3::new(1.0, 0.0, 0.5), 0.1), vec![s]);
        assert!(outside_ball(&s, &Point3::new(0.0, 0.0, 0.5), 2.0).is_empty());
    }

    /// z of eq. 5 equals −∇H of eq. 4 by finite differences (App. A), with the
    /// closest points held fixed on the link as the derivation does.
    #[test]
    fn reconfiguration_is_the_negative_gradient() {
        let robot = robot::builtin("arm4").unwrap();
        let q = [0.3, 0.7, -0.2, 0.9, 0.4, 0.5];
        let cfg = FollowConfig::default();
        let frames = robot.forward_kinematics(&q).unwrap();
        // A fixed model point s near link 4's middle; l is the link point.
        let link = LinkId(6);
        let l_local = Point3::new(0.0, 0.0, 0.5);
        let l = frames[6] * l_local;
        let s = l + Vector3::new(0.05, -0.04, 0.08);
        let prox = [LinkProximity {
            link,
            on_link: l,
            on_model: s,
            distance: (l - s).norm(),
            radius: 0.05,
        }];
        let z = reconfiguration(&robot, &frames, Objective::LinkDistance, &prox, &[], &cfg);
        let d0 = 0.5 * cfg.influence_m * cfg.influence_m;
        let h = |q: &[Real]| {
            let f = robot.forward_kinematics(q).unwrap();
            let l = f[6] * l_local;
            let d = 0.5 * (l - s).norm_squared();
            if d < d0 {
                d0 / Real::from(cfg.exponent) * (1.0 - d / d0).powi(cfg.exponent as i32)
            } else {
                0.0
            }
        };
        for k in 0..6 {
            let (mut qp, mut qm) = (q, q);
            qp[k] += 1e-6;
            qm[k] -= 1e-6;
            let grad = (h(&qp) - h(&qm)) / 2e-6;
            assert!(
                (z[k] + grad).abs() < 1e-7,
                "joint {k}: z {} vs −∇H {}",
                z[k],
                -grad
            );
        }
    }

    /// The null-space term does not move the control point (first order), and
    /// the ceiling holds.
    #[test]
    fn null_space_keeps_the_control_point() {
        let robot = robot::builtin("arm4").unwrap();
        let q = [0.3, 0.7, -0.2, 0.9, 0.4, 0.5];
        let cfg = FollowConfig {
            ceiling_revolute_deg: 1e6,
            damping: 0.0,
            ..FollowConfig::default()
        };
        let frames = robot.forward_kinematics(&q).unwrap();
        let (tool_link, tool) = robot.tool;
        let jac = robot
            .jacobian(&q, tool_link, &Point3::from(tool.translation.vector))
            .unwrap();
        let z = DVector::from_vec(vec![0.1, -0.2, 0.3, 0.05, -0.1, 0.2]);
        let dq = actuator_change(&robot, &q, &jac, &Vector3::zeros(), &z, &[], &cfg);
        assert!(dq.norm() > 1e-3);
        let j3 = DMatrix::from_fn(3, 6, |r, c| jac[(r, c)]);
        assert!((j3 * &dq).norm() < 1e-9 * dq.norm().max(1.0));
        let _ = frames;
        let capped = actuator_change(
            &robot,
            &q,
            &jac,
            &Vector3::zeros(),
            &z,
            &[],
            &FollowConfig::default(),
        );
        // At the ceiling (the second-order correction may leave it a little
        // under).
        let gamma = 3.8_f64.to_radians();
        assert!(capped.norm() <= gamma + 1e-12 && capped.norm() > 0.99 * gamma);
    }

    /// The link guard's projection by hand: a row met head-on takes the
    /// whole change, one met at 45° its part along the row, one the change
    /// moves away from nothing; two rows forming a wedge the change points
    /// out of take it all; a locked joint's entry of a row does not count.
    #[test]
    fn the_link_guard_keeps_what_does_not_close_on_a_link() {
        let v = |x: Real, y: Real, z: Real| DVector::from_vec(vec![x, y, z]);
        let free = [false; 3];
        let guarded = |rows: &[DVector<Real>], locked: &[bool]| {
            let mut dq = v(1.0, 0.0, 0.0);
            keep_links_off(&mut dq, rows, locked);
            dq
        };
        assert_eq!(guarded(&[v(-1.0, 0.0, 0.0)], &free), v(0.0, 0.0, 0.0));
        assert_eq!(guarded(&[v(-1.0, 1.0, 0.0)], &free), v(0.5, 0.5, 0.0));
        assert_eq!(guarded(&[v(1.0, 1.0, 0.0)], &free), v(1.0, 0.0, 0.0));
        let wedge = [v(-1.0, 1.0, 0.0), v(-1.0, -1.0, 0.0)];
        assert_eq!(guarded(&wedge, &free), v(0.0, 0.0, 0.0));
        // Joint 1 locked: the row's entry for it is zeroed, leaving (0, 1, 0),
        // which (1, 0, 0) does not close on.
        assert_eq!(
            guarded(&[v(-1.0, 1.0, 0.0)], &[true, false, false]),
            v(1.0, 0.0, 0.0)
        );
    }

    /// On arm4: the bounds on a null-space motion keep it in the null
    /// space (the control point stays, to first order), let a link come
    /// no more than its bound closer along a row the motion closes on, and
    /// leave a motion that moves away from the row as it is; through
    /// `actuator_change_bounded`, a row it moves away from changes nothing
    /// and one it closes on head-on with no room stops it (up to the
    /// second-order correction).
    #[test]
    fn bounded_reconfiguration_on_arm4() {
        let robot = robot::builtin("arm4").unwrap();
        let q = [0.3, 0.7, -0.2, 0.9, 0.4, 0.5];
        let cfg = FollowConfig {
            ceiling_revolute_deg: 1e6,
            damping: 0.0,
            ..FollowConfig::default()
        };
        let (tool_link, tool) = robot.tool;
        let jac = robot
            .jacobian(&q, tool_link, &Point3::from(tool.translation.vector))
            .unwrap();
        let j3 = DMatrix::from_fn(3, 6, |r, c| jac[(r, c)]);
        let pinv = robot::pseudo_inverse(&j3, 1e-12);
        let null = robot::null_space_projector(&j3, &pinv);
        let zb = DVector::from_vec(vec![0.1, -0.2, 0.3, 0.05, -0.1, 0.2]) * 1e-4;
        let free = &null * &zb * cfg.alpha;
        assert!(free.norm() > 1e-4);
        // A row through link 3's middle (link index 4) against the way the
        // free motion moves it.
        let lj = robot
            .jacobian(&q, LinkId(4), &Point3::new(0.0, 0.0, 0.5))
            .unwrap();
        let moved = Vector3::from_fn(|r, _| (0..6).map(|c| lj[(r, c)] * free[c]).sum());
        let n = geom::unit(moved).unwrap();
        let row = DVector::from_fn(6, |k, _| {
            -(n.x * lj[(0, k)] + n.y * lj[(1, k)] + n.z * lj[(2, k)])
        });
        let closing = -row.dot(&free);
        assert!(
            closing > 1e-5,
            "the free motion closes on the row: {closing}"
        );
        let unlocked = [false; 6];
        for b in [0.0, 0.25 * closing] {
            let mut v = free.clone();
            keep_links_off_in_null_space(&mut v, &null, &[(row.clone(), b)], &unlocked);
            assert!(row.dot(&v) >= -b - 1e-12, "bound {b}: {}", row.dot(&v));
            assert!(v.norm() > 1e-6, "bound {b}: the motion is kept in part");
            assert!(
                (&j3 * &v).norm() < 1e-9 * v.norm(),
                "bound {b}: off the null space"
            );
        }
        let mut v = free.clone();
        keep_links_off_in_null_space(&mut v, &null, &[(-row.clone(), 0.0)], &unlocked);
        assert_eq!(v, free);
        // Through the actuator change.
        let zero = DVector::zeros(6);
        let still = Vector3::zeros();
        let whole = actuator_change_bounded(&robot, &q, &jac, &still, &zero, &zb, &[], &[], &cfg);
        let away = [(-row.clone(), 0.0)];
        let kept = actuator_change_bounded(&robot, &q, &jac, &still, &zero, &zb, &[], &away, &cfg);
        assert_eq!(kept, whole);
        let against = [(row.clone(), 0.0)];
        let bounded =
            actuator_change_bounded(&robot, &q, &jac, &still, &zero, &zb, &[], &against, &cfg);
        assert!(
            row.dot(&bounded) >= -1e-2 * closing,
            "{}",
            row.dot(&bounded)
        );
    }

    /// On arm4: a guard row the control-point motion closes on head-on
    /// stops it; one it moves away from changes nothing.
    #[test]
    fn guard_rows_on_arm4() {
        let robot = robot::builtin("arm4").unwrap();
        let q = [0.3, 0.7, -0.2, 0.9, 0.4, 0.5];
        let cfg = FollowConfig {
            ceiling_revolute_deg: 1e6,
            damping: 0.0,
            ..FollowConfig::default()
        };
        let (tool_link, tool) = robot.tool;
        let jac = robot
            .jacobian(&q, tool_link, &Point3::from(tool.translation.vector))
            .unwrap();
        let motion = Vector3::new(0.01, 0.0, -0.02);
        let free = actuator_change(&robot, &q, &jac, &motion, &DVector::zeros(6), &[], &cfg);
        assert!(free.norm() > 0.0);
        // The control-point term J⁺ẋ, before the second-order correction.
        let j = DMatrix::from_fn(3, 6, |r, c| jac[(r, c)]);
        let task = robot::pseudo_inverse(&j, 1e-12) * DVector::from_column_slice(motion.as_slice());
        let stopped = actuator_change(
            &robot,
            &q,
            &jac,
            &motion,
            &DVector::zeros(6),
            &[-task.clone()],
            &cfg,
        );
        assert!(stopped.norm() < 1e-9 * task.norm(), "{stopped}");
        let kept = actuator_change(&robot, &q, &jac, &motion, &DVector::zeros(6), &[task], &cfg);
        assert!((kept - free).norm() < 1e-12);
    }

    /// A joint at its limit that eq. 3 would drive further is held there while
    /// the other joints still move the control point as asked (checked by
    /// forward kinematics); before, the limit scaling stopped the whole step.
    #[test]
    fn a_joint_at_its_limit_is_locked_not_the_whole_step() {
        let robot = robot::builtin("arm4").unwrap();
        let cfg = FollowConfig {
            ceiling_revolute_deg: 1e6,
            damping: 0.0,
            ..FollowConfig::default()
        };
        let (tool_link, tool) = robot.tool;
        let tool_point = Point3::from(tool.translation.vector);
        let lim = robot.limits()[0].unwrap();
        let q = [lim.max, 0.7, -0.2, 0.9, 0.4, 0.5];
        let jac = robot.jacobian(&q, tool_link, &tool_point).unwrap();
        let z = DVector::zeros(6);
        // A motion the free solution makes with joint 1 turning up its limit.
        let mut motion = Vector3::new(0.01, 0.0, -0.02);
        let free = |m: &Vector3| {
            let j = DMatrix::from_fn(3, 6, |r, c| jac[(r, c)]);
            robot::pseudo_inverse(&j, 1e-12) * DVector::from_column_slice(m.as_slice())
        };
        if free(&motion)[0] < 0.0 {
            motion = -motion;
        }
        assert!(free(&motion)[0] > 1e-4);
        let dq = actuator_change(&robot, &q, &jac, &motion, &z, &[], &cfg);
        assert_eq!(dq[0], 0.0, "joint 1 stays on its limit");
        let cp = |q: &[Real]| robot.tool_pose(q).unwrap() * Point3::origin();
        let q1: Vec<Real> = q.iter().zip(dq.iter()).map(|(a, b)| a + b).collect();
        let moved = cp(&q1) - cp(&q);
        assert!(
            (moved - motion).norm() < 0.1 * motion.norm(),
            "moved {moved:?} for {motion:?}"
        );
        // The guard judges the motion taken: a guard row that the locked
        // solution closes on (and the free one does not) changes it, and
        // the change taken no longer closes on it.
        let locked = dq.clone();
        let f = free(&motion);
        let g = -&locked + &f * (locked.dot(&f) / f.norm_squared());
        assert!(g.dot(&f).abs() < 1e-12 && g.dot(&locked) < 0.0);
        let guarded = actuator_change(
            &robot,
            &q,
            &jac,
            &motion,
            &z,
            std::slice::from_ref(&g),
            &cfg,
        );
        // (To first order: the second-order correction, a Newton step of
        // the order of the step squared, is not projected.)
        assert!(g.dot(&guarded) >= -1e-2 * g.norm() * guarded.norm());
        assert!((&guarded - &locked).norm() > 1e-6);
        assert_eq!(guarded[0], 0.0, "joint 1 stays on its limit");
        // Driven off its limit, the joint is free again.
        let back = actuator_change(&robot, &q, &jac, &-motion, &z, &[], &cfg);
        assert!(back[0] < 0.0);
    }

    /// The ceilings shared, by hand: all-revolute, `a` twice γ_r and `b`
    /// ten times γ_r across it. `a` is granted `task_share` (here 0.3) of γ_r,
    /// `b` the rest of the norm (√(1 − 0.3²) γ_r, the two being
    /// orthogonal); a small `a` is granted whole; `task_share` 0 leaves
    /// the sum to the one factor.
    #[test]
    fn the_ceilings_are_shared_control_point_first() {
        let kinds = [JointKind::Revolute; 3];
        let cfg = FollowConfig {
            task_share: 0.3,
            ..FollowConfig::default()
        };
        let g = cfg.ceiling_revolute_rad();
        let a = DVector::from_vec(vec![2.0 * g, 0.0, 0.0]);
        let b = DVector::from_vec(vec![0.0, 10.0 * g, 0.0]);
        let dq = share_ceilings(&kinds, &a, &b, &cfg);
        let expect = DVector::from_vec(vec![0.3 * g, (1.0_f64 - 0.09).sqrt() * g, 0.0]);
        assert!((&dq - &expect).norm() < 1e-12 * g, "{dq} against {expect}");
        let small = &a * 0.05;
        let dq = share_ceilings(&kinds, &small, &b, &cfg);
        assert!((dq[0] - 0.1 * g).abs() < 1e-15 && (dq.norm() - g).abs() < 1e-12 * g);
        // b small too: nothing to share, both whole.
        let dq = share_ceilings(&kinds, &small, &(&b * 0.01), &cfg);
        assert!((&dq - (&small + &b * 0.01)).norm() < 1e-15);
        let thesis = FollowConfig {
            task_share: 0.0,
            ..cfg
        };
        assert_eq!(share_ceilings(&kinds, &a, &b, &thesis), &a + &b);
    }

    /// The joint-limit term by hand: arm4's joints range over ±π, so at
    /// q₁ = 0.9π the first entry is −β·16·0.9¹⁵/π and at q₂ = −π/2 the
    /// second +β·16·0.5¹⁵/π (β = 0.01); a joint in the middle gives 0;
    /// gain 0 gives 0.
    #[test]
    fn joint_limit_gradient_by_hand() {
        let robot = robot::builtin("arm4").unwrap();
        let cfg = FollowConfig {
            joint_limit_gain: 0.01,
            ..FollowConfig::default()
        };
        let pi = std::f64::consts::PI;
        let q = [0.9 * pi, -0.5 * pi, 0.0, 0.0, 0.0, 0.0];
        let g = joint_limit_gradient(&robot, &q, &cfg);
        let beta = cfg.joint_limit_gain;
        assert!((g[0] + beta * 16.0 * 0.9_f64.powi(15) / pi).abs() < 1e-15);
        assert!((g[1] - beta * 16.0 * 0.5_f64.powi(15) / pi).abs() < 1e-15);
        assert_eq!(g[2], 0.0);
        let off = FollowConfig {
            joint_limit_gain: 0.0,
            ..cfg
        };
        assert!(
            joint_limit_gradient(&robot, &q, &off)
                .iter()
                .all(|v| *v == 0.0)
        );
    }

    /// The weight the joint-limit term yields to, by hand: with Pudney's
    /// influence √(2d₀) = 0.2 and g = 6, a link 0.1 m from the model has
    /// d = 0.005 of d₀ = 0.02 and weight (1 − 0.25)⁵; the largest of the
    /// links counts, a link beyond 0.2 m weighs 0, and one at the model 1.
    #[test]
    fn largest_link_weight_by_hand() {
        let cfg = FollowConfig::default();
        let near = |link: usize, distance: Real| LinkProximity {
            link: LinkId(link),
            on_link: Point3::new(0.0, 0.0, distance),
            on_model: Point3::origin(),
            distance,
            radius: 0.02,
        };
        let w = |ps: &[LinkProximity]| largest_link_weight(Objective::LinkDistance, ps, &[], &cfg);
        assert_eq!(w(&[]), 0.0);
        assert_eq!(w(&[near(1, 0.25)]), 0.0);
        assert!((w(&[near(1, 0.25), near(2, 0.1)]) - 0.75_f64.powi(5)).abs() < 1e-12);
        assert!((w(&[near(1, 0.1), near(2, 0.0)]) - 1.0).abs() < 1e-12);
    }

    /// A step of eq. 3 moves the control point by the first-order `J θ̇`
    /// (checked by forward kinematics), even when the reconfiguration fills the
    /// ceiling: before, a bare null-space step of 3.8° moved it by millimetres.
    #[test]
    fn a_full_step_moves_the_control_point_as_asked() {
        let robot = robot::builtin("arm4").unwrap();
        let cfg = FollowConfig::default();
        let (tool_link, tool) = robot.tool;
        let tool_point = Point3::from(tool.translation.vector);
        let cp = |q: &[Real]| robot.tool_pose(q).unwrap() * Point3::origin();
        let z = DVector::from_vec(vec![0.1, -0.2, 0.3, 0.05, -0.1, 0.2]);
        for (q, motion) in [
            ([0.3, 0.7, -0.2, 0.9, 0.4, 0.5], Vector3::zeros()),
            (
                [1.0, 1.2, 0.4, 1.5, -0.6, 1.1],
                Vector3::new(0.002, 0.0, -0.001),
            ),
        ] {
            let jac = robot.jacobian(&q, tool_link, &tool_point).unwrap();
            let dq = actuator_change(&robot, &q, &jac, &motion, &z, &[], &cfg);
            assert!(dq.norm() > 0.05, "the ceiling is filled");
            let q1: Vec<Real> = q.iter().zip(dq.iter()).map(|(a, b)| a + b).collect();
            let moved = cp(&q1) - cp(&q);
            // The ceiling scales the whole step: the control point moves
            // along the motion asked, no farther, and nowhere for none.
            let (along, across) = match geom::unit(motion) {
                Some(u) => {
                    let along = moved.dot(&u);
                    (along, (moved - u.into_inner() * along).norm())
                }
                None => (0.0, moved.norm()),
            };
            assert!(
                across < 2e-5 && along >= -2e-5 && along <= motion.norm() + 1e-9,
                "moved {moved:?} for {motion:?}"
            );
        }
    }
}
