//! How long a motion takes: every joint within its velocity and
//! acceleration limits, all joints on one straight line in joint space,
//! starting and ending at rest (SPEC §3.9, the robot clock).
//!
//! A motion from `a` to `b` runs `q(t) = a + s(t) (b − a)`, where `s` goes
//! from 0 to 1 on a trapezoidal velocity profile: it accelerates at its
//! limit, cruises, and brakes at its limit (a triangle when the motion is
//! too short to reach the cruise speed). Joint `i` moves `dᵢ = |bᵢ − aᵢ|`,
//! so its speed is `dᵢ ṡ` and its acceleration `dᵢ s̈`; the profile's
//! limits are the tightest over the joints, `ṡ ≤ minᵢ vᵢ/dᵢ` and
//! `|s̈| ≤ minᵢ aᵢ/dᵢ`. Every joint then starts and stops together and
//! the arm stays on the line the planner checked.
//!
//! ```
//! use robot::timing::MotionLimits;
//! // Two joints at 1 rad/s and 2 rad/s²: 1 rad takes 1 s cruising plus
//! // 0.5 s to speed up and slow down; 0.1 rad never reaches 1 rad/s.
//! let limits = MotionLimits::uniform(2, 1.0, 2.0);
//! assert!((limits.duration_s(&[0.0, 0.0], &[1.0, 0.5]) - 1.5).abs() < 1e-12);
//! assert!((limits.duration_s(&[0.0, 0.0], &[0.1, 0.0]) - 2.0 * (0.1f64 / 2.0).sqrt()).abs() < 1e-12);
//! ```

use crate::{JointKind, Robot};
use geom::Real;

/// Speed of a joint whose robot states none, rad/s (a conservative figure:
/// industrial arms of the DENSO VM's class publish 2.5–5 rad/s per joint).
pub const DEFAULT_VELOCITY_RAD_S: Real = 1.0;
/// Speed of a prismatic joint whose robot states none, m/s.
pub const DEFAULT_VELOCITY_M_S: Real = 0.25;
/// Acceleration of a revolute joint, rad/s²: URDF has no acceleration
/// limit and few makers publish one; 2 rad/s² is conservative (the UR
/// arms' `movej` default is 1.4 rad/s², their limit far higher).
pub const DEFAULT_ACCELERATION_RAD_S2: Real = 2.0;
/// Acceleration of a prismatic joint, m/s².
pub const DEFAULT_ACCELERATION_M_S2: Real = 1.0;
/// The largest velocity or acceleration a scenario may state (rad/s,
/// rad/s², m/s, m/s²).
pub const MAX_LIMIT: Real = 1000.0;

/// Velocity and acceleration limits of each actuated joint.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct MotionLimits {
    /// Largest speed per joint, rad/s (m/s prismatic).
    pub velocity: Vec<Real>,
    /// Largest acceleration per joint, rad/s² (m/s² prismatic).
    pub acceleration: Vec<Real>,
}

/// A timed straight-line motion: `s(t)` from 0 to its end (1 unless the
/// motion was [braked](Profile::braked)); see the module docs.
///
/// `s` speeds up at `s̈` until `t_up`, cruises at `s̈·t_up` until
/// `t_down`, and slows down at `s̈` to rest at `t_down + t_up`. A full
/// motion has `t_up = ṡ_max/s̈` and `t_down = 1/ṡ_max` (a triangle:
/// both `1/√s̈`), so it ends at `s̈·t_up·t_down = 1`.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Profile {
    /// Seconds the motion takes.
    pub duration_s: Real,
    /// `s̈` while speeding up and slowing down, per second².
    accel: Real,
    /// When speeding up ends, seconds.
    t_up: Real,
    /// When slowing down begins, seconds.
    t_down: Real,
    /// `s` at rest at the end: 1, or less once braked.
    end: Real,
}

impl Profile {
    /// A motion that does not move.
    pub const STILL: Self = Self {
        duration_s: 0.0,
        accel: 0.0,
        t_up: 0.0,
        t_down: 0.0,
        end: 1.0,
    };

    fn new(accel: Real, t_up: Real, t_down: Real, end: Real) -> Self {
        Self {
            duration_s: t_down + t_up,
            accel,
            t_up,
            t_down,
            end,
        }
    }

