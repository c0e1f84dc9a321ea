#![doc = include_str!("../README.md")]
//!
//! # Map of the crate
//!
//! | module | entry points |
//! |---|---|
//! | [`robot`](mod@robot) | [`PyRobot`] (`surveyor.Robot`): `from_urdf`, `builtin`, `fk`, `frames`, `jacobian`, `joint_limits` |
//! | [`scene`](mod@scene) | [`PyScene`] (`surveyor.Scene`): `from_file`, `builtin`, `raycast` |
//! | [`rays`] | [`rays::cast`]: NumPy rows checked, packed and cast as `surveyor raycast` casts its rays |
//! | [`arrays`] | NumPy arguments in, arrays out; every bad argument a `ValueError` naming it |
//! | [`runs`] | `surveyor.explore`, `surveyor.follow` (the jobs of the CLI into a run folder) and [`runs::PyRunFolder`] (a run folder read) |
//! | [`errors`] | the library errors as Python exceptions: `OSError` for files, `ValueError` for the rest |
//! | [`surface_model`] | [`PySurfaceModel`] (`surveyor.SurfaceModel`): `add_set`, `add_initial_segment`, `polygons`, `shared_edges`, `to_obj`, `to_json`, `check`, `stats` |
//! | [`mapper`](mod@mapper) | [`PyMapper`] (`surveyor.Mapper`): `insert_sweep`, `entropy`, `report`, `mesh`, `discs`, `segments` |
//! | [`studies`] | `surveyor.scale_like_discs` (discs of any points, timed) and `surveyor.candidate_coverage` (Paul Fig. 3.2), behind `surveyor.studies` |
//! | [`config_dict`] | configuration dicts in (serde, unknown keys refused), configs and reports out as dicts |

pub mod arrays;
pub mod config_dict;
pub mod errors;
pub mod mapper;
pub mod rays;
pub mod robot;
pub mod runs;
pub mod scene;
pub mod studies;
pub mod surface_model;

pub use mapper::PyMapper;
pub use robot::PyRobot;
pub use scene::PyScene;
pub use surface_model::PySurfaceModel;

use pyo3::prelude::*;

/// The native module `surveyor._surveyor`; the package `surveyor`
/// (`python/surveyor/__init__.py`) re-exports its classes.
#[pymodule]
fn _surveyor(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyRobot>()?;
    m.add_class::<PyScene>()?;
    m.add_class::<PySurfaceModel>()?;
    m.add_class::<PyMapper>()?;
    m.add_class::<runs::PyRunFolder>()?;
    m.add_function(wrap_pyfunction!(runs::_explore, m)?)?;
    m.add_function(wrap_pyfunction!(runs::_check_explore, m)?)?;
    m.add_function(wrap_pyfunction!(runs::_follow, m)?)?;
    m.add_function(wrap_pyfunction!(studies::scale_like_discs, m)?)?;
    m.add_function(wrap_pyfunction!(studies::candidate_coverage, m)?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
