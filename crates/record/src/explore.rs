//! The files of an exploration run (`surveyor explore`) other than the
//! viewpoint tables ([`crate::viewpoints`]): the summary `run.json`
//! ([`ExploreSummary`]), the map products `discs.csv` ([`DiscTable`]) and
//! `segments.json`, and the measured `cloud.ply` and the TSDF `mesh.ply`.

use crate::RecordError;
use crate::coverage::CoverageReport;
use crate::table::Table;
use crate::viewpoints::{UnsafeConfiguration, ViewpointRecord};
use geom::{Point3, Real, TriMesh, UnitVector3, Vector3};
use sensor::SweepPoint;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;

/// The summary file of a run.
pub const RUN_JSON: &str = "run.json";
/// Every measured point with its ray origin.
pub const CLOUD_PLY: &str = "cloud.ply";
/// The TSDF mesh.
pub const MESH_PLY: &str = "mesh.ply";
/// The Scale-Like Discs with their segment, viewpoint and material belief.
pub const DISCS_CSV: &str = "discs.csv";
/// The map segments: disc indices.
pub const SEGMENTS_JSON: &str = "segments.json";

/// `run.json` of an exploration: what the run did and, when it was judged
/// against a ground truth (a simulation), how well. Its keys are written in
/// alphabetical order at every level.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ExploreSummary {
    /// Version of the run folder's format ([`crate::FORMAT_VERSION`]).
    pub format_version: u32,
    /// Scenario name.
    pub scenario: String,
    /// Viewpoints per stage.
    pub viewpoints: StageCounts,
    /// Why Stage One stopped.
    pub termination: String,
    /// Why Stage Two stopped (`null` when it did not run).
    pub stage_two_termination: Option<String>,
    /// Ground-truth contacts along executed motions (`null` without a
    /// ground truth).
    pub collisions: Option<usize>,
    /// Configurations with `dist(Q) ≤ 1` along executed motions.
    pub unsafe_configurations: usize,
    /// Those configurations.
    pub unsafe_configuration_list: Vec<UnsafeConfiguration>,
    /// Smallest ground-truth clearance of the links, metres (`null`
    /// without a ground truth).
    pub min_clearance_m: Option<Real>,
    /// `H1` (weighted) and `H2` before the first sweep.
    pub initial_information: InitialInformation,
    /// Measured points.
    pub points: usize,
    /// Triangles of the TSDF mesh.
    pub mesh_triangles: usize,
    /// Scale-Like Discs.
    pub discs: usize,
    /// Map segments.
    pub segments: usize,
    /// The material names of the belief (the scene's table).
    pub materials: Vec<String>,
    /// Coverage of the true surfaces (`null` without a ground truth).
    pub coverage: Option<ExploreCoverage>,
    /// Share of the discs observed by the LRC whose most probable material is
    /// the true one (`null` without such discs).
    pub material_accuracy: Option<Real>,
    /// Discs with at least one LRC observation.
    pub discs_observed_by_lrc: usize,
    /// The run's material identification on the true surfaces of A2 beside
    /// the material oracle's (absent without a true scene with materials,
    /// without Stage Two, or with `--no-oracle`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub material_identification: Option<MaterialIdentification>,
    /// `H3` over every disc voxel at the end (eq. 4.17).
    pub h3: Option<Real>,
    /// Stage One decision times, ms.
    pub decision_ms: Spread,
    /// Stage Two decision times, ms.
    pub stage_two_decision_ms: Spread,
    /// Wall time of the whole run, seconds (0 when timings are off).
    pub wall_s: Real,
    /// The time a real arm with the scenario's joint limits would need
    /// (the robot clock, `hw::clock`): in all, per stage and per activity.
    #[serde(default)]
    pub robot_time_s: RobotTimeSummary,
    /// Where the job's wall time went, per phase (absent when timings are
    /// off, so such files stay the same byte for byte).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub timings: Option<PhaseTimings>,
}

/// `run.json`'s `robot_time_s`: a run's robot time in seconds, in all, per
/// stage, and per activity of the robot clock; the sum of its viewpoints'
/// (`viewpoints.csv`'s `robot_*` columns).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RobotTimeSummary {
    /// All of it.
    pub total: Real,
    /// Stage One's viewpoints.
    pub stage_one: Real,
    /// Stage Two's viewpoints (the map products between the stages
    /// included).
    pub stage_two: Real,
    /// Moving with the scanner scanning.
    pub moving_while_scanning: Real,
    /// Moving without scanning.
    pub moving: Real,
    /// Sweeping the scanner at viewpoints.
    pub standing_to_sweep: Real,
    /// Standing still while the loop integrates and decides (wall time,
    /// or a stated figure per decision with timings off).
    pub deciding: Real,
}

