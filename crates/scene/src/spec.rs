//! Scene descriptions as data: what a scenario file's `[scene]` holds.
//!
//! A [`SceneSpec`] lists materials and objects (primitive shapes or mesh files,
//! each with a material and an optional pose), or a point-cloud file. It
//! serialises to and from TOML, and [`SceneSpec::build`] turns it into a
//! queryable [`World`].

use crate::cloud_world::PointCloudWorld;
use crate::error::SceneError;
use crate::material::{Material, MaterialId, default_materials, validate_materials};
use crate::mesh::TriMesh;
use crate::primitives::{self, Axis, IBeamSection};
use crate::world::{Hit, RayCast, Scene};
use geom::{Isometry3, Point2, Point3, Ray, Real, Vector3};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// Most sides a cylinder's `segments` may ask for, and most vertices a prism
/// profile may have: the cap triangulation (ear clipping) costs O(n²), under a
/// second at this size even in a debug build, and 4 096 sides put the facets
/// within 3·10⁻⁷ × radius of the true cylinder. Larger values are refused before any mesh is allocated.
pub const MAX_PRIMITIVE_SEGMENTS: u32 = 4096;

pub use geom::MAX_COORDINATE_M;

/// The ground truth of a scenario: objects with materials, or a point cloud.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneSpec {
    /// Material table (defaults to the five of SPEC §3.1).
    #[serde(default = "default_materials")]
    pub materials: Vec<Material>,
    /// Objects made of surfaces.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub objects: Vec<ObjectSpec>,
    /// A point-cloud world instead of objects (real scans).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub point_cloud: Option<CloudSpec>,
}

/// One object: a shape, a material and a placement.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ObjectSpec {
    /// Unique name.
    pub name: String,
    /// Material name from the table.
    pub material: String,
    /// Placement applied to the shape (identity when absent).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pose: Option<PoseSpec>,
    /// The geometry.
    pub shape: ShapeSpec,
}

/// A rigid placement in user units: metres and degrees (roll, pitch, yaw about
/// fixed x, y, z — the URDF convention).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PoseSpec {
    /// Translation, metres.
    #[serde(default)]
    #[serde(deserialize_with = "geom::exact::array")]
    pub translation: [Real; 3],
    /// Roll, pitch, yaw in degrees.
    #[serde(default)]
    #[serde(deserialize_with = "geom::exact::array")]
    pub rpy_deg: [Real; 3],
}

impl PoseSpec {
    /// Check the numbers: every translation component finite and within
    /// ±[`MAX_COORDINATE_M`], every angle finite. `what` names the pose in the
    /// error (`object \`beam\` pose`), which then names the component.
    pub fn validate(&self, what: &str) -> Result<(), SceneError> {
        for (i, t) in self.translation.iter().enumerate() {
            if !(t.is_finite() && t.abs() <= MAX_COORDINATE_M) {
                return Err(SceneError::invalid(
                    format!("{what}: translation[{i}]"),
                    format!("expected a finite distance within ±{MAX_COORDINATE_M:e} m, got {t}"),
                ));
            }
        }
        for (i, a) in self.rpy_deg.iter().enumerate() {
            if !(a.is_finite() && a.abs() <= 360.0) {
                return Err(SceneError::invalid(
                    format!("{what}: rpy_deg[{i}]"),
                    format!("expected an angle within ±360 degrees, got {a}"),
                ));
            }
        }
        Ok(())
    }

    /// The placement as an isometry.
    pub fn isometry(&self) -> Isometry3 {
        geom::math::isometry_from_xyz_rpy(self.translation, self.rpy_deg.map(f64::to_radians))
    }
}

/// Geometry of an object.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum ShapeSpec {
    /// The axis-aligned box `[min, max]`.
    Box {
        /// Lowest corner.
        #[serde(deserialize_with = "geom::exact::array")]
        min: [Real; 3],
        /// Highest corner.
        #[serde(deserialize_with = "geom::exact::array")]
        max: [Real; 3],
    },
    /// An I-beam; `from`/`to` are the middle of the bottom flange's outer face at
    /// the two ends, `up` points toward the top flange.
    IBeam {
        /// Start of the beam.
        #[serde(deserialize_with = "geom::exact::array")]
        from: [Real; 3],
        /// End of the beam.
        #[serde(deserialize_with = "geom::exact::array")]
        to: [Real; 3],
        /// Direction from bottom to top flange.
        #[serde(deserialize_with = "geom::exact::array")]
        up: [Real; 3],
        /// Overall depth.
        depth: Real,
        /// Flange width.
        flange_width: Real,
        /// Flange thickness.
        flange_thickness: Real,
        /// Web thickness.
        web_thickness: Real,
    },
    /// A closed cylinder.
    Cylinder {
        /// Centre of one end.
        #[serde(deserialize_with = "geom::exact::array")]
        from: [Real; 3],
        /// Centre of the other end.
        #[serde(deserialize_with = "geom::exact::array")]
        to: [Real; 3],
        /// Radius.
        radius: Real,
        /// Number of sides.
        #[serde(default = "default_segments")]
        segments: u32,
    },
    /// A simple polygon extruded along a world axis; the profile is in the other
    /// two coordinates in increasing order ((y, z) for x, (x, z) for y, (x, y) for z).
    Prism {
        /// Extrusion axis.
        axis: Axis,
        /// Profile vertices.
        #[serde(deserialize_with = "geom::exact::vec_of_arrays")]
        profile: Vec<[Real; 2]>,
        /// Extrusion start along the axis.
        from: Real,
        /// Extrusion end along the axis.
        to: Real,
    },
    /// A mesh file (OBJ, STL, PLY), path relative to the scenario file.
    Mesh {
        /// The file.
        file: PathBuf,
        /// Uniform scale applied to the file's coordinates (e.g. 0.001 for mm).
        #[serde(default = "one")]
        scale: Real,
    },
}

