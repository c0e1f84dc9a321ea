//! Single-point range finders (Pudney §1.2, §4.2).

use geom::{Isometry3, Point3, Ray, Real, UnitVector3};
use rand::Rng;
use rand_distr::{Distribution, Normal};
use scene::RayCast;
use serde::{Deserialize, Serialize};

/// A range finder fixed in some mount frame (a robot link).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct RangeFinder {
    /// Sensor position `s` in the mount frame.
    pub origin: Point3,
    /// Unit sensing axis `â` in the mount frame.
    pub axis: UnitVector3,
    /// Longest distance it reports, metres.
    pub max_range_m: Real,
    /// Standard deviation of additive Gaussian range noise, metres (0: exact).
    pub noise_sigma_m: Real,
}

/// A sensor point (P eq. 1): the surface point `p = s + d·â` in the world
/// frame, with the sensing axis that measured it.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SensorPoint {
    /// The measured point.
    pub point: Point3,
    /// The sensing axis (world frame).
    pub axis: UnitVector3,
    /// The sensor position (world frame).
    pub sensor: Point3,
    /// The reading `d`.
    pub distance_m: Real,
}

impl SensorPoint {
    /// The point a reading `d` along `axis` from `sensor` gives: what a
    /// driver that reports only the distance (a ROS 2 `sensor_msgs/Range`)
    /// makes of it. One function for the simulator and the drivers, so
    /// that both place a reading on the same bits.
    pub fn along(sensor: Point3, axis: UnitVector3, d: Real) -> Self {
        Self {
            point: sensor + axis.into_inner() * d,
            axis,
            sensor,
            distance_m: d,
        }
    }
}

/// `x` as a float32 carries it (ROS 2's `sensor_msgs/LaserScan` and
/// `sensor_msgs/Range` carry ranges and intensities so): what a sensor's
/// driver reports.
pub fn float32(x: Real) -> Real {
    // The rounding is the point: a driver's message holds no more.
    #[allow(clippy::cast_possible_truncation)]
    Real::from(x as f32)
}

impl RangeFinder {
    /// The sensing ray in the world frame, given the mount's pose.
    pub fn ray(&self, world_from_mount: &Isometry3) -> Ray {
        Ray::new(world_from_mount * self.origin, world_from_mount * self.axis)
    }

    /// Take a reading: the first surface along the axis within range, with noise
    /// drawn from `rng` when `noise_sigma_m > 0`. `None` when nothing is in range.
    /// For point-cloud worlds the sensor point is the cloud point selected by the
    /// ε rule (P§4.2), not its projection on the axis.
    pub fn measure<W: RayCast + ?Sized, R: Rng + ?Sized>(
        &self,
        world: &W,
        world_from_mount: &Isometry3,
        rng: &mut R,
    ) -> Option<SensorPoint> {
        let ray = self.ray(world_from_mount);
        let hit = world.cast_ray(&ray, self.max_range_m)?;
        let noise = if self.noise_sigma_m > 0.0 {
            Normal::new(0.0, self.noise_sigma_m).map_or(0.0, |n| n.sample(rng))
        } else {
            0.0
        };
        // Noise moves the point along the sensing axis.
        let d = (hit.distance + noise).max(0.0);
        let point = hit.point + ray.dir.into_inner() * (d - hit.distance);
        Some(SensorPoint {
            point,
            axis: ray.dir,
            sensor: ray.origin,
            distance_m: d,
        })
    }
}
