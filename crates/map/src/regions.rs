//! Regions of interest A1 ⊂ A2 ⊂ A3 (A§4.2.1, Fig. 4.4).
//!
//! The regions are centred on the manipulator's first joint and cover its
//! workspace (A1), its reach plus the tool range (A2), and the surroundings a
//! tool could damage (A3). Here they are axis-aligned boxes; the occupancy
//! grid covers A3. The serde layout (`a1 = { min = [..], max = [..] }`)
//! matches the scenario files of `sim`.

use crate::MapError;
use geom::{Aabb, Point3, Real};
use serde::{Deserialize, Serialize};

/// One of the three nested regions, named by the innermost one that holds a
/// voxel.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
pub enum Region {
    /// The manipulator's workspace.
    A1,
    /// Reachable by the tool, outside A1.
    A2,
    /// Could be affected by the work, outside A2.
    A3,
}

impl Region {
    /// The three regions, innermost first.
    pub const ALL: [Self; 3] = [Self::A1, Self::A2, Self::A3];

    /// 0, 1 or 2.
    #[inline]
    pub const fn index(self) -> usize {
        match self {
            Self::A1 => 0,
            Self::A2 => 1,
            Self::A3 => 2,
        }
    }

    /// `"A1"`, `"A2"` or `"A3"`.
    pub const fn name(self) -> &'static str {
        match self {
            Self::A1 => "A1",
            Self::A2 => "A2",
            Self::A3 => "A3",
        }
    }
}

/// An axis-aligned box, world frame, metres.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RegionBox {
    /// Lowest corner.
    #[serde(deserialize_with = "geom::exact::array")]
    pub min: [Real; 3],
    /// Highest corner.
    #[serde(deserialize_with = "geom::exact::array")]
    pub max: [Real; 3],
}

impl std::fmt::Display for RegionBox {
    /// `min [x, y, z], max [x, y, z]` (metres).
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let [a, b, c] = self.min;
        let [x, y, z] = self.max;
        write!(f, "min [{a}, {b}, {c}], max [{x}, {y}, {z}]")
    }
}

impl RegionBox {
    /// A cube of half-size `half_m` around `centre`.
    pub fn around(centre: [Real; 3], half_m: Real) -> Self {
        Self {
            min: centre.map(|c| c - half_m),
            max: centre.map(|c| c + half_m),
        }
    }

    /// As a box.
    pub fn aabb(&self) -> Aabb {
        Aabb::new(Point3::from(self.min), Point3::from(self.max))
    }

    /// `true` when `p` lies inside or on the boundary.
    pub fn contains(&self, p: &Point3) -> bool {
        (0..3).all(|ax| p[ax] >= self.min[ax] && p[ax] <= self.max[ax])
    }

    fn is_valid(&self) -> bool {
        (0..3).all(|ax| {
            self.min[ax].is_finite() && self.max[ax].is_finite() && self.min[ax] < self.max[ax]
        })
    }

    fn contains_box(&self, inner: &Self) -> bool {
        (0..3).all(|ax| self.min[ax] <= inner.min[ax] && inner.max[ax] <= self.max[ax])
    }
}

/// The regions of interest: three nested boxes.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RegionsConfig {
    /// A1: the manipulator's workspace.
    pub a1: RegionBox,
    /// A2: reachable by the tool.
    pub a2: RegionBox,
    /// A3: could be affected by the work; the occupancy grid covers it.
    pub a3: RegionBox,
}

impl Default for RegionsConfig {
    /// The bridge scenarios' regions (SPEC §4): cubes of half-size 1.1, 1.6 and
    /// 2.1 m around the first joint at (0, 0, 0.475).
    fn default() -> Self {
        Self::around([0.0, 0.0, 0.475], [1.1, 1.6, 2.1])
    }
}

impl RegionsConfig {
    /// Cubes of half-sizes `half_m[k]` around `centre` (the first joint).
    pub fn around(centre: [Real; 3], half_m: [Real; 3]) -> Self {
        Self {
            a1: RegionBox::around(centre, half_m[0]),
            a2: RegionBox::around(centre, half_m[1]),
            a3: RegionBox::around(centre, half_m[2]),
        }
    }

    /// The box of a region.
    pub fn get(&self, region: Region) -> &RegionBox {
        match region {
            Region::A1 => &self.a1,
            Region::A2 => &self.a2,
            Region::A3 => &self.a3,
        }
    }

    /// Check that the boxes are proper and nested: A1 ⊆ A2 ⊆ A3.
    pub fn validate(&self) -> Result<(), MapError> {
        for (field, b) in [
            ("regions.a1", &self.a1),
            ("regions.a2", &self.a2),
            ("regions.a3", &self.a3),
        ] {
            if !b.is_valid() {
                return Err(MapError::config(
                    field,
                    "a box with finite corners and min < max on every axis",
                    b.to_string(),
                ));
            }
        }
        if !self.a2.contains_box(&self.a1) {
            return Err(MapError::config(
                "regions.a1",
                "a box inside regions.a2",
                self.a1.to_string(),
            ));
        }
        if !self.a3.contains_box(&self.a2) {
            return Err(MapError::config(
                "regions.a2",
                "a box inside regions.a3",
                self.a2.to_string(),
            ));
        }
        Ok(())
    }
}