/// A point-cloud world (P§4.2).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CloudSpec {
    /// The cloud file (PLY, PCD, text), path relative to the scenario file.
    pub file: PathBuf,
    /// ε of the ray rule; derived from the cloud when absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub epsilon: Option<Real>,
    /// Material attributed to every point, when known.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub material: Option<String>,
    /// Placement applied to the points.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pose: Option<PoseSpec>,
}

fn default_segments() -> u32 {
    48
}

fn one() -> Real {
    1.0
}

/// A built world: surfaces or a point set.
#[derive(Clone, Debug)]
pub enum World {
    /// Triangle-mesh objects with materials.
    Mesh(Scene),
    /// A point cloud queried by the ε rule.
    Cloud(PointCloudWorld),
}

impl World {
    /// The mesh scene, when this world has surfaces.
    pub fn as_scene(&self) -> Option<&Scene> {
        match self {
            Self::Mesh(s) => Some(s),
            Self::Cloud(_) => None,
        }
    }
}

impl RayCast for World {
    fn material(&self, id: MaterialId) -> Option<&Material> {
        match self {
            Self::Mesh(s) => s.material(id),
            Self::Cloud(_) => None,
        }
    }

    fn cast_ray(&self, ray: &Ray, max_range_m: Real) -> Option<Hit> {
        match self {
            Self::Mesh(s) => s.cast_ray(ray, max_range_m),
            Self::Cloud(c) => c.cast_ray(ray, max_range_m),
        }
    }
}

fn p3(a: &[Real; 3]) -> Point3 {
    Point3::new(a[0], a[1], a[2])
}

impl ShapeSpec {
    /// The shape's mesh before placement. `base_dir` resolves relative files.
    pub fn mesh(&self, base_dir: &Path) -> Result<TriMesh, SceneError> {
        // Finite and within ±MAX_COORDINATE_M.
        let finite = |vals: &[Real]| {
            vals.iter()
                .all(|v| v.is_finite() && v.abs() <= MAX_COORDINATE_M)
        };
        match self {
            Self::Box { min, max } => {
                if !finite(min) || !finite(max) || (0..3).any(|i| min[i] >= max[i]) {
                    return Err(SceneError::invalid(
                        "box",
                        format!(
                            "expected finite min < max on every axis, within ±{MAX_COORDINATE_M:e} m, got {min:?} and {max:?}"
                        ),
                    ));
                }
                Ok(primitives::cuboid(p3(min), p3(max)))
            }
            Self::IBeam {
                from,
                to,
                up,
                depth,
                flange_width,
                flange_thickness,
                web_thickness,
            } => {
                if !finite(from) || !finite(to) || !finite(up) {
                    return Err(SceneError::invalid(
                        "i_beam",
                        format!("coordinates must be finite and within ±{MAX_COORDINATE_M:e} m"),
                    ));
                }
                Ok(primitives::i_beam(
                    &p3(from),
                    &p3(to),
                    &Vector3::new(up[0], up[1], up[2]),
                    &IBeamSection {
                        depth: *depth,
                        flange_width: *flange_width,
                        flange_thickness: *flange_thickness,
                        web_thickness: *web_thickness,
                    },
                )?)
            }
            Self::Cylinder {
                from,
                to,
                radius,
                segments,
            } => {
                if !finite(from) || !finite(to) || !finite(&[*radius]) {
                    return Err(SceneError::invalid(
                        "cylinder",
                        format!(
                            "coordinates and radius must be finite and within ±{MAX_COORDINATE_M:e} m"
                        ),
                    ));
                }
                if *segments > MAX_PRIMITIVE_SEGMENTS {
                    return Err(SceneError::invalid(
                        "cylinder segments",
                        format!(
                            "expected at most {MAX_PRIMITIVE_SEGMENTS} sides (MAX_PRIMITIVE_SEGMENTS: the caps' triangulation is quadratic in it), got {segments}"
                        ),
                    ));
                }
                Ok(primitives::cylinder(
                    &p3(from),
                    &p3(to),
                    *radius,
                    *segments,
                )?)
            }
            Self::Prism {
                axis,
                profile,
                from,
                to,
            } => {
                if profile.len() > MAX_PRIMITIVE_SEGMENTS as usize {
                    return Err(SceneError::invalid(
                        "prism profile",
                        format!(
                            "expected at most {MAX_PRIMITIVE_SEGMENTS} vertices (MAX_PRIMITIVE_SEGMENTS: the caps' triangulation is quadratic in it), got {}",
                            profile.len()
                        ),
                    ));
                }
                if profile.iter().any(|p| !finite(p)) || !finite(&[*from, *to]) {
                    return Err(SceneError::invalid(
                        "prism",
                        format!(
                            "profile and from/to must be finite and within ±{MAX_COORDINATE_M:e} m"
                        ),
                    ));
                }
                let prof: Vec<Point2> = profile.iter().map(|p| Point2::new(p[0], p[1])).collect();
                Ok(primitives::prism(*axis, &prof, *from, *to)?)
            }
            Self::Mesh { file, scale } => {
                if !(scale.is_finite() && *scale > 0.0) {
                    return Err(SceneError::invalid(
                        file.display().to_string(),
                        format!("scale must be positive, got {scale}"),
                    ));
                }
                crate::io::load_mesh(&base_dir.join(file), *scale)
            }
        }
    }
}

