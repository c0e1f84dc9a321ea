//! `surveyor sim-robot --ros2`: the simulator as a ROS 2 robot.

use anyhow::{Result, bail};
use clap::Args;
use geom::Real;
use scenario::{LoadedScenario, Scenario};
use sim::SimRig;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

#[derive(Debug, Args)]
pub struct SimRobotArgs {
    /// Built-in scenario name or scenario file: the robot (with its scanner and
    /// range finders), where it stands, and the world its sensors see.
    #[arg(long)]
    scenario: String,
    /// Serve it over ROS 2 (DDS, no ROS installation needed): publishes
    /// /joint_states, /scan and /range/finder_K, executes
    /// trajectory_msgs/JointTrajectory on
    /// /joint_trajectory_controller/joint_trajectory. Domain from ROS_DOMAIN_ID;
    /// discovery on loopback only unless --all-networks.
    #[arg(long, required = true)]
    ros2: bool,
    /// Discover and talk on every network interface (a robot network), not
    /// only on loopback.
    #[arg(long)]
    all_networks: bool,
    /// Another robot, placed and started as `surveyor follow --robot` places
    /// it on this scenario (point3, arm4 or a URDF file; range finders only).
    #[arg(long)]
    robot: Option<String>,
    /// Seed of the sensor noise.
    #[arg(long, allow_negative_numbers = true, value_parser = crate::commands::whole::<u64>, default_value_t = 0)]
    seed: u64,
    /// Speed of the fastest joint of every motion, rad/s.
    #[arg(long, default_value_t = 1.0, allow_negative_numbers = true)]
    joint_speed: Real,
    /// Sense only when asked on /surveyor/sense (std_msgs/String `scan`,
    /// `ranges` or `seed N`), so that the noise follows the sequence of an
    /// in-process run (surveyor's own driver in lockstep).
    #[arg(long)]
    lockstep: bool,
    /// Robot seconds per second of wall time: the arm moves, the sensors
    /// sense and the stamps and `/clock` run this much faster than real time
    /// (at most 100; a driver following `/clock` times out on it).
    #[arg(long, default_value_t = 1.0, allow_negative_numbers = true)]
    rate: Real,
    /// Stop after this many seconds (default: run until Ctrl-C).
    #[arg(long = "for", allow_negative_numbers = true)]
    duration_s: Option<Real>,
}

/// The rig `sim-robot` serves: the scenario's robot with every sensor it
/// carries, or `robot` placed and started as `surveyor follow --robot`
/// places it.
pub fn served_rig(loaded: &LoadedScenario, robot: Option<&str>, seed: u64) -> Result<SimRig> {
    Ok(match robot {
        None => SimRig::with_every_sensor(loaded, seed)?,
        Some(name) => {
            let options = sim::follow_job::FollowRunOptions {
                robot: Some(name.to_owned()),
                seed,
                ..sim::follow_job::FollowRunOptions::default()
            };
            sim::follow_job::SimFollow::from_scenario(loaded, &options)?.rig
        }
    })
}

pub fn sim_robot(a: &SimRobotArgs) -> Result<()> {
    if !(a.joint_speed.is_finite() && a.joint_speed > 0.0 && a.joint_speed <= 10.0) {
        bail!(
            "--joint-speed {}: expected more than 0 and at most 10 rad/s",
            a.joint_speed
        );
    }
    if let Some(d) = a.duration_s
        && !(d.is_finite() && d > 0.0 && d <= 7.0 * 86_400.0)
    {
        bail!("--for {d}: expected more than 0 and at most a week of seconds");
    }
    if !(a.rate.is_finite() && a.rate > 0.0 && a.rate <= ros2::MAX_RATE) {
        bail!(
            "--rate {}: expected robot seconds per wall second above 0 and at most {}",
            a.rate,
            ros2::MAX_RATE
        );
    }
    let loaded = Scenario::load(&a.scenario)?;
    let mut rig = served_rig(&loaded, a.robot.as_deref(), a.seed)?;
    let robot = rig.robot().clone();
    let mut config = ros2::Ros2Config::from_env()?;
    config.loopback_only = !a.all_networks;
    let mut node = ros2::Ros2Node::new("surveyor_sim_robot", &config)?;
    let serve = ros2::ServeConfig {
        joint_speed: a.joint_speed,
        scan_range_m: rig
            .scan_range_m()
            .unwrap_or(ros2::ServeConfig::default().scan_range_m),
        finder_range_slack_m: 10.0 * rig.range_noise_sigma_m(),
        lockstep: a.lockstep,
        ros2: loaded.scenario.ros2.clone().unwrap_or_default(),
        rate: a.rate,
        // A lockstep robot answers each request at once; one faster than
        // real time turns as often in its own seconds as one in real time.
        tick_s: if a.lockstep {
            0.0005
        } else {
            (ros2::ServeConfig::default().tick_s / a.rate.max(1.0)).max(0.0005)
        },
        // Joint states at 100 Hz, as most arms publish them.
        state_period_s: 0.01,
        ..ros2::ServeConfig::default()
    };
    let stop = Arc::new(AtomicBool::new(false));
    {
        let stop = Arc::clone(&stop);
        if let Err(e) = ctrlc::set_handler(move || stop.store(true, Ordering::Relaxed)) {
            note!("note: Ctrl-C will not stop the robot cleanly ({e})");
        }
    }
    if let Some(d) = a.duration_s {
        let stop = Arc::clone(&stop);
        std::thread::spawn(move || {
            std::thread::sleep(std::time::Duration::from_secs_f64(d));
            stop.store(true, Ordering::Relaxed);
        });
    }
    say!(
        "{} ({}, {} joints, {} range finders{}) on ROS 2 domain {}{}; Ctrl-C stops",
        loaded.scenario.name,
        robot.name,
        robot.dof(),
        robot.range_finders.len(),
        if robot.scanner.is_some() {
            ", a scanner"
        } else {
            ""
        },
        config.domain_id,
        if config.loopback_only {
            ", loopback only"
        } else {
            ""
        }
    )?;
    let stats = ros2::serve_robot(&mut rig, &robot, &mut node, &serve, &stop, &mut |m| {
        note!("{m}");
    })?;
    say!(
        "served: {} joint states, {} scans, {} readings, {} trajectories ({} refused)",
        stats.states,
        stats.scans,
        stats.readings,
        stats.trajectories,
        stats.refused
    )?;
    Ok(())
}
