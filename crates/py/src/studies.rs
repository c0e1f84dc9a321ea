//! The library calls behind the theses' parameter studies
//! (`surveyor.studies`): Scale-Like Discs of any points with any
//! configuration, timed (Paul Figs 5.7–5.8), and the coverage of the
//! combined sweeps of `n_Q` candidate viewpoints (Paul Fig. 3.2).

use crate::config_dict::config_from_dict;
use crate::errors::{scenario_error, value_error};
use crate::mapper::{as_array, disc_table, finite_points, shape_text};
use geom::{Point3, TriMesh, Vector3};
use map::{Orientation, SldConfig, generate_discs};
use numpy::{PyArray1, PyArray2, PyArrayDescrMethods, PyArrayMethods, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use scenario::Scenario;
use scenario::job::explore::{ExploreOptions, explore_setup};
use sim::oracle::{MAX_CANDIDATES, candidate_coverage as coverage_of_candidates};
use std::time::Instant;

/// An integer argument of shape `(m, 3)`: vertex indices below `n`.
fn triangles_of(name: &str, obj: &Bound<'_, PyAny>, n: usize) -> PyResult<Vec<[u32; 3]>> {
    let a = as_array(name, obj)?;
    let kind = a.dtype().kind();
    if !(kind == b'i' || kind == b'u') {
        return Err(value_error(format!(
            "{name}: expected an integer dtype, got {} (convert with {name}.astype(numpy.int64))",
            a.dtype()
        )));
    }
    if a.ndim() != 2 || a.shape()[1] != 3 {
        return Err(value_error(format!(
            "{name}: expected shape (m, 3), three vertex indices per triangle, got {}",
            shape_text(&a)
        )));
    }
    let wide = a.call_method1("astype", (numpy::dtype::<i64>(obj.py()),))?;
    let typed = wide
        .cast_into::<PyArray2<i64>>()
        .map_err(|e| value_error(format!("{name}: {e}")))?;
    let ro = typed.readonly();
    let mut out = Vec::with_capacity(a.shape()[0]);
    for (k, row) in ro.as_array().outer_iter().enumerate() {
        let index = |v: i64| u32::try_from(v).ok().filter(|&v| (v as usize) < n);
        match (index(row[0]), index(row[1]), index(row[2])) {
            (Some(a), Some(b), Some(c)) => out.push([a, b, c]),
            _ => {
                return Err(value_error(format!(
                    "{name}: row {k} is ({}, {}, {}), expected vertex indices in [0, {n})",
                    row[0], row[1], row[2]
                )));
            }
        }
    }
    Ok(out)
}

/// Scale-Like Discs of ``points`` (Paul §5.2), as ``surveyor sld`` makes
/// them: returns ``(discs, info)``.
///
/// ``points`` is float64 of shape (n, 3). The discs' normals are oriented
/// by ``triangles`` when given (an integer array of shape (m, 3) indexing
/// ``points``, which are then a mesh's vertices: each disc agrees with its
/// points' vertex normals, as discs are made from a run's fused mesh), else
/// by ``origins`` when given (float64 (n, 3), each point's sensor origin: a
/// disc faces the sensors that saw it), else by a canonical sign.
/// ``config`` is a dict of ``SldConfig`` fields (``radius_m``, μ, default
/// 0.04; ``min_points``, n_min, default 8; ``plane_tolerance_m``;
/// ``min_eigen_ratio``: ``surveyor sld --print-config``); ``seed`` draws
/// the home points.
///
/// ``discs`` is a structured array, one row per disc in generation order:
/// ``cx cy cz nx ny nz radius`` (float64) and ``points`` (int64, points
/// registered). ``info`` is a dict: ``points`` (n), ``registered`` (points
/// registered to a disc), ``registered_fraction``, ``occupied_voxels``
/// (voxels of edge μ holding a point) and ``seconds``, the time of the
/// generation alone (one thread; the GIL released). Raises ``ValueError``
/// for a bad array, an index out of range, an unknown config key or a value
/// out of range.
#[pyfunction]
#[pyo3(signature = (points, triangles = None, origins = None, config = None, seed = 0))]
pub fn scale_like_discs<'py>(
    py: Python<'py>,
    points: &Bound<'py, PyAny>,
    triangles: Option<&Bound<'py, PyAny>>,
    origins: Option<&Bound<'py, PyAny>>,
    config: Option<&Bound<'py, PyAny>>,
    seed: u64,
) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyDict>)> {
    let cfg: SldConfig = config_from_dict("config", config)?;
    cfg.validate().map_err(|e| value_error(e.to_string()))?;
    let points = finite_points("points", points)?;
    let triangles = match triangles.filter(|t| !t.is_none()) {
        Some(t) => Some(triangles_of("triangles", t, points.len())?),
        None => None,
    };
    let origins = match origins.filter(|o| !o.is_none()) {
        Some(o) => {
            let o = finite_points("origins", o)?;
            if o.len() != points.len() {
                return Err(value_error(format!(
                    "origins has {} rows and points {}: give one sensor origin per point",
                    o.len(),
                    points.len()
                )));
            }
            Some(o)
        }
        None => None,
    };
    let (sld, seconds, points) = py
        .detach(move || {
            let (points, normals): (Vec<Point3>, Option<Vec<Vector3>>) = match triangles {
                Some(t) => {
                    let mesh = TriMesh::new(points, t, "points").map_err(|e| e.to_string())?;
                    let normals = mesh.vertex_normals();
                    (mesh.vertices, Some(normals))
                }
                None => (points, None),
            };
            let orientation = match (&normals, &origins) {
                (Some(n), _) => Orientation::ReferenceNormals(n),
                (None, Some(o)) => Orientation::SensorOrigins(o),
                (None, None) => Orientation::Canonical,
            };
            let start = Instant::now();
            let sld =
                generate_discs(&points, orientation, &cfg, seed).map_err(|e| e.to_string())?;
            Ok::<_, String>((sld, start.elapsed().as_secs_f64(), points.len()))
        })
        .map_err(value_error)?;
    let info = PyDict::new(py);
    info.set_item("points", points)?;
    info.set_item("registered", sld.registered)?;
    info.set_item("registered_fraction", sld.registered_fraction())?;
    info.set_item("occupied_voxels", sld.occupied_voxels)?;
    info.set_item("seconds", seconds)?;
    Ok((disc_table(py, &sld.discs, None)?, info))
}