impl RobotTimeSummary {
    /// The summary of `viewpoints`' robot times.
    pub fn of(viewpoints: &[ViewpointRecord]) -> Self {
        let mut all = robot::timing::RobotTime::default();
        let mut out = Self::default();
        for v in viewpoints {
            all.add(&v.robot_time);
            let t = v.robot_time.total_s();
            if v.stage == 1 {
                out.stage_one += t;
            } else {
                out.stage_two += t;
            }
        }
        Self {
            total: all.total_s(),
            moving_while_scanning: all.moving_while_scanning_s,
            moving: all.moving_s,
            standing_to_sweep: all.standing_to_sweep_s,
            deciding: all.deciding_s,
            ..out
        }
    }
}

impl std::fmt::Display for RobotTimeSummary {
    /// `6230 s in all, Stage One 5118 s, Stage Two 1111 s; moving while
    /// scanning …`.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{:.0} s in all, Stage One {:.0} s, Stage Two {:.0} s; moving while scanning {:.0} s, \
             moving {:.0} s, standing to sweep {:.0} s, deciding {:.0} s",
            self.total,
            self.stage_one,
            self.stage_two,
            self.moving_while_scanning,
            self.moving,
            self.standing_to_sweep,
            self.deciding
        )
    }
}

/// Where the wall time of a `surveyor explore` job went, seconds per phase
/// (of this process: a resumed run's replay counts in its stages).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PhaseTimings {
    /// The scenario's world, the C-space model (built or loaded), the
    /// planning grid, the judge.
    pub setup_s: Real,
    /// The coverage and material oracles: read from their caches, or the
    /// wait for them after the run when computed (they run beside the run,
    /// on the cores the run leaves idle; 0 without them).
    #[serde(default)]
    pub oracle_s: Real,
    /// Stage One: decisions, motions, sweeps, integration (a resumed run's
    /// replayed viewpoints included).
    pub stage_one_s: Real,
    /// Stage One's TSDF mesh, its Scale-Like Discs and segments.
    pub discs_s: Real,
    /// The LRC trained (or loaded from its cache), the material belief, and
    /// Stage One's sweeps classified.
    pub lrc_s: Real,
    /// Stage Two: decisions, motions, sweeps, classification.
    pub stage_two_s: Real,
    /// The TSDF mesh of both stages.
    pub final_mesh_s: Real,
    /// The blast plan (Paul App. A).
    pub blast_planning_s: Real,
    /// The run folder's files other than the report.
    pub write_s: Real,
    /// `report.html`.
    pub report_s: Real,
    /// The whole job.
    pub total_s: Real,
}

impl PhaseTimings {
    /// The phases in the order they run, with their names, seconds (the
    /// total not among them).
    pub fn phases(&self) -> [(&'static str, Real); 10] {
        [
            ("setup", self.setup_s),
            ("oracle (wait)", self.oracle_s),
            ("stage one", self.stage_one_s),
            ("mesh and discs", self.discs_s),
            ("LRC", self.lrc_s),
            ("stage two", self.stage_two_s),
            ("final mesh", self.final_mesh_s),
            ("blast planning", self.blast_planning_s),
            ("files", self.write_s),
            ("report", self.report_s),
        ]
    }

    /// One line per phase, `name  seconds  share of the total`, then the
    /// total and what no phase accounts for.
    pub fn table(&self) -> String {
        let mut out = String::new();
        let total = self.total_s.max(1e-9);
        let mut listed = 0.0;
        for (name, s) in self.phases() {
            listed += s;
            let _ = writeln!(out, "  {name:<15} {s:>7.2} s {:>5.1} %", 100.0 * s / total);
        }
        let _ = writeln!(
            out,
            "  {:<15} {:>7.2} s {:>5.1} %",
            "other",
            (self.total_s - listed).max(0.0),
            100.0 * (self.total_s - listed).max(0.0) / total
        );
        let _ = write!(out, "  {:<15} {:>7.2} s", "total", self.total_s);
        out
    }
}

/// Viewpoints per stage.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StageCounts {
    /// Stage One's, the start pose's sweep included.
    pub stage_one: usize,
    /// Stage Two's.
    pub stage_two: usize,
}

/// The information before the first sweep.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct InitialInformation {
    /// Weighted `H1` (eq. 4.11).
    #[serde(rename = "H1_weighted")]
    pub h1_weighted: Real,
    /// `H2` (eq. 4.14).
    #[serde(rename = "H2")]
    pub h2: Real,
}

/// Median and largest of a set of times.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Spread {
    /// Median (the upper one of an even count), 0 for none.
    pub median: Real,
    /// Largest, 0 for none.
    pub max: Real,
}

impl Spread {
    /// Of `values` (any order).
    pub fn of(mut values: Vec<Real>) -> Self {
        values.sort_by(Real::total_cmp);
        Self {
            median: values.get(values.len() / 2).copied().unwrap_or(0.0),
            max: values.last().copied().unwrap_or(0.0),
        }
    }
}

