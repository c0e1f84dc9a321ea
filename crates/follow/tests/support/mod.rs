//! A simulated world for the follower's tests and examples: the built-in
//! surface-following scenes as ground truth, range finders measured by ray
//! casting, and ground-truth collision checks of the robot's capsules.
//! (The full runner with scenario files, safety checks between steps and run
//! directories is `sim::follow_job`; this harness stays below `sim`.)

#![allow(dead_code, clippy::unwrap_used)]

use follow::{FollowConfig, Follower, Step};
use geom::{Isometry3, Point3, Real, Vector3};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use robot::{PosedShape, Robot};
use scene::{Scene, World};
use sensor::RangeFinder;
use surface::{SurfaceConfig, SurfaceModel};

/// Where arm4's base stands for the built-in scenes.
pub const ARM4_BASE: [Real; 3] = [-1.6, 0.0, 0.0];

/// The centre of a built-in scene's top face (SPEC §4).
pub fn top_centre(scene: &str) -> Point3 {
    match scene {
        "cube" => Point3::new(0.0, 0.0, 1.0),
        "block1" => Point3::new(-0.3, 0.0, 0.8),
        "block2" => Point3::new(0.025, 0.0, 0.6),
        _ => Point3::new(0.0, 0.0, 0.8),
    }
}

/// A follower in a simulated built-in scene.
pub struct Run {
    pub world: World,
    pub scene: Scene,
    pub robot: Robot,
    pub base: Isometry3,
    pub q: Vec<Real>,
    pub follower: Follower,
    pub rng: ChaCha8Rng,
    pub noise_m: Real,
}

impl Run {
    /// `robot` (point3 or arm4) δ above the top of `scene`, the table as an
    /// initial segment.
    pub fn new(scene_name: &str, robot_name: &str, config: FollowConfig, seed: u64) -> Self {
        Self::with_surface(
            scene_name,
            robot_name,
            config,
            SurfaceConfig::default(),
            seed,
        )
    }

    /// [`Run::new`] with a surface model configuration of its own.
    pub fn with_surface(
        scene_name: &str,
        robot_name: &str,
        config: FollowConfig,
        surface: SurfaceConfig,
        seed: u64,
    ) -> Self {
        let world = scene::builtin::scene(scene_name)
            .unwrap()
            .build(std::path::Path::new("."))
            .unwrap();
        let scene = world.as_scene().unwrap().clone();
        let robot = robot::builtin(robot_name).unwrap();
        let mut model = SurfaceModel::new(surface).unwrap();
        model
            .add_initial_segment(&[
                Point3::new(-2.0, -2.0, 0.0),
                Point3::new(2.0, -2.0, 0.0),
                Point3::new(2.0, 2.0, 0.0),
                Point3::new(-2.0, 2.0, 0.0),
            ])
            .unwrap();
        let start = top_centre(scene_name) + Vector3::z() * config.desired_distance_m;
        let (base, q) = if robot_name == "point3" {
            (Isometry3::identity(), vec![start.x, start.y, start.z])
        } else {
            let base = Isometry3::translation(ARM4_BASE[0], ARM4_BASE[1], ARM4_BASE[2]);
            let q = follow::place_tool(
                &robot,
                &base,
                &start,
                &-Vector3::z_axis(),
                &[vec![0.0, 0.8, 0.0, 1.0, 0.0, 1.0]],
            )
            .unwrap();
            (base, q)
        };
        let follower = Follower::new(robot.clone(), base, model, config).unwrap();
        Self {
            world,
            scene,
            robot,
            base,
            q,
            follower,
            rng: ChaCha8Rng::seed_from_u64(seed),
            noise_m: 0.0,
        }
    }

    /// Every range finder's reading at the current joints.
    pub fn readings(&mut self) -> Vec<Option<Point3>> {
        let frames = self.robot.forward_kinematics(&self.q).unwrap();
        self.robot
            .range_finders
            .iter()
            .map(|m| {
                RangeFinder {
                    origin: m.origin,
                    axis: m.axis,
                    max_range_m: m.max_range_m,
                    noise_sigma_m: self.noise_m,
                }
                .measure(&self.world, &(self.base * frames[m.link.0]), &mut self.rng)
                .map(|s| s.point)
            })
            .collect()
    }

    /// Sense, step and move; the step taken.
    pub fn step(&mut self) -> Step {
        let readings = self.readings();
        let step = self.follower.step(&self.q, &readings).unwrap();
        for (qi, d) in self.q.iter_mut().zip(&step.dq) {
            *qi += d;
        }
        step
    }

    /// The smallest signed distance between the robot's capsules (links ≥ 1)
    /// and the scene (negative: in collision), looking 0.3 m out.
    pub fn clearance(&self) -> Real {
        self.clearance_outside_control_zone(0.0)
    }

    /// Like [`Run::clearance`], but of the links outside the control
    /// point's zone (the ball of radius `exclusion` about it; 0: the whole
    /// links): what eq. 4's link descriptions cover, so what redundancy
    /// acts on (P§3.3).
    pub fn clearance_outside_control_zone(&self, exclusion: Real) -> Real {
        let frames = self.robot.forward_kinematics(&self.q).unwrap();
        let cp = self.follower.control_point(&self.q).unwrap();
        let mut best: Real = 0.3;
        for shape in self.robot.posed_collision_shapes(&frames) {
            if let PosedShape::Capsule { link, capsule } = shape {
                if link.0 == 0 {
                    continue;
                }
                let c = capsule.transformed(&self.base);
                let pieces = if exclusion > 0.0 {
                    follow::actuator::outside_ball(&c.segment, &cp, exclusion)
                } else {
                    vec![c.segment]
                };
                for piece in pieces {
                    let part = geom::Capsule::new(piece.a, piece.b, c.radius);
                    for face in self
                        .scene
                        .triangles_near(&part.bounding_box().loosened(best))
                    {
                        let tri = self.scene.mesh().triangle(face as usize);
                        best = best.min(part.distance_to_triangle(&tri));
                    }
                }
            }
        }
        best
    }

    /// Development aid: for each link touching the scene, where along its
    /// axis, the true distance there and the model's distance there.
    #[allow(dead_code)]
    pub fn explain_collision(&self, extra: Real) {
        let frames = self.robot.forward_kinematics(&self.q).unwrap();
        let cp = self.follower.control_point(&self.q).unwrap();
        for shape in self.robot.posed_collision_shapes(&frames) {
            if let PosedShape::Capsule { link, capsule } = shape {
                if link.0 == 0 {
                    continue;
                }
                let c = capsule.transformed(&self.base);
                for k in 0..=50 {
                    let t = Real::from(k) / 50.0;
                    let p = c.segment.point_at(t);
                    let mut d: Real = 1.0;
                    for face in self
                        .scene
                        .triangles_near(&geom::Aabb::from_points([&p]).loosened(0.2))
                    {
                        d = d.min(
                            self.scene
                                .mesh()
                                .triangle(face as usize)
                                .distance_to_point(&p),
                        );
                    }
                    if d < c.radius + extra {
                        let m = follow::query::closest_model_point(self.follower.model(), &p, 1.0)
                            .map_or(Real::INFINITY, |m| m.distance);
                        println!(
                            "   link {} t {t:.2} p ({:.3},{:.3},{:.3}) from cp {:.3}: scene {d:.3} model {m:.3}",
                            link.0,
                            p.x,
                            p.y,
                            p.z,
                            (p - cp).norm()
                        );
                    }
                }
            }
        }
    }
}
