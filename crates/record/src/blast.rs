//! A run's grit-blasting files (Paul App. A): what a plan is made from
//! (`blast_inputs.json`, [`BlastInputsFile`]) and the plan
//! (`blast_plan.json` and `blast_plan.csv`, [`BlastPlan`]). The element
//! types that belong to the algorithms (a disc, a grid's configuration, the
//! nozzle) are the files' type parameters; the layout, names and versions
//! are here.

use crate::RecordError;
use geom::Real;
use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};
use std::fmt::Write as _;

/// The file of a plan's inputs.
pub const BLAST_INPUTS_JSON: &str = "blast_inputs.json";
/// The plan.
pub const BLAST_PLAN_JSON: &str = "blast_plan.json";
/// The plan as a table.
pub const BLAST_PLAN_CSV: &str = "blast_plan.csv";

/// The name and version at the head of [`BLAST_INPUTS_JSON`].
pub const BLAST_INPUTS_FORMAT: &str = "surveyor-blast-inputs";
/// See [`BLAST_INPUTS_FORMAT`].
pub const BLAST_INPUTS_VERSION: u32 = 1;

/// A voxel's state in a stored grid.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Tri {
    /// Not observed.
    Unknown,
    /// Seen free.
    Free,
    /// Seen occupied.
    Occupied,
}

/// [`BLAST_INPUTS_JSON`]'s layout: an exploration's discs `D` with the
/// joints each disc's pose search starts from, their segments, and the
/// planning grid (its configuration `C` and voxel states). JSON numbers
/// round-trip exactly (`serde_json`'s `float_roundtrip`), so a loaded file
/// plans the same poses.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BlastInputsFile<D, C> {
    /// [`BLAST_INPUTS_FORMAT`].
    pub format: String,
    /// [`BLAST_INPUTS_VERSION`].
    pub version: u32,
    /// The discs.
    pub discs: Vec<D>,
    /// Per disc: the joints its pose selection starts from.
    pub start_joints: Vec<Vec<Real>>,
    /// The segments: disc indices.
    pub segments: Vec<Vec<usize>>,
    /// The planning grid.
    pub grid: GridFile<C>,
}

/// An occupancy grid's configuration and voxel states: the states
/// run-length encoded in the grid's order (x fastest, then y, then z) as
/// `<count><u|f|o>` runs (unknown, free, occupied), e.g. `120u7f2o`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GridFile<C> {
    /// The grid's configuration.
    pub config: C,
    /// The states, run-length encoded ([`encode_states`]).
    pub states: String,
}

/// The run-length text of `states`.
///
/// ```
/// use record::blast::{Tri, decode_states, encode_states};
/// let s = [Tri::Unknown, Tri::Unknown, Tri::Free, Tri::Occupied];
/// assert_eq!(encode_states(&s), "2u1f1o");
/// assert_eq!(decode_states("2u1f1o", 4, "grid")?, s);
/// assert!(decode_states("2u1f", 4, "grid").is_err()); // too few
/// # Ok::<(), record::RecordError>(())
/// ```
pub fn encode_states(states: &[Tri]) -> String {
    let mut out = String::new();
    let mut run: Option<(char, usize)> = None;
    for s in states {
        let c = match s {
            Tri::Unknown => 'u',
            Tri::Free => 'f',
            Tri::Occupied => 'o',
        };
        run = match run {
            Some((r, n)) if r == c => Some((r, n + 1)),
            Some((r, n)) => {
                let _ = write!(out, "{n}{r}");
                Some((c, 1))
            }
            None => Some((c, 1)),
        };
    }
    if let Some((r, n)) = run {
        let _ = write!(out, "{n}{r}");
    }
    out
}

/// The `count` states of a run-length text; `source` names it in errors.
/// More or fewer states than `count`, a run without a count or an unknown
/// letter is an error, found before more than `count` states are held.
pub fn decode_states(text: &str, count: usize, source: &str) -> Result<Vec<Tri>, RecordError> {
    let fail = |message: String| RecordError::Field {
        file: source.to_owned(),
        line: 1,
        field: "grid.states".into(),
        message,
    };
    let mut states = Vec::with_capacity(count);
    let mut digits = String::new();
    for c in text.chars() {
        if c.is_ascii_digit() {
            digits.push(c);
            continue;
        }
        let state = match c {
            'u' => Tri::Unknown,
            'f' => Tri::Free,
            'o' => Tri::Occupied,
            other => {
                return Err(fail(format!(
                    "expected runs `<count><u|f|o>`, found `{other}`"
                )));
            }
        };
        let n: usize = digits
            .parse()
            .map_err(|_| fail(format!("a run of `{c}` without a count")))?;
        digits.clear();
        if states.len() + n > count {
            return Err(fail(format!("more states than the grid's {count} voxels")));
        }
        states.extend(std::iter::repeat_n(state, n));
    }
    if !digits.is_empty() || states.len() != count {
        return Err(fail(format!(
            "{} states (and a trailing count `{digits}`) for a grid of {count} voxels",
            states.len()
        )));
    }
    Ok(states)
}

impl<D: Serialize + DeserializeOwned, C: Serialize + DeserializeOwned> BlastInputsFile<D, C> {
    /// The file's text (one line of JSON).
    pub fn to_json(&self) -> Result<String, RecordError> {
        serde_json::to_string(self).map_err(|e| RecordError::named(BLAST_INPUTS_JSON, e))
    }

