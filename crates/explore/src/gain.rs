//! Information gains: how Stage One scores a candidate's predicted sweep
//! (`[explore] gain`, issue 49).
//!
//! A candidate's sweep is predicted by casting its rays through the planning
//! grid ([`StageOne`](crate::StageOne), A§4.2, Fig. 4.3): each ray passes
//! free and unknown voxels in order and stops at the first occupied one.
//! What the rays pass is kept once per predicted sweep as a [`Trace`], and
//! a [`Gain`] turns it into a score, larger the better; the choice
//! (`selection = "information"`) takes the safe, clear candidate with the
//! largest score. [`GainContext`] holds what is the same for every
//! candidate of a decision: the grid, each voxel's A§4.2 information, the
//! information now and before the first sweep, and, computed at most once
//! per decision when a gain asks, each voxel's distance to the nearest
//! occupied voxel.
//!
//! The gains ([`GainKind`]):
//!
//! | `gain` | score | source |
//! |---|---|---|
//! | `"information"` | `ΔH1/H1₀ + ΔH2/H2₀`, each unknown voxel once | ours (A eq. 4.11, 4.14) |
//! | `"paul_f1"` | `ΔH1`: the weighted geometric information revealed | A§3.2.1.1, eq. 3.1, 4.11 |
//! | `"average_entropy"` | `Σ I_o(x) / N` over the `N` voxels the rays pass | Kriegel et al. 2015, as D compares it |
//! | `"occlusion_aware"` | `Σ P_v(x) I_o(x)` | D, occlusion aware |
//! | `"unobserved_voxel"` | `Σ P_v(x) I_u(x)` | D, unobserved voxel |
//! | `"rear_side_voxel"` | `Σ I_b(x)` | D, rear side voxel |
//! | `"rear_side_entropy"` | `Σ P_v(x) I_o(x)` over rear-side runs | D, rear side entropy |
//! | `"proximity_count"` | `Σ (d_max − d(x))` over unknown `x` with `d(x) ≤ d_max` | D, proximity count |
//!
//! D is Delmerico, Isler, Scaramuzza, "A comparison of volumetric
//! information gain metrics for active 3D object reconstruction",
//! Autonomous Robots 42 (2018) 197–208, whose symbols these are:
//!
//! * `P_o(x)` the voxel's probability of occupancy: 0.5 unknown, 0 free,
//!   1 occupied in our grid (A§4.2);
//! * `I_o(x) = −P_o ln P_o − (1 − P_o) ln(1 − P_o)`, the voxel's entropy
//!   (ln 2 unknown, 0 known here);
//! * `P_v(x_n) = Π_{i<n} (1 − P_o(x_i))`, the probability that the `n`-th
//!   voxel of a ray is visible: the voxels before it on the ray are free
//!   (each unknown one before it halves it);
//! * `I_u(x) = 1` when `x` is unknown, else 0;
//! * `I_b(x) = 1` when `x` is a rear-side voxel: an unknown voxel directly
//!   before the occupied voxel the ray stops at (the ray reaches the far
//!   side of a surface seen from elsewhere), counted without `P_v` as the
//!   reference implementation below counts them;
//! * a rear-side run: the unknown voxels directly before the occupied voxel
//!   a ray stops at (the ray's last unknown voxels, no known voxel between
//!   them and the hit); rays that stop at no occupied voxel have none;
//! * `d(x)` the distance from the centre of unknown voxel `x` to the centre
//!   of the nearest occupied voxel, `d_max` = [`PROXIMITY_RADIUS_M`].
//!
//! D's sums run over rays: a voxel met by two rays counts twice, with each
//! ray's `P_v` (the predicted rays are 2° apart, about one per 0.1 m voxel
//! at 3 m). The reference implementation (ETH's `ig_active_reconstruction`)
//! multiplies `P_v` by `P_o` rather than `1 − P_o`: the two agree on unknown
//! voxels (0.5), but a free voxel (0) would make every voxel behind it
//! invisible there. We follow D's `P_v`, under which free voxels do not
//! occlude.

use geom::{Point3, Real, UnitVector3};
use map::{OccupancyGrid, VoxelKey, VoxelState};
use serde::{Deserialize, Serialize};
use std::fmt;
use std::sync::{Arc, OnceLock};

/// `d_max` of the proximity count, metres: unknown voxels farther than this
/// from every occupied voxel score nothing.
pub const PROXIMITY_RADIUS_M: Real = 0.5;