    /// The fraction `s(t)` of the motion done `t` seconds after it began
    /// (0 before, [`Profile::end`] after).
    pub fn fraction(&self, t: Real) -> Real {
        if self.duration_s <= 0.0 || t >= self.duration_s {
            return self.end;
        }
        if t <= 0.0 {
            return 0.0;
        }
        let a = self.accel;
        if t < self.t_up {
            0.5 * a * t * t
        } else if t < self.t_down {
            0.5 * a * self.t_up * self.t_up + a * self.t_up * (t - self.t_up)
        } else {
            let left = self.duration_s - t;
            self.end - 0.5 * a * left * left
        }
    }

    /// `ṡ(t)`, per second.
    pub fn speed(&self, t: Real) -> Real {
        if self.duration_s <= 0.0 || t <= 0.0 || t >= self.duration_s {
            return 0.0;
        }
        self.accel * t.min(self.t_up).min(self.duration_s - t)
    }

    /// Where the motion comes to rest: 1 for a whole motion, less once
    /// braked.
    pub fn end(&self) -> Real {
        self.end
    }

    /// The motion braked at `t`: from then on it slows down at its
    /// acceleration limit to rest (unchanged when it is slowing down
    /// already, or has ended, at `t`).
    #[must_use]
    pub fn braked(&self, t: Real) -> Self {
        if self.duration_s <= 0.0 || t >= self.t_down {
            return *self;
        }
        let t = t.max(0.0);
        let t_up = self.t_up.min(t);
        // Slowing down from ṡ = s̈·t_up takes t_up and covers ½·s̈·t_up².
        let end = self.fraction(t) + 0.5 * self.accel * t_up * t_up;
        Self::new(self.accel, t_up, t, end.min(self.end))
    }
}

impl MotionLimits {
    /// The same limits on each of `dof` joints.
    pub fn uniform(dof: usize, velocity: Real, acceleration: Real) -> Self {
        Self {
            velocity: vec![velocity; dof],
            acceleration: vec![acceleration; dof],
        }
    }

    /// The limits of `robot`'s actuated joints: each joint's stated
    /// velocity ([`crate::Joint::max_velocity`]) or the conservative
    /// default, and the default acceleration.
    pub fn of(robot: &Robot) -> Self {
        let (velocity, acceleration) = robot
            .joints
            .iter()
            .filter(|j| j.is_actuated())
            .map(|j| {
                let prismatic = j.kind == JointKind::Prismatic;
                let v = j.max_velocity.unwrap_or(if prismatic {
                    DEFAULT_VELOCITY_M_S
                } else {
                    DEFAULT_VELOCITY_RAD_S
                });
                let a = if prismatic {
                    DEFAULT_ACCELERATION_M_S2
                } else {
                    DEFAULT_ACCELERATION_RAD_S2
                };
                (v, a)
            })
            .unzip();
        Self {
            velocity,
            acceleration,
        }
    }

    /// An error unless there is one finite positive velocity and
    /// acceleration of at most [`MAX_LIMIT`] per joint of a `dof`-joint arm:
    /// the message says which joint and what was expected.
    pub fn check(&self, dof: usize) -> Result<(), String> {
        let bad = |message: String| message;
        for (name, values) in [
            ("velocity", &self.velocity),
            ("acceleration", &self.acceleration),
        ] {
            if values.len() != dof {
                return Err(bad(format!(
                    "{} {name} limits for {dof} joints: expected one per joint",
                    values.len()
                )));
            }
            if let Some((i, v)) = values
                .iter()
                .enumerate()
                .find(|(_, v)| !(v.is_finite() && **v > 0.0 && **v <= MAX_LIMIT))
            {
                return Err(bad(format!(
                    "joint {} {name} limit {v}: expected more than 0 and at most {MAX_LIMIT}",
                    i + 1
                )));
            }
        }
        Ok(())
    }

