//! `surveyor.Mapper`: the AXBAM maps of `surveyor map` (the `map` crate's
//! occupancy grid and TSDF) fed with NumPy sweeps, and the Scale-Like Discs
//! and segments of the fused mesh.

use crate::arrays::rows3;
use crate::config_dict::{config_from_dict, to_python};
use crate::errors::{scenario_error, value_error};
use geom::{Point3, Real, TriMesh};
use map::{
    Disc, MapConfig, Mapper, Orientation, SegmentConfig, SldConfig, generate_discs, segment_discs,
};
use numpy::ndarray::Array2;
use numpy::{
    PyArray1, PyArray2, PyArrayDescrMethods, PyArrayMethods, PyUntypedArray, PyUntypedArrayMethods,
};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use sensor::{GridCell, Sweep, SweepPoint};

/// Both AXBAM maps, fed sweep by sweep: the tri-state occupancy grid over
/// the regions of interest A1 ⊂ A2 ⊂ A3 with its entropies (Paul §4.2–4.3)
/// and the TSDF whose zero level set is the fused mesh (§5.1.1); the mesh's
/// Scale-Like Discs (§5.2) and their segments (§5.3).
///
/// ``config`` is a dict of ``MapConfig`` fields, the tables of ``surveyor
/// map --print-config`` (``{"occupancy": {"voxel_m": ..., "regions": ...},
/// "tsdf": {...}}``); missing fields keep their defaults. ``voxel`` sets
/// both maps' voxel edge (the TSDF truncation follows at four voxels), as
/// ``--voxel``; ``scenario`` (a built-in name such as ``"bridge1"``, or a
/// scenario file) replaces the regions by the scenario's, as
/// ``--scenario``. Applied in that order, as ``surveyor map`` applies them.
/// The default regions are the bridge scenarios'. Raises ``ValueError`` for
/// an unknown key, a value out of range, an unknown scenario name or a
/// scenario without regions; ``OSError`` (``FileNotFoundError`` when
/// missing) for a scenario path (``.toml`` or with a folder) that cannot be
/// opened.
#[pyclass(name = "Mapper", module = "surveyor")]
pub struct PyMapper {
    mapper: Mapper,
    config: MapConfig,
}

impl PyMapper {
    /// The maps themselves.
    pub fn mapper(&self) -> &Mapper {
        &self.mapper
    }
}

/// The Python type name of `obj`, for messages.
fn type_name(obj: &Bound<'_, PyAny>) -> String {
    obj.get_type()
        .name()
        .map_or_else(|_| "object".to_owned(), |n| n.to_string())
}

/// `obj` as a NumPy array (a list converted by `numpy.asarray`).
pub(crate) fn as_array<'py>(
    name: &str,
    obj: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyUntypedArray>> {
    if let Ok(a) = obj.cast::<PyUntypedArray>() {
        return Ok(a.clone());
    }
    obj.py()
        .import("numpy")?
        .getattr("asarray")?
        .call1((obj,))
        .map_err(|e| {
            value_error(format!(
                "{name}: expected an array, got a {} that NumPy cannot convert: {e}",
                type_name(obj)
            ))
        })?
        .cast_into::<PyUntypedArray>()
        .map_err(|_| {
            value_error(format!(
                "{name}: expected an array, got a {}",
                type_name(obj)
            ))
        })
}

/// The shape of `a` as Python prints it.
pub(crate) fn shape_text(a: &Bound<'_, PyUntypedArray>) -> String {
    let s: Vec<String> = a.shape().iter().map(ToString::to_string).collect();
    if s.len() == 1 {
        format!("({},)", s[0])
    } else {
        format!("({})", s.join(", "))
    }
}

/// A float64 argument of shape `(n,)`, every value finite.
fn values_n(name: &str, obj: &Bound<'_, PyAny>, n: usize) -> PyResult<Vec<f64>> {
    let a = as_array(name, obj)?;
    let py = obj.py();
    if !a.dtype().is_equiv_to(&numpy::dtype::<f64>(py)) {
        return Err(value_error(format!(
            "{name}: expected dtype float64, got {} (convert with {name}.astype(numpy.float64))",
            a.dtype()
        )));
    }
    if a.shape() != [n] {
        return Err(value_error(format!(
            "{name}: expected shape ({n},), one value per point, got {}",
            shape_text(&a)
        )));
    }
    let typed = a
        .cast_into::<PyArray1<f64>>()
        .map_err(|e| value_error(format!("{name}: {e}")))?;
    let values = typed
        .to_vec()
        .map_err(|e| value_error(format!("{name}: {e}")))?;
    if let Some(k) = values.iter().position(|v| !v.is_finite()) {
        return Err(value_error(format!(
            "{name}: value {k} is not finite ({})",
            values[k]
        )));
    }
    Ok(values)
}