/// One voxel a predicted ray passes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Step {
    /// Its storage slot in the grid ([`map::GridGeometry::slot_of`]).
    pub slot: u32,
    /// Its state when the decision is made.
    pub state: VoxelState,
}

/// What the rays of one predicted sweep pass, ray by ray, from the scanner
/// outwards: free and unknown voxels, and the occupied voxel a ray stops at
/// as its last step. Built once per candidate and read by every gain.
#[derive(Clone, Debug, Default)]
pub struct Trace {
    steps: Vec<Step>,
    /// End of each ray's steps in `steps`.
    ends: Vec<usize>,
    /// Unknown voxels passed, each once, in the order first met.
    unknown: Vec<u32>,
    /// Per slot: `mark` when the slot is in `unknown`.
    stamp: Vec<u32>,
    mark: u32,
    /// Whether `steps` and `ends` are kept.
    keep_steps: bool,
}

impl Trace {
    /// An empty trace.
    pub fn new() -> Self {
        Self::default()
    }

    /// The trace of `rays` (origin, direction) cast through `grid` up to
    /// `max_range_m` ([`OccupancyGrid::cast_slots`]), replacing what this
    /// one held (its buffers are reused).
    pub fn cast(
        &mut self,
        grid: &OccupancyGrid,
        max_range_m: Real,
        rays: impl IntoIterator<Item = (Point3, UnitVector3)>,
    ) {
        self.begin(grid.geometry().slot_count(), true);
        for (origin, dir) in rays {
            self.cast_ray(grid, &origin, &dir, max_range_m);
        }
    }

    /// Empty the trace for a new sweep on a grid of `slots` storage slots,
    /// keeping the rays' steps or only the distinct unknown voxels.
    pub(crate) fn begin(&mut self, slots: usize, keep_steps: bool) {
        self.keep_steps = keep_steps;
        self.steps.clear();
        self.ends.clear();
        self.unknown.clear();
        if self.stamp.len() != slots {
            self.stamp = vec![0; slots];
            self.mark = 0;
        }
        self.mark = self.mark.wrapping_add(1);
        if self.mark == 0 {
            self.stamp.fill(0);
            self.mark = 1;
        }
    }

    /// Add one ray (after [`Trace::begin`]).
    pub(crate) fn cast_ray(
        &mut self,
        grid: &OccupancyGrid,
        origin: &Point3,
        dir: &UnitVector3,
        max_range_m: Real,
    ) {
        grid.cast_slots(origin, dir, max_range_m, |_: VoxelKey, slot, state| {
            let slot = slot as u32;
            if state == VoxelState::Unknown && self.stamp[slot as usize] != self.mark {
                self.stamp[slot as usize] = self.mark;
                self.unknown.push(slot);
            }
            if self.keep_steps {
                self.steps.push(Step { slot, state });
            }
        });
        if self.keep_steps {
            self.ends.push(self.steps.len());
        }
    }

    /// The rays, each its steps in order from the scanner (none when the
    /// gain scoring it does not [read steps](Gain::reads_steps)).
    pub fn rays(&self) -> impl ExactSizeIterator<Item = &[Step]> + '_ {
        (0..self.ends.len()).map(|i| {
            let start = if i == 0 { 0 } else { self.ends[i - 1] };
            &self.steps[start..self.ends[i]]
        })
    }

    /// Every step of every ray.
    pub fn steps(&self) -> &[Step] {
        &self.steps
    }

    /// The slots of the unknown voxels passed, each once.
    pub fn distinct_unknown(&self) -> &[u32] {
        &self.unknown
    }
}

/// What every candidate of one decision shares: the grid and the
/// information its voxels hold.
pub struct GainContext<'a> {
    grid: &'a OccupancyGrid,
    information: &'a [[Real; 2]],
    now: (Real, Real),
    initial: (Real, Real),
    proximity: OnceLock<Vec<f32>>,
}

impl fmt::Debug for GainContext<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("GainContext")
            .field("now", &self.now)
            .field("initial", &self.initial)
            .finish_non_exhaustive()
    }
}

