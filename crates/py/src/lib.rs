#![doc = include_str!("../README.md")]
//!
//! # Map of the crate
//!
//! | module | entry points |
//! |---|---|
//! | [`robot`](mod@robot) | [`PyRobot`] (`surveyor.Robot`): `from_urdf`, `builtin`, `fk`, `frames`, `jacobian`, `joint_limits` |
//! | [`scene`](mod@scene) | [`PyScene`] (`surveyor.Scene`): `from_file`, `builtin`, `raycast` |
//! | [`rays`] | [`rays::ray_records`]: NumPy rows checked and packed as the rays of `surveyor raycast` |
//! | [`arrays`] | NumPy arguments in, arrays out; every bad argument a `ValueError` naming it |
//! | [`errors`] | the library errors as Python exceptions: `OSError` for files, `ValueError` for the rest |

pub mod arrays;
pub mod errors;
pub mod rays;
pub mod robot;
pub mod scene;

pub use robot::PyRobot;
pub use scene::PyScene;

use pyo3::prelude::*;

/// The native module `surveyor._surveyor`; the package `surveyor`
/// (`python/surveyor/__init__.py`) re-exports its classes.
#[pymodule]
fn _surveyor(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyRobot>()?;
    m.add_class::<PyScene>()?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
