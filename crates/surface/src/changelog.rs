//! What an update changed, for the surface follower (P§3.4.6).

use crate::segment::{EdgeKey, SegmentId};
use serde::{Deserialize, Serialize};

/// One successful merger (P§2.4): `from[0]` and `from[1]` were replaced by `into`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Merger {
    /// The merged segments (S₁, S₂ of P§2.4).
    pub from: [SegmentId; 2],
    /// The segment that replaced them (S₃).
    pub into: SegmentId,
}

/// The changes one [`SurfaceModel::update`](crate::SurfaceModel::update) made
/// (P§3.4.6): mergers in the order they happened, deleted redundant segments,
/// and the edges that were changed.
///
/// "Changed" follows P§3.4.6: an edge changes when a perimeter section it lies on
/// is removed — extension to a projected point, bridging, union, forming shared
/// edges, filling fissures, forming corner vertices, deleting a segment.
/// Projection onto a new plane and repositioning of shared edges do not change an
/// edge; such edges keep their [`EdgeKey`], also when a merger carries them into
/// the new segment (find them again with
/// [`SurfaceModel::locate_edge`](crate::SurfaceModel::locate_edge)).
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct ChangeLog {
    /// Segments created by this update that still exist at its end (point
    /// segments from the new sensor points, and merger results), in id order.
    pub created: Vec<SegmentId>,
    /// Successful mergers, in order. Chains are possible: a merger's `into` may
    /// be a `from` of a later merger.
    pub mergers: Vec<Merger>,
    /// Redundant segments deleted (P§2.9), in order.
    pub deleted: Vec<SegmentId>,
    /// Edges of segments that existed before the update, addressed as
    /// `(segment, edge index)` in the model as it was *before* the update, that
    /// the update changed or removed.
    pub changed_edges: Vec<(SegmentId, usize)>,
    /// The keys of the same edges.
    pub changed_edge_keys: Vec<EdgeKey>,
    /// Segments marked modified during the update (P§2.3 step 1–2) that still
    /// exist at its end.
    pub modified: Vec<SegmentId>,
}

impl ChangeLog {
    /// What became of segment `id` during the update: the segment that now
    /// represents its points (following chains of mergers), itself when it was not
    /// merged, or `None` when it (or its successor) was deleted.
    ///
    /// ```
    /// use surface::{ChangeLog, Merger, SegmentId};
    /// let log = ChangeLog {
    ///     mergers: vec![
    ///         Merger { from: [SegmentId(1), SegmentId(2)], into: SegmentId(5) },
    ///         Merger { from: [SegmentId(5), SegmentId(3)], into: SegmentId(6) },
    ///     ],
    ///     ..ChangeLog::default()
    /// };
    /// assert_eq!(log.resolve(SegmentId(1)), Some(SegmentId(6)));
    /// assert_eq!(log.resolve(SegmentId(4)), Some(SegmentId(4)));
    /// ```
    pub fn resolve(&self, id: SegmentId) -> Option<SegmentId> {
        let mut current = id;
        for m in &self.mergers {
            if m.from.contains(&current) {
                current = m.into;
            }
        }
        (!self.deleted.contains(&current)).then_some(current)
    }

    /// `true` when edge `index` of segment `id` (pre-update addressing) changed.
    pub fn edge_changed(&self, id: SegmentId, index: usize) -> bool {
        self.changed_edges.contains(&(id, index))
    }
}