impl<'a> GainContext<'a> {
    /// The context of a decision on `grid`: `information` is its
    /// [`OccupancyGrid::information_by_slot`], `now` and `initial` the
    /// `(H1 weighted, H2)` now and before the first sweep.
    pub fn new(
        grid: &'a OccupancyGrid,
        information: &'a [[Real; 2]],
        now: (Real, Real),
        initial: (Real, Real),
    ) -> Self {
        Self {
            grid,
            information,
            now,
            initial,
            proximity: OnceLock::new(),
        }
    }

    /// The planning grid.
    pub fn grid(&self) -> &OccupancyGrid {
        self.grid
    }

    /// What revealing the voxel of `slot` is worth: `[`[`OccupancyGrid::h1_weight`]`,
    /// `[`OccupancyGrid::cspace_information`]`]`, zeros for a known voxel.
    pub fn information(&self, slot: u32) -> [Real; 2] {
        self.information
            .get(slot as usize)
            .copied()
            .unwrap_or([0.0; 2])
    }

    /// `(H1 weighted, H2)` now.
    pub fn information_now(&self) -> (Real, Real) {
        self.now
    }

    /// `(H1 weighted, H2)` before the first sweep.
    pub fn initial_information(&self) -> (Real, Real) {
        self.initial
    }

    /// The distance from the voxel of `slot` to the nearest occupied voxel
    /// (centre to centre, metres), when it is at most
    /// [`PROXIMITY_RADIUS_M`]. Computed for the whole grid at the first call
    /// of a decision.
    pub fn occupied_distance_m(&self, slot: u32) -> Option<Real> {
        let d = self.proximity.get_or_init(|| occupied_distances(self.grid));
        d.get(slot as usize)
            .copied()
            .filter(|d| d.is_finite())
            .map(Real::from)
    }
}

/// How a candidate's predicted sweep is scored: larger is better. Add one by
/// implementing it and giving it to [`Setup::with_gain`](crate::Setup::with_gain).
pub trait Gain: Send + Sync + fmt::Debug {
    /// A short name (reports and errors).
    fn name(&self) -> &str;

    /// The score of the sweep whose rays passed `trace`.
    fn score(&self, trace: &Trace, context: &GainContext<'_>) -> Real;

    /// Whether [`Gain::score`] reads the rays ([`Trace::rays`],
    /// [`Trace::steps`]). A gain that reads only
    /// [`Trace::distinct_unknown`] says false, and the rays' steps are not
    /// kept (a decision of ours on bridge1 took twice as long keeping them).
    fn reads_steps(&self) -> bool {
        true
    }
}

/// The built-in gains, by their `[explore] gain` name (see the
/// [module docs](self) for each formula).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum GainKind {
    /// Ours: `ΔH1/H1₀ + ΔH2/H2₀`.
    #[default]
    Information,
    /// Paul's f1 alone: `ΔH1`.
    PaulF1,
    /// Average entropy of the voxels passed.
    AverageEntropy,
    /// Visibility-weighted entropy.
    OcclusionAware,
    /// Visibility-weighted count of unknown voxels.
    UnobservedVoxel,
    /// Count of rear-side voxels.
    RearSideVoxel,
    /// Visibility-weighted entropy of rear-side runs.
    RearSideEntropy,
    /// Unknown voxels near occupied ones.
    ProximityCount,
}

impl GainKind {
    /// Every built-in gain.
    pub const ALL: [GainKind; 8] = [
        Self::Information,
        Self::PaulF1,
        Self::AverageEntropy,
        Self::OcclusionAware,
        Self::UnobservedVoxel,
        Self::RearSideVoxel,
        Self::RearSideEntropy,
        Self::ProximityCount,
    ];

    /// The gain.
    pub fn gain(self) -> Arc<dyn Gain> {
        match self {
            Self::Information => Arc::new(Information),
            Self::PaulF1 => Arc::new(PaulF1),
            Self::AverageEntropy => Arc::new(AverageEntropy),
            Self::OcclusionAware => Arc::new(OcclusionAware),
            Self::UnobservedVoxel => Arc::new(UnobservedVoxel),
            Self::RearSideVoxel => Arc::new(RearSideVoxel),
            Self::RearSideEntropy => Arc::new(RearSideEntropy),
            Self::ProximityCount => Arc::new(ProximityCount),
        }
    }
}

/// `I_o`: the entropy of a voxel of occupancy probability `p`, nats
/// (`0 ln 0 = 0`).
pub fn entropy(p: Real) -> Real {
    let h = |x: Real| if x > 0.0 { -x * x.ln() } else { 0.0 };
    h(p) + h(1.0 - p)
}