/// Coverage of the true surfaces in the regions of interest.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ExploreCoverage {
    /// Covered share of A1.
    #[serde(rename = "A1")]
    pub a1: Real,
    /// Covered share of A2.
    #[serde(rename = "A2")]
    pub a2: Real,
    /// Covered share of A3.
    #[serde(rename = "A3")]
    pub a3: Real,
    /// The samples some collision-free pose could observe, and how many of
    /// them were covered.
    pub observable: Observable,
    /// Covered share of A1 per material.
    #[serde(rename = "A1_per_material")]
    pub a1_per_material: BTreeMap<String, Real>,
    /// The full reports of A1, A2, A3.
    pub reports: Vec<CoverageReport>,
    /// What the coverage oracle reaches, and this run beside it (absent
    /// without a true scene, or with `--no-oracle`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub oracle: Option<OracleComparison>,
}

/// The coverage oracle (`sim::oracle`): tilt sweeps chosen greedily
/// *knowing the true scene*, each the one whose simulated points cover the
/// most A1 samples not yet covered, from the start pose and the roadmap's
/// nodes that the run's safety rule admits against the true scene; the
/// same scanner, noise and samples as the run.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CoverageOracle {
    /// The safety rule the oracle's poses obey.
    pub rule: String,
    /// Poses in its pool (the start and the roadmap's nodes).
    pub poses: usize,
    /// Of them, those clear under the rule with their whole sweep.
    pub clear_poses: usize,
    /// Share of A1 covered after 1, 2, … sweeps (the start's first), until
    /// no sweep adds a sample or the oracle's limit of sweeps.
    #[serde(rename = "A1_after_sweeps")]
    pub a1_after_sweeps: Vec<Real>,
    /// Share of A1 all the clear poses' sweeps and the start's cover
    /// together.
    #[serde(rename = "A1_all_poses")]
    pub a1_all_poses: Real,
}

impl CoverageOracle {
    /// The share of A1 covered after `n` sweeps (the last one when the
    /// greedy stopped earlier; 0 for none).
    pub fn after(&self, n: usize) -> Real {
        match n {
            0 => 0.0,
            n => self
                .a1_after_sweeps
                .get(n - 1)
                .or(self.a1_after_sweeps.last())
                .copied()
                .unwrap_or(0.0),
        }
    }
}

/// The oracle's coverage beside the run's.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OracleComparison {
    /// Viewpoints of Stage One (the start's included).
    pub stage_one_viewpoints: usize,
    /// The oracle's A1 coverage after as many sweeps.
    #[serde(rename = "A1_after_stage_one_viewpoints")]
    pub a1_after_stage_one_viewpoints: Real,
    /// The oracle's A1 coverage after 12 sweeps.
    #[serde(rename = "A1_after_12")]
    pub a1_after_12: Real,
    /// The run's A1 coverage after 12 Stage One viewpoints (at the end of
    /// Stage One when it took fewer) over the oracle's after 12.
    pub ratio_after_12: Real,
    /// The run's A1 coverage at the end of Stage One over the oracle's
    /// after 12.
    pub ratio_at_stage_one_end: Real,
    /// The oracle.
    pub oracle: CoverageOracle,
}

impl OracleComparison {
    /// The comparison of a run whose Stage One covered `stage_one_a1[k]`
    /// of A1 after viewpoint `k`.
    pub fn new(oracle: CoverageOracle, stage_one_a1: &[Real]) -> Self {
        let n = stage_one_a1.len();
        let twelve = oracle.after(12);
        let ratio = |x: Real| if twelve > 0.0 { x / twelve } else { 0.0 };
        let at = |k: usize| {
            stage_one_a1
                .get(k)
                .or(stage_one_a1.last())
                .copied()
                .unwrap_or(0.0)
        };
        Self {
            stage_one_viewpoints: n,
            a1_after_stage_one_viewpoints: oracle.after(n),
            a1_after_12: twelve,
            ratio_after_12: ratio(at(11)),
            ratio_at_stage_one_end: ratio(at(n.saturating_sub(1))),
            oracle,
        }
    }
}

