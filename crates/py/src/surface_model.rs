//! `surveyor.SurfaceModel`: Pudney's incremental surface model (the
//! `surface` crate) fed with NumPy sensor sets, the model of `surveyor model`.

use crate::arrays::{points_of, rows3};
use crate::config_dict::{config_from_dict, to_python};
use crate::errors::value_error;
use geom::{UnitVector3, Vector3};
use numpy::ndarray::Array2;
use numpy::{PyArray1, PyArray2};
use pyo3::exceptions::PyOSError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use std::path::{Path, PathBuf};
use surface::{SegmentJson, SensorSet, SurfaceConfig, SurfaceModel};

/// Pudney's incremental surface model (P ch. 2): planar polygon segments
/// with shared edges and corner vertices, built set by set from range
/// sensor readings.
///
/// ``config`` is a dict of ``SurfaceConfig`` fields (``lambda``,
/// ``mu_deg``, ``psi``, ``phi``, ``collinear_fraction``,
/// ``max_set_points``, ``merge_order``, ``snap_near_line_ends``), the keys
/// of ``surveyor model --print-config``; missing fields keep Pudney's
/// defaults. An unknown key or a value out of range is a ``ValueError``
/// naming it.
///
/// Feeding the sets of a file to ``add_set`` in order (after the file of
/// ``--initial`` segments to ``add_initial_segment``) builds the model
/// ``surveyor model --sets FILE`` builds: the same ``surface_model.json``
/// (``to_json``) and OBJ (``to_obj``).
#[pyclass(name = "SurfaceModel", module = "surveyor")]
pub struct PySurfaceModel {
    model: SurfaceModel,
}

impl PySurfaceModel {
    /// The model itself.
    pub fn model(&self) -> &SurfaceModel {
        &self.model
    }
}

/// `text` written to `path` through a temporary name in the same folder,
/// renamed into place: the file appears whole or not at all. An `OSError`
/// (its subclass for the error's kind) naming the file on failure.
pub(crate) fn write_whole(path: &Path, text: &str) -> PyResult<()> {
    let name = path
        .file_name()
        .ok_or_else(|| PyOSError::new_err(format!("{}: not a file name", path.display())))?;
    let mut tmp_name = std::ffi::OsString::from(".");
    tmp_name.push(name);
    tmp_name.push(format!(".{}.tmp", std::process::id()));
    let tmp = path.with_file_name(tmp_name);
    let result = std::fs::write(&tmp, text).and_then(|()| std::fs::rename(&tmp, path));
    result.map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        PyErr::from(std::io::Error::new(
            e.kind(),
            format!("{}: cannot write: {e}", path.display()),
        ))
    })
}

