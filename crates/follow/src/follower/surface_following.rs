//! Current surface following (P§3.4.1, Fig. 29): the branch-and-bound
//! shortest edge path to an incomplete segment, then along it.

use super::{Directive, Flow, Follower, Mode, Termination};
use crate::path::{shortest_edge_path, surface_edges};
use crate::query::{EdgeRef, Feature, ModelPoint, closest_on_perimeter, closest_on_segment};
use geom::{Point3, Vector3};
use std::collections::BTreeSet;
use surface::SegmentId;

impl Follower {
    /// Current surface following (P§3.4.1).
    pub(super) fn surface_following(&mut self, cp: &Point3, closest: &ModelPoint) -> Flow {
        let tol = self.model.config().lambda * 0.5;
        if let Some(s) = self.state.segment
            && (self.segment_complete(s) || !self.state.surface.contains(&s))
        {
            self.state.segment = None;
            self.state.path = None;
        }
        if self.state.path.is_none() {
            let surface: Vec<SegmentId> = self.state.surface.iter().copied().collect();
            let goals: BTreeSet<SegmentId> = surface
                .iter()
                .copied()
                .filter(|s| !self.segment_complete(*s))
                .collect();
            if goals.is_empty() {
                return self.next_surface(cp);
            }
            if goals.contains(&closest.segment) {
                return self.reach_segment(closest.segment);
            }
            let edges = surface_edges(&self.model, &surface);
            if let Some(path) = shortest_edge_path(&edges, cp, tol, |s| goals.contains(&s)) {
                self.state.segment = Some(path.target);
                self.state.path = Some(path);
                self.state.path_follow = 0;
                self.reset_progress();
            } else {
                // No edge path (a point segment, or goals not connected
                // by edges): head straight for the nearest goal.
                let nearest = goals
                    .iter()
                    .filter_map(|s| closest_on_segment(&self.model, *s, cp))
                    .min_by(|a, b| {
                        a.distance
                            .total_cmp(&b.distance)
                            .then(a.segment.cmp(&b.segment))
                    });
                let Some(n) = nearest else {
                    return self.next_surface(cp);
                };
                if n.distance <= self.config.stray_m {
                    return self.reach_segment(n.segment);
                }
                self.state.segment = Some(n.segment);
                return Flow::Go(Directive {
                    dir: n.point - cp,
                    step_limit: None,
                });
            }
        }
        let Some(path) = self.state.path.clone() else {
            return Flow::Again;
        };
        if closest.segment == path.target {
            return self.reach_segment(path.target);
        }
        // The follow edge: the furthest path edge from the follow edge on that
        // is within ρ of the control point (it never moves backwards).
        let rho = self.config.stray_m;
        let mut follow = self.state.path_follow.min(path.edges.len() - 1);
        for (k, e) in path.edges.iter().enumerate().skip(follow) {
            if e.distance_to(cp) < rho {
                follow = k;
            }
        }
        if follow != self.state.path_follow {
            self.state.path_follow = follow;
            self.reset_progress();
        }
        let e = path.edges[follow];
        let along = if path.forward[follow] {
            e.b - e.a
        } else {
            e.a - e.b
        };
        let mut owners = vec![e.segment];
        owners.extend(e.shared_with);
        Flow::Go(self.towards_and_along(cp, &e, &along, &owners))
    }

    /// The current surface is complete. Pudney stops here (Fig. 28); we first
    /// apply Fig. 28's first line again: an incomplete surface still within
    /// sensing range becomes the current surface. Under range noise the
    /// first sets of a face form small polygons whose planes differ by more
    /// than μ, so they neither merge nor share edges, and every slice of such a
    /// fragment finds model outside its edges (P§3.4.3): the fragment the
    /// robot started on was complete after a few steps and the run ended with
    /// 1 % of the cube modelled. Only an empty neighbourhood ends the run.
    pub(super) fn next_surface(&mut self, cp: &Point3) -> Flow {
        match self.choose_surface(cp) {
            Ok(()) => {
                self.state.segment = None;
                self.state.path = None;
                self.reset_progress();
                Flow::Again
            }
            Err(_) => Flow::Stop(Termination::SurfaceComplete),
        }
    }

    pub(super) fn reach_segment(&mut self, s: SegmentId) -> Flow {
        self.state.segment = Some(s);
        self.state.path = None;
        self.state.edge = None;
        self.state.follow = None;
        self.state.gap = None;
        self.state.mode = if self
            .model
            .segment(s)
            .is_some_and(|g| g.as_point().is_some())
        {
            self.state.point = None;
            Mode::Point
        } else {
            Mode::Segment
        };
        self.reset_progress();
        Flow::Again
    }

    /// Eq. 6 with the rule that keeps the control point outside the planes of
    /// the segments the followed edge belongs to (Fig. 29, Fig. 30).
    pub(super) fn towards_and_along(
        &self,
        cp: &Point3,
        e: &EdgeRef,
        along: &Vector3,
        owners: &[SegmentId],
    ) -> Directive {
        for &s in owners {
            if let Some(poly) = self.model.polygon(s)
                && poly.plane().signed_distance(cp) < 0.0
            {
                let (q, feature) = closest_on_perimeter(poly, cp);
                if let Feature::Edge(i) = feature
                    && let Some((a, b)) = poly.edge_points(i)
                {
                    let v1 = cp - q;
                    let v2 = b - a;
                    let s = v1.cross(&v2);
                    if s.norm() > 1e-12 {
                        return Directive {
                            dir: s,
                            step_limit: None,
                        };
                    }
                }
            }
        }
        let foot = e.segment3().closest_point(cp);
        let v1 = foot - cp;
        let d = v1.norm();
        let (delta, rho) = (self.config.desired_distance_m, self.config.stray_m);
        let r = if d <= delta {
            0.0
        } else if d < rho {
            (d - delta) / (rho - delta)
        } else {
            1.0
        };
        let u1 = if d > 1e-12 { v1 / d } else { Vector3::zeros() };
        let n2 = along.norm();
        let u2 = if n2 > 1e-12 {
            along / n2
        } else {
            Vector3::zeros()
        };
        Directive {
            dir: u1 * r + u2 * (1.0 - r),
            step_limit: None,
        }
    }
}