/// The material oracle (`sim::material_oracle`): what Stage Two could
/// identify *knowing the true scene*, with the run's robot, scanner, LRC
/// and safety rule. Its samples are true-surface samples of A2; a sample is
/// identified when its most probable material has `p ≥ 0.8` after the Bayes
/// fusion of the LRC's observations of the patch around it. Its pool: the
/// start, the roadmap's nodes and poses aimed at the samples by Stage Two's
/// pose selection on a perfect map, those clear under the rule.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MaterialOracle {
    /// The safety rule the oracle's poses obey.
    pub rule: String,
    /// Poses in its pool (the start, the roadmap's nodes, the aimed poses).
    pub poses: usize,
    /// Of them, those clear under the rule with their whole sweep.
    pub clear_poses: usize,
    /// Aimed poses in the pool (valid pose selections, clear or not).
    pub aimed_poses: usize,
    /// True-surface samples of A2.
    pub samples: usize,
    /// Their density, per m².
    pub samples_per_m2: Real,
    /// Share of the samples that some clear pose's sweep (or the start's)
    /// identifies on its own, or the greedy choice identifies.
    pub identifiable: Real,
    /// Share of the samples identified after 1, 2, … viewpoints (the
    /// start's sweep first, then each the clear pose that identifies the
    /// most more), until none adds one or the oracle's limit of viewpoints.
    pub identified_after_viewpoints: Vec<Real>,
    /// Share of the samples the greedy choice identified whose most
    /// probable material is the true one (`null` when it identified none).
    pub accuracy: Option<Real>,
}

impl MaterialOracle {
    /// The share identified after `n` viewpoints (the last one when the
    /// greedy stopped earlier; 0 for none).
    pub fn after(&self, n: usize) -> Real {
        match n {
            0 => 0.0,
            n => self
                .identified_after_viewpoints
                .get(n - 1)
                .or(self.identified_after_viewpoints.last())
                .copied()
                .unwrap_or(0.0),
        }
    }
}

/// The run's material identification on the material oracle's samples,
/// beside the oracle. A sample takes the belief of its *run disc*: the
/// nearest disc whose centre lies within the disc's radius plus 10 mm of
/// the sample and whose seen side faces the sample's (cosine above 0.5);
/// a sample without one is not identified.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MaterialIdentification {
    /// Share of the samples whose run disc's most probable material has
    /// `p ≥ 0.8`.
    pub identified: Real,
    /// Share of those whose most probable material is the true one (`null`
    /// when none is identified).
    pub accuracy: Option<Real>,
    /// Discs with their centre in A2 whose most probable material has
    /// `p ≥ 0.8`.
    pub discs_identified: usize,
    /// Viewpoints of Stage Two.
    pub stage_two_viewpoints: usize,
    /// The run's identified share of the samples when Stage Two started
    /// (Stage One's sweeps classified) and after each of its viewpoints
    /// (a sample counts from the viewpoint since which its run disc has
    /// been identified, discs.csv's `identified_at`): one more value than
    /// `stage_two_viewpoints`, the last equal to `identified`; empty for a
    /// run without that record.
    #[serde(default)]
    pub identified_after_viewpoints: Vec<Real>,
    /// The oracle's identified share after 10 viewpoints.
    pub oracle_after_10: Real,
    /// The oracle's identified share after as many viewpoints as Stage Two
    /// took.
    pub oracle_after_stage_two_viewpoints: Real,
    /// `identified` over the oracle's identifiable share (`null` when that
    /// is 0).
    pub ratio_to_identifiable: Option<Real>,
    /// `identified` over the oracle's after 10 viewpoints (`null` when
    /// that is 0).
    pub ratio_after_10: Option<Real>,
    /// `identified` over the oracle's after as many viewpoints as Stage Two
    /// took (`null` when that is 0, as after none).
    pub ratio_after_stage_two_viewpoints: Option<Real>,
    /// The oracle.
    pub oracle: MaterialOracle,
}

impl MaterialIdentification {
    /// The comparison of a run that identified the share `identified` of
    /// the oracle's samples (right on the share `accuracy` of them), `discs_identified`
    /// discs of A2, in `stage_two_viewpoints` viewpoints of Stage Two, with
    /// `identified_after_viewpoints` its share viewpoint by viewpoint (see
    /// the field).
    pub fn new(
        oracle: MaterialOracle,
        identified: Real,
        accuracy: Option<Real>,
        discs_identified: usize,
        stage_two_viewpoints: usize,
        identified_after_viewpoints: Vec<Real>,
    ) -> Self {
        let ratio = |of: Real| (of > 0.0).then(|| identified / of);
        let ten = oracle.after(10);
        let as_many = oracle.after(stage_two_viewpoints);
        Self {
            identified,
            accuracy,
            discs_identified,
            stage_two_viewpoints,
            identified_after_viewpoints,
            oracle_after_10: ten,
            oracle_after_stage_two_viewpoints: as_many,
            ratio_to_identifiable: ratio(oracle.identifiable),
            ratio_after_10: ratio(ten),
            ratio_after_stage_two_viewpoints: ratio(as_many),
            oracle,
        }
    }
}

/// Covered share of the observable samples per region, and the observable
/// share of A1.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Observable {
    /// Covered share of A1's observable samples.
    #[serde(rename = "A1")]
    pub a1: Option<Real>,
    /// Covered share of A2's observable samples.
    #[serde(rename = "A2")]
    pub a2: Option<Real>,
    /// Covered share of A3's observable samples.
    #[serde(rename = "A3")]
    pub a3: Option<Real>,
    /// Observable share of A1's samples.
    #[serde(rename = "A1_observable_share")]
    pub a1_observable_share: Option<Real>,
}