/// Paul's Fig. 3.2 (§3.2.3) on a simulated scene: the A1 coverage of the
/// combined sweeps of ``n_Q`` contending viewpoints drawn uniformly in
/// C-space, for each ``n_Q`` of ``sizes``.
///
/// ``scenario`` is a built-in name or a scenario file (with regions and a
/// scene of triangles). Candidates are drawn uniformly within the joint
/// limits, seeded by ``seed``; the first ``n_Q`` of one draw answer each
/// size. A candidate counts when its whole tilt sweep is clear by the run's
/// rule (``dist(Q) > 1`` against the voxels the true surface passes through,
/// and Stage One's clearance), or by the contact rule (no link touches the
/// true surface); its sweep is simulated as a run's would be. The start
/// pose's sweep is always counted, so ``n_Q = 0`` is its coverage alone.
///
/// Returns a dict of NumPy arrays, one entry per size (ascending, repeats
/// dropped): ``n_q``, ``clear_run``, ``coverage_run``, ``clear_contact``,
/// ``coverage_contact`` (coverage as a share of A1, 0 to 1). Sizes go up to
/// 20 000. Runs on all cores with the GIL released; the C-space model is
/// the one ``surveyor explore`` builds and caches. Raises ``ValueError``
/// for an unknown scenario or a size out of range.
#[pyfunction]
#[pyo3(signature = (scenario, sizes, seed = 0))]
#[expect(
    clippy::needless_pass_by_value,
    reason = "PyO3 extracts owned arguments"
)]
pub fn candidate_coverage<'py>(
    py: Python<'py>,
    scenario: &str,
    sizes: Vec<i64>,
    seed: u64,
) -> PyResult<Bound<'py, PyDict>> {
    let sizes: Vec<usize> = sizes
        .iter()
        .map(|&n| {
            usize::try_from(n)
                .ok()
                .filter(|&n| n <= MAX_CANDIDATES)
                .ok_or_else(|| {
                    value_error(format!(
                        "sizes: {n} candidates, expected 0 to {MAX_CANDIDATES}"
                    ))
                })
        })
        .collect::<PyResult<_>>()?;
    let loaded = Scenario::load(scenario).map_err(|e| scenario_error(&e))?;
    let rows = py
        .detach(|| {
            let options = ExploreOptions {
                cspace_cache: Some(
                    ExploreOptions::default_cspace_cache(&loaded).map_err(|e| e.to_string())?,
                ),
                ..ExploreOptions::default()
            };
            let (setup, world) = explore_setup(&loaded, &options).map_err(|e| e.to_string())?;
            let scanner = loaded.scenario.scanner.clone().unwrap_or_default().config;
            coverage_of_candidates(
                &setup,
                &world,
                &scanner,
                &loaded.scenario.metrics,
                &sizes,
                seed,
            )
            .map_err(|e| e.to_string())
        })
        .map_err(value_error)?;
    let out = PyDict::new(py);
    let column = |f: &dyn Fn(&sim::oracle::CandidateCoverage) -> usize| -> Vec<i64> {
        rows.iter().map(|r| f(r) as i64).collect()
    };
    out.set_item("n_q", PyArray1::from_vec(py, column(&|r| r.n_q)))?;
    out.set_item(
        "clear_run",
        PyArray1::from_vec(py, column(&|r| r.clear_run)),
    )?;
    out.set_item(
        "coverage_run",
        PyArray1::from_vec(py, rows.iter().map(|r| r.coverage_run).collect()),
    )?;
    out.set_item(
        "clear_contact",
        PyArray1::from_vec(py, column(&|r| r.clear_contact)),
    )?;
    out.set_item(
        "coverage_contact",
        PyArray1::from_vec(py, rows.iter().map(|r| r.coverage_contact).collect()),
    )?;
    Ok(out)
}
