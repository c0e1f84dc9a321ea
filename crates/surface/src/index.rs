//! The spatial index (SPEC §3.4): a uniform hash grid over segment bounding
//! boxes, so an update only looks at segments near the new points.
//!
//! Cell size is `2λ`: a query box loosened by λ (the reach of every operation of
//! P§2.3) touches at most a few cells per dimension. A segment whose box would
//! cover more than [`MAX_CELLS`] cells (a large initial segment such as a table)
//! is kept in a short list that every query returns. Query results are sorted, so
//! the hash map's iteration order never reaches the model.
//!
//! Cells hold *slots*, not segment ids: a merger result takes over the slot of
//! the merged segment with the larger footprint (`Grid::rename`), so absorbing
//! a point into a large polygon costs no cell updates unless the polygon's cell
//! range grows.

use crate::segment::SegmentId;
use geom::{Aabb, Real};
use std::collections::{BTreeMap, HashMap};
use std::hash::{BuildHasherDefault, Hasher};

/// Entries covering more cells than this go to the always-returned list.
pub const MAX_CELLS: i64 = 4096;

type Cell = (i64, i64, i64);
type Slot = u32;

/// FxHash-style hasher for cell keys (deterministic, fast).
#[derive(Default)]
pub(crate) struct CellHasher(u64);