impl ExploreCoverage {
    /// The coverage of A1, A2, A3 from their reports, and per region the
    /// observable samples and the covered ones among them (`None` when not
    /// measured).
    pub fn new(reports: &[CoverageReport; 3], observable: &[(usize, usize)]) -> Self {
        let share = |k: usize| {
            observable.get(k).map(|(n, c)| {
                if *n == 0 {
                    0.0
                } else {
                    *c as Real / *n as Real
                }
            })
        };
        let [a1, a2, a3] = reports;
        Self {
            a1: a1.fraction(),
            a2: a2.fraction(),
            a3: a3.fraction(),
            observable: Observable {
                a1: share(0),
                a2: share(1),
                a3: share(2),
                a1_observable_share: observable
                    .first()
                    .map(|(n, _)| *n as Real / a1.samples.max(1) as Real),
            },
            oracle: None,
            a1_per_material: a1
                .per_material
                .iter()
                .map(|m| {
                    let share = if m.samples == 0 {
                        0.0
                    } else {
                        m.covered as Real / m.samples as Real
                    };
                    (m.material.clone(), share)
                })
                .collect(),
            reports: reports.to_vec(),
        }
    }
}

impl ExploreSummary {
    /// `run.json`'s text: keys in alphabetical order at every level (as a
    /// JSON object's keys carry no order, sorting makes the file the same
    /// whatever the field order here), pretty-printed, a final newline.
    pub fn to_json(&self) -> Result<String, RecordError> {
        crate::sorted_json(self, RUN_JSON)
    }
}

/// A Scale-Like Disc's geometry as `discs.csv` holds it (the algorithm's
/// type is `map::Disc`).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct DiscRecord {
    /// Centre.
    pub centre: Point3,
    /// Unit normal.
    pub normal: UnitVector3,
    /// Radius, metres.
    pub radius_m: Real,
    /// Points registered to the disc.
    pub points: usize,
}

/// `discs.csv` of a run: the discs (columns `cx,cy,cz,nx,ny,nz,radius,points`,
/// the disc-file contract of `map::sld_io`), then per disc its `segment`,
/// the `viewpoint` that saw it, its `true_material` (−1 when unknown), and
/// when materials were identified the posterior `p_<material>` per
/// material, `h3`, `lrc_observations` and `identified_at` (the viewpoint
/// since which its most probable material has had `p ≥ 0.8`, −1 when it
/// has not).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct DiscTable {
    /// The discs.
    pub discs: Vec<DiscRecord>,
    /// Per disc: its segment.
    pub segment: Vec<usize>,
    /// Per disc: the viewpoint that saw it.
    pub viewpoint: Vec<usize>,
    /// Per disc: the material of the nearest true surface (runs judged
    /// against a ground truth).
    pub true_material: Vec<Option<usize>>,
    /// The material names of the posterior columns.
    pub material_names: Vec<String>,
    /// Per disc: the posterior over `material_names` (`None`: not written).
    pub posterior: Option<Vec<Vec<Real>>>,
    /// Per disc: `H3` and the LRC observations that updated it (`None`: not
    /// written).
    pub h3: Option<(Vec<Real>, Vec<usize>)>,
    /// Per disc: the viewpoint (`k`) since which it has been identified
    /// (`None` per disc: not identified; `None`: not written).
    pub identified_at: Option<Vec<Option<usize>>>,
}

/// Names `discs.csv` starts with.
pub const DISC_CSV_HEADER: [&str; 8] = ["cx", "cy", "cz", "nx", "ny", "nz", "radius", "points"];

