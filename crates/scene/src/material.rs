//! Surface materials and their optical parameters.
//!
//! The five defaults are the material types of Paul's bridge experiments (A§6,
//! App. B): the laser classifier tells them apart by how their return intensity
//! and range error vary with the angle of incidence, which the sensor model drives
//! (after Hancock's diffuse + specular model, A App. B) from each material's
//! `reflectance` `C_r` (the share of the return in the specular lobe around normal
//! incidence) and `roughness` `ψ` (the width of that lobe: 0 mirror-like, 1 broad).

use geom::Real;
use serde::{Deserialize, Serialize};

/// Index of a material in a scene's material table.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
pub struct MaterialId(pub u16);

/// A named material with the parameters the sensor model uses.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Material {
    /// Name used in scenario files (`painted_metal`, ...).
    pub name: String,
    /// Reflectance `C_r` in `[0, 1]`: weight of the specular lobe.
    pub reflectance: Real,
    /// Roughness `ψ` in `[0, 1]`: small values give a narrow specular lobe.
    pub roughness: Real,
}

impl Material {
    /// A material.
    pub fn new(name: &str, reflectance: Real, roughness: Real) -> Self {
        Self {
            name: name.to_owned(),
            reflectance,
            roughness,
        }
    }
}

/// The default material table (SPEC §3.1), in this order:
/// `painted_metal`, `timber`, `concrete`, `plastic`, `stainless_steel`.
pub fn default_materials() -> Vec<Material> {
    vec![
        Material::new("painted_metal", 0.50, 0.35),
        Material::new("timber", 0.30, 0.70),
        Material::new("concrete", 0.15, 0.95),
        Material::new("plastic", 0.60, 0.20),
        Material::new("stainless_steel", 0.90, 0.05),
    ]
}

/// Check a material table: non-empty, unique names, parameters in `[0, 1]`.
pub fn validate_materials(materials: &[Material]) -> Result<(), crate::SceneError> {
    if materials.is_empty() {
        return Err(crate::SceneError::invalid(
            "materials",
            "the material table is empty",
        ));
    }
    if materials.len() > usize::from(u16::MAX) {
        return Err(crate::SceneError::invalid(
            "materials",
            "too many materials",
        ));
    }
    for (i, m) in materials.iter().enumerate() {
        if materials[..i].iter().any(|o| o.name == m.name) {
            return Err(crate::SceneError::invalid(
                format!("materials[{i}]"),
                format!("material name `{}` is used twice", m.name),
            ));
        }
        for (field, v) in [("reflectance", m.reflectance), ("roughness", m.roughness)] {
            if !(0.0..=1.0).contains(&v) {
                return Err(crate::SceneError::invalid(
                    format!("materials[{i}].{field}"),
                    format!("expected a value in [0, 1], got {v}"),
                ));
            }
        }
    }
    Ok(())
}
