//! A finished run as its run folder's files ([`record`]).

use crate::ExploreError;
use crate::run::ExploreRun;
use geom::Real;
use record::Staging;
use record::explore::{
    CLOUD_PLY, DISCS_CSV, ExploreCoverage, ExploreSummary, InitialInformation, MESH_PLY, RUN_JSON,
    SEGMENTS_JSON, Spread, StageCounts,
};
use record::viewpoints::{
    CANDIDATES_CSV, PATH_CSV, VIEWPOINTS_CSV, candidates_csv, path_csv, viewpoints_csv,
};

impl ExploreRun {
    /// `run.json`'s summary; `coverage` is the judge's (`None` without a
    /// ground truth). A judge that knows the true materials adds the
    /// material identification against its oracle.
    pub fn summary(&self, coverage: Option<ExploreCoverage>) -> ExploreSummary {
        let times = |pick: &dyn Fn(&record::ViewpointRecord) -> bool| {
            Spread::of(
                self.viewpoints
                    .iter()
                    .filter(|r| pick(r))
                    .map(|r| r.decision_ms)
                    .collect::<Vec<Real>>(),
            )
        };
        let per_stage = |k: u8| self.viewpoints.iter().filter(|r| r.stage == k).count();
        ExploreSummary {
            format_version: record::FORMAT_VERSION,
            scenario: self.scenario.clone(),
            viewpoints: StageCounts {
                stage_one: per_stage(1),
                stage_two: per_stage(2),
            },
            termination: self.termination.name().to_owned(),
            stage_two_termination: self.stage_two_termination.clone(),
            collisions: self.tally.collisions,
            unsafe_configurations: self.unsafe_configurations.len(),
            unsafe_configuration_list: self.unsafe_configurations.clone(),
            min_clearance_m: self.tally.min_clearance_m,
            initial_information: InitialInformation {
                h1_weighted: self.initial_information.0,
                h2: self.initial_information.1,
            },
            points: self.cloud.len(),
            mesh_triangles: self.mesh.triangles.len(),
            discs: self.discs.discs.len(),
            segments: self.discs.segments.len(),
            materials: self.discs.material_names.clone(),
            coverage,
            material_accuracy: self.discs.material_accuracy(),
            discs_observed_by_lrc: self.discs.observations.iter().filter(|o| **o > 0).count(),
            material_identification: None,
            h3: self.discs.h3_total,
            decision_ms: times(&|r| r.f.is_some()),
            stage_two_decision_ms: times(&|r| r.stage == 2),
            wall_s: self.wall_s,
            robot_time_s: record::explore::RobotTimeSummary::of(&self.viewpoints),
            timings: self.timings,
        }
    }

    /// Stage the run's files: `viewpoints.csv`, `candidates.csv`, `path.csv`,
    /// `cloud.ply`, `mesh.ply`, `discs.csv`, `segments.json` and `run.json`
    /// (`summary`: [`Self::summary`] with what a judge adds).
    pub fn write(&self, staging: &Staging, summary: &ExploreSummary) -> Result<(), ExploreError> {
        staging.write(VIEWPOINTS_CSV, viewpoints_csv(&self.viewpoints))?;
        staging.write(CANDIDATES_CSV, candidates_csv(&self.viewpoints))?;
        staging.write(PATH_CSV, path_csv(&self.viewpoints))?;
        record::explore::write_cloud(&staging.path(CLOUD_PLY), &self.cloud)?;
        record::explore::write_mesh(&staging.path(MESH_PLY), &self.mesh)?;
        staging.write(DISCS_CSV, self.discs.table().to_csv()?)?;
        staging.write(SEGMENTS_JSON, self.discs.segments_file().to_json()?)?;
        staging.write(RUN_JSON, summary.to_json()?)?;
        Ok(())
    }

    /// Per disc: the joints of the viewpoint that saw it (where a pose
    /// search for the disc starts).
    pub fn disc_start_joints(&self) -> Result<Vec<Vec<Real>>, ExploreError> {
        self.discs
            .viewpoint
            .iter()
            .map(|&v| {
                self.viewpoints
                    .get(v)
                    .map(|r| r.joints.clone())
                    .ok_or_else(|| ExploreError::Resume {
                        what: "disc map".into(),
                        message: format!("a disc names viewpoint {v}, which the run lacks"),
                    })
            })
            .collect()
    }
}