impl DiscTable {
    /// The table as CSV text.
    pub fn to_csv(&self) -> Result<String, RecordError> {
        let n = self.discs.len();
        let mut columns: Vec<(String, Vec<Real>)> = vec![
            (
                "segment".into(),
                self.segment.iter().map(|v| *v as Real).collect(),
            ),
            (
                "viewpoint".into(),
                self.viewpoint.iter().map(|v| *v as Real).collect(),
            ),
            (
                "true_material".into(),
                self.true_material
                    .iter()
                    .map(|m| m.map_or(-1.0, |v| v as Real))
                    .collect(),
            ),
        ];
        if let Some(p) = &self.posterior {
            for (m, name) in self.material_names.iter().enumerate() {
                columns.push((
                    format!("p_{name}"),
                    p.iter().map(|p| p.get(m).copied().unwrap_or(0.0)).collect(),
                ));
            }
        }
        if let Some((h3, obs)) = &self.h3 {
            columns.push(("h3".into(), h3.clone()));
            columns.push((
                "lrc_observations".into(),
                obs.iter().map(|v| *v as Real).collect(),
            ));
        }
        if let Some(at) = &self.identified_at {
            columns.push((
                "identified_at".into(),
                at.iter().map(|k| k.map_or(-1.0, |v| v as Real)).collect(),
            ));
        }
        for (k, (name, values)) in columns.iter().enumerate() {
            let bad_name = name.is_empty()
                || name.contains([',', '\n', '\r', '"'])
                || DISC_CSV_HEADER.contains(&name.as_str())
                || columns[..k].iter().any(|o| &o.0 == name);
            if bad_name || values.len() != n {
                return Err(RecordError::Invalid {
                    what: format!("{DISCS_CSV} column `{name}`"),
                    message: format!(
                        "needs a unique name without commas and {n} values (has {})",
                        values.len()
                    ),
                });
            }
        }
        let mut out = DISC_CSV_HEADER.join(",");
        for (name, _) in &columns {
            out.push(',');
            out.push_str(name);
        }
        out.push('\n');
        for (i, d) in self.discs.iter().enumerate() {
            let _ = write!(
                out,
                "{},{},{},{},{},{},{},{}",
                d.centre.x,
                d.centre.y,
                d.centre.z,
                d.normal.x,
                d.normal.y,
                d.normal.z,
                d.radius_m,
                d.points
            );
            for (_, values) in &columns {
                let _ = write!(out, ",{}", values[i]);
            }
            out.push('\n');
        }
        Ok(out)
    }

    /// Read a run's `discs.csv`: the contract columns and every extra column
    /// the writer makes (`segment`, `viewpoint` and `true_material` are
    /// required; the posterior, `h3`, `lrc_observations` and `identified_at`
    /// are read when present). Every number must be finite and every normal a unit vector.
    pub fn read(path: &Path) -> Result<Self, RecordError> {
        let t = Table::read(path)?;
        let col = |n: &str| t.numbers(n);
        let [cx, cy, cz, nx, ny, nz, radius] = [
            col("cx")?,
            col("cy")?,
            col("cz")?,
            col("nx")?,
            col("ny")?,
            col("nz")?,
            col("radius")?,
        ];
        let points = t.indices("points")?;
        let mut discs = Vec::with_capacity(t.len());
        for i in 0..t.len() {
            let n = Vector3::new(nx[i], ny[i], nz[i]);
            if (n.norm() - 1.0).abs() > 1e-6 {
                return Err(RecordError::Field {
                    file: t.source.clone(),
                    line: i + 2,
                    field: "nx,ny,nz".into(),
                    message: format!("expected a unit normal, found one of length {}", n.norm()),
                });
            }
            discs.push(DiscRecord {
                centre: Point3::new(cx[i], cy[i], cz[i]),
                normal: UnitVector3::new_normalize(n),
                radius_m: radius[i],
                points: points[i],
            });
        }
        let material = t.numbers("true_material")?;
        let material_names: Vec<String> = t
            .columns_with_prefix("p_")
            .iter()
            .map(|c| c["p_".len()..].to_owned())
            .collect();
        let posterior = if material_names.is_empty() {
            None
        } else {
            let cols = material_names
                .iter()
                .map(|m| t.numbers(&format!("p_{m}")))
                .collect::<Result<Vec<_>, _>>()?;
            Some(
                (0..t.len())
                    .map(|i| cols.iter().map(|c| c[i]).collect())
                    .collect(),
            )
        };
        let h3 = if t.has("h3") {
            Some((t.numbers("h3")?, t.indices("lrc_observations")?))
        } else {
            None
        };
        let identified_at = if t.has("identified_at") {
            let at = t.numbers("identified_at")?;
            let mut out = Vec::with_capacity(at.len());
            for (i, &v) in at.iter().enumerate() {
                out.push(if v == -1.0 {
                    None
                } else if v >= 0.0 && v.fract() == 0.0 && v < usize::MAX as Real {
                    Some(v as usize)
                } else {
                    return Err(RecordError::Field {
                        file: t.source.clone(),
                        line: i + 2,
                        field: "identified_at".into(),
                        message: format!("expected a viewpoint index or -1, found {v}"),
                    });
                });
            }
            Some(out)
        } else {
            None
        };
        Ok(Self {
            discs,
            segment: t.indices("segment")?,
            viewpoint: t.indices("viewpoint")?,
            true_material: material
                .iter()
                .map(|m| (*m >= 0.0).then_some(*m as usize))
                .collect(),
            material_names,
            posterior,
            h3,
            identified_at,
        })
    }
}

/// The segments file: `{"segments": [[disc index, ...], ...]}`.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SegmentsFile {
    /// Disc indices of each segment.
    pub segments: Vec<Vec<usize>>,
}

