//! `surveyor scenario mjcf`: a scenario as a MuJoCo model.

use super::output::Staged;
use anyhow::{Context, Result, bail};
use clap::Args;
use hw::Arm;
use scenario::Scenario;
use scenario::mjcf::{MjcfArm, MjcfConfig};
use std::path::PathBuf;

#[derive(Debug, Args)]
pub struct MjcfArgs {
    /// Built-in scenario name or scenario file.
    name: String,
    /// Another robot, placed and started as `surveyor follow --robot` and
    /// `surveyor sim-robot --robot` place it (point3, arm4 or a URDF file).
    #[arg(long)]
    robot: Option<String>,
    /// Output MJCF file (`.xml`); its sidecar is written beside it with the
    /// extension `.json`.
    #[arg(long)]
    out: PathBuf,
}

pub fn mjcf(a: &MjcfArgs) -> Result<()> {
    if a.out.extension().is_none_or(|e| e != "xml") {
        bail!(
            "--out {}: expected a file name ending in .xml (the sidecar goes beside it as .json)",
            a.out.display()
        );
    }
    let loaded = Scenario::load(&a.name)?;
    let rig = super::robot_server::served_rig(&loaded, a.robot.as_deref(), 0)?;
    let start = rig.joints();
    let arm = MjcfArm {
        robot: rig.robot(),
        world_from_base: rig.world_from_base(),
        start_joints: &start,
        range_noise_sigma_m: rig.range_noise_sigma_m(),
    };
    let model = scenario::mjcf::model(&loaded, &arm, &MjcfConfig::default())?;
    let sidecar_path = a.out.with_extension("json");
    let mut staged = Staged::new();
    std::fs::write(staged.file(&a.out)?, &model.xml)
        .with_context(|| format!("writing {}", a.out.display()))?;
    let json = serde_json::to_string_pretty(&model.sidecar)?;
    std::fs::write(staged.file(&sidecar_path)?, json + "\n")
        .with_context(|| format!("writing {}", sidecar_path.display()))?;
    staged.commit()?;
    for n in &model.notes {
        note!("note: {n}");
    }
    let masses: Vec<String> = model
        .sidecar
        .link_masses_kg
        .iter()
        .filter(|(_, m)| *m > 0.0)
        .map(|(l, m)| format!("{l} {m:.2}"))
        .collect();
    say!(
        "{} ({}, {} joints, {} scene geoms) → {} and {}",
        loaded.scenario.name,
        arm.robot.name,
        model.sidecar.joints.len(),
        model.sidecar.scene_geoms.len(),
        a.out.display(),
        sidecar_path.display()
    )?;
    say!("link masses, kg: {}", masses.join(", "))?;
    let torques: Vec<String> = model
        .sidecar
        .joints
        .iter()
        .map(|j| format!("{} {:.1}", j.name, j.torque_limit))
        .collect();
    say!("torque limits, N·m (N): {}", torques.join(", "))?;
    Ok(())
}
