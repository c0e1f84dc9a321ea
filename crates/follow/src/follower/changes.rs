//! Change tracking (P§3.4.6): the current surface, segment and edges of
//! interest followed through the model's change log, and the completeness
//! tests of segments and edges.

use super::{Follower, Mode};
use crate::path::surface_edges;
use crate::query::{EdgeRef, Feature, ModelPoint};
use std::collections::{BTreeMap, BTreeSet};
use surface::{ChangeLog, EdgeKey, SegmentId};

impl Follower {
    // ---- P§3.4.6: surface modelling changes --------------------------------

    pub(super) fn track_changes(&mut self, log: &ChangeLog) {
        // An edge only leaves the model through a change the log records
        // (removal of its perimeter section, or deletion of its segment);
        // mergers carry unchanged edges, keys and all, into the new segment.
        let changed: BTreeSet<EdgeKey> = log.changed_edge_keys.iter().copied().collect();
        // The current segment through mergers and deletions.
        if let Some(s) = self.state.segment {
            if let Some(n) = log.resolve(s) {
                self.state.segment = Some(n);
            } else {
                self.state.segment = None;
                self.state.edge = None;
                self.state.follow = None;
                self.state.path = None;
                self.state.gap = None;
                self.state.point = None;
                self.state.mode = Mode::Surface;
            }
        }
        if let Some(s) = self.state.edge_segment {
            self.state.edge_segment = log.resolve(s);
        }
        // Marks follow their segments through mergers as the current segment
        // does (P§3.4.6 says so only of the current segment; the thesis is
        // silent on marks). A segment merged with an unreachable one is
        // unreachable until the control point is brought closest to it
        // (P§3.4.1's re-marking), and an unclosable point segment stays
        // unclosable while it is still a point segment. Dropping the marks
        // let a robot standing still, re-sensing the same points (so merging
        // its goal every step), take up the goal it just gave up at once.
        let mut unreachable: BTreeMap<SegmentId, bool> = BTreeMap::new();
        for (s, left) in std::mem::take(&mut self.marks.unreachable_segments) {
            if let Some(n) = log.resolve(s)
                && self.model.segment(n).is_some()
            {
                // Still-stuck (`left` false) wins when two marks merge.
                let e = unreachable.entry(n).or_insert(left);
                *e = *e && left;
            }
        }
        self.marks.unreachable_segments = unreachable;
        self.marks.unclosable_points = std::mem::take(&mut self.marks.unclosable_points)
            .into_iter()
            .filter_map(|s| log.resolve(s))
            .filter(|s| {
                self.model
                    .segment(*s)
                    .is_some_and(|g| g.as_point().is_some())
            })
            .collect();
        if let Some(e) = self.state.edge
            && changed.contains(&e)
        {
            // The current edge changed: choose another (P§3.4).
            self.state.edge = None;
        }
        if let Some(e) = self.state.follow
            && changed.contains(&e)
        {
            self.state.follow = None;
        }
        // The path's target and the owners of its edges through mergers, as
        // the current segment (P§3.4.6): a target merged with new points is
        // still the goal, and recomputing the path on every merger reset the
        // progress check (P§3.4.7) of a robot standing still for good.
        if let Some(path) = self.state.path.as_mut() {
            let from = self.state.path_follow.min(path.edges.len());
            let broken = path.edges[from..].iter().any(|e| changed.contains(&e.key));
            let target = log
                .resolve(path.target)
                .filter(|t| self.model.segment(*t).is_some());
            match target {
                Some(t) if !broken => {
                    path.target = t;
                    for e in &mut path.edges {
                        e.segment = log.resolve(e.segment).unwrap_or(e.segment);
                        e.shared_with = e.shared_with.map(|n| log.resolve(n).unwrap_or(n));
                    }
                }
                _ => self.state.path = None,
            }
        }
        // The current surface: what its members became, and everything now
        // connected to them.
        if self.state.started {
            let members: Vec<SegmentId> = self
                .state
                .surface
                .iter()
                .filter_map(|s| log.resolve(*s))
                .filter(|s| self.model.segment(*s).is_some())
                .collect();
            self.state.surface = self.component_of(&members);
        }
    }

    pub(super) fn component_of(&self, seeds: &[SegmentId]) -> BTreeSet<SegmentId> {
        let mut seen: BTreeSet<SegmentId> = seeds.iter().copied().collect();
        let mut stack: Vec<SegmentId> = seeds.to_vec();
        while let Some(s) = stack.pop() {
            if let Some(p) = self.model.polygon(s) {
                for n in p.neighbours() {
                    if self.model.segment(n).is_some() && seen.insert(n) {
                        stack.push(n);
                    }
                }
            }
        }
        seen
    }

    /// Re-mark as incomplete what the control point is *subsequently* brought
    /// closest to (P§3.4.1, P§3.4.2): a mark made while the control point was
    /// stuck next to its goal must not be undone at once, or a stalled robot
    /// gives up and takes up the same goal forever.
    pub(super) fn remark(&mut self, c: &ModelPoint) {
        let closest_edge = match c.feature {
            Feature::Edge(i) => self
                .model
                .polygon(c.segment)
                .and_then(|p| p.edge(i))
                .map(|e| e.key),
            _ => None,
        };
        self.marks.unreachable_segments.retain(|s, left| {
            if *s == c.segment {
                !*left
            } else {
                *left = true;
                true
            }
        });
        self.marks.unreachable_edges.retain(|e, left| {
            if Some(*e) == closest_edge {
                !*left
            } else {
                *left = true;
                true
            }
        });
    }

    // ---- completeness (P§3.4) ----------------------------------------------

    pub(super) fn edge_complete(&self, e: &EdgeRef) -> bool {
        e.shared_with.is_some()
            || self.marks.unreachable_edges.contains_key(&e.key)
            || self.marks.unclosable_edges.contains(&e.key)
            // A-priori segments (P§4.3) stand for known surface: their free
            // edges are where the description stops, not the border of an
            // unexposed region, so they never call the robot.
            || self.model.segment(e.segment).is_some_and(surface::Segment::is_initial)
    }

    pub(super) fn segment_complete(&self, id: SegmentId) -> bool {
        if self.marks.unreachable_segments.contains_key(&id)
            || self.marks.unclosable_points.contains(&id)
        {
            return true;
        }
        let Some(seg) = self.model.segment(id) else {
            return true;
        };
        if seg.is_initial() {
            return true;
        }
        let Some(poly) = seg.as_polygon() else {
            return false;
        };
        (0..poly.len()).all(|i| {
            poly.edge(i).is_none_or(|e| {
                e.share.is_some()
                    || self.marks.unreachable_edges.contains_key(&e.key)
                    || self.marks.unclosable_edges.contains(&e.key)
            })
        })
    }

    pub(super) fn edges_of(&self, id: SegmentId) -> Vec<EdgeRef> {
        surface_edges(&self.model, &[id])
    }
}
