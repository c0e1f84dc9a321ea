//! The `--ros2` paths of `explore` and `follow`: a ROS 2 robot as the
//! hardware of a job, and the live view of its run. A robot's exploration
//! runs the job of [`scenario::job::explore`], its surface following the
//! job of [`scenario::job::follow`], and neither uses a simulator type (the
//! architecture test reads this file to check it).

use anyhow::Result;
use clap::Args;
use follow::Follower;
use geom::Real;
use record::StepRow;
use scenario::job::JobError;
use scenario::job::explore::{ExploreOptions, HardwareExplore};
use scenario::job::follow::{FollowRun, FollowSetup, HardwareFollow, follow_with};
use std::cell::RefCell;
use std::path::Path;
use std::rc::Rc;
use std::sync::atomic::AtomicBool;

/// How `explore` and `follow` drive a ROS 2 robot instead of the simulator.
#[derive(Debug, Args)]
pub struct Ros2Flags {
    /// Drive a ROS 2 robot (DDS, no ROS installation needed) instead of the
    /// simulator: joint states from /joint_states, scans from /scan, range
    /// readings from /range/finder_K, motions sent as
    /// trajectory_msgs/JointTrajectory to
    /// /joint_trajectory_controller/joint_trajectory. The robot must stand at
    /// the run's start joints. Domain from ROS_DOMAIN_ID; discovery on
    /// loopback only unless --all-networks. No ground truth: no coverage,
    /// contact or clearance figures, no true materials.
    #[arg(long)]
    pub ros2: bool,
    /// With --ros2: discover and talk on every network interface (a robot
    /// network), not only on loopback.
    #[arg(long, requires = "ros2")]
    pub all_networks: bool,
    /// With --ros2: ask for every scan, range reading and noise seed on
    /// /surveyor/sense, and wait for each motion to end exactly on its goal
    /// (a `surveyor sim-robot --lockstep`: the run is then the in-process
    /// run of the same seed).
    #[arg(long, requires = "ros2")]
    pub lockstep: bool,
}

impl Ros2Flags {
    /// The ROS 2 robot of `robot` at `world_from_base`, its scanner's rays
    /// at `bearings`: waits for its first joint state.
    pub fn connect(
        &self,
        spec: &scenario::ros2::Ros2Spec,
        robot: &robot::Robot,
        world_from_base: &geom::Isometry3,
        bearings: &[Real],
    ) -> Result<ros2::Ros2Hardware> {
        let mut config = ros2::Ros2Config::from_env()?;
        config.loopback_only = !self.all_networks;
        let node = ros2::Ros2Node::new("surveyor", &config)?;
        let driver = ros2::DriverConfig {
            ros2: spec.clone(),
            lockstep: self.lockstep,
            limits: None,
        };
        note!(
            "waiting for {}'s joint states on ROS 2 domain {}{}",
            robot.name,
            config.domain_id,
            if config.loopback_only {
                " (loopback only)"
            } else {
                ""
            }
        );
        Ok(ros2::Ros2Hardware::new(
            node,
            robot,
            world_from_base,
            bearings,
            driver,
        )?)
    }

    /// With --ros2: the robot ([`Ros2Flags::connect`]) and the run's live
    /// view ([`Ros2Flags::live`]); without, none.
    pub fn open(
        &self,
        spec: &scenario::ros2::Ros2Spec,
        robot: &robot::Robot,
        world_from_base: &geom::Isometry3,
        bearings: &[Real],
    ) -> Result<Option<(ros2::Ros2Hardware, Rc<RefCell<ros2::LiveView>>)>> {
        if !self.ros2 {
            return Ok(None);
        }
        let hw = self.connect(spec, robot, world_from_base, bearings)?;
        Ok(Some((hw, self.live(robot, world_from_base)?)))
    }

    /// The live view of a run on `robot` standing at `world_from_base`:
    /// its own node beside the driver's, publishing on the topics the run's
    /// bag holds.
    pub fn live(
        &self,
        robot: &robot::Robot,
        world_from_base: &geom::Isometry3,
    ) -> Result<Rc<RefCell<ros2::LiveView>>> {
        let mut config = ros2::Ros2Config::from_env()?;
        config.loopback_only = !self.all_networks;
        let node = ros2::Ros2Node::new("surveyor_live", &config)?;
        Ok(Rc::new(RefCell::new(ros2::LiveView::new(
            node,
            robot,
            world_from_base,
        )?)))
    }

    /// How far from the start joints the robot may stand, radians (the
    /// `[ros2]` tolerance; none in lockstep).
    pub fn start_tolerance(&self, spec: &scenario::ros2::Ros2Spec) -> Real {
        ros2::DriverConfig {
            ros2: spec.clone(),
            lockstep: self.lockstep,
            limits: None,
        }
        .tolerance_rad()
    }
}

/// What the live view of an exploration publishes as the loop goes: the
/// arm's frames at the end of every motion and every sweep's points (a
/// watcher: it knows no truth).
pub struct LiveWatcher(pub Rc<RefCell<ros2::LiveView>>);

impl explore::Judge for LiveWatcher {
    fn motion(
        &mut self,
        _viewpoint: usize,
        _a: &[Real],
        b: &[Real],
        _checked: &[Vec<Real>],
    ) -> Result<(), explore::ExploreError> {
        self.0.borrow_mut().frames(b);
        Ok(())
    }

    fn sweep(&mut self, sweep: &sensor::Sweep) {
        self.0.borrow_mut().sweep(sweep.points());
    }