    /// The profile of the straight-line motion `from` → `to` (see the
    /// module docs); joints past the shorter slice do not move.
    pub fn profile(&self, from: &[Real], to: &[Real]) -> Profile {
        let (mut speed, mut accel) = (Real::INFINITY, Real::INFINITY);
        for (i, (a, b)) in from.iter().zip(to).enumerate() {
            let d = (b - a).abs();
            if d > 0.0 {
                let v = self
                    .velocity
                    .get(i)
                    .copied()
                    .unwrap_or(DEFAULT_VELOCITY_RAD_S);
                let acc = self
                    .acceleration
                    .get(i)
                    .copied()
                    .unwrap_or(DEFAULT_ACCELERATION_RAD_S2);
                speed = speed.min(v / d);
                accel = accel.min(acc / d);
            }
        }
        if !(speed.is_finite() && accel.is_finite() && speed > 0.0 && accel > 0.0) {
            return Profile::STILL;
        }
        // Cruising needs 1/2·ṡ²/s̈ to speed up and as much to slow down.
        if speed * speed / accel < 1.0 {
            Profile::new(accel, speed / accel, 1.0 / speed, 1.0)
        } else {
            // A triangle: the peak speed is √s̈.
            let t = 1.0 / accel.sqrt();
            Profile::new(accel, t, t, 1.0)
        }
    }

    /// These limits with every joint's speed at most `speed` (rad/s, m/s
    /// prismatic): a motion that must go slower than the arm can, such as
    /// a sweep that scans at a given spacing.
    #[must_use]
    pub fn capped(&self, speed: Real) -> Self {
        Self {
            velocity: self.velocity.iter().map(|v| v.min(speed)).collect(),
            acceleration: self.acceleration.clone(),
        }
    }

    /// Seconds the motion `from` → `to` takes.
    pub fn duration_s(&self, from: &[Real], to: &[Real]) -> Real {
        self.profile(from, to).duration_s
    }
}

/// Seconds of robot time per activity of the robot clock (`hw::clock`):
/// `run.json`'s `robot_time_s` and each viewpoint's share of it.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct RobotTime {
    /// Moving with the scanner scanning.
    pub moving_while_scanning_s: Real,
    /// Moving without scanning.
    pub moving_s: Real,
    /// Sweeping the scanner at a viewpoint.
    pub standing_to_sweep_s: Real,
    /// Standing still while the loop integrates and decides.
    pub deciding_s: Real,
}

impl RobotTime {
    /// All of it.
    pub fn total_s(&self) -> Real {
        self.moving_while_scanning_s + self.moving_s + self.standing_to_sweep_s + self.deciding_s
    }