/// The `(scan, ray)` cells of an integer argument of shape `(n, 2)`.
fn cells_n(name: &str, obj: &Bound<'_, PyAny>, n: usize) -> PyResult<Vec<GridCell>> {
    let a = as_array(name, obj)?;
    let py = obj.py();
    let kind = a.dtype().kind();
    if !(kind == b'i' || kind == b'u') {
        return Err(value_error(format!(
            "{name}: expected an integer dtype, got {} (convert with {name}.astype(numpy.int64))",
            a.dtype()
        )));
    }
    if a.shape() != [n, 2] {
        return Err(value_error(format!(
            "{name}: expected shape ({n}, 2), one (scan, ray) row per point, got {}",
            shape_text(&a)
        )));
    }
    let wide = a.call_method1("astype", (numpy::dtype::<i64>(py),))?;
    let typed = wide
        .cast_into::<PyArray2<i64>>()
        .map_err(|e| value_error(format!("{name}: {e}")))?;
    let ro = typed.readonly();
    let view = ro.as_array();
    let mut cells = Vec::with_capacity(n);
    for (k, row) in view.outer_iter().enumerate() {
        let index = |v: i64| u32::try_from(v).ok().filter(|&v| v < (1 << 24));
        match (index(row[0]), index(row[1])) {
            (Some(scan), Some(ray)) => cells.push(GridCell { scan, ray }),
            _ => {
                return Err(value_error(format!(
                    "{name}: row {k} is ({}, {}), expected whole numbers in [0, 16777215]",
                    row[0], row[1]
                )));
            }
        }
    }
    Ok(cells)
}

/// Points of an `(n, 3)` argument, every coordinate finite.
pub(crate) fn finite_points(name: &str, obj: &Bound<'_, PyAny>) -> PyResult<Vec<Point3>> {
    let rows = rows3(name, obj)?;
    rows.flat()
        .chunks_exact(3)
        .enumerate()
        .map(|(k, c)| {
            if c.iter().all(|v| v.is_finite()) {
                Ok(Point3::new(c[0], c[1], c[2]))
            } else {
                Err(value_error(format!(
                    "{name}: row {k} is not finite: [{}, {}, {}]",
                    c[0], c[1], c[2]
                )))
            }
        })
        .collect()
}

/// The discs of the mesh and the segment of each disc, as `surveyor map
/// --bag` and `surveyor explore` make them (Paul §5.2–5.3).
fn discs_and_segments(
    mesh: &TriMesh,
    seed: u64,
) -> Result<(Vec<Disc>, Vec<Vec<usize>>), map::MapError> {
    if mesh.vertices.is_empty() {
        return Ok((Vec::new(), Vec::new()));
    }
    let normals = mesh.vertex_normals();
    let sld = generate_discs(
        &mesh.vertices,
        Orientation::ReferenceNormals(&normals),
        &SldConfig::default(),
        seed,
    )?;
    let segments = segment_discs(&sld.discs, None, &SegmentConfig::default())?
        .into_iter()
        .map(|s| s.into_iter().map(|d| d.0).collect())
        .collect();
    Ok((sld.discs, segments))
}

/// Discs as a NumPy structured array, one row per disc: ``cx cy cz nx ny
/// nz radius`` (float64), ``points`` (int64) and, when given, ``segment``
/// (int64): the columns of ``discs.csv``.
pub(crate) fn disc_table<'py>(
    py: Python<'py>,
    discs: &[Disc],
    segment: Option<Vec<i64>>,
) -> PyResult<Bound<'py, PyAny>> {
    let np = py.import("numpy")?;
    let f8 = "<f8";
    let i8 = "<i8";
    let mut fields = vec![
        ("cx", f8),
        ("cy", f8),
        ("cz", f8),
        ("nx", f8),
        ("ny", f8),
        ("nz", f8),
        ("radius", f8),
        ("points", i8),
    ];
    if segment.is_some() {
        fields.push(("segment", i8));
    }
    let dtype = PyList::new(py, fields)?;
    let out = np.getattr("empty")?.call1((discs.len(), dtype))?;
    let column = |f: &dyn Fn(&Disc) -> f64| -> Vec<f64> { discs.iter().map(f).collect() };
    let floats: [(&str, Vec<f64>); 7] = [
        ("cx", column(&|d| d.centre.x)),
        ("cy", column(&|d| d.centre.y)),
        ("cz", column(&|d| d.centre.z)),
        ("nx", column(&|d| d.normal.x)),
        ("ny", column(&|d| d.normal.y)),
        ("nz", column(&|d| d.normal.z)),
        ("radius", column(&|d| d.radius_m)),
    ];
    for (name, values) in floats {
        out.set_item(name, PyArray1::from_vec(py, values))?;
    }
    let points: Vec<i64> = discs.iter().map(|d| d.points as i64).collect();
    out.set_item("points", PyArray1::from_vec(py, points))?;
    if let Some(segment) = segment {
        out.set_item("segment", PyArray1::from_vec(py, segment))?;
    }
    Ok(out)
}