    fn coverage_a1(&self) -> Option<Real> {
        None
    }

    fn true_material(&self, _: &geom::Point3, _: &geom::Vector3) -> Option<usize> {
        None
    }

    fn tally(&self) -> explore::SafetyTally {
        explore::SafetyTally::default()
    }

    fn restore(&mut self, _: explore::SafetyTally) {}
}

/// Say what the live view sent, and the first message it could not.
pub fn say_live(live: &RefCell<ros2::LiveView>) -> Result<()> {
    let live = live.borrow();
    say!(
        "live view: {} messages on /tf, /tf_static, /surveyor/sweep and the markers",
        live.messages_sent()
    )?;
    if let Some(f) = live.first_failure() {
        note!("live view: could not send {f}");
    }
    Ok(())
}

/// The live view's viewpoints and discs once the run has them.
pub fn publish_markers(
    live: &RefCell<ros2::LiveView>,
    loaded: &scenario::LoadedScenario,
    run: &explore::ExploreRun,
) -> Result<()> {
    let (viewpoints, discs) = scenario::job::explore::explore_markers(
        ros2::wall_clock_ns(),
        run,
        &loaded.build_robot()?,
        &loaded.scenario.world_from_base(),
    )?;
    let mut view = live.borrow_mut();
    view.markers(record::bag::topics::VIEWPOINTS, viewpoints);
    view.markers(record::bag::topics::DISCS, discs);
    drop(view);
    say_live(live)
}

/// The ROS 2 robot to explore with (`--ros2`), waiting for its first joint
/// state, and the run's live view; `None` for the simulator.
pub fn connect_explore(
    flags: &Ros2Flags,
    loaded: &scenario::LoadedScenario,
) -> Result<Option<(ros2::Ros2Hardware, Rc<RefCell<ros2::LiveView>>)>> {
    if !flags.ros2 {
        return Ok(None);
    }
    let spec = loaded.scenario.scanner.clone().unwrap_or_default();
    let bearings = sensor::Scanner::new(spec.config)?.bearings_rad().to_vec();
    flags.open(
        &loaded.scenario.ros2.clone().unwrap_or_default(),
        &loaded.build_robot()?,
        &loaded.scenario.world_from_base(),
        &bearings,
    )
}

/// The exploration of `loaded` under `options` on the ROS 2 robot `hw`,
/// which must stand at the scenario's start joints (within
/// `start_tolerance` radians), watched by the run's `live` view.
pub fn explore_job(
    loaded: &scenario::LoadedScenario,
    options: &ExploreOptions,
    hw: ros2::Ros2Hardware,
    live: Option<Rc<RefCell<ros2::LiveView>>>,
    start_tolerance: Real,
) -> Result<HardwareExplore<ros2::Ros2Hardware>, JobError> {
    let job = HardwareExplore::new(loaded, options, hw, start_tolerance)?;
    Ok(match live {
        Some(live) => job.judged_by(Box::new(LiveWatcher(live))),
        None => job,
    })
}

/// A live view of surface following publishes the surface model every
/// this many steps.
const LIVE_MODEL_EVERY: u64 = 25;

/// The live view of a step: the arm's frames at `q`, and `model` when given.
fn live_step(live: &RefCell<ros2::LiveView>, q: &[Real], model: Option<&surface::SurfaceModel>) {
    let mut view = live.borrow_mut();
    view.frames(q);
    if let Some(model) = model {
        view.markers(
            record::bag::topics::SURFACE_MODEL,
            record::bag::markers::surface_model(ros2::wall_clock_ns(), &model.to_model_json()),
        );
    }
}

/// The whole `surveyor follow --ros2` job: the surface following of
/// `setup` on the ROS 2 robot `flags` connect to under `spec` (waiting for
/// its first joint state; it must stand at the setup's start joints), its
/// run folder as [`follow_with`] writes it (`scenario_toml`, `out`,
/// `finish`), and its live view, which `progress` sees every step beside.
/// The run and its live view, for [`say_follow_live`].
#[allow(
    clippy::too_many_arguments,
    reason = "follow_with's arguments and the robot's two: each is one the binary reads"
)]
pub fn follow_job(
    flags: &Ros2Flags,
    spec: &scenario::ros2::Ros2Spec,
    setup: FollowSetup,
    scenario_toml: Option<String>,
    out: &Path,
    stop: &AtomicBool,
    progress: &mut dyn FnMut(&StepRow, &Follower),
    finish: &mut dyn FnMut(&record::Staging) -> Result<(), String>,
) -> Result<(FollowRun, Rc<RefCell<ros2::LiveView>>)> {
    let hw = flags.connect(spec, &setup.robot, &setup.world_from_base, &[])?;
    let live = flags.live(&setup.robot, &setup.world_from_base)?;
    let job = HardwareFollow::new(setup, hw, flags.start_tolerance(spec))?;
    let run = follow_with(
        scenario_toml,
        out,
        |stop, progress| job.run(stop, progress),
        stop,
        &mut |row, follower| {
            progress(row, follower);
            let model = row
                .step
                .is_multiple_of(LIVE_MODEL_EVERY)
                .then(|| follower.model());
            live_step(&live, &row.joints, model);
        },
        finish,
    )?;
    Ok((run, live))
}

/// The live view's last frames and surface model once the run has them,
/// and what it sent.
pub fn say_follow_live(live: &RefCell<ros2::LiveView>, run: &FollowRun) -> Result<()> {
    live_step(live, &run.episode.end_joints, Some(&run.model));
    say_live(live)
}