impl SegmentsFile {
    /// The file's text: one line of JSON.
    pub fn to_json(&self) -> Result<String, RecordError> {
        serde_json::to_string(self)
            .map(|s| s + "\n")
            .map_err(|e| RecordError::named(SEGMENTS_JSON, e))
    }
}

/// Write `cloud.ply`: every measured point (`x y z`) with its ray origin
/// (`origin_x origin_y origin_z`), binary little-endian `f32`.
pub fn write_cloud(path: &Path, cloud: &[SweepPoint]) -> Result<(), RecordError> {
    let cols: [Vec<f32>; 6] = [
        cloud.iter().map(|p| p.point.x as f32).collect(),
        cloud.iter().map(|p| p.point.y as f32).collect(),
        cloud.iter().map(|p| p.point.z as f32).collect(),
        cloud.iter().map(|p| p.origin.x as f32).collect(),
        cloud.iter().map(|p| p.origin.y as f32).collect(),
        cloud.iter().map(|p| p.origin.z as f32).collect(),
    ];
    let refs: Vec<&[f32]> = cols.iter().map(Vec::as_slice).collect();
    Ok(scene::io::write_ply_vertices_file(
        path,
        &["x", "y", "z", "origin_x", "origin_y", "origin_z"],
        &refs,
    )?)
}

