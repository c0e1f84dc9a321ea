//! The blast plan's oracle (issue 11): which discs a nozzle pose reaches
//! when everything is known, on a planning grid made from the ground truth.

use crate::SimError;
use blast::{BlastConfig, BlastInputs};
use geom::Isometry3;
use map::{OccupancyGrid, RegionBox, VoxelState};
use robot::Robot;

/// A grid of `like`'s configuration with the ground truth's occupancy:
/// occupied where `scene`'s surface passes within a voxel's half-diagonal of
/// its centre, free elsewhere (everything known).
pub fn ground_truth_grid(
    like: &OccupancyGrid,
    scene: &scene::Scene,
) -> Result<OccupancyGrid, SimError> {
    let g = *like.geometry();
    let v = g.voxel_m();
    let reach = 0.5 * v * 3f64.sqrt();
    let occupied: Vec<bool> = g
        .keys()
        .map(|key| scene.closest_point(&key.center(v), reach).is_some())
        .collect();
    Ok(OccupancyGrid::from_states(*like.config(), |k, _| {
        if occupied[k] {
            VoxelState::Occupied
        } else {
            VoxelState::Free
        }
    })?)
}

/// The discs of `inputs` in `a2` that a nozzle pose reaches when everything
/// is known: the same pose selection as [`blast::plan_blast`], against
/// [`ground_truth_grid`] of `inputs.grid`: one reading of "the discs
/// reachable by the tool" of issue 11 (the other, a pose on the run's own
/// map, is what its test holds to 95 %).
pub fn reachable_discs(
    inputs: &BlastInputs,
    robot: &Robot,
    world_from_base: Isometry3,
    a2: &RegionBox,
    scene: &scene::Scene,
    config: &BlastConfig,
) -> Result<Vec<usize>, SimError> {
    let truth = ground_truth_grid(&inputs.grid, scene)?;
    Ok(blast::discs_with_pose(
        inputs,
        robot,
        world_from_base,
        a2,
        &truth,
        config,
    )?)
}