fn p_o(step: Step) -> Real {
    step.state.occupancy_probability()
}

/// `Σ P_v(x) w(x)` along one ray, `P_v` of each voxel the product of
/// `1 − P_o` of those before it.
fn visible_sum(ray: &[Step], w: impl Fn(&Step) -> Real) -> Real {
    let mut p_v = 1.0;
    let mut sum = 0.0;
    for s in ray {
        sum += p_v * w(s);
        p_v *= 1.0 - p_o(*s);
    }
    sum
}

/// Ours: the share of the initial geometric information plus the share of
/// the initial C-space information the sweep reveals, each unknown voxel
/// counted once (`selection = "information"` before gains were pluggable).
#[derive(Clone, Copy, Debug, Default)]
pub struct Information;

impl Gain for Information {
    fn name(&self) -> &'static str {
        "information"
    }
    fn reads_steps(&self) -> bool {
        false
    }
    fn score(&self, trace: &Trace, context: &GainContext<'_>) -> Real {
        let (g1, g2) = revealed(trace, context);
        let (h1, h2) = context.information_now();
        let (h10, h20) = context.initial_information();
        // As `H − f` with f = H − g: the same arithmetic as the rank sum's
        // objectives, so the choice is the one made before gains were
        // pluggable, bit for bit.
        let share = |gain: Real, of: Real| if of > 0.0 { gain / of } else { 0.0 };
        share(h1 - (h1 - g1), h10) + share(h2 - (h2 - g2), h20)
    }
}

/// The information `(geometric weighted, C-space)` of the unknown voxels
/// passed, each once (A eq. 4.11, 4.14).
pub(crate) fn revealed(trace: &Trace, context: &GainContext<'_>) -> (Real, Real) {
    trace
        .distinct_unknown()
        .iter()
        .fold((0.0, 0.0), |(a, b), &slot| {
            let [h1, h2] = context.information(slot);
            (a + h1, b + h2)
        })
}

/// Paul's f1 as a gain: `ΔH1`, the weighted geometric information the sweep
/// reveals (A eq. 3.1 with 4.11; f1 is what remains, `H1 − ΔH1`).
#[derive(Clone, Copy, Debug, Default)]
pub struct PaulF1;

impl Gain for PaulF1 {
    fn name(&self) -> &'static str {
        "paul_f1"
    }
    fn reads_steps(&self) -> bool {
        false
    }
    fn score(&self, trace: &Trace, context: &GainContext<'_>) -> Real {
        revealed(trace, context).0
    }
}

/// D's average entropy (after Kriegel et al. 2015): `Σ I_o(x)` over every
/// voxel every ray passes, the occupied voxels they stop at included, over
/// their number; 0 when the rays pass none.
#[derive(Clone, Copy, Debug, Default)]
pub struct AverageEntropy;

impl Gain for AverageEntropy {
    fn name(&self) -> &'static str {
        "average_entropy"
    }
    fn score(&self, trace: &Trace, _: &GainContext<'_>) -> Real {
        let steps = trace.steps();
        if steps.is_empty() {
            return 0.0;
        }
        steps.iter().map(|s| entropy(p_o(*s))).sum::<Real>() / steps.len() as Real
    }
}

/// D's occlusion-aware gain: `Σ P_v(x) I_o(x)` over every ray's voxels.
#[derive(Clone, Copy, Debug, Default)]
pub struct OcclusionAware;

impl Gain for OcclusionAware {
    fn name(&self) -> &'static str {
        "occlusion_aware"
    }
    fn score(&self, trace: &Trace, _: &GainContext<'_>) -> Real {
        trace
            .rays()
            .map(|r| visible_sum(r, |s| entropy(p_o(*s))))
            .sum()
    }
}

/// D's unobserved-voxel gain: `Σ P_v(x) I_u(x)`, the visibility-weighted
/// count of unknown voxels.
#[derive(Clone, Copy, Debug, Default)]
pub struct UnobservedVoxel;

impl Gain for UnobservedVoxel {
    fn name(&self) -> &'static str {
        "unobserved_voxel"
    }
    fn score(&self, trace: &Trace, _: &GainContext<'_>) -> Real {
        trace
            .rays()
            .map(|r| visible_sum(r, |s| Real::from(u8::from(s.state == VoxelState::Unknown))))
            .sum()
    }
}

