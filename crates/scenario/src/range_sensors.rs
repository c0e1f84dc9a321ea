//! Single-point range finders declared in a scenario (`[range_sensors]`), for
//! any robot: individual sensors and *rings* that expand into evenly spaced
//! mounts, plus the range noise σ of every reading.
//!
//! ```toml
//! [range_sensors]
//! noise_sigma_m = 0.002
//!
//! [[range_sensors.sensors]]          # one sensor along the tool axis
//! link = "tool0"
//! origin = [0.0, 0.0, 0.0]
//! axis = [0.0, 0.0, 1.0]
//! max_range_m = 0.2
//!
//! [[range_sensors.rings]]            # eight sensors at 45° to the tool axis
//! link = "tool0"
//! centre = [0.0, 0.0, 0.0]
//! axis = [0.0, 0.0, 1.0]
//! radius_m = 0.0
//! count = 8
//! tilt_deg = 45.0
//! max_range_m = 0.2
//! ```
//!
//! A ring's mounts lie on the circle of radius `radius_m` about `centre` in the
//! plane perpendicular to the ring `axis` (all in the link frame). Mount `k` of
//! `count` sits at azimuth `φ_k = phase_deg + 360°·k/count`, measured from the
//! reference direction `e₁` (the link's x axis projected onto that plane, or its
//! y axis when the ring axis is within 1° of x) towards `e₂ = â × e₁`: its
//! radial direction is `u_k = cos φ_k e₁ + sin φ_k e₂`, its origin
//! `centre + radius_m·u_k` and its sensing axis `cos θ â + sin θ u_k` with
//! `θ = tilt_deg` (0°: along the ring axis, 90°: radial). This reproduces the
//! `arm4` control-point rings (P Fig. 40b) for `â = z`.

use geom::{Point3, Real, UnitVector3, Vector3, unit};
use robot::{LinkId, RangeFinderMount, Robot};
use serde::{Deserialize, Serialize};

/// Most mounts one ring may expand to (refused before anything is allocated).
pub const MAX_RING_COUNT: u32 = 10_000;

/// Largest range-noise σ, metres: noise of a metre makes every reading noise.
pub const MAX_NOISE_SIGMA_M: Real = 1.0;

/// Longest range of a range finder, metres.
pub const MAX_RANGE_M: Real = 1000.0;

/// The `[range_sensors]` table of a scenario.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct RangeSensorsSpec {
    /// Standard deviation of the additive Gaussian range noise of every reading,
    /// metres (0: exact readings). Drawn from the run's seeded RNG.
    pub noise_sigma_m: Real,
    /// Individual sensors, appended after the robot's own (built-in) sensors.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub sensors: Vec<RangeSensorSpec>,
    /// Rings of sensors, appended after `sensors`.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub rings: Vec<SensorRingSpec>,
}

/// One range finder on a named link.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RangeSensorSpec {
    /// Name of the link carrying the sensor (URDF link name, or a built-in's).
    pub link: String,
    /// Sensor origin in the link frame, metres.
    #[serde(deserialize_with = "geom::exact::array")]
    pub origin: [Real; 3],
    /// Sensing direction in the link frame (normalised on expansion).
    #[serde(deserialize_with = "geom::exact::array")]
    pub axis: [Real; 3],
    /// Sensing range, metres.
    pub max_range_m: Real,
}

/// A ring of evenly spaced range finders on a named link (see the
/// [module documentation](self) for the geometry).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SensorRingSpec {
    /// Name of the link carrying the ring.
    pub link: String,
    /// Centre of the ring in the link frame, metres.
    #[serde(deserialize_with = "geom::exact::array")]
    pub centre: [Real; 3],
    /// Axis of the ring in the link frame (normalised on expansion).
    #[serde(deserialize_with = "geom::exact::array")]
    pub axis: [Real; 3],
    /// Radius of the ring, metres (0: every sensor at the centre).
    #[serde(default)]
    pub radius_m: Real,
    /// Number of sensors, 1 to [`MAX_RING_COUNT`].
    pub count: u32,
    /// Angle between each sensing axis and the ring axis, degrees in
    /// `[0, 180]`: 0 along the axis, 90 radial, 45 half-way.
    pub tilt_deg: Real,
    /// Azimuth of the first sensor from the reference direction, degrees.
    #[serde(default)]
    pub phase_deg: Real,
    /// Sensing range, metres.
    pub max_range_m: Real,
}