#[pymethods]
impl PyMapper {
    /// Empty maps (see the class docs for ``config``, ``scenario`` and
    /// ``voxel``).
    #[new]
    #[pyo3(signature = (config = None, scenario = None, voxel = None))]
    fn new(
        config: Option<&Bound<'_, PyAny>>,
        scenario: Option<&str>,
        voxel: Option<Real>,
    ) -> PyResult<Self> {
        let mut config: MapConfig = config_from_dict("config", config)?;
        if let Some(v) = voxel {
            config = config.with_voxel_m(v);
        }
        if let Some(name) = scenario {
            // A file that cannot be opened is an OSError; a name that is
            // neither a built-in nor a path is the library's ValueError
            // (which lists the built-ins).
            let is_path = name.contains(std::path::MAIN_SEPARATOR)
                || std::path::Path::new(name)
                    .extension()
                    .is_some_and(|e| e.eq_ignore_ascii_case("toml"));
            if is_path
                && scenario::builtin_scenario(name).is_none()
                && let Err(e) = std::fs::File::open(name)
            {
                return Err(PyErr::from(std::io::Error::new(
                    e.kind(),
                    format!("scenario {name}: {e}"),
                )));
            }
            let loaded = scenario::Scenario::load(name).map_err(|e| scenario_error(&e))?;
            match loaded.scenario.regions {
                Some(regions) => config.occupancy.regions = regions,
                None => {
                    return Err(value_error(format!(
                        "scenario: {name} defines no regions of interest"
                    )));
                }
            }
        }
        let mapper = Mapper::new(&config).map_err(|e| value_error(format!("config: {e}")))?;
        Ok(Self { mapper, config })
    }

