//! `surveyor.Scene`: a triangle scene and bulk ray casting on NumPy arrays.

use crate::arrays::rows3;
use crate::errors::{scene_error, value_error};
use crate::rays::{cast, range_bound};
use numpy::ndarray::Array2;
use numpy::{PyArray1, PyArray2};
use pyo3::prelude::*;
use scene::{MaterialId, Scene, World, default_materials};
use std::path::{Path, PathBuf};

/// A scene of triangles to cast rays against: a mesh file
/// (``Scene.from_file``) or a built-in scene (``Scene.builtin``).
///
/// Face ids index ``triangles``: the scene's triangles in the order they
/// were loaded (a file's faces in file order, polygons split into
/// triangles; a built-in's objects one after another).
#[pyclass(name = "Scene", module = "surveyor", frozen)]
pub struct PyScene {
    scene: Scene,
    name: String,
}

impl PyScene {
    /// The scene itself.
    pub fn scene(&self) -> &Scene {
        &self.scene
    }
}

#[pymethods]
impl PyScene {
    /// Load a triangle mesh (``.obj``, ``.stl`` or ``.ply``) as one object,
    /// every coordinate multiplied by ``scale`` (1.0 for a file in metres).
    ///
    /// The scene ``surveyor raycast --scene PATH`` casts against. Raises
    /// ``OSError`` when the file cannot be read, ``ValueError`` when it is
    /// not a usable mesh or ``scale`` is not finite and positive.
    #[staticmethod]
    #[pyo3(signature = (path, scale = 1.0))]
    #[expect(
        clippy::needless_pass_by_value,
        reason = "PyO3 extracts owned arguments"
    )]
    fn from_file(py: Python<'_>, path: PathBuf, scale: f64) -> PyResult<Self> {
        // Reading, parsing and the BVH build take seconds for big meshes.
        let scene = py
            .detach(|| {
                let mesh = scene::io::load_mesh(&path, scale)?;
                Scene::from_mesh("scene", mesh, default_materials(), MaterialId(0))
            })
            .map_err(|e| scene_error(&e))?;
        Ok(Self {
            scene,
            name: path.display().to_string(),
        })
    }

    /// A built-in scene by name: ``"bridge1"``, ``"bridge2"``, ``"bridge3"``
    /// (Paul's steel-bridge channel), ``"cube"``, ``"block1"``,
    /// ``"block2"`` or ``"cylinder"``. Raises ``ValueError`` for another
    /// name, listing the valid ones.
    #[staticmethod]
    fn builtin(name: &str) -> PyResult<Self> {
        let spec = scene::builtin::scene(name).ok_or_else(|| {
            value_error(format!(
                "unknown built-in scene '{name}': valid names are {}",
                scene::builtin::NAMES.join(", ")
            ))
        })?;
        match spec.build(Path::new(".")).map_err(|e| scene_error(&e))? {
            World::Mesh(scene) => Ok(Self {
                scene,
                name: name.to_owned(),
            }),
            World::Cloud(_) => Err(value_error(format!(
                "built-in scene '{name}' is a point cloud, not triangles"
            ))),
        }
    }

    /// Cast rays and return the first hit of each: ``(distances,
    /// face_ids)``.
    ///
    /// ``origins`` and ``directions`` are float64 arrays of shape (n, 3), one
    /// row per ray; every direction must be a unit vector (``|‖d‖² − 1| ≤
    /// 1e-3``, the rule of ``surveyor raycast``'s rays files). Rays are cast
    /// in single precision, as ``surveyor raycast`` casts them, so the
    /// distances are its distances bit for bit (as float64). A hit is at a
    /// distance in ``[0, max_range]``; a miss has distance ``inf`` and face
    /// id -1. ``distances`` is float64 of shape (n,), ``face_ids`` int64 of
    /// shape (n,), indexing ``triangles``.
    ///
    /// Runs on all cores with the GIL released. A C-contiguous array is read
    /// in place while the rays are cast, so do not write to ``origins`` or
    /// ``directions`` from another thread during the call; other layouts are
    /// copied once. Raises ``ValueError`` for a
    /// wrong dtype or shape, a NaN or infinite value, a zero-length or
    /// non-unit direction, or a negative or NaN ``max_range``.
    #[pyo3(signature = (origins, directions, max_range = f64::INFINITY))]
    #[expect(
        clippy::type_complexity,
        reason = "the (distances, face_ids) pair Python receives"
    )]
    fn raycast<'py>(
        &self,
        py: Python<'py>,
        origins: &Bound<'py, PyAny>,
        directions: &Bound<'py, PyAny>,
        max_range: f64,
    ) -> PyResult<(Bound<'py, PyArray1<f64>>, Bound<'py, PyArray1<i64>>)> {
        let t_max = range_bound(max_range).map_err(value_error)?;
        let o = rows3("origins", origins)?;
        let d = rows3("directions", directions)?;
        let (o, d) = (o.flat(), d.flat());
        // The rows are read in place with the GIL released (see above).
        let (distances, faces) = py
            .detach(|| cast(&self.scene, o, d, t_max))
            .map_err(value_error)?;
        Ok((
            PyArray1::from_vec(py, distances),
            PyArray1::from_vec(py, faces),
        ))
    }

    /// The vertices of the scene's triangles: a float64 array of shape
    /// (number of vertices, 3), metres.
    #[getter]
    fn vertices<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        let v = &self.scene.mesh().vertices;
        PyArray2::from_owned_array(py, Array2::from_shape_fn((v.len(), 3), |(k, c)| v[k][c]))
    }

    /// The scene's triangles as rows of three indices into ``vertices``: an
    /// int64 array of shape (``face_count``, 3); row ``i`` is face id ``i``.
    #[getter]
    fn triangles<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<i64>> {
        let t = &self.scene.mesh().triangles;
        PyArray2::from_owned_array(
            py,
            Array2::from_shape_fn((t.len(), 3), |(k, c)| i64::from(t[k][c])),
        )
    }

    /// Number of triangles (face ids run from 0 to ``face_count - 1``).
    #[getter]
    fn face_count(&self) -> usize {
        self.scene.mesh().len()
    }

    /// The built-in's name, or the file the scene was loaded from.
    #[getter]
    fn name(&self) -> &str {
        &self.name
    }

    fn __repr__(&self) -> String {
        format!(
            "Scene(name='{}', face_count={})",
            self.name,
            self.scene.mesh().len()
        )
    }
}
