//! Which true faces a surface-following robot can bring its control point
//! to from where it stands (issue 24: Pudney gave his objects' occluded
//! faces as initial segments, P§4.3; a robot on a post beside a 1 m object
//! cannot reach its far faces).
//!
//! The test is inverse kinematics against the true scene: every face is
//! sampled (stratified, [`ReachConfig::spacing_m`] apart); a sample is
//! reachable when some joint vector within the limits puts the control point
//! δ out from it along the face's normal, with the tool axis pointing at the
//! face or tilted from that by up to [`ReachConfig::tilt_deg`], and keeps
//! every link capsule at least [`ReachConfig::clearance_m`] from the scene
//! ([`follow::place_tool`] from several start guesses, then
//! [`plan::contact::min_clearance`]). A pose is all it asks: whether the
//! follower finds a path there is the run's business.
//!
//! A follow job's setup gives the faces a robot cannot reach a priori
//! ([`unreachable_faces`], [`super::follow::FollowSetup::from_scenario`]):
//! the scene is the scenario's, known before the run as Pudney knew his
//! objects' occluded faces, so this needs no simulator.

use geom::{Isometry3, Point3, Real, UnitVector3, Vector3};
use plan::contact::min_clearance;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use robot::Robot;
use scene::Scene;
use scene::faces::{TrueFace, face_outline, triangle_samples, true_faces};
use serde::Serialize;

/// How [`face_reachability`] tests.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct ReachConfig {
    /// δ: how far out from the face the control point goes, metres.
    pub desired_distance_m: Real,
    /// Spacing of the samples on each face, metres.
    pub spacing_m: Real,
    /// Smallest clearance of every link capsule from the scene, metres.
    pub clearance_m: Real,
    /// Largest tilt of the tool axis from the face's inward normal tried,
    /// degrees (the normal itself and four tilts by this much).
    pub tilt_deg: Real,
    /// Random start guesses within the joint limits, besides the given ones.
    pub random_guesses: usize,
}

impl Default for ReachConfig {
    fn default() -> Self {
        Self {
            desired_distance_m: 0.1,
            spacing_m: 0.1,
            clearance_m: 0.02,
            tilt_deg: 45.0,
            random_guesses: 12,
        }
    }
}

/// How much of one true face the control point can be brought to.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FaceReach {
    /// The face ([`true_faces`]' index).
    pub face: usize,
    /// Its outward normal.
    pub normal: [Real; 3],
    /// Its area, m².
    pub area_m2: Real,
    /// Samples tested.
    pub samples: usize,
    /// Samples reached.
    pub reached: usize,
}

impl FaceReach {
    /// The share of the face's samples reached, `[0, 1]`.
    pub fn fraction(&self) -> Real {
        if self.samples == 0 {
            0.0
        } else {
            self.reached as Real / self.samples as Real
        }
    }
}

/// Per true face of `scene` that `keep` accepts, how much of it the control
/// point of `robot` (standing at `world_from_base`) can be brought to (see
/// the [module docs](self)). `guesses` are start guesses of the inverse
/// kinematics (joint vectors of the robot's length); random ones within the
/// limits, drawn from a fixed seed, are added. Deterministic.
pub fn face_reachability(
    scene: &Scene,
    robot: &Robot,
    world_from_base: &Isometry3,
    guesses: &[Vec<Real>],
    keep: impl Fn(&TrueFace) -> bool,
    config: &ReachConfig,
) -> Vec<FaceReach> {
    let seeds = start_guesses(robot, guesses, config.random_guesses);
    let mut out = Vec::new();
    for face in true_faces(scene).iter().filter(|f| keep(f)) {
        let mut samples = Vec::new();
        for &t in &face.triangles {
            triangle_samples(
                &scene.mesh().triangle(t as usize),
                config.spacing_m,
                &mut samples,
            );
        }
        let reached = samples
            .iter()
            .filter(|(p, _)| {
                reachable(
                    scene,
                    robot,
                    world_from_base,
                    &seeds,
                    p,
                    &face.normal,
                    config,
                )
            })
            .count();
        out.push(FaceReach {
            face: face.id,
            normal: [face.normal.x, face.normal.y, face.normal.z],
            area_m2: face.area_m2,
            samples: samples.len(),
            reached,
        });
    }
    out
}