    /// Integrate one sweep into both maps, as ``surveyor map --scans`` does
    /// for each scan file.
    ///
    /// ``points`` (the returns) and ``origins`` (the origin of each return's
    /// ray: the scanner) are float64 arrays of shape (n, 3), world frame;
    /// ``intensities`` float64 of shape (n,) (kept with the returns; the
    /// maps do not use them). ``cells``, an integer array of shape (n, 2),
    /// gives each return's ``(scan, ray)`` cell of the sweep's range grid
    /// (the ``scan ray`` columns of a ``surveyor scan`` file), strictly
    /// increasing scan-major: with it, occlusions are found between grid
    /// neighbours (Paul §4.2.1), without it between neighbours in the list.
    ///
    /// Returns what the sweep did: ``{"occupancy": {"rays", "newly_known",
    /// "newly_occupied", "range_jumps", "newly_important",
    /// "rays_outside", ...}, "tsdf": {"points", "skipped", "voxel_updates",
    /// "new_blocks"}}``. Raises ``ValueError`` naming the argument for a
    /// wrong dtype or shape, unequal lengths, or a value that is not
    /// finite. Runs with the GIL released.
    #[pyo3(signature = (points, origins, intensities = None, cells = None))]
    fn insert_sweep<'py>(
        &mut self,
        py: Python<'py>,
        points: &Bound<'py, PyAny>,
        origins: &Bound<'py, PyAny>,
        intensities: Option<&Bound<'py, PyAny>>,
        cells: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let points = finite_points("points", points)?;
        let origins = finite_points("origins", origins)?;
        let n = points.len();
        if origins.len() != n {
            return Err(value_error(format!(
                "origins: {} rows for {n} points (one ray origin per point)",
                origins.len()
            )));
        }
        let intensities = match intensities.filter(|o| !o.is_none()) {
            Some(obj) => values_n("intensities", obj, n)?,
            None => vec![0.0; n],
        };
        let cells = match cells.filter(|o| !o.is_none()) {
            Some(obj) => Some(cells_n("cells", obj, n)?),
            None => None,
        };
        let sweep_points = (0..n)
            .map(|k| SweepPoint {
                point: points[k],
                origin: origins[k],
                intensity: intensities[k],
                material: None,
                cell: cells.as_ref().map(|c| c[k]),
            })
            .collect();
        let sweep = Sweep::from_points(sweep_points).map_err(|e| {
            let text = e.to_string();
            if cells.is_some() && text.contains("cell") {
                value_error(format!("cells: {text}"))
            } else {
                value_error(text)
            }
        })?;
        let mapper = &mut self.mapper;
        let summary = py.detach(|| mapper.integrate_sweep(&sweep));
        to_python(py, &summary)
    }

    /// The entropies of the occupancy grid, in nats: ``{"h1_unweighted":
    /// n_u ln 2 over A3 (Paul eq. 4.10), "h1_weighted": eq. 4.11 with the
    /// region weights and occlusion importance, "h2": eq. 4.14 (0 until
    /// C-space probabilities are set)}``; the H1 values ``surveyor map``
    /// prints, the fields of its ``occupancy.json``.
    fn entropy<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let r = self.mapper.occupancy().report();
        let d = PyDict::new(py);
        d.set_item("h1_unweighted", r.h1_unweighted)?;
        d.set_item("h1_weighted", r.h1_weighted)?;
        d.set_item("h2", r.h2)?;
        Ok(d)
    }

    /// The whole occupancy report, the dict of ``surveyor map``'s
    /// ``occupancy.json``: voxel size, grid dimensions, weights, the free,
    /// unknown and occupied voxels of A1, A2 and A3, and the entropies.
    fn report<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        to_python(py, &self.mapper.occupancy().report())
    }

    /// The TSDF's zero level set (marching cubes): ``(vertices,
    /// triangles)``, float64 of shape (m, 3) and int64 of shape (k, 3)
    /// indexing ``vertices`` — the mesh of ``surveyor map``'s ``mesh.ply``
    /// (which stores the vertices as float32). Runs with the GIL released.
    fn mesh<'py>(&self, py: Python<'py>) -> (Bound<'py, PyArray2<f64>>, Bound<'py, PyArray2<i64>>) {
        let tsdf = self.mapper.tsdf();
        let mesh = py.detach(|| tsdf.extract_mesh());
        let v = &mesh.vertices;
        let t = &mesh.triangles;
        (
            PyArray2::from_owned_array(py, Array2::from_shape_fn((v.len(), 3), |(k, c)| v[k][c])),
            PyArray2::from_owned_array(
                py,
                Array2::from_shape_fn((t.len(), 3), |(k, c)| i64::from(t[k][c])),
            ),
        )
    }

    /// The Scale-Like Discs of the fused mesh (Paul §5.2), as ``surveyor
    /// map --bag`` and ``surveyor explore`` make them: the mesh's vertices
    /// (float64) oriented by its vertex normals, the default ``SldConfig``
    /// (radius 0.04 m, 8 points), home points drawn with ``seed``.
    ///
    /// A NumPy structured array, one row per disc in generation order, with
    /// the columns of ``discs.csv``: ``cx cy cz`` (centre), ``nx ny nz``
    /// (unit normal) and ``radius`` (float64), ``points`` (points
    /// registered) and ``segment`` (the index of the disc's segment in
    /// ``segments(seed)``) (int64). Runs with the GIL released.
    #[pyo3(signature = (seed = 0))]
    fn discs<'py>(&self, py: Python<'py>, seed: u64) -> PyResult<Bound<'py, PyAny>> {
        let tsdf = self.mapper.tsdf();
        let (discs, segments) = py
            .detach(|| discs_and_segments(&tsdf.extract_mesh(), seed))
            .map_err(|e| value_error(e.to_string()))?;
        let mut segment = vec![-1_i64; discs.len()];
        for (s, members) in segments.iter().enumerate() {
            for &d in members {
                segment[d] = s as i64;
            }
        }
        disc_table(py, &discs, Some(segment))
    }

    /// The segments of the discs (Paul §5.3, Algorithm 1, without the pose
    /// graph, as ``surveyor segment --discs`` without ``--poses``; default
    /// ``SegmentConfig``): a list of int64 arrays of disc indices (rows of
    /// ``discs(seed)``), members ascending, segments ordered by their
    /// smallest member.
    #[pyo3(signature = (seed = 0))]
    fn segments<'py>(&self, py: Python<'py>, seed: u64) -> PyResult<Bound<'py, PyList>> {
        let tsdf = self.mapper.tsdf();
        let (_, segments) = py
            .detach(|| discs_and_segments(&tsdf.extract_mesh(), seed))
            .map_err(|e| value_error(e.to_string()))?;
        let list = PyList::empty(py);
        for s in segments {
            let members: Vec<i64> = s.into_iter().map(|d| d as i64).collect();
            list.append(PyArray1::from_vec(py, members))?;
        }
        Ok(list)
    }

    /// The configuration in effect, every field (a dict, as ``surveyor map
    /// --print-config`` prints it, the scenario's regions included).
    #[getter]
    fn config<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        to_python(py, &self.config)
    }

    fn __repr__(&self) -> String {
        let r = self.mapper.occupancy().report();
        format!(
            "Mapper(voxel_m={}, dims={:?}, h1_unweighted={})",
            r.voxel_m, r.dims, r.h1_unweighted
        )
    }
}