impl Hasher for CellHasher {
    fn finish(&self) -> u64 {
        self.0
    }
    fn write(&mut self, bytes: &[u8]) {
        for b in bytes {
            self.write_u64(u64::from(*b));
        }
    }
    fn write_i64(&mut self, i: i64) {
        self.write_u64(i as u64);
    }
    fn write_u64(&mut self, i: u64) {
        self.0 = (self.0.rotate_left(5) ^ i).wrapping_mul(0x51_7c_c1_b7_27_22_0a_95);
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Footprint {
    Cells { lo: Cell, hi: Cell },
    Big,
}

impl Footprint {
    fn cells(&self) -> i64 {
        match self {
            Self::Big => i64::MAX,
            Self::Cells { lo, hi } => (hi.0 - lo.0 + 1) * (hi.1 - lo.1 + 1) * (hi.2 - lo.2 + 1),
        }
    }
}

#[derive(Clone, Copy, Debug)]
struct Entry {
    id: SegmentId,
    bounds: Aabb,
    footprint: Footprint,
}

/// Uniform grid of segment boxes.
#[derive(Clone, Debug)]
pub(crate) struct Grid {
    cell: Real,
    cells: HashMap<Cell, Vec<Slot>, BuildHasherDefault<CellHasher>>,
    big: Vec<Slot>,
    slots: Vec<Option<Entry>>,
    free: Vec<Slot>,
    by_id: BTreeMap<SegmentId, Slot>,
}

impl Grid {
    pub fn new(cell: Real) -> Self {
        Self {
            cell,
            cells: HashMap::default(),
            big: Vec::new(),
            slots: Vec::new(),
            free: Vec::new(),
            by_id: BTreeMap::new(),
        }
    }

    fn cell_of(&self, x: Real, y: Real, z: Real) -> Cell {
        let f = |v: Real| {
            let c = (v / self.cell).floor();
            if c.is_finite() {
                c.clamp(-1e15, 1e15) as i64
            } else {
                0
            }
        };
        (f(x), f(y), f(z))
    }

    fn footprint(&self, b: &Aabb) -> Footprint {
        if b.is_empty() {
            return Footprint::Big;
        }
        let lo = self.cell_of(b.min.x, b.min.y, b.min.z);
        let hi = self.cell_of(b.max.x, b.max.y, b.max.z);
        let count = (hi.0 - lo.0 + 1)
            .saturating_mul(hi.1 - lo.1 + 1)
            .saturating_mul(hi.2 - lo.2 + 1);
        if count > MAX_CELLS || count <= 0 {
            Footprint::Big
        } else {
            Footprint::Cells { lo, hi }
        }
    }

    fn place(&mut self, slot: Slot, fp: Footprint) {
        match fp {
            Footprint::Big => self.big.push(slot),
            Footprint::Cells { lo, hi } => {
                for x in lo.0..=hi.0 {
                    for y in lo.1..=hi.1 {
                        for z in lo.2..=hi.2 {
                            self.cells.entry((x, y, z)).or_default().push(slot);
                        }
                    }
                }
            }
        }
    }

    fn unplace(&mut self, slot: Slot, fp: Footprint) {
        match fp {
            Footprint::Big => self.big.retain(|s| *s != slot),
            Footprint::Cells { lo, hi } => {
                for x in lo.0..=hi.0 {
                    for y in lo.1..=hi.1 {
                        for z in lo.2..=hi.2 {
                            if let Some(v) = self.cells.get_mut(&(x, y, z)) {
                                v.retain(|s| *s != slot);
                                if v.is_empty() {
                                    self.cells.remove(&(x, y, z));
                                }
                            }
                        }
                    }
                }
            }
        }
    }

    /// Insert `id` with box `b`, or move it there.
    pub fn insert(&mut self, id: SegmentId, b: Aabb) {
        let fp = self.footprint(&b);
        if let Some(&slot) = self.by_id.get(&id) {
            let Some(Some(entry)) = self.slots.get_mut(slot as usize) else {
                return;
            };
            let old = entry.footprint;
            entry.bounds = b;
            entry.footprint = fp;
            if old != fp {
                self.unplace(slot, old);
                self.place(slot, fp);
            }
            return;
        }
        let slot = if let Some(s) = self.free.pop() {
            s
        } else {
            self.slots.push(None);
            (self.slots.len() - 1) as Slot
        };
        if let Some(s) = self.slots.get_mut(slot as usize) {
            *s = Some(Entry {
                id,
                bounds: b,
                footprint: fp,
            });
        }
        self.by_id.insert(id, slot);
        self.place(slot, fp);
    }

    /// Remove `id`.
    pub fn remove(&mut self, id: SegmentId) {
        let Some(slot) = self.by_id.remove(&id) else {
            return;
        };
        let Some(entry) = self.slots.get_mut(slot as usize).and_then(Option::take) else {
            return;
        };
        self.unplace(slot, entry.footprint);
        self.free.push(slot);
    }

    /// Give `old`'s slot to `new` (a merger result replacing `old`); `new` must
    /// not be indexed yet.
    pub fn rename(&mut self, old: SegmentId, new: SegmentId) {
        if self.by_id.contains_key(&new) {
            return;
        }
        let Some(slot) = self.by_id.remove(&old) else {
            return;
        };
        if let Some(Some(entry)) = self.slots.get_mut(slot as usize) {
            entry.id = new;
        }
        self.by_id.insert(new, slot);
    }

    /// Number of cells `id` covers (`i64::MAX` for the always-returned list).
    pub fn cells_of(&self, id: SegmentId) -> i64 {
        self.by_id
            .get(&id)
            .and_then(|s| self.slots.get(*s as usize))
            .and_then(|e| e.as_ref())
            .map_or(0, |e| e.footprint.cells())
    }

    /// Ids whose boxes may meet `b`, sorted and unique.
    pub fn query(&self, b: &Aabb) -> Vec<SegmentId> {
        let fp = self.footprint(b);
        // A box covering more cells than there are entries is cheaper to answer
        // by testing every entry.
        if fp.cells() > 2 * self.by_id.len() as i64 {
            return self
                .by_id
                .iter()
                .filter(|(_, s)| {
                    self.slots
                        .get(**s as usize)
                        .and_then(|e| e.as_ref())
                        .is_some_and(|e| e.bounds.intersects(b))
                })
                .map(|(id, _)| *id)
                .collect();
        }
        let mut slots: Vec<Slot> = self.big.clone();
        match fp {
            Footprint::Big => slots.extend(self.by_id.values().copied()),
            Footprint::Cells { lo, hi } => {
                for x in lo.0..=hi.0 {
                    for y in lo.1..=hi.1 {
                        for z in lo.2..=hi.2 {
                            if let Some(v) = self.cells.get(&(x, y, z)) {
                                slots.extend(v.iter().copied());
                            }
                        }
                    }
                }
            }
        }
        slots.sort_unstable();
        slots.dedup();
        let mut out: Vec<SegmentId> = slots
            .into_iter()
            .filter_map(|s| self.slots.get(s as usize).and_then(|e| e.as_ref()))
            .filter(|e| e.bounds.intersects(b))
            .map(|e| e.id)
            .collect();
        out.sort_unstable();
        out
    }

    /// The box stored for `id`.
    pub fn stored(&self, id: SegmentId) -> Option<Aabb> {
        let slot = self.by_id.get(&id)?;
        self.slots.get(*slot as usize)?.as_ref().map(|e| e.bounds)
    }

    /// Number of indexed segments.
    pub fn len(&self) -> usize {
        self.by_id.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use geom::Point3;

    #[test]
    fn insert_query_remove_rename() {
        let mut g = Grid::new(0.1);
        let b = |x: Real| Aabb::new(Point3::new(x, 0.0, 0.0), Point3::new(x + 0.05, 0.05, 0.0));
        g.insert(SegmentId(1), b(0.0));
        g.insert(SegmentId(2), b(1.0));
        g.insert(
            SegmentId(3),
            Aabb::new(
                Point3::new(-100.0, -100.0, 0.0),
                Point3::new(100.0, 100.0, 0.0),
            ),
        );
        assert_eq!(g.query(&b(0.01)), vec![SegmentId(1), SegmentId(3)]);
        g.insert(SegmentId(1), b(1.0));
        assert_eq!(
            g.query(&b(1.01)),
            vec![SegmentId(1), SegmentId(2), SegmentId(3)]
        );
        g.remove(SegmentId(3));
        assert_eq!(g.query(&b(0.01)), Vec::<SegmentId>::new());
        g.rename(SegmentId(2), SegmentId(7));
        assert_eq!(g.query(&b(1.01)), vec![SegmentId(1), SegmentId(7)]);
        assert_eq!(g.stored(SegmentId(7)), Some(b(1.0)));
        assert_eq!(g.len(), 2);
    }
}