/// `guesses`, then `random` joint vectors drawn uniformly within the limits
/// (±π for unlimited joints) from a fixed seed.
fn start_guesses(robot: &Robot, guesses: &[Vec<Real>], random: usize) -> Vec<Vec<Real>> {
    let mut rng = ChaCha8Rng::seed_from_u64(24);
    let limits = robot.limits();
    let mut out: Vec<Vec<Real>> = guesses.to_vec();
    for _ in 0..random {
        out.push(
            limits
                .iter()
                .map(|l| {
                    let (lo, hi) = l.map_or((-std::f64::consts::PI, std::f64::consts::PI), |l| {
                        (l.min, l.max)
                    });
                    rng.random_range(lo..=hi)
                })
                .collect(),
        );
    }
    out
}

/// Whether the control point can stand δ out from `p` (outward normal `n`).
fn reachable(
    scene: &Scene,
    robot: &Robot,
    world_from_base: &Isometry3,
    seeds: &[Vec<Real>],
    p: &Point3,
    n: &UnitVector3,
    config: &ReachConfig,
) -> bool {
    let target = p + n.into_inner() * config.desired_distance_m;
    let inward = -n.into_inner();
    let helper = if inward.x.abs() < 0.9 {
        Vector3::x()
    } else {
        Vector3::y()
    };
    // `helper` is never parallel to `inward`, so the cross product is not 0.
    let Some(t1) = geom::unit(inward.cross(&helper)) else {
        return false;
    };
    let t1 = t1.into_inner();
    let t2 = inward.cross(&t1);
    let tilt = config.tilt_deg.to_radians();
    let (c, s) = (tilt.cos(), tilt.sin());
    let mut axes = vec![inward];
    if tilt > 0.0 {
        axes.extend([t1, -t1, t2, -t2].map(|t| inward * c + t * s));
    }
    let search = config.clearance_m + 0.01;
    for axis in axes {
        let Some(axis) = geom::unit(axis) else {
            continue;
        };
        for seed in seeds {
            let Ok(q) = follow::place_tool(
                robot,
                world_from_base,
                &target,
                &axis,
                std::slice::from_ref(seed),
            ) else {
                continue;
            };
            let Ok(frames) = robot.forward_kinematics(&q) else {
                continue;
            };
            if min_clearance(robot, &frames, world_from_base, scene, search) >= config.clearance_m {
                return true;
            }
        }
    }
    false
}

/// A true face given a priori because the robot cannot reach it.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct AprioriFace {
    /// The face ([`true_faces`]' index).
    pub face: usize,
    /// Its outward normal.
    pub normal: [Real; 3],
    /// Its outline ([`face_outline`]), the initial segment.
    pub outline: Vec<Point3>,
}

/// The faces `keep` accepts of which the robot reaches under half the
/// samples ([`face_reachability`], samples 0.2 m apart), with their
/// outlines; a face whose outline is not one loop is left out.
pub fn unreachable_faces(
    scene: &Scene,
    robot: &Robot,
    world_from_base: &Isometry3,
    guesses: &[Vec<Real>],
    keep: impl Fn(&TrueFace) -> bool,
) -> Vec<AprioriFace> {
    let config = ReachConfig {
        spacing_m: 0.2,
        ..ReachConfig::default()
    };
    let faces = true_faces(scene);
    face_reachability(scene, robot, world_from_base, guesses, keep, &config)
        .into_iter()
        .filter(|r| r.fraction() < 0.5)
        .filter_map(|r| {
            let outline = face_outline(scene, faces.get(r.face)?)?;
            Some(AprioriFace {
                face: r.face,
                normal: r.normal,
                outline,
            })
        })
        .collect()
}