impl Default for SceneSpec {
    fn default() -> Self {
        Self {
            materials: default_materials(),
            objects: Vec::new(),
            point_cloud: None,
        }
    }
}

impl SceneSpec {
    /// Resolve a material name to its id.
    pub fn material_id(&self, name: &str) -> Result<MaterialId, SceneError> {
        self.materials
            .iter()
            .position(|m| m.name == name)
            .map(|i| MaterialId(i as u16))
            .ok_or_else(|| {
                let known: Vec<&str> = self.materials.iter().map(|m| m.name.as_str()).collect();
                SceneError::invalid(
                    format!("material `{name}`"),
                    format!("unknown material; known: {}", known.join(", ")),
                )
            })
    }

    /// The same scene with its relative file paths (meshes, point cloud)
    /// resolved against `base_dir`, so that it reads the same files from
    /// anywhere.
    #[must_use]
    pub fn rebased(&self, base_dir: &Path) -> Self {
        let mut out = self.clone();
        for o in &mut out.objects {
            if let ShapeSpec::Mesh { file, .. } = &mut o.shape {
                *file = absolute(base_dir, file);
            }
        }
        if let Some(c) = &mut out.point_cloud {
            c.file = absolute(base_dir, &c.file);
        }
        out
    }

    /// Build the world. Relative file paths are resolved against `base_dir`
    /// (the scenario file's folder).
    pub fn build(&self, base_dir: &Path) -> Result<World, SceneError> {
        validate_materials(&self.materials)?;
        match (&self.point_cloud, self.objects.is_empty()) {
            (Some(_), false) => Err(SceneError::invalid(
                "scene",
                "give either objects or a point_cloud, not both",
            )),
            (None, true) => Err(SceneError::invalid("scene", "has no objects")),
            (Some(c), true) => {
                if let Some(pose) = &c.pose {
                    pose.validate("point_cloud pose")?;
                }
                let mut cloud = crate::io::load_cloud(&base_dir.join(&c.file))?;
                if let Some(pose) = &c.pose {
                    let iso = pose.isometry();
                    for p in &mut cloud.points {
                        *p = iso * *p;
                    }
                    if let Some(ns) = &mut cloud.normals {
                        for n in ns.iter_mut() {
                            *n = iso.rotation * *n;
                        }
                    }
                }
                let material = c
                    .material
                    .as_deref()
                    .map(|m| self.material_id(m))
                    .transpose()?;
                Ok(World::Cloud(PointCloudWorld::new(
                    cloud, c.epsilon, material,
                )?))
            }
            (None, false) => {
                let mut objects = Vec::with_capacity(self.objects.len());
                for o in &self.objects {
                    if let Some(pose) = &o.pose {
                        pose.validate(&format!("object `{}` pose", o.name))?;
                    }
                    let material = self.material_id(&o.material).map_err(|e| {
                        SceneError::invalid(format!("object `{}`", o.name), e.to_string())
                    })?;
                    let mut mesh = o.shape.mesh(base_dir).map_err(|e| match e {
                        SceneError::Invalid { what, message } => {
                            SceneError::invalid(format!("object `{}` ({what})", o.name), message)
                        }
                        other => other,
                    })?;
                    if let Some(pose) = &o.pose {
                        mesh.transform(&pose.isometry());
                    }
                    objects.push((o.name.clone(), material, mesh));
                }
                Ok(World::Mesh(Scene::from_objects(
                    self.materials.clone(),
                    objects,
                )?))
            }
        }
    }
}

/// `file` joined to `base_dir`, made absolute when the working directory is
/// known (an absolute `file` is kept).
fn absolute(base_dir: &Path, file: &Path) -> PathBuf {
    let joined = base_dir.join(file);
    std::path::absolute(&joined).unwrap_or(joined)
}