/// Whether a ray stops at an occupied voxel reached directly from an
/// unknown one: the index where its rear-side run starts, if so.
fn rear_side_run(ray: &[Step]) -> Option<usize> {
    let (hit, before) = ray.split_last()?;
    if hit.state != VoxelState::Occupied || before.last()?.state != VoxelState::Unknown {
        return None;
    }
    let known = before
        .iter()
        .rposition(|s| s.state != VoxelState::Unknown)
        .map_or(0, |i| i + 1);
    Some(known)
}

/// D's rear-side voxel count: `Σ I_b(x)`, one for each ray that reaches an
/// occupied voxel directly from an unknown one.
#[derive(Clone, Copy, Debug, Default)]
pub struct RearSideVoxel;

impl Gain for RearSideVoxel {
    fn name(&self) -> &'static str {
        "rear_side_voxel"
    }
    fn score(&self, trace: &Trace, _: &GainContext<'_>) -> Real {
        trace.rays().filter(|r| rear_side_run(r).is_some()).count() as Real
    }
}

/// D's rear-side entropy: on each ray that reaches an occupied voxel
/// directly from an unknown one, `Σ P_v(x) I_o(x)` over the rear-side run
/// (`P_v` from the ray's start).
#[derive(Clone, Copy, Debug, Default)]
pub struct RearSideEntropy;

impl Gain for RearSideEntropy {
    fn name(&self) -> &'static str {
        "rear_side_entropy"
    }
    fn score(&self, trace: &Trace, _: &GainContext<'_>) -> Real {
        trace
            .rays()
            .filter_map(|r| {
                let start = rear_side_run(r)?;
                let p_v: Real = r[..start].iter().map(|s| 1.0 - p_o(*s)).product();
                let run = &r[start..r.len() - 1];
                Some(p_v * visible_sum(run, |s| entropy(p_o(*s))))
            })
            .sum()
    }
}

/// D's proximity count: `Σ (d_max − d(x))` over the unknown voxels the rays
/// pass within `d_max` ([`PROXIMITY_RADIUS_M`]) of an occupied voxel.
#[derive(Clone, Copy, Debug, Default)]
pub struct ProximityCount;

impl Gain for ProximityCount {
    fn name(&self) -> &'static str {
        "proximity_count"
    }
    fn score(&self, trace: &Trace, context: &GainContext<'_>) -> Real {
        trace
            .steps()
            .iter()
            .filter(|s| s.state == VoxelState::Unknown)
            .filter_map(|s| context.occupied_distance_m(s.slot))
            .map(|d| PROXIMITY_RADIUS_M - d)
            .sum()
    }
}

/// Per slot: the distance to the nearest occupied voxel within
/// [`PROXIMITY_RADIUS_M`], infinity beyond (and for padding); `f32`, half
/// the memory of a grid's slots in `f64`.
fn occupied_distances(grid: &OccupancyGrid) -> Vec<f32> {
    let g = grid.geometry();
    let v = g.voxel_m();
    let mut out = vec![f32::INFINITY; g.slot_count()];
    let r = (PROXIMITY_RADIUS_M / v + 1e-9).floor() as i32;
    let mut offsets = Vec::new();
    for dz in -r..=r {
        for dy in -r..=r {
            for dx in -r..=r {
                let d = v * Real::from(dx * dx + dy * dy + dz * dz).sqrt();
                if d <= PROXIMITY_RADIUS_M + 1e-9 {
                    offsets.push(([dx, dy, dz], d as f32));
                }
            }
        }
    }
    for key in g.keys() {
        if grid.state(key) != VoxelState::Occupied {
            continue;
        }
        let [x, y, z] = key.coords();
        for &([dx, dy, dz], d) in &offsets {
            let n = VoxelKey::new(x + dx, y + dy, z + dz);
            if let Some(slot) = g.slot_of(n) {
                let e = &mut out[slot];
                *e = e.min(d);
            }
        }
    }
    out
}