    /// Parse the text of a [`BLAST_INPUTS_JSON`], checking its format and
    /// version; `source` names it in errors.
    pub fn from_json(text: &str, source: &str) -> Result<Self, RecordError> {
        let file: Self = serde_json::from_str(text).map_err(|e| RecordError::named(source, e))?;
        if file.format != BLAST_INPUTS_FORMAT || file.version != BLAST_INPUTS_VERSION {
            return Err(RecordError::named(
                source,
                format!(
                    "format `{}` version {}: expected `{BLAST_INPUTS_FORMAT}` version {BLAST_INPUTS_VERSION}",
                    file.format, file.version
                ),
            ));
        }
        Ok(file)
    }

    /// Read `path`.
    pub fn read(path: &std::path::Path) -> Result<Self, RecordError> {
        let text = std::fs::read_to_string(path).map_err(|e| {
            RecordError::file(
                path,
                format!("cannot read ({e}); `surveyor explore` writes it in its --out folder"),
            )
        })?;
        Self::from_json(&text, &path.display().to_string())
    }
}

/// One target of a plan: a disc and the pose that blasts it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BlastTarget {
    /// The disc (index into the run's discs).
    pub disc: usize,
    /// The joints.
    pub joints: Vec<Real>,
    /// Nozzle tip, world frame.
    pub nozzle: [Real; 3],
    /// Stream direction, world frame.
    pub direction: [Real; 3],
    /// Angle between the stream and the disc normal, degrees.
    pub phi_deg: Real,
    /// Stream length to the disc's plane, metres.
    pub d_m: Real,
    /// Distance from where the stream meets the plane to the disc centre, m.
    pub aim_error_m: Real,
    /// `dist(Q)` against the run's occupied and unknown voxels.
    pub dist: Real,
}

/// The weights `α` (travel, per metre) and `β` (joint movement, per radian)
/// of eq. A.6 a segment's orders were compared with.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct PathWeights {
    /// Weight of the travel distance.
    pub alpha: Real,
    /// Weight of the joint movement.
    pub beta: Real,
}

/// The plan of one segment.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SegmentPlan {
    /// The segment (index into the run's segments).
    pub segment: usize,
    /// The targets, in the GA's order.
    pub targets: Vec<BlastTarget>,
    /// Discs of the segment in A2 without a valid pose.
    pub no_pose: Vec<usize>,
    /// The comparison weights (eq. A.10 on the nearest-neighbour order).
    pub weights: PathWeights,
    /// Cost (eq. A.9) of the nearest-neighbour order.
    pub cost_nearest_neighbour: Real,
    /// Cost of its 2-opt improvement.
    pub cost_two_opt: Real,
    /// Cost of the GA's order.
    pub cost_ga: Real,
}

/// A blast plan; `T` is the nozzle and its limits (`blast::BlastTool`), a
/// reader that only shows the plan takes [`serde_json::Value`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BlastPlan<T = serde_json::Value> {
    /// The nozzle and its limits.
    pub tool: T,
    /// Discs in A2 (the ones a plan is sought for).
    pub discs_in_scope: usize,
    /// Of those, the ones with a valid pose.
    pub discs_with_pose: usize,
    /// Segments with at least one disc in A2, in segment order.
    pub segments: Vec<SegmentPlan>,
}

impl<T: Serialize> BlastPlan<T> {
    /// One line: discs with a pose, segments, and the summed path cost
    /// (eq. A.9) of the nearest-neighbour, 2-opt and GA orders.
    pub fn summary(&self) -> String {
        let cost = |f: fn(&SegmentPlan) -> Real| self.segments.iter().map(f).sum::<Real>();
        format!(
            "blast plan: a nozzle pose for {} of the {} discs in A2, {} segments; path cost (eq. A.9) nearest neighbour {:.1}, 2-opt {:.1}, GA {:.1}",
            self.discs_with_pose,
            self.discs_in_scope,
            self.segments.len(),
            cost(|s| s.cost_nearest_neighbour),
            cost(|s| s.cost_two_opt),
            cost(|s| s.cost_ga)
        )
    }

    /// `blast_plan.csv`: one row per target, segments in order and the
    /// targets of each in the GA's order.
    pub fn csv(&self) -> String {
        let mut out = String::from(
            "segment,order,disc,q1,q2,q3,q4,q5,q6,nozzle_x,nozzle_y,nozzle_z,dir_x,dir_y,dir_z,phi_deg,d_m,aim_error_m,dist\n",
        );
        for s in &self.segments {
            for (k, t) in s.targets.iter().enumerate() {
                let _ = write!(out, "{},{k},{}", s.segment, t.disc);
                for v in t.joints.iter().chain(&t.nozzle).chain(&t.direction).chain([
                    &t.phi_deg,
                    &t.d_m,
                    &t.aim_error_m,
                    &t.dist,
                ]) {
                    let _ = write!(out, ",{v}");
                }
                out.push('\n');
            }
        }
        out
    }

    /// `blast_plan.json`'s text (pretty, no final newline).
    pub fn to_json(&self) -> Result<String, RecordError> {
        serde_json::to_string_pretty(self).map_err(|e| RecordError::named(BLAST_PLAN_JSON, e))
    }
}