fn finite3(v: &[Real; 3]) -> bool {
    v.iter()
        .all(|c| c.is_finite() && c.abs() <= scene::MAX_COORDINATE_M)
}

fn check_range(what: &str, r: Real) -> Result<(), String> {
    if r.is_finite() && r > 0.0 && r <= MAX_RANGE_M {
        Ok(())
    } else {
        Err(format!(
            "{what}.max_range_m: expected a distance in (0, 1000] metres, got {r}"
        ))
    }
}

fn link_of(robot: &Robot, what: &str, name: &str) -> Result<LinkId, String> {
    robot.link_index(name).ok_or_else(|| {
        let known: Vec<&str> = robot.links.iter().map(|l| l.name.as_str()).collect();
        format!(
            "{what}.link: unknown link `{name}` (robot `{}` has links: {})",
            robot.name,
            known.join(", ")
        )
    })
}

fn direction(what: &str, v: &[Real; 3]) -> Result<UnitVector3, String> {
    if !finite3(v) {
        return Err(format!("{what}: expected finite components, got {v:?}"));
    }
    unit(Vector3::new(v[0], v[1], v[2]))
        .ok_or_else(|| format!("{what}: expected a non-zero direction, got {v:?}"))
}

impl RangeSensorsSpec {
    /// `true` when the table adds nothing (no sensors, no noise): it is then
    /// left out of a printed scenario.
    pub fn is_empty(&self) -> bool {
        self.noise_sigma_m == 0.0 && self.sensors.is_empty() && self.rings.is_empty()
    }

    /// Check the numbers that need no robot: `noise_sigma_m` finite and ≥ 0;
    /// every origin, centre and axis finite, axes non-zero; ranges finite > 0;
    /// ring radius finite ≥ 0, count in `1..=`[`MAX_RING_COUNT`], tilt in
    /// `[0, 180]`°, phase finite. Errors name the field by its TOML path
    /// (`range_sensors.rings[1].count: ...`).
    pub fn validate(&self) -> Result<(), String> {
        if !(self.noise_sigma_m.is_finite()
            && (0.0..=MAX_NOISE_SIGMA_M).contains(&self.noise_sigma_m))
        {
            return Err(format!(
                "range_sensors.noise_sigma_m: expected a standard deviation from 0 to 1 metre, got {}",
                self.noise_sigma_m
            ));
        }
        for (i, s) in self.sensors.iter().enumerate() {
            let what = format!("range_sensors.sensors[{i}]");
            if !finite3(&s.origin) {
                return Err(format!(
                    "{what}.origin: expected finite coordinates within ±{:e} m, got {:?}",
                    scene::MAX_COORDINATE_M,
                    s.origin
                ));
            }
            direction(&format!("{what}.axis"), &s.axis)?;
            check_range(&what, s.max_range_m)?;
        }
        for (i, r) in self.rings.iter().enumerate() {
            let what = format!("range_sensors.rings[{i}]");
            if !finite3(&r.centre) {
                return Err(format!(
                    "{what}.centre: expected finite coordinates within ±{:e} m, got {:?}",
                    scene::MAX_COORDINATE_M,
                    r.centre
                ));
            }
            direction(&format!("{what}.axis"), &r.axis)?;
            if !(r.radius_m.is_finite()
                && r.radius_m >= 0.0
                && r.radius_m <= scene::MAX_COORDINATE_M)
            {
                return Err(format!(
                    "{what}.radius_m: expected a finite radius ≥ 0 (metres), got {}",
                    r.radius_m
                ));
            }
            if r.count == 0 || r.count > MAX_RING_COUNT {
                return Err(format!(
                    "{what}.count: expected 1 to {MAX_RING_COUNT} sensors, got {}",
                    r.count
                ));
            }
            if !(r.tilt_deg.is_finite() && (0.0..=180.0).contains(&r.tilt_deg)) {
                return Err(format!(
                    "{what}.tilt_deg: expected an angle in [0, 180] degrees, got {}",
                    r.tilt_deg
                ));
            }
            if !r.phase_deg.is_finite() {
                return Err(format!(
                    "{what}.phase_deg: expected a finite angle in degrees, got {}",
                    r.phase_deg
                ));
            }
            check_range(&what, r.max_range_m)?;
        }
        Ok(())
    }