/// The unknown voxels the rays of `trace` enter directly from a free
/// voxel, each once: where they cross the frontier (a free voxel beside an
/// unknown one, Yamauchi 1997; the steps of a ray are face neighbours).
pub fn frontier_crossings(trace: &Trace) -> usize {
    let mut entered: Vec<u32> = trace
        .rays()
        .flat_map(|r| r.windows(2))
        .filter(|w| w[0].state == VoxelState::Free && w[1].state == VoxelState::Unknown)
        .map(|w| w[1].slot)
        .collect();
    entered.sort_unstable();
    entered.dedup();
    entered.len()
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;
    use map::{OccupancyConfig, RegionBox, RegionsConfig};
    use std::f64::consts::LN_2;

    /// A hand-made grid of 0.1 m voxels, 8 × 3 × 1, every voxel in A1.
    /// Row y = 0 holds, along x: free, unknown, free, unknown, unknown,
    /// occupied, unknown, unknown; row y = 2: free, then seven unknown;
    /// row y = 1 is unknown.
    fn grid() -> OccupancyGrid {
        let b = RegionBox {
            min: [0.0, 0.0, 0.0],
            max: [0.8, 0.3, 0.1],
        };
        let config = OccupancyConfig {
            voxel_m: 0.1,
            regions: RegionsConfig {
                a1: b,
                a2: b,
                a3: b,
            },
            ..OccupancyConfig::default()
        };
        let row0 = "FUFUUOUU";
        OccupancyGrid::from_states(config, |_, key| {
            let [x, y, _] = key.coords();
            let c = match y {
                0 => row0.as_bytes()[x as usize],
                2 if x == 0 => b'F',
                _ => b'U',
            };
            match c {
                b'F' => VoxelState::Free,
                b'O' => VoxelState::Occupied,
                _ => VoxelState::Unknown,
            }
        })
        .unwrap()
    }

    fn ray(y: Real) -> (Point3, UnitVector3) {
        (
            Point3::new(0.05, y, 0.05),
            UnitVector3::new_normalize(geom::Vector3::x()),
        )
    }

    /// The two rays along rows 0 and 2 (`twice`: row 0's ray twice).
    fn trace(grid: &OccupancyGrid, twice: bool) -> Trace {
        let mut rays = vec![ray(0.05), ray(0.25)];
        if twice {
            rays.push(ray(0.05));
        }
        let mut t = Trace::new();
        t.cast(grid, 10.0, rays);
        t
    }

    fn score(gain: GainKind, twice: bool) -> Real {
        let g = grid();
        let info = g.information_by_slot();
        let ctx = GainContext::new(&g, &info, (100.0, 10.0), (200.0, 20.0));
        gain.gain().score(&trace(&g, twice), &ctx)
    }

    fn close(a: Real, b: Real) {
        assert!((a - b).abs() < 1e-12, "{a} against {b}");
    }

    #[test]
    fn the_trace_holds_each_ray_to_its_first_occupied_voxel() {
        let g = grid();
        let t = trace(&g, false);
        let states: Vec<String> = t
            .rays()
            .map(|r| {
                r.iter()
                    .map(|s| match s.state {
                        VoxelState::Free => 'F',
                        VoxelState::Unknown => 'U',
                        VoxelState::Occupied => 'O',
                    })
                    .collect()
            })
            .collect();
        assert_eq!(states, ["FUFUUO", "FUUUUUUU"]);
        // x = 1, 3, 4 of row 0 and x = 1..=7 of row 2, each once.
        assert_eq!(t.distinct_unknown().len(), 10);
        assert_eq!(trace(&g, true).distinct_unknown().len(), 10);
    }

    /// `I_o`: ln 2 at 0.5, 0 at 0 and 1, and the binary entropy between.
    #[test]
    fn entropy_by_hand() {
        close(entropy(0.5), LN_2);
        close(entropy(0.0), 0.0);
        close(entropy(1.0), 0.0);
        close(entropy(0.25), -(0.25 * 0.25f64.ln() + 0.75 * 0.75f64.ln()));
    }

    /// Ours: ten unknown voxels in A1, each `ln 2 · (0.6 + 0.35 + 0.05)`,
    /// over H1₀ = 200; no C-space information; each voxel once however many
    /// rays pass it.
    #[test]
    fn information_by_hand() {
        close(score(GainKind::Information, false), 10.0 * LN_2 / 200.0);
        close(score(GainKind::Information, true), 10.0 * LN_2 / 200.0);
    }

    /// Paul's f1: ΔH1 = 10 ln 2, once per voxel.
    #[test]
    fn paul_f1_by_hand() {
        close(score(GainKind::PaulF1, false), 10.0 * LN_2);
        close(score(GainKind::PaulF1, true), 10.0 * LN_2);
    }

    /// Average entropy: 14 voxels passed (6 + 8), 10 of them unknown.
    #[test]
    fn average_entropy_by_hand() {
        close(score(GainKind::AverageEntropy, false), 10.0 * LN_2 / 14.0);
        // Row 0 again: 16 of 20.
        close(score(GainKind::AverageEntropy, true), 13.0 * LN_2 / 20.0);
    }

    /// Occlusion aware: row 0's unknown voxels are seen with P_v = 1, ½, ¼
    /// (each unknown voxel before halves it; free ones do not); row 2's
    /// seven with 1, ½, …, 1/64.
    #[test]
    fn occlusion_aware_by_hand() {
        let row0 = 1.0 + 0.5 + 0.25;
        let row2 = 2.0 - 1.0 / 64.0;
        close(score(GainKind::OcclusionAware, false), (row0 + row2) * LN_2);
        close(
            score(GainKind::OcclusionAware, true),
            (2.0 * row0 + row2) * LN_2,
        );
    }

    /// Unobserved voxels: the same visibilities, counted without the
    /// entropy.
    #[test]
    fn unobserved_voxel_by_hand() {
        close(
            score(GainKind::UnobservedVoxel, false),
            1.75 + 2.0 - 1.0 / 64.0,
        );
    }

    /// Rear side voxel: row 0's ray reaches the occupied voxel at x = 5
    /// from the unknown one at x = 4; row 2's ray hits nothing.
    #[test]
    fn rear_side_voxel_by_hand() {
        close(score(GainKind::RearSideVoxel, false), 1.0);
        close(score(GainKind::RearSideVoxel, true), 2.0);
    }

    /// Rear side entropy: row 0's rear-side run is x = 3, 4 (the free voxel
    /// at x = 2 ends the run before it), with P_v ½ and ¼.
    #[test]
    fn rear_side_entropy_by_hand() {
        close(score(GainKind::RearSideEntropy, false), 0.75 * LN_2);
    }

    /// Proximity count: `d_max − d` of every unknown voxel passed within
    /// 0.5 m of the occupied voxel (5, 0): row 0's x = 1, 3, 4 at 0.4, 0.2,
    /// 0.1 m; row 2's x = 1..=7 at 0.1·√(dx² + 4) m, dx = x − 5.
    #[test]
    fn proximity_count_by_hand() {
        let row0 = 0.1 + 0.3 + 0.4;
        let row2: Real = [4, 3, 2, 1, 0, 1, 2]
            .iter()
            .map(|&dx: &i32| 0.5 - 0.1 * Real::from(dx * dx + 4).sqrt())
            .sum();
        // The distances are kept as f32.
        let got = score(GainKind::ProximityCount, false);
        assert!((got - (row0 + row2)).abs() < 1e-6, "{got}");
    }

    /// Frontier crossings: row 0's ray enters x = 1 and x = 3 from free
    /// voxels (x = 4 from an unknown one), row 2's x = 1; row 0's ray again
    /// adds none.
    #[test]
    fn frontier_crossings_by_hand() {
        let g = grid();
        assert_eq!(frontier_crossings(&trace(&g, false)), 3);
        assert_eq!(frontier_crossings(&trace(&g, true)), 3);
    }

    /// The distance to the nearest occupied voxel, within `d_max` only.
    #[test]
    fn occupied_distances_by_hand() {
        let g = grid();
        let info = g.information_by_slot();
        let ctx = GainContext::new(&g, &info, (1.0, 1.0), (1.0, 1.0));
        let slot = |x, y| g.geometry().slot_of(VoxelKey::new(x, y, 0)).unwrap() as u32;
        close(ctx.occupied_distance_m(slot(5, 0)).unwrap(), 0.0);
        // 0.5 m away: within d_max (scoring 0); √29/10 m: beyond.
        close(ctx.occupied_distance_m(slot(0, 0)).unwrap(), 0.5);
        assert_eq!(ctx.occupied_distance_m(slot(0, 2)), None);
    }

    /// Every built-in gain round-trips through its `[explore] gain` name.
    #[test]
    fn gain_names_are_the_config_names() {
        for kind in GainKind::ALL {
            let name = kind.gain().name().to_owned();
            let d: serde::de::value::StrDeserializer<'_, serde::de::value::Error> =
                serde::de::IntoDeserializer::into_deserializer(name.as_str());
            let parsed = GainKind::deserialize(d).unwrap();
            assert_eq!(parsed, kind);
        }
    }
}