/// A `[x, y, z]` as a float64 array of shape (3,).
fn vec3(py: Python<'_>, v: [f64; 3]) -> Bound<'_, PyArray1<f64>> {
    PyArray1::from_slice(py, &v)
}

#[pymethods]
impl PySurfaceModel {
    /// An empty model with the configuration ``config`` (a dict of
    /// ``SurfaceConfig`` fields; ``None`` for Pudney's defaults: λ = 0.05 m,
    /// μ = 10°, ψ = 20, φ = 0.05).
    #[new]
    #[pyo3(signature = (config = None))]
    fn new(config: Option<&Bound<'_, PyAny>>) -> PyResult<Self> {
        let config: SurfaceConfig = config_from_dict("config", config)?;
        let model = SurfaceModel::new(config).map_err(|e| value_error(format!("config: {e}")))?;
        Ok(Self { model })
    }

    /// Feed one sensor set (P§2.3): ``points`` and ``axes`` are float64
    /// arrays of shape (n, 3), world frame; ``axes[i]`` is the unit sensing
    /// axis of the sensor that measured ``points[i]`` (pointing from the
    /// sensor into the surface), as in a ``surveyor model --sets`` line.
    ///
    /// Raises ``ValueError`` (naming ``points[i]`` or ``axes[i]``) for a
    /// wrong dtype or shape, unequal lengths, a value that is not finite, an
    /// axis whose norm is not 1 (within 1e-6), or more points than
    /// ``max_set_points``; the model is then unchanged. Runs with the GIL
    /// released.
    fn add_set(
        &mut self,
        py: Python<'_>,
        points: &Bound<'_, PyAny>,
        axes: &Bound<'_, PyAny>,
    ) -> PyResult<()> {
        let points = points_of("points", points)?;
        let axes: Vec<UnitVector3> = rows3("axes", axes)?
            .flat()
            .chunks_exact(3)
            .map(|c| UnitVector3::new_unchecked(Vector3::new(c[0], c[1], c[2])))
            .collect();
        let set = SensorSet { points, axes };
        set.validate().map_err(|e| value_error(e.to_string()))?;
        let model = &mut self.model;
        py.detach(|| model.update(&set))
            .map(|_| ())
            .map_err(|e| value_error(e.to_string()))
    }

    /// Add an initial (a priori) segment (P§4.3), as ``surveyor model
    /// --initial`` does: ``vertices`` a float64 array of shape (k, 3), k ≥ 3,
    /// coplanar, anticlockwise about the outward normal (a table seen from
    /// above runs anticlockwise). Returns the new segment's id. Raises
    /// ``ValueError`` for vertices that are not finite, not coplanar, or do
    /// not bound a simple polygon of positive area, and for a polygon that
    /// overlaps an initial segment already added on the same surface
    /// (initial segments never merge).
    fn add_initial_segment(&mut self, vertices: &Bound<'_, PyAny>) -> PyResult<u32> {
        let vertices = points_of("vertices", vertices)?;
        self.model
            .add_initial_segment(&vertices)
            .map(|id| id.0)
            .map_err(|e| value_error(format!("vertices: {e}")))
    }

    /// The planar polygon segments in id order, one dict each: ``id``
    /// (int), ``vertices`` (float64, shape (k, 3), anticlockwise about the
    /// normal), ``normal`` and ``centroid`` (float64, shape (3,)),
    /// ``points`` (sensor points represented) and ``initial`` (bool): the
    /// ``"polygon"`` segments of ``surface_model.json``.
    fn polygons<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyList>> {
        let list = PyList::empty(py);
        for segment in self.model.to_model_json().segments {
            let SegmentJson::Polygon {
                id,
                points,
                initial,
                centroid,
                normal,
                vertices,
                ..
            } = segment
            else {
                continue;
            };
            let d = PyDict::new(py);
            d.set_item("id", id)?;
            let v = Array2::from_shape_fn((vertices.len(), 3), |(k, c)| vertices[k][c]);
            d.set_item("vertices", PyArray2::from_owned_array(py, v))?;
            d.set_item("normal", vec3(py, normal))?;
            d.set_item("centroid", vec3(py, centroid))?;
            d.set_item("points", points)?;
            d.set_item("initial", initial)?;
            list.append(d)?;
        }
        Ok(list)
    }

    /// The shared edges (P§2.4), each pair once: an int64 array of shape
    /// (``stats["shared_edge_pairs"]``, 4), rows ``[segment, edge,
    /// neighbour, neighbour_edge]`` with ``(segment, edge) < (neighbour,
    /// neighbour_edge)``. Edge ``i`` of a polygon joins its vertices ``i``
    /// and ``i + 1`` (``polygons()``).
    fn shared_edges<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<i64>> {
        let mut rows: Vec<[i64; 4]> = Vec::new();
        for segment in self.model.to_model_json().segments {
            let SegmentJson::Polygon { id, edges, .. } = segment else {
                continue;
            };
            for (i, e) in edges.iter().enumerate() {
                if let (Some(n), Some(j)) = (e.shared_with, e.corresponding_edge) {
                    let row = [i64::from(id), i as i64, i64::from(n), j as i64];
                    if (row[0], row[1]) < (row[2], row[3]) {
                        rows.push(row);
                    }
                }
            }
        }
        PyArray2::from_owned_array(
            py,
            Array2::from_shape_fn((rows.len(), 4), |(k, c)| rows[k][c]),
        )
    }

    /// Write the model as Wavefront OBJ (polygons triangulated, one ``g``
    /// group per segment, point segments as ``p`` elements): the
    /// ``surface_model.obj`` of ``surveyor model``. Written through a
    /// temporary name in the same folder, then renamed. Raises ``OSError``
    /// when the file cannot be written.
    #[expect(
        clippy::needless_pass_by_value,
        reason = "PyO3 extracts owned arguments"
    )]
    fn to_obj(&self, path: PathBuf) -> PyResult<()> {
        write_whole(&path, &self.model.to_obj())
    }

    /// Write the model as ``surface_model.json`` (every segment with its
    /// vertices, edges and neighbours; the surfaces), the text ``surveyor
    /// model`` writes. Written as ``to_obj`` writes. Raises ``OSError`` when
    /// the file cannot be written.
    #[expect(
        clippy::needless_pass_by_value,
        reason = "PyO3 extracts owned arguments"
    )]
    fn to_json(&self, path: PathBuf) -> PyResult<()> {
        let text = serde_json::to_string_pretty(&self.model.to_model_json())
            .map_err(|e| value_error(format!("formatting the model: {e}")))?;
        write_whole(&path, &text)
    }

    /// Run the invariant checker (SPEC §3.4; what ``surveyor model --check``
    /// runs after every set). Returns ``None`` for a valid model, raises
    /// ``ValueError`` naming the broken rule otherwise.
    fn check(&self) -> PyResult<()> {
        self.model
            .check_invariants()
            .map_err(|e| value_error(e.to_string()))
    }

    /// Counts of the model, the ``model`` record of ``run.json``: a dict of
    /// ``updates``, ``segments``, ``polygons``, ``points`` (point
    /// segments), ``shared_edge_pairs`` and ``corner_vertices``.
    #[getter]
    fn stats<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        to_python(py, &self.model.stats())
    }

    /// The configuration in effect, every field (a dict, as ``surveyor model
    /// --print-config`` prints it).
    #[getter]
    fn config<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        to_python(py, self.model.config())
    }

    fn __repr__(&self) -> String {
        let s = self.model.stats();
        format!(
            "SurfaceModel(updates={}, segments={}, polygons={}, shared_edge_pairs={})",
            s.updates, s.segments, s.polygons, s.shared_edge_pairs
        )
    }
}