    /// The declared sensors as mounts on `robot`, sensors first then rings, each
    /// ring in azimuth order. Errors (as from [`validate`](Self::validate), or
    /// an unknown link, naming the robot's links) name the field.
    pub fn mounts(&self, robot: &Robot) -> Result<Vec<RangeFinderMount>, String> {
        self.validate()?;
        let mut out = Vec::new();
        for (i, s) in self.sensors.iter().enumerate() {
            let what = format!("range_sensors.sensors[{i}]");
            out.push(RangeFinderMount {
                link: link_of(robot, &what, &s.link)?,
                origin: Point3::from(s.origin),
                axis: direction(&format!("{what}.axis"), &s.axis)?,
                max_range_m: s.max_range_m,
            });
        }
        for (i, r) in self.rings.iter().enumerate() {
            let what = format!("range_sensors.rings[{i}]");
            let link = link_of(robot, &what, &r.link)?;
            out.extend(r.expand(link, &what)?);
        }
        Ok(out)
    }

    /// Append the declared sensors to `robot.range_finders`. On error the robot
    /// is left unchanged.
    pub fn apply(&self, robot: &mut Robot) -> Result<(), String> {
        let mounts = self.mounts(robot)?;
        robot.range_finders.extend(mounts);
        Ok(())
    }
}

impl SensorRingSpec {
    /// The reference direction `e₁` and `e₂ = â × e₁` of a ring about `axis`:
    /// the in-plane axes of [`geom::PlaneFrame::with_u_axis`] with the link's
    /// x axis (its y axis within 1° of x) as the first.
    pub fn basis(axis: &UnitVector3) -> (UnitVector3, UnitVector3) {
        let reference = if axis.x.abs() < 1f64.to_radians().cos() {
            Vector3::x()
        } else {
            Vector3::y()
        };
        let f = geom::PlaneFrame::with_u_axis(Point3::origin(), *axis, &reference);
        (f.u, f.v)
    }

    /// The ring's mounts on link index `link`; `what` names the ring in errors.
    fn expand(&self, link: LinkId, what: &str) -> Result<Vec<RangeFinderMount>, String> {
        let axis = direction(&format!("{what}.axis"), &self.axis)?;
        let (e1, e2) = Self::basis(&axis);
        let (st, ct) = self.tilt_deg.to_radians().sin_cos();
        let centre = Point3::from(self.centre);
        (0..self.count)
            .map(|k| {
                let phi =
                    (self.phase_deg + 360.0 * Real::from(k) / Real::from(self.count)).to_radians();
                let (s, c) = phi.sin_cos();
                let radial = e1.into_inner() * c + e2.into_inner() * s;
                let dir = unit(axis.into_inner() * ct + radial * st)
                    .ok_or_else(|| format!("{what}: sensor {k} has no direction"))?;
                Ok(RangeFinderMount {
                    link,
                    origin: centre + radial * self.radius_m,
                    axis: dir,
                    max_range_m: self.max_range_m,
                })
            })
            .collect()
    }
}