/// Write `mesh.ply` (binary PLY, `scene::io`'s mesh layout).
pub fn write_mesh(path: &Path, mesh: &TriMesh) -> Result<(), RecordError> {
    Ok(scene::io::write_mesh_ply(path, mesh)?)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::coverage::MaterialCoverage;

    fn summary() -> ExploreSummary {
        let report = CoverageReport {
            samples: 10,
            covered: 4,
            covered_within_m: 0.01,
            region: None,
            samples_per_m2: 40_000.0,
            density_capped: false,
            per_material: vec![MaterialCoverage {
                material: "timber".into(),
                samples: 10,
                covered: 4,
            }],
        };
        ExploreSummary {
            format_version: crate::FORMAT_VERSION,
            scenario: "bridge1".into(),
            viewpoints: StageCounts {
                stage_one: 3,
                stage_two: 1,
            },
            termination: "information_converged".into(),
            stage_two_termination: None,
            collisions: Some(0),
            unsafe_configurations: 0,
            unsafe_configuration_list: vec![],
            min_clearance_m: Some(0.05),
            initial_information: InitialInformation {
                h1_weighted: 2.5,
                h2: 96.0,
            },
            points: 7,
            mesh_triangles: 2,
            discs: 1,
            segments: 1,
            materials: vec!["timber".into()],
            coverage: Some(ExploreCoverage::new(
                &[report.clone(), report.clone(), report],
                &[(5, 2)],
            )),
            material_accuracy: None,
            discs_observed_by_lrc: 0,
            material_identification: None,
            h3: Some(0.5),
            decision_ms: Spread::of(vec![3.0, 1.0, 2.0]),
            stage_two_decision_ms: Spread::default(),
            wall_s: 0.0,
            robot_time_s: RobotTimeSummary::default(),
            timings: None,
        }
    }

    /// Every object's keys in `text`'s order, at every level, are sorted.
    fn keys_sorted(v: &serde_json::Value) -> bool {
        match v {
            serde_json::Value::Object(m) => {
                let keys: Vec<&String> = m.keys().collect();
                keys.windows(2).all(|w| w[0] < w[1]) && m.values().all(keys_sorted)
            }
            serde_json::Value::Array(a) => a.iter().all(keys_sorted),
            _ => true,
        }
    }

    #[test]
    fn the_summary_is_written_with_sorted_keys_and_read_back() {
        let s = summary();
        let text = s.to_json().unwrap();
        assert!(text.ends_with("}\n"));
        // The keys as the text has them (the order the reader sees).
        let order: Vec<&str> = text
            .lines()
            .filter(|l| l.starts_with("  \"") && !l.starts_with("   "))
            .map(|l| l.trim().split('"').nth(1).unwrap())
            .collect();
        let mut sorted = order.clone();
        sorted.sort_unstable();
        assert_eq!(order, sorted);
        assert!(order.contains(&"format_version"));
        let v: serde_json::Value = serde_json::from_str(&text).unwrap();
        assert!(keys_sorted(&v));
        let back: ExploreSummary = serde_json::from_str(&text).unwrap();
        assert_eq!(back, s);
        assert_eq!(
            back.decision_ms,
            Spread {
                median: 2.0,
                max: 3.0
            }
        );
        assert_eq!(back.coverage.unwrap().observable.a1, Some(0.4));
    }

    /// Without timings `run.json` has no `timings` key (the same bytes as
    /// before the key existed); with them every phase is written, sorted,
    /// and read back, and the table lists each phase and the rest.
    #[test]
    fn timings_are_written_only_when_recorded() {
        let mut s = summary();
        assert!(!s.to_json().unwrap().contains("timings"));
        let t = PhaseTimings {
            setup_s: 1.0,
            oracle_s: 0.0,
            stage_one_s: 2.0,
            discs_s: 0.25,
            lrc_s: 0.5,
            stage_two_s: 3.0,
            final_mesh_s: 0.125,
            blast_planning_s: 4.0,
            write_s: 0.5,
            report_s: 0.5,
            total_s: 12.5,
        };
        s.timings = Some(t);
        let text = s.to_json().unwrap();
        let v: serde_json::Value = serde_json::from_str(&text).unwrap();
        assert!(keys_sorted(&v));
        assert_eq!(v["timings"]["blast_planning_s"], 4.0);
        let back: ExploreSummary = serde_json::from_str(&text).unwrap();
        assert_eq!(back.timings, Some(t));
        let table = t.table();
        assert_eq!(table.lines().count(), 12, "{table}");
        assert!(
            table.contains("blast planning     4.00 s  32.0 %"),
            "{table}"
        );
        assert!(table.contains("other              0.62 s"), "{table}");
    }

    /// The ratios are the run's share over the oracle's, `null` over 0; the
    /// oracle after more viewpoints than its curve is its last value; the
    /// object is written only when there is one, and read back.
    #[test]
    fn material_identification_is_compared_written_and_read_back() {
        let oracle = MaterialOracle {
            rule: "rule".into(),
            poses: 10,
            clear_poses: 6,
            aimed_poses: 3,
            samples: 1000,
            samples_per_m2: 400.0,
            identifiable: 0.8,
            identified_after_viewpoints: vec![0.1, 0.3, 0.4, 0.5],
            accuracy: Some(0.99),
        };
        assert_eq!(oracle.after(0), 0.0);
        assert_eq!(oracle.after(2), 0.3);
        assert_eq!(oracle.after(10), 0.5);
        let m = MaterialIdentification::new(
            oracle.clone(),
            0.2,
            Some(0.95),
            17,
            2,
            vec![0.1, 0.15, 0.2],
        );
        assert_eq!(m.oracle_after_10, 0.5);
        assert_eq!(m.oracle_after_stage_two_viewpoints, 0.3);
        assert_eq!(m.ratio_to_identifiable, Some(0.25));
        assert_eq!(m.ratio_after_10, Some(0.4));
        assert!((m.ratio_after_stage_two_viewpoints.unwrap() - 2.0 / 3.0).abs() < 1e-15);
        let none = MaterialIdentification::new(oracle, 0.2, None, 0, 0, Vec::new());
        assert_eq!(none.ratio_after_stage_two_viewpoints, None);
        let mut s = summary();
        assert!(!s.to_json().unwrap().contains("material_identification"));
        s.material_identification = Some(m);
        let text = s.to_json().unwrap();
        let v: serde_json::Value = serde_json::from_str(&text).unwrap();
        assert!(keys_sorted(&v));
        assert_eq!(v["material_identification"]["oracle"]["aimed_poses"], 3);
        let back: ExploreSummary = serde_json::from_str(&text).unwrap();
        assert_eq!(back, s);
    }

    #[test]
    fn disc_tables_round_trip() {
        let table = DiscTable {
            discs: vec![
                DiscRecord {
                    centre: Point3::new(0.1, -0.2, 1.5),
                    normal: UnitVector3::new_normalize(Vector3::new(0.0, 0.6, 0.8)),
                    radius_m: 0.04,
                    points: 9,
                };
                2
            ],
            segment: vec![0, 0],
            viewpoint: vec![2, 3],
            true_material: vec![None, Some(1)],
            material_names: vec!["timber".into(), "concrete".into()],
            posterior: Some(vec![vec![0.25, 0.75], vec![0.1, 0.9]]),
            h3: Some((vec![0.56, 0.3], vec![1, 2])),
            identified_at: Some(vec![None, Some(17)]),
        };
        let text = table.to_csv().unwrap();
        assert!(text.starts_with(
            "cx,cy,cz,nx,ny,nz,radius,points,segment,viewpoint,true_material,p_timber,p_concrete,h3,\
             lrc_observations,identified_at\n"
        ));
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join(DISCS_CSV);
        std::fs::write(&path, &text).unwrap();
        assert_eq!(DiscTable::read(&path).unwrap(), table);
        // Neither a fraction nor a negative other than -1 is a viewpoint.
        for bad in ["17.5", "-2"] {
            let edited = text.replacen(",17\n", &format!(",{bad}\n"), 1);
            std::fs::write(&path, &edited).unwrap();
            let err = DiscTable::read(&path).unwrap_err().to_string();
            assert!(
                err.contains("identified_at") && err.contains("line 3"),
                "{err}"
            );
        }
    }
}