    /// `other` added, activity by activity.
    pub fn add(&mut self, other: &Self) {
        self.moving_while_scanning_s += other.moving_while_scanning_s;
        self.moving_s += other.moving_s;
        self.standing_to_sweep_s += other.standing_to_sweep_s;
        self.deciding_s += other.deciding_s;
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    /// Hand-computed: 2 rad at 1 rad/s and 2 rad/s² cruises 1.5 s after
    /// 0.5 s speeding up (0.25 rad) and 0.5 s slowing down: 2.5 s. A
    /// second joint moving 1 rad keeps pace at half speed.
    #[test]
    fn a_trapezoid_by_hand() {
        let limits = MotionLimits::uniform(2, 1.0, 2.0);
        let p = limits.profile(&[0.0, 0.0], &[2.0, -1.0]);
        assert!((p.duration_s - 2.5).abs() < 1e-12);
        assert!((p.fraction(0.5) - 0.25 / 2.0).abs() < 1e-12);
        assert!((p.fraction(1.25) - 0.5).abs() < 1e-12);
        assert!((p.fraction(2.0) - 1.75 / 2.0).abs() < 1e-12);
        assert_eq!((p.fraction(-1.0), p.fraction(3.0)), (0.0, 1.0));
    }

    /// The slowest joint sets the pace: a joint of 0.5 rad/s moving 1 rad
    /// takes as long as a lone 2 rad motion at 1 rad/s would; a joint with
    /// a low acceleration makes a short motion a triangle of its own.
    #[test]
    fn the_tightest_joint_sets_the_profile() {
        let limits = MotionLimits {
            velocity: vec![1.0, 0.5],
            acceleration: vec![4.0, 1.0],
        };
        // Joint 2: 1 rad at 0.5 rad/s, 1 rad/s² → 2 s cruise + 0.5 s.
        let p = limits.profile(&[0.0, 0.0], &[0.1, 1.0]);
        assert!((p.duration_s - 2.5).abs() < 1e-12, "{p:?}");
        // 0.04 rad at 1 rad/s² is a triangle: 2·√0.04 = 0.4 s.
        let p = limits.profile(&[0.0, 0.0], &[0.0, 0.04]);
        assert!((p.duration_s - 0.4).abs() < 1e-12, "{p:?}");
        assert!((p.fraction(0.2) - 0.5).abs() < 1e-12);
        // Standing still takes no time.
        assert_eq!(limits.duration_s(&[0.3, 0.2], &[0.3, 0.2]), 0.0);
    }

    /// Braked at any moment, a motion is the same until then, keeps its
    /// speed continuous and within its limits after, and rests where its
    /// fraction ends; braking while slowing down changes nothing.
    #[test]
    fn a_braked_motion_keeps_its_past_and_its_limits() {
        let limits = MotionLimits::uniform(2, 1.0, 2.0);
        for (to, brakes) in [
            ([2.0, 1.0], [0.1, 0.5, 0.9, 1.7, 2.2, 2.4]),
            ([0.1, 0.0], [0.05, 0.2, 0.22, 0.3, 0.4, 0.5]),
        ] {
            let p = limits.profile(&[0.0, 0.0], &to);
            let peak = (0..=1000)
                .map(|k| p.speed(k as Real * p.duration_s / 1000.0))
                .fold(0.0, Real::max);
            for tb in brakes {
                let b = p.braked(tb);
                if tb >= p.t_down {
                    assert_eq!(b, p);
                    continue;
                }
                assert!(b.duration_s <= p.duration_s + 1e-12);
                assert!((b.fraction(b.duration_s) - b.end()).abs() < 1e-12);
                assert!(b.end() < 1.0);
                let dt = 1e-4;
                let mut t = 0.0;
                while t < b.duration_s {
                    if t <= tb {
                        assert!((b.fraction(t) - p.fraction(t)).abs() < 1e-12);
                    }
                    let v = b.speed(t);
                    assert!(v <= peak + 1e-12);
                    let a = (b.speed(t + dt) - v).abs() / dt;
                    assert!(a <= p.accel * (1.0 + 1e-6), "{a} at {t}");
                    t += dt;
                }
            }
        }
    }

    /// Sampled along the profile, no joint ever exceeds its speed or
    /// acceleration, and the motion is continuous from 0 to 1.
    #[test]
    fn sampled_motion_keeps_every_limit() {
        let limits = MotionLimits {
            velocity: vec![1.0, 3.0, 0.7],
            acceleration: vec![2.0, 5.0, 1.0],
        };
        for (from, to) in [
            ([0.0, 0.0, 0.0], [1.0, -2.5, 0.3]),
            ([0.1, 0.2, 0.3], [0.12, 0.2, 0.31]),
            ([0.0, 0.0, 0.0], [-3.0, 0.0, 0.0]),
        ] {
            let p = limits.profile(&from, &to);
            let dt = p.duration_s / 2000.0;
            let mut prev_v = 0.0;
            for k in 1..=2000 {
                let t = k as Real * dt;
                let ds = (p.fraction(t) - p.fraction(t - dt)) / dt;
                for j in 0..3 {
                    let d = (to[j] - from[j]) as Real;
                    let v = (d * ds).abs();
                    assert!(
                        v <= limits.velocity[j] * (1.0 + 1e-6),
                        "joint {j} at {t}: {v}"
                    );
                }
                let acc = (ds - prev_v) / dt;
                for j in 0..3 {
                    let d = (to[j] - from[j]) as Real;
                    assert!(
                        (d * acc).abs() <= limits.acceleration[j] * 1.01 + 1e-9,
                        "joint {j} at {t}"
                    );
                }
                prev_v = ds;
            }
            assert!((p.fraction(p.duration_s) - 1.0).abs() < 1e-12);
        }
    }

    #[test]
    fn limits_of_a_robot_and_their_check() {
        let denso = crate::builtin("denso-vm6083").unwrap();
        let l = MotionLimits::of(&denso);
        assert_eq!(l.velocity, vec![DEFAULT_VELOCITY_RAD_S; 6]);
        assert!(l.check(6).is_ok());
        assert!(l.check(5).is_err());
        let point = crate::builtin("point3").unwrap();
        assert_eq!(
            MotionLimits::of(&point).velocity,
            vec![DEFAULT_VELOCITY_M_S; 3]
        );
        let mut bad = l.clone();
        bad.acceleration[2] = Real::NAN;
        let e = bad.check(6).unwrap_err();
        assert!(e.contains("joint 3 acceleration"), "{e}");
    }
}
